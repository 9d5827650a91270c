// oiio_module.cpp — the OpenImageIO half of imageio.h as a loadable module (taslab_oiio.so; imageio_oiio.h says
// why): EXR writing and reading of every format but PNG (png.c), as a thin shim over the C++ API.
#include "imageio_oiio.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include "taslab/tl_error.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

using namespace OIIO;

// OpenImageIO error strings can span lines (one per failing layer); keep the first line.
static std::string first_line(std::string e)
{
	size_t nl = e.find('\n');
	if (nl != std::string::npos)
		e.resize(nl);
	return e.empty() ? std::string("unknown error") : e;
}

// Written by file name to `tmp`, the caller's atomic-write temporary, which the caller commits only on success.
static int write_exr_half(const char *tmp, const char *path, uint32_t width, uint32_t height, const uint16_t *rgba_half,
			  const imageio_attr *attrs, size_t attr_count, char *err, size_t err_size)
{
	ImageSpec spec((int)width, (int)height, 4, TypeDesc::HALF);
	spec.channelnames = {"R", "G", "B", "A"};
	spec.alpha_channel = 3;
	spec.attribute("compression", "zip");
	spec.attribute("oiio:ColorSpace", "Linear");
	/* OIIO's EXR writer stamps the wall-clock time as DateTime unless one is given; an empty one writes none. Frames are
	 * a pure function of their inputs (DESIGN section 2), so the same frame rendered twice (a sweep resumed on a
	 * cluster, tests/test_sweep_slurm.sh) must be the same bytes. */
	spec.attribute("DateTime", "");
	for (size_t i = 0; i < attr_count; i++)
		spec.attribute(attrs[i].name, attrs[i].value);
	auto out = ImageOutput::create("openexr");
	if (!out) {
		snprintf(err, err_size, "%s: OpenImageIO has no openexr writer: %s", path, first_line(OIIO::geterror()).c_str());
		return TL_ERR_INTERNAL;
	}
	if (!out->open(tmp, spec)) {
		snprintf(err, err_size, "%s: cannot write: %s", path, first_line(out->geterror()).c_str());
		return TL_ERR_OUTPUT;
	}
	bool ok = out->write_image(TypeDesc::HALF, rgba_half);
	ok = out->close() && ok;
	if (!ok) {
		snprintf(err, err_size, "%s: write failed: %s", path, first_line(out->geterror()).c_str());
		return TL_ERR_OUTPUT;
	}
	return 0;
}

// An input reading the file's bytes in memory (imageio.c read them from a regular file, bounded): `proxy` must
// outlive it. IMAGEIO_FORMAT_EXR: OpenImageIO's OpenEXR reader only; IMAGEIO_FORMAT_ANY: the reader the extension of
// `path` names, and OpenImageIO's search of the other readers when that one cannot open it (on these bytes only).
// OpenImageIO associates (premultiplies) alpha on reading unless asked not to: colours are read as stored.
static std::unique_ptr<ImageInput> open_input(const char *path, int format, Filesystem::IOMemReader &proxy,
					      std::string &why)
{
	ImageSpec config;
	config.attribute("oiio:UnassociatedAlpha", 1);
	if (format == IMAGEIO_FORMAT_EXR) {
		auto in = ImageInput::create("openexr", false, &config, &proxy);
		ImageSpec spec;
		if (!in) {
			why = first_line(OIIO::geterror());
			return nullptr;
		}
		if (!in->supports("ioproxy") || !in->set_ioproxy(&proxy) || !in->open(path, spec, config)) {
			why = in->supports("ioproxy") ? first_line(in->geterror()) : std::string("the EXR reader cannot read from memory");
			return nullptr;
		}
		return in;
	}
	auto in = ImageInput::open(path, &config, &proxy);
	if (!in)
		why = first_line(OIIO::geterror());
	return in;
}

static int read_rgb8(const char *path, const void *data, size_t size, int format, uint32_t *width, uint32_t *height,
		     uint8_t **rgb, char *err, size_t err_size)
{
	*rgb = nullptr;
	Filesystem::IOMemReader proxy(data, size);
	std::string why;
	auto in = open_input(path, format, proxy, why);
	if (!in) {
		snprintf(err, err_size, "%s: cannot read image: %s", path, why.c_str());
		return TL_ERR_INPUT;
	}
	const ImageSpec &spec = in->spec();
	if (spec.width <= 0 || spec.height <= 0 || spec.nchannels < 1) {
		snprintf(err, err_size, "%s: image has no pixels", path);
		return TL_ERR_INPUT;
	}
	size_t n = (size_t)spec.width * spec.height;
	std::vector<uint8_t> all(n * spec.nchannels);
	if (!in->read_image(0, 0, 0, spec.nchannels, TypeDesc::UINT8, all.data())) {
		snprintf(err, err_size, "%s: cannot decode image: %s", path, first_line(in->geterror()).c_str());
		return TL_ERR_INPUT;
	}
	uint8_t *out = (uint8_t *)malloc(n * 3);
	if (!out) {
		snprintf(err, err_size, "%s: out of memory", path);
		return TL_ERR_NOMEM;
	}
	// One or two channels (grey, grey + alpha): grey in R, G and B; otherwise the first three.
	for (size_t i = 0; i < n; i++)
		for (int c = 0; c < 3; c++)
			out[i * 3 + c] = all[i * spec.nchannels + (spec.nchannels >= 3 ? c : 0)];
	*width = (uint32_t)spec.width;
	*height = (uint32_t)spec.height;
	*rgb = out;
	return 0;
}

static int read_rgba_float(const char *path, const void *data, size_t size, int format, uint32_t *width,
			   uint32_t *height, float **rgba, int reject_nonfinite, char *err, size_t err_size)
{
	*rgba = nullptr;
	Filesystem::IOMemReader proxy(data, size);
	std::string why;
	auto in = open_input(path, format, proxy, why);
	if (!in) {
		snprintf(err, err_size, "%s: cannot read image: %s", path, why.c_str());
		return TL_ERR_INPUT;
	}
	const ImageSpec &spec = in->spec();
	int nc = spec.nchannels;
	if (spec.width <= 0 || spec.height <= 0 || nc < 1) {
		snprintf(err, err_size, "%s: image has no pixels", path);
		return TL_ERR_INPUT;
	}
	size_t n = (size_t)spec.width * spec.height;
	std::vector<float> all(n * nc);
	if (!in->read_image(0, 0, 0, nc, TypeDesc::FLOAT, all.data())) {
		snprintf(err, err_size, "%s: cannot decode image (truncated or corrupt?): %s", path,
			 first_line(in->geterror()).c_str());
		return TL_ERR_INPUT;
	}
	float *out = (float *)malloc(n * 4 * sizeof(float));
	if (!out) {
		snprintf(err, err_size, "%s: out of memory", path);
		return TL_ERR_NOMEM;
	}
	for (size_t i = 0; i < n; i++) {
		for (int c = 0; c < 4; c++) // grey (+ alpha): grey in R, G and B
			out[i * 4 + c] = c < 3 ? all[i * nc + (nc >= 3 ? c : 0)]
				       : nc == 2 || nc >= 4 ? all[i * nc + (nc == 2 ? 1 : 3)] : 1.0f;
		if (reject_nonfinite)
			for (int c = 0; c < 4; c++)
				if (!std::isfinite(out[i * 4 + c])) {
					snprintf(err, err_size, "%s: non-finite value (NaN or Inf) at pixel (%zu, %zu)", path,
						 i % spec.width, i / spec.width);
					free(out);
					return TL_ERR_INPUT;
				}
	}
	*width = (uint32_t)spec.width;
	*height = (uint32_t)spec.height;
	*rgba = out;
	return 0;
}

static int read_attr(const char *path, const void *data, size_t size, const char *name, char *value, size_t value_size,
		     char *err, size_t err_size)
{
	Filesystem::IOMemReader proxy(data, size);
	std::string why;
	auto in = open_input(path, IMAGEIO_FORMAT_ANY, proxy, why);
	if (!in) {
		snprintf(err, err_size, "%s: cannot read image: %s", path, why.c_str());
		return TL_ERR_INPUT;
	}
	std::string v = in->spec().get_string_attribute(name);
	snprintf(value, value_size, "%s", v.c_str());
	return 0;
}

// The module's one exported symbol (imageio_oiio.h).
extern "C" __attribute__((visibility("default"))) const imageio_oiio_api taslab_oiio_api = {
    IMAGEIO_OIIO_VERSION, write_exr_half, read_rgb8, read_rgba_float, read_attr,
};
