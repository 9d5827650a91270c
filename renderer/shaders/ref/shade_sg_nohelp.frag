#version 460
#extension GL_GOOGLE_include_directive : require
// shade_sg_nohelp.frag - ref/shade.glsl counting its shading with one atomic per subgroup on llvmpipe, which
// has no helper invocations and cannot compile gl_HelperInvocation (ref/count.glsl).
#define TL_SUBGROUP 1
#define TL_NO_HELPERS 1
#include "ref/shade.glsl"
