/* test_metrics.c — metrics against independently computed references:
 *  - small hand-computed images (values worked out in the comments);
 *  - percentiles against a full sort (numpy's default "linear" definition);
 *  - SSIM against scikit-image (tests/reference/ssim_reference.json, produced by ssim_reference.py), 1e-5;
 *  - Phi^-1 against R's qnorm (qnorm(0.75) = 0.6744897501960817), Wilson interval against its closed form;
 *  - FLIP against NVIDIA's FLIP v1.6 tool (../shared/reference/flip, README.md there): mean within 1e-4 of its
 *    double-precision mean, weighted median / quartiles within 1e-3, through the library and through `diff`;
 *    identical images give 0, a changed pixel is found at its place, 1x1 and odd sizes, bad input;
 *  - the metric registry: --metrics selection keeps the column layout, unknown metrics and options are refused;
 *  - bad input: sizes, frame counts, unreadable files, NaN in EXR; run folders checked against their manifest
 *    (stale, missing and resized frames, --no-exr, no manifest; test_diff_runs_checked). */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "taslab/colour.h"
#include "taslab/imageio.h"
#include "taslab/metrics.h"
#include "taslab/metrics_diff.h"
#include "taslab/metrics_flip.h"
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

static float *load_png_float(const char *path, uint32_t *w, uint32_t *h);

/* SSIM in double precision, the same definition (separable 11-tap Gaussian, valid windows), as an oracle for images
 * too large for the scikit-image cases. */
static double ssim_double(const float *A, const float *B, uint32_t w, uint32_t h)
{
	double g[11], gs = 0;
	for (int k = -5; k <= 5; k++)
		gs += g[k + 5] = exp(-(double)(k * k) / (2 * 1.5 * 1.5));
	for (int k = 0; k < 11; k++)
		g[k] /= gs;
	const uint32_t ow = w - 10, oh = h - 10;
	double *t = malloc(sizeof(double) * 5 * (size_t)h * ow), total = 0;
	for (int c = 0; c < 3; c++) {
		for (uint32_t y = 0; y < h; y++)
			for (uint32_t x = 0; x < ow; x++) {
				double s[5] = {0};
				for (int k = 0; k < 11; k++) {
					double a = A[((size_t)y * w + x + k) * 3 + c], b = B[((size_t)y * w + x + k) * 3 + c];
					s[0] += g[k] * a, s[1] += g[k] * b, s[2] += g[k] * a * a, s[3] += g[k] * b * b, s[4] += g[k] * a * b;
				}
				for (int q = 0; q < 5; q++)
					t[((size_t)q * h + y) * ow + x] = s[q];
			}
		for (uint32_t y = 0; y < oh; y++)
			for (uint32_t x = 0; x < ow; x++) {
				double s[5] = {0};
				for (int k = 0; k < 11; k++)
					for (int q = 0; q < 5; q++)
						s[q] += g[k] * t[((size_t)q * h + y + k) * ow + x];
				double ma = s[0], mb = s[1], va = s[2] - ma * ma, vb = s[3] - mb * mb, cv = s[4] - ma * mb;
				const double C1 = 6.5025, C2 = 58.5225;
				total += ((2 * ma * mb + C1) * (2 * cv + C2)) / ((ma * ma + mb * mb + C1) * (va + vb + C2));
			}
	}
	free(t);
	return total / (3.0 * ow * oh);
}

/* A crop of a rendered frame pair (tests/reference/ssim_frame_{ref,test}.png: the calm scene, shaded vs trivial
 * shading, 160x90): bright flat regions make E[a^2] - E[a]^2 lose most of its digits in float. SSIM must be within
 * 1e-5 (the scikit-image tolerance) of the double-precision result; the implementation before the plug-in registry
 * was 1.2e-4 off here (and 5.8e-5 on the whole 1080p frame), the current one is 2e-6 off. */
static void test_ssim_frame(void **state)
{
	(void)state;
	uint32_t w, h, w2, h2;
	float *a = load_png_float(TASLAB_SOURCE_DIR "/tests/reference/ssim_frame_ref.png", &w, &h);
	float *b = load_png_float(TASLAB_SOURCE_DIR "/tests/reference/ssim_frame_test.png", &w2, &h2);
	assert_true(w == 160 && h == 90 && w2 == w && h2 == h);
	mtr_image A = {w, h, a}, B = {w, h, b};
	double expect = ssim_double(a, b, w, h);
	for (int threads = 1; threads <= 2; threads++) {
		double got = mtr_ssim(&A, &B, threads);
		if (fabs(got - expect) > 1e-5)
			fail_msg("%d threads: SSIM %.9f, double precision %.9f (diff %.1e)", threads, got, expect, got - expect);
	}
	/* Issue 31.9: an image against itself is exactly 1 (eq. 13 is x/x there; it was 1 +- 1e-9 from rounding), for
	 * code values and for the non-integer values of tone-mapped EXRs (a fixed pseudo-random image 0..255). */
	float *n = malloc((size_t)w * h * 3 * sizeof *n);
	uint32_t seed = 12345;
	for (size_t i = 0; i < (size_t)w * h * 3; i++) {
		seed = seed * 1664525u + 1013904223u;
		n[i] = (float)(seed >> 8) / (float)(1u << 24) * 255.0f;
	}
	mtr_image N = {w, h, n};
	for (int threads = 1; threads <= 3; threads++) {
		double aa = mtr_ssim(&A, &A, threads), bb = mtr_ssim(&B, &B, threads), nn = mtr_ssim(&N, &N, threads);
		if (aa != 1.0 || bb != 1.0 || nn != 1.0)
			fail_msg("%d threads: SSIM of an image with itself 1%+.3e, 1%+.3e, 1%+.3e (noise); expected exactly 1", threads,
				 aa - 1, bb - 1, nn - 1);
	}
	free(n);
	free(a);
	free(b);
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
	/* Issue 30.5: a reference that is no folder is an input error (was a bare -1, read as a bad argument). */
	d.ref = "/nonexistent/ref";
	assert_int_equal(mtr_diff_run(&d, &r, err, sizeof err), TL_ERR_INPUT);
	assert_non_null(strstr(err, "not a folder"));
	d.ref = a;
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

/* A run folder for diff: manifest.json for frames 0..2 at w x h, PNG frames 0..n-1 of size fw x fh in RUN/frames. */
static void make_png_run(const char *dir, int n, uint32_t fw, uint32_t fh, int bump)
{
	char p[4200];
	snprintf(p, sizeof p, "rm -rf %s && mkdir -p %s/frames", dir, dir);
	assert_int_equal(system(p), 0);
	snprintf(p, sizeof p, "%s/frames", dir);
	write_png_dir(p, n, fw, fh, bump);
	snprintf(p, sizeof p, "%s/manifest.json", dir);
	FILE *f = fopen(p, "w");
	fputs("{\"inputs\": {\"method\": \"ref\", \"frames\": [0, 2], \"size\": [20, 16], \"fps\": 60}, "
	      "\"outputs\": {\"png\": true, \"exr\": false}}", f);
	fclose(f);
}

/* Issue 12, stale run folders: diff checks a run folder's frames against its manifest (range, presence, size) and
 * refuses an incomplete run, where it used to compare whatever frames the folder held. */
static void test_diff_runs_checked(void **state)
{
	(void)state;
	const char *base = tu_tmpdir("metrics_diff_runs");
	char a[4096], b[4096], out[4096], err[1024], p[4200];
	snprintf(a, sizeof a, "%s/a", base);
	snprintf(b, sizeof b, "%s/b", base);
	snprintf(out, sizeof out, "%s/out", base);
	mtr_diff_desc d = {.ref = a, .test = b, .out = out, .threads = 1, .metrics = "maxrgb"};
	mtr_diff_result r;
	make_png_run(a, 3, 20, 16, -1);
	make_png_run(b, 3, 20, 16, 1);
	if (mtr_diff_run(&d, &r, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(r.frames, 3);
	/* A frame left by a longer earlier run, in both folders (their names still match). */
	make_png_run(a, 4, 20, 16, -1);
	make_png_run(b, 4, 20, 16, 1);
	assert_int_equal(mtr_diff_run(&d, &r, err, sizeof err), TL_ERR_INPUT);
	assert_non_null(strstr(err, "000003.png: not a frame of this run"));
	/* The same frame missing in both. */
	make_png_run(a, 3, 20, 16, -1);
	make_png_run(b, 3, 20, 16, 1);
	snprintf(p, sizeof p, "%s/frames/000001.png", a);
	unlink(p);
	snprintf(p, sizeof p, "%s/frames/000001.png", b);
	unlink(p);
	assert_int_equal(mtr_diff_run(&d, &r, err, sizeof err), TL_ERR_INPUT);
	assert_non_null(strstr(err, "frame 000001.png is missing"));
	/* Every frame of both runs at another size than the manifest's. */
	make_png_run(a, 3, 10, 8, -1);
	make_png_run(b, 3, 10, 8, 1);
	assert_int_not_equal(mtr_diff_run(&d, &r, err, sizeof err), 0);
	assert_non_null(strstr(err, "differs from the run's 20x16"));
	/* EXRs of a --no-exr run; an incomplete run (no manifest). */
	make_png_run(a, 3, 20, 16, -1);
	make_png_run(b, 3, 20, 16, 1);
	colour_desc cdesc = {0};
	colour *cl = NULL;
	if (colour_create(&cdesc, &cl, err, sizeof err))
		fail_msg("%s", err);
	d.format = MTR_FORMAT_EXR;
	d.colour = cl;
	assert_int_not_equal(mtr_diff_run(&d, &r, err, sizeof err), 0);
	assert_non_null(strstr(err, "--no-exr"));
	colour_destroy(&cl);
	d.format = MTR_FORMAT_PNG;
	d.colour = NULL;
	snprintf(p, sizeof p, "%s/manifest.json", b);
	unlink(p);
	assert_int_not_equal(mtr_diff_run(&d, &r, err, sizeof err), 0);
	assert_non_null(strstr(err, "without manifest.json"));
	/* No summary of a refused comparison. */
	snprintf(p, sizeof p, "%s/summary.json", out);
	assert_false(tu_file_exists(p));
	/* --out inside a run folder (the CLI). */
	make_png_run(b, 3, 20, 16, 1);
	char args[8192];
	snprintf(args, sizeof args, "metrics diff --ref %s --test %s --out %s/diff", a, b, b);
	tu_expect_cli_error(args, "lies inside the run folder");
}

/* ------------------------------------------------------------------ FLIP */

typedef struct flip_case {
	char name[128], ref[256], test[256];
	unsigned w, h;
	double mean, mean_f64, median, q1, q3, min, max, ppd;
} flip_case;

/* Reads ../shared/reference/flip/expected.csv (NVIDIA FLIP v1.6 values, README.md beside it); 0 when absent. */
static size_t flip_cases(flip_case *out, size_t max)
{
	FILE *fp = fopen(TASLAB_SHARED_DIR "/reference/flip/expected.csv", "r");
	if (!fp)
		return 0;
	char line[2048];
	size_t n = 0;
	if (!fgets(line, sizeof line, fp)) {
		fclose(fp);
		return 0;
	}
	while (n < max && fgets(line, sizeof line, fp)) {
		flip_case *e = &out[n];
		memset(e, 0, sizeof *e);
		for (char *c = line; *c; c++)
			if (*c == ',')
				*c = ' ';
		if (sscanf(line, "%127s %u %u %lf %lf %lf %lf %lf %lf %lf %lf %255s %255s", e->name, &e->w, &e->h, &e->mean,
			   &e->mean_f64, &e->median, &e->q1, &e->q3, &e->min, &e->max, &e->ppd, e->ref, e->test) == 13)
			n++;
	}
	fclose(fp);
	return n;
}

static float *load_png_float(const char *path, uint32_t *w, uint32_t *h)
{
	uint8_t *px = NULL;
	char err[512];
	if (imageio_read_rgb8(path, w, h, &px, err, sizeof err))
		fail_msg("%s", err);
	float *f = malloc((size_t)*w * *h * 3 * sizeof *f);
	for (size_t i = 0; i < (size_t)*w * *h * 3; i++)
		f[i] = px[i];
	free(px);
	return f;
}

static void test_flip_reference(void **state)
{
	(void)state;
	flip_case cs[16];
	size_t n = flip_cases(cs, 16);
	if (!tu_require(n > 0, "test_flip_reference: no FLIP reference values at %s/reference/flip (the shared folder "
			       "beside the repository)", TASLAB_SHARED_DIR))
		skip();
	assert_true(n >= 5);
	mtr_flip *f = NULL;
	char err[256];
	assert_int_equal(mtr_flip_create(MTR_FLIP_PPD_DEFAULT, &f, err, sizeof err), 0);
	for (size_t i = 0; i < n; i++) {
		const flip_case *e = &cs[i];
		char pa[1024], pb[1024];
		uint32_t w, h, w2, h2;
		snprintf(pa, sizeof pa, "%s/reference/flip/%s", TASLAB_SHARED_DIR, e->ref);
		snprintf(pb, sizeof pb, "%s/reference/flip/%s", TASLAB_SHARED_DIR, e->test);
		float *a = load_png_float(pa, &w, &h), *b = load_png_float(pb, &w2, &h2);
		assert_true(w == e->w && h == e->h && w2 == w && h2 == h);
		assert_true(fabs(e->ppd - MTR_FLIP_PPD_DEFAULT) < 1e-5); /* the csv prints it rounded */
		float *map = malloc((size_t)w * h * sizeof *map);
		for (int threads = 1; threads <= 2; threads++) {
			double mean = -1;
			assert_int_equal(mtr_flip_compute(f, w, h, a, b, map, threads, &mean, err, sizeof err), 0);
			mtr_flip_pool p;
			assert_int_equal(mtr_flip_pool_stats(map, (size_t)w * h, &p), 0);
			if (fabs(mean - e->mean_f64) > 1e-4 || fabs(p.weighted_median - e->median) > 1e-3 ||
			    fabs(p.q1_weighted - e->q1) > 1e-3 || fabs(p.q3_weighted - e->q3) > 1e-3 ||
			    fabs(p.min - e->min) > 1e-3 || fabs(p.max - e->max) > 1e-3)
				fail_msg("%s (%d threads): mean %.9f (ref %.9f), median %.6f (%.6f), q1 %.6f (%.6f), q3 %.6f (%.6f), "
					 "min %.6f (%.6f), max %.6f (%.6f)",
					 e->name, threads, mean, e->mean_f64, p.weighted_median, e->median, p.q1_weighted, e->q1,
					 p.q3_weighted, e->q3, p.min, e->min, p.max, e->max);
			assert_float_equal(p.mean, mean, 1e-9);
			if (e->mean_f64 == 0)
				assert_true(mean == 0 && p.max == 0);
		}
		/* The same through the comparer: flip_mean exact, the histogram-pooled quartiles within 1e-3. */
		mtr_comparer *c = NULL;
		mtr_compare_desc d = {.metrics = "flip", .threads = 2};
		assert_int_equal(mtr_comparer_create(&d, &c, err, sizeof err), 0);
		mtr_image A = {w, h, a}, B = {w, h, b};
		mtr_frame_stats s, pooled;
		if (mtr_comparer_frame(c, &A, &B, NULL, NULL, NULL, NULL, &s, err, sizeof err))
			fail_msg("%s", err);
		mtr_comparer_pool(c, &s, 1, &pooled);
		if (fabs(pooled.flip_mean - e->mean_f64) > 1e-4 || fabs(pooled.flip_weighted_median - e->median) > 1e-3 ||
		    fabs(pooled.flip_q1_weighted - e->q1) > 1e-3 || fabs(pooled.flip_q3_weighted - e->q3) > 1e-3 ||
		    fabs(pooled.flip_min - e->min) > 1e-3 || fabs(pooled.flip_max - e->max) > 1e-3)
			fail_msg("%s pooled: mean %.9f (%.9f) median %.6f (%.6f) q1 %.6f (%.6f) q3 %.6f (%.6f)", e->name,
				 pooled.flip_mean, e->mean_f64, pooled.flip_weighted_median, e->median, pooled.flip_q1_weighted,
				 e->q1, pooled.flip_q3_weighted, e->q3);
		assert_true(isnan(pooled.psnr) && isnan(pooled.ssim) && isnan(pooled.mean)); /* not selected */
		mtr_comparer_destroy(&c);
		assert_null(c);
		free(map);
		free(a);
		free(b);
	}
	mtr_flip_destroy(&f);
	assert_null(f);
}

/* Reference images as a run: `diff --metrics flip` writes flip_mean and the pooled statistics into summary.json. */
static void test_flip_diff(void **state)
{
	(void)state;
	flip_case cs[16];
	size_t n = flip_cases(cs, 16), k = 0;
	while (k < n && strcmp(cs[k].name, "noise_320x180"))
		k++;
	if (!tu_require(k < n, "test_flip_diff: no FLIP reference case noise_320x180 at %s/reference/flip (the shared "
			       "folder beside the repository)", TASLAB_SHARED_DIR))
		skip();
	const char *base = tu_tmpdir("metrics_flip_diff");
	char cmd[8192], out[4096], err[1024], p[4096];
	snprintf(cmd, sizeof cmd, "mkdir -p %s/a %s/b && cp %s/reference/flip/%s %s/a/000000.png && "
		 "cp %s/reference/flip/%s %s/b/000000.png", base, base, TASLAB_SHARED_DIR, cs[k].ref, base,
		 TASLAB_SHARED_DIR, cs[k].test, base);
	assert_int_equal(system(cmd), 0);
	char a[4096], b[4096];
	snprintf(a, sizeof a, "%s/a", base);
	snprintf(b, sizeof b, "%s/b", base);
	snprintf(out, sizeof out, "%s/out", base);
	mtr_diff_desc d = {.ref = a, .test = b, .out = out, .threads = 2, .metrics = "maxrgb,flip", .heatmaps = true};
	mtr_diff_result r;
	if (mtr_diff_run(&d, &r, err, sizeof err))
		fail_msg("%s", err);
	snprintf(p, sizeof p, "%s/summary.json", out);
	json_error_t je;
	json_t *js = json_load_file(p, 0, &je);
	assert_non_null(js);
	assert_float_equal(json_real_value(json_object_get(js, "flip_mean")), cs[k].mean_f64, 1e-4);
	assert_float_equal(json_real_value(json_object_get(js, "flip_weighted_median")), cs[k].median, 1e-3);
	assert_float_equal(json_real_value(json_object_get(js, "flip_q1_weighted")), cs[k].q1, 1e-3);
	assert_float_equal(json_real_value(json_object_get(js, "flip_q3_weighted")), cs[k].q3, 1e-3);
	assert_float_equal(json_real_value(json_object_get(js, "flip_min")), cs[k].min, 1e-3);
	assert_float_equal(json_real_value(json_object_get(js, "flip_max")), cs[k].max, 1e-3);
	assert_true(json_is_null(json_object_get(js, "psnr")) && json_is_null(json_object_get(js, "ssim")));
	assert_true(json_is_real(json_object_get(js, "maxrgb_mean")));
	json_decref(js);
	snprintf(p, sizeof p, "%s/heatmaps/flip/000000.png", out);
	assert_true(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/heatmaps/000000.png", out);
	assert_true(tu_file_exists(p));
	/* frames.csv: every column of DESIGN section 6, the unselected ones empty. */
	snprintf(p, sizeof p, "%s/frames.csv", out);
	char *csv = tu_read_file(p, NULL);
	assert_non_null(csv);
	const char *row = strchr(csv, '\n') + 1;
	int commas = 0;
	for (const char *c = row; *c && *c != '\n'; c++)
		commas += *c == ',';
	assert_int_equal(commas, 15);
	assert_non_null(strstr(row, ",,,,")); /* psnr, ssim, flicker_mean empty */
	free(csv);
}

static void test_flip_identical_and_pixel(void **state)
{
	(void)state;
	mtr_flip *f = NULL;
	char err[256];
	assert_int_equal(mtr_flip_create(MTR_FLIP_PPD_DEFAULT, &f, err, sizeof err), 0);
	/* Identical non-integral images (the EOTF formula path): exactly 0 everywhere. */
	const uint32_t w = 97, h = 53;
	float *a = malloc(sizeof(float) * 3 * w * h), *map = malloc(sizeof(float) * w * h);
	unsigned seed = 3;
	for (size_t i = 0; i < 3 * (size_t)w * h; i++) {
		seed = seed * 1103515245u + 12345u;
		a[i] = (float)((seed >> 8) % 25500) / 100.0f;
	}
	double mean = -1;
	assert_int_equal(mtr_flip_compute(f, w, h, a, a, map, 2, &mean, err, sizeof err), 0);
	assert_true(mean == 0.0);
	for (size_t i = 0; i < (size_t)w * h; i++)
		assert_true(map[i] == 0.0f);
	free(a);
	free(map);
	/* One changed pixel (128 -> 168 grey at (37, 22)) on 64x64: the maximum is within 2 pixels of it, the error is
	 * 0 beyond the 21x21 footprint of the filters (radius 10 at 67 ppd) and nonzero inside. */
	const uint32_t W = 64, H = 64, px = 37, py = 22;
	float *ra = malloc(sizeof(float) * 3 * W * H), *rb = malloc(sizeof(float) * 3 * W * H);
	map = malloc(sizeof(float) * W * H);
	for (size_t i = 0; i < 3 * (size_t)W * H; i++)
		ra[i] = rb[i] = 128.0f;
	for (int c = 0; c < 3; c++)
		rb[3 * ((size_t)py * W + px) + c] = 168.0f;
	assert_int_equal(mtr_flip_compute(f, W, H, ra, rb, map, 0, &mean, err, sizeof err), 0);
	assert_true(mean > 0);
	uint32_t mx = 0, my = 0;
	float best = -1;
	int inside = 0;
	for (uint32_t y = 0; y < H; y++)
		for (uint32_t x = 0; x < W; x++) {
			float v = map[(size_t)y * W + x];
			if (v > best)
				best = v, mx = x, my = y;
			if (abs((int)x - (int)px) > 10 || abs((int)y - (int)py) > 10)
				assert_true(v == 0.0f);
			else
				inside += v > 0.0f;
		}
	assert_true(abs((int)mx - (int)px) <= 2 && abs((int)my - (int)py) <= 2);
	assert_true(inside > 0);
	free(ra);
	free(rb);
	free(map);
	mtr_flip_destroy(&f);
}

static void test_flip_sizes_and_errors(void **state)
{
	(void)state;
	mtr_flip *f = NULL;
	char err[256];
	assert_int_equal(mtr_flip_create(MTR_FLIP_PPD_DEFAULT, &f, err, sizeof err), 0);
	/* 1x1, thin and odd sizes (smaller than the kernels, strip and band boundaries): in [0,1], NULL map and 1 vs 4
	 * threads agree exactly. */
	const uint32_t sizes[][2] = {{1, 1}, {3, 2}, {2, 3}, {1, 40}, {40, 1}, {17, 5}, {700, 37}};
	unsigned seed = 11;
	for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
		uint32_t w = sizes[k][0], h = sizes[k][1];
		float *a = malloc(sizeof(float) * 3 * w * h), *b = malloc(sizeof(float) * 3 * w * h);
		float *map = malloc(sizeof(float) * w * h);
		for (size_t i = 0; i < 3 * (size_t)w * h; i++) {
			seed = seed * 1103515245u + 12345u;
			a[i] = (float)((seed >> 16) % 256);
			seed = seed * 1103515245u + 12345u;
			b[i] = (float)((seed >> 16) % 256);
		}
		double m1 = -1, m2 = -2, s = 0;
		assert_int_equal(mtr_flip_compute(f, w, h, a, b, map, 1, &m1, err, sizeof err), 0);
		assert_int_equal(mtr_flip_compute(f, w, h, a, b, NULL, 4, &m2, err, sizeof err), 0);
		for (size_t i = 0; i < (size_t)w * h; i++) {
			assert_true(map[i] >= 0.0f && map[i] <= 1.0f);
			s += map[i];
		}
		assert_true(m1 > 0 && m1 == m2);
		assert_float_equal(s / ((double)w * h), m1, 1e-12);
		free(a);
		free(b);
		free(map);
	}
	/* Out-of-range inputs are clamped to 0..255 (metrics_flip.h): a pair with values below 0, above 255, infinite
	 * and NaN gives the same map, bit for bit, as the pair clamped by hand (NaN as 0). 33x19 pixels: 8-value vector
	 * chunks and scalar tails. */
	{
		const uint32_t w = 33, h = 19;
		const size_t n = 3 * (size_t)w * h;
		float *a = malloc(sizeof(float) * n), *b = malloc(sizeof(float) * n), *ac = malloc(sizeof(float) * n),
		      *bc = malloc(sizeof(float) * n), *m1 = malloc(sizeof(float) * w * h), *m2 = malloc(sizeof(float) * w * h);
		const float odd[] = {-7.5f, 300.0f, INFINITY, -INFINITY, NAN, 255.5f, -0.0f, 1e30f};
		for (size_t i = 0; i < n; i++) {
			seed = seed * 1103515245u + 12345u;
			a[i] = (float)((seed >> 16) % 256);
			b[i] = i % 5 == 0 ? odd[(i / 5) % 8] : 255.0f - a[i];
		}
		for (size_t i = 0; i < n; i++) {
			ac[i] = a[i];
			bc[i] = isnan(b[i]) ? 0.0f : (b[i] < 0 ? 0.0f : (b[i] > 255 ? 255.0f : b[i]));
		}
		double e1 = -1, e2 = -2;
		assert_int_equal(mtr_flip_compute(f, w, h, a, b, m1, 1, &e1, err, sizeof err), 0);
		assert_int_equal(mtr_flip_compute(f, w, h, ac, bc, m2, 1, &e2, err, sizeof err), 0);
		assert_true(e1 > 0 && e1 == e2);
		assert_memory_equal(m1, m2, sizeof(float) * w * h);
		free(a), free(b), free(ac), free(bc), free(m1), free(m2);
	}
	/* Bad input: one-line messages, tl_err codes. */
	float px[3] = {1, 2, 3};
	double mean;
	err[0] = 0;
	assert_int_equal(mtr_flip_compute(f, 0, 5, px, px, NULL, 1, &mean, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "empty"));
	assert_int_equal(mtr_flip_compute(f, 1, 1, NULL, px, NULL, 1, &mean, err, sizeof err), TL_ERR_ARG);
	assert_int_equal(mtr_flip_compute(NULL, 1, 1, px, px, NULL, 1, &mean, err, sizeof err), TL_ERR_ARG);
	mtr_flip *g = (mtr_flip *)1;
	assert_int_equal(mtr_flip_create(0.0, &g, err, sizeof err), TL_ERR_ARG);
	assert_null(g);
	assert_non_null(strstr(err, "pixels per degree"));
	assert_int_equal(mtr_flip_create(NAN, &g, NULL, 0), TL_ERR_ARG);
	mtr_flip_pool p;
	assert_int_equal(mtr_flip_pool_stats(px, 0, &p), TL_ERR_ARG);
	mtr_flip_destroy(&f);
	mtr_flip_destroy(&f); /* NULL is fine */
	/* Sizes through the comparer: a size mismatch and a frame of another size than the previous ones. */
	mtr_comparer *c = NULL;
	mtr_compare_desc d = {.metrics = "flip,maxrgb"};
	assert_int_equal(mtr_comparer_create(&d, &c, err, sizeof err), 0);
	float big[3 * 6] = {0}, small[3 * 4] = {0};
	mtr_image A = {3, 2, big}, B = {2, 2, small};
	mtr_frame_stats s;
	assert_int_equal(mtr_comparer_frame(c, &A, &B, NULL, NULL, NULL, NULL, &s, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "sizes differ"));
	assert_int_equal(mtr_comparer_frame(c, &B, &B, NULL, NULL, NULL, NULL, &s, err, sizeof err), 0);
	assert_true(s.flip_mean == 0 && s.mean == 0 && isnan(s.ssim) && isnan(s.psnr));
	assert_int_equal(mtr_comparer_frame(c, &A, &A, NULL, NULL, NULL, NULL, &s, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "previous frames"));
	mtr_comparer_destroy(&c);
}

/* ------------------------------------------------------------------ the registry */

static void test_registry(void **state)
{
	(void)state;
	char list[256], err[256];
	assert_string_equal(mtr_metric_list(list, sizeof list), "maxrgb,psnr,ssim,flicker,flip");
	assert_int_equal(mtr_metric_count(), 5);
	assert_int_equal(mtr_metric_find("flip"), 4);
	assert_int_equal(mtr_metric_find("vmaf"), -1);
	uint32_t m;
	assert_int_equal(mtr_metric_parse("maxrgb,flip", &m, err, sizeof err), 0);
	assert_int_equal(m, 1u | 16u);
	assert_int_equal(mtr_metric_parse(NULL, &m, err, sizeof err), 0);
	assert_int_equal(m, 31u);
	assert_int_equal(mtr_metric_parse("all", &m, err, sizeof err), 0);
	assert_int_equal(m, 31u);
	assert_int_equal(mtr_metric_parse("maxrgb,vmaf", &m, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "'vmaf'"));
	assert_non_null(strstr(err, "maxrgb,psnr,ssim,flicker,flip"));
	assert_int_equal(mtr_metric_parse("maxrgb,", &m, err, sizeof err), TL_ERR_ARG); /* empty item */
	/* The column layout is DESIGN section 6's, whatever is selected. */
	const char *frames_cols = "maxrgb_mean,maxrgb_p50,maxrgb_p95,maxrgb_p99,maxrgb_max,exceed_2,exceed_4,exceed_8,"
				  "exceed_16,exceed_32,exceed_64,psnr,ssim,flicker_mean,flip_mean";
	char got[1024] = "";
	for (int c = 0; mtr_column_name(c); c++)
		if (mtr_column_where(c) & 1u)
			snprintf(got + strlen(got), sizeof got - strlen(got), "%s%s", got[0] ? "," : "", mtr_column_name(c));
	assert_string_equal(got, frames_cols);
	/* Options: known and in range, or refused with a message. */
	mtr_comparer *c = NULL;
	mtr_option_value bad[] = {{"ppd", 0.0}}, unknown[] = {{"gamma", 2.2}}, good[] = {{"ppd", 30.0}};
	mtr_compare_desc d = {.metrics = "flip", .options = bad, .option_count = 1};
	assert_int_equal(mtr_comparer_create(&d, &c, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "--ppd"));
	d.options = unknown;
	assert_int_equal(mtr_comparer_create(&d, &c, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "gamma"));
	d.metrics = "ssim,nope";
	d.options = good;
	assert_int_equal(mtr_comparer_create(&d, &c, err, sizeof err), TL_ERR_ARG);
	assert_null(c);
	/* A lower ppd (viewer closer) changes FLIP: the same pair differs at 30 and 67 ppd. */
	d.metrics = "flip";
	assert_int_equal(mtr_comparer_create(&d, &c, err, sizeof err), 0);
	float a[3 * 16 * 16], b[3 * 16 * 16];
	for (int i = 0; i < 3 * 256; i++)
		a[i] = (float)(i % 200), b[i] = (float)((i * 3) % 200);
	mtr_image A = {16, 16, a}, B = {16, 16, b};
	mtr_frame_stats s30, s67;
	assert_int_equal(mtr_comparer_frame(c, &A, &B, NULL, NULL, NULL, NULL, &s30, err, sizeof err), 0);
	mtr_comparer_destroy(&c);
	assert_int_equal(mtr_frame_compare(&A, &B, NULL, NULL, NULL, 1, &s67, err, sizeof err), 0);
	assert_true(s30.flip_mean > 0 && s67.flip_mean > 0 && fabs(s30.flip_mean - s67.flip_mean) > 1e-4);
	assert_int_equal(s67.metrics, 31u);
	assert_int_equal(s30.metrics, 16u);
}

/* Percentiles from the pass's histogram (integral d) equal the quickselect ones on the same map; fractional inputs
 * take the quickselect path and agree with a full sort. */
static void test_percentile_paths(void **state)
{
	(void)state;
	const uint32_t w = 123, h = 45;
	size_t n = (size_t)w * h;
	float *a = malloc(n * 3 * sizeof *a), *b = malloc(n * 3 * sizeof *b), *map = malloc(n * sizeof *map);
	for (int frac = 0; frac <= 1; frac++) {
		fill(a, w, h, 5);
		fill(b, w, h, 9);
		if (frac)
			for (size_t i = 0; i < n * 3; i++)
				a[i] = a[i] * 0.97f + 0.25f;
		mtr_image A = {w, h, a}, B = {w, h, b};
		mtr_frame_stats s;
		char err[256];
		assert_int_equal(mtr_frame_compare(&A, &B, NULL, NULL, map, 2, &s, err, sizeof err), 0);
		float *sorted = malloc(n * sizeof *sorted);
		memcpy(sorted, map, n * sizeof *map);
		qsort(sorted, n, sizeof *sorted, cmp_f);
		const double pct[3] = {50, 95, 99}, got[3] = {s.p50, s.p95, s.p99};
		for (int k = 0; k < 3; k++) {
			double hh = (double)(n - 1) * pct[k] / 100.0, lo = floor(hh);
			float flo = sorted[(size_t)lo], fhi = sorted[(size_t)lo + 1];
			double ref = flo + (hh - lo) * (fhi - flo);
			if (fabs(got[k] - ref) > 1e-9)
				fail_msg("%s inputs: p%g %.9f, sort %.9f", frac ? "fractional" : "integral", pct[k], got[k], ref);
		}
		free(sorted);
	}
	free(a);
	free(b);
	free(map);
}

static void make_run(const char *dir, const char *method, double T, const char *size, const char *csv)
{
	char p[4096];
	snprintf(p, sizeof p, "mkdir -p %s", dir);
	assert_int_equal(system(p), 0);
	snprintf(p, sizeof p, "%s/manifest.json", dir);
	FILE *f = fopen(p, "w");
	/* method_facts as the registry writes them (issue 30.1): the atlas methods reduce against sa */
	bool ref = !strcmp(method, "ref"), atlas = !strcmp(method, "sa") || !strcmp(method, "tasa");
	fprintf(f, "{\"inputs\": {\"method\": \"%s\", \"scene\": \"s\", \"camera\": \"c\", \"threshold\": %g, "
		   "\"frames\": [0, 2], \"size\": %s, \"fps\": 60, \"method_facts\": {\"family\": \"x\", \"baseline\": \"%s\", "
		   "\"reference\": %s, \"takes_threshold\": true, \"takes_period\": false}}}",
		method, T, size, atlas ? "sa" : "ref", ref ? "true" : "false");
	fclose(f);
	snprintf(p, sizeof p, "%s/stats.csv", dir);
	f = fopen(p, "w");
	fputs(csv, f);
	fclose(f);
}

static void test_runs_summary(void **state)
{
	(void)state;
	/* Hand-made runs (3 frames, 100 visible samples each).
	 * ref: shaded 100 per frame = 300, gpu ms 10, 14, 12 -> median 12; fs_invocations 1000 + 1000 (one empty cell).
	 * tas@8: shaded 30 + 20 + 25 = 75 -> reduction 1 - 75/300 = 75%; reuse mean (0.7 + 0.8 + 0.75)/3 = 0.75;
	 * gpu ms 4, 8, 6 -> median 6 -> speedup 12/6 = 2; late_samples 1 + 0 + 2 = 3 of reused 70 + 80 + 75 = 225.
	 * big: the same as tas but 16x16 frames: no ref or baseline run of its size -> NAN. */
	const char *base = tu_tmpdir("metrics_runs");
	char ref[4096], tas[4096], big[4096], out[4096], err[1024];
	snprintf(ref, sizeof ref, "%s/ref", base);
	snprintf(tas, sizeof tas, "%s/tas", base);
	snprintf(big, sizeof big, "%s/big", base);
	snprintf(out, sizeof out, "%s/out", base);
	const char *hdr = "frame,time_s,visible_samples,shaded_samples,visible_units,shaded_units,new_units,reuse_fraction,"
			  "fs_invocations,cs_invocations,gpu_ms_total,gpu_ms_shade";
	char csv[2048];
	snprintf(csv, sizeof csv, "%s\n0,0,100,100,1,1,,0,1000,,10,1\n1,0,100,100,1,1,,0,,,14,1\n2,0,100,100,1,1,,0,1000,0,12,1\n",
		 hdr);
	make_run(ref, "ref", 8, "[8, 8]", csv);
	snprintf(csv, sizeof csv,
		 "%s,reused_samples,late_samples\n0,0,100,30,1,1,,0.7,300,50,4,1,70,1\n"
		 "1,0,100,20,1,1,,0.8,200,50,8,1,80,0\n2,0,100,25,1,1,,0.75,100,50,6,1,75,2\n",
		 hdr);
	make_run(tas, "tas", 8, "[8, 8]", csv);
	make_run(big, "tas", 8, "[16, 16]", csv);
	const char *runs[3] = {tas, ref, big};
	mtr_run_summary s[3];
	if (mtr_runs_summarise(runs, 3, NULL, s, err, sizeof err))
		fail_msg("%s", err);
	assert_float_equal(s[1].shaded_samples, 300, 0);
	assert_float_equal(s[1].fs_invocations, 2000, 0);
	assert_float_equal(s[0].shaded_samples, 75, 0);
	assert_float_equal(s[0].reduction, 0.75, 1e-12);
	assert_string_equal(s[0].baseline, "ref");
	assert_float_equal(s[1].reduction, 0, 0);
	assert_float_equal(s[0].reuse_mean, 0.75, 1e-12);
	assert_float_equal(s[1].gpu_ms_median, 12, 0);
	assert_float_equal(s[0].speedup_vs_ref, 2.0, 1e-12);
	assert_float_equal(s[0].late_samples, 3, 0);
	assert_float_equal(s[0].reused_samples, 225, 0);
	assert_true(isnan(s[1].late_samples) && isnan(s[1].allocated_samples));
	assert_true(isnan(s[2].reduction) && isnan(s[2].speedup_vs_ref)); /* no partner of its size */
	assert_int_equal(mtr_runs_write(s, 3, out, err, sizeof err), 0);
	char p[4096];
	snprintf(p, sizeof p, "%s/table1.md", out);
	char *md = tu_read_file(p, NULL);
	assert_non_null(md);
	assert_non_null(strstr(md, "| tas | 25 | 75.00 % vs ref | 75.00 % | 2.00x |"));
	assert_non_null(strstr(md, "## s / c (), 16x16, 3 frames from 0"));
	free(md);
	snprintf(p, sizeof p, "%s/runs.csv", out);
	char *rcsv = tu_read_file(p, NULL);
	assert_non_null(strstr(rcsv, ",reused_samples,late_samples,late_percent\n"));
	assert_non_null(strstr(rcsv, ",225,3,1.3333\n")); /* late_percent = 3 / 225 */
	free(rcsv);
	/* An atlas method reduces against sa when an sa run of the same clip is there (Table 1), else against ref. */
	char sa_run[4096], tasa_run[4096];
	snprintf(sa_run, sizeof sa_run, "%s/sa", base);
	snprintf(tasa_run, sizeof tasa_run, "%s/tasa", base);
	snprintf(csv, sizeof csv, "%s\n0,0,100,200,1,1,,0,,,1,1\n1,0,100,200,1,1,,0,,,1,1\n2,0,100,200,1,1,,0,,,1,1\n", hdr);
	make_run(sa_run, "sa", 0, "[8, 8]", csv);
	snprintf(csv, sizeof csv, "%s\n0,0,100,200,1,1,,0,,,1,1\n1,0,100,50,1,1,,0,,,1,1\n2,0,100,50,1,1,,0,,,1,1\n", hdr);
	make_run(tasa_run, "tasa", 8, "[8, 8]", csv);
	const char *atlas_runs[3] = {tasa_run, ref, sa_run};
	mtr_run_summary sa3[3];
	if (mtr_runs_summarise(atlas_runs, 3, NULL, sa3, err, sizeof err))
		fail_msg("%s", err);
	assert_string_equal(sa3[0].baseline, "sa");
	assert_float_equal(sa3[0].reduction, 0.5, 1e-12); /* 1 - 300 / 600 */
	assert_string_equal(sa3[2].baseline, "sa");
	if (mtr_runs_summarise(atlas_runs, 2, NULL, sa3, err, sizeof err)) /* no sa run: against ref */
		fail_msg("%s", err);
	assert_string_equal(sa3[0].baseline, "ref");
	assert_float_equal(sa3[0].reduction, 0.0, 1e-12);
	/* Another baseline variant: reductions against it. */
	if (mtr_runs_summarise(runs, 3, "tas", s, err, sizeof err))
		fail_msg("%s", err);
	assert_float_equal(s[1].reduction, -3.0, 1e-12); /* ref shades 4x as much as tas */
	/* A run with a short row, and a folder that is no run. */
	snprintf(csv, sizeof csv, "%s\n0,0,1\n", hdr);
	make_run(tas, "tas", 8, "[8, 8]", csv);
	assert_int_not_equal(mtr_runs_summarise(runs, 2, NULL, s, err, sizeof err), 0);
	assert_non_null(strstr(err, "row 2"));
	make_run(tas, "tas", 8, "[8, 8]", csv); /* a manifest from before method_facts: render it again */
	snprintf(p, sizeof p, "sed -i 's/, \"method_facts\".*/}}/' %s/manifest.json", tas);
	assert_int_equal(system(p), 0);
	assert_int_not_equal(mtr_runs_summarise(runs, 2, NULL, s, err, sizeof err), 0);
	assert_non_null(strstr(err, "render the run again"));
	const char *none[1] = {base};
	assert_int_not_equal(mtr_runs_summarise(none, 1, NULL, s, err, sizeof err), 0);
	assert_non_null(strstr(err, "manifest.json"));
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_hand_computed),  cmocka_unit_test(test_identical_and_single_pixel),
		cmocka_unit_test(test_percentile_vs_sort), cmocka_unit_test(test_ssim_vs_skimage),
		cmocka_unit_test(test_jnd),            cmocka_unit_test(test_colormap),
		cmocka_unit_test(test_diff_files),       cmocka_unit_test(test_runs_summary),
		cmocka_unit_test(test_flip_reference),   cmocka_unit_test(test_flip_diff),
		cmocka_unit_test(test_flip_identical_and_pixel), cmocka_unit_test(test_flip_sizes_and_errors),
		cmocka_unit_test(test_registry),         cmocka_unit_test(test_percentile_paths),
		cmocka_unit_test(test_ssim_frame),       cmocka_unit_test(test_diff_runs_checked),
	};
	return tu_finish(cmocka_run_group_tests(tests, NULL, NULL));
}
