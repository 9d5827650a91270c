/* metrics.c — per-frame image and temporal statistics, pooling, JND maths (see metrics.h).
 * Inner loops run over row bands on worker threads; each loop is a plain float loop the compiler vectorises. */
#include "taslab/metrics.h"

#include <gsl/gsl_cdf.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

const double mtr_thresholds[MTR_THRESHOLD_COUNT] = {2, 4, 8, 16, 32, 64};

#define MAX_THREADS 64

static int thread_count(int requested, uint32_t rows)
{
	long n = requested > 0 ? requested : sysconf(_SC_NPROCESSORS_ONLN);
	if (n < 1)
		n = 1;
	if (n > MAX_THREADS)
		n = MAX_THREADS;
	if ((uint32_t)n > rows)
		n = rows ? rows : 1;
	return (int)n;
}

/* Runs fn(ctx, band, y0, y1) for `threads` contiguous row bands of [0, rows), in parallel. */
typedef void (*band_fn)(void *ctx, int band, uint32_t y0, uint32_t y1);

typedef struct band_task {
	band_fn fn;
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

static void parallel_rows(uint32_t rows, int threads, band_fn fn, void *ctx)
{
	pthread_t th[MAX_THREADS];
	band_task task[MAX_THREADS];
	int started[MAX_THREADS] = {0};
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

/* ------------------------------------------------------------------ difference statistics */

typedef struct diff_ctx {
	const mtr_image *a, *b, *ap, *bp;
	float *map;
	struct {
		double sum, sq, flicker;
		uint64_t exceed[MTR_THRESHOLD_COUNT];
		float max;
		uint32_t max_x, max_y;
	} acc[MAX_THREADS];
} diff_ctx;

static void diff_band(void *p, int band, uint32_t y0, uint32_t y1)
{
	diff_ctx *c = p;
	uint32_t w = c->a->width;
	double sum = 0, sq = 0, fl = 0;
	uint64_t ex[MTR_THRESHOLD_COUNT] = {0};
	float mx = -1.0f;
	uint32_t mx_x = 0, mx_y = 0;
	for (uint32_t y = y0; y < y1; y++) {
		const float *a = c->a->rgb + (size_t)y * w * 3, *b = c->b->rgb + (size_t)y * w * 3;
		float *m = c->map + (size_t)y * w;
		float row_sum = 0, row_sq = 0;
		for (uint32_t x = 0; x < w; x++) {
			float dr = a[3 * x] - b[3 * x], dg = a[3 * x + 1] - b[3 * x + 1], db = a[3 * x + 2] - b[3 * x + 2];
			float d = fmaxf(fabsf(dr), fmaxf(fabsf(dg), fabsf(db)));
			m[x] = d;
			row_sum += d;
			row_sq += dr * dr + dg * dg + db * db;
		}
		sum += row_sum;
		sq += row_sq;
		for (uint32_t x = 0; x < w; x++) {
			float d = m[x];
			for (int k = 0; k < MTR_THRESHOLD_COUNT; k++)
				ex[k] += d > (float)mtr_thresholds[k];
			if (d > mx) {
				mx = d;
				mx_x = x;
				mx_y = y;
			}
		}
		if (c->ap) {
			const float *ap = c->ap->rgb + (size_t)y * w * 3, *bp = c->bp->rgb + (size_t)y * w * 3;
			float row_fl = 0;
			for (uint32_t x = 0; x < w; x++) {
				float f = 0;
				for (int ch = 0; ch < 3; ch++) {
					size_t i = 3 * (size_t)x + ch;
					f = fmaxf(f, fabsf((a[i] - ap[i]) - (b[i] - bp[i])));
				}
				row_fl += f;
			}
			fl += row_fl;
		}
	}
	c->acc[band].sum = sum;
	c->acc[band].sq = sq;
	c->acc[band].flicker = fl;
	memcpy(c->acc[band].exceed, ex, sizeof ex);
	c->acc[band].max = mx;
	c->acc[band].max_x = mx_x;
	c->acc[band].max_y = mx_y;
}

static int same_size(const mtr_image *a, const mtr_image *b)
{
	return a->width == b->width && a->height == b->height;
}

int mtr_frame_compare(const mtr_image *a, const mtr_image *b, const mtr_image *a_prev, const mtr_image *b_prev,
		      float *map, int threads, mtr_frame_stats *out, char *err, size_t err_size)
{
	if (!a->width || !a->height || !same_size(a, b)) {
		snprintf(err, err_size, "image sizes differ: %ux%u vs %ux%u", a->width, a->height, b->width, b->height);
		return TL_ERR_ARG;
	}
	if ((a_prev == NULL) != (b_prev == NULL) || (a_prev && (!same_size(a, a_prev) || !same_size(a, b_prev)))) {
		snprintf(err, err_size, "previous frames missing or of another size");
		return TL_ERR_ARG;
	}
	size_t n = (size_t)a->width * a->height;
	float *own = NULL;
	if (!map && !(map = own = malloc(n * sizeof *map))) {
		snprintf(err, err_size, "out of memory");
		return TL_ERR_NOMEM;
	}
	int nt = thread_count(threads, a->height);
	diff_ctx *c = calloc(1, sizeof *c);
	float *sorted = malloc(n * sizeof *sorted);
	if (!c || !sorted) {
		free(c);
		free(sorted);
		free(own);
		snprintf(err, err_size, "out of memory");
		return TL_ERR_NOMEM;
	}
	c->a = a, c->b = b, c->ap = a_prev, c->bp = b_prev, c->map = map;
	parallel_rows(a->height, nt, diff_band, c);
	memset(out, 0, sizeof *out);
	double sum = 0, sq = 0, fl = 0;
	uint64_t ex[MTR_THRESHOLD_COUNT] = {0};
	out->max = -1;
	for (int t = 0; t < nt; t++) { /* bands in row order: the first maximum in row order wins ties */
		sum += c->acc[t].sum;
		sq += c->acc[t].sq;
		fl += c->acc[t].flicker;
		for (int k = 0; k < MTR_THRESHOLD_COUNT; k++)
			ex[k] += c->acc[t].exceed[k];
		if (c->acc[t].max > out->max) {
			out->max = c->acc[t].max;
			out->max_x = c->acc[t].max_x;
			out->max_y = c->acc[t].max_y;
		}
	}
	out->mean = sum / (double)n;
	for (int k = 0; k < MTR_THRESHOLD_COUNT; k++)
		out->exceed[k] = (double)ex[k] / (double)n;
	out->mse = sq / (3.0 * (double)n);
	out->psnr = out->mse > 0 ? 10.0 * log10(255.0 * 255.0 / out->mse) : INFINITY;
	out->flicker_mean = a_prev ? fl / (double)n : NAN;
	memcpy(sorted, map, n * sizeof *sorted);
	out->p99 = mtr_percentile(sorted, n, 99);
	out->p95 = mtr_percentile(sorted, n, 95);
	out->p50 = mtr_percentile(sorted, n, 50);
	out->ssim = mtr_ssim(a, b, threads);
	free(sorted);
	free(c);
	free(own);
	return TL_OK;
}

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

double mtr_psnr(const mtr_image *a, const mtr_image *b)
{
	double sq = 0;
	size_t n = (size_t)a->width * a->height * 3;
	for (size_t i = 0; i < n; i++) {
		double d = (double)a->rgb[i] - (double)b->rgb[i];
		sq += d * d;
	}
	double mse = sq / (double)n;
	return mse > 0 ? 10.0 * log10(255.0 * 255.0 / mse) : INFINITY;
}

/* ------------------------------------------------------------------ SSIM (Wang et al. 2004) */

#define SSIM_R 5 /* 11x11 window */

typedef struct ssim_ctx {
	const mtr_image *a, *b;
	float g[2 * SSIM_R + 1];
	double sum[MAX_THREADS];
	int oom;
} ssim_ctx;

static void ssim_band(void *p, int band, uint32_t y0, uint32_t y1)
{
	/* Band of output rows [y0, y1) of the valid region (rows R..H-R-1 of the image). Per channel: the
	 * horizontal pass filters the needed input rows into 5 planes (mu_a, mu_b, E[a^2], E[b^2], E[ab]); the
	 * vertical pass accumulates 11 rows per output row; both inner loops run along x (vectorised). */
	ssim_ctx *c = p;
	uint32_t w = c->a->width;
	uint32_t in0 = y0, rows = (y1 - y0) + 2 * SSIM_R; /* input rows [y0, y1 + 2R) */
	uint32_t ow = w - 2 * SSIM_R;
	float *hp = malloc((size_t)5 * rows * ow * sizeof *hp);
	float *ra = malloc((size_t)w * 2 * sizeof *ra), *rb = ra ? ra + w : NULL;
	float *acc = malloc((size_t)5 * ow * sizeof *acc);
	if (!hp || !ra || !acc) {
		free(hp), free(ra), free(acc);
		c->oom = 1;
		return;
	}
	const float C1 = (0.01f * 255) * (0.01f * 255), C2 = (0.03f * 255) * (0.03f * 255);
	double total = 0;
	for (int ch = 0; ch < 3; ch++) {
		for (uint32_t r = 0; r < rows; r++) {
			const float *ar = c->a->rgb + (size_t)(in0 + r) * w * 3 + ch, *br = c->b->rgb + (size_t)(in0 + r) * w * 3 + ch;
			for (uint32_t x = 0; x < w; x++) /* de-interleave the channel */
				ra[x] = ar[(size_t)x * 3], rb[x] = br[(size_t)x * 3];
			float *q[5];
			for (int k = 0; k < 5; k++) {
				q[k] = hp + ((size_t)k * rows + r) * ow;
				memset(q[k], 0, ow * sizeof(float));
			}
			for (int k = 0; k <= 2 * SSIM_R; k++) {
				const float g = c->g[k], *va = ra + k, *vb = rb + k;
				for (uint32_t x = 0; x < ow; x++) {
					q[0][x] += g * va[x];
					q[1][x] += g * vb[x];
					q[2][x] += g * va[x] * va[x];
					q[3][x] += g * vb[x] * vb[x];
					q[4][x] += g * va[x] * vb[x];
				}
			}
		}
		for (uint32_t y = 0; y < y1 - y0; y++) {
			memset(acc, 0, (size_t)5 * ow * sizeof *acc);
			for (int qi = 0; qi < 5; qi++)
				for (int k = 0; k <= 2 * SSIM_R; k++) {
					const float g = c->g[k], *src = hp + ((size_t)qi * rows + y + k) * ow;
					float *dst = acc + (size_t)qi * ow;
					for (uint32_t x = 0; x < ow; x++)
						dst[x] += g * src[x];
				}
			float row = 0;
			for (uint32_t x = 0; x < ow; x++) {
				float ma = acc[x], mb = acc[ow + x];
				float va = acc[2 * ow + x] - ma * ma, vb = acc[3 * ow + x] - mb * mb, cov = acc[4 * ow + x] - ma * mb;
				row += ((2 * ma * mb + C1) * (2 * cov + C2)) / ((ma * ma + mb * mb + C1) * (va + vb + C2));
			}
			total += row;
		}
	}
	free(hp);
	free(ra);
	free(acc);
	c->sum[band] = total;
}

double mtr_ssim(const mtr_image *a, const mtr_image *b, int threads)
{
	if (!same_size(a, b) || a->width < 2 * SSIM_R + 1 || a->height < 2 * SSIM_R + 1)
		return NAN;
	ssim_ctx *c = calloc(1, sizeof *c);
	if (!c)
		return NAN;
	c->a = a;
	c->b = b;
	double gs = 0;
	for (int k = -SSIM_R; k <= SSIM_R; k++)
		gs += (c->g[k + SSIM_R] = (float)exp(-(double)(k * k) / (2 * 1.5 * 1.5)));
	for (int k = 0; k <= 2 * SSIM_R; k++)
		c->g[k] = (float)(c->g[k] / gs);
	uint32_t valid_rows = a->height - 2 * SSIM_R;
	int nt = thread_count(threads, valid_rows);
	parallel_rows(valid_rows, nt, ssim_band, c);
	double sum = 0;
	for (int t = 0; t < nt; t++)
		sum += c->sum[t];
	int oom = c->oom;
	free(c);
	if (oom)
		return NAN;
	return sum / (3.0 * (double)valid_rows * (double)(a->width - 2 * SSIM_R));
}

/* ------------------------------------------------------------------ pooling */

void mtr_pool(const mtr_frame_stats *f, size_t n, mtr_frame_stats *p)
{
	memset(p, 0, sizeof *p);
	if (n == 0)
		return;
	size_t nf = 0, ns = 0;
	p->max = -1;
	double fl = 0, ss = 0;
	for (size_t i = 0; i < n; i++) {
		p->mean += f[i].mean;
		p->p50 += f[i].p50;
		p->p95 += f[i].p95;
		p->p99 += f[i].p99;
		p->mse += f[i].mse;
		for (int k = 0; k < MTR_THRESHOLD_COUNT; k++)
			p->exceed[k] += f[i].exceed[k];
		if (!isnan(f[i].ssim)) {
			ss += f[i].ssim;
			ns++;
		}
		if (!isnan(f[i].flicker_mean)) {
			fl += f[i].flicker_mean;
			nf++;
		}
		if (f[i].max > p->max) {
			p->max = f[i].max;
			p->max_x = f[i].max_x;
			p->max_y = f[i].max_y;
		}
	}
	double k = 1.0 / (double)n;
	p->mean *= k;
	p->p50 *= k;
	p->p95 *= k;
	p->p99 *= k;
	p->mse *= k;
	for (int t = 0; t < MTR_THRESHOLD_COUNT; t++)
		p->exceed[t] *= k;
	p->psnr = p->mse > 0 ? 10.0 * log10(255.0 * 255.0 / p->mse) : INFINITY;
	p->ssim = ns ? ss / (double)ns : NAN;
	p->flicker_mean = nf ? fl / (double)nf : NAN;
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
