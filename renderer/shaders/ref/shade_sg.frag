#version 460
#extension GL_GOOGLE_include_directive : require
// shade_sg.frag - ref/shade.glsl counting its shading with one atomic per subgroup (ref/count.glsl), helper
// invocations left out.
#define TL_SUBGROUP 1
#include "ref/shade.glsl"
