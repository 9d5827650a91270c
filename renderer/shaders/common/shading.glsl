// shading.glsl - forward PBR shading of one surface sample (glTF 2.0 metal-roughness).
//
// BRDF as used by the paper's test scenes (sec. 3: "physically based materials [Schlick 1994]"):
// GGX / Trowbridge-Reitz normal distribution, height-correlated Smith visibility (Heitz 2014),
// Schlick Fresnel with F0 = mix(0.04, base colour, metallic), Lambert diffuse weighted by (1 - F)
// and (1 - metallic). Punctual lights follow KHR_lights_punctual (inverse square falloff with the
// smooth range window, spot cone smoothstep). Every light may cast a shadow from a shadow-map layer,
// filtered with a fixed 16-tap Poisson disk of hardware 2x2 PCF lookups (fixed, not rotated per
// pixel, so shading stays temporally stable and deterministic).
//
// Inputs are object-space (position, normal, tangent, uv) plus a state slot, so the same surface
// point can be shaded as it was at another time (temporal forward rendering, DESIGN section 4).
#ifndef TASLAB_SHADING_GLSL
#define TASLAB_SHADING_GLSL

#include "common/common.glsl"

// TL_BRDF_PART (rrc --payload diffuse, [S] sec. 4.1): 1 the diffuse term only (Lambert per light, shadowed, and the
// ambient term: the payload the cache keeps), 2 the rest (the specular term per light and the emission: what is
// shaded every frame); 0, the default, both.
#ifndef TL_BRDF_PART
#define TL_BRDF_PART 0
#endif

const float PI = 3.14159265358979;

const vec2 POISSON16[16] = vec2[](
	vec2(-0.94201624, -0.39906216), vec2(0.94558609, -0.76890725), vec2(-0.09418410, -0.92938870),
	vec2(0.34495938, 0.29387760), vec2(-0.91588581, 0.45771432), vec2(-0.81544232, -0.87912464),
	vec2(-0.38277543, 0.27676845), vec2(0.97484398, 0.75648379), vec2(0.44323325, -0.97511554),
	vec2(0.53742981, -0.47373420), vec2(-0.26496911, -0.41893023), vec2(0.79197514, 0.19090188),
	vec2(-0.24188840, 0.99706507), vec2(-0.81409955, 0.91437590), vec2(0.19984126, 0.78641367),
	vec2(0.14383161, -0.14100790));

struct Surface {
	vec3 position;   // world
	vec3 normal;     // world, shading normal (normal map applied), facing the viewer side
	vec3 base_color; // linear
	float alpha;
	float metallic;
	float roughness;
	float occlusion;
	vec3 emissive;
};

// Lights and shadow chunks, fixed when the pipeline is created (passes/shadow.c). The shadow pool pins every
// logical shadow layer to one array image ("chunk"), so the chunk a light samples is a constant: the light
// loop is unrolled (TL_LIGHT below) and each light samples shadow_maps[] with a constant index. lavapipe has
// no descriptor indexing and a SIMD CPU driver executes every branch some lane might take, so a run-time
// chunk switch cost one lookup per chunk in use (3x the shadow filtering of the TFR history).
// LIGHT_SHADOW_i: -1 no shadow; else bits 0-7 the chunk of faces below `split`, bits 8-15 the chunk of the
// faces from `split` on, bits 16-23 `split` (a point light whose six faces did not fit one chunk).
layout(constant_id = 2) const int LIGHT_COUNT = 0;
layout(constant_id = 3) const int LIGHT_SHADOW_0 = -1;
layout(constant_id = 4) const int LIGHT_SHADOW_1 = -1;
layout(constant_id = 5) const int LIGHT_SHADOW_2 = -1;
layout(constant_id = 6) const int LIGHT_SHADOW_3 = -1;
layout(constant_id = 7) const int LIGHT_SHADOW_4 = -1;
layout(constant_id = 8) const int LIGHT_SHADOW_5 = -1;
layout(constant_id = 9) const int LIGHT_SHADOW_6 = -1;
layout(constant_id = 10) const int LIGHT_SHADOW_7 = -1;
layout(constant_id = 11) const int LIGHT_SHADOW_8 = -1;
layout(constant_id = 12) const int LIGHT_SHADOW_9 = -1;
layout(constant_id = 13) const int LIGHT_SHADOW_10 = -1;
layout(constant_id = 14) const int LIGHT_SHADOW_11 = -1;
layout(constant_id = 15) const int LIGHT_SHADOW_12 = -1;
layout(constant_id = 16) const int LIGHT_SHADOW_13 = -1;
layout(constant_id = 17) const int LIGHT_SHADOW_14 = -1;
layout(constant_id = 18) const int LIGHT_SHADOW_15 = -1;

// Projects `world_pos` into shadow layer `layer` of `slot`: texture coordinates, depth, filter radius and
// the layer within its chunk. False when the point lies outside the layer's frustum (then it is lit).
bool shadow_coords(uint slot, int layer, vec3 world_pos, out vec2 uv, out float depth, out float radius, out float pl)
{
	vec4 lc = states[slot].shadow_matrix[layer] * vec4(world_pos, 1.0);
	vec3 ndc = lc.xyz / lc.w;
	uv = ndc.xy * 0.5 + 0.5;
	depth = ndc.z;
	radius = states[slot].shadow_params.x * states[slot].shadow_params.y;
	uint phys = states[slot].shadow_phys[layer >> 2][layer & 3];
	pl = float(phys & 0xFFFFu);
	return !(any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0))) || ndc.z >= 1.0);
}

// 16-tap Poisson PCF of chunk c (a constant expression).
#define TL_PCF(c, uv, depth, radius, pl, lit)                                                                   \
	for (int k_ = 0; k_ < 16; k_++)                                                                         \
		lit += texture(shadow_maps[(c)], vec4(uv + POISSON16[k_] * radius, pl, depth));

// Cube face (shadow layer offset 0..5: +X, -X, +Y, -Y, +Z, -Z) seen from the light along d.
int cube_face(vec3 d)
{
	vec3 a = abs(d);
	if (a.x >= a.y && a.x >= a.z)
		return d.x > 0.0 ? 0 : 1;
	if (a.y >= a.z)
		return d.y > 0.0 ? 2 : 3;
	return d.z > 0.0 ? 4 : 5;
}

vec3 brdf_ggx(Surface s, vec3 v, vec3 l, vec3 radiance)
{
	vec3 n = s.normal;
	float ndl = max(dot(n, l), 0.0);
	if (ndl <= 0.0)
		return vec3(0.0);
	float ndv = max(dot(n, v), 1e-4);
	vec3 h = normalize(v + l);
	float ndh = max(dot(n, h), 0.0);
	float vdh = max(dot(v, h), 0.0);
	float a = max(s.roughness * s.roughness, 1e-3);
	float a2 = a * a;
	float dd = ndh * ndh * (a2 - 1.0) + 1.0;
	float D = a2 / (PI * dd * dd);
	float gv = ndl * sqrt(ndv * ndv * (1.0 - a2) + a2);
	float gl = ndv * sqrt(ndl * ndl * (1.0 - a2) + a2);
	float V = 0.5 / max(gv + gl, 1e-6);
	vec3 f0 = mix(vec3(0.04), s.base_color, s.metallic);
	vec3 F = f0 + (1.0 - f0) * pow(1.0 - vdh, 5.0);
	vec3 diffuse = (1.0 - F) * (1.0 - s.metallic) * s.base_color / PI;
#if TL_BRDF_PART == 1
	return diffuse * radiance * ndl;
#elif TL_BRDF_PART == 2
	return F * D * V * radiance * ndl;
#else
	return (diffuse + F * D * V) * radiance * ndl;
#endif
}

// Direction, attenuation and shadow lookup point of light i at surface s (KHR_lights_punctual falloff, spot
// cone, normal-offset bias). False when the light contributes nothing (outside range/cone, or behind).
bool light_setup(uint slot, Surface s, uint i, out vec3 l, out float atten, out vec3 p)
{
	GpuLight L = states[slot].lights[i];
	uint kind = uint(L.direction_type.w);
	atten = 1.0;
	if (kind == GPU_LIGHT_DIRECTIONAL) {
		l = -L.direction_type.xyz;
	} else {
		vec3 d = L.position_range.xyz - s.position;
		float dist2 = max(dot(d, d), 1e-4);
		l = d * inversesqrt(dist2);
		float range = L.position_range.w;
		float win = 1.0;
		if (range > 0.0) {
			float r = dist2 / (range * range);
			win = clamp(1.0 - r * r, 0.0, 1.0);
			win *= win;
		}
		atten = win / dist2;
		if (kind == GPU_LIGHT_SPOT) {
			float cd = dot(L.direction_type.xyz, -l);
			float t = clamp((cd - L.cone_shadow.x) * L.cone_shadow.y, 0.0, 1.0);
			atten *= t * t;
		}
	}
	// Normal-offset bias: the shadow lookup point moves along the geometric normal.
	p = s.position + s.normal * L.cone_shadow.w;
	return !(atten <= 0.0 || dot(s.normal, l) <= 0.0);
}

// The shadow factor vis_ of light L_ with shadow code SH (a constant) at the lookup point p_: the 16-tap PCF.
#define TL_SHADOW_PCF(SH, L_, p_, vis_)                                                                         \
	{                                                                                                       \
		int layer_ = int(L_.cone_shadow.z);                                                             \
		int face_ = uint(L_.direction_type.w) == GPU_LIGHT_POINT ? cube_face(p_ - L_.position_range.xyz) : 0; \
		vec2 uv_;                                                                                       \
		float d_, r_, pl_, lit_ = 0.0;                                                                  \
		bool in_ = shadow_coords(slot, layer_ + face_, p_, uv_, d_, r_, pl_);                            \
		TL_PCF((SH) & 255, uv_, d_, r_, pl_, lit_)                                                      \
		if ((((SH) >> 8) & 255) != ((SH) & 255)) {                                                      \
			float lit2_ = 0.0;                                                                      \
			TL_PCF(((SH) >> 8) & 255, uv_, d_, r_, pl_, lit2_)                                      \
			lit_ = face_ < (((SH) >> 16) & 255) ? lit_ : lit2_;                                     \
		}                                                                                               \
		vis_ = in_ ? lit_ * (1.0 / 16.0) : 1.0;                                                         \
	}

// TL_CACHED_VIS (rrc --payload shadow, [S] sec. 4.1: reproj/compose.frag.in): the shadow factors of lights 0..7 come
// from the payload cache through tl_cached_vis(i), which the including shader defines; lights from 8 on filter theirs
// every frame. (i) is a constant, so the choice is made by the compiler, not at run time; tl_cached_vis(i) is compiled
// for i >= 8 too, in the branch it drops, so it must stay well-formed there (the cache holds 8 factors: never read them).
#ifdef TL_CACHED_VIS
float tl_cached_vis(int i);
#define TL_SHADOW_VIS(i, SH, L_, p_, vis_)                                                                      \
	if ((SH) >= 0) {                                                                                        \
		if ((i) < 8)                                                                                    \
			vis_ = tl_cached_vis(i);                                                                \
		else                                                                                            \
			TL_SHADOW_PCF(SH, L_, p_, vis_)                                                         \
	}
#else
#define TL_SHADOW_VIS(i, SH, L_, p_, vis_)                                                                      \
	if ((SH) >= 0)                                                                                          \
		TL_SHADOW_PCF(SH, L_, p_, vis_)
#endif

// Light i with shadow code SH (LIGHT_SHADOW_i): accumulates its contribution into `sum`. Unrolled per light so
// that the chunks sampled are constants.
#define TL_LIGHT(i, SH)                                                                                         \
	if ((i) < LIGHT_COUNT) {                                                                                \
		vec3 l_, p_;                                                                                    \
		float atten_;                                                                                   \
		if (light_setup(slot, s, (i), l_, atten_, p_)) {                                                \
			GpuLight L_ = states[slot].lights[(i)];                                                 \
			float vis_ = 1.0;                                                                       \
			TL_SHADOW_VIS(i, SH, L_, p_, vis_)                                                      \
			if (vis_ > 0.0)                                                                         \
				sum += brdf_ggx(s, v, l_, L_.color.rgb * (atten_ * vis_));                      \
		}                                                                                               \
	}

#ifdef TL_SHADOW_FACTORS
// rrc --payload shadow ([S] sec. 4.1: "per-light shadow factors"; reproj/payload.frag.in): the shadow factors of
// lights 0..7 at surface s, f[i] = 1 where light i casts no shadow. A shadowed light's factor is filtered even where
// the light does not reach s now (outside a spot's cone, n.l <= 0): a moving light may reach it before the sample is
// refreshed, and a 1 kept there would show it lit inside a shadow. light_setup's lookup point p_ does not depend on
// whether the light reaches s.
#define TL_FACTOR(i, SH)                                                                                        \
	if ((i) < LIGHT_COUNT && (SH) >= 0) {                                                                   \
		vec3 l_, p_;                                                                                    \
		float atten_;                                                                                   \
		light_setup(slot, s, (i), l_, atten_, p_);                                                      \
		GpuLight L_ = states[slot].lights[(i)];                                                         \
		TL_SHADOW_PCF(SH, L_, p_, f[(i)])                                                               \
	}

void shadow_factors(uint slot, Surface s, out float f[8])
{
	for (int i = 0; i < 8; i++)
		f[i] = 1.0;
	TL_FACTOR(0, LIGHT_SHADOW_0) TL_FACTOR(1, LIGHT_SHADOW_1) TL_FACTOR(2, LIGHT_SHADOW_2) TL_FACTOR(3, LIGHT_SHADOW_3)
	TL_FACTOR(4, LIGHT_SHADOW_4) TL_FACTOR(5, LIGHT_SHADOW_5) TL_FACTOR(6, LIGHT_SHADOW_6) TL_FACTOR(7, LIGHT_SHADOW_7)
}
#endif

vec3 shade_lights(uint slot, Surface s)
{
	vec3 eye = states[slot].camera_time.xyz;
	vec3 v = normalize(eye - s.position);
	vec3 sum = vec3(0.0);
	TL_LIGHT(0, LIGHT_SHADOW_0) TL_LIGHT(1, LIGHT_SHADOW_1) TL_LIGHT(2, LIGHT_SHADOW_2) TL_LIGHT(3, LIGHT_SHADOW_3)
	TL_LIGHT(4, LIGHT_SHADOW_4) TL_LIGHT(5, LIGHT_SHADOW_5) TL_LIGHT(6, LIGHT_SHADOW_6) TL_LIGHT(7, LIGHT_SHADOW_7)
	TL_LIGHT(8, LIGHT_SHADOW_8) TL_LIGHT(9, LIGHT_SHADOW_9) TL_LIGHT(10, LIGHT_SHADOW_10) TL_LIGHT(11, LIGHT_SHADOW_11)
	TL_LIGHT(12, LIGHT_SHADOW_12) TL_LIGHT(13, LIGHT_SHADOW_13) TL_LIGHT(14, LIGHT_SHADOW_14)
	TL_LIGHT(15, LIGHT_SHADOW_15)
	vec3 ambient = states[slot].ambient_exposure.rgb * s.occlusion * s.base_color *
		       (1.0 - 0.5 * s.metallic) * (0.75 + 0.25 * s.normal.y);
#if TL_BRDF_PART == 1
	return sum + ambient;
#elif TL_BRDF_PART == 2
	return sum + s.emissive;
#else
	return sum + ambient + s.emissive;
#endif
}

// Texture lookups of the material: implicit derivatives in fragment shaders; compute shaders (the shading atlas)
// define TL_EXPLICIT_GRADIENTS and set tl_duv_dx / tl_duv_dy (screen-space derivatives of uv) first: in a compute
// shader texture() silently samples mip 0 (TAS-METHODS section 8.4).
#ifdef TL_EXPLICIT_GRADIENTS
vec2 tl_duv_dx, tl_duv_dy;
#ifdef TL_TEXTURE_LOD0 // ablation (atlas --texture-lod0): what texture() silently does in a compute shader
#define TL_TEX(sampler, coord) textureLod(sampler, coord, 0.0)
#else
#define TL_TEX(sampler, coord) textureGrad(sampler, coord, tl_duv_dx, tl_duv_dy)
#endif
#else
#define TL_TEX(sampler, coord) texture(sampler, coord)
#endif

// The side of a triangle the eye sees, as the rasterizer decides gl_FrontFacing: the winding of its world-space
// corners a, b, c seen from the eye at point p on it, counter-clockwise in front, clockwise for a mirrored object
// (GpuObject.material.y: its world matrix has a negative determinant, glTF 2.0 section 3.7.2.1; the draws set the front
// face alike, frame/draw.c render_set_facing). The compute passes that shade a triangle fetched per pixel (the
// atlas, the compacted sample path) use it in place of gl_FrontFacing.
bool winding_front(GpuObject o, vec3 a, vec3 b, vec3 c, vec3 p, vec3 eye)
{
	return (dot(cross(b - a, c - a), eye - p) > 0.0) != (o.material.y != 0u);
}

// Material evaluation at a surface point given in object space, with the object's transform at `slot`.
Surface surface_at(uint slot, uint object, vec3 p_obj, vec3 n_obj, vec4 t_obj, vec2 uv, bool front_facing)
{
	GpuObject o = object_at(slot, object);
	GpuMaterial m = materials[o.material.x];
	Surface s;
	s.position = (o.world * vec4(p_obj, 1.0)).xyz;
	vec3 n = normalize(mat3(o.normal_matrix) * n_obj);
	vec3 t = normalize(mat3(o.world) * t_obj.xyz);
	if (!front_facing) {
		n = -n;
	}
	vec4 base = m.base_color;
	if (m.tex0.x >= 0)
		base *= TL_TEX(color_textures, vec3(uv, float(m.tex0.x)));
	s.base_color = base.rgb;
	s.alpha = base.a;
	s.metallic = m.mr_occ_cutoff.x;
	s.roughness = m.mr_occ_cutoff.y;
	if (m.tex0.y >= 0) {
		vec4 mr = TL_TEX(data_textures, vec3(uv, float(m.tex0.y)));
		s.roughness *= mr.g;
		s.metallic *= mr.b;
	}
	s.roughness = clamp(s.roughness, 0.03, 1.0);
	if (m.tex0.z >= 0) {
		vec3 tn = TL_TEX(data_textures, vec3(uv, float(m.tex0.z))).xyz * 2.0 - 1.0;
		tn.xy *= m.emissive_normal_scale.w;
		t = normalize(t - n * dot(n, t));
		// glTF's bitangent cross(normal, tangent) * w is in object space; a mirroring world matrix reverses the
		// cross product of the transformed vectors, so a mirrored object's normal map is the mirror image
		vec3 b = cross(n, t) * (o.material.y != 0u ? -t_obj.w : t_obj.w);
		n = normalize(mat3(t, b, n) * tn);
	}
	s.normal = n;
	s.occlusion = 1.0;
	if (m.tex1.x >= 0)
		s.occlusion = 1.0 + m.mr_occ_cutoff.z * (TL_TEX(data_textures, vec3(uv, float(m.tex1.x))).r - 1.0);
	s.emissive = m.emissive_normal_scale.rgb;
	if (m.tex0.w >= 0)
		s.emissive *= TL_TEX(color_textures, vec3(uv, float(m.tex0.w))).rgb;
	return s;
}

#endif
