// display.glsl — scene-linear to display-referred encoding.
// TEMPORARY (until the OpenColorIO issue lands): a plain sRGB encoding (IEC 61966-2-1 OETF) of the
// clamped linear value. DESIGN section 3 asks for the OCIO ACES view transform; it will replace
// display_encode() here and in the CPU path, and T is compared on these values.
#ifndef TASLAB_DISPLAY_GLSL
#define TASLAB_DISPLAY_GLSL

vec3 display_encode(vec3 linear_rgb)
{
	vec3 c = clamp(linear_rgb, 0.0, 1.0);
	vec3 lo = 12.92 * c;
	vec3 hi = 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055;
	return mix(hi, lo, lessThanEqual(c, vec3(0.0031308)));
}

#endif
