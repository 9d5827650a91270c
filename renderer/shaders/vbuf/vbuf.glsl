// vbuf.glsl - resources and helpers of the compacted sample path (renderer/src/passes/vbuf.c; BASELINES.md
// section 0): decide per pixel, append the samples to shade to a list (select), shade the listed samples only with
// an indirect dispatch (shade), then copy or interpolate per pixel (resolve). Needs common/common.glsl first.
//
// A sample is (location, object, triangle, footprint w x h): it lives at its *leader* pixel p (the first pixel of
// its coarse pixel, in raster order, covered by the same object and triangle), and its location is the centre of
// the coarse pixel ([V] sec. 3, Fig. 3.2: the plane is extrapolated where that centre leaves the triangle). Its
// shaded value is stored at p in `svals`, so every value has one writer and the frame does not depend on the
// order of the list (atomic appends).
#ifndef TASLAB_VBUF_GLSL
#define TASLAB_VBUF_GLSL

layout(std430, set = 1, binding = 0) readonly buffer Vertices { float vtx[]; };   // the scene's (vertex_pull.glsl)
layout(std430, set = 1, binding = 1) readonly buffer Indices { uint indices[]; };
layout(std430, set = 1, binding = 2) readonly buffer ObjInfo { uvec4 obj_info[]; }; // per object: first index, vertex offset
layout(std430, set = 1, binding = 3) buffer List { uvec2 list[]; };                 // samples: x | y << 16, w | h << 8
// 0 appended this round, 1 listed this round (shade's bound), 2-4 the VkDispatchIndirectCommand of the shade,
// 5 samples shaded (counted by the shading), 6 pixels interpolated (ads), 7 pixels filled by a copy (resolve),
// 8 late pixels (--truth, truth.comp.in), 9 samples listed in the frame (all rounds), 10-15 method counters
layout(std430, set = 1, binding = 4) buffer Counters { uint count[16]; };
layout(std430, set = 1, binding = 5) buffer Rates { uint rate[]; };                 // per 16x16 tile: w | h << 8
layout(set = 1, binding = 6, rgba32ui) uniform readonly uimage2D ids;              // passes/ids.h
layout(set = 1, binding = 7, rgba16f) uniform image2D svals;                       // shaded (and ads: interpolated) values
layout(set = 1, binding = 8, rgba16f) uniform image2D hdr;

#include "common/vertex_pull.glsl"

const uint VBUF_TILE = 16u;

#include "vbuf/plane.glsl"

#ifdef VBUF_ADS_DISPLAY
// ads (shade.comp.in with ADS, ads_select.comp.in; after the OCIO display transform): the display code values (0..255)
// of each covered pixel's value in svals, stored once where the value is made - by the shade pass for a shaded pixel,
// by ads_display.comp.in for an interpolated one; none for the last step's pixels, which no later step reads - and
// read by the later selects' variance of a candidate's neighbours, instead of transforming four neighbours per
// candidate in each of the five rounds. They are computed from the value read back from svals (its half rounding, as
// the neighbours' svals were read before), in fixed point in RG32UI (tas/disp.glsl: within 6.2e-5 code values; an
// RGBA32F texel cost four channel accesses on lavapipe).
#include "tas/disp.glsl"
layout(set = 1, binding = 9, rg32ui) uniform uimage2D sdisp;

vec3 vbuf_display_cv(vec3 c)
{
	return clamp(ocio_display(vec4(c, 1.0)).rgb, 0.0, 1.0) * 255.0;
}

// After svals[p] is written by this invocation (its own write is visible to its read).
void vbuf_store_display(ivec2 p)
{
	imageStore(sdisp, p, uvec4(disp_pack(vbuf_display_cv(imageLoad(svals, p).rgb)), 0u, 0u));
}
#endif

// Barycentrics w of the sample at q (pixels) of footprint r on the triangle A, B, C of `object` at `slot`, and its
// texture gradients: the differences of uv between the centres of the coarse pixels of its 2x2 coarse quad, in x
// and y from the quad's first one (as the rasterizer's quad derivatives at this rate, so vref's texture LOD is
// ref's; plane.glsl, also the analytic diagnostic).
vec3 vbuf_bary(Vertex A, Vertex B, Vertex C, uint slot, uint object, vec2 q, vec2 size, uvec2 r, out vec2 duv_dx,
	       out vec2 duv_dy)
{
	mat4 m = states[slot].view_proj * object_at(slot, object).world;
	vec4 ca = m * vec4(A.p, 1.0), cb = m * vec4(B.p, 1.0), cc = m * vec4(C.p, 1.0);
	vec3 va = vec3(ca.x, ca.y, ca.w), vb = vec3(cb.x, cb.y, cb.w), vc = vec3(cc.x, cc.y, cc.w);
	vec3 w = vbuf_lambda(va, vb, vc, q, size);
	vec3 dwx, dwy;
	vbuf_plane_diffs(va, vb, vc, q, size, r, dwx, dwy);
	duv_dx = A.uv * dwx.x + B.uv * dwx.y + C.uv * dwx.z;
	duv_dy = A.uv * dwy.x + B.uv * dwy.y + C.uv * dwy.z;
	return w;
}

// The vertices of triangle `tri` of `object` (object info: first index, vertex offset of its mesh).
void vbuf_triangle(uint object, uint tri, out Vertex A, out Vertex B, out Vertex C)
{
	uvec4 oi = obj_info[object];
	uint k = oi.x + 3u * tri;
	A = vertex_at(indices[k] + oi.y);
	B = vertex_at(indices[k + 1u] + oi.y);
	C = vertex_at(indices[k + 2u] + oi.y);
}

// The rate (footprint) of the tile holding pixel p.
uvec2 vbuf_rate(ivec2 p, ivec2 size)
{
	uint tiles_x = (uint(size.x) + VBUF_TILE - 1u) / VBUF_TILE;
	uint code = rate[(uint(p.y) / VBUF_TILE) * tiles_x + uint(p.x) / VBUF_TILE];
	return uvec2(code & 0xFFu, (code >> 8) & 0xFFu);
}

// The leader of pixel p (object + 1 and triangle `id`) in its coarse pixel of footprint r: the first pixel in raster
// order with the same object and triangle. Rates are powers of two dividing the tile, so coarse pixels are aligned.
ivec2 vbuf_leader(ivec2 p, uvec2 id, ivec2 size, uvec2 r)
{
	ivec2 o = p - (p % ivec2(r));
	for (int y = o.y; y <= p.y; y++)
		for (int x = o.x; x < o.x + int(r.x); x++) {
			if (y == p.y && x >= p.x)
				return p;
			if (x < size.x && y < size.y && imageLoad(ids, ivec2(x, y)).xy == id)
				return ivec2(x, y);
		}
	return p;
}

// The mean of the pixel centres of the coarse pixel (footprint r) holding p that show the primitive `id` (object + 1,
// triangle): the centroid location of [V] sec. 3 (BASELINES.md A7 --centroid).
vec2 vbuf_centroid(ivec2 p, uvec2 id, ivec2 size, uvec2 r)
{
	ivec2 o = p - (p % ivec2(r));
	vec2 sum = vec2(0.0);
	float n = 0.0;
	for (int y = o.y; y < o.y + int(r.y); y++)
		for (int x = o.x; x < o.x + int(r.x); x++)
			if (x < size.x && y < size.y && imageLoad(ids, ivec2(x, y)).xy == id) {
				sum += vec2(x, y) + 0.5;
				n += 1.0;
			}
	return n > 0.0 ? sum / n : vec2(p) + 0.5;
}

// The workgroup's wanting invocations each get one of consecutive indices counted in count[k] (and, with `listed`,
// also in count[9]), with one global atomic per workgroup; every invocation calls it (uniform control flow).
shared uint vbuf_wg_count, vbuf_wg_base;
uint vbuf_wg_reserve(bool want, uint k, bool listed)
{
	if (gl_LocalInvocationIndex == 0u)
		vbuf_wg_count = 0u;
	barrier();
	uint slot = 0u;
	if (want)
		slot = atomicAdd(vbuf_wg_count, 1u);
	barrier();
	if (gl_LocalInvocationIndex == 0u && vbuf_wg_count > 0u) {
		vbuf_wg_base = atomicAdd(count[k], vbuf_wg_count);
		if (listed)
			atomicAdd(count[9], vbuf_wg_count);
	}
	barrier();
	return vbuf_wg_base + slot;
}

// Appends sample (p, footprint r) to the list; every invocation of the workgroup calls it (uniform control flow),
// `want` says whether it has a sample.
void vbuf_append(bool want, ivec2 p, uvec2 r)
{
	uint i = vbuf_wg_reserve(want, 0u, true);
	if (want)
		list[i] = uvec2(uint(p.x) | uint(p.y) << 16, r.x | r.y << 8);
}

// The list entry of this invocation of an indirect dispatch over a list (64 a workgroup, the 2-D grid of vbuf_grid).
uint vbuf_list_index()
{
	return (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64u + gl_LocalInvocationIndex;
}

// The 2-D grid of `groups` workgroups within the 65 535 a dimension may count: as few rows as fit, the groups spread
// evenly over them, so that no more than y - 1 empty workgroups are launched.
uvec2 vbuf_grid(uint groups)
{
	uint gy = max((groups + 65534u) / 65535u, 1u);
	return uvec2((groups + gy - 1u) / gy, gy);
}

#ifdef ADS
// ads: the pixels a select step interpolated, appended from the list's top end down (entry W H - 1 - i) and counted
// in count[10], so that their display values are made by a pass over them alone (ads_display.comp.in) instead of in a
// branch of the select, which a SIMD CPU driver runs for every pixel of the step. A step's shaded and interpolated
// pixels together are at most its lattice's, fewer than W H: the two ends never meet. Uniform control flow.
void vbuf_append_interp(bool want, ivec2 p)
{
	uint i = vbuf_wg_reserve(want, 10u, false);
	ivec2 size = imageSize(ids);
	if (want)
		list[uint(size.x * size.y) - 1u - i] = uvec2(uint(p.x) | uint(p.y) << 16, 0x101u);
}
#endif

// Adds a per-invocation 0/1 to counter k with one atomic per workgroup (uniform control flow).
shared uint vbuf_wg_sum;
void vbuf_count(bool yes, uint k)
{
	if (gl_LocalInvocationIndex == 0u)
		vbuf_wg_sum = 0u;
	barrier();
	if (yes)
		atomicAdd(vbuf_wg_sum, 1u);
	barrier();
	if (gl_LocalInvocationIndex == 0u && vbuf_wg_sum > 0u)
		atomicAdd(count[k], vbuf_wg_sum);
}

#endif
