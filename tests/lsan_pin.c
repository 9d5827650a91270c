/* lsan_pin.c — a preload library for the processes the tests start (LD_PRELOAD, see tu_child_env in test_util.h):
 * in a taslab process it keeps Mesa's lavapipe driver and the validation layer loaded until exit, as test_vk.c does
 * inside the test binaries. The Vulkan loader dlcloses them at vkDestroyInstance; afterwards LeakSanitizer cannot
 * attribute their allocations to a module ("<unknown module>") and so cannot apply lsan.supp: `taslab render`
 * reported "240 byte(s) leaked in 3 allocation(s)" that way, all of it lavapipe's global state (pinned, it stays
 * reachable and nothing is reported). The libraries are opened RTLD_LOCAL: none of their symbols (the layer exports
 * vkGetDeviceProcAddr, ...) is put in front of the loader's. Other programs (cp, sh, ...) it leaves alone, so it can
 * be preloaded into a whole shell command. Built without sanitizers (tests/CMakeLists.txt). Our own leaks still
 * show. */
#define _DEFAULT_SOURCE
#include <dlfcn.h>
#include <string.h>
#include <unistd.h>

__attribute__((constructor)) static void lsan_pin_vulkan_libraries(void)
{
	char exe[4096];
	ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
	if (n <= 0)
		return;
	exe[n] = 0;
	const char *base = strrchr(exe, '/');
	if (strcmp(base ? base + 1 : exe, "taslab"))
		return;
	dlopen("libvulkan_lvp.so", RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
	dlopen("libVkLayer_khronos_validation.so", RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
}
