/* imageio.h — image files: EXR and others through OpenImageIO (C shim over the C++ API), PNG through libpng.
 *
 * Writers are atomic: the file is written under a temporary name in the same folder and renamed
 * into place, so an interrupted run never leaves a truncated image under the final name; PNG writes
 * are checked to the last byte (a full disk is an error, not a truncated file).
 * Readers give colours as stored: an image with alpha is never premultiplied (alpha is dropped by the
 * 8-bit reader), grey is copied to R, G and B. Errors: negative return and a one-line message in `err`,
 * nothing printed by the decoder library.
 */
#ifndef TASLAB_IMAGEIO_H
#define TASLAB_IMAGEIO_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "taslab/tl_error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Which decoder may read a file (issue 31.6). Readers read only regular files of at most IMAGEIO_MAX_FILE_B bytes,
 * into memory first (a device such as /dev/zero, a FIFO or a folder is refused with one line, never probed), and
 * decode from there; a run's frames are read with the format its manifest names (PNG frames/NNNNNN.png, EXR
 * frames/NNNNNN.exr), so no other decoder is tried on them. */
typedef enum imageio_format {
	IMAGEIO_FORMAT_ANY = 0, /* PNG by its signature, else OpenImageIO by the file name's extension */
	IMAGEIO_FORMAT_PNG,     /* libpng only; anything else is "not a PNG file" */
	IMAGEIO_FORMAT_EXR,     /* OpenImageIO's OpenEXR reader only */
	IMAGEIO_FORMAT_COUNT
} imageio_format;
#define IMAGEIO_MAX_FILE_B (4ull << 30)

typedef struct imageio_attr {
	const char *name;  /* e.g. "taslab:scene" */
	const char *value;
} imageio_attr;

/* Scene-linear RGBA half-float EXR (ZIP compression) with string attributes. */
int imageio_write_exr_half(const char *path, uint32_t width, uint32_t height, const uint16_t *rgba_half,
			   const imageio_attr *attrs, size_t attr_count, char *err, size_t err_size);
/* 8-bit RGB PNG from RGBA8 pixels (alpha dropped: display frames are opaque). */
int imageio_write_png_rgb8(const char *path, uint32_t width, uint32_t height, const uint8_t *rgba8, char *err,
			   size_t err_size);
/* Reads a PNG, or any image OpenImageIO can read, as 8-bit RGB; *rgb is malloc'ed (caller frees). */
int imageio_read_rgb8(const char *path, uint32_t *width, uint32_t *height, uint8_t **rgb, char *err, size_t err_size);
/* Reads an image as float RGBA (missing channels: RGB from the first channel, alpha 1; a PNG as code values
 * / 255); *rgba is malloc'ed.
 * Fails with a message naming the first non-finite pixel when `reject_nonfinite` is set. */
int imageio_read_rgba_float(const char *path, uint32_t *width, uint32_t *height, float **rgba, int reject_nonfinite,
			    char *err, size_t err_size);
/* The same two readers for a file whose format the caller knows (a run's frames: the format from its manifest). */
int imageio_read_rgb8_as(const char *path, imageio_format format, uint32_t *width, uint32_t *height, uint8_t **rgb,
			 char *err, size_t err_size);
int imageio_read_rgba_float_as(const char *path, imageio_format format, uint32_t *width, uint32_t *height, float **rgba,
			       int reject_nonfinite, char *err, size_t err_size);
/* 8-bit RGB PNG from RGB8 pixels. */
int imageio_write_png_rgb8_packed(const char *path, uint32_t width, uint32_t height, const uint8_t *rgb, char *err,
				  size_t err_size);
/* The same PNG into an open stream (e.g. a tl_atomic's, for files committed as a set); `path` names it in
 * messages. The caller checks the stream's flush and close (tl_atomic_detach / commit). */
int imageio_write_png_stream(FILE *f, const char *path, uint32_t width, uint32_t height, const uint8_t *rgb, char *err,
			     size_t err_size);
/* Reads a string attribute of an image's header into `value` (empty if absent). */
int imageio_read_attr(const char *path, const char *name, char *value, size_t value_size, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
