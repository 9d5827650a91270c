// colour.cpp — OpenColorIO view transform on CPU and GPU (see colour.h).
#include "taslab/colour.h"

#include <OpenColorIO/OpenColorIO.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace OCIO = OCIO_NAMESPACE;

struct colour {
	OCIO::ConstCPUProcessorRcPtr cpu;
	std::string glsl;
	std::string name;
};

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
		return -1;
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
				return -1;
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
				return -1;
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
				return -1;
			}
			proc = cfg->getProcessor(OCIO::ROLE_SCENE_LINEAR, display, view, OCIO::TRANSFORM_DIR_FORWARD);
			c->name = std::string(path) + ": scene_linear -> " + display + " / " + view;
		}
		c->cpu = proc->getOptimizedCPUProcessor(OCIO::BIT_DEPTH_F32, OCIO::BIT_DEPTH_F32, OCIO::OPTIMIZATION_LOSSLESS);
		auto gpu = proc->getOptimizedGPUProcessor(OCIO::OPTIMIZATION_LOSSLESS);
		auto sd = OCIO::GpuShaderDesc::CreateShaderDesc();
		sd->setLanguage(OCIO::GPU_LANGUAGE_GLSL_4_0);
		sd->setFunctionName("ocio_display");
		sd->setResourcePrefix("ocio_");
		gpu->extractGpuShaderInfo(sd);
		if (sd->getNumTextures() || sd->getNum3DTextures() || sd->getNumUniforms()) {
			std::snprintf(err, err_size, "%s: this view transform needs LUT textures or dynamic uniforms on the GPU, "
						 "which taslab does not support yet; choose a view built from analytic transforms",
				      path ? path : "default");
			delete c;
			return -1;
		}
		c->glsl = sd->getShaderText();
	} catch (OCIO::Exception &e) {
		std::string msg = e.what();
		for (char &ch : msg)
			if (ch == '\n')
				ch = ' ';
		std::snprintf(err, err_size, "OpenColorIO: %s", msg.c_str());
		delete c;
		return -1;
	}
	*out = c;
	return 0;
}

extern "C" void colour_destroy(colour **c)
{
	if (!c || !*c)
		return;
	delete *c;
	*c = nullptr;
}

extern "C" const char *colour_name(const colour *c) { return c->name.c_str(); }
extern "C" const char *colour_glsl(const colour *c) { return c->glsl.c_str(); }

extern "C" void colour_apply(const colour *c, float *pixels, size_t n, int channels)
{
	OCIO::PackedImageDesc img(pixels, (long)n, 1, channels);
	c->cpu->apply(img);
}
