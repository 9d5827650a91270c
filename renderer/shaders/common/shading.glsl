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

// Shadow-map chunks the renderer may use (render_shadow.c), set when the pipeline is created.
layout(constant_id = 1) const int SHADOW_CHUNKS_USED = 1;

float shadow_lookup(uint slot, int layer, vec3 world_pos)
{
	vec4 lc = states[slot].shadow_matrix[layer] * vec4(world_pos, 1.0);
	vec3 ndc = lc.xyz / lc.w;
	vec2 uv = ndc.xy * 0.5 + 0.5;
	if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0))) || ndc.z >= 1.0)
		return 1.0;
	float radius = states[slot].shadow_params.x * states[slot].shadow_params.y;
	uint phys = states[slot].shadow_phys[layer >> 2][layer & 3];
	float pl = float(phys & 0xFFFFu);
	float lit = 0.0;
	// No descriptor indexing on lavapipe: each chunk is sampled with a constant index, and only the
	// SHADOW_CHUNKS_USED chunks the pool can ever use are compiled in (a SIMD CPU driver pays for every
	// branch some lane might take, so a 16-way switch would cost 16 lookups).
#define TL_PCF(c) if ((c) < SHADOW_CHUNKS_USED && (SHADOW_CHUNKS_USED == 1 || chunk == (c))) \
	for (int i = 0; i < 16; i++) lit += texture(shadow_maps[c], vec4(uv + POISSON16[i] * radius, pl, ndc.z));
	int chunk = int(phys >> 16);
	TL_PCF(0) TL_PCF(1) TL_PCF(2) TL_PCF(3) TL_PCF(4) TL_PCF(5) TL_PCF(6) TL_PCF(7)
	TL_PCF(8) TL_PCF(9) TL_PCF(10) TL_PCF(11) TL_PCF(12) TL_PCF(13) TL_PCF(14) TL_PCF(15)
#undef TL_PCF
	return lit * (1.0 / 16.0);
}

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
	return (diffuse + F * D * V) * radiance * ndl;
}

vec3 shade_lights(uint slot, Surface s)
{
	vec3 eye = states[slot].camera_time.xyz;
	vec3 v = normalize(eye - s.position);
	uint count = uint(states[slot].sky_lights.w);
	vec3 sum = vec3(0.0);
	for (uint i = 0u; i < count; i++) {
		GpuLight L = states[slot].lights[i];
		uint kind = uint(L.direction_type.w);
		vec3 l;
		float atten = 1.0;
		if (kind == LIGHT_DIRECTIONAL) {
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
			if (kind == LIGHT_SPOT) {
				float cd = dot(L.direction_type.xyz, -l);
				float t = clamp((cd - L.cone_shadow.x) * L.cone_shadow.y, 0.0, 1.0);
				atten *= t * t;
			}
		}
		if (atten <= 0.0 || dot(s.normal, l) <= 0.0)
			continue;
		int layer = int(L.cone_shadow.z);
		float vis = 1.0;
		if (layer >= 0) {
			// Normal-offset bias: move the lookup point along the geometric normal.
			vec3 p = s.position + s.normal * L.cone_shadow.w;
			if (kind == LIGHT_POINT)
				layer += cube_face(p - L.position_range.xyz);
			vis = shadow_lookup(slot, layer, p);
		}
		if (vis > 0.0)
			sum += brdf_ggx(s, v, l, L.color.rgb * (atten * vis));
	}
	vec3 ambient = states[slot].ambient_exposure.rgb * s.occlusion * s.base_color *
		       (1.0 - 0.5 * s.metallic) * (0.75 + 0.25 * s.normal.y);
	return sum + ambient + s.emissive;
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
		base *= texture(color_textures, vec3(uv, float(m.tex0.x)));
	s.base_color = base.rgb;
	s.alpha = base.a;
	s.metallic = m.mr_occ_cutoff.x;
	s.roughness = m.mr_occ_cutoff.y;
	if (m.tex0.y >= 0) {
		vec4 mr = texture(data_textures, vec3(uv, float(m.tex0.y)));
		s.roughness *= mr.g;
		s.metallic *= mr.b;
	}
	s.roughness = clamp(s.roughness, 0.03, 1.0);
	if (m.tex0.z >= 0) {
		vec3 tn = texture(data_textures, vec3(uv, float(m.tex0.z))).xyz * 2.0 - 1.0;
		tn.xy *= m.emissive_normal_scale.w;
		t = normalize(t - n * dot(n, t));
		vec3 b = cross(n, t) * t_obj.w;
		n = normalize(mat3(t, b, n) * tn);
	}
	s.normal = n;
	s.occlusion = 1.0;
	if (m.tex1.x >= 0)
		s.occlusion = 1.0 + m.mr_occ_cutoff.z * (texture(data_textures, vec3(uv, float(m.tex1.x))).r - 1.0);
	s.emissive = m.emissive_normal_scale.rgb;
	if (m.tex0.w >= 0)
		s.emissive *= texture(color_textures, vec3(uv, float(m.tex0.w))).rgb;
	return s;
}

#endif
