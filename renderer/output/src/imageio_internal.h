/* imageio_internal.h (private) — the PNG codec behind imageio.h (png.c, libpng). */
#ifndef TASLAB_IMAGEIO_INTERNAL_H
#define TASLAB_IMAGEIO_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* True when the bytes start with the PNG signature. */
bool imageio_is_png(const uint8_t *data, size_t size);
/* 8-bit RGB as stored (16-bit rounded, palette and grey expanded, alpha dropped, never multiplied in), decoded from
 * the file's bytes in memory; `path` names it in messages. */
int imageio_png_read_rgb8(const char *path, const uint8_t *data, size_t size, uint32_t *width, uint32_t *height,
			  uint8_t **rgb, char *err, size_t err_size);
/* 8-bit RGB PNG from pixels `stride` bytes apart (3: RGB, 4: RGBA with alpha dropped), atomically (tl_fs.h). */
int imageio_png_write_rgb8(const char *path, uint32_t width, uint32_t height, const uint8_t *pixels, size_t stride,
			   char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
