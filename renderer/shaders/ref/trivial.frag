#version 460
#extension GL_GOOGLE_include_directive : require
// trivial.frag - benchmark stand-in for shade.frag: same inputs and outputs, base colour only.
// scripts/bench-render swaps it in to measure the share of frame time spent in shading.
#include "common/common.glsl"
#include "ref/count.glsl"

layout(location = 0) in vec3 v_position;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in vec2 v_uv;
layout(location = 3) in vec4 v_tangent;

layout(location = 0) out vec4 o_hdr;

void main()
{
	GpuMaterial m = materials[object_at(pc.slot, pc.object).material.x];
	o_hdr = vec4(m.base_color.rgb * states[pc.slot].ambient_exposure.w, 1.0);
	count_shading(); // as shade.frag, so that the benchmark's stand-in does the same counting work
}
