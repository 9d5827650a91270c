// atlas.glsl - resources and geometry of the shading-atlas methods sa, sau, tasa (renderer/src/methods/atlas.c;
// TAS-METHODS sections 4-6). Needs common/common.glsl before it.
//
// A pid is a pair of triangles (or one) sharing a block of 2^lw x 2^lh texels in the atlas. Corner-aligned
// layout: texel (i, j) of a W x H block is the surface point at u = i / (W - 1), v = j / (H - 1), so border texels
// lie on the pid's edges and bilinear lookups never leave the block. Side A (u + v <= 1, or a single triangle):
// barycentrics (1 - u - v, u, v) over corners (a0, a1, a2); side B: (u + v - 1, 1 - u, 1 - v) over (b0, a2, a1).
#ifndef TASLAB_ATLAS_GLSL
#define TASLAB_ATLAS_GLSL

const uint SINGLE = 0xFFFFFFFFu;

layout(std430, set = 1, binding = 0) readonly buffer Patches { uvec4 corners[]; };  // a0 a1 a2 b0: vertex indices
layout(std430, set = 1, binding = 1) readonly buffer TriInfo { uint tri_info[]; };  // pid << 3 | side << 2 | rot
// per object, two entries: [2o] pid base, mesh pid base, mesh triangle base, 1 if it has patches; [2o + 1] unused
// (it held the mesh's first index and vertex offset for the ids pass, which takes them as push constants now)
layout(std430, set = 1, binding = 2) readonly buffer ObjInfo { uvec4 obj_info[]; };
// per pid: corner x | y << 16; lw | lh << 8 | age << 16 (frames since its last shading, 0 = new); mesh pid; object
layout(std430, set = 1, binding = 3) readonly buffer Blocks { uvec4 blocks[]; };
layout(std430, set = 1, binding = 4) readonly buffer Work { uvec2 work[]; };        // chunks of 8 texels: pid, first texel
layout(std430, set = 1, binding = 5) buffer Visible { uint visible[]; };            // per pid: bit v, seen by view v
layout(std430, set = 1, binding = 6) readonly buffer Grad { float G[]; };           // tasa: per pid, last frame
layout(std430, set = 1, binding = 7) buffer Filtered { uint F[]; };                 // tasa: 2x2 image max (float bits)
layout(std430, set = 1, binding = 8) buffer GradNew { uint Gnew[]; };               // tasa: max g of the shading (bits)
layout(std430, set = 1, binding = 9) buffer Counters { uint count[8]; };            // 0 committed blocks, 1 their texels, 2 late texels, 3 texels shaded by shade.comp, 4/5 of those in blocks the left/right eye sees
layout(std430, set = 1, binding = 11) buffer DMax { uint dmax[]; };                 // oracle: per pid max d (bits)
layout(set = 1, binding = 12, rgba32ui) uniform readonly uimage2D ids;             // the ids pass (passes/ids.h)
layout(set = 1, binding = 13, rgba16f) uniform image2D atlas;
layout(set = 1, binding = 14, rgba16f) uniform image2D scratch;                    // oracle
layout(set = 1, binding = 15, rgba16f) uniform image2D hdr;
layout(set = 1, binding = 17, rg32ui) uniform uimage2D shown; // tasa: display code values of the atlas (disp_pack)
layout(std430, set = 1, binding = 10) readonly buffer Vertices { float vtx[]; };    // common/vertex_pull.glsl
layout(std430, set = 1, binding = 16) readonly buffer Indices { uint indices[]; }; // unused since the ids pass moved (issue 30.4)

// Push constants (pc.aux): [0] work chunks offset, [1] chunk count, [2] frame number, [3] T (float bits).

#include "common/vertex_pull.glsl"

// The block of a pid: corner and size in texels.
void block_of(uint pid, out uvec2 origin, out uvec2 size)
{
	uvec4 b = blocks[pid];
	origin = uvec2(b.x & 0xFFFFu, b.x >> 16);
	size = uvec2(1u << (b.y & 0xFFu), 1u << ((b.y >> 8) & 0xFFu));
}

const uint NO_PATCH = 0xFFFFFFFFu;

// The pid of the surface visible at pixel p (the id pass), or NO_PATCH for the background; also the
// triangle's side and rotation in its pid and its barycentrics in index order. The ids pass writes the pid with the
// side and rotation (passes/ids.h, IDS_PATCHES: looked up per vertex there), so this reads the image only.
uint patch_at(ivec2 p, out uint info, out vec3 bary)
{
	uvec4 id = imageLoad(ids, p);
	info = 0u;
	bary = vec3(1.0, 0.0, 0.0);
	if (id.x == 0u)
		return NO_PATCH;
	info = id.y & 7u;
	float b1 = uintBitsToFloat(id.z), b2 = uintBitsToFloat(id.w);
	bary = vec3(1.0 - b1 - b2, b1, b2);
	return id.y >> 3;
}

// Side and barycentrics of block coordinates (u, v) of a pid with corners c: the three vertices (indices) and
// the weights. Singles use side A everywhere (the B half extrapolates A's plane).
void patch_point(uvec4 c, vec2 uv, out uvec3 tri, out vec3 w)
{
	if (c.w == SINGLE || uv.x + uv.y <= 1.0) {
		tri = c.xyz;
		w = vec3(1.0 - uv.x - uv.y, uv.x, uv.y);
	} else {
		tri = uvec3(c.w, c.z, c.y);
		w = vec3(uv.x + uv.y - 1.0, 1.0 - uv.x, 1.0 - uv.y);
	}
}

#endif
