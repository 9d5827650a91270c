// tas.glsl - helpers shared by the temporally adaptive passes (tfr and the TFR analysis): shading of a
// surface point at a state slot, display-referred comparison (DESIGN section 3) and reprojection.
// Needs shading.glsl and the OpenColorIO function ocio_display() before it.
#ifndef TASLAB_TAS_GLSL
#define TASLAB_TAS_GLSL

// Scene-linear shading (times exposure) of the surface point given in object space, with every
// time-dependent input (object transform, lights, camera, shadow maps) taken from `slot`
// (temporal forward rendering, paper sec. 3).
vec3 shade_point(uint slot, uint object, vec3 p_obj, vec3 n_obj, vec4 t_obj, vec2 uv, bool front)
{
	Surface s = surface_at(slot, object, p_obj, n_obj, t_obj, uv, front);
	return shade_lights(slot, s) * states[slot].ambient_exposure.w;
}

// Display-referred value in 8-bit code values, as float (compared before quantisation).
vec3 display_cv(vec3 c)
{
	return clamp(ocio_display(vec4(c, 1.0)).rgb, 0.0, 1.0) * 255.0;
}

#include "tas/disp.glsl" // disp_pack, disp_unpack

// d(a, b) = max(|a.r-b.r|, |a.g-b.g|, |a.b-b.b|) on display values (DESIGN section 3).
float maxrgb(vec3 a, vec3 b)
{
	vec3 d = abs(a - b);
	return max(d.r, max(d.g, d.b));
}

// Pixel `q` at which the surface point (object, p_obj) appears in the frame of state `slot`, and the
// point's distance from that frame's eye. False when it projects outside the frame or behind the eye.
bool reproject(uint slot, uint object, vec3 p_obj, ivec2 size, out ivec2 q, out float dist)
{
	vec4 w = object_at(slot, object).world * vec4(p_obj, 1.0);
	vec4 c = states[slot].view_proj * w;
	q = ivec2(0);
	dist = distance(w.xyz, states[slot].camera_time.xyz);
	if (c.w <= 0.0)
		return false;
	vec2 f = (c.xy / c.w * 0.5 + 0.5) * vec2(size);
	if (any(lessThan(f, vec2(0.0))) || any(greaterThanEqual(f, vec2(size))))
		return false;
	q = ivec2(f);
	return true;
}

// Visibility record of a pixel: object index + 1 (0 = background) and the view distance (float bits).
// A reprojected point was visible there iff the object matches and the distances agree within 2%
// (the point lies between pixel centres, so depth varies across the pixel on slanted surfaces).
bool was_visible(uvec4 rec, uint object, float dist)
{
	return rec.y == object + 1u && abs(uintBitsToFloat(rec.z) - dist) <= 0.02 * dist;
}

#endif
