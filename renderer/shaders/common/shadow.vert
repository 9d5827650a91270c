#version 460
#extension GL_GOOGLE_include_directive : require
// shadow.vert - renders depth from a light's view into shadow layer pc.layer (depth only, no FS).
#include "common/common.glsl"

layout(location = 0) in vec3 in_position;

void main()
{
	GpuObject o = object_at(pc.slot, pc.object);
	gl_Position = states[pc.slot].shadow_matrix[pc.layer] * (o.world * vec4(in_position, 1.0));
}
