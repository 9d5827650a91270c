/* metric_maxrgb.c — the `maxrgb` metric: statistics of the max-RGB difference d = max_c |a_c - b_c| (paper sec. 3,
 * DESIGN sections 3 and 6): mean, type-7 percentiles p50/p95/p99, max and where, exceed_T = fraction of pixels
 * with d > T for T = 2..64. The per-pixel work is the shared pass (pixel.c). Percentiles: when every d is a whole
 * number (8-bit inputs: always for PNG frames) the pass's 256-bin histogram is the exact distribution and gives
 * exact type-7 percentiles without touching the pixels again; otherwise (EXR frames, fractional values) the map is
 * copied and three quickselects run (mtr_percentile), as exact. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "metric.h"

/* Quickselect: the k-th smallest of v[0..n-1] (0-based), partially reordering v. */
static float select_kth(float *v, size_t n, size_t k)
{
	size_t lo = 0, hi = n - 1;
	while (lo < hi) {
		float pivot = v[lo + (hi - lo) / 2];
		size_t i = lo, j = hi;
		while (i <= j) {
			while (v[i] < pivot)
				i++;
			while (v[j] > pivot)
				j--;
			if (i <= j) {
				float t = v[i];
				v[i] = v[j];
				v[j] = t;
				i++;
				if (j == 0)
					break;
				j--;
			}
		}
		if (k <= j)
			hi = j;
		else if (k >= i)
			lo = i;
		else
			return v[k];
	}
	return v[k];
}

double mtr_percentile(float *values, size_t n, double pct)
{
	if (n == 0)
		return NAN;
	double h = (double)(n - 1) * pct / 100.0;
	size_t k = (size_t)floor(h);
	double frac = h - (double)k;
	float lo = select_kth(values, n, k);
	if (frac == 0.0 || k + 1 >= n)
		return lo;
	/* After selecting k, every value right of k is >= v[k]: the next order statistic is their minimum. */
	float hi = values[k + 1];
	for (size_t i = k + 2; i < n; i++)
		hi = values[i] < hi ? values[i] : hi;
	return lo + frac * (hi - lo);
}

typedef struct maxrgb_state {
	float *sorted; /* fractional inputs only: a copy of the map for the quickselects */
	size_t cap;
} maxrgb_state;

static int maxrgb_compute(void *state, const mtr_pair *p, mtr_frame_stats *out, char *err, size_t err_size)
{
	maxrgb_state *s = state;
	const mtr_pixel_result *px = p->px;
	const uint64_t n = (uint64_t)p->a->width * p->a->height;
	out->mean = px->sum_d / (double)n;
	out->max = px->max;
	out->max_x = px->max_x;
	out->max_y = px->max_y;
	for (int k = 0; k < MTR_THRESHOLD_COUNT; k++)
		out->exceed[k] = (double)px->exceed[k] / (double)n;
	if (px->integral) {
		out->p50 = mtr_hist_percentile(px->hist, n, 50);
		out->p95 = mtr_hist_percentile(px->hist, n, 95);
		out->p99 = mtr_hist_percentile(px->hist, n, 99);
		return TL_OK;
	}
	if (s->cap < n) {
		free(s->sorted);
		s->cap = 0;
		if (!(s->sorted = malloc(n * sizeof *s->sorted)))
			return tl_error(err, err_size, TL_ERR_NOMEM, "maxrgb: out of memory");
		s->cap = n;
	}
	if (p->map) {
		memcpy(s->sorted, p->map, n * sizeof *s->sorted);
	} else { /* the caller kept no map: d again (rare path, fractional inputs without a map) */
		const float *a = p->a->rgb, *b = p->b->rgb;
		for (size_t i = 0; i < n; i++)
			s->sorted[i] = fmaxf(fabsf(a[3 * i] - b[3 * i]),
					     fmaxf(fabsf(a[3 * i + 1] - b[3 * i + 1]), fabsf(a[3 * i + 2] - b[3 * i + 2])));
	}
	out->p99 = mtr_percentile(s->sorted, n, 99);
	out->p95 = mtr_percentile(s->sorted, n, 95);
	out->p50 = mtr_percentile(s->sorted, n, 50);
	return TL_OK;
}

static void maxrgb_pool(void *state, const mtr_frame_stats *f, size_t n, mtr_frame_stats *p)
{
	(void)state;
	p->mean = p->p50 = p->p95 = p->p99 = 0;
	for (int k = 0; k < MTR_THRESHOLD_COUNT; k++)
		p->exceed[k] = 0;
	p->max = -1;
	for (size_t i = 0; i < n; i++) {
		p->mean += f[i].mean;
		p->p50 += f[i].p50;
		p->p95 += f[i].p95;
		p->p99 += f[i].p99;
		for (int k = 0; k < MTR_THRESHOLD_COUNT; k++)
			p->exceed[k] += f[i].exceed[k];
		if (f[i].max > p->max) {
			p->max = f[i].max;
			p->max_x = f[i].max_x;
			p->max_y = f[i].max_y;
		}
	}
	const double k = 1.0 / (double)n;
	p->mean *= k;
	p->p50 *= k;
	p->p95 *= k;
	p->p99 *= k;
	for (int t = 0; t < MTR_THRESHOLD_COUNT; t++)
		p->exceed[t] *= k;
}

static void maxrgb_destroy(void *state)
{
	maxrgb_state *s = state;
	free(s->sorted);
	s->sorted = NULL;
	s->cap = 0;
}

#define COL(n, f) {n, offsetof(mtr_frame_stats, f), MTR_COL_BOTH}
static const mtr_column maxrgb_columns[] = {
	COL("maxrgb_mean", mean), COL("maxrgb_p50", p50), COL("maxrgb_p95", p95), COL("maxrgb_p99", p99),
	COL("maxrgb_max", max),   COL("exceed_2", exceed[0]), COL("exceed_4", exceed[1]), COL("exceed_8", exceed[2]),
	COL("exceed_16", exceed[3]), COL("exceed_32", exceed[4]), COL("exceed_64", exceed[5]),
	{0},
};

const mtr_metric mtr_metric_maxrgb = {
	.name = "maxrgb",
	.help = "max-RGB difference: mean, p50, p95, p99, max, exceed_T (T = 2..64)",
	.pixel_pass = MTR_PASS_MAXRGB,
	.columns = maxrgb_columns,
	.state_size = sizeof(maxrgb_state),
	.compute = maxrgb_compute,
	.pool = maxrgb_pool,
	.destroy = maxrgb_destroy,
};
