// shade.glsl - reference forward shading (method `ref`): every visible sample, every frame.
// Writes scene-linear radiance (times exposure) with coverage in alpha. Specialised per alpha mode:
// ALPHA_BLEND outputs the material alpha for "over" blending (glTF alphaMode BLEND).
// Compiled as ref/shade.frag (one counter atomic per fragment), ref/shade_sg.frag and ref/shade_sg_nohelp.frag
// (one per subgroup, ref/count.glsl), chosen by the device (frame/pipeline.c render_count_mode).
#include "common/shading.glsl"
#include "ref/count.glsl"

layout(location = 0) in vec3 v_position;
layout(location = 1) in vec3 v_normal;
layout(location = 2) in vec2 v_uv;
layout(location = 3) in vec4 v_tangent;

layout(location = 0) out vec4 o_hdr;

layout(constant_id = 0) const bool ALPHA_BLEND = false;

void main()
{
	Surface s = surface_at(pc.slot, pc.object, v_position, v_normal, v_tangent, v_uv, gl_FrontFacing);
	vec3 c = shade_lights(pc.slot, s) * states[pc.slot].ambient_exposure.w;
	o_hdr = vec4(c, ALPHA_BLEND ? s.alpha : 1.0);
	if (!ALPHA_BLEND)
		count_shading();
}
