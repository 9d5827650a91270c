/* test_vbuf.c — the compacted sample path (BASELINES.md section 0), vref and ads (A8): acceptance checks of
 * BASELINES.md section C on lavapipe with the validation layer (any message fails):
 *  B1  vref vs ref on every built-in scene: p99 of the per-pixel max-RGB difference <= 1 code value, the maximum
 *      frozen; shaded = visible, counted by the shading itself; nothing filled, every listed sample shaded;
 *  B3  (vref part) flat: shaded = covered pixels;
 *  D1  flat at 65x65: ads shades exactly the 17 x 17 grid of level 0 and interpolates the rest; frames equal vref;
 *  D2  ads with S < 0 and ads --force-reshade equal vref (display and HDR) and shade every covered pixel;
 *  D3  ramp (linear in the linear HDR values across the view: the bilinear magnification between two texels of
 *      an sRGB texture, decoded before filtering), S = 255: within 1 code value of vref while interpolating most
 *      pixels;
 *  D4  the shaded count of ads equals a CPU replay of its decisions on the frame's own values at 64x64 (raw display,
 *      so disp() is known on the CPU); the shaded count does not increase with S and never drops below the covered
 *      pixels of level 0;
 *  determinism (same inputs, same frames) and every built-in scene with every method of the path (VRS: 2 frames, the
 *  second runs the rate pass on the first's history). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_vk.h"

#include "taslab/colour.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

static const char *const builtin[] = {"scenes/calm.json", "scenes/moderate.json", "scenes/dynamic.json",
				      "scenes/turntable.json"};
enum { NBUILTIN = sizeof builtin / sizeof builtin[0] };

/* p-th percentile and maximum of the per-pixel max-RGB display difference over all frames of two clips. */
static void diff_stats(const tu_clip *a, const tu_clip *b, double p, int *pct, int *max)
{
	size_t px = (size_t)a->w * a->h, n = px * a->n;
	size_t hist[256] = {0};
	*max = 0;
	for (uint32_t f = 0; f < a->n; f++)
		for (size_t i = 0; i < px; i++) {
			int m = tu_max_diff(a->disp[f] + 4 * i, b->disp[f] + 4 * i, 1);
			hist[m]++;
			if (m > *max)
				*max = m;
		}
	size_t want = (size_t)ceil(p * (double)n), acc = 0;
	*pct = 0;
	for (int k = 0; k < 256; k++) {
		acc += hist[k];
		if (acc >= want) {
			*pct = k;
			break;
		}
	}
}

/* ---- B1 ---- */

static void test_vref_vs_ref(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	enum { W = 96, H = 64, F = 3 };
	for (int k = 0; k < NBUILTIN; k++) {
		scene *s = tu_load_scene(builtin[k]);
		tu_clip ref = tu_render_clip(dev, s, 0, "ref", NULL, NULL, W, H, F, false);
		tu_clip v = tu_render_clip(dev, s, 0, "vref", NULL, NULL, W, H, F, false);
		int p99, mx;
		diff_stats(&ref, &v, 0.99, &p99, &mx);
		printf("B1 %s: vref vs ref p99 %d, max %d code values\n", builtin[k], p99, mx);
		assert_true(p99 <= 1);
		/* frozen: the largest seen (0 / 1 with quad-difference gradients; analytic: p99 3, max 15). vref shades in
		 * another pipeline than ref: exact on lavapipe, on a GPU its compiler contracts differently (FMA; an H200,
		 * 2026-11-27: max 2 on moderate, p99 1), so there the bound is 4, still far under analytic gradients' 15 */
		assert_true(mx <= (TU_ON_LAVAPIPE ? 1 : 4));
		for (uint32_t f = 0; f < F; f++) {
			assert_int_equal(v.st[f].visible_samples, ref.st[f].visible_samples);
			assert_int_equal(v.st[f].shaded_samples, v.st[f].visible_samples);
			assert_int_equal(v.st[f].reused_samples, 0);
			assert_true(tu_extra(&v.st[f], "filled_samples") == 0);
			assert_true(tu_extra(&v.st[f], "listed_samples") == (double)v.st[f].shaded_samples);
			assert_true(tu_extra(&v.st[f], "tiles_1x1") == (double)(((W + 15) / 16) * ((H + 15) / 16)));
			assert_true(tu_extra(&v.st[f], "tiles_4x4") == 0);
			/* issue 32.5: the path has no rasterized shading pass, so the pipeline-statistics query is not recorded
			 * and not read: waiting on a query never written hung NVIDIA's driver (H200, 580.159) */
			assert_int_equal(v.st[f].fs_invocations, -1);
			assert_true(ref.st[f].fs_invocations > 0);
		}
		tu_clip_free(&ref);
		tu_clip_free(&v);
		scene_destroy(&s);
	}
	vkdev_destroy(&dev);
}

/* ---- determinism; every built-in scene with every method ---- */

static const char *const path_methods[] = {"vref",     "ads",     "ads@0", "ads@8", "ads-edge-guard",
					    "casedge", "castexel", "mas",   "fovea", "taas"};

static void test_builtin_every_method(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	enum { W = 64, H = 48, F = 2 };
	for (int k = 0; k < NBUILTIN; k++) {
		scene *s = tu_load_scene(builtin[k]);
		tu_clip v = tu_render_clip(dev, s, 0, "vref", NULL, NULL, W, H, F, false);
		for (size_t m = 0; m < sizeof path_methods / sizeof path_methods[0]; m++) {
			const char *edge[] = {"edge-guard", NULL};
			bool eg = strstr(path_methods[m], "edge") != NULL;
			tu_clip c = tu_render_clip(dev, s, 0, eg ? "ads" : path_methods[m], eg ? edge : NULL, NULL, W, H, F, false);
			for (uint32_t f = 0; f < F; f++) {
				const frame_stats *st = &c.st[f];
				assert_int_equal(st->visible_samples, v.st[f].visible_samples);
				assert_true(st->shaded_samples > 0 && st->shaded_samples <= st->visible_samples);
				assert_int_equal(st->reused_samples, st->visible_samples - st->shaded_samples);
				assert_true(tu_extra(st, "listed_samples") == (double)st->shaded_samples);
				if (strncmp(path_methods[m], "ads", 3) == 0)
					assert_true(tu_extra(st, "interpolated_samples") ==
						    (double)(st->visible_samples - st->shaded_samples));
			}
			printf("%s %s: shaded %.3f of visible\n", builtin[k], path_methods[m],
			       (double)c.st[F - 1].shaded_samples / (double)c.st[F - 1].visible_samples);
			tu_clip_free(&c);
		}
		tu_clip_free(&v);
		scene_destroy(&s);
	}
	vkdev_destroy(&dev);
}

static void test_determinism(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("scenes/dynamic.json");
	const char *variants[] = {"vref", "ads@2"};
	for (int k = 0; k < 2; k++) {
		tu_clip a = tu_render_clip(dev, s, 0, variants[k], NULL, NULL, 80, 56, 3, false);
		tu_clip b = tu_render_clip(dev, s, 0, variants[k], NULL, NULL, 80, 56, 3, false);
		tu_assert_same_frames(&a, &b, true);
		for (uint32_t f = 0; f < 3; f++)
			assert_int_equal(a.st[f].shaded_samples, b.st[f].shaded_samples);
		tu_clip_free(&a);
		tu_clip_free(&b);
	}
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* ---- D1, B3 (vref) ---- */

static void test_flat(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("vbuf_flat");
	enum { W = 65, H = 65, F = 2 };
	tu_clip v = tu_render_clip(dev, s, 0, "vref", NULL, NULL, W, H, F, false);
	tu_clip a = tu_render_clip(dev, s, 0, "ads", NULL, NULL, W, H, F, false);
	for (uint32_t f = 0; f < F; f++) {
		assert_int_equal(v.st[f].visible_samples, W * H); /* the plane fills the view */
		assert_int_equal(v.st[f].shaded_samples, W * H);
		assert_int_equal(a.st[f].shaded_samples, 17 * 17); /* x, y in {0, 4, ..., 64} */
		assert_true(tu_extra(&a.st[f], "interpolated_samples") == W * H - 17 * 17);
	}
	tu_assert_same_frames(&v, &a, true);
	tu_clip_free(&v);
	tu_clip_free(&a);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* ---- D2 ---- */

static void test_full_setting(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("scenes/moderate.json");
	enum { W = 72, H = 48, F = 2 };
	tu_clip v = tu_render_clip(dev, s, 0, "vref", NULL, NULL, W, H, F, false);
	tu_clip a = tu_render_clip(dev, s, 0, "ads@-1", NULL, NULL, W, H, F, false);
	const char *force[] = {"force-reshade", NULL};
	tu_clip b = tu_render_clip(dev, s, 0, "ads@8", force, NULL, W, H, F, false);
	tu_assert_same_frames(&v, &a, true);
	tu_assert_same_frames(&v, &b, true);
	for (uint32_t f = 0; f < F; f++) {
		assert_int_equal(a.st[f].shaded_samples, v.st[f].visible_samples);
		assert_int_equal(b.st[f].shaded_samples, v.st[f].visible_samples);
		assert_true(tu_extra(&a.st[f], "interpolated_samples") == 0);
	}
	tu_clip_free(&v);
	tu_clip_free(&a);
	tu_clip_free(&b);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* ---- D3 ---- */

static void test_ramp(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("vbuf_ramp");
	colour *raw = tu_raw_colour();
	enum { W = 65, H = 65 }; /* the grid reaches the borders (else border pixels extrapolate from one side) */
	tu_clip v = tu_render_clip(dev, s, 0, "vref", NULL, raw, W, H, 1, false);
	tu_clip a = tu_render_clip(dev, s, 0, "ads@255", NULL, raw, W, H, 1, false);
	int d = tu_max_diff(v.disp[0], a.disp[0], (size_t)W * H);
	printf("D3: ramp, ads@255 vs vref: max %d code values, %lld of %lld shaded\n", d, (long long)a.st[0].shaded_samples,
	       (long long)a.st[0].visible_samples);
	/* BASELINES.md D3: within 1 code value (raw display: code values are linear in the HDR values ads interpolates) */
	assert_true(d <= 1);
	/* and the ramp is a ramp: it spans more than 100 code values across the view */
	int lo = 255, hi = 0;
	for (size_t i = 0; i < (size_t)W * H; i++) {
		lo = v.disp[0][4 * i] < lo ? v.disp[0][4 * i] : lo;
		hi = v.disp[0][4 * i] > hi ? v.disp[0][4 * i] : hi;
	}
	printf("D3: vref spans code values %d..%d\n", lo, hi);
	assert_true(hi - lo > 100);
	assert_true(a.st[0].shaded_samples < a.st[0].visible_samples / 4); /* most pixels interpolated */
	tu_clip_free(&v);
	tu_clip_free(&a);
	colour_destroy(&raw);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* ---- D4 ---- */

/* The ads decisions replayed on the CPU from the frame's own values (each pixel's value is what the GPU stored for
 * it: shaded or interpolated), with the raw display (disp(h) = clamp(h, 0, 1) * 255); float arithmetic in the
 * shader's order. Returns the shaded count. */
static int64_t ads_replay(const uint16_t *hdr, int W, int H, int s0, float S)
{
	int64_t shaded = 0;
#define COVERED(x, y) (tu_half_to_float(hdr[4 * ((size_t)(y) * W + (x)) + 3]) != 0.0f)
	for (int y = 0; y < H; y += s0)
		for (int x = 0; x < W; x += s0)
			shaded += COVERED(x, y);
	for (int s = s0; s >= 2; s /= 2) {
		int h = s / 2;
		for (int kind = 1; kind <= 2; kind++)
			for (int y = 0; y < H; y++)
				for (int x = 0; x < W; x++) {
					bool on = kind == 1 ? (x % s == h && y % s == h)
							    : ((x % s == h && y % s == 0) || (x % s == 0 && y % s == h));
					if (!on || !COVERED(x, y))
						continue;
					int nb[4][2];
					if (kind == 1) {
						int d[4][2] = {{-h, -h}, {h, -h}, {-h, h}, {h, h}};
						memcpy(nb, d, sizeof nb);
					} else {
						int d[4][2] = {{-h, 0}, {h, 0}, {0, -h}, {0, h}};
						memcpy(nb, d, sizeof nb);
					}
					float v[4][3], sum[3] = {0, 0, 0};
					int n = 0;
					for (int k = 0; k < 4; k++) {
						int xx = x + nb[k][0], yy = y + nb[k][1];
						if (xx < 0 || yy < 0 || xx >= W || yy >= H || !COVERED(xx, yy))
							continue;
						for (int c = 0; c < 3; c++) {
							float hv = tu_half_to_float(hdr[4 * ((size_t)yy * W + xx) + c]);
							v[n][c] = fminf(fmaxf(hv, 0.0f), 1.0f) * 255.0f;
							sum[c] += v[n][c];
						}
						n++;
					}
					bool shade = n < 2 || S < 0;
					if (!shade) {
						float var[3] = {0, 0, 0};
						for (int c = 0; c < 3; c++) {
							float mean = sum[c] / (float)n;
							for (int k = 0; k < n; k++)
								var[c] += (v[k][c] - mean) * (v[k][c] - mean);
							var[c] /= (float)n;
						}
						shade = sqrtf(fmaxf(var[0], fmaxf(var[1], var[2]))) > S;
					}
					shaded += shade;
				}
	}
#undef COVERED
	return shaded;
}

static void test_replay(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("scenes/calm.json");
	colour *raw = tu_raw_colour();
	enum { W = 64, H = 64, F = 2 };
	const float Ss[] = {0, 0.5f, 1, 2, 4, 8, 32, 255};
	int64_t last = INT64_MAX;
	for (size_t k = 0; k < sizeof Ss / sizeof Ss[0]; k++) {
		char var[32];
		snprintf(var, sizeof var, "ads@%g", (double)Ss[k]);
		tu_clip a = tu_render_clip(dev, s, 0, var, NULL, raw, W, H, F, false);
		int64_t level0 = 0;
		for (int y = 0; y < H; y += 4)
			for (int x = 0; x < W; x += 4)
				level0 += tu_half_to_float(a.hdr[F - 1][4 * ((size_t)y * W + x) + 3]) != 0.0f;
		for (uint32_t f = 0; f < F; f++) {
			int64_t want = ads_replay(a.hdr[f], W, H, 4, Ss[k]);
			if (want != a.st[f].shaded_samples)
				fail_msg("%s frame %u: shaded %lld, CPU replay %lld", var, f, (long long)a.st[f].shaded_samples,
					 (long long)want);
		}
		int64_t sh = a.st[F - 1].shaded_samples;
		printf("D4 %s: shaded %lld of %lld (%.3f)\n", var, (long long)sh, (long long)a.st[F - 1].visible_samples,
		       (double)sh / (double)a.st[F - 1].visible_samples);
		assert_true(sh <= last);
		assert_true(sh >= level0);
		last = sh;
		tu_clip_free(&a);
	}
	colour_destroy(&raw);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_flat),	     cmocka_unit_test(test_full_setting), cmocka_unit_test(test_ramp),
		cmocka_unit_test(test_replay),	     cmocka_unit_test(test_determinism),  cmocka_unit_test(test_vref_vs_ref),
		cmocka_unit_test(test_builtin_every_method),
	};
	if (getenv("TU_FILTER")) /* iterating on one case: TU_FILTER=test_ramp build-test/tests/test_vbuf */
		cmocka_set_test_filter(getenv("TU_FILTER"));
	return cmocka_run_group_tests(tests, NULL, NULL);
}
