/* metrics.c — row-band threads, one-shot comparison and pooling over the registry, JND maths (see metrics.h).
 * The metrics themselves are the plug-ins metric_*.c (registry.c); compare.c runs them per frame pair. */
#include "taslab/metrics.h"

#include <assert.h>

#include <gsl/gsl_cdf.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "metric.h"

const double mtr_thresholds[MTR_THRESHOLD_COUNT] = {2, 4, 8, 16, 32, 64};

static_assert(MTR_MAX_THREADS <= 64, "thread arrays on the stack");

int mtr_thread_count(int requested, uint32_t rows)
{
	long n = requested > 0 ? requested : sysconf(_SC_NPROCESSORS_ONLN);
	if (n < 1)
		n = 1;
	if (n > MTR_MAX_THREADS)
		n = MTR_MAX_THREADS;
	if ((uint32_t)n > rows)
		n = rows ? rows : 1;
	return (int)n;
}

typedef struct band_task {
	mtr_band_fn fn;
	void *ctx;
	int band;
	uint32_t y0, y1;
} band_task;

static void *band_main(void *p)
{
	band_task *t = p;
	t->fn(t->ctx, t->band, t->y0, t->y1);
	return NULL;
}

void mtr_parallel_rows(uint32_t rows, int threads, mtr_band_fn fn, void *ctx)
{
	pthread_t th[MTR_MAX_THREADS];
	band_task task[MTR_MAX_THREADS];
	int started[MTR_MAX_THREADS] = {0};
	for (int b = 0; b < threads; b++) {
		task[b] = (band_task){fn, ctx, b, (uint32_t)((uint64_t)rows * b / threads),
				      (uint32_t)((uint64_t)rows * (b + 1) / threads)};
		if (b > 0)
			started[b] = pthread_create(&th[b], NULL, band_main, &task[b]) == 0;
	}
	band_main(&task[0]);
	for (int b = 1; b < threads; b++) {
		if (started[b])
			pthread_join(th[b], NULL);
		else
			band_main(&task[b]); /* could not start a thread: do the band here */
	}
}

/* ------------------------------------------------------------------ one frame pair, pooling */

int mtr_frame_compare(const mtr_image *a, const mtr_image *b, const mtr_image *a_prev, const mtr_image *b_prev,
		      float *map, int threads, mtr_frame_stats *out, char *err, size_t err_size)
{
	mtr_comparer *c = NULL;
	mtr_compare_desc desc = {.threads = threads};
	int rc = mtr_comparer_create(&desc, &c, err, err_size);
	if (!rc)
		rc = mtr_comparer_frame(c, a, b, a_prev, b_prev, map, NULL, out, err, err_size);
	mtr_comparer_destroy(&c);
	return rc;
}

void mtr_pool(const mtr_frame_stats *f, size_t n, mtr_frame_stats *p)
{
	uint32_t seen = 0;
	for (size_t i = 0; i < n; i++)
		seen |= f[i].metrics;
	memset(p, 0, sizeof *p);
	for (int i = 0; mtr_metric_registry[i]; i++) {
		const mtr_metric *m = mtr_metric_registry[i];
		mtr_metric_clear(m, p);
		if (n && (seen & (1u << i)))
			m->pool(NULL, f, n, p);
	}
	p->metrics = n ? seen : 0;
}

/* ------------------------------------------------------------------ JND */

double mtr_jnd_from_p(double p)
{
	return gsl_cdf_ugaussian_Pinv(p) / gsl_cdf_ugaussian_Pinv(0.75);
}

int mtr_jnd_from_counts(double n_ref, double n_tie, double n, double confidence, mtr_jnd *out)
{
	if (!(n > 0) || n_ref < 0 || n_tie < 0 || n_ref + n_tie > n + 1e-9 || !(confidence > 0 && confidence < 1))
		return TL_ERR_ARG;
	double p = (n_ref + 0.5 * n_tie) / n;
	/* Wilson score interval (Wilson 1927) for a proportion observed in n trials. */
	double z = gsl_cdf_ugaussian_Pinv(0.5 + 0.5 * confidence);
	double z2 = z * z, den = 1 + z2 / n;
	double centre = (p + z2 / (2 * n)) / den;
	double half = z * sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / den;
	out->p = p;
	out->p_lo = fmax(0.0, centre - half);
	out->p_hi = fmin(1.0, centre + half);
	double lo = 0.5 / n, hi = 1.0 - 0.5 / n;
	double pc = fmin(fmax(p, lo), hi);
	out->clamped = pc != p;
	out->jnd = mtr_jnd_from_p(pc);
	out->jnd_lo = mtr_jnd_from_p(fmin(fmax(out->p_lo, lo), hi));
	out->jnd_hi = mtr_jnd_from_p(fmin(fmax(out->p_hi, lo), hi));
	return TL_OK;
}
