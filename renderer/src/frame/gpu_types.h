/* gpu_types.h (private) — C mirror of the std430 structures in shaders/common.glsl. */
#ifndef TASLAB_GPU_TYPES_H
#define TASLAB_GPU_TYPES_H

#include <stdint.h>

#include "taslab/scene.h"

#define GPU_LIGHT_DIRECTIONAL 1
#define GPU_LIGHT_POINT 2
#define GPU_LIGHT_SPOT 3

typedef struct gpu_light {
	float position_range[4];
	float direction_type[4];
	float color[4];
	float cone_shadow[4];
} gpu_light;

typedef struct gpu_frame_state {
	float view[16];
	float proj[16];
	float view_proj[16];
	float camera_time[4];
	float ambient_exposure[4];
	float sky_lights[4];
	float shadow_params[4];
	gpu_light lights[SCENE_MAX_LIGHTS];
	float shadow_matrix[SCENE_MAX_SHADOW_LAYERS][16];
	uint32_t shadow_phys[SCENE_MAX_SHADOW_LAYERS]; /* chunk << 16 | layer in chunk */
} gpu_frame_state;

#define GPU_SHADOW_CHUNKS 16

typedef struct gpu_object {
	float world[16];
	float normal_matrix[16];
	uint32_t material[4];
} gpu_object;

typedef struct gpu_material {
	float base_color[4];
	float emissive_normal_scale[4];
	float mr_occ_cutoff[4];
	int32_t tex0[4];
	int32_t tex1[4];
} gpu_material;

typedef struct gpu_push {
	uint32_t slot, object, object_count, layer;
	uint32_t aux[4];
} gpu_push;

_Static_assert(sizeof(gpu_light) == 64, "std430 GpuLight");
_Static_assert(sizeof(gpu_frame_state) == 3 * 64 + 4 * 16 + SCENE_MAX_LIGHTS * 64 + SCENE_MAX_SHADOW_LAYERS * 64 +
		       SCENE_MAX_SHADOW_LAYERS * 4,
	       "std430 FrameState");
_Static_assert(sizeof(gpu_object) == 144, "std430 GpuObject");
_Static_assert(sizeof(gpu_material) == 80, "std430 GpuMaterial");

#endif
