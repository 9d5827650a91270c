#version 460
#extension GL_GOOGLE_include_directive : require
// tfa_grad.comp - TFR analysis after the scan: per pixel and T, the true deadline D and the three gradient
// estimates (G), and the coherent length histogram (Fig. 4). Background pixels (coverage 0) count nowhere.
#include "analysis/tfa.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

void main()
{
	ivec2 p = ivec2(gl_GlobalInvocationID.xy);
	if (any(greaterThanEqual(p, imageSize(s0_img))))
		return;
	bool covered = imageLoad(s0_img, p).w > 0.0;
	for (uint i = 0u; i < an.threshold_count; i++) {
		vec4 a = imageLoad(a_img, ivec3(p, i)), b = imageLoad(b_img, ivec3(p, i));
		uint k1 = covered ? uint(b.x) : 0u;
		vec4 g = vec4(0.0);
		if (covered) {
			uint len = k1 == 0u ? uint(TFA_HISTORY) : k1 - 1u;
			atomicAdd(an.hist[i * (TFA_HISTORY + 1) + len], 1u);
			if (k1 >= 1u && k1 <= uint(TFA_K)) // unchanged within K: no deadline, no gradient
				g = vec4(a.w, b.y > 0.0 ? b.w : 0.0, b.z, float(k1));
		}
		imageStore(g_img, ivec3(p, i), g);
	}
}
