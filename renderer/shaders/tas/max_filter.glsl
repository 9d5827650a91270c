// max_filter.glsl - resources of the spatial max filter (renderer/src/passes/tas_filter.c; paper secs. 5.3,
// 6.1: "a downsampling factor of 8x8, followed by a filter of size 9x9 (overall touching 72x72 pixels)").
// The gradients are per-channel maxima in .xyz (w is ignored and written 0), one 2D-array layer per
// threshold (TFR analysis) or a single layer (tarc).
#ifndef TASLAB_MAX_FILTER_GLSL
#define TASLAB_MAX_FILTER_GLSL

layout(set = 0, binding = 0, rgba32f) uniform readonly image2DArray src_img; // W x H gradients
layout(set = 0, binding = 1, rgba32f) uniform image2DArray mid_img;          // 8x8 max, ceil(W/8) x ceil(H/8)
layout(set = 0, binding = 2, rgba32f) uniform writeonly image2DArray dst_img; // 9x9 max of mid
layout(push_constant) uniform MaxFilterPush { uint layers; } mf;

#endif
