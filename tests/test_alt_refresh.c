/* test_alt_refresh.c — the survey's random and interleaved refresh (BASELINES.md A2; section C) on lavapipe with the
 * validation layer (any message fails):
 *  R5  static view, N in {2, 4, 8}, rrc-random and rrc-interleaved (and rrc-random --group 2x2): the shaded count of
 *      every frame after the first equals a CPU count of eq. 1's refresh set (no misses on a static view: new_units
 *      0), so every covered pixel is shaded exactly once in N consecutive frames; frames equal vref (display, HDR);
 *  R6  N = 1 equals vref and shades every covered pixel;
 *  R7  --truth (BASELINES.md section 0): on the static view rrc-random/4 and rrc-interleaved/4 count 0 late at
 *      T = 0 (their frames equal vref); on moderate's moving camera warp/1 counts 0 and warp/2's extrapolated frame
 *      counts exactly the pixels whose display value is more than T from vref's (a CPU count); the truth interval
 *      is left out of the frame time; warp/4 with --truth keeps its keyframes at t mod 4 = 0 and its frames and
 *      counts (on extrapolated frames every second frame was a keyframe until 2026-11-27). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "test_vk.h"

#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

static double now_s(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- R5, R6 ---- */

/* The CPU replica of decide.comp.in's refresh rule (eq. 1 with the A2 patterns). */
static uint32_t pcg(uint32_t v)
{
	uint32_t st = v * 747796405u + 2891336453u;
	uint32_t word = ((st >> ((st >> 28u) + 4u)) ^ st) * 277803737u;
	return (word >> 22u) ^ word;
}

static bool refresh_due(bool random, uint32_t x, uint32_t y, uint32_t w, uint32_t t, uint32_t n, uint32_t gx,
			uint32_t gy)
{
	x /= gx, y /= gy;
	if (random)
		return (t + pcg(x + (w + gx - 1) / gx * y) % n) % n == 0;
	uint32_t a = n == 8 ? 4 : n == 4 ? 2 : n, b = n / a, k = t % n;
	return x % a == k % a && y % b == k / a;
}

static void test_refresh_patterns(void **state)
{
	(void)state;
	double t0 = now_s();
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("tfr_static");
	enum { W = 48, H = 32, F = 9 };
	tu_clip v = tu_render_clip(dev, s, 0, "vref", NULL, NULL, W, H, F, false);
	const char *const g22[] = {"group=2x2", NULL};
	for (int random = 0; random <= 1; random++)
		for (uint32_t n = random ? 1 : 2; n <= 8; n *= 2)
			for (int grouped = 0; grouped <= (random && n == 4); grouped++) {
				char var[32];
				snprintf(var, sizeof var, "%s/%u", random ? "rrc-random" : "rrc-interleaved", n);
				uint32_t frames = n + 1;
				tu_clip c = tu_render_clip(dev, s, 0, var, grouped ? g22 : NULL, NULL, W, H, frames, false);
				int64_t over_n = 0;
				for (uint32_t f = 0; f < frames; f++) {
					int64_t want = 0;
					for (uint32_t y = 0; y < H; y++)
						for (uint32_t x = 0; x < W; x++)
							want += tu_half_to_float(v.hdr[f][4 * ((size_t)y * W + x) + 3]) != 0.0f &&
								(f == 0 || refresh_due(random, x, y, W, f, n, grouped ? 2 : 1,
										       grouped ? 2 : 1));
					if (c.st[f].shaded_samples != want)
						fail_msg("R5 %s%s frame %u: shaded %lld, eq. 1 on the CPU %lld", var,
							 grouped ? " --group 2x2" : "", f, (long long)c.st[f].shaded_samples,
							 (long long)want);
					assert_int_equal(c.st[f].visible_samples, v.st[f].visible_samples);
					assert_int_equal(c.st[f].new_units, f == 0 ? c.st[f].visible_samples : 0);
					if (f >= 1 && f <= n)
						over_n += c.st[f].shaded_samples;
				}
				/* every covered pixel exactly once in N consecutive frames (frames 1..N) */
				assert_int_equal(over_n, v.st[1].visible_samples);
				tu_clip vv = v;
				vv.n = frames;
				tu_assert_same_frames(&c, &vv, true);
				printf("R5 %s%s: shaded %lld of %lld at frame 1, frames = vref\n", var,
				       grouped ? " --group 2x2" : "", (long long)c.st[1].shaded_samples,
				       (long long)c.st[1].visible_samples);
				tu_clip_free(&c);
			}
	tu_clip_free(&v);
	scene_destroy(&s);
	vkdev_destroy(&dev);
	printf("(%.1f s)\n", now_s() - t0);
}

/* ---- R7 ---- */

static int64_t cpu_late(const uint8_t *a, const uint8_t *b, const uint16_t *hdr, size_t px, int T)
{
	int64_t n = 0;
	for (size_t i = 0; i < px; i++)
		n += tu_half_to_float(hdr[4 * i + 3]) != 0.0f && tu_max_diff(a + 4 * i, b + 4 * i, 1) > T;
	return n;
}

static void assert_truth_left_out(const tu_clip *c)
{
	for (uint32_t f = 0; f < c->n; f++) {
		double sum = 0;
		for (uint32_t p = 0; p < c->st[f].pass_count; p++)
			if (strcmp(c->st[f].pass_names[p], "truth"))
				sum += c->st[f].gpu_ms[p];
		assert_true(fabs(sum - c->st[f].gpu_ms_total) < 1e-6 * (1 + sum));
	}
}

static void test_truth(void **state)
{
	(void)state;
	double t0 = now_s();
	vkdev *dev = tu_lavapipe();
	enum { W = 48, H = 32, F = 5 };
	const char *const t0opt[] = {"truth", "truth-threshold=0", NULL};
	const char *const t8opt[] = {"truth", NULL};
	/* static view: the rrc variants' frames equal vref's (R5), so 0 late at T = 0 on every frame */
	scene *s = tu_load_scene("tfr_static");
	const char *const vars[] = {"rrc-random/4", "rrc-interleaved/4"};
	for (size_t i = 0; i < 2; i++) {
		tu_clip c = tu_render_clip(dev, s, 0, vars[i], t0opt, NULL, W, H, F, false);
		for (uint32_t f = 0; f < F; f++)
			if (c.st[f].late_samples != 0)
				fail_msg("R7 %s frame %u: late %lld, want 0", vars[i], f, (long long)c.st[f].late_samples);
		assert_truth_left_out(&c);
		printf("R7 %s --truth-threshold 0 on a static view: 0 late on %d frames\n", vars[i], F);
		tu_clip_free(&c);
	}
	scene_destroy(&s);
	/* moderate's moving camera: warp/1 (ref) 0 late; warp/2's keyframe 0 late, its extrapolated frame 1 late
	 * exactly where its display value is more than T from vref's. The truth pass compares unrounded display values,
	 * the CPU 8-bit ones (< 1 apart), so the count is exact at a T where no covered pixel's 8-bit difference is
	 * T or T + 1: T = 26 here (asserted) */
	s = tu_load_scene("scenes/moderate.json");
	int cam = -1;
	for (size_t i = 0; i < s->camera_count && cam < 0; i++)
		if (s->cameras[i].motion == SCENE_CAMERA_MOVING)
			cam = (int)i;
	assert_true(cam >= 0);
	tu_clip v = tu_render_clip(dev, s, cam, "vref", NULL, NULL, W, H, 2, false);
	tu_clip w1 = tu_render_clip(dev, s, cam, "warp/1", t8opt, NULL, W, H, 2, false);
	for (uint32_t f = 0; f < 2; f++)
		assert_int_equal(w1.st[f].late_samples, 0);
	enum { T = 26 };
	const char *const tTopt[] = {"truth", "truth-threshold=26", NULL};
	tu_clip w2 = tu_render_clip(dev, s, cam, "warp/2", tTopt, NULL, W, H, 2, false);
	size_t px = (size_t)W * H;
	assert_int_equal(cpu_late(w2.disp[1], v.disp[1], v.hdr[1], px, T - 1),
			 cpu_late(w2.disp[1], v.disp[1], v.hdr[1], px, T + 1));
	assert_int_equal(w2.st[0].late_samples, 0);
	int64_t by_cpu = cpu_late(w2.disp[1], v.disp[1], v.hdr[1], px, T);
	printf("R7 warp/2 frame 1 (moderate, moving camera), T %d: late %lld, CPU %lld, holes %lld\n", T,
	       (long long)w2.st[1].late_samples, (long long)by_cpu, (long long)w2.st[1].new_units);
	assert_true(by_cpu > 0);
	assert_int_equal(w2.st[1].late_samples, by_cpu);
	assert_truth_left_out(&w2);
	/* --truth leaves warp/4's run as it was: the keyframes at t mod 4 = 0 only, the same frames and counts (on an
	 * extrapolated frame the truth renders frame t's shadow maps itself) */
	enum { F4 = 6 };
	tu_clip w4 = tu_render_clip(dev, s, cam, "warp/4", NULL, NULL, W, H, F4, false);
	tu_clip w4t = tu_render_clip(dev, s, cam, "warp/4", t8opt, NULL, W, H, F4, false);
	tu_assert_same_frames(&w4, &w4t, true);
	for (uint32_t f = 0; f < F4; f++) {
		double key = f % 4 == 0 ? 1.0 : 0.0;
		if (tu_extra(&w4.st[f], "key_frame") != key || tu_extra(&w4t.st[f], "key_frame") != key)
			fail_msg("warp/4 frame %u: key_frame %g, with --truth %g, want %g", f, tu_extra(&w4.st[f], "key_frame"),
				 tu_extra(&w4t.st[f], "key_frame"), key);
		assert_int_equal(w4.st[f].shaded_samples, w4t.st[f].shaded_samples);
		assert_int_equal(w4.st[f].new_units, w4t.st[f].new_units);
	}
	tu_clip *all[] = {&v, &w1, &w2, &w4, &w4t};
	for (size_t i = 0; i < 5; i++)
		tu_clip_free(all[i]);
	scene_destroy(&s);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	vkdev_destroy(&dev);
	printf("(%.1f s)\n", now_s() - t0);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_refresh_patterns),
		cmocka_unit_test(test_truth),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
