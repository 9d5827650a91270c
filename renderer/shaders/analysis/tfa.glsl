// tfa.glsl - resources of the TFR analysis (renderer/src/analyze.c, taslab/analyze.h), descriptor set 1.
// Per-pixel state of the history scan, per threshold T_i (array layer i):
//   A[i] = (s_k1.rgb, g_single)            s_k1: display value at the first exceedance k1
//   B[i] = (k1, k2, g_inst, g_long)        0 = not found yet
// Gradients are in 8-bit code values per frame. G[i] = (g_single, g_long, g_inst, D) after the scan,
// L1/L2 the 8x8 max-downsampled and then 9x9 max-filtered gradients.
#ifndef TASLAB_TFA_GLSL
#define TASLAB_TFA_GLSL

#define TFA_MAX_T 8
#define TFA_HISTORY 120
#define TFA_K 119
#define TFA_PREDICTORS 6
#define TFA_CLASSES 4

layout(set = 1, binding = 0, rgba32f) uniform image2D s0_img;     // display s_0, w = coverage
layout(set = 1, binding = 1, rgba32f) uniform image2D prev_img;   // display s_(k-1)
layout(set = 1, binding = 2, rgba32f) uniform image2DArray a_img;
layout(set = 1, binding = 3, rgba32f) uniform image2DArray b_img;
layout(set = 1, binding = 4, rgba32ui) uniform uimage2D vis_img;  // t-1 visibility records (tas.glsl)
layout(set = 1, binding = 5, rgba32f) uniform image2DArray g_img;
layout(set = 1, binding = 6, rgba32f) uniform image2DArray l1_img;
layout(set = 1, binding = 7, rgba32f) uniform image2DArray l2_img;
layout(std430, set = 1, binding = 8) buffer Analysis {
	float thresholds[TFA_MAX_T];
	uint threshold_count;
	uint visible;
	uint visible_prev;
	uint want_inst;                                        // host: instantaneous derivatives wanted
	uint need_inst;                                        // step found first exceedances (derivative pass due)
	uint pad0, pad1, pad2;                                 // mirror of tfa_buffer in analyze.c
	uint hist[TFA_MAX_T * (TFA_HISTORY + 1)];              // coherent length L = k1 - 1 (or 120)
	uint classes[TFA_MAX_T * TFA_PREDICTORS * TFA_CLASSES]; // late, early, on time, unchanged
} an;

#endif
