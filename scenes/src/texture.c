/* texture.c — sRGB, 8-bit encoding, area resampling and mips (texture.h): the one place textures are
 * processed on the CPU (glTF images, procedural textures, the renderer's mip chains). */
#include "taslab/texture.h"

#include <math.h>
#include <stddef.h>

float tex_srgb_to_linear(float c)
{
	return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}

float tex_linear_to_srgb(float l)
{
	return l <= 0.0031308f ? 12.92f * l : 1.055f * powf(l, 1.0f / 2.4f) - 0.055f;
}

uint8_t tex_unorm8(float v)
{
	return (uint8_t)lrintf(fminf(fmaxf(v, 0.0f), 1.0f) * 255.0f);
}

void tex_resample_area(const uint8_t *src, int w, int h, int comp, uint32_t n, bool srgb, uint8_t *dst)
{
	/* Decoded channel values per byte, computed exactly as the per-pixel expression would (so the bytes
	 * stay the same): one powf per possible byte instead of one per pixel and channel. */
	float dec[256], lin[256];
	for (int i = 0; i < 256; i++) {
		lin[i] = (float)i / 255.0f;
		dec[i] = srgb ? tex_srgb_to_linear(lin[i]) : lin[i];
	}
	/* A texel covering exactly one source pixel (every texel when magnifying) is a function of that pixel's
	 * bytes alone: its encoded value per byte, for colour (dec -> encode) and alpha (lin) channels. */
	uint8_t one_col[256], one_alpha[256];
	for (int i = 0; i < 256; i++) {
		float v = dec[i] * 1.0f;
		if (srgb)
			v = tex_linear_to_srgb(v);
		one_col[i] = (uint8_t)lroundf(fminf(fmaxf(v, 0.0f), 1.0f) * 255.0f);
		one_alpha[i] = (uint8_t)lroundf(fminf(fmaxf(lin[i] * 1.0f, 0.0f), 1.0f) * 255.0f);
	}
	const uint8_t opaque = (uint8_t)lroundf(1.0f * 255.0f);
	for (uint32_t y = 0; y < n; y++)
		for (uint32_t x = 0; x < n; x++) {
			int x0 = (int)((uint64_t)x * (uint64_t)w / n), x1 = (int)((uint64_t)(x + 1) * (uint64_t)w / n);
			int y0 = (int)((uint64_t)y * (uint64_t)h / n), y1 = (int)((uint64_t)(y + 1) * (uint64_t)h / n);
			if (x1 < x0 + 1)
				x1 = x0 + 1;
			if (y1 < y0 + 1)
				y1 = y0 + 1;
			uint8_t *out = dst + ((size_t)y * n + x) * 4;
			if (x1 == x0 + 1 && y1 == y0 + 1) {
				const uint8_t *p = src + ((size_t)y0 * (size_t)w + (size_t)x0) * (size_t)comp;
				for (int c = 0; c < 3; c++)
					out[c] = c < comp ? one_col[p[c]] : one_col[p[0]];
				out[3] = comp == 4 ? one_alpha[p[3]] : opaque;
				continue;
			}
			float acc[4] = {0, 0, 0, 0};
			for (int yy = y0; yy < y1; yy++)
				for (int xx = x0; xx < x1; xx++) {
					const uint8_t *p = src + ((size_t)yy * (size_t)w + (size_t)xx) * (size_t)comp;
					for (int c = 0; c < 3; c++)
						acc[c] += dec[c < comp ? p[c] : p[0]];
					acc[3] += comp == 4 ? lin[p[3]] : 1.0f;
				}
			float k = 1.0f / (float)((x1 - x0) * (y1 - y0));
			for (int c = 0; c < 4; c++) {
				float v = acc[c] * k;
				if (srgb && c < 3)
					v = tex_linear_to_srgb(v);
				/* Ties round away from zero here (lround), to even in tex_unorm8: kept as the loaders had
				 * them so that frames stay byte-identical; unify when the goldens are regenerated. */
				out[c] = (uint8_t)lroundf(fminf(fmaxf(v, 0.0f), 1.0f) * 255.0f);
			}
		}
}

void tex_mip_down(const uint8_t *src, uint32_t n, uint8_t *dst, bool srgb)
{
	uint32_t m = n / 2;
	for (uint32_t y = 0; y < m; y++)
		for (uint32_t x = 0; x < m; x++)
			for (int c = 0; c < 4; c++) {
				float s = 0.0f;
				for (int k = 0; k < 4; k++) {
					uint8_t v = src[(((size_t)(2 * y + (k >> 1))) * n + 2 * x + (k & 1)) * 4 + c];
					s += (srgb && c < 3) ? tex_srgb_to_linear(v / 255.0f) : v / 255.0f;
				}
				s *= 0.25f;
				dst[((size_t)y * m + x) * 4 + c] = tex_unorm8((srgb && c < 3) ? tex_linear_to_srgb(s) : s);
			}
}

uint32_t tex_mip_count(uint32_t n)
{
	uint32_t m = 1;
	while (n > 1) {
		n /= 2;
		m++;
	}
	return m;
}
