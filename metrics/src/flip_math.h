/* flip_math.h — branch-free float approximations for flip.c's vectorised row loops (private to metrics/src).
 * Scalar ones are plain C that gcc vectorises (no calls, no branches: selects through bit masks); the 8-float ones
 * (GCC vector extensions) look up small tables with a register permute. fast_log2 keeps one division. Accuracies
 * are stated per function, measured against double-precision libm over the ranges flip.c uses. */
#ifndef TASLAB_FLIP_MATH_H
#define TASLAB_FLIP_MATH_H

#include <stdint.h>
#include <string.h>

static inline float bits_to_float(uint32_t u)
{
	float x;
	memcpy(&x, &u, sizeof x);
	return x;
}

static inline uint32_t float_to_bits(float x)
{
	uint32_t u;
	memcpy(&u, &x, sizeof u);
	return u;
}

/* Branch-free select (c ? a : b) through bit masks. A plain ?: whose operands are floating-point expressions is
 * not if-converted by gcc under the default -ftrapping-math (the arithmetic could trap if speculated), which blocks
 * vectorisation; this form is. */
static inline float select_f(int c, float a, float b)
{
	uint32_t m = 0u - (uint32_t)(c != 0);
	return bits_to_float((float_to_bits(a) & m) | (float_to_bits(b) & ~m));
}

/* log2(x) for positive normal x; error within ~1 ulp of the result (measured < 1.1e-6 absolute for |log2 x| <= 20,
 * < 2e-7 near x = 1). Mantissa reduced to [sqrt(1/2), sqrt(2)), then
 * ln(m) = 2 atanh(s), s = (m-1)/(m+1), by its odd series up to s^9. */
static inline float fast_log2(float x)
{
	uint32_t u = float_to_bits(x);
	int32_t e = (int32_t)((u >> 23) & 0xffu) - 127;
	float m = bits_to_float((u & 0x007fffffu) | 0x3f800000u);
	int big = m > 1.41421356f;
	m = select_f(big, m * 0.5f, m);
	e += big;
	float s = (m - 1.0f) / (m + 1.0f), s2 = s * s;
	float p = 1.0f / 9.0f;
	p = p * s2 + 1.0f / 7.0f;
	p = p * s2 + 1.0f / 5.0f;
	p = p * s2 + 1.0f / 3.0f;
	p = p * s2 + 1.0f;
	return (float)e + s * p * 2.88539008f; /* 2 / ln 2 */
}

/* 2^x, x clamped to [-126, 127]; relative error < 1e-7 (measured). n = round(x), 2^f for f in [-0.5, 0.5] by Taylor
 * series. */
static inline float fast_exp2(float x)
{
	x = select_f(x > -126.0f, x, -126.0f); /* also maps NaN to -126 */
	x = select_f(x < 127.0f, x, 127.0f);
	int32_t n = (int32_t)(x + 127.5f) - 127; /* floor(x + 0.5); argument positive so truncation is floor */
	float t = (x - (float)n) * 0.693147181f;
	float p = 1.0f / 5040.0f;
	p = p * t + 1.0f / 720.0f;
	p = p * t + 1.0f / 120.0f;
	p = p * t + 1.0f / 24.0f;
	p = p * t + 1.0f / 6.0f;
	p = p * t + 0.5f;
	p = p * t + 1.0f;
	p = p * t + 1.0f;
	return p * bits_to_float((uint32_t)(n + 127) << 23);
}

/* sRGB EOTF (IEC 61966-2-1) for values in 0..1 (clamped into it): linear segment below 0.04045, else b^2.4 with
 * b = (c + 0.055) / 1.055 in [0.09, 1]. Written b = m 2^e with m in [1, 2): b^2.4 = m^2.4 2^(2.4 e), m^2.4 by a
 * degree-6 polynomial in t = 2m - 3 (its Chebyshev interpolant on [1, 2]) and 2^(2.4 e), e in [-7, 0], from an
 * 8-entry table (one register permute; srgb_eotf8 below). No division, log/exp or iteration; relative error < 5e-7
 * over [0.04045, 1] (measured against pow() in double). */
#define EOTF_C0 2.6461777687072754f
#define EOTF_C1 2.1169426441192627f
#define EOTF_C2 0.4939531087875366f
#define EOTF_C3 0.02195076271891594f
#define EOTF_C4 -0.001097148866392672f
#define EOTF_C5 0.00012242597586009651f
#define EOTF_C6 -1.7943819329957478e-05f
/* 2^(2.4 (k - 7)), k = 0..7, rounded to float */
#define EOTF_T0 8.76387276e-06f
#define EOTF_T1 4.62559983e-05f
#define EOTF_T2 0.000244140625f
#define EOTF_T3 0.00128858199f
#define EOTF_T4 0.00680117635f
#define EOTF_T5 0.0358968228f
#define EOTF_T6 0.189464569f
#define EOTF_T7 1.0f

/* ---- 8-float vectors (GCC vector extensions) ---- */

typedef float v8f __attribute__((vector_size(32)));
typedef int32_t v8i __attribute__((vector_size(32)));
typedef float v8f_u __attribute__((vector_size(32), aligned(4), may_alias));
#define LD8(p) (*(const v8f_u *)(const void *)(p))
#define ST8(p, v) (*(v8f_u *)(void *)(p) = (v))

/* Lane-wise c ? a : b for a comparison mask c (all bits set or clear per lane). (Static functions with vector
 * arguments are fine in every clone; flip.c is built with -Wno-psabi, whose note concerns exported ones.) */
#define SELECT8(c, a, b) ((v8f)(((c) & (v8i)(a)) | (~(c) & (v8i)(b))))

/* tab[idx[i] & 7] in each lane: GCC's __builtin_shuffle (one permute); clang, which builds the libFuzzer harnesses,
 * has no shuffle with a run-time mask, so lane by lane there (the same values). */
static inline v8f table8(v8f tab, v8i idx)
{
#if defined(__clang__)
	v8f r;
	for (int i = 0; i < 8; i++)
		r[i] = tab[idx[i] & 7];
	return r;
#else
	return __builtin_shuffle(tab, idx);
#endif
}

static inline v8f clamp01_8(v8f v)
{
	const v8f zero = {0}, one = zero + 1.0f;
	v = SELECT8(v > zero, v, zero); /* also NaN -> 0 */
	return SELECT8(v < one, v, one);
}

/* Cube root for t in [0.008856, 1] (the CIELAB range it is used on): t = m 2^e, m in [1, 2), e in [-7, 0];
 * cbrt(t) = cbrt(m) 2^(e/3), cbrt(m) by a degree-6 polynomial in 2m - 3 (its Chebyshev interpolant on [1, 2]),
 * 2^(e/3) from an 8-entry table (a register permute). Relative error < 3.3e-7 (measured against cbrt() in double);
 * no division or iteration. */
static inline v8f cbrt8(v8f t)
{
	const v8f zero = {0};
	const v8f tab = {0.198425129f, 0.25f, 0.314980268f, 0.396850258f, 0.5f, 0.629960537f, 0.793700516f, 1.0f};
	const v8i u = (v8i)t;
	const v8f x = 2.0f * (v8f)((u & 0x007fffff) | 0x3f800000) - 3.0f;
	v8f p = zero - 4.223959331284277e-05f;
	p = p * x + 0.00016145936388056725f;
	p = p * x - 0.0005787980044260621f;
	p = p * x + 0.0026071437168866396f;
	p = p * x - 0.014132625423371792f;
	p = p * x + 0.1271917223930359f;
	p = p * x + 1.1447142362594604f;
	return p * table8(tab, ((u >> 23) - 120) & 7);
}

/* CIELAB companding f(t) (colour pipeline, CIELAB): cube root above (6/29)^3, else t / (3 (6/29)^2) + 4/29. */
static inline v8f lab_f8(v8f t)
{
	const v8f zero = {0}, lo = zero + 0.008856f;
	const v8f cr = cbrt8(SELECT8(t > lo, t, lo)); /* keep the unused branch in the table's range */
	return SELECT8(t > 0.00885645168f, cr, t * 7.78703704f + 0.137931034f);
}

/* The sRGB EOTF (see EOTF_C0 above) of 8 values: out[i] = EOTF(in[i] * scale). */
static inline void srgb_eotf8(const float *in, float scale, float *out)
{
	v8f v = LD8(in) * scale;
	const v8f zero = {0}, one = zero + 1.0f, lin_hi = zero + 0.04045f;
	const v8f tab = {EOTF_T0, EOTF_T1, EOTF_T2, EOTF_T3, EOTF_T4, EOTF_T5, EOTF_T6, EOTF_T7};
	v = SELECT8(v > zero, v, zero);
	v = SELECT8(v < one, v, one);
	const v8f b = SELECT8(v > lin_hi, v * (1.0f / 1.055f) + (0.055f / 1.055f), zero + 0.5f);
	const v8i u = (v8i)b;
	const v8f t = 2.0f * (v8f)((u & 0x007fffff) | 0x3f800000) - 3.0f;
	v8f p = zero + EOTF_C6;
	p = p * t + EOTF_C5;
	p = p * t + EOTF_C4;
	p = p * t + EOTF_C3;
	p = p * t + EOTF_C2;
	p = p * t + EOTF_C1;
	p = p * t + EOTF_C0;
	const v8f hi = p * table8(tab, ((u >> 23) - 120) & 7);
	ST8(out, SELECT8(v <= lin_hi, v * (1.0f / 12.92f), hi));
}

#endif
