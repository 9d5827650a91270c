#version 460
#extension GL_GOOGLE_include_directive : require
// shade.frag - ref/shade.glsl counting its shading with one atomic per fragment (devices without ballot
// subgroup operations in fragment shaders, or TASLAB_COUNT_ATOMICS=1).
#include "ref/shade.glsl"
