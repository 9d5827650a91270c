// common.glsl - the resources every pass sees: the scene set (set 0) and the push constants, with the data layout
// of common/gpu_layout.h (shared with the C renderer: renderer/src/frame/gpu_types.h).
//
// Scene state is kept in rings indexed by a *state slot*: slot s holds the scene evaluated at
// some time t_s (camera, lights, shadow matrices, object transforms). The reference method
// shades with the current slot only; temporal forward rendering (DESIGN section 4) shades the
// same surface point with an older slot, which is why shading takes object-space inputs plus a slot.
#ifndef TASLAB_COMMON_GLSL
#define TASLAB_COMMON_GLSL

// The structures and constants are shared with the C renderer from one header (issue 30.4).
#include "common/gpu_layout.h"

layout(std430, set = 0, binding = 0) readonly buffer FrameStates { FrameState states[]; };
layout(std430, set = 0, binding = 1) readonly buffer Objects { GpuObject objects[]; };
layout(std430, set = 0, binding = 2) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = 3) uniform sampler2DArray color_textures; // sRGB formats: decoded on fetch
layout(set = 0, binding = 4) uniform sampler2DArray data_textures;  // linear formats
// the shadow-map pool (gpu_layout.h: GPU_SHADOW_CHUNKS)
layout(set = 0, binding = 5) uniform sampler2DArrayShadow shadow_maps[GPU_SHADOW_CHUNKS];
// binding 6: the reference shading's invocation counter, declared by the shaders that count (ref/count.glsl)

layout(push_constant) uniform Push { GpuPush pc; }; // pc.slot, pc.object, ... (gpu_layout.h)

GpuObject object_at(uint slot, uint object) { return objects[slot * pc.object_count + object]; }

#endif
