/* imageio_oiio.h (private) — the OpenImageIO half of imageio.h, built as a loadable module (taslab_oiio.so,
 * oiio_module.cpp) that imageio.c opens on first use.
 *
 * Why a module: OpenImageIO 2.4 as Debian builds it pulls in ~260 shared libraries whose loading and symbol binding
 * cost ~0.2 s per process (measured: an empty program linked with it takes 0.21 s, taslab --version took 0.23 s).
 * Most commands never touch an EXR (PNG goes through libpng, png.c), so they no longer pay it. The module exports
 * one symbol of its own, IMAGEIO_OIIO_SYMBOL, a table of the functions below; the version field guards against a
 * stale module from another build. Semantics are those of the same-named imageio.h functions, except that the EXR writer
 * writes to `tmp` (the caller's atomic-write temporary, tl_fs.h) and names `path` in messages. */
#ifndef TASLAB_IMAGEIO_OIIO_H
#define TASLAB_IMAGEIO_OIIO_H

#include <stddef.h>
#include <stdint.h>

#include "taslab/imageio.h"

#ifdef __cplusplus
extern "C" {
#endif

#define IMAGEIO_OIIO_SYMBOL "taslab_oiio_api"
#define IMAGEIO_OIIO_VERSION 2
#define IMAGEIO_OIIO_FILE "taslab_oiio.so"

typedef struct imageio_oiio_api {
	int version; /* IMAGEIO_OIIO_VERSION */
	int (*write_exr_half)(const char *tmp, const char *path, uint32_t width, uint32_t height,
			      const uint16_t *rgba_half, const imageio_attr *attrs, size_t attr_count, char *err,
			      size_t err_size);
	/* Readers decode the file's bytes (data, size: read by imageio.c from a regular file) with the decoder of
	 * `format` (IMAGEIO_FORMAT_ANY: by the extension of `path`, which otherwise only names the file in messages). */
	int (*read_rgb8)(const char *path, const void *data, size_t size, int format, uint32_t *width, uint32_t *height,
			 uint8_t **rgb, char *err, size_t err_size);
	int (*read_rgba_float)(const char *path, const void *data, size_t size, int format, uint32_t *width,
			       uint32_t *height, float **rgba, int reject_nonfinite, char *err, size_t err_size);
	int (*read_attr)(const char *path, const void *data, size_t size, const char *name, char *value, size_t value_size,
			 char *err, size_t err_size);
} imageio_oiio_api;

#ifdef __cplusplus
}
#endif
#endif
