#version 460
#extension GL_GOOGLE_include_directive : require
// max_down_state.comp - tarc's step 1 of the spatial max filter (tas/max_down.comp; paper sec. 5.3): the max over
// 8x8 pixel blocks of G, the gradients of the steady samples, read from the provisional cache state the reproject
// pass wrote (reproject.frag.in): g = state.w for a covered sample that is neither new nor in its second frame,
// else 0 — what the reproject pass used to store into a G image per sample (a fragment-shader storage store per
// sample; here one compute load). (New samples and those in their second frame carry w = 0 anyway: the first shading
// stores g = 0; the test states the rule, not that coincidence.) Writes the 8x8 level as tas/max_down.comp does (g
// in .x), for max_kernel.comp.
#include "reproj/state_bits.glsl"

layout(set = 0, binding = 0, rgba32ui) uniform readonly uimage2D state_img; // the next cache's state
layout(set = 0, binding = 1, rgba32f) uniform image2DArray mid_img;          // 8x8 max, ceil(W/8) x ceil(H/8) x 1
layout(push_constant) uniform MaxFilterPush { uint layers; } mf;           // 1

layout(local_size_x = 8, local_size_y = 8) in;

void main()
{
	ivec2 q = ivec2(gl_GlobalInvocationID.xy);
	if (any(greaterThanEqual(q, imageSize(mid_img).xy)))
		return;
	ivec2 size = imageSize(state_img);
	float m = 0.0;
	for (int y = 0; y < 8; y++)
		for (int x = 0; x < 8; x++) {
			ivec2 p = q * 8 + ivec2(x, y);
			if (all(lessThan(p, size))) {
				uvec4 st = imageLoad(state_img, p);
				if (st.x != 0u && (st.z & (NEW_BIT | PHASE_BIT)) == 0u)
					m = max(m, uintBitsToFloat(st.w));
			}
		}
	imageStore(mid_img, ivec3(q, 0), vec4(m, 0.0, 0.0, 0.0));
}
