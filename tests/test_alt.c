/* test_alt.c — the survey's temporal-reuse alternatives (BASELINES.md A2, A3 target, A6; section C) on lavapipe with
 * the validation layer (any message fails), at tiny sizes:
 *  S1  ref --ssaa 2 (ref-ssaa2) at W x H equals the 2 x 2 box filter, on the CPU, of ref's HDR at 2W x 2H (within one
 *      half-float rounding) and shades exactly what ref shades at 2W x 2H; ref-ssaa1 is ref;
 *  (R5, R6: test_alt_refresh.c)
 *  W1  warp/1 equals ref byte for byte (display and HDR) on a moving built-in scene; warp/2 on a pan: key frames
 *      equal ref and count ref's shading, the others launch no opaque shading, fill every hole (moderate's
 *      moving camera) and stay within 8 code values of ref on the pan; on a static view every frame equals ref;
 *      at 49x31 the static view equals ref and every hole is filled;
 *  determinism of warp (same inputs, same frames; R5 checks rrc's frames against vref) and bad variants. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_vk.h"

#include "taslab/method.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

#include <time.h>
static double now_s(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- S1 ---- */

static void test_ssaa(void **state)
{
	(void)state;
	double t0 = now_s();
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("tfr_static");
	enum { W = 48, H = 32, F = 2 };
	tu_clip big = tu_render_clip(dev, s, 0, "ref", NULL, NULL, 2 * W, 2 * H, F, false);
	tu_clip ss = tu_render_clip(dev, s, 0, "ref-ssaa2", NULL, NULL, W, H, F, false);
	const char *const k2[] = {"ssaa=2", NULL};
	tu_clip opt = tu_render_clip(dev, s, 0, "ref", k2, NULL, W, H, F, false);
	tu_assert_same_frames(&ss, &opt, true); /* the option and the variant token are one configuration */
	double worst = 0;
	for (uint32_t f = 0; f < F; f++) {
		assert_int_equal(ss.st[f].shaded_samples, big.st[f].shaded_samples);
		for (uint32_t y = 0; y < H; y++)
			for (uint32_t x = 0; x < W; x++)
				for (int c = 0; c < 4; c++) {
					float sum = 0;
					for (int k = 0; k < 4; k++) {
						size_t i = (size_t)(2 * y + (k >> 1)) * 2 * W + 2 * x + (k & 1);
						sum += tu_half_to_float(big.hdr[f][4 * i + c]);
					}
					float want = sum / 4.0f;
					float got = tu_half_to_float(ss.hdr[f][4 * ((size_t)y * W + x) + c]);
					double d = fabs((double)got - (double)want) / fmax(fabs((double)want), 1e-4);
					if (d > worst)
						worst = d;
				}
	}
	printf("S1 ref-ssaa2 vs CPU box filter of ref at 2W x 2H: worst relative difference %.2e\n", worst);
	assert_true(worst <= 1.0 / 1024.0); /* one half-float rounding of the mean */
	tu_clip plain = tu_render_clip(dev, s, 0, "ref", NULL, NULL, W, H, F, false);
	tu_clip one = tu_render_clip(dev, s, 0, "ref-ssaa1", NULL, NULL, W, H, F, false);
	tu_assert_same_frames(&plain, &one, true);
	tu_clip *all[] = {&big, &ss, &opt, &plain, &one};
	for (size_t i = 0; i < 5; i++)
		tu_clip_free(all[i]);
	scene_destroy(&s);
	vkdev_destroy(&dev);
	printf("(%.1f s)\n", now_s() - t0);
}

/* ---- W1 ---- */

static void test_warp(void **state)
{
	(void)state;
	double t0 = now_s();
	vkdev *dev = tu_lavapipe();
	enum { W = 48, H = 32, F = 4 };
	scene *s = tu_load_scene("scenes/moderate.json");
	int cam = -1;
	for (size_t i = 0; i < s->camera_count && cam < 0; i++)
		if (s->cameras[i].motion == SCENE_CAMERA_MOVING)
			cam = (int)i;
	assert_true(cam >= 0);
	tu_clip ref = tu_render_clip(dev, s, cam, "ref", NULL, NULL, W, H, 3, false);
	tu_clip w1 = tu_render_clip(dev, s, cam, "warp/1", NULL, NULL, W, H, 3, false);
	tu_assert_same_frames(&ref, &w1, true);
	for (uint32_t f = 0; f < 3; f++)
		assert_int_equal(w1.st[f].shaded_samples, ref.st[f].shaded_samples);
	/* frame 1 extrapolated from frame 0: the moving camera disoccludes pixels, every hole is filled by pull-push */
	tu_clip wm = tu_render_clip(dev, s, cam, "warp/2", NULL, NULL, W, H, 2, false);
	printf("W1 warp/2 frame 1 (moderate, moving camera): holes %lld, filled %g, max difference to ref %d\n",
	       (long long)wm.st[1].new_units, tu_extra(&wm.st[1], "filled_samples"),
	       tu_max_diff(wm.disp[1], ref.disp[1], (size_t)W * H));
	assert_true(wm.st[1].new_units > 0);
	assert_true(tu_extra(&wm.st[1], "filled_samples") == (double)wm.st[1].new_units);
	assert_int_equal(wm.st[1].shaded_samples, 0);
	tu_clip_free(&wm);
	tu_clip_free(&ref);
	tu_clip_free(&w1);
	scene_destroy(&s);
	/* a panning camera over a lit floor (tests/data/rrc_pan.json) */
	s = tu_load_scene("rrc_pan");
	ref = tu_render_clip(dev, s, 0, "ref", NULL, NULL, W, H, F, false);
	tu_clip w2 = tu_render_clip(dev, s, 0, "warp/2", NULL, NULL, W, H, F, false);
	size_t px = (size_t)W * H;
	for (uint32_t f = 0; f < F; f++) {
		if (f % 2 == 0) {
			assert_memory_equal(w2.disp[f], ref.disp[f], px * 4);
			assert_int_equal(w2.st[f].shaded_samples, ref.st[f].shaded_samples);
			assert_true(tu_extra(&w2.st[f], "key_frame") == 1.0);
		} else {
			assert_int_equal(w2.st[f].shaded_samples, 0);
			assert_true(tu_extra(&w2.st[f], "key_frame") == 0.0);
			int mx = tu_max_diff(w2.disp[f], ref.disp[f], px);
			printf("W1 warp/2 frame %u (panning camera): holes %lld, filled %g, max difference to ref %d\n", f,
			       (long long)w2.st[f].new_units, tu_extra(&w2.st[f], "filled_samples"), mx);
			assert_true(tu_extra(&w2.st[f], "filled_samples") == (double)w2.st[f].new_units);
			assert_true(mx <= 8);
		}
	}
	/* determinism */
	tu_clip again = tu_render_clip(dev, s, 0, "warp/2", NULL, NULL, W, H, F, false);
	tu_assert_same_frames(&w2, &again, true);
	tu_clip *all[] = {&ref, &w2, &again};
	for (size_t i = 0; i < 3; i++)
		tu_clip_free(all[i]);
	scene_destroy(&s);
	/* a static view: the keyframe reprojected onto itself, every frame equals ref */
	s = tu_load_scene("tfr_static");
	ref = tu_render_clip(dev, s, 0, "ref", NULL, NULL, W, H, 4, false);
	w2 = tu_render_clip(dev, s, 0, "warp/4", NULL, NULL, W, H, 4, false);
	tu_assert_same_frames(&ref, &w2, true);
	for (uint32_t f = 1; f < 4; f++) {
		assert_int_equal(w2.st[f].shaded_samples, 0);
		assert_int_equal(w2.st[f].new_units, 0);
	}
	tu_clip_free(&ref);
	tu_clip_free(&w2);
	/* at 49x31 (no 4x4 decide block, 8x8 workgroup or pyramid level divides it: levels 25x16, 13x8, ...): the static
	 * view still equals ref; on moderate's moving camera every hole of frame 1 is filled */
	enum { W2 = 49, H2 = 31 };
	ref = tu_render_clip(dev, s, 0, "ref", NULL, NULL, W2, H2, 3, false);
	w2 = tu_render_clip(dev, s, 0, "warp/4", NULL, NULL, W2, H2, 3, false);
	tu_assert_same_frames(&ref, &w2, true);
	tu_clip_free(&ref);
	tu_clip_free(&w2);
	scene_destroy(&s);
	s = tu_load_scene("scenes/moderate.json");
	w2 = tu_render_clip(dev, s, cam, "warp/2", NULL, NULL, W2, H2, 2, false);
	printf("W1 warp/2 frame 1 at %dx%d (moderate, moving camera): holes %lld, filled %g\n", W2, H2,
	       (long long)w2.st[1].new_units, tu_extra(&w2.st[1], "filled_samples"));
	assert_true(w2.st[1].new_units > 0);
	assert_true(tu_extra(&w2.st[1], "filled_samples") == (double)w2.st[1].new_units);
	tu_clip_free(&w2);
	scene_destroy(&s);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	vkdev_destroy(&dev);
	printf("(%.1f s)\n", now_s() - t0);
}

/* ---- bad input ---- */

static void test_bad_variants(void **state)
{
	(void)state;
	const char *bad[] = {"warp", "warp/0", "warp/17", "rrc-random", "rrc-random/3", "rrc-interleaved/16",
			     "ref-ssaa5", "ref-ssaa", "ref-ssaa0", "ref-ssaa2-ssaa2", "warp-ssaa2/2", "ref@8",
			     "stu", "stu/3", "stu/1", "amss/4", "amss@2"};
	for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
		method_config c;
		char err[512] = "";
		int rc = method_config_parse_variant(&c, bad[i], err, sizeof err);
		printf("refused %-20s %s\n", bad[i], err);
		assert_int_equal(rc, TL_ERR_ARG);
		assert_true(err[0] != 0);
	}
	method_config c;
	char err[512], buf[64];
	assert_int_equal(method_config_parse_variant(&c, "ref-ssaa2", err, sizeof err), 0);
	method_config_variant(&c, buf, sizeof buf);
	assert_string_equal(buf, "ref-ssaa2");
	method_config_id(&c, buf, sizeof buf);
	assert_string_equal(buf, "ref-ssaa2");
	assert_int_equal(method_config_parse_variant(&c, "ref-ssaa1", err, sizeof err), 0);
	method_config_variant(&c, buf, sizeof buf);
	assert_string_equal(buf, "ref");
	assert_int_equal(method_config_parse_variant(&c, "rrc-interleaved/8", err, sizeof err), 0);
	method_config_id(&c, buf, sizeof buf);
	assert_string_equal(buf, "rrc-interleaved-N8");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_bad_variants),
		cmocka_unit_test(test_ssaa),
		cmocka_unit_test(test_warp),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
