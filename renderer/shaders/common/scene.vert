#version 460
#extension GL_GOOGLE_include_directive : require
// scene.vert - transforms object-space vertices with the state slot's matrices. Used by the depth
// pre-pass and the shading pass alike; the position is computed `precise` (no contraction or
// reassociation) so both pipelines produce bit-identical depth and the shading pass can test with
// EQUAL and shade each visible sample exactly once. (`invariant gl_Position` would say the same, but
// the validation layer's SPIR-V checker in Debian 12 flags glslang's encoding of it.)
#include "common/common.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) in vec4 in_tangent;

layout(location = 0) out vec3 v_position; // object space
layout(location = 1) out vec3 v_normal;   // object space
layout(location = 2) out vec2 v_uv;
layout(location = 3) out vec4 v_tangent;  // object space, w = bitangent sign

void main()
{
	GpuObject o = object_at(pc.slot, pc.object);
	precise vec4 world = o.world * vec4(in_position, 1.0);
	precise vec4 clip = states[pc.slot].view_proj * world;
	gl_Position = clip;
	v_position = in_position;
	v_normal = in_normal;
	v_uv = in_uv;
	v_tangent = in_tangent;
}
