/* colour_gpu.h — the display transform of colour.h evaluated on the Vulkan device: the GLSL OpenColorIO
 * generates, compiled at run time, applied to a buffer of pixels. For checking GPU/CPU agreement and
 * debugging (test_colour); the frame pipeline inlines the same function into its own shaders. */
#ifndef TASLAB_COLOUR_GPU_H
#define TASLAB_COLOUR_GPU_H

#include <stddef.h>

#include "taslab/colour.h"
#include "taslab/vkdev.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The transform's GLSL for one device: ocio_display() with the view's LUTs (colour_lut) read from a buffer on the
 * device through buffer references instead of samplers, so that a shader includes it without binding anything
 * (colour_gpu.c says how); for an analytic view, colour_glsl() as it is. Shaders put colour_device_extensions()
 * right after their #version line ("" without LUTs). Lives as long as the shaders compiled with it are used. */
typedef struct colour_device colour_device;
int colour_device_create(vkdev *dev, const colour *c, colour_device **out, char *err, size_t err_size);
void colour_device_destroy(vkdev *dev, colour_device **cd);
const char *colour_device_glsl(const colour_device *cd);
const char *colour_device_extensions(const colour_device *cd);

/* Applies the GPU version of the transform to `n` RGBA float pixels in place, on `dev`. Returns TL_OK,
 * colour_device_create's code, TL_ERR_ARG (no pixels), TL_ERR_NOMEM, TL_ERR_VULKAN or TL_ERR_INTERNAL (the
 * generated shader does not compile). */
int colour_apply_gpu(vkdev *dev, const colour *c, float *rgba, size_t n, char *err, size_t err_size);

/* Issue 31.7: the GPU version of the transform against the CPU one (OCIO's processor) on a fixed set of linear
 * inputs (COLOUR_CHECK_LEVELS^3 colours: 0 and 1e-4..64 log-spaced per channel, so HDR values and saturated colours),
 * compared as they reach the display (clamped to [0, 1], on the 0-255 scale). TL_ERR_INPUT with a one-line message
 * naming the worst input when they differ by more than COLOUR_CHECK_TOLERANCE code values: frames rendered on the
 * GPU and metrics computed on the CPU would not show the same images; else colour_apply_gpu's code. *worst (may be
 * NULL): the largest difference. */
#define COLOUR_CHECK_LEVELS 12
#define COLOUR_CHECK_TOLERANCE 1.0
int colour_check_gpu(vkdev *dev, const colour *c, double *worst, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
