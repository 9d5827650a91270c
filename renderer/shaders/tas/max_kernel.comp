#version 460
#extension GL_GOOGLE_include_directive : require
// max_kernel.comp - spatial max filter, step 2 (paper sec. 5.3): 9x9 max kernel on the 8x8-downsampled
// gradients (72x72 pixels in all); the kernel is clipped at the image border.
#include "tas/max_filter.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main()
{
	ivec2 q = ivec2(gl_GlobalInvocationID.xy);
	ivec2 size = imageSize(mid_img).xy;
	if (any(greaterThanEqual(q, size)))
		return;
	for (uint i = 0u; i < mf.layers; i++) {
		vec3 m = vec3(0.0);
		for (int y = -4; y <= 4; y++)
			for (int x = -4; x <= 4; x++) {
				ivec2 p = q + ivec2(x, y);
				if (all(greaterThanEqual(p, ivec2(0))) && all(lessThan(p, size)))
					m = max(m, imageLoad(mid_img, ivec3(p, i)).xyz);
			}
		imageStore(dst_img, ivec3(q, i), vec4(m, 0.0));
	}
}
