#version 460
#extension GL_GOOGLE_include_directive : require
// tfa_classify.comp - predictor evaluation (DESIGN section 4, paper Figs. 7, 9): predicted deadline
// d = T/g clamped to [1, 118] (g = 0: 118); late if d > D, early if d < D - 1, else on time; samples
// without a change within K are unchanged. Predictors: single, long, inst, then the same filtered.
#include "analysis/tfa.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

uint classify(float T, float g, float D)
{
	float d = g > 0.0 ? clamp(T / g, 1.0, 118.0) : 118.0;
	return d > D ? 0u : d < D - 1.0 ? 1u : 2u;
}

void main()
{
	ivec2 p = ivec2(gl_GlobalInvocationID.xy);
	if (any(greaterThanEqual(p, imageSize(s0_img))) || imageLoad(s0_img, p).w == 0.0)
		return;
	for (uint i = 0u; i < an.threshold_count; i++) {
		vec4 g = imageLoad(g_img, ivec3(p, i));
		vec3 gf = imageLoad(l2_img, ivec3(p / 8, i)).xyz;
		uint base = i * TFA_PREDICTORS * TFA_CLASSES;
		for (uint pr = 0u; pr < 6u; pr++) {
			uint c = 3u;
			if (g.w > 0.0)
				c = classify(an.thresholds[i], pr < 3u ? g[pr] : gf[pr - 3u], g.w);
			atomicAdd(an.classes[base + pr * TFA_CLASSES + c], 1u);
		}
	}
}
