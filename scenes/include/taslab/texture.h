/* texture.h — CPU texture processing shared by scene loading (glTF images, procedural textures) and the
 * renderer's upload (mip chains): sRGB transfer functions, 8-bit encoding, area resampling, 2x2 mips.
 * Colour data is averaged in linear light (sRGB decoded first, re-encoded after). RGBA8, row-major,
 * tightly packed. Deterministic: the same input gives the same bytes on every machine. */
#ifndef TASLAB_TEXTURE_H
#define TASLAB_TEXTURE_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* IEC 61966-2-1 (sRGB) decoding and encoding of one channel value in [0, 1]. */
float tex_srgb_to_linear(float c);
float tex_linear_to_srgb(float l);
/* [0, 1] -> 0..255, clamped, rounded to nearest (ties to even). */
uint8_t tex_unorm8(float v);

/* Resamples a w x h image with `comp` 8-bit channels (1..4; missing colour channels repeat the first,
 * missing alpha is 255) to n x n RGBA8: area average when minifying, nearest when magnifying; colour
 * channels are averaged in linear light when `srgb`. */
void tex_resample_area(const uint8_t *src, int w, int h, int comp, uint32_t n, bool srgb, uint8_t *dst);

/* Next mip level of an n x n RGBA8 image: 2x2 box filter into (n/2) x (n/2), linear light when `srgb`. */
void tex_mip_down(const uint8_t *src, uint32_t n, uint8_t *dst, bool srgb);
/* Levels of a full mip chain of an n x n image (1 for n = 1). */
uint32_t tex_mip_count(uint32_t n);

#ifdef __cplusplus
}
#endif
#endif
