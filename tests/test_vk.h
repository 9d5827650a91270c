/* test_vk.h — helpers for the tests of the Vulkan renderer (linked with test_vk.c). */
#ifndef TASLAB_TEST_VK_H
#define TASLAB_TEST_VK_H

#include "test_util.h"

struct scene;
struct vkdev;
/* Loads scenes/NAME.json and opens lavapipe with the validation layer; 0 or -1 (message printed). */
int tu_open_scene_and_device(const char *name, struct scene **scn, struct vkdev **dev);
/* Frees both; returns -1 when the device saw any validation message, so a group teardown fails. */
int tu_close_scene_and_device(struct scene **scn, struct vkdev **dev);

#endif
