#version 460
#extension GL_GOOGLE_include_directive : require
// reproject.vert - the rrc/tarc depth pre-pass's vertex shader for opaque objects (reproject_vert.glsl).
#include "reproj/reproject_vert.glsl"
