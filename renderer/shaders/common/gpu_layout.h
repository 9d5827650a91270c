/* gpu_layout.h - the GPU data layout shared by the C renderer and the shaders, written once in the common subset
 * of C11 and GLSL 4.60 (issue 30.4: before, common.glsl and frame/gpu_types.h each spelled it out and could drift).
 *
 * Included by shaders/common/common.glsl (glslang: at build time through -I renderer/shaders, at run time from the
 * embedded shader library) and by renderer/src/frame/gpu_types.h (C, which includes <stdint.h> first and adds the
 * C names gpu_light, gpu_frame_state, ...). GLSL for Vulkan predefines VULKAN (GL_KHR_vulkan_glsl); C does not.
 *
 * Rules that keep the two languages' layouts equal (gpu_types.h asserts the sizes): structs hold only 16-byte
 * members (vec4, ivec4, uvec4, mat4) and arrays of them, so std430 adds no padding C would not; scalars only in
 * GpuPush (push constants, std430 scalars of 4 bytes). Constants carry the u suffix where GLSL compares them with
 * uints. No #include here: the run-time include resolver would expand it in both branches. */
#ifndef TASLAB_GPU_LAYOUT_H
#define TASLAB_GPU_LAYOUT_H

/* Loop and array bounds; the scene library's limits equal them (gpu_types.h asserts SCENE_MAX_LIGHTS and
 * SCENE_MAX_SHADOW_LAYERS). */
#define GPU_MAX_LIGHTS 16
#define GPU_MAX_SHADOW_LAYERS 48
/* Shadow maps live in a pool of physical layers spread over GPU_SHADOW_CHUNKS array images (the shadow-map history
 * of temporal forward rendering needs more layers than one allocation holds); a state slot maps its logical layers
 * to physical ones (FrameState.shadow_phys), so slots share layers that did not change (passes/shadow.c). */
#define GPU_SHADOW_CHUNKS 16
/* Floats per vertex in the scene's vertex buffer (scene_vertex: position, normal, uv, tangent), for vertex
 * pulling (common/vertex_pull.glsl). */
#define GPU_VERTEX_FLOATS 12u

/* GpuLight.direction_type.w */
#define GPU_LIGHT_DIRECTIONAL 1u
#define GPU_LIGHT_POINT 2u
#define GPU_LIGHT_SPOT 3u

/* GpuMaterial.tex1.y: the glTF alpha mode (scene_alpha_mode) */
#define GPU_ALPHA_OPAQUE 0
#define GPU_ALPHA_MASK 1
#define GPU_ALPHA_BLEND 2

#ifdef VULKAN
#define GPU_STRUCT(T) struct T
#define GPU_VEC4(n) vec4 n
#define GPU_IVEC4(n) ivec4 n
#define GPU_UVEC4(n) uvec4 n
#define GPU_MAT4(n) mat4 n
#define GPU_MAT4_ARRAY(n, count) mat4 n[count]
#define GPU_UINT(n) uint n
#define GPU_UINT_ARRAY(n, count) uint n[count]
/* count uints packed as uvec4s (std430 would pad a uint array in a struct to 16-byte elements); count % 4 == 0 */
#define GPU_UINT_ARRAY4(n, count) uvec4 n[(count) / 4]
#else
#define GPU_STRUCT(T)                                                                                              \
	typedef struct T T;                                                                                        \
	struct T
#define GPU_VEC4(n) float n[4]
#define GPU_IVEC4(n) int32_t n[4]
#define GPU_UVEC4(n) uint32_t n[4]
#define GPU_MAT4(n) float n[16]
#define GPU_MAT4_ARRAY(n, count) float n[count][16]
#define GPU_UINT(n) uint32_t n
#define GPU_UINT_ARRAY(n, count) uint32_t n[count]
#define GPU_UINT_ARRAY4(n, count) uint32_t n[count]
#endif

GPU_STRUCT(GpuLight) {
	GPU_VEC4(position_range);  /* xyz world position, w range (0 = infinite) */
	GPU_VEC4(direction_type);  /* xyz unit direction the light points, w kind (GPU_LIGHT_*) */
	GPU_VEC4(color);           /* rgb colour * intensity */
	GPU_VEC4(cone_shadow);     /* x cos(outer), y 1/(cos(inner)-cos(outer)), z first shadow layer or -1, w normal-offset bias */
};

/* The scene at one state slot's time (common.glsl: the FrameStates ring). */
GPU_STRUCT(FrameState) {
	GPU_MAT4(view);
	GPU_MAT4(proj);
	GPU_MAT4(view_proj);
	GPU_VEC4(camera_time);      /* xyz eye position, w time in seconds */
	GPU_VEC4(ambient_exposure); /* rgb ambient radiance, w exposure */
	GPU_VEC4(sky_lights);       /* rgb sky radiance, w light count */
	GPU_VEC4(shadow_params);    /* x 1/shadow map size, y PCF radius in texels */
	GpuLight lights[GPU_MAX_LIGHTS];
	GPU_MAT4_ARRAY(shadow_matrix, GPU_MAX_SHADOW_LAYERS); /* world -> light clip space, per shadow layer */
	/* physical shadow-map layer of each logical layer: chunk << 16 | layer in chunk */
	GPU_UINT_ARRAY4(shadow_phys, GPU_MAX_SHADOW_LAYERS);
};

GPU_STRUCT(GpuObject) {
	GPU_MAT4(world);
	GPU_MAT4(normal_matrix); /* inverse transpose of world (upper 3x3 used) */
	GPU_UVEC4(material);     /* x material index, y 1 when world mirrors (det < 0: clockwise front faces, glTF 2.0 section 3.7.2.1) */
};

GPU_STRUCT(GpuMaterial) {
	GPU_VEC4(base_color);
	GPU_VEC4(emissive_normal_scale); /* rgb emissive factor, w normal scale */
	GPU_VEC4(mr_occ_cutoff);         /* x metallic, y roughness, z occlusion strength, w alpha cutoff */
	GPU_IVEC4(tex0);                 /* layers: x base colour (colour array), y metal-rough, z normal (data array), w emissive (colour) */
	GPU_IVEC4(tex1);                 /* x occlusion (data array), y alpha mode (GPU_ALPHA_*), z double sided */
};

/* The push constants of every scene pass (common.glsl: `pc`). */
GPU_STRUCT(GpuPush) {
	GPU_UINT(slot);             /* state slot shaded / rasterised */
	GPU_UINT(object);           /* object index */
	GPU_UINT(object_count);     /* objects per slot in the Objects ring */
	GPU_UINT(layer);            /* shadow pass: shadow layer being rendered */
	GPU_UINT_ARRAY(aux, 4);     /* pass- or method-specific (tfr: previous slot, max age K, frame flags, threshold bits) */
};

#endif
