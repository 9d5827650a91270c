/* png.c — PNG frames through libpng directly (imageio.h routes every PNG here).
 *
 * Why not OpenImageIO for PNG: its reader (2.4) leaves libpng's default error handler in place, which prints
 * "libpng error: ..." lines to stderr beside our one-line message; it premultiplies RGBA PNGs by their alpha
 * (associated alpha is its convention), so an RGBA frame compared or encoded as RGB had other colours; and its
 * writer loses write errors on a full disk (a truncated PNG was renamed into place). Here libpng's errors and
 * warnings come back to us as one line, colours are read as stored (alpha is dropped, never multiplied in), and
 * the file is written through the atomic-write helper's stream, whose every write, flush and fsync is checked.
 */
#include "taslab/imageio.h"

#include <errno.h>
#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "imageio_internal.h"
#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"

#define PNG_MAX_SIDE 16384 /* the largest frame taslab makes (--size) */

typedef struct png_msg {
	char text[256];
} png_msg;

static void on_error(png_structp png, png_const_charp msg)
{
	png_msg *m = png_get_error_ptr(png);
	/* libpng's stdio I/O says only "Write Error" / "Read Error": the system's reason is in errno. */
	int e = errno;
	if (e && (!strcmp(msg, "Write Error") || !strcmp(msg, "Read Error")))
		snprintf(m->text, sizeof m->text, "%s", strerror(e));
	else
		snprintf(m->text, sizeof m->text, "%s", msg);
	png_longjmp(png, 1);
}

/* Warnings (an unusual ancillary chunk, a known-bad sRGB profile) do not change the pixels: not shown. */
static void on_warning(png_structp png, png_const_charp msg)
{
	(void)png;
	(void)msg;
}

bool imageio_is_png(const uint8_t *data, size_t size)
{
	return size >= 8 && png_sig_cmp(data, 0, 8) == 0;
}

/* The file's bytes, already read into memory by imageio.c (a regular file, bounded): libpng reads from here. */
typedef struct png_src {
	const uint8_t *data;
	size_t size, pos;
	bool truncated;
} png_src;

static void read_mem(png_structp png, png_bytep out, size_t n)
{
	png_src *src = png_get_io_ptr(png);
	if (n > src->size - src->pos) {
		src->truncated = true;
		png_error(png, "truncated");
	}
	memcpy(out, src->data + src->pos, n);
	src->pos += n;
}

int imageio_png_read_rgb8(const char *path, const uint8_t *data, size_t size, uint32_t *width, uint32_t *height,
			  uint8_t **rgb, char *err, size_t err_size)
{
	*rgb = NULL;
	png_src src = {data, size, 0, false};
	png_msg msg = {"unknown error"};
	png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &msg, on_error, on_warning);
	png_infop info = png ? png_create_info_struct(png) : NULL;
	if (!info) {
		png_destroy_read_struct(&png, NULL, NULL);
		return tl_error(err, err_size, TL_ERR_NOMEM, "%s: out of memory", path);
	}
	uint8_t *volatile out = NULL;
	png_bytep *volatile rows = NULL;
	if (setjmp(png_jmpbuf(png))) {
		free(out);
		free(rows);
		png_destroy_read_struct(&png, &info, NULL);
		if (src.truncated)
			return tl_error(err, err_size, TL_ERR_INPUT, "%s: the file ends before its image does (truncated PNG); write it "
					"again", path);
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: cannot decode image: %s (corrupt PNG?)", path, msg.text);
	}
	png_set_user_limits(png, PNG_MAX_SIDE, PNG_MAX_SIDE);
	png_set_read_fn(png, &src, read_mem);
	errno = 0;
	png_read_info(png, info);
	png_uint_32 w, h;
	int depth, type;
	png_get_IHDR(png, info, &w, &h, &depth, &type, NULL, NULL, NULL);
	/* To 8-bit RGB as stored: 16-bit rounded to 8, palettes and grey expanded, alpha dropped (not multiplied in),
	 * a tRNS colour key ignored. No gamma or colour-chunk conversion: frames are display-referred code values. */
	if (depth == 16)
		png_set_scale_16(png);
	if (type == PNG_COLOR_TYPE_PALETTE)
		png_set_palette_to_rgb(png);
	if ((type == PNG_COLOR_TYPE_GRAY || type == PNG_COLOR_TYPE_GRAY_ALPHA) && depth < 8)
		png_set_expand_gray_1_2_4_to_8(png);
	if (type == PNG_COLOR_TYPE_GRAY || type == PNG_COLOR_TYPE_GRAY_ALPHA)
		png_set_gray_to_rgb(png);
	if (type & PNG_COLOR_MASK_ALPHA)
		png_set_strip_alpha(png);
	png_set_interlace_handling(png);
	png_read_update_info(png, info);
	if (png_get_rowbytes(png, info) != (size_t)w * 3)
		png_error(png, "unexpected pixel layout after conversion to 8-bit RGB");
	out = malloc((size_t)w * h * 3);
	rows = malloc((size_t)h * sizeof *rows);
	if (!out || !rows)
		png_error(png, "out of memory");
	for (png_uint_32 y = 0; y < h; y++)
		rows[y] = out + (size_t)y * w * 3;
	png_read_image(png, rows);
	png_read_end(png, NULL);
	free(rows);
	png_destroy_read_struct(&png, &info, NULL);
	*width = w;
	*height = h;
	*rgb = out;
	return TL_OK;
}

/* PNG data into `f`; a libpng failure is one line naming `path`. */
static int png_write_stream(FILE *f, const char *path, uint32_t width, uint32_t height, const uint8_t *pixels,
			    size_t stride, char *err, size_t err_size)
{
	if (width < 1 || height < 1 || width > PNG_MAX_SIDE || height > PNG_MAX_SIDE)
		return tl_error(err, err_size, TL_ERR_ARG, "%s: cannot write a %ux%u image", path, width, height);
	png_msg msg = {"unknown error"};
	png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &msg, on_error, on_warning);
	png_infop info = png ? png_create_info_struct(png) : NULL;
	if (!info) {
		png_destroy_write_struct(&png, NULL);
		return tl_error(err, err_size, TL_ERR_NOMEM, "%s: out of memory", path);
	}
	uint8_t *volatile row = NULL;
	if (setjmp(png_jmpbuf(png))) {
		free(row);
		png_destroy_write_struct(&png, &info);
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write: %s", path, msg.text);
	}
	png_init_io(png, f);
	errno = 0;
	png_set_IHDR(png, info, width, height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
		     PNG_FILTER_TYPE_DEFAULT);
	png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_ABSOLUTE);
	png_write_info(png, info);
	if (stride != 3 && !(row = malloc((size_t)width * 3)))
		png_error(png, "out of memory");
	for (uint32_t y = 0; y < height; y++) {
		const uint8_t *src = pixels + (size_t)y * width * stride;
		if (row) {
			for (uint32_t x = 0; x < width; x++)
				memcpy(row + (size_t)x * 3, src + (size_t)x * stride, 3);
			png_write_row(png, row);
		} else {
			png_write_row(png, (png_const_bytep)src);
		}
	}
	png_write_end(png, info);
	free(row);
	png_destroy_write_struct(&png, &info);
	return TL_OK;
}

int imageio_write_png_stream(FILE *f, const char *path, uint32_t width, uint32_t height, const uint8_t *rgb, char *err,
			     size_t err_size)
{
	return png_write_stream(f, path, width, height, rgb, 3, err, err_size);
}

int imageio_png_write_rgb8(const char *path, uint32_t width, uint32_t height, const uint8_t *pixels, size_t stride,
			   char *err, size_t err_size)
{
	tl_atomic a;
	int rc = tl_atomic_open(&a, path, err, err_size);
	if (rc)
		return rc;
	if ((rc = png_write_stream(a.f, path, width, height, pixels, stride, err, err_size))) {
		tl_atomic_abort(&a);
		return rc;
	}
	/* libpng checks each fwrite; the flush and the fsync are checked here (tl_atomic_commit), so a full disk is
	 * reported and nothing is renamed into place. */
	return tl_atomic_commit(&a, err, err_size);
}
