/* test_rrc_payload.c — rrc --payload shadow|diffuse ([S] sec. 4.1 "caching partial payloads"; BASELINES.md A5) on the
 * test device with the validation layer (any message fails):
 *  P1  N = 1 (every payload recomputed every frame) equals ref on display values, on a moving shadow (tfr_shadow), on
 *      a light ramp with nine lights, unshadowed ones among them and a shadowed ninth, which filters every frame
 *      (payload_ramp), and on a MASK fence (reuse_mask); the payload is evaluated for every covered sample
 *      (shaded_samples) and the shading completed with it for every covered sample (composed_samples), both counted
 *      where the passes run;
 *  P2  the payload refreshes on rrc's schedule: rrc-shadow/N and rrc-diffuse/N shade, reuse and miss exactly the
 *      samples rrc/N does, frame by frame, with the same decision maps (N = 2, 4; a moving box), and the reused
 *      payloads are shown: under the moving box's shadow rrc-shadow/N differs from rrc-shadow/1;
 *  P3  what is cached is what lags: on payload_ramp (nothing moves, one light's intensity ramps) the shadow factors do
 *      not change, so rrc-shadow/4 equals rrc-shadow/1 bit for bit (HDR) while rrc/4, which caches the colour, lags
 *      the ramp; rrc-diffuse/4 lags by its diffuse term only, less than rrc/4 (the specular term is shaded every
 *      frame);
 *  P4  bad input: --truth with a payload, a payload on a method without one, the variant's spelling. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_vk.h"

#include "taslab/method.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

enum { W = 48, H = 32 };

/* Mean and max over the frame of the max-RGB display difference. */
static double mean_diff(const tu_clip *a, const tu_clip *b, uint32_t f, int *max)
{
	double sum = 0;
	*max = 0;
	for (size_t i = 0; i < (size_t)a->w * a->h; i++) {
		int m = tu_max_diff(a->disp[f] + 4 * i, b->disp[f] + 4 * i, 1);
		sum += m;
		*max = m > *max ? m : *max;
	}
	return sum / ((double)a->w * a->h);
}

static void test_full_rate(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	const char *const scenes[] = {"tfr_shadow", "payload_ramp", "reuse_mask"};
	const char *const variants[] = {"rrc-shadow/1", "rrc-diffuse/1"};
	/* exact on lavapipe; elsewhere two pipelines (ref's one pass, the payload's two) may round apart by 1 */
	int tol = TU_ON_LAVAPIPE ? 0 : 1;
	for (int k = 0; k < 3; k++) {
		scene *s = tu_load_scene(scenes[k]);
		enum { F = 5 };
		tu_clip ref = tu_render_clip(dev, s, 0, "ref", NULL, NULL, W, H, F, false);
		for (int v = 0; v < 2; v++) {
			tu_clip c = tu_render_clip(dev, s, 0, variants[v], NULL, NULL, W, H, F, false);
			for (uint32_t f = 0; f < F; f++) {
				int mx;
				double mean = mean_diff(&c, &ref, f, &mx);
				printf("P1 %s %s frame %u: against ref mean %.4f max %d\n", scenes[k], variants[v], f, mean, mx);
				assert_true(mx <= tol);
				assert_true(c.st[f].visible_samples > W * H / 4);
				assert_int_equal(c.st[f].shaded_samples, c.st[f].visible_samples);
				assert_true(tu_extra(&c.st[f], "composed_samples") == (double)c.st[f].visible_samples);
			}
			tu_clip_free(&c);
		}
		tu_clip_free(&ref);
		scene_destroy(&s);
	}
	vkdev_destroy(&dev);
}

static void test_schedule(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("tfr_shadow");
	enum { F = 9 };
	const uint32_t periods[] = {2, 4};
	tu_clip sh1 = tu_render_clip(dev, s, 0, "rrc-shadow/1", NULL, NULL, W, H, F, false);
	for (int p = 0; p < 2; p++) {
		char name[32];
		snprintf(name, sizeof name, "rrc/%u", periods[p]);
		tu_clip col = tu_render_clip(dev, s, 0, name, NULL, NULL, W, H, F, true);
		for (int k = 0; k < 2; k++) {
			snprintf(name, sizeof name, "rrc-%s/%u", k ? "diffuse" : "shadow", periods[p]);
			tu_clip c = tu_render_clip(dev, s, 0, name, NULL, NULL, W, H, F, true);
			int64_t reused = 0;
			for (uint32_t f = 0; f < F; f++) {
				assert_int_equal(c.st[f].shaded_samples, col.st[f].shaded_samples);
				assert_int_equal(c.st[f].reused_samples, col.st[f].reused_samples);
				assert_int_equal(c.st[f].new_units, col.st[f].new_units);
				assert_true(tu_extra(&c.st[f], "composed_samples") == (double)c.st[f].visible_samples);
				assert_memory_equal(c.dec[f], col.dec[f], (size_t)W * H);
				reused += c.st[f].reused_samples;
			}
			size_t lag = 0; /* pixels whose HDR value differs from rrc-shadow/1's (the shadow moves slowly) */
			for (uint32_t f = 1; f < F && !k; f++)
				for (size_t i = 0; i < (size_t)W * H; i++)
					lag += memcmp(c.hdr[f] + 4 * i, sh1.hdr[f] + 4 * i, 8) != 0;
			printf("P2 %s: shaded, reused and new equal rrc/%u's on %d frames (%lld reused)", name, periods[p], F,
			       (long long)reused);
			if (!k)
				printf("; %zu pixel-frames differ from rrc-shadow/1 (HDR)", lag);
			printf("\n");
			assert_true(reused > 0);
			assert_true(k || lag > 0); /* the cached factors lag the moving shadow: the compose pass reads them */
			tu_clip_free(&c);
		}
		tu_clip_free(&col);
	}
	tu_clip_free(&sh1);
	scene_destroy(&s);
	vkdev_destroy(&dev);
}

static void test_what_lags(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("payload_ramp");
	enum { F = 8 };
	tu_clip ref = tu_render_clip(dev, s, 0, "ref", NULL, NULL, W, H, F, false);
	tu_clip sh1 = tu_render_clip(dev, s, 0, "rrc-shadow/1", NULL, NULL, W, H, F, false);
	tu_clip sh4 = tu_render_clip(dev, s, 0, "rrc-shadow/4", NULL, NULL, W, H, F, false);
	tu_clip df4 = tu_render_clip(dev, s, 0, "rrc-diffuse/4", NULL, NULL, W, H, F, false);
	tu_clip col4 = tu_render_clip(dev, s, 0, "rrc/4", NULL, NULL, W, H, F, false);
	tu_assert_same_frames(&sh4, &sh1, true);
	double col_sum = 0, df_sum = 0;
	for (uint32_t f = 1; f < F; f++) {
		int mc, md;
		double c = mean_diff(&col4, &ref, f, &mc), d = mean_diff(&df4, &ref, f, &md);
		printf("P3 payload_ramp frame %u against ref: rrc/4 mean %.4f max %d, rrc-diffuse/4 mean %.4f max %d, "
		       "rrc-shadow/4 reused %lld samples, equal to rrc-shadow/1\n",
		       f, c, mc, d, md, (long long)sh4.st[f].reused_samples);
		assert_true(sh4.st[f].reused_samples > 0);
		col_sum += c;
		df_sum += d;
	}
	assert_true(col_sum > 0.1 * (F - 1)); /* the colour cache lags the ramp */
	assert_true(df_sum > 0.0);             /* so does the diffuse term */
	assert_true(df_sum < col_sum);         /* by less: the specular term is shaded every frame */
	tu_clip *clips[] = {&ref, &sh1, &sh4, &df4, &col4};
	for (int i = 0; i < 5; i++)
		tu_clip_free(clips[i]);
	scene_destroy(&s);
	vkdev_destroy(&dev);
}

static void test_bad_input(void **state)
{
	(void)state;
	tu_expect_cli_error("render --scene calm --method rrc-shadow/4 --truth --size 16x16 --frames 0:1 --out /nonexistent/x",
			    "--truth counts late colours");
	tu_expect_cli_error("render --scene calm --method rrc-random-shadow/4 --size 16x16 --frames 0:1 --out /nonexistent/x",
			    "has no '-shadow' form");
	tu_expect_cli_error("render --scene calm --method rrc/4 --payload specular --size 16x16 --frames 0:1 "
			    "--out /nonexistent/x",
			    "is not one of: colour, shadow, diffuse");
	tu_expect_cli_error("render --scene calm --method rrc-shadow --size 16x16 --frames 0:1 --out /nonexistent/x",
			    "needs its period");
	/* the variant's spelling: the payload is a -VALUE suffix, the default none */
	const char *const in[] = {"rrc-shadow/4", "rrc-diffuse/2", "rrc-colour/4", "rrc/8"};
	const char *const want[] = {"rrc-shadow/4", "rrc-diffuse/2", "rrc/4", "rrc/8"};
	for (int i = 0; i < 4; i++) {
		method_config c;
		char err[256], out[64];
		assert_int_equal(method_config_parse_variant(&c, in[i], err, sizeof err), 0);
		method_config_variant(&c, out, sizeof out);
		assert_string_equal(out, want[i]);
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_full_rate),
		cmocka_unit_test(test_schedule),
		cmocka_unit_test(test_what_lags),
		cmocka_unit_test(test_bad_input),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
