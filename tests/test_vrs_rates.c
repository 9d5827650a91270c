/* test_vrs_rates.c — `render --rate-images` (RUN/rates/NNNNNN.png, run.h): the shading rate of every 16x16 tile of a
 * VRS method as one coloured pixel per tile, taken from the GPU's rate buffer that the select pass read. End to end
 * through the command line (lavapipe, validation layer on: a message fails the run), tiny sizes:
 *  - casedge on calm, 96x64, 4 frames: each image is ceil(W/16) x ceil(H/16), every pixel a palette colour, its
 *    counts of 1x1, 2x2, 4x4 and other tiles equal stats.csv's tiles_* columns exactly, and every tile equals the rate
 *    an in-process render of the same frames reads from its rate buffer (vbuf_debug_rates);
 *  - mas --rates all on the pan (tests/data/vbuf_pan.json) at 16, 14, 10 and 8 px/frame: the images show 4x2, 2x4,
 *    2x1 and 1x2 (BASELINES.md V3 through the README's map of --rates all) on the tiles a source reaches, 1x1 on the
 *    others, with the counts of stats.csv;
 *  - bad input: --rate-images with a method without tile rates (ref, ads) or with --stereo is one line, non-zero exit,
 *    and no run folder. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_vk.h"

#include "../renderer/src/methods/method_debug.h"
#include "taslab/frame.h"
#include "taslab/imageio.h"
#include "taslab/render.h"
#include "taslab/run.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

#include "test_vrs.h"

/* the rate code of the path (w | h << 8) of each frame_rate */
static const uint32_t code_of[FRAME_RATE_COUNT] = {
	[FRAME_RATE_4X4] = RATE(4, 4), [FRAME_RATE_4X2] = RATE(4, 2), [FRAME_RATE_2X4] = RATE(2, 4),
	[FRAME_RATE_2X2] = RATE(2, 2), [FRAME_RATE_2X1] = RATE(2, 1), [FRAME_RATE_1X2] = RATE(1, 2),
	[FRAME_RATE_1X1] = RATE(1, 1)};

/* Reads RUN/rates/NNNNNN.png of frame f as rate codes (tx x ty, checked) and checks its histogram against the stats
 * row; returns the codes (caller frees). */
static uint32_t *read_rates(const char *run, const run_stats *st, uint32_t f, uint32_t tx, uint32_t ty)
{
	char path[4096], err[1024];
	snprintf(path, sizeof path, "%s/rates/%06u.png", run, f);
	uint32_t w, h;
	uint8_t *rgb = NULL;
	if (imageio_read_rgb8(path, &w, &h, &rgb, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(w, tx);
	assert_int_equal(h, ty);
	uint32_t *codes = malloc((size_t)tx * ty * sizeof *codes);
	double hist[4] = {0};
	for (uint32_t t = 0; t < tx * ty; t++) {
		int c = run_rate_code(rgb + 3 * t);
		if (c < 0) { /* fail_msg does not return; the break tells the compiler so (-O3 -Warray-bounds) */
			fail_msg("%s tile %u: colour %u,%u,%u is no rate", path, t, rgb[3 * t], rgb[3 * t + 1], rgb[3 * t + 2]);
			break;
		}
		codes[t] = code_of[c];
		hist[c == FRAME_RATE_1X1 ? 0 : c == FRAME_RATE_2X2 ? 1 : c == FRAME_RATE_4X4 ? 2 : 3] += 1;
	}
	free(rgb);
	const char *cols[4] = {"tiles_1x1", "tiles_2x2", "tiles_4x4", "tiles_other"};
	for (int k = 0; k < 4; k++)
		if (run_stats_get(st, f, cols[k]) != hist[k])
			fail_msg("%s: %g %s tiles in the image, %g in stats.csv", path, hist[k], cols[k],
				 run_stats_get(st, f, cols[k]));
	return codes;
}

static void read_stats(const char *run, run_stats *st, uint32_t frames)
{
	char err[1024];
	if (run_stats_read(run, st, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(st->rows, frames);
}

static void render_cli(const char *args, const char *run)
{
	char cmd[8192], out[16384];
	snprintf(cmd, sizeof cmd, "%s render %s --rate-images --no-exr --quiet --out %s", TASLAB_BINARY, args, run);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s\n%s", cmd, out);
}

static void test_casedge_calm(void **state)
{
	(void)state;
	enum { W = 96, H = 64, F = 4, TX = (W + 15) / 16, TY = (H + 15) / 16 };
	const char *dir = tu_tmpdir("vrs_rates_calm");
	char run[4096], args[4096];
	snprintf(run, sizeof run, "%s/run", dir);
	snprintf(args, sizeof args, "--scene %s/scenes/calm.json --method casedge --size %dx%d --frames 0:%d",
		 TASLAB_SOURCE_DIR, W, H, F);
	render_cli(args, run);
	run_stats st;
	read_stats(run, &st, F);
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("scenes/calm.json");
	render *r = tu_render_open(dev, s, 0, "casedge", NULL, NULL, W, H, false);
	int mixed = 0;
	for (uint32_t f = 0; f < F; f++) {
		char err[1024];
		frame_image img;
		frame_stats fs;
		if (render_frame(r, f, &img, &fs, err, sizeof err))
			fail_msg("frame %u: %s", f, err);
		assert_int_equal(fs.shaded_samples, (int64_t)run_stats_get(&st, f, "shaded_samples"));
		uint32_t *codes = read_rates(run, &st, f, TX, TY);
		const uint32_t *rates = vbuf_debug_rates(r);
		int kinds = 0, seen[3] = {0};
		for (uint32_t t = 0; t < TX * TY; t++) {
			if (codes[t] != rates[t])
				fail_msg("frame %u tile %u: the image shows %#x, the rate buffer holds %#x", f, t, codes[t], rates[t]);
			int k = codes[t] == RATE(1, 1) ? 0 : codes[t] == RATE(2, 2) ? 1 : 2;
			kinds += !seen[k];
			seen[k] = 1;
		}
		if (f == 0 && kinds != 1)
			fail_msg("frame 0 is all 1x1 (no history yet)");
		mixed += kinds >= 2;
		free(codes);
	}
	assert_true(mixed >= 2); /* the coarse rates of frames 1.. show, not only the frame-0 1x1 */
	assert_int_equal(vkdev_validation_messages(dev), 0);
	render_destroy(&r);
	run_stats_free(&st);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

static void test_mas_rates_all(void **state)
{
	(void)state;
	enum { W = 64, H = 64, F = 3, TX = W / 16, TY = H / 16 };
	scene *s = tu_load_scene("vbuf_pan");
	const scene_camera *cam = &s->cameras[0];
	double speed = fabs((double)cam->keys[1].position.x - cam->keys[0].position.x) / (cam->keys[1].t - cam->keys[0].t);
	double ppm = H / (2.0 * cam->keys[0].position.y); /* 90 degrees, looking straight down */
	const struct {
		double v;
		uint32_t code;
	} cases[] = {{16, RATE(4, 2)}, {14, RATE(2, 4)}, {10, RATE(2, 1)}, {8, RATE(1, 2)}};
	const char *dir = tu_tmpdir("vrs_rates_pan");
	for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
		char run[4096], args[4096];
		snprintf(run, sizeof run, "%s/v%g", dir, cases[k].v);
		snprintf(args, sizeof args,
			 "--scene %s/tests/data/vbuf_pan.json --method mas --rates all --size %dx%d --frames 0:%d --fps %.17g",
			 TASLAB_SOURCE_DIR, W, H, F, speed * ppm / cases[k].v);
		render_cli(args, run);
		run_stats st;
		read_stats(run, &st, F);
		uint32_t *codes = read_rates(run, &st, F - 1, TX, TY);
		int reached = 0;
		for (uint32_t t = 0; t < TX * TY; t++) {
			if (codes[t] != cases[k].code && codes[t] != RATE(1, 1))
				fail_msg("v %g tile %u: %#x, expected %#x or 1x1 (unreached)", cases[k].v, t, codes[t], cases[k].code);
			reached += codes[t] == cases[k].code;
		}
		assert_true(reached >= TX * TY / 2);
		free(codes);
		for (uint32_t f = 0; f + 1 < F; f++)
			free(read_rates(run, &st, f, TX, TY));
		run_stats_free(&st);
	}
	scene_destroy(&s);
}

static void test_bad_input(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("vrs_rates_bad");
	char args[4096], path[4096];
	const struct {
		const char *opts, *needle;
	} cases[] = {
		{"--method ref --rate-images", "chooses no tile rates"},
		{"--method ads@2 --rate-images", "chooses no tile rates"},
		{"--method casedge --stereo --rate-images", "mono runs only"},
	};
	for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
		snprintf(args, sizeof args, "render --scene %s/tests/data/vbuf_flat.json --size 32x32 --frames 0:1 %s --out %s/r",
			 TASLAB_SOURCE_DIR, cases[i].opts, dir);
		tu_expect_cli_error(args, cases[i].needle);
	}
	snprintf(path, sizeof path, "%s/r", dir);
	assert_false(tu_file_exists(path)); /* refused before anything was created */
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_bad_input),
		cmocka_unit_test(test_casedge_calm),
		cmocka_unit_test(test_mas_rates_all),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
