/* metric_flip.c — the `flip` metric: LDR-FLIP (Andersson et al., "FLIP: A Difference Evaluator for Alternating
 * Images", HPG 2020; the algorithm is flip.c) on the display values, at --ppd pixels per degree (DESIGN section 6).
 * Columns: flip_mean per frame (mean of the per-pixel error) and, in summary.json, the pooled values NVIDIA's tool
 * prints for an image — mean, weighted median, weighted 1st and 3rd quartiles (weights = the error values: the
 * first value whose running sum exceeds p x the total, "pooling" in flip.c), min, max — over all pixels of all
 * frames.
 *
 * Pooling over a clip without keeping every error map: a histogram of the error values with their sums per bin,
 * binned by the float's exponent and top 12 mantissa bits over [2^-16, 1] (65537 bins; values below 2^-16 share bin
 * 0). The weighted percentile is located exactly at bin level (the running sum of the bins' exact sums) and
 * reported as the mean value of its bin, so it is off by less than the bin width, 2^-12 (2.4e-4) times the value —
 * within the 1e-3 the reference comparison allows. Mean, min and max are exact. The histogram is filled on FLIP's
 * worker threads as rows are computed (mtr_flip_compute_rows), one per band, so no error map is stored or re-read.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "metric.h"
#include "taslab/metrics_flip.h"

#define HIST_LO_BITS 0x37800000u /* 2^-16 */
#define HIST_SHIFT 11            /* keep 12 mantissa bits */
#define HIST_BINS (((0x3F800000u - HIST_LO_BITS) >> HIST_SHIFT) + 1) /* up to and including 1.0 */

/* A bin's count and sum side by side: binning a value touches one cache line, not two. */
typedef struct flip_bin {
	uint64_t count;
	double sum;
} flip_bin;

typedef struct flip_hist {
	flip_bin bin[HIST_BINS];
} flip_hist;

typedef struct flip_state {
	double ppd; /* option */
	mtr_flip *f;
	flip_hist *frame[MTR_MAX_THREADS]; /* per band, for the current frame */
	flip_hist *clip;                   /* all frames so far */
	float fmin, fmax;                  /* clip-wide */
	float bmin[MTR_MAX_THREADS], bmax[MTR_MAX_THREADS];
} flip_state;

static inline uint32_t hist_bin(float v)
{
	uint32_t u;
	memcpy(&u, &v, sizeof u);
	/* Errors are in [0, 1]; anything else (never produced) is clamped into the end bins. */
	int64_t k = ((int64_t)u - (int64_t)HIST_LO_BITS) >> HIST_SHIFT;
	k = k < 0 ? 0 : k;
	k = k > (int64_t)HIST_BINS - 1 ? (int64_t)HIST_BINS - 1 : k;
	return (uint32_t)k;
}

/* Row consumer (mtr_flip_row_fn): bins the error values while FLIP's worker has them in cache. */
static void bin_row(void *p, int band, uint32_t y, uint32_t x0, const float *err, size_t n)
{
	(void)y, (void)x0;
	flip_state *s = p;
	flip_hist *h = s->frame[band];
	float lo = s->bmin[band], hi = s->bmax[band];
	for (size_t i = 0; i < n; i++) {
		const float v = err[i];
		flip_bin *b = &h->bin[hist_bin(v)];
		b->count++;
		b->sum += v;
		lo = v < lo ? v : lo; /* errors are never NaN: plain compares, not fminf / fmaxf calls */
		hi = v > hi ? v : hi;
	}
	s->bmin[band] = lo;
	s->bmax[band] = hi;
}

/* Weighted percentiles of a histogram (first bin whose running sum exceeds p * total; 0 for an all-zero map). */
static void hist_weighted(const flip_hist *h, double *q1, double *median, double *q3)
{
	double total = 0;
	for (uint32_t k = 0; k < HIST_BINS; k++)
		total += h->bin[k].sum;
	const double ps[3] = {0.25, 0.5, 0.75};
	double *res[3] = {q1, median, q3}, run = 0;
	int q = 0;
	for (uint32_t k = 0; k < HIST_BINS && q < 3; k++) {
		run += h->bin[k].sum;
		while (q < 3 && run > ps[q] * total)
			*res[q++] = h->bin[k].sum / (double)h->bin[k].count;
	}
	for (; q < 3; q++)
		*res[q] = 0.0;
}

static int flip_create(void *state, char *err, size_t err_size)
{
	flip_state *s = state;
	s->fmin = INFINITY;
	s->fmax = -INFINITY;
	if (!(s->clip = calloc(1, sizeof *s->clip)))
		return tl_error(err, err_size, TL_ERR_NOMEM, "flip: out of memory");
	return mtr_flip_create(s->ppd, &s->f, err, err_size);
}

static int flip_compute(void *state, const mtr_pair *p, mtr_frame_stats *out, char *err, size_t err_size)
{
	flip_state *s = state;
	const uint32_t w = p->a->width, h = p->a->height;
	/* One histogram per band of FLIP's workers (at most nt bands), filled as the rows are computed. */
	int nt = mtr_thread_count(p->threads, h);
	for (int t = 0; t < nt; t++) {
		if (!s->frame[t] && !(s->frame[t] = malloc(sizeof *s->frame[t])))
			return tl_error(err, err_size, TL_ERR_NOMEM, "flip: out of memory");
		memset(s->frame[t], 0, sizeof *s->frame[t]);
		s->bmin[t] = INFINITY;
		s->bmax[t] = -INFINITY;
	}
	double mean = 0;
	int rc = mtr_flip_compute_rows(s->f, w, h, p->a->rgb, p->b->rgb, p->flip_map, bin_row, s, nt, &mean, err,
				       err_size);
	if (rc)
		return rc;
	/* Per-frame pooled statistics from this frame's histogram; the histogram then joins the clip's. */
	for (int t = 1; t < nt; t++)
		for (uint32_t k = 0; k < HIST_BINS; k++) {
			s->frame[0]->bin[k].count += s->frame[t]->bin[k].count;
			s->frame[0]->bin[k].sum += s->frame[t]->bin[k].sum;
		}
	float lo = s->bmin[0], hi = s->bmax[0];
	for (int t = 1; t < nt; t++) {
		lo = fminf(lo, s->bmin[t]);
		hi = fmaxf(hi, s->bmax[t]);
	}
	for (uint32_t k = 0; k < HIST_BINS; k++) {
		s->clip->bin[k].count += s->frame[0]->bin[k].count;
		s->clip->bin[k].sum += s->frame[0]->bin[k].sum;
	}
	s->fmin = fminf(s->fmin, lo);
	s->fmax = fmaxf(s->fmax, hi);
	out->flip_mean = mean;
	out->flip_min = lo;
	out->flip_max = hi;
	hist_weighted(s->frame[0], &out->flip_q1_weighted, &out->flip_weighted_median, &out->flip_q3_weighted);
	return TL_OK;
}

static void flip_pool(void *state, const mtr_frame_stats *f, size_t n, mtr_frame_stats *p)
{
	flip_state *s = state;
	double mean = 0, lo = INFINITY, hi = -INFINITY;
	for (size_t i = 0; i < n; i++) {
		mean += f[i].flip_mean; /* frames of one size: the mean of means is the mean over all pixels */
		lo = fmin(lo, f[i].flip_min);
		hi = fmax(hi, f[i].flip_max);
	}
	p->flip_mean = mean / (double)n;
	p->flip_min = lo;
	p->flip_max = hi;
	if (s)
		hist_weighted(s->clip, &p->flip_q1_weighted, &p->flip_weighted_median, &p->flip_q3_weighted);
	else
		p->flip_q1_weighted = p->flip_weighted_median = p->flip_q3_weighted = NAN;
}

static void flip_merge(void *into, const void *from)
{
	flip_state *a = into;
	const flip_state *b = from;
	for (uint32_t k = 0; k < HIST_BINS; k++) {
		a->clip->bin[k].count += b->clip->bin[k].count;
		a->clip->bin[k].sum += b->clip->bin[k].sum;
	}
}

static void flip_destroy(void *state)
{
	flip_state *s = state;
	mtr_flip_destroy(&s->f);
	free(s->clip);
	for (int t = 0; t < MTR_MAX_THREADS; t++)
		free(s->frame[t]);
	memset(s, 0, sizeof *s);
}

static const mtr_column flip_columns[] = {
	{"flip_mean", offsetof(mtr_frame_stats, flip_mean), MTR_COL_BOTH},
	{"flip_weighted_median", offsetof(mtr_frame_stats, flip_weighted_median), MTR_COL_SUMMARY},
	{"flip_q1_weighted", offsetof(mtr_frame_stats, flip_q1_weighted), MTR_COL_SUMMARY},
	{"flip_q3_weighted", offsetof(mtr_frame_stats, flip_q3_weighted), MTR_COL_SUMMARY},
	{"flip_min", offsetof(mtr_frame_stats, flip_min), MTR_COL_SUMMARY},
	{"flip_max", offsetof(mtr_frame_stats, flip_max), MTR_COL_SUMMARY},
	{0},
};

static const mtr_metric_option flip_options[] = {
	{"ppd", "FLIP: pixels per degree of visual angle (default 67.0206: 0.7 m from a 0.7 m wide 3840-pixel monitor)",
	 offsetof(flip_state, ppd), MTR_FLIP_PPD_DEFAULT, 1e-3, 1000.0},
	{0},
};

const mtr_metric mtr_metric_flip = {
	.name = "flip",
	.help = "LDR-FLIP (Andersson et al. 2020) at --ppd: mean per-pixel error; weighted quartiles in summary.json",
	.columns = flip_columns,
	.options = flip_options,
	.state_size = sizeof(flip_state),
	.create = flip_create,
	.compute = flip_compute,
	.pool = flip_pool,
	.merge = flip_merge,
	.destroy = flip_destroy,
};
