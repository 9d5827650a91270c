/* pixel.c — the one pass over the pixels that maxrgb, psnr and flicker share (metric.h).
 *
 * Per row: a branch-free loop over x computes d = max-RGB difference (paper sec. 3, DESIGN section 3), the
 * squared channel differences (PSNR's MSE) and the flicker term max_c |(a - a_prev) - (b - b_prev)| (DESIGN
 * section 6) into row buffers, summed by mtr_lane_sum (8 independent partial sums: gcc vectorises them at -O3
 * without reassociating, so results do not depend on the ISA); a second loop over the L1-resident row counts
 * exceedances and the 256-bin histogram of floor(d) and finds the row maximum. Which quantities are computed is
 * decided per call, outside the loops (specialised by constant flags), so no per-pixel branch remains.
 */
#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "metric.h"


typedef struct pass_ctx {
	const mtr_image *a, *b, *ap, *bp;
	unsigned what;
	float *map;
	int oom;
	mtr_pixel_result part[MTR_MAX_THREADS];
} pass_ctx;

static inline uint32_t float_bits(float v)
{
	uint32_t u;
	memcpy(&u, &v, sizeof u);
	return u;
}

static inline float max3(float a, float b, float c)
{
	/* Not fmaxf: its NaN rules keep gcc from vectorising it; the inputs are finite. */
	float m = a > b ? a : b;
	return m > c ? m : c;
}

/* d, squared error and flicker of one row into d[], sq[], fl[] (plain loops over x: gcc vectorises the stride-3
 * loads with permutes), then their row sums through s[3]. */
static inline void row_kernel(const float *restrict a, const float *restrict b, const float *restrict ap,
			      const float *restrict bp, size_t w, float *restrict d, float *restrict sq,
			      float *restrict fl, int want_sq, int want_fl, double s[3])
{
	for (size_t x = 0; x < w; x++) {
		const float dr = a[3 * x] - b[3 * x], dg = a[3 * x + 1] - b[3 * x + 1], db = a[3 * x + 2] - b[3 * x + 2];
		d[x] = max3(fabsf(dr), fabsf(dg), fabsf(db));
		if (want_sq)
			sq[x] = dr * dr + dg * dg + db * db;
		if (want_fl)
			fl[x] = max3(fabsf(dr - (ap[3 * x] - bp[3 * x])), fabsf(dg - (ap[3 * x + 1] - bp[3 * x + 1])),
				     fabsf(db - (ap[3 * x + 2] - bp[3 * x + 2])));
	}
	s[0] = mtr_lane_sum(d, w);
	s[1] = want_sq ? mtr_lane_sum(sq, w) : 0;
	s[2] = want_fl ? mtr_lane_sum(fl, w) : 0;
}

MTR_TARGET_CLONES static void pass_band(void *p, int band, uint32_t y0, uint32_t y1)
{
	pass_ctx *c = p;
	const uint32_t w = c->a->width;
	mtr_pixel_result *r = &c->part[band];
	memset(r, 0, sizeof *r);
	r->max = -1.0f;
	r->integral = true;
	float *scratch = malloc((size_t)w * 3 * sizeof *scratch); /* d (without a map), squared error, flicker */
	/* Four sub-histograms (by x mod 4): runs of equal d would otherwise chain every increment through memory. */
	uint32_t (*h4)[256] = calloc(4, sizeof *h4);
	if (!scratch || !h4) {
		free(scratch);
		free(h4);
		c->oom = 1;
		return;
	}
	const int want_sq = (c->what & MTR_PASS_SQ) != 0, want_fl = (c->what & MTR_PASS_FLICKER) && c->ap;
	static_assert(MTR_THRESHOLD_COUNT == 6, "one counter per threshold below");
	const uint32_t t0 = float_bits((float)mtr_thresholds[0]), t1 = float_bits((float)mtr_thresholds[1]),
		       t2 = float_bits((float)mtr_thresholds[2]), t3 = float_bits((float)mtr_thresholds[3]),
		       t4 = float_bits((float)mtr_thresholds[4]), t5 = float_bits((float)mtr_thresholds[5]),
		       t255 = float_bits(255.0f);
	int integral = 1;
	for (uint32_t y = y0; y < y1; y++) {
		const size_t o = (size_t)y * w * 3;
		const float *a = c->a->rgb + o, *b = c->b->rgb + o;
		const float *ap = want_fl ? c->ap->rgb + o : NULL, *bp = want_fl ? c->bp->rgb + o : NULL;
		float *d = c->map ? c->map + (size_t)y * w : scratch, *sq = scratch + w, *fl = scratch + 2 * (size_t)w;
		double s[3];
		/* Constant flags: the compiler emits one specialised loop per combination. */
		if (want_sq && want_fl)
			row_kernel(a, b, ap, bp, w, d, sq, fl, 1, 1, s);
		else if (want_sq)
			row_kernel(a, b, ap, bp, w, d, sq, fl, 1, 0, s);
		else if (want_fl)
			row_kernel(a, b, ap, bp, w, d, sq, fl, 0, 1, s);
		else
			row_kernel(a, b, ap, bp, w, d, sq, fl, 0, 0, s);
		r->sum_d += s[0];
		r->sum_sq += s[1];
		r->sum_flicker += s[2];
		/* Exceedances, integrality and the row maximum: branch-free, vectorised. d >= 0, so floats compare like
		 * their bit patterns as integers; integer compares vectorise where float ones (which may trap, under
		 * gcc's default -ftrapping-math) would stay branches. One counter per T, written out. */
		uint32_t e0 = 0, e1 = 0, e2 = 0, e3 = 0, e4 = 0, e5 = 0, mb = 0;
		int32_t ok = 1;
		for (uint32_t x = 0; x < w; x++) {
			const float v = d[x];
			uint32_t u;
			memcpy(&u, &v, sizeof u);
			e0 += u > t0;
			e1 += u > t1;
			e2 += u > t2;
			e3 += u > t3;
			e4 += u > t4;
			e5 += u > t5;
			mb = mb > u ? mb : u;
			const uint32_t cu = u < t255 ? u : t255;
			float cl;
			memcpy(&cl, &cu, sizeof cl);
			ok &= (float)(int32_t)cl == v;
		}
		float rmax;
		memcpy(&rmax, &mb, sizeof rmax);
		const uint32_t ex[MTR_THRESHOLD_COUNT] = {e0, e1, e2, e3, e4, e5};
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
				const float v = d[x + (uint32_t)u];
				int32_t bin = (int32_t)(v < 255.0f ? v : 255.0f);
				h4[u][bin]++;
			}
		for (; x < w; x++)
			h4[0][(int32_t)(d[x] < 255.0f ? d[x] : 255.0f)]++;
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
