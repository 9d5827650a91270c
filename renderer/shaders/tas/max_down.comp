#version 460
#extension GL_GOOGLE_include_directive : require
// max_down.comp - spatial max filter, step 1 (paper sec. 5.3): max of the gradients over 8x8 pixel
// blocks aligned to the image origin (blocks at the border are clipped).
#include "tas/max_filter.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main()
{
	ivec2 q = ivec2(gl_GlobalInvocationID.xy);
	if (any(greaterThanEqual(q, imageSize(mid_img).xy)))
		return;
	ivec2 size = imageSize(src_img).xy;
	for (uint i = 0u; i < mf.layers; i++) {
		vec3 m = vec3(0.0);
		for (int y = 0; y < 8; y++)
			for (int x = 0; x < 8; x++) {
				ivec2 p = q * 8 + ivec2(x, y);
				if (all(lessThan(p, size)))
					m = max(m, imageLoad(src_img, ivec3(p, i)).xyz);
			}
		imageStore(mid_img, ivec3(q, i), vec4(m, 0.0));
	}
}
