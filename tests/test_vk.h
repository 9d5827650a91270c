/* test_vk.h — helpers for the tests of the Vulkan renderer (linked with test_vk.c). */
#ifndef TASLAB_TEST_VK_H
#define TASLAB_TEST_VK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "test_util.h"
#include "taslab/frame.h"

struct scene;
struct vkdev;
struct colour;
/* Loads scenes/NAME.json and opens the test device (lavapipe by default) with the validation layer; 0 or -1 (message printed). */
int tu_open_scene_and_device(const char *name, struct scene **scn, struct vkdev **dev);
/* Frees both; returns -1 when the device saw any validation message, so a group teardown fails. */
int tu_close_scene_and_device(struct scene **scn, struct vkdev **dev);

/* ---- clips rendered in memory (the method tests) ---- */
typedef struct tu_clip {
	uint32_t n, w, h;
	uint8_t **disp;  /* RGBA8 per frame */
	uint16_t **hdr;  /* RGBA half per frame */
	uint8_t **dec;   /* frame_decision per pixel (render --decisions), NULL without */
	frame_stats *st;
} tu_clip;

/* tests/data/NAME.json, or a path below the source tree when NAME contains '/'; fails the test on error. */
struct scene *tu_load_scene(const char *name);
/* The test device (TASLAB_TEST_DEVICE, lavapipe by default) with the validation layer; fails the test on error. */
struct vkdev *tu_lavapipe(void);
/* True when the tests render on lavapipe (the default). Exact equalities between *different pipelines* (tfr's
 * shading vs ref's, OCIO's GLSL vs its rewrite, ...) hold there: llvmpipe compiles the same arithmetic the same way.
 * A GPU's compiler contracts and reorders differently per pipeline (FMA, shadow-compare flips at a few pixels), so
 * those tests state a tolerance for other devices (README "Tests": on an NVIDIA GPU). */
#define TU_ON_LAVAPIPE (!strcmp(TASLAB_TEST_DEVICE, "lavapipe"))
int tu_camera_index(const struct scene *s, const char *name);
/* Renders frames [0, n) of a variant token with extra options ("name=value" or a flag name, NULL-terminated),
 * optionally a display transform and decision maps; checks the device saw no validation message. */
tu_clip tu_render_clip(struct vkdev *dev, const struct scene *s, int camera, const char *variant,
		       const char *const *opts, const struct colour *col, uint32_t w, uint32_t h, uint32_t n, bool decisions);
void tu_clip_free(tu_clip *c);
/* The renderer tu_render_clip uses, for tests that look at a method's state between frames (method_debug.h). */
struct render *tu_render_open(struct vkdev *dev, const struct scene *s, int camera, const char *variant,
			      const char *const *opts, const struct colour *col, uint32_t w, uint32_t h, bool decisions);
/* Largest difference over R, G, B of two RGBA8 images. */
int tu_max_diff(const uint8_t *a, const uint8_t *b, size_t pixels);
/* Fails unless the PNG (and, with `hdr`, the half-float) frames of two clips are identical. */
void tu_assert_same_frames(const tu_clip *a, const tu_clip *b, bool hdr);
/* A raw OCIO config (display = scene-linear, clamped): shading linear in time gives display values linear in
 * time. Fails the test on error. */
struct colour *tu_raw_colour(void);
/* A method's extra stats.csv column by name (NAN when absent). */
double tu_extra(const frame_stats *st, const char *name);

#endif
