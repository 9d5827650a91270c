/* test_metrics.c — metrics against independently computed references:
 *  - small hand-computed images (values worked out in the comments);
 *  - percentiles against a full sort (numpy's default "linear" definition);
 *  - SSIM against scikit-image (tests/reference/ssim_reference.json, produced by ssim_reference.py), 1e-5;
 *  - Phi^-1 against R's qnorm (qnorm(0.75) = 0.6744897501960817), Wilson interval against its closed form;
 *  - bad input: sizes, frame counts, unreadable files, NaN in EXR. */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/imageio.h"
#include "taslab/metrics.h"
#include "taslab/metrics_diff.h"
#include "taslab/metrics_runs.h"
#include "test_util.h"

static void test_hand_computed(void **state)
{
	(void)state;
	/* 2x2 images. Pixel differences (r,g,b): (0,0,0), (3,-1,0), (0,0,-10), (70,70,70).
	 * max-RGB d = 0, 3, 10, 70: mean 20.75, max 70 at (1,1); sorted 0,3,10,70 -> p50 = 6.5 (type 7);
	 * exceed_2 = 3/4, exceed_4 = exceed_8 = 2/4, exceed_16 = exceed_32 = exceed_64 = 1/4;
	 * MSE = (9 + 1 + 100 + 3*4900) / 12 = 14810/12 -> PSNR = 10 log10(65025 / 1234.1667) = 17.2169. */
	float a[12] = {10, 10, 10, 20, 20, 20, 30, 30, 30, 100, 100, 100};
	float b[12] = {10, 10, 10, 17, 21, 20, 30, 30, 40, 30, 30, 30};
	mtr_image A = {2, 2, a}, B = {2, 2, b};
	mtr_frame_stats s;
	char err[256];
	float map[4];
	assert_int_equal(mtr_frame_compare(&A, &B, NULL, NULL, map, 1, &s, err, sizeof err), 0);
	assert_float_equal(s.mean, 20.75, 1e-9);
	assert_float_equal(s.max, 70, 0);
	assert_int_equal(s.max_x, 1);
	assert_int_equal(s.max_y, 1);
	assert_float_equal(s.p50, 6.5, 1e-9);
	double ex[6] = {0.75, 0.5, 0.5, 0.25, 0.25, 0.25};
	for (int k = 0; k < 6; k++)
		assert_float_equal(s.exceed[k], ex[k], 1e-12);
	assert_float_equal(s.psnr, 10 * log10(65025.0 / (14810.0 / 12)), 1e-9);
	assert_float_equal(map[1], 3, 0);
	assert_true(isnan(s.flicker_mean));
	assert_true(isnan(s.ssim)); /* smaller than the 11x11 window */
	/* Flicker: previous frames equal to the current ones except the test's (0,0) pixel was 40 higher in all
	 * channels: frame-to-frame change a: 0, b: -40 at (0,0) -> f = 40 there, 0 elsewhere -> mean 10. */
	float bp[12];
	memcpy(bp, b, sizeof bp);
	bp[0] = bp[1] = bp[2] = 50;
	mtr_image Ap = {2, 2, a}, Bp = {2, 2, bp};
	assert_int_equal(mtr_frame_compare(&A, &B, &Ap, &Bp, NULL, 2, &s, err, sizeof err), 0);
	assert_float_equal(s.flicker_mean, 10.0, 1e-9);
}

static void fill(float *v, uint32_t w, uint32_t h, unsigned seed)
{
	for (size_t i = 0; i < (size_t)w * h * 3; i++) {
		seed = seed * 1103515245u + 12345u;
		v[i] = (float)((seed >> 16) % 256);
	}
}

static void test_identical_and_single_pixel(void **state)
{
	(void)state;
	const uint32_t w = 64, h = 48;
	float *a = malloc(w * h * 3 * sizeof *a), *b = malloc(w * h * 3 * sizeof *b);
	fill(a, w, h, 7);
	memcpy(b, a, w * h * 3 * sizeof *a);
	mtr_image A = {w, h, a}, B = {w, h, b};
	mtr_frame_stats s;
	char err[256];
	assert_int_equal(mtr_frame_compare(&A, &B, &A, &B, NULL, 0, &s, err, sizeof err), 0);
	assert_true(s.mean == 0 && s.max == 0 && s.p99 == 0 && s.exceed[0] == 0 && s.flicker_mean == 0);
	assert_true(isinf(s.psnr));
	assert_float_equal(s.ssim, 1.0, 1e-12);
	/* One pixel, one channel, +37 at (41, 29): found there with that size; exceedance 1/(w*h) up to T = 32. */
	b[((size_t)29 * w + 41) * 3 + 1] += 37;
	assert_int_equal(mtr_frame_compare(&A, &B, NULL, NULL, NULL, 3, &s, err, sizeof err), 0);
	assert_float_equal(s.max, 37, 0);
	assert_int_equal(s.max_x, 41);
	assert_int_equal(s.max_y, 29);
	assert_float_equal(s.exceed[4], 1.0 / (w * h), 1e-15);
	assert_float_equal(s.exceed[5], 0, 0);
	assert_float_equal(s.mean, 37.0 / (w * h), 1e-12);
	free(a);
	free(b);
}

static int cmp_f(const void *x, const void *y)
{
	float a = *(const float *)x, b = *(const float *)y;
	return (a > b) - (a < b);
}

static void test_percentile_vs_sort(void **state)
{
	(void)state;
	for (size_t n = 1; n < 400; n += 37) {
		float *v = malloc(n * sizeof *v), *s = malloc(n * sizeof *s);
		unsigned seed = (unsigned)n;
		for (size_t i = 0; i < n; i++) {
			seed = seed * 1664525u + 1013904223u;
			v[i] = (float)(seed % 1000) / 7.0f; /* with ties */
		}
		memcpy(s, v, n * sizeof *v);
		qsort(s, n, sizeof *s, cmp_f);
		double pcts[5] = {0, 50, 95, 99, 100};
		for (int k = 0; k < 5; k++) {
			float *c = malloc(n * sizeof *c);
			memcpy(c, v, n * sizeof *v);
			double h = (n - 1) * pcts[k] / 100.0, lo = floor(h);
			double ref = s[(size_t)lo] + (h - lo) * ((size_t)lo + 1 < n ? s[(size_t)lo + 1] - s[(size_t)lo] : 0);
			assert_float_equal(mtr_percentile(c, n, pcts[k]), ref, 1e-4);
			free(c);
		}
		free(v);
		free(s);
	}
}

/* Same integer formulas as tests/reference/ssim_reference.py. */
static void make_pair(int kind, uint32_t w, uint32_t h, float *a, float *b)
{
	for (uint32_t y = 0; y < h; y++)
		for (uint32_t x = 0; x < w; x++)
			for (int c = 0; c < 3; c++) {
				int va, vb;
				if (kind == 0) {
					va = (int)((x * 7 + y * 13 + c * 29) % 256);
					vb = va + (int)((x * y + c) % 9) - 4;
					vb = vb < 0 ? 0 : vb > 255 ? 255 : vb;
				} else if (kind == 1) {
					va = (((x / 4) + (y / 4)) % 2 ? 200 : 40) + c * 10;
					vb = ((((x + 1) / 4) + (y / 4)) % 2 ? 200 : 40) + c * 10;
				} else {
					va = (int)((x * x + 3 * y + 50 * c) % 256);
					vb = (x + y) % 7 == 0 ? 255 - va : va;
				}
				a[((size_t)y * w + x) * 3 + c] = (float)va;
				b[((size_t)y * w + x) * 3 + c] = (float)vb;
			}
}

static void test_ssim_vs_skimage(void **state)
{
	(void)state;
	json_error_t je;
	json_t *ref = json_load_file(TASLAB_SOURCE_DIR "/tests/reference/ssim_reference.json", 0, &je);
	assert_non_null(ref);
	json_t *cases = json_object_get(ref, "cases");
	assert_int_equal(json_array_size(cases), 3);
	for (size_t i = 0; i < json_array_size(cases); i++) {
		json_t *c = json_array_get(cases, i);
		int kind = (int)json_integer_value(json_object_get(c, "kind"));
		uint32_t w = (uint32_t)json_integer_value(json_object_get(c, "width"));
		uint32_t h = (uint32_t)json_integer_value(json_object_get(c, "height"));
		float *a = malloc((size_t)w * h * 3 * sizeof *a), *b = malloc((size_t)w * h * 3 * sizeof *b);
		make_pair(kind, w, h, a, b);
		mtr_image A = {w, h, a}, B = {w, h, b};
		double expect = json_real_value(json_object_get(c, "ssim"));
		for (int threads = 1; threads <= 3; threads++) {
			double got = mtr_ssim(&A, &B, threads);
			if (fabs(got - expect) > 1e-5)
				fail_msg("case %d (%ux%u, %d threads): SSIM %.8f, scikit-image %.8f", kind, w, h, threads, got, expect);
		}
		free(a);
		free(b);
	}
	json_decref(ref);
}

static void test_jnd(void **state)
{
	(void)state;
	/* R: qnorm(0.75) = 0.6744897501960817, qnorm(0.9) = 1.2815515655446004. */
	assert_float_equal(mtr_jnd_from_p(0.75), 1.0, 1e-12);
	assert_float_equal(mtr_jnd_from_p(0.5), 0.0, 1e-12);
	assert_float_equal(mtr_jnd_from_p(0.9), 1.2815515655446004 / 0.6744897501960817, 1e-9);
	mtr_jnd j;
	/* Wilson 95% for 5/10: centre 0.5, half-width z*sqrt(0.025 + z^2/400)/(1 + z^2/10), z = 1.959964
	 * -> (0.236593, 0.763407). */
	assert_int_equal(mtr_jnd_from_counts(4, 2, 10, 0.95, &j), 0);
	assert_float_equal(j.p, 0.5, 1e-12);
	assert_float_equal(j.p_lo, 0.236593, 1e-6);
	assert_float_equal(j.p_hi, 0.763407, 1e-6);
	assert_false(j.clamped);
	/* p = 1 and p = 0 stay finite: p clamped to 1 - 1/(2n) and 1/(2n). */
	assert_int_equal(mtr_jnd_from_counts(20, 0, 20, 0.95, &j), 0);
	assert_true(j.clamped && isfinite(j.jnd) && isfinite(j.jnd_lo) && isfinite(j.jnd_hi));
	assert_float_equal(j.jnd, mtr_jnd_from_p(1 - 1 / 40.0), 1e-12);
	assert_int_equal(mtr_jnd_from_counts(0, 0, 20, 0.95, &j), 0);
	assert_float_equal(j.jnd, -mtr_jnd_from_p(1 - 1 / 40.0), 1e-9);
	assert_int_not_equal(mtr_jnd_from_counts(5, 6, 10, 0.95, &j), 0); /* more answers than trials */
	assert_int_not_equal(mtr_jnd_from_counts(1, 0, 0, 0.95, &j), 0);
}

static void test_colormap(void **state)
{
	(void)state;
	/* Lightness (Rec. 709 luma of the sRGB values as a proxy) increases monotonically along the map. */
	double prev = -1;
	for (int i = 0; i <= 64; i++) {
		uint8_t c[3];
		mtr_colormap(i / 64.0, c);
		double y = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
		assert_true(y > prev);
		prev = y;
	}
}

static void write_png_dir(const char *dir, int frames, uint32_t w, uint32_t h, int bump_frame)
{
	char p[4096], err[256];
	uint8_t *rgb = malloc((size_t)w * h * 3);
	for (int f = 0; f < frames; f++) {
		for (size_t i = 0; i < (size_t)w * h * 3; i++)
			rgb[i] = (uint8_t)((i * 7 + f * 3) % 200);
		if (f == bump_frame)
			rgb[0] += 50;
		snprintf(p, sizeof p, "%s/%06d.png", dir, f);
		assert_int_equal(imageio_write_png_rgb8_packed(p, w, h, rgb, err, sizeof err), 0);
	}
	free(rgb);
}

static void test_diff_files(void **state)
{
	(void)state;
	const char *base = tu_tmpdir("metrics_diff");
	char a[4096], b[4096], c[4096], out[4096], err[1024], cmd[8192];
	snprintf(a, sizeof a, "%s/a", base);
	snprintf(b, sizeof b, "%s/b", base);
	snprintf(c, sizeof c, "%s/c", base);
	snprintf(out, sizeof out, "%s/out", base);
	snprintf(cmd, sizeof cmd, "mkdir -p %s %s %s", a, b, c);
	assert_int_equal(system(cmd), 0);
	write_png_dir(a, 3, 20, 16, -1);
	write_png_dir(b, 3, 20, 16, 1);
	write_png_dir(c, 2, 20, 16, -1);
	mtr_diff_desc d = {.ref = a, .test = b, .out = out, .threads = 2};
	mtr_diff_result r;
	if (mtr_diff_run(&d, &r, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(r.frames, 3);
	assert_float_equal(r.pooled.max, 50, 0);
	char p[4096];
	snprintf(p, sizeof p, "%s/frames.csv", out);
	char *csv = tu_read_file(p, NULL);
	assert_non_null(csv);
	assert_int_equal(tu_count_lines(csv), 4);
	const char *expect = "frame,maxrgb_mean,maxrgb_p50,maxrgb_p95,maxrgb_p99,maxrgb_max,exceed_2,exceed_4,exceed_8,"
			     "exceed_16,exceed_32,exceed_64,psnr,ssim,flicker_mean,flip_mean\n0,0,0,0,0,0,0,0,0,0,0,0,,1,,0\n";
	assert_true(strncmp(csv, expect, strlen(expect)) == 0); /* identical frame 0: psnr empty (inf), no flicker */
	free(csv);
	/* Pooled distribution: 3 frames x 320 pixels, one pixel at d = 50, the rest at 0. */
	snprintf(p, sizeof p, "%s/distribution.csv", out);
	char *dist = tu_read_file(p, NULL);
	assert_non_null(dist);
	assert_non_null(strstr(dist, "\n0,1,959,"));
	assert_non_null(strstr(dist, "\n50,51,1,"));
	assert_int_equal(tu_count_lines(dist), 257);
	free(dist);
	snprintf(p, sizeof p, "%s/summary.json", out);
	json_error_t je;
	json_t *js = json_load_file(p, 0, &je);
	assert_non_null(js);
	assert_float_equal(json_real_value(json_object_get(js, "maxrgb_max")), 50, 0);
	assert_float_equal(json_real_value(json_object_get(js, "exceed_32")), 1.0 / (20 * 16) / 3, 1e-12);
	json_decref(js);
	/* Different frame counts, a size mismatch, an unreadable frame, NaN in an EXR. */
	d.test = c;
	assert_int_not_equal(mtr_diff_run(&d, &r, err, sizeof err), 0);
	assert_non_null(strstr(err, "has 3 frames"));
	write_png_dir(c, 3, 21, 16, -1);
	assert_int_not_equal(mtr_diff_run(&d, &r, err, sizeof err), 0);
	assert_non_null(strstr(err, "same size"));
	snprintf(cmd, sizeof cmd, "echo garbage > %s/000002.png", c);
	assert_int_equal(system(cmd), 0);
	write_png_dir(c, 2, 20, 16, -1);
	assert_int_not_equal(mtr_diff_run(&d, &r, err, sizeof err), 0);
	assert_non_null(strstr(err, "000002.png"));
	uint16_t half[4 * 4 * 4];
	for (int i = 0; i < 64; i++)
		half[i] = 0x3800; /* 0.5 */
	half[5] = 0x7E00;        /* NaN */
	snprintf(p, sizeof p, "%s/000000.exr", c);
	assert_int_equal(imageio_write_exr_half(p, 4, 4, half, NULL, 0, err, sizeof err), 0);
	uint32_t w, h;
	float *px;
	assert_int_not_equal(imageio_read_rgba_float(p, &w, &h, &px, 1, err, sizeof err), 0);
	assert_non_null(strstr(err, "NaN"));
}

static void make_run(const char *dir, const char *method, double T, const char *csv)
{
	char p[4096];
	snprintf(p, sizeof p, "mkdir -p %s", dir);
	assert_int_equal(system(p), 0);
	snprintf(p, sizeof p, "%s/manifest.json", dir);
	FILE *f = fopen(p, "w");
	fprintf(f, "{\"inputs\": {\"method\": \"%s\", \"scene\": \"s\", \"camera\": \"c\", \"threshold\": %g, "
		   "\"frames\": [0, 3], \"size\": [8, 8], \"fps\": 60}}", method, T);
	fclose(f);
	snprintf(p, sizeof p, "%s/stats.csv", dir);
	f = fopen(p, "w");
	fputs(csv, f);
	fclose(f);
}

static void test_runs_summary(void **state)
{
	(void)state;
	/* Hand-made runs. ref: invocations 1000 + 1000 = 2000, gpu ms 10, 12, 14 -> median 12.
	 * tas@8: invocations (300+50) + (200+50) + (100+50) = 750 -> reduction 1 - 750/2000 = 62.5%;
	 * reuse mean (0.5 + 0.7 + 0.9)/3 = 0.7; gpu ms 4, 8, 6 -> median 6 -> speedup 12/6 = 2;
	 * tallies late 1+0+2 = 3, early 4, on_time 10, unchanged 100. */
	const char *base = tu_tmpdir("metrics_runs");
	char ref[4096], tas[4096], out[4096], err[1024];
	snprintf(ref, sizeof ref, "%s/ref", base);
	snprintf(tas, sizeof tas, "%s/tas", base);
	snprintf(out, sizeof out, "%s/out", base);
	const char *hdr = "frame,time_s,visible_samples,shaded_samples,visible_units,shaded_units,new_units,reuse_fraction,"
			  "fs_invocations,cs_invocations,gpu_ms_total,gpu_ms_shade";
	char csv[2048];
	snprintf(csv, sizeof csv, "%s\n0,0,1,1,1,1,,0,1000,,10,1\n1,0,1,1,1,1,,0,,,14,1\n2,0,1,1,1,1,,0,1000,0,12,1\n", hdr);
	make_run(ref, "ref", 8, csv);
	snprintf(csv, sizeof csv, "%s,late,early,on_time,unchanged\n0,0,1,1,1,1,,0.5,300,50,4,1,1,1,3,30\n"
		 "1,0,1,1,1,1,,0.7,200,50,8,1,0,2,3,30\n2,0,1,1,1,1,,0.9,100,50,6,1,2,1,4,40\n", hdr);
	make_run(tas, "tas", 8, csv);
	const char *runs[2] = {tas, ref};
	mtr_run_summary s[2];
	if (mtr_runs_summarise(runs, 2, -1, s, err, sizeof err))
		fail_msg("%s", err);
	assert_float_equal(s[1].invocations, 2000, 0);
	assert_float_equal(s[0].invocation_reduction, 0.625, 1e-12);
	assert_float_equal(s[0].reuse_mean, 0.7, 1e-12);
	assert_float_equal(s[1].gpu_ms_median, 12, 0);
	assert_float_equal(s[0].speedup_vs_ref, 2.0, 1e-12);
	assert_float_equal(s[0].late, 3, 0);
	assert_float_equal(s[0].early, 4, 0);
	assert_float_equal(s[0].on_time, 10, 0);
	assert_float_equal(s[0].unchanged, 100, 0);
	assert_true(isnan(s[1].late));
	assert_int_equal(mtr_runs_write(s, 2, out, err, sizeof err), 0);
	char p[4096];
	snprintf(p, sizeof p, "%s/table1.md", out);
	char *md = tu_read_file(p, NULL);
	assert_non_null(md);
	assert_non_null(strstr(md, "| tas | 62.5 |"));
	free(md);
	/* A run with a short row, and a folder that is no run. */
	snprintf(csv, sizeof csv, "%s\n0,0,1\n", hdr);
	make_run(tas, "tas", 8, csv);
	assert_int_not_equal(mtr_runs_summarise(runs, 2, -1, s, err, sizeof err), 0);
	assert_non_null(strstr(err, "row 2"));
	const char *none[1] = {base};
	assert_int_not_equal(mtr_runs_summarise(none, 1, -1, s, err, sizeof err), 0);
	assert_non_null(strstr(err, "manifest.json"));
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_hand_computed),  cmocka_unit_test(test_identical_and_single_pixel),
		cmocka_unit_test(test_percentile_vs_sort), cmocka_unit_test(test_ssim_vs_skimage),
		cmocka_unit_test(test_jnd),            cmocka_unit_test(test_colormap),
		cmocka_unit_test(test_diff_files),       cmocka_unit_test(test_runs_summary),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
