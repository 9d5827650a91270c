// colour.cpp — OpenColorIO view transform on CPU and GPU (see colour.h).
#include "taslab/colour.h"
#include "taslab/tl_error.h"

#include <OpenColorIO/OpenColorIO.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <strings.h>
#include <string>
#include <vector>

namespace OCIO = OCIO_NAMESPACE;

/* A LUT of the view (colour_lut), owning its name and values. */
struct lut_store {
	std::string sampler;
	std::vector<float> values;
	colour_lut info;
};

struct colour {
	OCIO::ConstCPUProcessorRcPtr cpu;
	std::string glsl;
	std::string name;
	std::string config; /* the config file's path; empty for the built-in default */
	int rewritten; /* B-spline curve functions restructured (restructure_glsl) */
	std::vector<lut_store> luts;
};

/* The LUT textures OCIO's GLSL samples (1D LUTs as 1D or 2D textures of one or three channels, 3D LUTs as RGB 3D
 * textures) and their filtering: nearest for INTERP_NEAREST, and for a 3D LUT's INTERP_TETRAHEDRAL (OCIO's shader
 * does the tetrahedral maths itself from reads at texel centres, where nearest and linear filtering agree), else
 * linear. The sampler's
 * type is read from its declaration in the GLSL (a one-row 1D LUT may be a sampler1D). */
static void collect_luts(const OCIO::GpuShaderDescRcPtr &sd, const std::string &glsl, std::vector<lut_store> &out)
{
	out.clear();
	for (unsigned i = 0; i < sd->getNumTextures(); i++) {
		const char *tex = nullptr, *sampler = nullptr;
		unsigned w = 0, h = 0;
		OCIO::GpuShaderDesc::TextureType channel;
		OCIO::Interpolation interp;
		sd->getTexture(i, tex, sampler, w, h, channel, interp);
		const float *v = nullptr;
		sd->getTextureValues(i, v);
		lut_store l;
		l.sampler = sampler;
		const int channels = channel == OCIO::GpuShaderDesc::TEXTURE_RED_CHANNEL ? 1 : 3;
		l.values.assign(v, v + (size_t)w * h * channels);
		const bool one_d = glsl.find("sampler1D " + l.sampler + ";") != std::string::npos;
		l.info = colour_lut{nullptr, one_d ? 1 : 2, w, h, 1, channels, interp != OCIO::INTERP_NEAREST, nullptr};
		out.push_back(std::move(l));
	}
	for (unsigned i = 0; i < sd->getNum3DTextures(); i++) {
		const char *tex = nullptr, *sampler = nullptr;
		unsigned e = 0;
		OCIO::Interpolation interp;
		sd->get3DTexture(i, tex, sampler, e, interp);
		const float *v = nullptr;
		sd->get3DTextureValues(i, v);
		lut_store l;
		l.sampler = sampler;
		l.values.assign(v, v + (size_t)e * e * e * 3);
		l.info = colour_lut{nullptr, 3, e, e, e, 3, interp != OCIO::INTERP_NEAREST && interp != OCIO::INTERP_TETRAHEDRAL,
				    nullptr};
		out.push_back(std::move(l));
	}
	for (lut_store &l : out) { /* pointers last: the vector no longer moves */
		l.info.sampler = l.sampler.c_str();
		l.info.values = l.values.data();
	}
}

/* ---- restructuring the GLSL OpenColorIO emits (issue "frame cost") ----
 * OCIO 2.1 evaluates GradingRGBCurve B-splines (the ACES RRT and ODT tone scales) in GLSL with a loop that
 * searches the knot interval and reads coefficients from constant arrays with dynamic indices. A SIMD CPU
 * driver (llvmpipe) runs such loops for every lane and turns each dynamic index into a gather: 96% of the
 * display transform's time went there (400 ns per pixel on lavapipe; 16 ns with the curves removed). The
 * rewrite below replaces each curve function by straight-line code over constant segments: every segment
 * polynomial is evaluated with the same constants and the same expressions (t = x - knot; (A*t + B)*t + C,
 * the same end extrapolations) and the one OCIO's loop would pick is selected, so the results are
 * bit-identical to OCIO's own GLSL (checked over 1M random HDR inputs: 0 of 3M floats differ) at 20 ns per
 * pixel. If the emitted text does not have the expected shape (another OCIO version), it is kept as it is. */
/* The items of `const int|float NAME[N] = int|float[N](a, b, ...);` in src (no std::regex: GCC 12's <regex>
 * trips -Wmaybe-uninitialized under AddressSanitizer). */
static bool parse_list(const std::string &src, const std::string &name, std::vector<std::string> &out)
{
	size_t at = std::string::npos;
	for (const char *type : {"const int ", "const float "}) {
		size_t p = src.find(type + name + "[");
		if (p != std::string::npos)
			at = p;
	}
	if (at == std::string::npos)
		return false;
	size_t open = src.find('(', at), close = open == std::string::npos ? open : src.find(')', open);
	size_t semi = src.find(';', at);
	if (close == std::string::npos || semi < close)
		return false;
	out.clear();
	std::string list = src.substr(open + 1, close - open - 1);
	size_t pos = 0;
	for (;;) {
		size_t comma = list.find(',', pos);
		std::string item = list.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
		size_t a = item.find_first_not_of(' '), b = item.find_last_not_of(' ');
		if (a == std::string::npos)
			return false;
		out.push_back(item.substr(a, b - a + 1));
		if (comma == std::string::npos)
			return true;
		pos = comma + 1;
	}
}

static bool unroll_bspline(std::string &glsl, const std::string &n)
{
	const std::string pre = "ocio_grading_rgbcurve_";
	std::vector<std::string> ko, co, kn, cf;
	if (!parse_list(glsl, pre + "knotsOffsets_" + n, ko) || !parse_list(glsl, pre + "coefsOffsets_" + n, co) ||
	    !parse_list(glsl, pre + "knots_" + n, kn) || !parse_list(glsl, pre + "coefs_" + n, cf) || ko.size() != 8 ||
	    co.size() != 8)
		return false;
	const std::string head = "float " + pre + "evalBSplineCurve_" + n + "(in int curveIdx, in float x)\n{";
	size_t start = glsl.find(head);
	size_t end = start == std::string::npos ? start : glsl.find("\n}\n", start);
	if (end == std::string::npos)
		return false;
	std::string f = head + "\n";
	for (int c = 0; c < 4; c++) {
		int k_off = std::stoi(ko[2 * c]), k_cnt = std::stoi(ko[2 * c + 1]);
		int c_off = std::stoi(co[2 * c]), c_cnt = std::stoi(co[2 * c + 1]), sets = c_cnt / 3;
		f += "  if (curveIdx == " + std::to_string(c) + ")\n  {\n";
		if (sets == 0) {
			f += "    return x;\n  }\n";
			continue;
		}
		if (k_off < 0 || c_off < 0 || k_cnt < 2 || sets != k_cnt - 1 || (size_t)(k_off + k_cnt) > kn.size() ||
		    (size_t)(c_off + 3 * sets) > cf.size())
			return false;
		auto K = [&](int i) { return kn[(size_t)(k_off + i)]; };
		auto A = [&](int i) { return cf[(size_t)(c_off + i)]; };
		auto B = [&](int i) { return cf[(size_t)(c_off + sets + i)]; };
		auto C = [&](int i) { return cf[(size_t)(c_off + 2 * sets + i)]; };
		/* the interval OCIO's loop finds is the last i <= k_cnt - 2 with x >= knot[i] */
		f += "    float t = x - " + K(0) + ";\n    float v = ( " + A(0) + " * t + " + B(0) + " ) * t + " + C(0) + ";\n";
		for (int i = 1; i <= k_cnt - 2; i++)
			f += "    t = x - " + K(i) + ";\n    v = x >= " + K(i) + " ? ( " + A(i) + " * t + " + B(i) + " ) * t + " + C(i) +
			     " : v;\n";
		int l = sets - 1;
		f += "    float te = " + K(k_cnt - 1) + " - " + K(k_cnt - 2) + ";\n";
		f += "    v = x >= " + K(k_cnt - 1) + " ? (x - " + K(k_cnt - 1) + ") * (2. * " + A(l) + " * te + " + B(l) +
		     ") + (( " + A(l) + " * te + " + B(l) + " ) * te + " + C(l) + ") : v;\n";
		f += "    v = x <= " + K(0) + " ? (x - " + K(0) + ") * " + B(0) + " + " + C(0) + " : v;\n";
		f += "    return v;\n  }\n";
	}
	f += "  return x;\n}";
	glsl.replace(start, end + 2 - start, f);
	return true;
}

/* Rewrites every B-spline curve function of `glsl`; returns how many were rewritten. */
static int restructure_glsl(std::string &glsl)
{
	int n = 0;
	const std::string fn = "float ocio_grading_rgbcurve_evalBSplineCurve_";
	std::vector<std::string> ids;
	for (size_t p = glsl.find(fn); p != std::string::npos; p = glsl.find(fn, p + 1)) {
		size_t e = glsl.find('(', p);
		if (e != std::string::npos)
			ids.push_back(glsl.substr(p + fn.size(), e - p - fn.size()));
	}
	for (const std::string &id : ids)
		n += unroll_bspline(glsl, id);
	return n;
}

/* Issue 31.7: a LUT entry that is NaN or Inf is refused. OCIO's file readers accept "nan" and "inf" (strtod), and
 * its CPU and GPU paths then treat them differently (the CPU's lookups and the GPU's filtering propagate or clamp
 * them in different places: up to 148 code values apart on 41 % of the pixels of a test view), so no result made
 * with such a LUT could be trusted. The processor's ops as transforms (OCIO 2 Processor::createGroupTransform) are
 * the LUTs as OCIO's optimiser left them (combined and resampled, so a bad entry shows up elsewhere), before any GPU
 * baking; *what says which entry. The GPU textures are checked as well
 * (collect_luts), for values that only baking makes non-finite. */
static bool lut_values_finite(const OCIO::ConstProcessorRcPtr &proc, std::string &what)
{
	auto g = proc->createGroupTransform();
	char msg[160];
	for (int i = 0; i < g->getNumTransforms(); i++) {
		auto t = g->getTransform(i);
		if (auto l1 = OCIO::DynamicPtrCast<const OCIO::Lut1DTransform>(t)) {
			for (unsigned long k = 0; k < l1->getLength(); k++) {
				float r, gr, b;
				l1->getValue(k, r, gr, b);
				if (!std::isfinite(r) || !std::isfinite(gr) || !std::isfinite(b)) {
					std::snprintf(msg, sizeof msg, "entry %lu of a 1D LUT of %lu entries is (%g, %g, %g)", k,
						      l1->getLength(), (double)r, (double)gr, (double)b);
					what = msg;
					return false;
				}
			}
		} else if (auto l3 = OCIO::DynamicPtrCast<const OCIO::Lut3DTransform>(t)) {
			const unsigned long n = l3->getGridSize();
			for (unsigned long x = 0; x < n; x++)
				for (unsigned long y = 0; y < n; y++)
					for (unsigned long z = 0; z < n; z++) {
						float r, gr, b;
						l3->getValue(x, y, z, r, gr, b);
						if (!std::isfinite(r) || !std::isfinite(gr) || !std::isfinite(b)) {
							std::snprintf(msg, sizeof msg,
								      "entry (%lu, %lu, %lu) of a %lu^3 3D LUT is (%g, %g, %g)", x, y, z,
								      n, (double)r, (double)gr, (double)b);
							what = msg;
							return false;
						}
					}
		}
	}
	return true;
}

/* The LUT files of a transform (FileTransforms, inside groups too), each checked alone so that the message names the
 * file: the processor of a whole view has its LUTs combined by OCIO's optimiser (a NaN in a 3D LUT showed up in the
 * 1D shaper before it). *file gets the resolved path of the first file with a non-finite value. */
static bool lut_files_finite(const OCIO::ConstConfigRcPtr &cfg, const OCIO::ConstTransformRcPtr &t, std::string &file,
			     std::string &what)
{
	if (!t)
		return true;
	if (auto g = OCIO::DynamicPtrCast<const OCIO::GroupTransform>(t)) {
		for (int i = 0; i < g->getNumTransforms(); i++)
			if (!lut_files_finite(cfg, g->getTransform(i), file, what))
				return false;
		return true;
	}
	auto f = OCIO::DynamicPtrCast<const OCIO::FileTransform>(t);
	if (!f || !f->getSrc())
		return true;
	auto one = OCIO::FileTransform::Create();
	one->setSrc(f->getSrc());
	one->setInterpolation(f->getInterpolation());
	one->setCCCId(f->getCCCId());
	if (lut_values_finite(cfg->getProcessor(one), what))
		return true;
	const char *resolved = cfg->getCurrentContext()->resolveFileLocation(f->getSrc());
	file = resolved ? resolved : f->getSrc();
	return false;
}

/* Issue 31 (fuzz_lut finding): OpenColorIO 2.1's .cube reader allocates the grid a LUT_3D_SIZE / LUT_1D_SIZE line
 * declares before it reads a single entry (a 37-byte file declaring 600^3 asked for 2.6 GB), while its other readers
 * bound the size (spi3d, csp and clf grids at 129, 1D lengths at 1024x1024). OCIO tries every reader on a file whose
 * extension fails, so every LUT file is checked, whatever its name: a declared size must be within the Adobe Cube
 * LUT Specification 1.0 (3D grid 2-256, 1D 2-65536) and backed by the file (each entry line is at least "0 0 0\n",
 * 6 bytes). Returns "" or what is wrong. */
static std::string lut_declared_size_problem(const char *path)
{
	FILE *f = std::fopen(path, "rb");
	if (!f)
		return ""; /* OCIO says why it cannot read it */
	std::fseek(f, 0, SEEK_END);
	long size = std::ftell(f);
	std::rewind(f);
	char line[256];
	std::string why;
	bool at_start = true; /* this chunk begins a line (fgets splits lines longer than the buffer) */
	while (why.empty() && std::fgets(line, sizeof line, f)) {
		bool starts = at_start;
		at_start = std::strchr(line, '\n') != nullptr;
		const char *p = line + std::strspn(line, " \t");
		/* OCIO matches the keywords without regard to case (its reader lower-cases the line's first token): a
		 * fuzzed "LUT_3D_SIZe 600" was read as a 600^3 grid. The whole file: a keyword may follow the data. */
		bool three = !strncasecmp(p, "LUT_3D_SIZE", 11), one = !strncasecmp(p, "LUT_1D_SIZE", 11);
		if (!starts || (!three && !one) || !std::strchr(" \t", p[11]) || !p[11])
			continue;
		char *end;
		unsigned long long v = std::strtoull(p + 11, &end, 10);
		unsigned long long entries = three ? v * v * v : v, max = three ? 256 : 65536;
		if (end == p + 11 || v < 2 || v > max)
			why = std::string(three ? "LUT_3D_SIZE" : "LUT_1D_SIZE") + " must be 2 to " + std::to_string(max) +
			      " (Adobe Cube LUT Specification 1.0)";
		else if (size < 0 || entries * 6 > (unsigned long long)size)
			why = "declares " + std::to_string(entries) + " entries, more than its " + std::to_string(size) +
			      " bytes can hold";
	}
	std::fclose(f);
	return why;
}

/* The LUT files of a transform (FileTransforms, inside groups too) checked with lut_declared_size_problem before
 * OCIO reads any of them. *file gets the resolved path of the first bad file. */
static bool lut_files_bounded(const OCIO::ConstConfigRcPtr &cfg, const OCIO::ConstTransformRcPtr &t, std::string &file,
			      std::string &why)
{
	if (!t)
		return true;
	if (auto g = OCIO::DynamicPtrCast<const OCIO::GroupTransform>(t)) {
		for (int i = 0; i < g->getNumTransforms(); i++)
			if (!lut_files_bounded(cfg, g->getTransform(i), file, why))
				return false;
		return true;
	}
	auto f = OCIO::DynamicPtrCast<const OCIO::FileTransform>(t);
	if (!f || !f->getSrc())
		return true;
	const char *resolved = nullptr;
	try {
		resolved = cfg->getCurrentContext()->resolveFileLocation(f->getSrc());
	} catch (const OCIO::Exception &) {
		return true; /* not found: OCIO's own message says so when it builds the processor */
	}
	why = resolved ? lut_declared_size_problem(resolved) : "";
	if (why.empty())
		return true;
	file = resolved;
	return false;
}

static OCIO::ConstProcessorRcPtr default_processor(OCIO::ConstConfigRcPtr &cfg)
{
	cfg = OCIO::Config::CreateRaw();
	auto g = OCIO::GroupTransform::Create();
	// Linear Rec.709 (D65) to CIE XYZ D65 (ITU-R BT.709 primaries, as in OCIO's builtin configs).
	static const double rec709_to_xyz[16] = {0.412390799266, 0.357584339384, 0.180480788402, 0,
						 0.212639005872, 0.715168678768, 0.072192315361, 0,
						 0.019330818716, 0.119194779795, 0.950532152250, 0,
						 0, 0, 0, 1};
	auto m = OCIO::MatrixTransform::Create();
	m->setMatrix(rec709_to_xyz);
	g->appendTransform(m);
	auto to_ap0 = OCIO::BuiltinTransform::Create();
	to_ap0->setStyle("UTILITY - ACES-AP0_to_CIE-XYZ-D65_BFD");
	to_ap0->setDirection(OCIO::TRANSFORM_DIR_INVERSE);
	g->appendTransform(to_ap0);
	auto ot = OCIO::BuiltinTransform::Create();
	ot->setStyle("ACES-OUTPUT - ACES2065-1_to_CIE-XYZ-D65 - SDR-VIDEO_1.0");
	g->appendTransform(ot);
	auto disp = OCIO::BuiltinTransform::Create();
	disp->setStyle("DISPLAY - CIE-XYZ-D65_to_sRGB");
	g->appendTransform(disp);
	return cfg->getProcessor(g);
}

extern "C" int colour_create(const colour_desc *desc, colour **out, char *err, size_t err_size)
{
	*out = nullptr;
	colour *c = new (std::nothrow) colour;
	if (!c) {
		std::snprintf(err, err_size, "out of memory");
		return TL_ERR_NOMEM;
	}
	const char *path = desc->config_path;
	if (!path && !desc->ignore_env) {
		const char *env = std::getenv("OCIO");
		if (env && *env)
			path = env;
	}
	try {
		OCIO::ConstConfigRcPtr cfg;
		OCIO::ConstProcessorRcPtr proc;
		if (!path) {
			if (desc->display || desc->view) {
				std::snprintf(err, err_size, "--display/--view need an OCIO config (--ocio-config FILE or $OCIO); "
							 "the built-in default is ACES 1.0 SDR-video on sRGB");
				delete c;
				return TL_ERR_ARG;
			}
			proc = default_processor(cfg);
			c->name = std::string("ACES 1.0 SDR-video output transform -> sRGB display (OCIO ") +
				  OCIO::GetVersion() + " builtin transforms)";
		} else {
			cfg = OCIO::Config::CreateFromFile(path);
			const char *display = desc->display ? desc->display : cfg->getDefaultDisplay();
			bool found = false;
			for (int i = 0; i < cfg->getNumDisplays(); i++)
				found = found || std::string(cfg->getDisplay(i)) == display;
			if (!found) {
				std::string all;
				for (int i = 0; i < cfg->getNumDisplays(); i++)
					all += (i ? ", " : "") + std::string(cfg->getDisplay(i));
				std::snprintf(err, err_size, "%s: no display '%s' (displays: %s)", path, display, all.c_str());
				delete c;
				return TL_ERR_ARG;
			}
			const char *view = desc->view ? desc->view : cfg->getDefaultView(display);
			found = false;
			std::string views;
			for (int i = 0; i < cfg->getNumViews(display); i++) {
				found = found || std::string(cfg->getView(display, i)) == view;
				views += (i ? ", " : "") + std::string(cfg->getView(display, i));
			}
			if (!found) {
				std::snprintf(err, err_size, "%s: display '%s' has no view '%s' (views: %s)", path, display, view,
					      views.c_str());
				delete c;
				return TL_ERR_ARG;
			}
			std::string file, why;
			for (const char *cs : {cfg->getDisplayViewColorSpaceName(display, view), (const char *)OCIO::ROLE_SCENE_LINEAR}) {
				auto space = cs ? cfg->getColorSpace(cs) : nullptr;
				if (space && file.empty() &&
				    lut_files_bounded(cfg, space->getTransform(OCIO::COLORSPACE_DIR_TO_REFERENCE), file, why))
					lut_files_bounded(cfg, space->getTransform(OCIO::COLORSPACE_DIR_FROM_REFERENCE), file, why);
			}
			if (!file.empty()) {
				std::snprintf(err, err_size, "%s: %s; fix the LUT file", file.c_str(), why.c_str());
				delete c;
				return TL_ERR_INPUT;
			}
			proc = cfg->getProcessor(OCIO::ROLE_SCENE_LINEAR, display, view, OCIO::TRANSFORM_DIR_FORWARD);
			c->name = std::string(path) + ": scene_linear -> " + display + " / " + view;
			c->config = path;
		}
		std::string bad, file;
		if (path) { /* the view's colour space and scene_linear's: their LUT files by name */
			const char *display = desc->display ? desc->display : cfg->getDefaultDisplay();
			const char *view = desc->view ? desc->view : cfg->getDefaultView(display);
			for (const char *cs : {cfg->getDisplayViewColorSpaceName(display, view), (const char *)OCIO::ROLE_SCENE_LINEAR}) {
				auto space = cs ? cfg->getColorSpace(cs) : nullptr;
				if (!space || !file.empty())
					continue;
				if (!lut_files_finite(cfg, space->getTransform(OCIO::COLORSPACE_DIR_TO_REFERENCE), file, bad))
					continue;
				lut_files_finite(cfg, space->getTransform(OCIO::COLORSPACE_DIR_FROM_REFERENCE), file, bad);
			}
			if (!file.empty()) {
				/* (no entry index: OCIO's optimiser resamples even a LUT alone, so its entries are not the file's) */
				std::snprintf(err, err_size, "%s: a value of this LUT is not a finite number (NaN or Inf); fix the LUT file",
					      file.c_str());
				delete c;
				return TL_ERR_INPUT;
			}
		}
		if (!lut_values_finite(proc, bad)) {
			std::snprintf(err, err_size, "%s: %s: a LUT value is not a finite number (NaN or Inf); fix the LUT file",
				      c->name.c_str(), bad.c_str());
			delete c;
			return TL_ERR_INPUT;
		}
		c->cpu = proc->getOptimizedCPUProcessor(OCIO::BIT_DEPTH_F32, OCIO::BIT_DEPTH_F32, OCIO::OPTIMIZATION_LOSSLESS);
		auto gpu = proc->getOptimizedGPUProcessor(OCIO::OPTIMIZATION_LOSSLESS);
		auto sd = OCIO::GpuShaderDesc::CreateShaderDesc();
		sd->setLanguage(OCIO::GPU_LANGUAGE_GLSL_4_0);
		sd->setFunctionName("ocio_display");
		sd->setResourcePrefix("ocio_");
		gpu->extractGpuShaderInfo(sd);
		if (sd->getNumUniforms()) {
			std::snprintf(err, err_size, "%s: this view transform has dynamic properties (GPU uniforms), which "
						 "taslab does not support; make them static in the config",
				      path ? path : "default");
			delete c;
			return TL_ERR_UNSUPPORTED;
		}
		c->glsl = sd->getShaderText();
		collect_luts(sd, c->glsl, c->luts);
		for (const lut_store &l : c->luts)
			for (size_t i = 0; i < l.values.size(); i++)
				if (!std::isfinite(l.values[i])) {
					std::snprintf(err, err_size, "%s: value %zu of the GPU LUT %s is not a finite number (NaN or "
								 "Inf); fix the LUT files of the view",
						      c->name.c_str(), i, l.sampler.c_str());
					delete c;
					return TL_ERR_INPUT;
				}
		c->rewritten = desc->keep_ocio_glsl ? 0 : restructure_glsl(c->glsl);
	} catch (OCIO::Exception &e) {
		std::string msg = e.what();
		for (char &ch : msg)
			if (ch == '\n')
				ch = ' ';
		std::snprintf(err, err_size, "OpenColorIO: %s", msg.c_str());
		delete c;
		return TL_ERR_INPUT;
	} catch (...) { /* std::bad_alloc (a large LUT copied): nothing may leave an extern "C" function */
		std::snprintf(err, err_size, "%s: out of memory creating the view transform", path ? path : "default");
		delete c;
		return TL_ERR_NOMEM;
	}
	*out = c;
	return TL_OK;
}

extern "C" void colour_destroy(colour **c)
{
	if (!c || !*c)
		return;
	delete *c;
	*c = nullptr;
}

extern "C" const char *colour_name(const colour *c) { return c->name.c_str(); }
extern "C" const char *colour_config_path(const colour *c) { return c->config.empty() ? nullptr : c->config.c_str(); }
extern "C" const char *colour_library_version(void) { return OCIO::GetVersion(); }
extern "C" size_t colour_lut_count(const colour *c) { return c->luts.size(); }
extern "C" const colour_lut *colour_lut_get(const colour *c, size_t i)
{
	return i < c->luts.size() ? &c->luts[i].info : nullptr;
}
extern "C" const char *colour_glsl(const colour *c) { return c->glsl.c_str(); }
extern "C" int colour_glsl_rewritten(const colour *c) { return c->rewritten; }

extern "C" void colour_apply(const colour *c, float *pixels, size_t n, int channels)
{
	OCIO::PackedImageDesc img(pixels, (long)n, 1, channels);
	c->cpu->apply(img);
}
