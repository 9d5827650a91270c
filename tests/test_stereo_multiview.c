/* test_stereo_multiview.c — `--multiview on|off` (STEREO.md "Vulkan multiview", README "Multiview"): the atlas methods'
 * visibility pass of both eyes recorded as one VK_KHR_multiview render pass (viewMask 0b11, 2-layer attachments, the
 * eye's view_proj by gl_ViewIndex) against one pass per eye, on lavapipe with the validation layer (any message
 * fails), at a tiny size. Any other device must give byte-identical ids, frames and counts; lavapipe does not: its
 * rasteriser writes a few fragments of view 1 (thin far triangles) into layer 0, so the test bounds the difference
 * (<= 3 % of the pixels) and requires every differing pixel to be one of those (README "Multiview"):
 *  - sa and tasa@8 on tests/data/stereo_multiview.json (OPAQUE, a MASK fence with holes, a BLEND ball composited on the
 *    ids pass's depth, a spinning box, a shadow), 3 frames: both eyes' display and HDR frames, the ids images and every
 *    count of the frame statistics (per-eye columns included) equal; the multiview path was taken (not a fallback);
 *  - the CLI: `taslab render --stereo --multiview on` and `off` both write every frame (both eyes, side by side), the
 *    same stats.csv columns, images that agree but for the driver's fragments below;
 *  - bad input: --multiview without --stereo, an unknown mode. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_vk.h"

#include "../renderer/src/methods/method_debug.h"
#include "taslab/imageio.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

enum { W = 48, H = 32, FRAMES = 3 };


typedef struct eyes {
	uint8_t *disp[2][FRAMES];
	uint16_t *hdr[2][FRAMES];
	uint32_t *ids[2][FRAMES];
	frame_stats st[FRAMES];
	bool multiview;
} eyes;

static eyes render_eyes(vkdev *dev, const scene *s, const char *variant, render_multiview mv)
{
	char err[1024];
	method_config mc;
	if (method_config_parse_variant(&mc, variant, err, sizeof err))
		fail_msg("%s: %s", variant, err);
	render *r = NULL;
	render_desc d = {.scene = s, .camera = 0, .width = W, .height = H, .method = &mc, .views = 2, .ipd = 0.063f,
			 .multiview = mv};
	if (render_create(dev, &d, &r, err, sizeof err))
		fail_msg("%s: %s", variant, err);
	eyes e = {.multiview = atlas_debug_multiview(r)};
	size_t px = (size_t)W * H;
	for (uint32_t f = 0; f < FRAMES; f++) {
		frame_image img;
		if (render_frame(r, f, &img, &e.st[f], err, sizeof err))
			fail_msg("%s frame %u: %s", variant, f, err);
		for (uint32_t v = 0; v < 2; v++) {
			frame_image vi;
			assert_int_equal(render_view_image(r, v, &vi), TL_OK);
			e.disp[v][f] = malloc(px * 4);
			e.hdr[v][f] = malloc(px * 8);
			e.ids[v][f] = malloc(px * 16);
			memcpy(e.disp[v][f], vi.display_rgba, px * 4);
			memcpy(e.hdr[v][f], vi.hdr_rgba_half, px * 8);
			if (atlas_debug_ids_view(r, v, e.ids[v][f], false, err, sizeof err))
				fail_msg("%s ids: %s", variant, err);
		}
	}
	render_destroy(&r);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	return e;
}

static void eyes_free(eyes *e)
{
	for (uint32_t v = 0; v < 2; v++)
		for (uint32_t f = 0; f < FRAMES; f++) {
			free(e->disp[v][f]);
			free(e->hdr[v][f]);
			free(e->ids[v][f]);
		}
}

static void test_same_frames(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	if (!dev->has_multiview) { /* then `on` is refused with one line, and auto is the two-pass path */
		char err[512];
		method_config mc;
		scene *s = tu_load_scene("stereo_multiview");
		render *r = NULL;
		assert_int_equal(method_config_parse_variant(&mc, "sa", err, sizeof err), 0);
		render_desc d = {.scene = s, .width = W, .height = H, .method = &mc, .views = 2, .ipd = 0.063f,
				 .multiview = RENDER_MULTIVIEW_ON};
		assert_int_equal(render_create(dev, &d, &r, err, sizeof err), TL_ERR_UNSUPPORTED);
		scene_destroy(&s);
		vkdev_destroy(&dev);
		skip();
	}
	scene *s = tu_load_scene("stereo_multiview");
	const char *variants[] = {"sa", "tasa@8"};
	size_t px = (size_t)W * H;
	/* any other device: bit-exact ids, frames and counts (the spec's multiview renders view v as its own pass) */
	const bool exact = !vkdev_is_lavapipe(dev);
	for (size_t i = 0; i < 2; i++) {
		const char *v = variants[i];
		eyes two = render_eyes(dev, s, v, RENDER_MULTIVIEW_OFF);
		eyes one = render_eyes(dev, s, v, RENDER_MULTIVIEW_ON);
		assert_false(two.multiview);
		assert_true(one.multiview);
		for (uint32_t f = 0; f < FRAMES; f++) {
			/* the eyes differ (ipd 0.063 on a near scene): a pass that drew one eye twice would not pass */
			assert_true(memcmp(two.ids[0][f], two.ids[1][f], px * 16) != 0);
			for (uint32_t e = 0; e < 2; e++) {
				/* lavapipe (Mesa's llvmpipe rasteriser) writes a few fragments of view 1 into layer 0: thin far
				 * triangles at the floor's far edge, 14 of 1536 pixels here. Layer 0 then holds the right eye's ids
				 * there and layer 1 misses them (background). Bounded and characterised here; README "Multiview". */
				size_t ids_px = 0, disp_px = 0, odd_px = 0;
				for (size_t q = 0; q < px; q++) {
					const uint32_t *x = two.ids[e][f] + 4 * q, *y = one.ids[e][f] + 4 * q;
					if (!memcmp(x, y, 16))
						continue;
					ids_px++;
					/* eye 0: a surface of one of the eyes (the right eye's floor fragment, maybe hidden there by
					 * the fence); eye 1: nothing drawn (the lost fragment; the floor is the last surface) */
					const uint32_t *r = two.ids[1][f] + 4 * q;
					odd_px += e == 0 ? (y[0] != x[0] && y[0] != r[0]) : y[0] != 0;
					if (getenv("MV_DEBUG"))
						fprintf(stderr, "  (%zu,%zu) %u %u / %u %u (right %u %u)\n", q % W, q / W, x[0], x[1], y[0],
							y[1], r[0], r[1]);
				}
				for (size_t q = 0; q < px * 4; q++)
					disp_px += two.disp[e][f][q] != one.disp[e][f][q];
				fprintf(stderr, "%s frame %u eye %u: multiview vs two passes: ids differ at %zu of %zu px\n", v, f, e,
					ids_px, px);
				if (exact && ids_px)
					fail_msg("%s frame %u eye %u: multiview ids differ from the two-pass ids", v, f, e);
				assert_true(ids_px * 100 <= px * 3);     /* measured 14 px, 0.9 % */
				assert_true(disp_px * 100 <= px * 4 * 3); /* display channels that differ */
				if (odd_px)
					fail_msg("%s frame %u eye %u: %zu px differ otherwise than by the driver's misrouted fragments", v,
						 f, e, odd_px);
			}
			const frame_stats *a = &two.st[f], *b = &one.st[f];
			assert_true(a->shaded_samples > 0 || f > 0);
			const char *cols[] = {"visible_samples_l", "visible_samples_r", "shaded_samples_l", "shaded_samples_r"};
			/* the counts: equal where the eyes' ids are; within 5 % with the misrouted fragments */
			int64_t ca[] = {a->visible_samples, a->shaded_samples, a->allocated_samples, a->visible_units,
					a->shaded_units, (int64_t)tu_extra(a, cols[0]), (int64_t)tu_extra(a, cols[1]),
					(int64_t)tu_extra(a, cols[2]), (int64_t)tu_extra(a, cols[3])};
			int64_t cb[] = {b->visible_samples, b->shaded_samples, b->allocated_samples, b->visible_units,
					b->shaded_units, (int64_t)tu_extra(b, cols[0]), (int64_t)tu_extra(b, cols[1]),
					(int64_t)tu_extra(b, cols[2]), (int64_t)tu_extra(b, cols[3])};
			for (size_t k = 0; k < sizeof ca / sizeof ca[0]; k++) {
				if (ca[k] != cb[k])
					fprintf(stderr, "%s frame %u: count %zu: %lld vs %lld\n", v, f, k, (long long)ca[k], (long long)cb[k]);
				if (exact)
					assert_int_equal(ca[k], cb[k]);
				assert_true(llabs(ca[k] - cb[k]) * 20 <= ca[k]); /* within 5 % (measured <= 2.2 %) */
			}
		}
		eyes_free(&two);
		eyes_free(&one);
	}
	scene_destroy(&s);
	vkdev_destroy(&dev);
}

static void test_cli(void **state)
{
	(void)state;
	char cmd[4096], out[8192], dir[2][1024], a[1200], b[1200];
	const char *modes[2] = {"off", "on"};
	for (int k = 0; k < 2; k++) {
		snprintf(dir[k], sizeof dir[k], "%s", tu_tmpdir(k ? "multiview_on" : "multiview_off"));
		snprintf(cmd, sizeof cmd, "%s render --scene %s/tests/data/stereo_multiview.json --size 48x32 --frames 0:2 "
			 "--stereo --multiview %s --method tasa@8 --validation --quiet --out %s", TASLAB_BINARY, TASLAB_SOURCE_DIR,
			 modes[k], dir[k]);
		if (tu_run(cmd, out, sizeof out))
			fail_msg("%s\n%s", cmd, out);
	}
	/* both runs complete with every frame; the images agree but for the driver's misrouted fragments (test above) */
	const char *files[] = {"frames/L/000000.png", "frames/R/000000.png", "frames/L/000001.png", "frames/R/000001.png",
			       "sbs/000001.png"};
	for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
		uint32_t w[2] = {0}, h[2] = {0};
		uint8_t *px[2] = {NULL};
		char err[512];
		for (int k = 0; k < 2; k++) {
			snprintf(a, sizeof a, "%s/%s", dir[k], files[i]);
			if (imageio_read_rgb8(a, &w[k], &h[k], &px[k], err, sizeof err))
				fail_msg("%s", err);
		}
		assert_int_equal(w[0], w[1]);
		assert_int_equal(h[0], h[1]);
		size_t n = (size_t)w[0] * h[0], diff = 0;
		for (size_t q = 0; q < n; q++)
			diff += memcmp(px[0] + 3 * q, px[1] + 3 * q, 3) != 0;
		if (diff * 100 > n * 3)
			fail_msg("%s: --multiview on and off differ at %zu of %zu px", files[i], diff, n);
		free(px[0]);
		free(px[1]);
		snprintf(a, sizeof a, "%s/frames/R/000001.exr", dir[0]);
		snprintf(b, sizeof b, "%s/frames/R/000001.exr", dir[1]);
		assert_true(tu_file_exists(a) && tu_file_exists(b));
	}
	snprintf(a, sizeof a, "%s/stats.csv", dir[0]);
	snprintf(b, sizeof b, "%s/stats.csv", dir[1]);
	char *ca = tu_read_file(a, NULL), *cb = tu_read_file(b, NULL);
	assert_non_null(ca);
	assert_non_null(cb);
	assert_string_equal(strtok(ca, "\n"), strtok(cb, "\n")); /* the same columns */
	assert_non_null(strstr(ca, "shaded_samples_r"));
	free(ca);
	free(cb);
	tu_expect_cli_error("render --scene calm --multiview on", "--multiview needs --stereo");
	tu_expect_cli_error("render --scene calm --stereo --multiview both", "--multiview 'both'");
}

int main(void)
{
	const struct CMUnitTest tests[] = {cmocka_unit_test(test_same_frames), cmocka_unit_test(test_cli)};
	return tu_finish(cmocka_run_group_tests(tests, NULL, NULL));
}
