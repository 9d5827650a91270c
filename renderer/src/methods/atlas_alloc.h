/* atlas_alloc.h (private) — the CPU side of the shading-atlas methods sa, sau, tasa (TAS-METHODS section 4):
 * patches (triangle pairs), block sizes from projected edges with hysteresis, and the deterministic shelf +
 * buddy allocator that keeps a block's address while its patch stays visible at the same size. No Vulkan:
 * tests/test_atlas.c checks it directly. */
#ifndef TASLAB_ATLAS_ALLOC_H
#define TASLAB_ATLAS_ALLOC_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "taslab/scene.h"

#define ATLAS_SINGLE UINT32_MAX /* patch corner b0 of a single triangle */

/* ---- patches ([TAS] sec. 6.2: "two triangles packed into a rectangle of 2^N x 2^M texels") ----
 * Per mesh, triangle 2k pairs with 2k+1 when they share an edge (procedural quads), then a greedy pass over
 * an edge map pairs each unpaired triangle, in index order, with an unpaired neighbour across its longest
 * shared edge; the rest are single patches. A patch has corners a0 (unshared vertex of triangle A), a1, a2
 * (the shared edge, in A's winding) and b0 (B's unshared vertex); block corners (0,0)=a0, (1,0)=a1, (0,1)=a2,
 * (1,1)=b0. Triangle info: patch-in-mesh << 3 | side (0 A, 1 B) << 2 | rotation r, where the triangle's index
 * position (r + k) mod 3 holds its corner k (A: a0 a1 a2; B: b0 a2 a1). */
typedef struct atlas_patches {
	size_t mesh_count;
	uint32_t *mesh_patch_base; /* per mesh: first patch in `corners` */
	uint32_t *mesh_tri_base;   /* per mesh: first triangle in `tri_info` */
	uint32_t *corners;         /* 4 per patch: a0, a1, a2, b0 (mesh-local vertex indices; b0 ATLAS_SINGLE) */
	uint32_t *tri_info;        /* per triangle */
	size_t patch_total, tri_total;
	size_t paired;             /* patches made of two triangles */
} atlas_patches;

int atlas_patches_build(const scene *s, atlas_patches *out, char *err, size_t err_size);
void atlas_patches_free(atlas_patches *p);

/* ---- block sizes ---- */
/* Lengths in pixels of the patch's u and v edges (Lu = max(|a1-a0|, |b0-a2|), Lv = max(|a2-a0|, |b0-a1|);
 * singles: the two legs) from the corners in clip space (x, y, z, w of a0, a1, a2, b0), clipped to w >= 1e-5 (the near side). */
void atlas_edge_lengths(const float *clip, bool single, uint32_t width, uint32_t height, float *lu, float *lv);
/* log2 size of a side of length L pixels at density rho texels per pixel: clamp(ceil(log2(rho L + 1)), 1, lmax)
 * with hysteresis around the current level `cur` (0: none): kept while log2(rho L + 1) lies in
 * (cur - 1.25, cur + 0.25]. *clamped is set when the unclamped level exceeds lmax. */
uint32_t atlas_level(float length, float rho, uint32_t lmax, uint32_t cur, bool *clamped);
/* The hysteresis band of atlas_level, in levels below and above the current one (recorded in the manifest). */
#define ATLAS_HYSTERESIS_BELOW 1.25f
#define ATLAS_HYSTERESIS_ABOVE 0.25f

/* ---- the allocator: shelves of one power-of-two height handed out by a buddy over the atlas rows, blocks
 * inside a shelf by a buddy over the atlas width; lowest address first; empty shelves go back. ---- */
typedef struct atlas_alloc atlas_alloc;

/* width and height powers of two (>= 2). */
int atlas_alloc_create(uint32_t width, uint32_t height, atlas_alloc **out, char *err, size_t err_size);
void atlas_alloc_destroy(atlas_alloc **a);
/* A block of 2^lw x 2^lh texels: its corner, or false when it does not fit. */
bool atlas_alloc_block(atlas_alloc *a, uint32_t lw, uint32_t lh, uint32_t *x, uint32_t *y);
void atlas_alloc_free(atlas_alloc *a, uint32_t x, uint32_t y, uint32_t lw, uint32_t lh);
/* Texels in use (sum of the live blocks' areas). */
uint64_t atlas_alloc_used(const atlas_alloc *a);

#endif
