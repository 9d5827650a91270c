// vrs.glsl - the rate selection of the VRS methods (casedge, castexel, mas, fovea, taas; BASELINES.md A7, [V]
// chapter 4), set 2 of their passes (renderer/src/methods/vrs.c). Needs common/common.glsl and vbuf/vbuf.glsl first.
//
// Per 16x16 tile a palette index 0..10 (S: two halves of `index`, the current frame's and the previous one's, which
// swap every frame: Alg. 4.1 reads S as "previous" after clearing it, so S is double-buffered). The history images
// hold what frame t-1 left for the rate pass of frame t (written by history.comp.in at the end of each frame; hist_aux
// by the ids pass of frame t-1, common/ids.frag.in IDS_VRS_AUX; taas's two colour images swap every frame, vrs.c;
// casedge reads frame t-1's displayed image, which the display pass wrote).
#ifndef TASLAB_VRS_GLSL
#define TASLAB_VRS_GLSL

layout(std430, set = 2, binding = 0) buffer Index { int sidx[]; };          // 2 x tiles: [half * tiles + tile]
#ifdef CASEDGE
// casedge: the frame t-1 as shown, the display pass's RGBA8 image itself (vrs.c binds it; FXAA reads an LDR frame)
layout(set = 2, binding = 1, rgba8) uniform readonly image2D hist_color;
#else
layout(set = 2, binding = 1, rgba16f) uniform image2D hist_color;          // display values 0..1 of frame t-1
#endif
layout(set = 2, binding = 2, rgba16f) uniform image2D hist_color2;         // ... of frame t-2
layout(set = 2, binding = 3, rgba32f) uniform image2D hist_pos;            // world position at t-1, w: covered
layout(set = 2, binding = 4, rgba32f) uniform image2D hist_aux;            // xy motion t-2 -> t-1 (pixels), z texel density
layout(std430, set = 2, binding = 5) buffer TileDebug { vec4 tile_dbg[]; }; // per tile: P', r, sr, target tile (tests)

// Push constants of the VRS passes: aux[0] the current half of `index` (0/1), aux[1] 1 when the history holds a
// frame (t >= 1), aux[2] 1 when it holds two (t >= 2), aux[3] method parameter bits (fovea: packed gaze).

// The palette [P]: indices 0-2 -> 4x4, 3-5 -> 2x2, 6-10 -> 1x1 ([V] sec. 4.1: "index zero denotes a coarse shading
// rate of 4x4 and index ten a supersampling shading rate of x8"; the rates of Table 5.1 at 1x MSAA).
// VRS_RATES_ALL (--rates all) [P]: the seven rates of the palette at 1x MSAA in ascending shading density,
// 0-1 -> 4x4, 2 -> 4x2, 3 -> 2x4, 4-5 -> 2x2, 6 -> 2x1, 7 -> 1x2, 8-10 -> 1x1 (w x h).
uint vrs_palette(int i)
{
#ifdef VRS_RATES_ALL
	const uint all_rates[11] = uint[11](4u | 4u << 8, 4u | 4u << 8, 4u | 2u << 8, 2u | 4u << 8, 2u | 2u << 8,
					     2u | 2u << 8, 2u | 1u << 8, 1u | 2u << 8, 1u | 1u << 8, 1u | 1u << 8, 1u | 1u << 8);
	return all_rates[clamp(i, 0, 10)];
#else
	return i <= 2 ? (4u | 4u << 8) : i <= 5 ? (2u | 2u << 8) : (1u | 1u << 8);
#endif
}

#endif
