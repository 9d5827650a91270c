/* metric_ssim.c — the `ssim` metric: SSIM (Wang, Bovik, Sheikh, Simoncelli, "Image Quality Assessment: From Error
 * Visibility to Structural Similarity", IEEE TIP 13(4), 2004), eq. 13 with the 11x11 Gaussian window (sigma 1.5)
 * of their sec. III-C, K1 = 0.01, K2 = 0.03, L = 255, population (co)variances, per RGB channel over the windows
 * that fit inside the image, averaged over pixels and channels — equal to scikit-image's
 * structural_similarity(gaussian_weights=True, use_sample_covariance=False, data_range=255, channel_axis=2)
 * within 1e-5 (tests/reference/ssim_reference.json).
 *
 * Speed: one sweep down each row band. Every input row is filtered horizontally once, for all 12 quantities at once
 * (a, b, a^2 + b^2, ab for the three channels: eq. 13 needs the variances only as their sum), into a ring of the last
 * 12 rows; output rows are then made two at a time by the vertical filter of the ring (the 12 rows loaded once for
 * both: the ring, ~1 MB for a 1080p row, is read from L2, whose bandwidth bounded a one-row pass — 14.4 -> 12.4 ms per
 * 1080p pair on 2 threads, same bits) followed by eq. 13. Both filters fold the symmetric window (6 multiplies for
 * 11 taps) in branch-free loops over x that gcc vectorises; row sums of eq. 13 in 8 independent partial sums, then
 * double. Values are centred (v - 128) before the products, so the variances E[a^2] - E[a]^2 are differences of
 * smaller numbers; the means get the 128 back for the luminance term. On a rendered 1080p pair the result is within
 * 1e-7 of a double-precision evaluation (the implementation before this one: 5.8e-5, over the 1e-5 tolerance;
 * tests/test_metrics.c test_ssim_frame).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "metric.h"

#define SSIM_R 5 /* 11x11 window */
#define SSIM_N (2 * SSIM_R + 1)
#define SSIM_Q 12 /* quantities filtered: 4 per channel */
#define SSIM_RING (SSIM_N + 1) /* ring of filtered input rows: two output rows at a time */
#define VW 8

typedef struct ssim_ctx {
	const mtr_image *a, *b;
	float g[SSIM_R + 1]; /* half window: g[k] = weight at offset +-k */
	double sum[MTR_MAX_THREADS];
	int oom;
} ssim_ctx;

/* out[x] = sum_k g[|k|] in[x + R + k], x in [0, n): the symmetric window folded. */
static inline void hfilter(const float *restrict in, float *restrict out, uint32_t n, const float *g)
{
	const float g0 = g[0], g1 = g[1], g2 = g[2], g3 = g[3], g4 = g[4], g5 = g[5];
	for (uint32_t x = 0; x < n; x++) {
		const float *v = in + x + SSIM_R;
		out[x] = g0 * v[0] + g1 * (v[-1] + v[1]) + g2 * (v[-2] + v[2]) + g3 * (v[-3] + v[3]) + g4 * (v[-4] + v[4]) +
			 g5 * (v[-5] + v[5]);
	}
}

/* Two output rows at once, out0[x] = sum_k g[|k - R|] rows[k][x] and out1 the same over rows[k + 1]: the 12 rows are
 * loaded once for both (the ring lives in L2, whose bandwidth bounded the one-row pass: 11 loads per output). Each
 * output is summed in the same order as a one-row pass would, so the results do not depend on the pairing. */
static inline void vfilter2(float *const *rows, float *restrict out0, float *restrict out1, uint32_t n, const float *g)
{
	const float g0 = g[0], g1 = g[1], g2 = g[2], g3 = g[3], g4 = g[4], g5 = g[5];
	const float *r0 = rows[0], *r1 = rows[1], *r2 = rows[2], *r3 = rows[3], *r4 = rows[4], *r5 = rows[5],
		    *r6 = rows[6], *r7 = rows[7], *r8 = rows[8], *r9 = rows[9], *r10 = rows[10], *r11 = rows[11];
	for (uint32_t x = 0; x < n; x++) {
		const float v0 = r0[x], v1 = r1[x], v2 = r2[x], v3 = r3[x], v4 = r4[x], v5 = r5[x], v6 = r6[x], v7 = r7[x],
			    v8 = r8[x], v9 = r9[x], v10 = r10[x], v11 = r11[x];
		out0[x] = g0 * v5 + g1 * (v4 + v6) + g2 * (v3 + v7) + g3 * (v2 + v8) + g4 * (v1 + v9) + g5 * (v0 + v10);
		out1[x] = g0 * v6 + g1 * (v5 + v7) + g2 * (v4 + v8) + g3 * (v3 + v9) + g4 * (v2 + v10) + g5 * (v1 + v11);
	}
}

/* Eq. 13 over one output row of one channel from its vertically filtered quantities (mu_a, mu_b, E[a^2 + b^2],
 * E[ab] at v, v + owp, ...); the row's sum through mtr_lane_sum. */
static inline double ssim_row(const float *v, size_t owp, uint32_t ow, float *restrict srow)
{
	const float C1 = (0.01f * 255) * (0.01f * 255), C2 = (0.03f * 255) * (0.03f * 255);
	const float *ma = v, *mb = v + owp, *ess = v + 2 * owp, *eab = v + 3 * owp;
	for (uint32_t x = 0; x < ow; x++) {
		/* sigma_a^2 + sigma_b^2 = E[a^2 + b^2] - mu_a^2 - mu_b^2 (centred values), written as
		 * E[a^2 + b^2] - 2 mu_a mu_b - (mu_a - mu_b)^2, and mu_a^2 + mu_b^2 as 2 mu_a mu_b + (mu_a - mu_b)^2: the same
		 * values, but for identical images (mu_a = mu_b, E[a^2 + b^2] = 2 E[ab] exactly: doubling commutes with
		 * rounding) each denominator is then its numerator bit for bit and eq. 13 is exactly 1 (issue 31.9: it was
		 * 1 +- 2e-10). Eq. 13 is at most 1 (sec. III-B); a rounding above it is clamped. */
		const float dm = ma[x] - mb[x], dmu = (ma[x] + 128.0f) - (mb[x] + 128.0f);
		const float vsum = (ess[x] - 2 * (ma[x] * mb[x])) - dm * dm, cov = eab[x] - ma[x] * mb[x];
		const float ua = ma[x] + 128.0f, ub = mb[x] + 128.0f;
		const float s = ((2 * (ua * ub) + C1) * (2 * cov + C2)) / ((2 * (ua * ub) + dmu * dmu + C1) * (vsum + C2));
		srow[x] = s < 1.0f ? s : 1.0f;
	}
	return mtr_lane_sum(srow, ow);
}

MTR_TARGET_CLONES static void ssim_band(void *p, int band, uint32_t y0, uint32_t y1)
{
	/* Output rows [y0, y1) of the valid region (image rows y + R); input rows [y0, y1 + 2R). Output rows go in pairs
	 * (vfilter2) from a ring of the last 2R + 2 filtered input rows; an odd last row goes alone. */
	ssim_ctx *c = p;
	const uint32_t w = c->a->width, ow = w - 2 * SSIM_R;
	const size_t owp = ((size_t)ow + VW - 1) / VW * VW;
	float *ring = malloc((size_t)SSIM_RING * SSIM_Q * owp * sizeof *ring);
	float *in = malloc((size_t)4 * w * sizeof *in); /* one channel's a, b, a^2 + b^2, ab of an input row */
	float *v = malloc((size_t)8 * owp * sizeof *v); /* vertically filtered quantities of one channel, two rows */
	float *srow = malloc(owp * sizeof *srow);
	if (!ring || !in || !v || !srow) {
		free(ring), free(in), free(v), free(srow);
		c->oom = 1;
		return;
	}
	double total = 0;
	for (uint32_t r = y0; r < y1 + 2 * SSIM_R; r++) {
		/* Horizontal pass of input row r into ring slot r mod 12, all 12 quantities. */
		float *slot = ring + (size_t)(r % SSIM_RING) * SSIM_Q * owp;
		const float *ar = c->a->rgb + (size_t)r * w * 3, *br = c->b->rgb + (size_t)r * w * 3;
		for (int ch = 0; ch < 3; ch++) {
			float *ia = in, *ib = in + w, *iss = in + 2 * (size_t)w, *iab = in + 3 * (size_t)w;
			for (uint32_t x = 0; x < w; x++) {
				float va = ar[3 * (size_t)x + ch] - 128.0f, vb = br[3 * (size_t)x + ch] - 128.0f;
				ia[x] = va;
				ib[x] = vb;
				iss[x] = va * va + vb * vb;
				iab[x] = va * vb;
			}
			for (int q = 0; q < 4; q++)
				hfilter(in + (size_t)q * w, slot + (size_t)(4 * ch + q) * owp, ow, c->g);
		}
		if (r < y0 + 2 * SSIM_R)
			continue;
		/* Output row o = r - 2R is ready. Odd positions in the band finish a pair (o - 1, o); the band's last row,
		 * if at an even position, goes alone (its pair partner would be outside the band). */
		const uint32_t o = r - 2 * SSIM_R;
		const int pair = ((o - y0) & 1u) == 1u;
		if (!pair && o + 1 != y1)
			continue;
		const uint32_t o0 = pair ? o - 1 : o;
		double rs[2][3] = {{0}}; /* row sums, added to the total row by row as a one-row pass would */
		for (int ch = 0; ch < 3; ch++) {
			for (int q = 0; q < 4; q++) {
				float *rows[SSIM_RING];
				for (int k = 0; k < SSIM_RING; k++) /* rows o0 .. o0 + 2R + 1 (the last unused when alone) */
					rows[k] = ring + ((size_t)((o0 + (uint32_t)k) % SSIM_RING) * SSIM_Q + (size_t)(4 * ch + q)) *
								 owp;
				if (!pair) /* alone: rows[11] would be a stale slot; read row o0 + 2R twice instead (out1 unused) */
					rows[SSIM_RING - 1] = rows[SSIM_RING - 2];
				vfilter2(rows, v + (size_t)q * owp, v + (size_t)(4 + q) * owp, ow, c->g);
			}
			rs[0][ch] = ssim_row(v, owp, ow, srow);
			if (pair)
				rs[1][ch] = ssim_row(v + 4 * owp, owp, ow, srow);
		}
		for (int i = 0; i < 1 + pair; i++)
			for (int ch = 0; ch < 3; ch++)
				total += rs[i][ch];
	}
	free(ring);
	free(in);
	free(v);
	free(srow);
	c->sum[band] = total;
}

double mtr_ssim(const mtr_image *a, const mtr_image *b, int threads)
{
	if (a->width != b->width || a->height != b->height || a->width < SSIM_N || a->height < SSIM_N)
		return NAN;
	ssim_ctx *c = calloc(1, sizeof *c);
	if (!c)
		return NAN;
	c->a = a;
	c->b = b;
	double gs = 0, g[SSIM_R + 1];
	for (int k = 0; k <= SSIM_R; k++) {
		g[k] = exp(-(double)(k * k) / (2 * 1.5 * 1.5));
		gs += (k ? 2 : 1) * g[k];
	}
	for (int k = 0; k <= SSIM_R; k++)
		c->g[k] = (float)(g[k] / gs);
	uint32_t valid_rows = a->height - 2 * SSIM_R;
	int nt = mtr_thread_count(threads, valid_rows);
	mtr_parallel_rows(valid_rows, nt, ssim_band, c);
	double sum = 0;
	for (int t = 0; t < nt; t++)
		sum += c->sum[t];
	int oom = c->oom;
	free(c);
	if (oom)
		return NAN;
	return sum / (3.0 * (double)valid_rows * (double)(a->width - 2 * SSIM_R));
}

static int ssim_compute(void *state, const mtr_pair *p, mtr_frame_stats *out, char *err, size_t err_size)
{
	(void)state;
	out->ssim = mtr_ssim(p->a, p->b, p->threads); /* NAN for images smaller than the window */
	if (isnan(out->ssim) && p->a->width >= SSIM_N && p->a->height >= SSIM_N)
		return tl_error(err, err_size, TL_ERR_NOMEM, "ssim: out of memory");
	return TL_OK;
}

static void ssim_pool(void *state, const mtr_frame_stats *f, size_t n, mtr_frame_stats *p)
{
	(void)state;
	double s = 0;
	size_t k = 0;
	for (size_t i = 0; i < n; i++)
		if (!isnan(f[i].ssim))
			s += f[i].ssim, k++;
	p->ssim = k ? s / (double)k : NAN;
}

static const mtr_column ssim_columns[] = {
	{"ssim", offsetof(mtr_frame_stats, ssim), MTR_COL_BOTH},
	{0},
};

const mtr_metric mtr_metric_ssim = {
	.name = "ssim",
	.help = "SSIM (Wang et al. 2004), 11x11 Gaussian window, per RGB channel, averaged",
	.columns = ssim_columns,
	.compute = ssim_compute,
	.pool = ssim_pool,
};
