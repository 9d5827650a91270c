/* test_vrs.c — the VRS rate methods on the compacted sample path (BASELINES.md A7 and section C), on lavapipe with the
 * validation layer (any message fails):
 *  B2  every VRS method at its full setting (--force-reshade; fovea also with --inner 180) equals vref;
 *  B3  flat (one colour) under casedge's coarse rates equals vref, and the shaded count equals the CPU count of
 *      distinct (coarse pixel, object, triangle) from the frame's ids image and tile rates;
 *  V1  the stabiliser on constant-r sequences: the index goes 10 -> settles at min(r + 2, 10) (split, pan);
 *  V2  split (black | white at a tile boundary): E_s = 1/16 at the two edge tiles and 0 elsewhere, r = 0, every tile
 *      4x4 from frame 1, frames equal vref;
 *  V3  pan, mas, from frame 2: v = 0 -> r 10 (1x1), v = 12 px/frame -> r 2 (2x2), v >= 16 -> r 0 (4x4);
 *  V6  fovea: the tile rates equal a CPU replica of the eccentricity rule. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_vk.h"

#include "../renderer/src/methods/method_debug.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/tl_math.h"
#include "taslab/vkdev.h"

#include "test_vrs.h"

static void frame_of(render *r, uint32_t f, frame_image *img, frame_stats *st)
{
	char err[1024];
	if (render_frame(r, f, img, st, err, sizeof err))
		fail_msg("frame %u: %s", f, err);
}

/* ---- B2 ---- */

static void test_full_setting(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("scenes/moderate.json");
	enum { W = 64, H = 48, F = 3 };
	tu_clip v = tu_render_clip(dev, s, 0, "vref", NULL, NULL, W, H, F, false);
	const char *methods[] = {"casedge", "castexel", "mas", "fovea", "taas"};
	const char *force[] = {"force-reshade", NULL}, *wide[] = {"inner=180", "outer=180", NULL};
	for (int k = 0; k < 5; k++)
		for (int o = 0; o < (k == 3 ? 2 : 1); o++) {
			tu_clip c = tu_render_clip(dev, s, 0, methods[k], o ? wide : force, NULL, W, H, F, false);
			tu_assert_same_frames(&v, &c, true);
			for (uint32_t f = 0; f < F; f++)
				assert_int_equal(c.st[f].shaded_samples, v.st[f].shaded_samples);
			tu_clip_free(&c);
		}
	tu_clip_free(&v);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* ---- V2, V1 (r = 0), B3 ---- */

static void test_split(void **state)
{
	(void)state;
	char err[1024];
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("vbuf_split");
	enum { W = 128, H = 48, F = 4 };
	tu_clip v = tu_render_clip(dev, s, 0, "vref", NULL, NULL, W, H, F, false);
	render *r = tu_render_open(dev, s, 0, "casedge", NULL, NULL, W, H, false);
	uint32_t *ids = malloc((size_t)W * H * 16);
	for (uint32_t f = 0; f < F; f++) {
		frame_image img;
		frame_stats st;
		frame_of(r, f, &img, &st);
		assert_int_equal(tu_max_diff(img.display_rgba, v.disp[f], (size_t)W * H), 0);
		uint32_t tx, ty;
		const int32_t *S;
		const float *dbg = vrs_debug_tiles(r, &S, &tx, &ty);
		const uint32_t *rates = vbuf_debug_rates(r);
		for (uint32_t t = 0; t < tx * ty; t++) {
			if (f == 0) {
				assert_int_equal(S[t], 10);
				assert_int_equal(rates[t], RATE(1, 1));
				continue;
			}
			uint32_t col = t % tx;
			/* the edge between pixels 63 and 64: tiles 3 and 4 of each row hold one column of edge pixels */
			float want = col == 3 || col == 4 ? 1.0f / 16.0f : 0.0f;
			if (fabsf(dbg[4 * t] - want) > 1e-6f)
				fail_msg("frame %u tile %u: E_s %g, expected %g", f, t, (double)dbg[4 * t], (double)want);
			assert_true(dbg[4 * t + 1] == 0.0f); /* r */
			assert_int_equal(S[t], 2);           /* min(r + 2, 10) */
			assert_int_equal(rates[t], RATE(4, 4));
		}
		if (f > 0)
			assert_true(tu_extra(&st, "tiles_4x4") == (double)(tx * ty));
		assert_int_equal(vbuf_debug_ids(r, ids, err, sizeof err), TL_OK);
		assert_int_equal(st.shaded_samples, tu_vrs_cpu_samples(ids, rates, W, H)); /* B3 */
		if (f > 0)
			assert_true(st.shaded_samples < st.visible_samples / 8);
	}
	free(ids);
	render_destroy(&r);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	tu_clip_free(&v);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* ---- V3, V1 ---- */

static void pan_case(vkdev *dev, scene *s, double v_want, int r_want)
{
	enum { W = 96, H = 64, F = 4 };
	/* the pan in pixels per frame: fronto-parallel floor at height h, fov 90: H / (2 h) pixels per metre */
	scene_camera *cam = &s->cameras[0];
	double speed = fabs((double)cam->keys[1].position.x - cam->keys[0].position.x) / (cam->keys[1].t - cam->keys[0].t);
	double ppm = H / (2.0 * cam->keys[0].position.y);
	float keep = s->fps;
	if (v_want == 0.0) {
		cam->keys[1].position = cam->keys[0].position;
		cam->keys[1].target = cam->keys[0].target;
	} else {
		s->fps = (float)(speed * ppm / v_want);
	}
	render *r = tu_render_open(dev, s, 0, "mas", NULL, NULL, W, H, false);
	int idx_want = r_want + 2 < 10 ? r_want + 2 : 10;
	uint32_t want_rate = idx_want <= 2 ? RATE(4, 4) : idx_want <= 5 ? RATE(2, 2) : RATE(1, 1);
	for (uint32_t f = 0; f < F; f++) {
		frame_image img;
		frame_stats st;
		frame_of(r, f, &img, &st);
		if (f < 2)
			continue;
		uint32_t tx, ty;
		const int32_t *S;
		const float *dbg = vrs_debug_tiles(r, &S, &tx, &ty);
		const uint32_t *rates = vbuf_debug_rates(r);
		int reached = 0;
		for (uint32_t t = 0; t < tx * ty; t++) {
			if (dbg[4 * t + 3] >= 0.0f && dbg[4 * t + 1] != (float)r_want)
				fail_msg("v %g frame %u tile %u: r %g (P' %g), expected %d", v_want, f, t, (double)dbg[4 * t + 1],
					 (double)dbg[4 * t], r_want);
			bool hit = false; /* a source tile lands here: its index and rate are the stabilised ones */
			for (uint32_t u = 0; u < tx * ty; u++)
				hit = hit || dbg[4 * u + 3] == (float)t;
			if (hit) {
				reached++;
				if (S[t] != idx_want || rates[t] != want_rate)
					fail_msg("v %g frame %u tile %u: index %d rate %#x, expected %d", v_want, f, t, S[t], rates[t],
						 idx_want);
			} else {
				assert_int_equal(S[t], 10); /* no source: 10 [P] */
			}
		}
		assert_true(reached >= (int)(tx * ty) / 2);
	}
	render_destroy(&r);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	s->fps = keep;
}

static void test_pan(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("vbuf_pan");
	pan_case(dev, s, 12.0, 2);
	pan_case(dev, s, 16.0, 0);
	pan_case(dev, s, 24.0, 0);
	pan_case(dev, s, 0.0, 10); /* last: it stops the camera */
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* ---- V6 ---- */

static void test_fovea(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("scenes/calm.json");
	enum { W = 160, H = 96 };
	const char *opts[] = {"gaze-x=0.3", "gaze-y=0.6", "inner=8", "outer=16", NULL};
	render *r = tu_render_open(dev, s, 0, "fovea", opts, NULL, W, H, false);
	frame_image img;
	frame_stats st;
	frame_of(r, 0, &img, &st);
	uint32_t tx, ty;
	const uint32_t *rates = vbuf_debug_rates(r);
	vrs_debug_tiles(r, NULL, &tx, &ty);
	double f = 1.0 / tan(s->cameras[0].fov_deg * TLM_PI / 360.0), fx = f / ((double)W / H);
	double gx = lround(0.3 * W), gy = lround(0.6 * H);
	int counts[3] = {0, 0, 0};
	for (uint32_t t = 0; t < tx * ty; t++) {
		double cx = (t % tx) * 16.0 + 0.5 * fmin(16.0, W - (t % tx) * 16.0);
		double cy = (t / tx) * 16.0 + 0.5 * fmin(16.0, H - (t / tx) * 16.0);
		double a[3] = {(gx / W * 2 - 1) / fx, (gy / H * 2 - 1) / f, 1}, b[3] = {(cx / W * 2 - 1) / fx, (cy / H * 2 - 1) / f, 1};
		double la = sqrt(a[0] * a[0] + a[1] * a[1] + 1), lb = sqrt(b[0] * b[0] + b[1] * b[1] + 1);
		double ecc = acos(fmin(1.0, (a[0] * b[0] + a[1] * b[1] + 1) / (la * lb))) * 180.0 / TLM_PI;
		if (fabs(ecc - 8.0) < 0.01 || fabs(ecc - 16.0) < 0.01)
			continue; /* on a boundary: float rounding decides */
		uint32_t want = ecc <= 8.0 ? RATE(1, 1) : ecc <= 16.0 ? RATE(2, 2) : RATE(4, 4);
		counts[ecc <= 8.0 ? 0 : ecc <= 16.0 ? 1 : 2]++;
		if (rates[t] != want)
			fail_msg("tile %u (eccentricity %.3f deg): rate %#x, expected %#x", t, ecc, rates[t], want);
	}
	assert_true(counts[0] > 0 && counts[1] > 0 && counts[2] > 0); /* all three rings present */
	render_destroy(&r);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_split),
		cmocka_unit_test(test_pan),
		cmocka_unit_test(test_fovea),
		cmocka_unit_test(test_full_setting),
	};
	if (getenv("TU_FILTER")) /* iterating on one case: TU_FILTER=test_ramp build-test/tests/test_vbuf */
		cmocka_set_test_filter(getenv("TU_FILTER"));
	return cmocka_run_group_tests(tests, NULL, NULL);
}
