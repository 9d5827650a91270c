// reproject_vert.glsl - the vertex shader of the rrc/tarc depth pre-pass (reproject.vert; reproject_mask.vert with
// MASK: also the texture coordinates, for the alpha test of glTF alphaMode MASK). gl_Position exactly as
// common/scene.vert computes it (`precise`, same data), so the shading passes test depth EQUAL against it.
// Everything the cache lookup needs from the object's and the camera's matrices is an affine (or, for the clip
// position, linear homogeneous) function of the object-space position, so it is computed here per vertex and
// interpolated perspective-correctly, which is exact for such functions: no fragment shader reads a matrix (on
// lavapipe a storage-buffer matrix read per fragment cost a quarter of the old reproject pass). Push constants:
// aux[0] the previous frame's state slot.
#include "common/common.glsl"

layout(location = 0) in vec3 in_position;
#ifdef MASK
layout(location = 2) in vec2 in_uv;
#endif

layout(location = 0) out vec4 v_prev_clip; // clip position in the previous frame
layout(location = 1) out vec3 v_prev_eye;  // world position minus the camera position, previous frame
layout(location = 2) out vec3 v_cur_eye;   // the same, this frame
#ifdef MASK
layout(location = 3) out vec2 v_uv;
#endif

void main()
{
	GpuObject o = object_at(pc.slot, pc.object);
	precise vec4 world = o.world * vec4(in_position, 1.0);
	precise vec4 clip = states[pc.slot].view_proj * world;
	gl_Position = clip;
	uint prev = pc.aux[0];
	vec4 pw = object_at(prev, pc.object).world * vec4(in_position, 1.0);
	v_prev_clip = states[prev].view_proj * pw;
	v_prev_eye = pw.xyz - states[prev].camera_time.xyz;
	v_cur_eye = world.xyz - states[pc.slot].camera_time.xyz;
#ifdef MASK
	v_uv = in_uv;
#endif
}
