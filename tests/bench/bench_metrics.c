/* bench_metrics.c — compute-only throughput of mtr_frame_compare on two 1920x1080 float RGB frames (from
 * PNG files, or synthetic), against a plain memory-bandwidth measurement over the same two buffers:
 * a multithreaded read of every float (the least any comparison must do). Medians of 9. Not a test.
 *   bench_metrics [A.png B.png] */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

#include "taslab/imageio.h"
#include "taslab/metrics.h"

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

typedef struct rd {
	const float *a, *b;
	size_t n;
	double sum;
} rd;

static void *read_part(void *p)
{
	rd *r = p;
	float s = 0;
	for (size_t i = 0; i < r->n; i++)
		s += r->a[i] + r->b[i];
	r->sum = s;
	return NULL;
}

int main(int argc, char **argv)
{
	uint32_t w = 1920, h = 1080;
	size_t n = (size_t)w * h * 3;
	float *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
	if (argc == 3) {
		char err[512];
		uint8_t *pa, *pb;
		uint32_t w2, h2;
		if (imageio_read_rgb8(argv[1], &w, &h, &pa, err, sizeof err) || imageio_read_rgb8(argv[2], &w2, &h2, &pb, err, sizeof err) ||
		    w != w2 || h != h2 || (size_t)w * h * 3 != n) {
			fprintf(stderr, "bench_metrics: need two 1920x1080 images (%s)\n", err);
			return 1;
		}
		for (size_t i = 0; i < n; i++)
			a[i] = pa[i], b[i] = pb[i];
		free(pa);
		free(pb);
	} else {
		for (size_t i = 0; i < n; i++)
			a[i] = (float)(i % 251), b[i] = (float)((i * 7) % 253);
	}
	mtr_image A = {w, h, a}, B = {w, h, b};
	float *map = malloc((size_t)w * h * sizeof *map);
	double tc[9], tr[9];
	long cores = sysconf(_SC_NPROCESSORS_ONLN);
	int nt = cores > 0 ? (int)cores : 1;
	for (int k = 0; k < 9; k++) {
		mtr_frame_stats s;
		char err[256];
		double t0 = now();
		mtr_frame_compare(&A, &B, &A, &B, map, 0, &s, err, sizeof err);
		tc[k] = now() - t0;
		pthread_t th[64];
		rd parts[64];
		t0 = now();
		for (int t = 0; t < nt && t < 64; t++) {
			size_t lo = n * t / nt, hi = n * (t + 1) / nt;
			parts[t] = (rd){a + lo, b + lo, hi - lo, 0};
			pthread_create(&th[t], NULL, read_part, &parts[t]);
		}
		for (int t = 0; t < nt && t < 64; t++)
			pthread_join(th[t], NULL);
		tr[k] = now() - t0;
	}
	qsort(tc, 9, sizeof *tc, cmpd);
	qsort(tr, 9, sizeof *tr, cmpd);
	double bytes = 2.0 * n * sizeof(float); /* current pair; the previous pair (flicker) adds the same again */
	printf("compare (all statistics incl. SSIM, percentiles, flicker): %.1f ms/pair, %.2f GB/s of input\n", tc[4] * 1e3,
	       2 * bytes / tc[4] / 1e9);
	printf("plain read of the same buffers (%d threads):              %.1f ms,      %.2f GB/s\n", nt, tr[4] * 1e3,
	       bytes / tr[4] / 1e9);
	printf("ratio: compare runs at %.1f%% of the read bandwidth\n", 100.0 * (2 * bytes / tc[4]) / (bytes / tr[4]));
	free(a);
	free(b);
	free(map);
	return 0;
}
