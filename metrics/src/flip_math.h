/* flip_math.h — branch-free float approximations for flip.c's vectorised row loops (private to metrics/src).
 * Each is plain C that gcc vectorises: no calls, no branches (selects through bit masks), Newton iterations without
 * division where one converges (cube root, fifth root); fast_log2 keeps one division. Accuracies
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

/* Cube root of a positive normal float in [0.008856, 1] (the CIELAB range it is used on): z = t^(-1/3) from a
 * bit-level guess and three Newton steps z <- z (4 - t z^3) / 3 (no division), then t z^2; relative error
 * < 3.3e-7 over that range (measured against cbrt() in double). */
static inline float fast_cbrt(float t)
{
	float z = bits_to_float(0x54a0f000u - float_to_bits(t) / 3u);
	for (int i = 0; i < 3; i++)
		z = z * (1.33333333f - 0.333333333f * t * (z * z * z));
	return t * z * z;
}

/* CIELAB companding f(t) (colour pipeline, CIELAB): cube root above (6/29)^3, else t / (3 (6/29)^2) + 4/29. */
static inline float lab_f_fast(float t)
{
	float cr = fast_cbrt(select_f(t > 0.008856f, t, 0.008856f)); /* keep the unused branch finite */
	return select_f(t > 0.00885645168f, cr, t * 7.78703704f + 0.137931034f);
}

static inline float clamp01(float v)
{
	v = select_f(v > 0.0f, v, 0.0f);
	return select_f(v < 1.0f, v, 1.0f);
}

/* sRGB EOTF (IEC 61966-2-1) for values in 0..1: linear segment below 0.04045, else b^2.4 with b = (c + 0.055) / 1.055,
 * computed as b^3 z^3 with z = b^(-1/5) from a bit-level guess and three Newton steps z <- z (6 - b z^5) / 5
 * (no division, no log/exp; relative error < 7e-7 over [0.04045, 1], measured against pow() in double). */
static inline float srgb_eotf_fast(float v)
{
	float b = v * (1.0f / 1.055f) + (0.055f / 1.055f);
	b = select_f(b > 0.01f, b, 0.01f); /* keep the unused branch finite */
	float z = bits_to_float(0x4c25e800u - float_to_bits(b) / 5u);
	for (int i = 0; i < 3; i++) {
		float z2 = z * z;
		z = z * (1.2f - 0.2f * b * (z2 * z2 * z));
	}
	float hi = (b * b * b) * (z * z * z);
	return select_f(v <= 0.04045f, v * (1.0f / 12.92f), hi);
}

#endif
