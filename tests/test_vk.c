/* test_vk.c — helpers for the tests of the Vulkan renderer (test_vk.h): lavapipe with validation, pinned. */
#include "test_vk.h"

#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/colour.h"
#include "taslab/render.h"
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
	vkdev_desc d = {.device = TASLAB_TEST_DEVICE, .validation = true};
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

scene *tu_load_scene(const char *name)
{
	char path[4096], err[1024];
	scene *s = NULL;
	if (strchr(name, '/'))
		snprintf(path, sizeof path, "%s/%s", TASLAB_SOURCE_DIR, name);
	else
		snprintf(path, sizeof path, "%s/tests/data/%s.json", TASLAB_SOURCE_DIR, name);
	if (scene_load(path, &s, err, sizeof err))
		fail_msg("%s", err);
	return s;
}

vkdev *tu_lavapipe(void)
{
	char err[1024];
	vkdev *dev = NULL;
	vkdev_desc d = {.device = TASLAB_TEST_DEVICE, .validation = true};
	if (vkdev_create(&d, &dev, err, sizeof err))
		fail_msg("%s", err);
	return dev;
}

int tu_camera_index(const scene *s, const char *name)
{
	for (size_t i = 0; i < s->camera_count; i++)
		if (!strcmp(s->cameras[i].name, name))
			return (int)i;
	fail_msg("no camera %s", name);
	return -1;
}

render *tu_render_open(vkdev *dev, const scene *s, int camera, const char *variant, const char *const *opts,
		       const colour *col, uint32_t w, uint32_t h, bool decisions)
{
	char err[1024];
	method_config mc;
	if (method_config_parse_variant(&mc, variant, err, sizeof err))
		fail_msg("%s: %s", variant, err);
	for (size_t i = 0; opts && opts[i]; i++) {
		char name[64];
		const char *eq = strchr(opts[i], '=');
		snprintf(name, sizeof name, "%.*s", eq ? (int)(eq - opts[i]) : (int)strlen(opts[i]), opts[i]);
		if (method_config_set(&mc, name, eq ? eq + 1 : "true", err, sizeof err))
			fail_msg("%s: %s", variant, err);
	}
	if (method_config_check(&mc, err, sizeof err))
		fail_msg("%s: %s", variant, err);
	render *r = NULL;
	render_desc d = {.scene = s, .camera = camera, .width = w, .height = h, .method = &mc, .colour = col,
			 .decisions = decisions};
	if (render_create(dev, &d, &r, err, sizeof err))
		fail_msg("%s: %s", variant, err);
	return r;
}

/* Renders frames [0, n) of `variant` with extra options ("name=value", NULL-terminated). */
tu_clip tu_render_clip(vkdev *dev, const scene *s, int camera, const char *variant, const char *const *opts,
			const colour *col, uint32_t w, uint32_t h, uint32_t n, bool decisions)
{
	char err[1024];
	render *r = tu_render_open(dev, s, camera, variant, opts, col, w, h, decisions);
	tu_clip c = {.n = n, .w = w, .h = h};
	c.disp = calloc(n, sizeof *c.disp);
	c.hdr = calloc(n, sizeof *c.hdr);
	c.dec = calloc(n, sizeof *c.dec);
	c.st = calloc(n, sizeof *c.st);
	size_t px = (size_t)w * h;
	for (uint32_t f = 0; f < n; f++) {
		frame_image img;
		if (render_frame(r, f, &img, &c.st[f], err, sizeof err))
			fail_msg("%s frame %u: %s", variant, f, err);
		c.disp[f] = malloc(px * 4);
		c.hdr[f] = malloc(px * 8);
		memcpy(c.disp[f], img.display_rgba, px * 4);
		memcpy(c.hdr[f], img.hdr_rgba_half, px * 8);
		if (decisions) {
			assert_non_null(img.decisions);
			c.dec[f] = malloc(px);
			memcpy(c.dec[f], img.decisions, px);
		} else {
			assert_null(img.decisions);
		}
	}
	render_destroy(&r);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	return c;
}

void tu_clip_free(tu_clip *c)
{
	for (uint32_t f = 0; f < c->n; f++) {
		free(c->disp[f]);
		free(c->hdr[f]);
		free(c->dec[f]);
	}
	free(c->disp);
	free(c->hdr);
	free(c->dec);
	free(c->st);
	memset(c, 0, sizeof *c);
}

int tu_max_diff(const uint8_t *a, const uint8_t *b, size_t pixels)
{
	int m = 0;
	for (size_t i = 0; i < pixels * 4; i++) {
		if (i % 4 == 3)
			continue;
		int d = abs((int)a[i] - (int)b[i]);
		m = d > m ? d : m;
	}
	return m;
}

void tu_assert_same_frames(const tu_clip *a, const tu_clip *b, bool hdr)
{
	size_t px = (size_t)a->w * a->h;
	for (uint32_t f = 0; f < a->n; f++) {
		if (memcmp(a->disp[f], b->disp[f], px * 4))
			fail_msg("frame %u: PNG pixels differ (max %d code values)", f, tu_max_diff(a->disp[f], b->disp[f], px));
		if (hdr && memcmp(a->hdr[f], b->hdr[f], px * 8))
			fail_msg("frame %u: EXR (half) pixels differ", f);
	}
}

double tu_extra(const frame_stats *st, const char *name)
{
	for (uint32_t e = 0; e < st->extra_count; e++)
		if (!strcmp(st->extra_names[e], name))
			return st->extra[e];
	return NAN;
}

/* A raw OCIO config: display values = scene-linear values (clamped), so shading linear in time gives display
 * values linear in time (as test_tfr). */
colour *tu_raw_colour(void)
{
	const char *dir = tu_tmpdir("raw_ocio");
	char path[4096], err[1024];
	snprintf(path, sizeof path, "%s/raw.ocio", dir);
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	fputs("ocio_profile_version: 2\n"
	      "roles:\n  default: raw\n  scene_linear: raw\n"
	      "displays:\n  linear:\n    - !<View> {name: Raw, colorspace: raw}\n"
	      "colorspaces:\n  - !<ColorSpace>\n    name: raw\n    isdata: false\n",
	      f);
	fclose(f);
	colour *c = NULL;
	colour_desc cd = {.config_path = path, .display = "linear", .view = "Raw"};
	if (colour_create(&cd, &c, err, sizeof err))
		fail_msg("%s", err);
	return c;
}
