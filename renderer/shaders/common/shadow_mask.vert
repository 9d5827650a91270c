#version 460
#extension GL_GOOGLE_include_directive : require
// shadow_mask.vert - shadow.vert plus the UV that depth_mask.frag needs for alpha-tested casters.
#include "common/common.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 2) in vec2 in_uv;
layout(location = 2) out vec2 v_uv;

void main()
{
	GpuObject o = object_at(pc.slot, pc.object);
	gl_Position = states[pc.slot].shadow_matrix[pc.layer] * (o.world * vec4(in_position, 1.0));
	v_uv = in_uv;
}
