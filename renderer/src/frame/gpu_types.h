/* gpu_types.h (private) — the C names of the GPU data layout. The structures and constants themselves are written
 * once, in the common subset of C and GLSL, in renderer/shaders/common/gpu_layout.h, which the shaders include
 * too (common.glsl); this header adds the C type names and checks what C cannot share with GLSL: the scene
 * library's limits and the std430 sizes (issue 30.4). */
#ifndef TASLAB_GPU_TYPES_H
#define TASLAB_GPU_TYPES_H

#include <stdint.h>

#include "../../shaders/common/gpu_layout.h"
#include "taslab/scene.h"

typedef GpuLight gpu_light;
typedef FrameState gpu_frame_state;
typedef GpuObject gpu_object;
typedef GpuMaterial gpu_material;
typedef GpuPush gpu_push;

/* The scene library (no GPU) has its own limits; the shader loops and arrays are sized by these. */
_Static_assert(SCENE_MAX_LIGHTS == GPU_MAX_LIGHTS, "scene.h and gpu_layout.h disagree on the light count");
_Static_assert(SCENE_MAX_SHADOW_LAYERS == GPU_MAX_SHADOW_LAYERS, "scene.h and gpu_layout.h disagree on shadow layers");
_Static_assert(GPU_MAX_SHADOW_LAYERS % 4 == 0, "FrameState.shadow_phys packs 4 layers per uvec4");
_Static_assert(SCENE_ALPHA_OPAQUE == GPU_ALPHA_OPAQUE && SCENE_ALPHA_MASK == GPU_ALPHA_MASK &&
		       SCENE_ALPHA_BLEND == GPU_ALPHA_BLEND,
	       "scene_alpha_mode and GpuMaterial.tex1.y");
_Static_assert(sizeof(scene_vertex) == GPU_VERTEX_FLOATS * sizeof(float), "scene_vertex and vertex pulling");

/* std430 sizes of what the C compiler laid out (gpu_layout.h's rules keep them equal; a vec3 or a lone scalar in a
 * struct would not be) */
_Static_assert(sizeof(gpu_light) == 64, "std430 GpuLight");
_Static_assert(sizeof(gpu_frame_state) == 3 * 64 + 4 * 16 + GPU_MAX_LIGHTS * 64 + GPU_MAX_SHADOW_LAYERS * 64 +
		       GPU_MAX_SHADOW_LAYERS * 4,
	       "std430 FrameState");
_Static_assert(sizeof(gpu_object) == 144, "std430 GpuObject");
_Static_assert(sizeof(gpu_material) == 80, "std430 GpuMaterial");
_Static_assert(sizeof(gpu_push) == 32, "push constants GpuPush");

#endif
