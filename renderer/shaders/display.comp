#version 460
#extension GL_GOOGLE_include_directive : require
// display.comp — display-referred 8-bit image from the scene-linear HDR target (sky where alpha = 0).
// The 8-bit value is round(255 * display_encode(hdr)), the same quantisation as the PNG frames.
#include "display.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba16f) uniform readonly image2D hdr;
layout(set = 0, binding = 1, rgba8) uniform writeonly image2D display;

void main()
{
	ivec2 p = ivec2(gl_GlobalInvocationID.xy);
	if (any(greaterThanEqual(p, imageSize(hdr))))
		return;
	vec4 c = imageLoad(hdr, p);
	imageStore(display, p, vec4(display_encode(c.rgb), 1.0));
}
