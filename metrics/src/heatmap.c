/* heatmap.c — difference maps as images: a perceptually ordered colour map and a legend (see metrics.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/imageio.h"
#include "taslab/metrics.h"
#include "taslab/tl_error.h"

#define MTR_PI 3.14159265358979323846

static double srgb_encode(double l)
{
	l = l < 0 ? 0 : (l > 1 ? 1 : l);
	return l <= 0.0031308 ? 12.92 * l : 1.055 * pow(l, 1.0 / 2.4) - 0.055;
}

void mtr_colormap(double u, uint8_t rgb[3])
{
	u = u < 0 ? 0 : (u > 1 ? 1 : u);
	/* Oklab (Ottosson 2020) ramp: L linear in u; hue 285 deg (blue-violet) -> 100 deg (yellow) through teal
	 * and green; chroma dips mid-way so the ramp stays inside the sRGB gamut. */
	double L = 0.27 + 0.66 * u;
	double hue = (285.0 - 185.0 * u) * MTR_PI / 180.0;
	double C = 0.13 - 0.06 * sin(MTR_PI * u) + 0.05 * u * u;
	double a = C * cos(hue), b = C * sin(hue);
	double l_ = L + 0.3963377774 * a + 0.2158037573 * b;
	double m_ = L - 0.1055613458 * a - 0.0638541728 * b;
	double s_ = L - 0.0894841775 * a - 1.2914855480 * b;
	double l = l_ * l_ * l_, m = m_ * m_ * m_, s = s_ * s_ * s_;
	double r = +4.0767416621 * l - 3.3077115913 * m + 0.2309699292 * s;
	double g = -1.2684380046 * l + 2.6097574011 * m - 0.3413193965 * s;
	double bl = -0.0041960863 * l - 0.7034186147 * m + 1.7076147010 * s;
	rgb[0] = (uint8_t)lrint(255.0 * srgb_encode(r));
	rgb[1] = (uint8_t)lrint(255.0 * srgb_encode(g));
	rgb[2] = (uint8_t)lrint(255.0 * srgb_encode(bl));
}

/* 3x5 digit glyphs for legend labels, one row of 3 bits per line (our own minimal font). */
static const uint8_t GLYPH[12][5] = {
	{7, 5, 5, 5, 7}, {2, 6, 2, 2, 7}, {7, 1, 7, 4, 7}, {7, 1, 7, 1, 7}, {5, 5, 7, 1, 1}, {7, 4, 7, 1, 7},
	{7, 4, 7, 5, 7}, {7, 1, 1, 1, 1}, {7, 5, 7, 5, 7}, {7, 5, 7, 1, 7}, {0, 0, 0, 0, 2}, {0, 0, 7, 0, 0},
};

static void draw_text(uint8_t *img, uint32_t w, uint32_t h, uint32_t x, uint32_t y, const char *s, int scale)
{
	for (; *s; s++, x += 4 * scale) {
		int gi = *s >= '0' && *s <= '9' ? *s - '0' : *s == '.' ? 10 : *s == '-' ? 11 : -1;
		if (gi < 0)
			continue;
		for (int r = 0; r < 5; r++)
			for (int c = 0; c < 3; c++)
				if (GLYPH[gi][r] & (4 >> c))
					for (int dy = 0; dy < scale; dy++)
						for (int dx = 0; dx < scale; dx++) {
							uint32_t px = x + c * scale + dx, py = y + r * scale + dy;
							if (px < w && py < h)
								memset(img + ((size_t)py * w + px) * 3, 255, 3);
						}
	}
}

int mtr_heatmap_write(const char *path, const float *map, uint32_t width, uint32_t height, double vmax, char *err,
		      size_t err_size)
{
	int scale = width >= 640 ? 2 : 1;
	uint32_t bar = 10 * scale, pad = 4 * scale, text = 5 * scale;
	uint32_t H = height + pad + bar + pad + text + pad;
	uint8_t *img = calloc((size_t)width * H, 3);
	if (!img)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	if (!(vmax > 0))
		vmax = 1;
	/* The colour map through a table of 4096 steps (finer than 8-bit output can show): mtr_colormap per pixel
	 * costs three pow() and the Oklab maths, which made heatmaps slower than the metrics. */
	enum { STEPS = 4096 };
	uint8_t lut[STEPS][3];
	for (int k = 0; k < STEPS; k++)
		mtr_colormap((double)k / (STEPS - 1), lut[k]);
	const float lut_scale = (float)((STEPS - 1) / vmax);
	for (size_t i = 0; i < (size_t)width * height; i++) {
		float u = map[i] * lut_scale + 0.5f;
		int k = u > 0.0f ? (u < (float)(STEPS - 1) ? (int)u : STEPS - 1) : 0; /* also maps NaN to 0 */
		memcpy(img + i * 3, lut[k], 3);
	}
	for (uint32_t y = height + pad; y < height + pad + bar; y++)
		for (uint32_t x = 0; x < width; x++)
			mtr_colormap((double)x / (width > 1 ? width - 1 : 1), img + ((size_t)y * width + x) * 3);
	char lab[32];
	uint32_t ty = height + pad + bar + pad;
	draw_text(img, width, H, 1, ty, "0", scale);
	snprintf(lab, sizeof lab, "%g", vmax / 2);
	draw_text(img, width, H, width / 2 - (uint32_t)strlen(lab) * 2 * scale, ty, lab, scale);
	snprintf(lab, sizeof lab, "%g", vmax);
	uint32_t tw = (uint32_t)strlen(lab) * 4 * scale;
	draw_text(img, width, H, width > tw ? width - tw : 0, ty, lab, scale);
	int rc = imageio_write_png_rgb8_packed(path, width, H, img, err, err_size);
	free(img);
	return rc;
}
