// disp.glsl - display code values kept between shadings (tarc's disp, reproj/reproj.glsl; tasa's shown,
// atlas/atlas.glsl) in fixed point in two 32-bit channels, R and G in 1/8192, B in 1/16384 code value, so a difference
// d taken against them is within 6.2e-5 code values of the floats' (issue 32.1: an RGBA32F texel cost lavapipe four
// channel accesses per load and store, ~4 ms a pass at 960x540).
#ifndef TASLAB_DISP_GLSL
#define TASLAB_DISP_GLSL

// [0, 255] <-> RG32UI: x = R (21 bits) | B's low 11 bits << 21, y = G | B's high 11 bits << 21
uvec2 disp_pack(vec3 cv)
{
	// masked to their fields, so that nothing (a value past 255, a NaN's undefined conversion) spills into another
	uvec3 q = uvec3(round(clamp(cv, 0.0, 255.0) * vec3(8192.0, 8192.0, 16384.0))) & uvec3(0x1FFFFFu, 0x1FFFFFu, 0x3FFFFFu);
	return uvec2(q.r | (q.b & 0x7FFu) << 21, q.g | (q.b >> 11) << 21);
}
vec3 disp_unpack(uvec2 u)
{
	return vec3(float(u.x & 0x1FFFFFu) / 8192.0, float(u.y & 0x1FFFFFu) / 8192.0,
		    float((u.x >> 21) | (u.y >> 21) << 11) / 16384.0);
}

#endif
