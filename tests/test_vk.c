/* test_vk.c — helpers for the tests of the Vulkan renderer (test_vk.h): lavapipe with validation, pinned. */
#include "test_vk.h"

#include <dlfcn.h>
#include <stdio.h>

#include "taslab/scene.h"
#include "taslab/vkdev.h"

/* Keep Mesa's lavapipe driver and the validation layer loaded until exit: the Vulkan loader
 * dlcloses them, after which LeakSanitizer cannot attribute their allocations to a module (and so
 * cannot apply lsan.supp); pinned, their global state stays reachable and our own leaks still show. */
__attribute__((constructor)) static void tu_pin_vulkan_libraries(void)
{
	dlopen("libvulkan_lvp.so", RTLD_NOW | RTLD_NODELETE);
	dlopen("libVkLayer_khronos_validation.so", RTLD_NOW | RTLD_NODELETE);
}

int tu_open_scene_and_device(const char *name, scene **scn, vkdev **dev)
{
	char err[1024], path[4096];
	snprintf(path, sizeof path, "%s/scenes/%s.json", TASLAB_SOURCE_DIR, name);
	vkdev_desc d = {.device = "lavapipe", .validation = true};
	if (scene_load(path, scn, err, sizeof err) || vkdev_create(&d, dev, err, sizeof err)) {
		fprintf(stderr, "%s\n", err);
		return -1;
	}
	return 0;
}

int tu_close_scene_and_device(scene **scn, vkdev **dev)
{
	uint32_t msgs = *dev ? vkdev_validation_messages(*dev) : 0;
	vkdev_destroy(dev);
	scene_destroy(scn);
	return msgs ? -1 : 0;
}

