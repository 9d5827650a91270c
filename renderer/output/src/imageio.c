/* imageio.c — image files (imageio.h): PNG through libpng (png.c) in-process; EXR and every other format through
 * OpenImageIO in the module taslab_oiio.so (oiio_module.cpp), opened on the first call that needs it, so that the
 * commands that never meet an EXR do not pay OpenImageIO's ~0.2 s of library loading (imageio_oiio.h).
 *
 * The module is looked for, in order: $TASLAB_OIIO_MODULE (a file path; then only there — a bare name without a '/'
 * is searched on the library path, as dlopen does), next to the running executable, and in the build folder it was
 * built into (TASLAB_MODULE_DIR, for tests and tools built elsewhere in the tree). When none loads, the message
 * gives the first real loading error, else says where it looked. */
#define _GNU_SOURCE
#include "taslab/imageio.h"

#include <dlfcn.h>
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "imageio_internal.h"
#include "imageio_oiio.h"
#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"

#ifndef TASLAB_MODULE_DIR
#define TASLAB_MODULE_DIR "."
#endif

static pthread_once_t oiio_once = PTHREAD_ONCE_INIT;
static const imageio_oiio_api *oiio_api;
static char oiio_why[512]; /* why loading failed (when oiio_api is NULL) */

static const imageio_oiio_api *try_open(const char *file, char *why, size_t why_size)
{
	void *h = dlopen(file, RTLD_NOW | RTLD_LOCAL);
	if (!h) {
		const char *e = dlerror();
		snprintf(why, why_size, "%s", e ? e : file);
		return NULL;
	}
	const imageio_oiio_api *api = (const imageio_oiio_api *)dlsym(h, IMAGEIO_OIIO_SYMBOL);
	if (!api || api->version != IMAGEIO_OIIO_VERSION) {
		snprintf(why, why_size, "%s: not a taslab OpenImageIO module of this build (version %d, expected %d)", file,
			 api ? api->version : -1, IMAGEIO_OIIO_VERSION);
		dlclose(h);
		return NULL;
	}
	return api; /* kept open for the life of the process */
}

static void oiio_load(void)
{
	const char *env = getenv("TASLAB_OIIO_MODULE");
	if (env && *env) {
		oiio_api = try_open(env, oiio_why, sizeof oiio_why);
		return;
	}
	char path[PATH_MAX + sizeof IMAGEIO_OIIO_FILE + 1];
	char exe[PATH_MAX];
	ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
	if (n > 0) {
		exe[n] = '\0';
		char *slash = strrchr(exe, '/');
		if (slash) {
			*slash = '\0';
			snprintf(path, sizeof path, "%s/%s", exe, IMAGEIO_OIIO_FILE);
			if (access(path, F_OK) == 0 && (oiio_api = try_open(path, oiio_why, sizeof oiio_why)))
				return;
		}
	}
	snprintf(path, sizeof path, "%s/%s", TASLAB_MODULE_DIR, IMAGEIO_OIIO_FILE);
	if (access(path, F_OK) != 0) {
		if (!oiio_why[0]) /* else keep why the module next to the executable would not load */
			snprintf(oiio_why, sizeof oiio_why, "%s not found next to the executable or in %s",
				 IMAGEIO_OIIO_FILE, TASLAB_MODULE_DIR);
		return;
	}
	oiio_api = try_open(path, oiio_why, sizeof oiio_why);
}

/* The module, or NULL with a one-line message naming the file that needed it. */
static const imageio_oiio_api *oiio(const char *path, char *err, size_t err_size)
{
	pthread_once(&oiio_once, oiio_load);
	if (!oiio_api)
		tl_error(err, err_size, TL_ERR_UNSUPPORTED,
			 "%s: EXR and non-PNG images need OpenImageIO, whose module could not be loaded (%s): rebuild "
			 "(scripts/setup) or set TASLAB_OIIO_MODULE to taslab_oiio.so",
			 path, oiio_why);
	return oiio_api;
}

int imageio_write_exr_half(const char *path, uint32_t width, uint32_t height, const uint16_t *rgba_half,
			   const imageio_attr *attrs, size_t attr_count, char *err, size_t err_size)
{
	const imageio_oiio_api *api = oiio(path, err, err_size);
	if (!api)
		return TL_ERR_UNSUPPORTED;
	/* Written by file name to the atomic-write helper's temporary file, which is fsync'ed and renamed into place
	 * only when OpenImageIO reports success for the pixels and for closing (tl_fs.h). */
	tl_atomic a;
	int rc = tl_atomic_open(&a, path, err, err_size);
	if (rc || (rc = tl_atomic_detach(&a, err, err_size)))
		return rc;
	rc = api->write_exr_half(a.tmp, path, width, height, rgba_half, attrs, attr_count, err, err_size);
	if (rc) {
		tl_atomic_abort(&a);
		return rc;
	}
	return tl_atomic_commit(&a, err, err_size);
}

int imageio_write_png_rgb8(const char *path, uint32_t width, uint32_t height, const uint8_t *rgba8, char *err,
			   size_t err_size)
{
	return imageio_png_write_rgb8(path, width, height, rgba8, 4, err, err_size);
}

int imageio_write_png_rgb8_packed(const char *path, uint32_t width, uint32_t height, const uint8_t *rgb, char *err,
				  size_t err_size)
{
	return imageio_png_write_rgb8(path, width, height, rgb, 3, err, err_size);
}

/* The whole file in memory: a regular file of at most IMAGEIO_MAX_FILE_B bytes (tl_read_file: a device such as
 * /dev/zero, which OpenImageIO's format probing read for ever, or a FIFO is refused at once). Decoders read these
 * bytes, never the path again (nothing to swap in between). */
static int load(const char *path, imageio_format format, uint8_t **data, size_t *size, char *err, size_t err_size)
{
	*data = NULL;
	if ((unsigned)format >= IMAGEIO_FORMAT_COUNT)
		return tl_error(err, err_size, TL_ERR_ARG, "%s: unknown image format %d", path, (int)format);
	char *d = NULL;
	int rc = tl_read_file(path, (size_t)IMAGEIO_MAX_FILE_B, &d, size, err, err_size);
	if (rc)
		return rc;
	*data = (uint8_t *)d;
	if (format == IMAGEIO_FORMAT_PNG && !imageio_is_png(*data, *size)) {
		free(d);
		*data = NULL;
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: not a PNG file (no PNG signature); write the frame again", path);
	}
	return TL_OK;
}

int imageio_read_rgb8_as(const char *path, imageio_format format, uint32_t *width, uint32_t *height, uint8_t **rgb,
			 char *err, size_t err_size)
{
	*rgb = NULL;
	uint8_t *data;
	size_t size;
	int rc = load(path, format, &data, &size, err, err_size);
	if (rc)
		return rc;
	if (format == IMAGEIO_FORMAT_PNG || (format == IMAGEIO_FORMAT_ANY && imageio_is_png(data, size))) {
		rc = imageio_png_read_rgb8(path, data, size, width, height, rgb, err, err_size);
	} else {
		const imageio_oiio_api *api = oiio(path, err, err_size);
		rc = api ? api->read_rgb8(path, data, size, (int)format, width, height, rgb, err, err_size) : TL_ERR_UNSUPPORTED;
	}
	free(data);
	return rc;
}

int imageio_read_rgb8(const char *path, uint32_t *width, uint32_t *height, uint8_t **rgb, char *err, size_t err_size)
{
	return imageio_read_rgb8_as(path, IMAGEIO_FORMAT_ANY, width, height, rgb, err, err_size);
}

int imageio_read_rgba_float_as(const char *path, imageio_format format, uint32_t *width, uint32_t *height, float **rgba,
			       int reject_nonfinite, char *err, size_t err_size)
{
	*rgba = NULL;
	uint8_t *data;
	size_t size;
	int rc = load(path, format, &data, &size, err, err_size);
	if (rc)
		return rc;
	if (format != IMAGEIO_FORMAT_PNG && !(format == IMAGEIO_FORMAT_ANY && imageio_is_png(data, size))) {
		const imageio_oiio_api *api = oiio(path, err, err_size);
		rc = api ? api->read_rgba_float(path, data, size, (int)format, width, height, rgba, reject_nonfinite, err, err_size)
			 : TL_ERR_UNSUPPORTED;
		free(data);
		return rc;
	}
	/* A PNG: code values / 255, alpha 1. */
	uint8_t *px = NULL;
	uint32_t w, h;
	rc = imageio_png_read_rgb8(path, data, size, &w, &h, &px, err, err_size);
	free(data);
	if (rc)
		return rc;
	size_t n = (size_t)w * h;
	float *out = malloc(n * 4 * sizeof(float));
	if (!out) {
		free(px);
		return tl_error(err, err_size, TL_ERR_NOMEM, "%s: out of memory", path);
	}
	for (size_t i = 0; i < n; i++) {
		for (int c = 0; c < 3; c++)
			out[i * 4 + c] = px[i * 3 + c] / 255.0f;
		out[i * 4 + 3] = 1.0f;
	}
	free(px);
	*width = w;
	*height = h;
	*rgba = out;
	return 0;
}

int imageio_read_rgba_float(const char *path, uint32_t *width, uint32_t *height, float **rgba, int reject_nonfinite,
			    char *err, size_t err_size)
{
	return imageio_read_rgba_float_as(path, IMAGEIO_FORMAT_ANY, width, height, rgba, reject_nonfinite, err, err_size);
}

int imageio_read_attr(const char *path, const char *name, char *value, size_t value_size, char *err, size_t err_size)
{
	uint8_t *data;
	size_t size;
	int rc = load(path, IMAGEIO_FORMAT_ANY, &data, &size, err, err_size);
	if (rc)
		return rc;
	const imageio_oiio_api *api = oiio(path, err, err_size);
	rc = api ? api->read_attr(path, data, size, name, value, value_size, err, err_size) : TL_ERR_UNSUPPORTED;
	free(data);
	return rc;
}
