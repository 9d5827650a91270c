/* test_reuse_checks.c — acceptance checks of TAS-METHODS section 9 for rrc and tarc that look inside the cache
 * (renderer/src/methods/method_debug.h) or compare runs, on lavapipe with the validation layer (any message fails);
 * test_reuse.c has the others:
 *  R3  rrc under a constant sub-pixel pan (diffuse floor, static lamp): with bilinear lookups the error against ref
 *      grows with the frames since the tile's refresh (each reuse resamples once more) and is 0 when refreshed;
 *      with nearest lookups the shown value lags the surface by at most n |v| pixels (n frames since refresh,
 *      v the pan in pixels per frame), checked at pixel resolution (the lamp stands left of the view, so the
 *      floor's shading falls monotonically along every row);
 *  T4  the stored gradient: on a linear light ramp (raw OCIO config, display = linear) every pixel's cached g is the
 *      change per frame between its last two shadings, measured here on ref's frames, and that equals the ramp's
 *      constant slope up to the half-float rounding of the two values (the reshade intervals are in test_reuse);
 *  T6  clip-mean reuse of tarc is non-decreasing in T in {2, 4, 8, 16, 32, 64} on a built-in scene. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_vk.h"

#include "../renderer/src/methods/method_debug.h"
#include "taslab/colour.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

/* disp(x) of the raw config for one channel: the clamped HDR value in code values (TAS-METHODS section 0) */
static float raw_cv(uint16_t h) { return fminf(fmaxf(tu_half_to_float(h), 0), 1) * 255.0f; }

/* max over RGB of the raw display difference of two HDR pixels */
static float raw_maxrgb(const uint16_t *a, const uint16_t *b)
{
	float m = 0;
	for (int k = 0; k < 3; k++)
		m = fmaxf(m, fabsf(raw_cv(a[k]) - raw_cv(b[k])));
	return m;
}

/* ---- R3 ---- */

static void test_rrc_pan(void **state)
{
	(void)state;
	scene *s = tu_load_scene("rrc_pan");
	vkdev *dev = tu_lavapipe();
	enum { N = 4, F = 20, W = 96, H = 64 };
	/* the pan in pixels per frame: the camera moves at a constant speed (two keys: the Hermite path is the chord)
	 * over a floor at depth h, looking straight down; fovy gives f = 1 / tan(fovy / 2) and H / 2 pixels per f */
	const scene_camera *cam = &s->cameras[0];
	double speed = fabs((double)cam->keys[1].position.x - cam->keys[0].position.x) / (cam->keys[1].t - cam->keys[0].t);
	double v = speed / s->fps * (1.0 / tan(cam->fov_deg * TLM_PI / 360.0)) * (H / 2.0) / cam->keys[0].position.y;
	assert_true(v > 0.1 && v < 0.5); /* sub-pixel: nearest lookups keep each pixel's own value */
	tu_clip ref = tu_render_clip(dev, s, 0, "ref", NULL, NULL, W, H, F, false);
	const char *nearest[] = {"resample=nearest", NULL};
	tu_clip bil = tu_render_clip(dev, s, 0, "rrc/4", NULL, NULL, W, H, F, true);
	tu_clip nea = tu_render_clip(dev, s, 0, "rrc/4", nearest, NULL, W, H, F, true);
	uint32_t tiles_x = (W + 15) / 16;
	/* pixels whose cache chain since the refresh stays in their tile and away from the frame's edges: content
	 * moves at most N v < 2 pixels across the frames of a period */
	int margin = (int)ceil(N * v) + 1;
	double sum[N] = {0};
	size_t cnt[N] = {0}, checked = 0;
	for (uint32_t t = N; t < F; t++)
		for (int y = 0; y < H; y++)
			for (int x = margin; x < W - margin; x++) {
				if (x % 16 < margin || x % 16 > 15 - margin)
					continue;
				size_t i = (size_t)y * W + x;
				uint32_t n = (t + (uint32_t)(y >> 4) * tiles_x + (uint32_t)(x >> 4)) % N;
				frame_decision want = n == 0 ? FRAME_DECISION_SCHEDULED : FRAME_DECISION_REUSED;
				assert_int_equal(bil.dec[t][i], want);
				assert_int_equal(nea.dec[t][i], want);
				sum[n] += raw_maxrgb(bil.hdr[t] + 4 * i, ref.hdr[t] + 4 * i);
				cnt[n]++;
				/* nearest: the shown value is ref's somewhere within n v pixels along the pan, i.e. (at pixel
				 * resolution, between pixel centres the floor's shading is monotone) within the range of ref's
				 * pixels within ceil(n v) of it; one half-float ulp for the rounding of the two shadings */
				int K = (int)ceil(n * v);
				for (int c = 0; c < 3; c++) {
					float got = raw_cv(nea.hdr[t][4 * i + c]), lo = 1e30f, hi = -1e30f;
					for (int k = -K; k <= K; k++) {
						float r = raw_cv(ref.hdr[t][4 * (i + k) + c]);
						lo = fminf(lo, r), hi = fmaxf(hi, r);
					}
					float a = fmaxf(got / 255.0f, 6.1e-5f), ulp = ldexpf(1.0f, (int)floorf(log2f(a)) - 10) * 255.0f;
					if (got < lo - ulp || got > hi + ulp)
						fail_msg("nearest, frame %u pixel (%d,%d), %u frames since refresh: %.3f outside ref's "
							 "[%.3f, %.3f] within %d pixels (lag > n |v| = %.2f)",
							 t, x, y, n, (double)got, (double)lo, (double)hi, K, n * v);
				}
				checked++;
			}
	double mean[N];
	for (int n = 0; n < N; n++) {
		assert_true(cnt[n] > 100);
		mean[n] = sum[n] / (double)cnt[n];
		print_message("R3: pan %.3f px/frame, bilinear, %d frames since refresh: mean max-RGB vs ref %.5f (%zu px)\n", v,
			      n, mean[n], cnt[n]);
	}
	assert_true(mean[0] == 0); /* refreshed tiles are ref's shading */
	for (int n = 1; n < N; n++)
		assert_true(mean[n] > mean[n - 1]); /* each reuse resamples once more */
	assert_true(checked > 1000);
	tu_clip_free(&ref);
	tu_clip_free(&bil);
	tu_clip_free(&nea);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* ---- T4: the stored gradient ---- */

static void test_tarc_stored_gradient(void **state)
{
	(void)state;
	char err[1024];
	scene *s = tu_load_scene("tarc_ramp");
	vkdev *dev = tu_lavapipe();
	colour *col = tu_raw_colour();
	enum { F = 24, W = 64, H = 48 }; /* the floor covers the whole frame */
	size_t px = (size_t)W * H;
	tu_clip ref = tu_render_clip(dev, s, 0, "ref", NULL, col, W, H, F, false);
	/* the ramp's slope per pixel over the clip (the shading is linear in the lamp's intensity) */
	float *slope = malloc(px * sizeof *slope);
	for (size_t i = 0; i < px; i++)
		slope[i] = raw_maxrgb(ref.hdr[F - 1] + 4 * i, ref.hdr[0] + 4 * i) / (float)(F - 1);
	const char *variants[] = {"tarc@4", "tarc@8"};
	for (int v = 0; v < 2; v++) {
		render *r = tu_render_open(dev, s, 0, variants[v], NULL, col, W, H, true);
		uint32_t *last = calloc(px, sizeof *last), *prev = calloc(px, sizeof *prev);
		float *stored = calloc(px, sizeof *stored);
		size_t compared = 0, reshades = 0;
		double worst = 0;
		for (uint32_t f = 0; f < F; f++) {
			frame_image img;
			frame_stats st;
			if (render_frame(r, f, &img, &st, err, sizeof err))
				fail_msg("%s", err);
			const uint32_t *cache = reproj_debug_state(r);
			assert_non_null(cache);
			for (size_t i = 0; i < px; i++) {
				uint8_t d = img.decisions[i];
				float g;
				memcpy(&g, &cache[4 * i + 3], sizeof g);
				assert_true(d != FRAME_DECISION_NONE);
				if (d == FRAME_DECISION_REUSED) {
					assert_true(g == stored[i]); /* carried over unchanged */
					continue;
				}
				prev[i] = last[i], last[i] = f;
				stored[i] = g;
				if (d == FRAME_DECISION_NEW) {
					assert_true(f == 0 && g == 0.0f); /* no difference yet */
					continue;
				}
				/* g = d(s, C') / a': the change since the previous shading per frame, on ref's values */
				uint32_t age = f - prev[i];
				float want = raw_maxrgb(ref.hdr[f] + 4 * i, ref.hdr[prev[i]] + 4 * i) / (float)age;
				if (fabsf(g - want) > 1e-3f) /* float arithmetic on the same half values */
					fail_msg("%s frame %u pixel %zu: stored g %.6f, ref's change per frame %.6f (age %u)", variants[v],
						 f, i, (double)g, (double)want, age);
				/* and that is the ramp's per-frame change, up to the half-float rounding of both values (half an
				 * ulp each, in code values, over the age) */
				float tol = 0;
				for (int c = 0; c < 3; c++) {
					float a = fabsf(tu_half_to_float(ref.hdr[f][4 * i + c])), b = fabsf(tu_half_to_float(ref.hdr[prev[i]][4 * i + c]));
					float ua = ldexpf(1.0f, (a > 6.1e-5f ? (int)floorf(log2f(a)) : -14) - 10);
					float ub = ldexpf(1.0f, (b > 6.1e-5f ? (int)floorf(log2f(b)) : -14) - 10);
					tol = fmaxf(tol, 0.5f * (ua + ub) * 255.0f / (float)age);
				}
				tol += 0.5f * 255.0f * ldexpf(1.0f, -10) / (float)(F - 1); /* the slope's own rounding, roughly */
				if (fabsf(g - slope[i]) > tol)
					fail_msg("%s frame %u pixel %zu: stored g %.6f, ramp slope %.6f (tolerance %.6f)", variants[v], f,
						 i, (double)g, (double)slope[i], (double)tol);
				worst = fmax(worst, fabs(g - slope[i]) / slope[i]);
				compared++;
				reshades += d == FRAME_DECISION_PREDICTED;
			}
		}
		print_message("T4 %s: %zu stored gradients compared (%zu after predicted reshades), largest relative "
			      "deviation from the slope %.4f\n", variants[v], compared, reshades, worst);
		assert_true(compared >= px && reshades >= px); /* the second frame and at least one predicted reshade */
		free(last);
		free(prev);
		free(stored);
		render_destroy(&r);
	}
	assert_int_equal(vkdev_validation_messages(dev), 0);
	free(slope);
	tu_clip_free(&ref);
	colour_destroy(&col);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* ---- T6 ---- */

static void test_tarc_reuse_monotone(void **state)
{
	(void)state;
	/* a stationary path with local changes (falling boulders); at this size the filter's 72x72-pixel footprint
	 * still covers much of the frame, so reuse is low at small T, but it must not fall as T rises */
	scene *s = tu_load_scene("scenes/moderate.json");
	vkdev *dev = tu_lavapipe();
	int cam = tu_camera_index(s, "boulders");
	enum { F = 16, W = 96, H = 54 };
	const char *variants[] = {"tarc@2", "tarc@4", "tarc@8", "tarc@16", "tarc@32", "tarc@64"};
	double prev = -1;
	for (int k = 0; k < 6; k++) {
		tu_clip c = tu_render_clip(dev, s, cam, variants[k], NULL, NULL, W, H, F, false);
		double reuse = 0;
		for (uint32_t f = 0; f < F; f++)
			reuse += (double)c.st[f].reused_samples / (double)c.st[f].visible_samples / F; /* clip mean */
		print_message("T6: %s clip-mean reuse %.4f\n", variants[k], reuse);
		if (reuse < prev)
			fail_msg("%s reuses %.4f, less than %s (%.4f)", variants[k], reuse, variants[k - 1], prev);
		prev = reuse;
		tu_clip_free(&c);
	}
	assert_true(prev > 0.3); /* and T = 64 does reuse */
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_rrc_pan),
		cmocka_unit_test(test_tarc_stored_gradient),
		cmocka_unit_test(test_tarc_reuse_monotone),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
