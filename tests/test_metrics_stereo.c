/* test_metrics_stereo.c — `taslab metrics diff` of two stereo runs (STEREO.md "metrics per eye against ref's same
 * eye, then pooled"; issue 25): each eye against the same eye into OUT/L and OUT/R (a mono diff of that eye's
 * images, value for value), both eyes pooled into OUT/frames.csv and OUT/summary.json — the pooled values equal a
 * mono diff of one sequence holding both eyes' frames (every pixel of both eyes: distribution and FLIP's weighted
 * quartiles included), flicker the mean of the eyes'; a stereo run against a mono run or a folder of images is
 * refused with one line. Stereo run folders are written here (manifest inputs.stereo, frames/L, frames/R). */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

#include "taslab/imageio.h"
#include "taslab/metrics_diff.h"

enum { W = 24, H = 16, N = 3 };

/* Frame f of eye e of run `run` (0: reference, 1: test): a smooth pattern, the test run with some eye-specific
 * differences so that the eyes' scores differ. */
static void frame_pixels(int run, int e, int f, uint8_t *rgb)
{
	for (uint32_t y = 0; y < H; y++)
		for (uint32_t x = 0; x < W; x++)
			for (int c = 0; c < 3; c++) {
				int v = (int)((x * 9 + y * 5 + (uint32_t)c * 40 + (uint32_t)f * 7 + (uint32_t)e * 3) % 230);
				if (run == 1 && e == 0 && (x + y + (uint32_t)f) % 5 == 0)
					v += 6 + f; /* left: small errors spread out */
				if (run == 1 && e == 1 && x < 6 && y < 4)
					v += 20 + 10 * f; /* right: a larger block error */
				rgb[((size_t)y * W + x) * 3 + (size_t)c] = (uint8_t)v;
			}
}

static void write_frame(const char *dir, int f, const uint8_t *rgb)
{
	char p[4300], err[256];
	snprintf(p, sizeof p, "%s/%06d.png", dir, f);
	if (imageio_write_png_rgb8_packed(p, W, H, rgb, err, sizeof err))
		fail_msg("%s", err);
}

/* A stereo run folder RUN (frames/L, frames/R, manifest) and, when `both` is given, a folder of images holding the
 * left eye's frames 0..N-1 and the right eye's as N..2N-1. */
static void make_stereo_run(const char *dir, int run, const char *both)
{
	char p[4300];
	snprintf(p, sizeof p, "rm -rf %s && mkdir -p %s/frames/L %s/frames/R", dir, dir, dir);
	assert_int_equal(system(p), 0);
	if (both) {
		snprintf(p, sizeof p, "rm -rf %s && mkdir -p %s", both, both);
		assert_int_equal(system(p), 0);
	}
	uint8_t rgb[W * H * 3];
	for (int e = 0; e < 2; e++)
		for (int f = 0; f < N; f++) {
			frame_pixels(run, e, f, rgb);
			snprintf(p, sizeof p, "%s/frames/%s", dir, e ? "R" : "L");
			write_frame(p, f, rgb);
			if (both)
				write_frame(both, e * N + f, rgb);
		}
	snprintf(p, sizeof p, "%s/manifest.json", dir);
	FILE *fp = fopen(p, "w");
	assert_non_null(fp);
	fprintf(fp, "{\"inputs\": {\"method\": \"ref\", \"frames\": [0, %d], \"size\": [%d, %d], \"fps\": 60, "
		"\"stereo\": true, \"ipd\": 0.063}, \"outputs\": {\"png\": true, \"exr\": false}}", N - 1, W, H);
	fclose(fp);
}

static json_t *load_json(const char *dir, const char *name)
{
	char p[4300];
	json_error_t je;
	snprintf(p, sizeof p, "%s/%s", dir, name);
	json_t *j = json_load_file(p, 0, &je);
	if (!j)
		fail_msg("%s: %s", p, je.text);
	return j;
}

static double num(json_t *j, const char *key)
{
	json_t *v = json_object_get(j, key);
	if (!json_is_number(v))
		fail_msg("summary.json: %s is not a number", key);
	return json_number_value(v);
}

/* The pooled keys that do not depend on how frames are sequenced (flicker does: compared separately). */
static const char *const pooled_keys[] = {"maxrgb_mean", "maxrgb_p50", "maxrgb_p95", "maxrgb_p99", "maxrgb_max",
					   "exceed_2", "exceed_4", "exceed_8", "exceed_16", "exceed_32", "exceed_64",
					   "psnr", "ssim", "flip_mean", "flip_weighted_median", "flip_q1_weighted",
					   "flip_q3_weighted", "flip_min", "flip_max"};

static void test_stereo_diff(void **state)
{
	(void)state;
	const char *base = tu_tmpdir("metrics_stereo");
	char a[4096], b[4096], ab[4096], bb[4096], out[4096], mono[4096], eye[3][4096], err[1024], p[4300];
	snprintf(a, sizeof a, "%s/a", base);
	snprintf(b, sizeof b, "%s/b", base);
	snprintf(ab, sizeof ab, "%s/a_both", base);
	snprintf(bb, sizeof bb, "%s/b_both", base);
	snprintf(out, sizeof out, "%s/out", base);
	make_stereo_run(a, 0, ab);
	make_stereo_run(b, 1, bb);
	mtr_diff_desc d = {.ref = a, .test = b, .out = out, .threads = 2};
	mtr_diff_result r;
	if (mtr_diff_run(&d, &r, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(r.views, 2);
	assert_int_equal(r.frames, N);
	json_t *pooled = load_json(out, "summary.json");
	assert_true(json_is_true(json_object_get(pooled, "stereo")));
	assert_int_equal(json_integer_value(json_object_get(pooled, "frames")), N);
	/* each eye: exactly the mono diff of that eye's images */
	json_t *per[2];
	for (int e = 0; e < 2; e++) {
		const char *name = e ? "R" : "L";
		char ea[4200], eb[4200];
		snprintf(ea, sizeof ea, "%s/frames/%s", a, name);
		snprintf(eb, sizeof eb, "%s/frames/%s", b, name);
		snprintf(eye[e], sizeof eye[e], "%s/mono_%s", base, name);
		mtr_diff_desc de = {.ref = ea, .test = eb, .out = eye[e], .threads = 2};
		mtr_diff_result re;
		if (mtr_diff_run(&de, &re, err, sizeof err))
			fail_msg("%s", err);
		assert_int_equal(re.views, 1);
		snprintf(p, sizeof p, "%s/%s", out, name);
		per[e] = load_json(p, "summary.json");
		json_t *m = load_json(eye[e], "summary.json");
		assert_string_equal(json_string_value(json_object_get(per[e], "eye")), name);
		for (size_t k = 0; k < sizeof pooled_keys / sizeof *pooled_keys; k++)
			if (num(per[e], pooled_keys[k]) != num(m, pooled_keys[k]))
				fail_msg("eye %s: %s = %.17g, the mono diff of its images %.17g", name, pooled_keys[k],
					 num(per[e], pooled_keys[k]), num(m, pooled_keys[k]));
		assert_true(num(per[e], "flicker_mean") == num(m, "flicker_mean"));
		assert_true(num(per[e], "maxrgb_max") == (e ? r.eye[1].max : r.eye[0].max));
		json_decref(m);
		/* the eye's frames.csv and distribution.csv are the mono diff's */
		for (int k = 0; k < 2; k++) {
			const char *file = k ? "distribution.csv" : "frames.csv";
			char pe[4300], pm[4300];
			snprintf(pe, sizeof pe, "%s/%s/%s", out, name, file);
			snprintf(pm, sizeof pm, "%s/%s", eye[e], file);
			char *x = tu_read_file(pe, NULL), *y = tu_read_file(pm, NULL);
			assert_non_null(x);
			assert_non_null(y);
			assert_string_equal(x, y);
			free(x);
			free(y);
		}
	}
	/* the eyes do score differently, so pooling is seen */
	assert_true(num(per[0], "maxrgb_max") != num(per[1], "maxrgb_max"));
	assert_true(num(per[0], "flip_weighted_median") != num(per[1], "flip_weighted_median"));
	/* pooled: as one sequence of both eyes' frames (all pixels of both eyes) */
	snprintf(mono, sizeof mono, "%s/mono_both", base);
	mtr_diff_desc dm = {.ref = ab, .test = bb, .out = mono, .threads = 2};
	if (mtr_diff_run(&dm, &r, err, sizeof err))
		fail_msg("%s", err);
	json_t *m = load_json(mono, "summary.json");
	for (size_t k = 0; k < sizeof pooled_keys / sizeof *pooled_keys; k++) {
		double want = num(m, pooled_keys[k]), got = num(pooled, pooled_keys[k]);
		if (fabs(got - want) > 1e-12 * fmax(1.0, fabs(want)))
			fail_msg("pooled %s = %.17g, both eyes as one sequence %.17g", pooled_keys[k], got, want);
	}
	json_decref(m);
	assert_float_equal(num(pooled, "flicker_mean"), (num(per[0], "flicker_mean") + num(per[1], "flicker_mean")) / 2,
			   1e-12);
	char pd[4300], md[4300];
	snprintf(pd, sizeof pd, "%s/distribution.csv", out);
	snprintf(md, sizeof md, "%s/distribution.csv", mono);
	char *x = tu_read_file(pd, NULL), *y = tu_read_file(md, NULL);
	assert_non_null(x);
	assert_non_null(y);
	assert_string_equal(x, y);
	free(x);
	free(y);
	/* pooled frames.csv: one row per frame, the eyes' mean of means and max of maxima */
	snprintf(p, sizeof p, "%s/frames.csv", out);
	char *csv = tu_read_file(p, NULL);
	assert_non_null(csv);
	assert_int_equal(tu_count_lines(csv), N + 1);
	free(csv);
	json_decref(per[0]);
	json_decref(per[1]);
	json_decref(pooled);
	/* a stereo run against a mono run or a folder of images: one line, no summary */
	char mrun[4096];
	snprintf(mrun, sizeof mrun, "%s/monorun", base);
	snprintf(p, sizeof p, "rm -rf %s && mkdir -p %s && cp -r %s/frames/L %s/frames && sed 's/, \"stereo\": true, \"ipd\": "
		 "0.063//' %s/manifest.json > %s/manifest.json", mrun, mrun, b, mrun, b, mrun);
	assert_int_equal(system(p), 0);
	const char *others[2] = {mrun, ab};
	for (int k = 0; k < 2; k++) {
		d.test = others[k];
		assert_int_equal(mtr_diff_run(&d, &r, err, sizeof err), TL_ERR_INPUT);
		assert_non_null(strstr(err, "is a stereo run but"));
		assert_null(strchr(err, '\n'));
		snprintf(p, sizeof p, "%s/summary.json", out);
		assert_false(tu_file_exists(p));
		snprintf(p, sizeof p, "%s/L/summary.json", out);
		assert_false(tu_file_exists(p));
	}
	/* the command line: the same refusal, exit 2 */
	char args[8192];
	snprintf(args, sizeof args, "metrics diff --ref %s --test %s --out %s/cli", mrun, a, base);
	tu_expect_cli_error(args, "is mono but");
}

int main(void)
{
	const struct CMUnitTest tests[] = {cmocka_unit_test(test_stereo_diff)};
	return tu_finish(cmocka_run_group_tests(tests, NULL, NULL));
}
