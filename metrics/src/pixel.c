/* pixel.c — the one pass over the pixels that maxrgb, psnr and flicker share (metric.h).
 *
 * Per row: a branch-free loop over x computes d = max-RGB difference (paper sec. 3, DESIGN section 3), the
 * squared channel differences (PSNR's MSE) and the flicker term max_c |(a - a_prev) - (b - b_prev)| (DESIGN
 * section 6) into row buffers and lane accumulators (VW independent partial sums: gcc vectorises them at -O3
 * without reassociating, so results do not depend on the ISA); a second loop over the L1-resident row counts
 * exceedances and the 256-bin histogram of floor(d) and finds the row maximum. Which quantities are computed is
 * decided per call, outside the loops (specialised by constant flags), so no per-pixel branch remains.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "metric.h"

#define VW 8 /* lanes of the partial sums */

typedef struct pass_ctx {
	const mtr_image *a, *b, *ap, *bp;
	unsigned what;
	float *map;
	int oom;
	mtr_pixel_result part[MTR_MAX_THREADS];
} pass_ctx;

/* d, squared error and flicker of one row; returns the three row sums through s[3]. */
static inline void row_kernel(const float *restrict a, const float *restrict b, const float *restrict ap,
			      const float *restrict bp, uint32_t w, float *restrict d, int want_sq, int want_fl,
			      double s[3])
{
	float acc_d[VW] = {0}, acc_sq[VW] = {0}, acc_fl[VW] = {0};
	uint32_t x = 0;
	for (; x + VW <= w; x += VW)
		for (int u = 0; u < VW; u++) {
			const size_t i = 3 * (size_t)(x + (uint32_t)u);
			float dr = a[i] - b[i], dg = a[i + 1] - b[i + 1], db = a[i + 2] - b[i + 2];
			float m = fmaxf(fabsf(dr), fmaxf(fabsf(dg), fabsf(db)));
			d[x + (uint32_t)u] = m;
			acc_d[u] += m;
			if (want_sq)
				acc_sq[u] += dr * dr + dg * dg + db * db;
			if (want_fl) {
				float fr = fabsf(dr - (ap[i] - bp[i])), fg = fabsf(dg - (ap[i + 1] - bp[i + 1])),
				      fb = fabsf(db - (ap[i + 2] - bp[i + 2]));
				acc_fl[u] += fmaxf(fr, fmaxf(fg, fb));
			}
		}
	for (; x < w; x++) { /* tail: lane 0 */
		const size_t i = 3 * (size_t)x;
		float dr = a[i] - b[i], dg = a[i + 1] - b[i + 1], db = a[i + 2] - b[i + 2];
		float m = fmaxf(fabsf(dr), fmaxf(fabsf(dg), fabsf(db)));
		d[x] = m;
		acc_d[0] += m;
		if (want_sq)
			acc_sq[0] += dr * dr + dg * dg + db * db;
		if (want_fl) {
			float fr = fabsf(dr - (ap[i] - bp[i])), fg = fabsf(dg - (ap[i + 1] - bp[i + 1])),
			      fb = fabsf(db - (ap[i + 2] - bp[i + 2]));
			acc_fl[0] += fmaxf(fr, fmaxf(fg, fb));
		}
	}
	s[0] = s[1] = s[2] = 0;
	for (int u = 0; u < VW; u++) {
		s[0] += acc_d[u];
		s[1] += acc_sq[u];
		s[2] += acc_fl[u];
	}
}

static void pass_band(void *p, int band, uint32_t y0, uint32_t y1)
{
	pass_ctx *c = p;
	const uint32_t w = c->a->width;
	mtr_pixel_result *r = &c->part[band];
	memset(r, 0, sizeof *r);
	r->max = -1.0f;
	r->integral = true;
	float *scratch = c->map ? NULL : malloc((size_t)w * sizeof *scratch);
	/* Four sub-histograms (by x mod 4): runs of equal d would otherwise chain every increment through memory. */
	uint32_t (*h4)[256] = calloc(4, sizeof *h4);
	if ((!c->map && !scratch) || !h4) {
		free(scratch);
		free(h4);
		c->oom = 1;
		return;
	}
	const int want_sq = (c->what & MTR_PASS_SQ) != 0, want_fl = (c->what & MTR_PASS_FLICKER) && c->ap;
	float thr[MTR_THRESHOLD_COUNT];
	for (int k = 0; k < MTR_THRESHOLD_COUNT; k++)
		thr[k] = (float)mtr_thresholds[k];
	int integral = 1;
	for (uint32_t y = y0; y < y1; y++) {
		const size_t o = (size_t)y * w * 3;
		const float *a = c->a->rgb + o, *b = c->b->rgb + o;
		const float *ap = want_fl ? c->ap->rgb + o : NULL, *bp = want_fl ? c->bp->rgb + o : NULL;
		float *d = c->map ? c->map + (size_t)y * w : scratch;
		double s[3];
		/* Constant flags: the compiler emits one specialised loop per combination. */
		if (want_sq && want_fl)
			row_kernel(a, b, ap, bp, w, d, 1, 1, s);
		else if (want_sq)
			row_kernel(a, b, ap, bp, w, d, 1, 0, s);
		else if (want_fl)
			row_kernel(a, b, ap, bp, w, d, 0, 1, s);
		else
			row_kernel(a, b, ap, bp, w, d, 0, 0, s);
		r->sum_d += s[0];
		r->sum_sq += s[1];
		r->sum_flicker += s[2];
		/* Exceedances, integrality and the row maximum: branch-free, vectorised. */
		uint32_t ex[MTR_THRESHOLD_COUNT] = {0};
		float rmax = -1.0f;
		int ok = 1;
		for (uint32_t x = 0; x < w; x++) {
			const float v = d[x];
			for (int k = 0; k < MTR_THRESHOLD_COUNT; k++)
				ex[k] += v > thr[k];
			rmax = fmaxf(rmax, v);
			const float cl = fminf(v, 255.0f);
			ok &= (float)(int32_t)cl == v;
		}
		integral &= ok;
		for (int k = 0; k < MTR_THRESHOLD_COUNT; k++)
			r->exceed[k] += ex[k];
		if (rmax > r->max) { /* first maximum in row order */
			uint32_t x = 0;
			while (d[x] != rmax)
				x++;
			r->max = rmax;
			r->max_x = x;
			r->max_y = y;
		}
		uint32_t x = 0;
		for (; x + 4 <= w; x += 4)
			for (int u = 0; u < 4; u++) {
				int32_t bin = (int32_t)fminf(d[x + (uint32_t)u], 255.0f);
				h4[u][bin]++;
			}
		for (; x < w; x++)
			h4[0][(int32_t)fminf(d[x], 255.0f)]++;
	}
	for (int k = 0; k < 256; k++)
		r->hist[k] = (uint64_t)h4[0][k] + h4[1][k] + h4[2][k] + h4[3][k];
	r->integral = integral != 0;
	free(scratch);
	free(h4);
}

int mtr_pixel_pass(const mtr_image *a, const mtr_image *b, const mtr_image *a_prev, const mtr_image *b_prev,
		   unsigned what, float *map, int threads, mtr_pixel_result *out)
{
	pass_ctx *c = calloc(1, sizeof *c);
	if (!c)
		return TL_ERR_NOMEM;
	/* Bands hold at most 2^32 - 1 pixels for the 32-bit per-band counts. */
	int nt = mtr_thread_count(threads, a->height);
	while (nt < MTR_MAX_THREADS && (uint64_t)a->width * ((a->height + (uint32_t)nt - 1) / (uint32_t)nt) > UINT32_MAX)
		nt++;
	*c = (pass_ctx){.a = a, .b = b, .ap = a_prev, .bp = b_prev, .what = what, .map = map};
	mtr_parallel_rows(a->height, nt, pass_band, c);
	if (c->oom) {
		free(c);
		return TL_ERR_NOMEM;
	}
	memset(out, 0, sizeof *out);
	out->max = -1.0f;
	out->integral = true;
	for (int t = 0; t < nt; t++) { /* bands in row order: the first maximum in row order wins ties */
		const mtr_pixel_result *r = &c->part[t];
		out->sum_d += r->sum_d;
		out->sum_sq += r->sum_sq;
		out->sum_flicker += r->sum_flicker;
		for (int k = 0; k < 256; k++)
			out->hist[k] += r->hist[k];
		for (int k = 0; k < MTR_THRESHOLD_COUNT; k++)
			out->exceed[k] += r->exceed[k];
		out->integral = out->integral && r->integral;
		if (r->max > out->max) {
			out->max = r->max;
			out->max_x = r->max_x;
			out->max_y = r->max_y;
		}
	}
	free(c);
	return TL_OK;
}

/* Order statistic k (0-based) of the histogrammed values: the smallest bin whose cumulative count exceeds k. */
static double hist_order(const uint64_t hist[256], uint64_t k)
{
	uint64_t cum = 0;
	for (int v = 0; v < 256; v++) {
		cum += hist[v];
		if (cum > k)
			return v;
	}
	return 255;
}

double mtr_hist_percentile(const uint64_t hist[256], uint64_t n, double pct)
{
	if (n == 0)
		return NAN;
	/* Type 7 (numpy's default), the same arithmetic as mtr_percentile: h = (n-1) p/100, interpolate between the
	 * order statistics floor(h) and floor(h)+1. */
	double h = (double)(n - 1) * pct / 100.0;
	uint64_t k = (uint64_t)floor(h);
	double frac = h - (double)k;
	float lo = (float)hist_order(hist, k);
	if (frac == 0.0 || k + 1 >= n)
		return lo;
	float hi = (float)hist_order(hist, k + 1);
	return lo + frac * (hi - lo);
}
