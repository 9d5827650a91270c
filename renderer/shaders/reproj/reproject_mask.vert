#version 460
#extension GL_GOOGLE_include_directive : require
// reproject_mask.vert - the rrc/tarc depth pre-pass's vertex shader for alpha-masked objects (reproject_vert.glsl).
#define MASK 1
#include "reproj/reproject_vert.glsl"
