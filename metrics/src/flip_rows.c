/* flip_rows.c — the row kernels of LDR-FLIP (flip.c runs them; the paper and the pipeline are described there):
 * colour conversion into the opponent planes, the vertical and horizontal passes of the separable filters (colour
 * pipeline: CSF spatial filtering; feature pipeline: edge and point detection), Hunt-adjusted CIELAB, and the colour,
 * feature and final errors.
 *
 * Implementation notes (speed): all filters are applied separably, vertical pass first then horizontal, over
 * column strips of at most STRIP_W output pixels so the working set stays in L2. The vertical pass makes two output
 * rows at a time from their 2R+2 converted input rows in a ring buffer, each loaded once for both (each input row
 * is converted once per strip; the next row's part is prefetched, as the hardware prefetcher does not follow a
 * strip's row-to-row stride). Each pass runs one loop per input plane, each as long as its own kernels (the
 * achromatic and red-green CSFs are narrow, see kernel_reach in flip.c), written with GCC vector extensions so that
 * accumulators and pointers stay in registers. No per-pixel branches; the transcendental functions are float
 * approximations (sRGB EOTF and cube root: a polynomial in the mantissa and an 8-entry table for the exponent;
 * series for log2/exp2; each within 1e-6 relative, measured) and sqrt is the hardware instruction
 * (-fno-math-errno). On x86-64 the hot functions get AVX-512 and AVX2+FMA clones (FLIP_TARGET_CLONES) with fused
 * multiply-adds (-ffp-contract=fast): clones round differently in the last bits (a machine always picks the same
 * one, so results are reproducible on it); every clone stays within 1e-7 of the reference means
 * (tests/test_metrics.c; the baseline clone checked by hand).
 */
#include "flip_internal.h"

#include "flip_math.h"

#include <math.h>
#include <string.h>

/* Colour pipeline, colour space transform: n packed sRGB pixels (0..255) -> linear RGB (sRGB EOTF) -> the three
 * opponent planes Y/Yn = (Yy + 16) / 116, X/Xn - Y/Yn = Cx / 500, Y/Yn - Z/Zn = Cz / 200 (YyCxCz up to constant
 * scale and offset, which the unit-sum CSF filters commute with). Y/Yn is also the feature pipeline's input.
 * One vectorised loop for every input (integral 8-bit values or not): the EOTF formula costs less than a 256-entry
 * table lookup, which x86 can only do with gathers. */
FLIP_TARGET_CLONES void flip_convert_row(const mtr_flip *f, const float *restrict rgb, uint32_t n,
                                         float *restrict lin, float *restrict py, float *restrict pcx,
                                         float *restrict pcz)
{
	const float m0 = f->lin2opp[0], m1 = f->lin2opp[1], m2 = f->lin2opp[2], m3 = f->lin2opp[3], m4 = f->lin2opp[4],
	            m5 = f->lin2opp[5], m6 = f->lin2opp[6], m7 = f->lin2opp[7], m8 = f->lin2opp[8];
	/* The EOTF over the interleaved values (dense vectors), then the matrix, which de-interleaves. */
	uint32_t i = 0;
	for (; i + 8 <= 3 * n; i += 8)
		srgb_eotf8(rgb + i, 1.0f / 255.0f, lin + i);
	if (i < 3 * n) { /* the row's last values, through the same 8-value function */
		float in8[8] = {0}, out8[8];
		memcpy(in8, rgb + i, (3 * n - i) * sizeof(float));
		srgb_eotf8(in8, 1.0f / 255.0f, out8);
		memcpy(lin + i, out8, (3 * n - i) * sizeof(float));
	}
	/* Eight pixels at a time: their 24 interleaved values de-interleaved by register permutes (gcc turns the
	 * stride-3 loads of the plain loop into scalar inserts). */
	const v8i mr = {0, 3, 6, 9, 12, 15, 0, 0}, mr2 = {0, 1, 2, 3, 4, 5, 10, 13};
	const v8i mg = {1, 4, 7, 10, 13, 0, 0, 0}, mg2 = {0, 1, 2, 3, 4, 8, 11, 14};
	const v8i mb = {2, 5, 8, 11, 14, 0, 0, 0}, mb2 = {0, 1, 2, 3, 4, 9, 12, 15};
	uint32_t p = 0;
	for (; p + 8 <= n; p += 8) {
		const v8f A = LD8(lin + 3 * p), B = LD8(lin + 3 * p + 8), C = LD8(lin + 3 * p + 16);
#if defined(__clang__) /* the libFuzzer build: the same permutations with clang's constant-index builtin */
		(void)mr, (void)mr2, (void)mg, (void)mg2, (void)mb, (void)mb2;
		const v8f r = __builtin_shufflevector(__builtin_shufflevector(A, B, 0, 3, 6, 9, 12, 15, 0, 0), C, 0, 1, 2, 3, 4, 5, 10, 13);
		const v8f g = __builtin_shufflevector(__builtin_shufflevector(A, B, 1, 4, 7, 10, 13, 0, 0, 0), C, 0, 1, 2, 3, 4, 8, 11, 14);
		const v8f b = __builtin_shufflevector(__builtin_shufflevector(A, B, 2, 5, 8, 11, 14, 0, 0, 0), C, 0, 1, 2, 3, 4, 9, 12, 15);
#else
		const v8f r = __builtin_shuffle(__builtin_shuffle(A, B, mr), C, mr2);
		const v8f g = __builtin_shuffle(__builtin_shuffle(A, B, mg), C, mg2);
		const v8f b = __builtin_shuffle(__builtin_shuffle(A, B, mb), C, mb2);
#endif
		ST8(py + p, m0 * r + m1 * g + m2 * b);
		ST8(pcx + p, m3 * r + m4 * g + m5 * b);
		ST8(pcz + p, m6 * r + m7 * g + m8 * b);
	}
	for (; p < n; p++) {
		const float r = lin[3 * p], g = lin[3 * p + 1], b = lin[3 * p + 2];
		py[p] = m0 * r + m1 * g + m2 * b;
		pcx[p] = m3 * r + m4 * g + m5 * b;
		pcz[p] = m6 * r + m7 * g + m8 * b;
	}
}

/* The filter loops are written with GCC's vector extensions (v8f, LD8, ST8 in flip_math.h: 8 floats, one AVX
 * register; two SSE registers in the baseline clone), mostly two vectors (VW = 16 floats) per accumulator so that
 * independent multiply-adds overlap. Loads and stores go through an unaligned, may-alias vector type. */

/* Vertical pass of the separable filters (colour pipeline: CSF spatial filtering; feature pipeline: edge / point
 * detection) for two output rows y and y + 1 at once (o0, o1: their V_N vertically filtered planes), buffer columns
 * [j0, j1) (multiples of VW). ry/rcx/rcz[R + k], -R <= k <= R + 1, are the opponent planes of source rows
 * clamp(y + k). Symmetric kernels fold the taps at -k and +k, the antisymmetric first derivative takes their
 * difference; one loop per input plane, each as long as its own kernels. Tap k of row y pairs source rows
 * y - k and y + k, tap k of row y + 1 pairs y + 1 - k and y + 1 + k; going outwards, each step loads the two new rows
 * y - k and y + 1 + k and reuses the two of the step before (y + k = y + 1 + (k - 1), y + 1 - k = y - (k - 1)), so
 * the 2R + 2 ring rows are read once for both outputs: half the ring traffic of two single passes (the ring is read
 * from L2, whose bandwidth bounds this pass; the same change made SSIM's vertical pass 14 % faster). */
FLIP_TARGET_CLONES void flip_vertical_pass(const mtr_flip *f, float *const *ry, float *const *rcx,
                                           float *const *rcz, size_t j0, size_t j1, float *const *o0,
                                           float *const *o1)
{
	const int R = f->R, kyf = f->ry > f->fr ? f->ry : f->fr;
	const float *wy = f->wy, *wcx = f->wcx, *wz1 = f->wcz1, *wz2 = f->wcz2;
	const float *fg = f->fg, *fdg = f->fdg, *fdd = f->fddg;
	/* Y/Yn: achromatic CSF and the three feature kernels, one 8-float vector per accumulator (eight of them). */
	for (size_t j = j0; j < j1; j += 8) {
		const v8f c0 = LD8(ry[R] + j), c1 = LD8(ry[R + 1] + j);
		v8f ay0 = wy[0] * c0, ag0 = fg[0] * c0, ad0 = (v8f){0}, add0 = fdd[0] * c0;
		v8f ay1 = wy[0] * c1, ag1 = fg[0] * c1, ad1 = (v8f){0}, add1 = fdd[0] * c1;
		v8f mprev = c0, pprev = c1;
		for (int k = 1; k <= kyf; k++) {
			const v8f m = LD8(ry[R - k] + j), p = LD8(ry[R + 1 + k] + j);
			const float a = wy[k], b = fg[k], d = fdg[k], e = fdd[k];
			const v8f sm0 = m + pprev, df0 = pprev - m, sm1 = mprev + p, df1 = p - mprev;
			ay0 += a * sm0;
			ag0 += b * sm0;
			ad0 += d * df0;
			add0 += e * sm0;
			ay1 += a * sm1;
			ag1 += b * sm1;
			ad1 += d * df1;
			add1 += e * sm1;
			mprev = m;
			pprev = p;
		}
		ST8(o0[V_Y] + j, ay0);
		ST8(o0[V_G] + j, ag0);
		ST8(o0[V_DG] + j, ad0);
		ST8(o0[V_DDG] + j, add0);
		ST8(o1[V_Y] + j, ay1);
		ST8(o1[V_G] + j, ag1);
		ST8(o1[V_DG] + j, ad1);
		ST8(o1[V_DDG] + j, add1);
	}
	/* Cx / 500: the red-green CSF. */
	for (size_t j = j0; j < j1; j += VW) {
		v8f a0[2], a1[2], mprev[2], pprev[2];
		for (int h = 0; h < 2; h++) {
			mprev[h] = LD8(rcx[R] + j + 8 * h);
			pprev[h] = LD8(rcx[R + 1] + j + 8 * h);
			a0[h] = wcx[0] * mprev[h];
			a1[h] = wcx[0] * pprev[h];
		}
		for (int k = 1; k <= f->rx; k++) {
			const float w = wcx[k];
			for (int h = 0; h < 2; h++) {
				const v8f m = LD8(rcx[R - k] + j + 8 * h), p = LD8(rcx[R + 1 + k] + j + 8 * h);
				a0[h] += w * (m + pprev[h]);
				a1[h] += w * (mprev[h] + p);
				mprev[h] = m;
				pprev[h] = p;
			}
		}
		for (int h = 0; h < 2; h++) {
			ST8(o0[V_CX] + j + 8 * h, a0[h]);
			ST8(o1[V_CX] + j + 8 * h, a1[h]);
		}
	}
	/* Cz / 200: the blue-yellow CSF's two Gaussians. */
	for (size_t j = j0; j < j1; j += VW) {
		v8f a0[2], b0[2], a1[2], b1[2], mprev[2], pprev[2];
		for (int h = 0; h < 2; h++) {
			mprev[h] = LD8(rcz[R] + j + 8 * h);
			pprev[h] = LD8(rcz[R + 1] + j + 8 * h);
			a0[h] = wz1[0] * mprev[h];
			b0[h] = wz2[0] * mprev[h];
			a1[h] = wz1[0] * pprev[h];
			b1[h] = wz2[0] * pprev[h];
		}
		for (int k = 1; k <= f->r; k++) {
			const float w1 = wz1[k], w2 = wz2[k];
			for (int h = 0; h < 2; h++) {
				const v8f m = LD8(rcz[R - k] + j + 8 * h), p = LD8(rcz[R + 1 + k] + j + 8 * h);
				const v8f sm0 = m + pprev[h], sm1 = mprev[h] + p;
				a0[h] += w1 * sm0;
				b0[h] += w2 * sm0;
				a1[h] += w1 * sm1;
				b1[h] += w2 * sm1;
				mprev[h] = m;
				pprev[h] = p;
			}
		}
		for (int h = 0; h < 2; h++) {
			ST8(o0[V_CZ1] + j + 8 * h, a0[h]);
			ST8(o0[V_CZ2] + j + 8 * h, b0[h]);
			ST8(o1[V_CZ1] + j + 8 * h, a1[h]);
			ST8(o1[V_CZ2] + j + 8 * h, b1[h]);
		}
	}
}

/* Two planes, each with its own symmetric kernel (half kernels w1, w2, taps 1..r): o1[i] = sum_k w1[|k|] p1[i + k],
 * likewise o2, i in [0, n) (multiple of VW); p1, p2 have r readable values either side. */
static inline void hfilter_pair(const float *p1, const float *w1, const float *p2, const float *w2, int r, size_t n,
                                float *o1, float *o2)
{
	for (size_t i = 0; i < n; i += VW) {
		v8f a1[2], a2[2];
		for (int u = 0; u < 2; u++) {
			a1[u] = w1[0] * LD8(p1 + i + 8 * u);
			a2[u] = w2[0] * LD8(p2 + i + 8 * u);
		}
		for (int k = 1; k <= r; k++) {
			const float c1 = w1[k], c2 = w2[k];
			for (int u = 0; u < 2; u++) {
				a1[u] += c1 * (LD8(p1 + i + 8 * u - k) + LD8(p1 + i + 8 * u + k));
				a2[u] += c2 * (LD8(p2 + i + 8 * u - k) + LD8(p2 + i + 8 * u + k));
			}
		}
		for (int u = 0; u < 2; u++) {
			ST8(o1 + i + 8 * u, a1[u]);
			ST8(o2 + i + 8 * u, a2[u]);
		}
	}
}

/* Horizontal pass of the separable filters: output i in [0, n) (n multiple of VW) reads the vertically filtered
 * planes at i + R + offset (the R halo columns were filled by clamp-to-edge). Produces the CSF-filtered Y, Cx,
 * Cz = (Cz Gaussian 1 + Cz Gaussian 2) and the detectors: edge x = d/dx (x) Gaussian (y), edge y = Gaussian (x)
 * d/dy (y), and likewise for the points with the second derivative. Four loops with at most four input streams
 * each, so that pointers and accumulators stay in registers. */
FLIP_TARGET_CLONES void flip_horizontal_pass(const mtr_flip *f, const float *v, size_t swp, size_t n, float *h)
{
	const int R = f->R, rxy = f->ry > f->rx ? f->ry : f->rx;
	const float *wy = f->wy, *wcx = f->wcx, *wz1 = f->wcz1, *wz2 = f->wcz2;
	const float *fg = f->fg, *fdg = f->fdg, *fdd = f->fddg;
	const float *iy = v + V_Y * swp + R, *ix = v + V_CX * swp + R, *iz1 = v + V_CZ1 * swp + R,
	            *iz2 = v + V_CZ2 * swp + R, *ig = v + V_G * swp + R, *id = v + V_DG * swp + R,
	            *idd = v + V_DDG * swp + R;
	/* Achromatic and red-green CSFs (wy, wcx are zero beyond their own radius). */
	hfilter_pair(iy, wy, ix, wcx, rxy, n, h + H_Y * swp, h + H_CX * swp);
	/* Blue-yellow CSF: the two Gaussians in their own accumulators, summed at the end. */
	for (size_t i = 0; i < n; i += VW) {
		v8f a1[2], a2[2];
		for (int u = 0; u < 2; u++) {
			a1[u] = wz1[0] * LD8(iz1 + i + 8 * u);
			a2[u] = wz2[0] * LD8(iz2 + i + 8 * u);
		}
		for (int k = 1; k <= f->r; k++) {
			const float c1 = wz1[k], c2 = wz2[k];
			for (int u = 0; u < 2; u++) {
				a1[u] += c1 * (LD8(iz1 + i + 8 * u - k) + LD8(iz1 + i + 8 * u + k));
				a2[u] += c2 * (LD8(iz2 + i + 8 * u - k) + LD8(iz2 + i + 8 * u + k));
			}
		}
		for (int u = 0; u < 2; u++)
			ST8(h + H_CZ * swp + i + 8 * u, a1[u] + a2[u]);
	}
	/* Feature pipeline, x derivatives of the vertically Gaussian-filtered plane: edges (first derivative,
	 * antisymmetric) and points (second derivative). */
	for (size_t i = 0; i < n; i += VW) {
		v8f ae[2], ap[2];
		for (int u = 0; u < 2; u++) {
			v8f c = LD8(ig + i + 8 * u);
			ae[u] = (v8f){0};
			ap[u] = fdd[0] * c;
		}
		for (int k = 1; k <= f->fr; k++) {
			const float d = fdg[k], dd = fdd[k];
			for (int u = 0; u < 2; u++) {
				v8f gl = LD8(ig + i + 8 * u - k), gh = LD8(ig + i + 8 * u + k);
				ae[u] += d * (gh - gl);
				ap[u] += dd * (gl + gh);
			}
		}
		for (int u = 0; u < 2; u++) {
			ST8(h + H_EX * swp + i + 8 * u, ae[u]);
			ST8(h + H_PX * swp + i + 8 * u, ap[u]);
		}
	}
	/* y derivatives: the vertical first / second derivative planes filtered with the Gaussian along x. */
	hfilter_pair(id, fg, idd, fg, f->fr, n, h + H_EY * swp, h + H_PY * swp);
}

/* Filtered opponent values -> linear RGB clamped to [0,1] -> Hunt-adjusted CIELAB (colour pipeline):
 * (py, pcx, pcz) -> (pl, pa, pb), eight pixels at a time (n is a multiple of VW). */
FLIP_TARGET_CLONES void flip_hunt_lab_row(const mtr_flip *f, const float *restrict py, const float *restrict pcx,
                                          const float *restrict pcz, float *restrict pl, float *restrict pa,
                                          float *restrict pb, size_t n)
{
	const float *m = f->opp2rgb, *nm = f->rgb2xyzn;
	const float m0 = m[0], m1 = m[1], m2 = m[2], m3 = m[3], m4 = m[4], m5 = m[5], m6 = m[6], m7 = m[7], m8 = m[8];
	const float n0 = nm[0], n1 = nm[1], n2 = nm[2], n3 = nm[3], n4 = nm[4], n5 = nm[5], n6 = nm[6], n7 = nm[7],
	            n8 = nm[8];
	/* Two independent 8-pixel groups per iteration: the polynomials are chains of dependent multiply-adds; two
	 * groups give the scheduler independent work (a few per cent of FLIP, within the noise of one run). */
	for (size_t i0 = 0; i0 < n; i0 += 16) {
		v8f fx[2], fy[2], fz[2];
		for (int h = 0; h < 2; h++) {
			const size_t i = i0 + 8 * (size_t)h;
			const v8f y = LD8(py + i), cx = LD8(pcx + i), cz = LD8(pcz + i);
			const v8f r = clamp01_8(m0 * y + m1 * cx + m2 * cz);
			const v8f g = clamp01_8(m3 * y + m4 * cx + m5 * cz);
			const v8f b = clamp01_8(m6 * y + m7 * cx + m8 * cz);
			fx[h] = n0 * r + n1 * g + n2 * b;
			fy[h] = n3 * r + n4 * g + n5 * b;
			fz[h] = n6 * r + n7 * g + n8 * b;
		}
		for (int h = 0; h < 2; h++) {
			fx[h] = lab_f8(fx[h]);
			fy[h] = lab_f8(fy[h]);
			fz[h] = lab_f8(fz[h]);
		}
		for (int h = 0; h < 2; h++) {
			const size_t i = i0 + 8 * (size_t)h;
			const v8f l = 116.0f * fy[h] - 16.0f;
			ST8(pl + i, l);
			ST8(pa + i, 0.01f * l * 500.0f * (fx[h] - fy[h])); /* Hunt: a' = 0.01 L a */
			ST8(pb + i, 0.01f * l * 200.0f * (fy[h] - fz[h])); /* Hunt: b' = 0.01 L b */
		}
	}
}

/* Colour difference, feature difference and final error for n (multiple of VW) pixels; hr / ht hold L, a', b' (see
 * hunt_lab_row) and the edge / point responses. */
FLIP_TARGET_CLONES void flip_finalize_row(const mtr_flip *f, const float *restrict hr, const float *restrict ht,
                                          size_t swp, size_t n, float *restrict out)
{
	const float cmax_lo = f->cmax_lo, slope_lo = f->slope_lo, slope_hi = f->slope_hi, log2_slope_lo = f->log2_slope_lo;
	for (size_t i = 0; i < n; i += VW) {
		for (int u = 0; u < VW; u++) {
			const size_t p = i + (size_t)u;
			/* HyAB distance, then ^q_c and the compression re-mapping into [0,1]. */
			float dl = hr[H_L * swp + p] - ht[H_L * swp + p];
			float da = hr[H_A * swp + p] - ht[H_A * swp + p], db = hr[H_B * swp + p] - ht[H_B * swp + p];
			float hy = fabsf(dl) + sqrtf(da * da + db * db);
			const float lq = (float)FLIP_QC * fast_log2(select_f(hy > 1e-30f, hy, 1e-30f)); /* log2 hy^q_c */
			const float pq = fast_exp2(lq);
			const int lower = pq < cmax_lo;
			float dc = select_f(lower, slope_lo * pq, (float)FLIP_PT + (pq - cmax_lo) * slope_hi);
			dc = select_f(hy > 0.0f, dc, 0.0f);
			/* log2 dc for the final error's power, without a second fast_log2: below the knee
			 * log2(slope_lo hy^q_c) = log2 slope_lo + q_c log2 hy; above it dc is in [p_t, 1], where
			 * log2(1 + x), x = dc - 1 in [-0.05, 0], is its series to x^6 (error < 2e-10). */
			const float x = dc - 1.0f;
			float ls = -1.0f / 6.0f;
			ls = ls * x + 0.2f;
			ls = ls * x - 0.25f;
			ls = ls * x + 1.0f / 3.0f;
			ls = ls * x - 0.5f;
			ls = ls * x + 1.0f;
			const float ldc = select_f(lower, log2_slope_lo + lq, ls * x * 1.44269504f); /* 1 / ln 2 */
			/* Feature pipeline: edge and point magnitudes, difference, / sqrt(2), ^q_f (q_f = 0.5 -> sqrt). */
			float ex1 = hr[H_EX * swp + p], ey1 = hr[H_EY * swp + p], px1 = hr[H_PX * swp + p],
			      py1 = hr[H_PY * swp + p];
			float ex2 = ht[H_EX * swp + p], ey2 = ht[H_EY * swp + p], px2 = ht[H_PX * swp + p],
			      py2 = ht[H_PY * swp + p];
			float de = fabsf(sqrtf(ex1 * ex1 + ey1 * ey1) - sqrtf(ex2 * ex2 + ey2 * ey2));
			float dp = fabsf(sqrtf(px1 * px1 + py1 * py1) - sqrtf(px2 * px2 + py2 * py2));
			float df = sqrtf(select_f(de > dp, de, dp) * 0.707106781f);
			/* Final error dE_c^(1 - dE_f); 0^0 = 1 as with pow(). */
			float ex = 1.0f - df;
			float e = fast_exp2(ex * ldc);
			out[p] = select_f(dc > 0.0f, e, select_f(ex == 0.0f, 1.0f, 0.0f));
		}
	}
}
