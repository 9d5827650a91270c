#version 460
#extension GL_GOOGLE_include_directive : require
// tfa_maxdown.comp - spatial max filter, step 1 (paper sec. 5): max of the gradients over 8x8 pixel blocks.
#include "tfa.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main()
{
	ivec2 q = ivec2(gl_GlobalInvocationID.xy);
	if (any(greaterThanEqual(q, imageSize(l1_img).xy)))
		return;
	ivec2 size = imageSize(g_img).xy;
	for (uint i = 0u; i < an.threshold_count; i++) {
		vec3 m = vec3(0.0);
		for (int y = 0; y < 8; y++)
			for (int x = 0; x < 8; x++) {
				ivec2 p = q * 8 + ivec2(x, y);
				if (all(lessThan(p, size)))
					m = max(m, imageLoad(g_img, ivec3(p, i)).xyz);
			}
		imageStore(l1_img, ivec3(q, i), vec4(m, 0.0));
	}
}
