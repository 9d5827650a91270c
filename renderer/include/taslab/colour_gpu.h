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

/* Applies the GPU version of the transform to `n` RGBA float pixels in place, on `dev`. */
int colour_apply_gpu(vkdev *dev, const colour *c, float *rgba, size_t n, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
