// common.glsl - GPU data layout shared by all passes. Must match renderer/src/gpu_types.h.
//
// Scene state is kept in rings indexed by a *state slot*: slot s holds the scene evaluated at
// some time t_s (camera, lights, shadow matrices, object transforms). The reference method
// shades with the current slot only; temporal forward rendering (DESIGN section 4) shades the
// same surface point with an older slot, which is why shading takes object-space inputs plus a slot.
#ifndef TASLAB_COMMON_GLSL
#define TASLAB_COMMON_GLSL

#define MAX_LIGHTS 16
#define MAX_SHADOW_LAYERS 48

#define LIGHT_DIRECTIONAL 1u
#define LIGHT_POINT 2u
#define LIGHT_SPOT 3u

struct GpuLight {
	vec4 position_range;  // xyz world position, w range (0 = infinite)
	vec4 direction_type;  // xyz unit direction the light points, w kind (LIGHT_*)
	vec4 color;           // rgb colour * intensity
	vec4 cone_shadow;     // x cos(outer), y 1/(cos(inner)-cos(outer)), z first shadow layer or -1, w normal-offset bias
};

struct FrameState {
	mat4 view;
	mat4 proj;
	mat4 view_proj;
	vec4 camera_time;      // xyz eye position, w time in seconds
	vec4 ambient_exposure; // rgb ambient radiance, w exposure
	vec4 sky_lights;       // rgb sky radiance, w light count
	vec4 shadow_params;    // x 1/shadow map size, y PCF radius in texels
	GpuLight lights[MAX_LIGHTS];
	mat4 shadow_matrix[MAX_SHADOW_LAYERS]; // world -> light clip space, per shadow layer
	uvec4 shadow_phys[MAX_SHADOW_LAYERS / 4]; // physical shadow-map layer of each logical layer: chunk << 16 | layer
};

struct GpuObject {
	mat4 world;
	mat4 normal_matrix;  // inverse transpose of world (upper 3x3 used)
	uvec4 material;      // x material index
};

struct GpuMaterial {
	vec4 base_color;
	vec4 emissive_normal_scale;  // rgb emissive factor, w normal scale
	vec4 mr_occ_cutoff;          // x metallic, y roughness, z occlusion strength, w alpha cutoff
	ivec4 tex0;                  // layers: x base colour (colour array), y metal-rough, z normal (data array), w emissive (colour)
	ivec4 tex1;                  // x occlusion (data array), y alpha mode, z double sided
};

layout(std430, set = 0, binding = 0) readonly buffer FrameStates { FrameState states[]; };
layout(std430, set = 0, binding = 1) readonly buffer Objects { GpuObject objects[]; };
layout(std430, set = 0, binding = 2) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = 3) uniform sampler2DArray color_textures; // sRGB formats: decoded on fetch
layout(set = 0, binding = 4) uniform sampler2DArray data_textures;  // linear formats
// Shadow maps live in a pool of physical layers spread over SHADOW_CHUNKS array images (the shadow-map
// history of temporal forward rendering needs more layers than one allocation holds); the state slot
// maps its logical layers to physical ones (shadow_phys), so slots share layers that did not change.
#define SHADOW_CHUNKS 16
layout(set = 0, binding = 5) uniform sampler2DArrayShadow shadow_maps[SHADOW_CHUNKS];

layout(push_constant) uniform Push {
	uint slot;          // state slot shaded / rasterised
	uint object;        // object index
	uint object_count;  // objects per slot in the Objects ring
	uint layer;         // shadow pass: shadow layer being rendered
	uint aux[4];        // method-specific (tfr: previous slot, max age K, frame flags, threshold bits)
} pc;

GpuObject object_at(uint slot, uint object) { return objects[slot * pc.object_count + object]; }

#endif
