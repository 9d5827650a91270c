/* bench_metrics.c — compute-only speed of the metrics on one 1920x1080 frame pair (from PNG files, or synthetic)
 * with its previous pair (flicker), medians of `runs` (default 9). Not a test. Prints:
 *  - the whole comparison (every metric, an mtr_comparer as `metrics diff` uses it) per pair, and each metric alone;
 *  - LDR-FLIP alone (mtr_flip_compute with its error map) on 1 and 2 threads, against NVIDIA's FLIP tool's 1.14 s /
 *    0.60 s per 1080p pair on this kind of 2-core machine (../shared/reference/flip/README.md);
 *  - a plain multithreaded read of the same four float buffers (vectorised, independent partial sums: the least any
 *    comparison must do) and the comparison's speed as a share of it;
 *  - the roofline: the machine's vector arithmetic peak on the same threads (independent multiply-add and add chains in
 *    the filters' mix) and the time the exact separable filters of FLIP and SSIM alone would take at that peak.
 *   bench_metrics [--runs N] [--threads N] [A.png B.png]
 * Older binaries (before the plug-in registry) print only the first lines; scripts/bench-metrics parses by key. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "taslab/imageio.h"
#include "taslab/metrics.h"
/* The same source also builds against the code before the plug-in registry (scripts/bench-metrics --before REV),
 * where only mtr_frame_compare exists. */
#if __has_include("taslab/metrics_flip.h")
#include "taslab/metrics_flip.h"
#define HAVE_REGISTRY 1
#else
#define HAVE_REGISTRY 0
#endif

static double now(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec + 1e-9 * t.tv_nsec;
}

static int cmpd(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static double median(double *t, int n)
{
	qsort(t, (size_t)n, sizeof *t, cmpd);
	return t[n / 2];
}

typedef struct rd {
	const float *buf[4];
	size_t lo, hi;
	float sum;
} rd;

static void *read_part(void *p)
{
	rd *r = p;
	float acc[16] = {0};
	for (int k = 0; k < 4; k++) {
		const float *v = r->buf[k];
		size_t i = r->lo;
		for (; i + 16 <= r->hi; i += 16)
			for (int u = 0; u < 16; u++)
				acc[u] += v[i + (size_t)u];
		for (; i < r->hi; i++)
			acc[0] += v[i];
	}
	float s = 0;
	for (int u = 0; u < 16; u++)
		s += acc[u];
	r->sum = s;
	return NULL;
}

/* ---- roofline: vector arithmetic peak ---- */

typedef float pv16 __attribute__((vector_size(64)));
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) &&                           \
	!defined(__SANITIZE_THREAD__)
#define PEAK_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define PEAK_CLONES
#endif
#define PEAK_ITERS 20000000L
#define PEAK_CHAINS 12

/* 12 independent chains of 16-float operations (one AVX-512 instruction; two AVX2 ones), 7 multiply-add and 5 add
 * (42 % adds: the mix of the filters counted in filter_ops), enough in flight to cover the latencies. Counted in
 * lane-operations, a multiply-add once, as in filter_ops. (On this kind of machine, AMD Zen 4, 16-lane instructions
 * gave 191 G lane-operations/s on 2 threads where 8-lane ones gave 154 G: the wider one is the peak.) */
PEAK_CLONES __attribute__((optimize("fp-contract=fast"))) static void *peak_part(void *p)
{
	pv16 a[PEAK_CHAINS];
	const pv16 m = (pv16){0} + 0.999f, c = (pv16){0} + 1e-3f;
	volatile float seed = 0.5f; /* opaque start values: no chain can be folded at compile time */
	for (int i = 0; i < PEAK_CHAINS; i++)
		a[i] = (pv16){0} + seed * (float)(i + 1);
	for (long n = 0; n < PEAK_ITERS; n++) {
		for (int i = 0; i < 7; i++)
			a[i] = a[i] * m + c;
		for (int i = 7; i < PEAK_CHAINS; i++)
			a[i] = a[i] + c;
	}
	float s = 0;
	for (int i = 0; i < PEAK_CHAINS; i++)
		s += a[i][0];
	*(float *)p = s;
	return NULL;
}

/* Lane-operations per second on nt threads (median of runs). */
static double peak_ops(int nt, int runs, double *t)
{
	for (int r = 0; r < runs; r++) {
		pthread_t th[64];
		float res[64];
		double t0 = now();
		for (int k = 1; k < nt; k++)
			pthread_create(&th[k], NULL, peak_part, &res[k]);
		peak_part(&res[0]);
		for (int k = 1; k < nt; k++)
			pthread_join(th[k], NULL);
		t[r] = now() - t0;
	}
	return (double)nt * PEAK_ITERS * PEAK_CHAINS * 16 / median(t, runs);
}

/* Lane-operations per pixel of a pair that the exact separable filters need at least, with symmetric taps folded
 * (a tap pair costs one add or subtract, shared by every kernel filtering the same plane, and one multiply-add per
 * kernel; the centre one multiply), radii as flip.c and metric_ssim.c use them at 67.02 pixels per degree:
 *   FLIP, per image: vertical pass: Y/Yn with the achromatic CSF (radius 6) and the feature Gaussian, first and
 *   second derivative (radius 9): 9 sums + 9 differences + 7 + 10 + 9 + 10 = 54; Cx (radius 7): 7 + 8 = 15; Cz, two
 *   Gaussians (radius 10): 10 + 11 + 11 = 32. Horizontal pass: Y 6 + 7 = 13; Cx 15; Cz 2 x 21 + 1 = 43; the Gaussian
 *   plane's x derivatives 9 + 9 + 9 + 10 = 37; the two derivative planes' Gaussians 2 x 19 = 38. 247 per image.
 *   SSIM (radius 5), per channel: products a^2 + b^2 and ab, 3; 4 quantities x 2 passes x (5 + 6) = 88. 91 x 3.
 * Colour conversions, the final formulas, maxrgb, psnr, flicker and pooling are not counted: a lower bound. */
static double filter_ops(void)
{
	return 2 * 247 + 3 * 91;
}

int main(int argc, char **argv)
{
	int runs = 9, nt = 0;
	const char *files[2] = {NULL, NULL};
	int nf = 0;
	for (int i = 1; i < argc; i++) {
		if (!strcmp(argv[i], "--runs") && i + 1 < argc)
			runs = atoi(argv[++i]);
		else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
			nt = atoi(argv[++i]);
		else if (nf < 2)
			files[nf++] = argv[i];
	}
	if (runs < 1 || runs > 99)
		runs = 9;
	if (nt > 64) /* thread arrays below hold 64 */
		nt = 64;
	if (nt <= 0) {
		long cores = sysconf(_SC_NPROCESSORS_ONLN);
		nt = cores > 0 ? (int)(cores < 64 ? cores : 64) : 1;
	}
	uint32_t w = 1920, h = 1080;
	size_t n = (size_t)w * h * 3;
	float *buf[4];
	for (int k = 0; k < 4; k++)
		if (!(buf[k] = malloc(n * sizeof(float))))
			return 1;
	if (nf == 2) {
		char err[512];
		uint8_t *pa, *pb;
		uint32_t w2, h2;
		if (imageio_read_rgb8(files[0], &w, &h, &pa, err, sizeof err) ||
		    imageio_read_rgb8(files[1], &w2, &h2, &pb, err, sizeof err) || w != w2 || h != h2 ||
		    (size_t)w * h * 3 != n) {
			fprintf(stderr, "bench_metrics: need two 1920x1080 images (%s)\n", err);
			return 1;
		}
		for (size_t i = 0; i < n; i++)
			buf[0][i] = pa[i], buf[1][i] = pb[i];
		free(pa);
		free(pb);
	} else {
		for (size_t i = 0; i < n; i++)
			buf[0][i] = (float)(i % 251), buf[1][i] = (float)((i * 7) % 253);
	}
	/* The previous pair: the same frames one pixel to the left (distinct buffers, as in a sequence). */
	for (size_t i = 0; i < n; i++) {
		buf[2][i] = buf[0][i >= 3 ? i - 3 : i];
		buf[3][i] = buf[1][i >= 3 ? i - 3 : i];
	}
	mtr_image A = {w, h, buf[0]}, B = {w, h, buf[1]}, Ap = {w, h, buf[2]}, Bp = {w, h, buf[3]};
	double *t = malloc(sizeof(double) * (size_t)runs);
	char err[256];

	/* Plain read of the four buffers on nt threads. */
	for (int r = 0; r < runs; r++) {
		pthread_t th[64];
		rd parts[64];
		double t0 = now();
		for (int k = 0; k < nt; k++) {
			parts[k] = (rd){{buf[0], buf[1], buf[2], buf[3]}, n * (size_t)k / (size_t)nt, n * (size_t)(k + 1) / (size_t)nt, 0};
			if (k)
				pthread_create(&th[k], NULL, read_part, &parts[k]);
		}
		read_part(&parts[0]);
		for (int k = 1; k < nt; k++)
			pthread_join(th[k], NULL);
		t[r] = now() - t0;
	}
	const double bytes = 4.0 * (double)n * sizeof(float), t_read = median(t, runs);

	/* The one-shot API (all metrics; allocates per call), the same call before and after the registry. */
	{
		mtr_frame_stats s;
		mtr_frame_compare(&A, &B, &Ap, &Bp, NULL, nt, &s, err, sizeof err);
		for (int r = 0; r < runs; r++) {
			double t0 = now();
			if (mtr_frame_compare(&A, &B, &Ap, &Bp, NULL, nt, &s, err, sizeof err)) {
				fprintf(stderr, "bench_metrics: %s\n", err);
				return 1;
			}
			t[r] = now() - t0;
		}
		printf("frame_compare_ms %.2f  (mtr_frame_compare, all metrics of this version)\n", median(t, runs) * 1e3);
	}
	printf("read_ms %.2f  (plain %d-thread read of the same 4 float buffers, %.2f GB/s)\n", t_read * 1e3, nt,
	       bytes / t_read / 1e9);
#if HAVE_REGISTRY
	/* The whole comparison, as `metrics diff` runs it (one comparer, kept across frames). */
	const char *sel[] = {"all", "maxrgb", "psnr", "ssim", "flicker", "flip", "maxrgb,psnr,flicker",
			     "maxrgb,psnr,ssim,flicker"};
	double t_all = 0;
	for (size_t m = 0; m < sizeof sel / sizeof sel[0]; m++) {
		mtr_comparer *c = NULL;
		mtr_compare_desc d = {.metrics = sel[m], .threads = nt};
		if (mtr_comparer_create(&d, &c, err, sizeof err)) {
			fprintf(stderr, "bench_metrics: %s\n", err);
			return 1;
		}
		mtr_frame_stats s;
		mtr_comparer_frame(c, &A, &B, &Ap, &Bp, NULL, NULL, &s, err, sizeof err); /* warm-up: allocations */
		for (int r = 0; r < runs; r++) {
			double t0 = now();
			if (mtr_comparer_frame(c, &A, &B, &Ap, &Bp, NULL, NULL, &s, err, sizeof err)) {
				fprintf(stderr, "bench_metrics: %s\n", err);
				return 1;
			}
			t[r] = now() - t0;
		}
		mtr_comparer_destroy(&c);
		double tm = median(t, runs);
		if (m == 0) {
			t_all = tm;
			printf("compare_ms %.2f  (all metrics, %d threads, per 1920x1080 pair)\n", tm * 1e3, nt);
		} else if (!strcmp(sel[m], "maxrgb,psnr,ssim,flicker")) { /* what the code before FLIP computed */
			printf("compare_noflip_ms %.2f  (%s)\n", tm * 1e3, sel[m]);
		} else if (strchr(sel[m], ',')) { /* the metrics of the shared pixel pass: memory-bound */
			printf("pass_ms %.2f  (%s: one pass over the 4 buffers, %.1f%% of the plain read)\n", tm * 1e3, sel[m],
			       100.0 * t_read / tm);
		} else {
			printf("metric_ms %-8s %.2f\n", sel[m], tm * 1e3);
		}
	}
	printf("compare_gbps %.3f\n", bytes / t_all / 1e9);
	printf("compare_share_of_read_bw %.1f%%\n", 100.0 * t_read / t_all);

	/* FLIP alone, 1 and 2 threads, with its error map (as the reference tool produces one). */
	mtr_flip *f = NULL;
	float *map = malloc((size_t)w * h * sizeof *map);
	if (!map || mtr_flip_create(MTR_FLIP_PPD_DEFAULT, &f, err, sizeof err)) {
		fprintf(stderr, "bench_metrics: %s\n", err);
		return 1;
	}
	const double ref_s[3] = {0, 1.14, 0.60};
	for (int threads = 1; threads <= 2; threads++) {
		double mean;
		mtr_flip_compute(f, w, h, buf[0], buf[1], map, threads, &mean, err, sizeof err);
		for (int r = 0; r < runs; r++) {
			double t0 = now();
			mtr_flip_compute(f, w, h, buf[0], buf[1], map, threads, &mean, err, sizeof err);
			t[r] = now() - t0;
		}
		double tm = median(t, runs);
		printf("flip_%dt_ms %.2f  (NVIDIA FLIP tool %.2f s: %.1fx)\n", threads, tm * 1e3, ref_s[threads],
		       ref_s[threads] / tm);
	}
	mtr_flip_destroy(&f);
	free(map);
	{
		double peak = peak_ops(nt, runs < 5 ? runs : 5, t);
		double floor_s = filter_ops() * w * h / peak;
		printf("peak_gops %.1f  (vector lane-operations per second on %d threads: multiply-add and add chains)\n",
		       peak / 1e9, nt);
		printf("floor_filters_ms %.2f  (FLIP's and SSIM's exact filters alone, %.0f operations per pixel, at that peak: "
		       "the whole compute at %.1f%% of the plain read at best)\n",
		       floor_s * 1e3, filter_ops(), 100.0 * t_read / floor_s);
	}
#endif
	for (int k = 0; k < 4; k++)
		free(buf[k]);
	free(t);
	return 0;
}
