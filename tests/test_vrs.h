/* tests/test_vrs.h — shared by test_vrs.c and test_vrs_checks.c: the rate code a VRS tile stores and the CPU
 * count of the samples a compacted VRS frame shades (BASELINES.md B3). */
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* a tile's rate as the rate pass stores it: width in bits 0-7, height in bits 8-15 */
#define RATE(w, h) ((uint32_t)(w) | (uint32_t)(h) << 8)

/* One shading per coarse pixel per primitive (BASELINES.md A7): the samples of a frame are its distinct
 * (coarse pixel, object, triangle) triples, counted at the first pixel (raster order) of the coarse pixel with that
 * (object, triangle). ids: the ids pass's RGBA32UI image (object + 1, triangle, ...), rates: one code per 16x16 tile. */
static inline int64_t tu_vrs_cpu_samples(const uint32_t *ids, const uint32_t *rates, int W, int H)
{
	int tx = (W + 15) / 16;
	int64_t n = 0;
	for (int y = 0; y < H; y++)
		for (int x = 0; x < W; x++) {
			const uint32_t *id = ids + 4 * ((size_t)y * W + x);
			if (!id[0])
				continue;
			uint32_t code = rates[(y / 16) * tx + x / 16];
			int rw = (int)(code & 0xFF), rh = (int)(code >> 8 & 0xFF), ox = x - x % rw, oy = y - y % rh;
			bool first = true;
			for (int yy = oy; yy <= y && first; yy++)
				for (int xx = ox; xx < ox + rw && first; xx++) {
					if (yy == y && xx >= x)
						break;
					const uint32_t *o = ids + 4 * ((size_t)yy * W + xx);
					if (xx < W && o[0] == id[0] && o[1] == id[1])
						first = false;
				}
			n += first;
		}
	return n;
}
