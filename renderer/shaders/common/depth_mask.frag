#version 460
#extension GL_GOOGLE_include_directive : require
// depth_mask.frag - alpha-tested depth for glTF alphaMode MASK (depth pre-pass and shadow maps):
// discards where base colour alpha (factor times texture) is below the material's alpha cutoff.
#include "common/common.glsl"

layout(location = 2) in vec2 v_uv;

void main()
{
	GpuMaterial m = materials[object_at(pc.slot, pc.object).material.x];
	float a = m.base_color.a;
	if (m.tex0.x >= 0)
		a *= texture(color_textures, vec3(v_uv, float(m.tex0.x))).a;
	if (a < m.mr_occ_cutoff.w)
		discard;
}
