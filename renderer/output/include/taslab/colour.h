/* colour.h — the display (view) transform through OpenColorIO, on the CPU and as GLSL for the GPU.
 *
 * T is defined on display-referred values (DESIGN section 3), so the renderer encodes inside its shaders
 * with the GLSL OpenColorIO emits for the same processor the CPU path uses (metrics, `taslab tonemap`).
 * Default (no config): ACES 1.0 SDR-video output transform to an sRGB display, built from OCIO
 * BuiltinTransforms (OCIO 2.1 in Debian 12 ships no built-in config): scene-linear Rec.709 -> CIE XYZ D65
 * (matrix) -> ACES2065-1 (inverse "UTILITY - ACES-AP0_to_CIE-XYZ-D65_BFD") -> "ACES-OUTPUT -
 * ACES2065-1_to_CIE-XYZ-D65 - SDR-VIDEO_1.0" -> "DISPLAY - CIE-XYZ-D65_to_sRGB".
 * With a config (`config_path`, else $OCIO): role scene_linear -> display/view (defaults: the config's).
 *
 * Errors: negative return, one line in `err`. Ownership: colour_create allocates, colour_destroy frees.
 */
#ifndef TASLAB_COLOUR_H
#define TASLAB_COLOUR_H

#include <stddef.h>
#include <stdint.h>

#include "taslab/tl_error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct colour colour;

typedef struct colour_desc {
	const char *config_path; /* NULL: $OCIO if set, else the built-in ACES default */
	const char *display;     /* NULL: the config's default display */
	const char *view;        /* NULL: the display's default view */
	int ignore_env;          /* do not read $OCIO (tests) */
	int keep_ocio_glsl;      /* use OCIO's GLSL as emitted, without the curve rewrite (tests compare both) */
} colour_desc;

/* The view transform of desc (issue 30.5: tl_err values). TL_OK; TL_ERR_ARG: --display/--view without a config, a
 * display or view the config does not have; TL_ERR_INPUT: a config or LUT file OpenColorIO cannot read, a LUT value
 * that is not finite, a .cube size the file does not back; TL_ERR_UNSUPPORTED: a view with dynamic properties;
 * TL_ERR_NOMEM. `err` gets one line. */
int colour_create(const colour_desc *desc, colour **out, char *err, size_t err_size);
void colour_destroy(colour **c);
/* One line naming the transform, e.g. "ACES 1.0 SDR-video -> sRGB (OCIO 2.1.2 builtins)". */
const char *colour_name(const colour *c);
/* The config file the transform was read from; NULL for the built-in default. */
const char *colour_config_path(const colour *c);
/* The version of the OpenColorIO library taslab runs with ("2.1.2"), for manifests. */
const char *colour_library_version(void);
/* GLSL (Vulkan GLSL 4.60 compatible) defining `vec4 ocio_display(vec4 linear_rgba)`. No uniforms (creation fails
 * with a clear message for a view with dynamic properties); a view built from LUT files declares one sampler per
 * LUT (colour_lut_get), which the renderer turns into buffer reads (renderer/src/device/colour_gpu.c). The text is OCIO's,
 * with its B-spline curve functions restructured into straight-line code that computes bit-identical values
 * (colour.cpp explains why: a 20x faster display transform on a SIMD CPU driver). */
const char *colour_glsl(const colour *c);
/* A lookup table sampled by colour_glsl(): `uniform samplerND <sampler>;` there, read with texture(). */
typedef struct colour_lut {
	const char *sampler;           /* its GLSL name, e.g. "ocio_lut3d_1Sampler" */
	int dims;                      /* 1, 2 or 3: sampler1D, sampler2D, sampler3D */
	unsigned width, height, depth; /* texels (height and depth 1 where unused) */
	int channels;                  /* 1 (red only: texture() gives (v, 0, 0, 1)) or 3 (RGB) */
	int linear;                    /* linear filtering, else nearest; clamp to edge in both */
	const float *values;           /* width*height*depth*channels floats, x fastest, channels interleaved */
} colour_lut;
/* The view's LUTs (0 for an analytic view such as the built-in ACES one); valid while the colour lives. */
size_t colour_lut_count(const colour *c);
const colour_lut *colour_lut_get(const colour *c, size_t i);
/* How many curve functions were restructured (0: OCIO's text as emitted). */
int colour_glsl_rewritten(const colour *c);
/* Applies the transform in place to `n` RGB(A) float pixels (channels 3 or 4, alpha untouched). */
void colour_apply(const colour *c, float *pixels, size_t n, int channels);
/* A content hash of the transform (16 hex digits, FNV-1a 64 over its GLSL and every LUT's values): the same config
 * path with an edited config or LUT file gives another one (sweeps and run manifests record it; issue 31.4). */
#define COLOUR_DIGEST_HEX 17
void colour_digest(const colour *c, char out[COLOUR_DIGEST_HEX]);

#ifdef __cplusplus
}
#endif
#endif
