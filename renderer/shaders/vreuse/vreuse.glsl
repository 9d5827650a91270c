// vreuse.glsl - the per-pixel cache of temporal reuse on the compacted sample path (renderer/src/methods/vreuse.c;
// BASELINES.md A2, A6). Needs common/common.glsl and vbuf/vbuf.glsl first.
//
// The cache holds an earlier frame (rrc variants: t-1; warp: the keyframe) at state slot pc.aux[0]: per pixel
// (object + 1, view distance bits, the colour as shown before BLEND as three halves) in one texel, so that a tap of
// the lookup is one load (amss keeps its colours in sub-pixel buffers). stu's record is (object + 1, view distance)
// alone, two channels, and its colours live in cache_col (L) and the sub buffers: no lookup, no packed texel.
// Compiled per method: RRC_RANDOM, RRC_INTERLEAVED, WARP, AMSS, STU.
#ifndef TASLAB_VREUSE_GLSL
#define TASLAB_VREUSE_GLSL

layout(set = 2, binding = 0, rgba16f) uniform image2D cache_col;
// the cache's record: stu keeps (object + 1, view distance bits) alone, in two channels (vreuse.c)
#ifdef STU
#define VREUSE_REC_FORMAT rg32ui
#else
#define VREUSE_REC_FORMAT rgba32ui
#endif
layout(set = 2, binding = 1, VREUSE_REC_FORMAT) uniform uimage2D cache_rec;
layout(set = 2, binding = 2, rgba32ui) uniform uimage2D rec_new;   // this frame's record (amss)
layout(set = 2, binding = 3, r32ui) uniform uimage2D flags;        // 1 shaded this frame, 2 a hole (warp)
#ifndef VREUSE_PYR_QUALIFIER
#define VREUSE_PYR_QUALIFIER
#endif
layout(std430, set = 2, binding = 4) VREUSE_PYR_QUALIFIER buffer Pyramid { vec4 pyr[]; }; // pull-push: (rgb, weight) per level texel
// stu: each pixel's normal (float bits) and object + 1 (w), and its world position (float bits) and g (w, float
// bits), from the visibility pass (vis.frag.in VIS_SURFACE; background 0); stu.comp.in STU_G sets g at phase pixels
layout(set = 2, binding = 11, rgba32ui) uniform readonly uimage2D snrm;
layout(set = 2, binding = 12, rgba32ui) uniform uimage2D spos;
// amss: the 2x2 sub-pixel buffers (2W x 2H; alpha 1 = filled) of the previous frame and of this one (swapped per frame)
layout(set = 2, binding = 5, rgba16f) uniform readonly image2D sub_prev;
layout(set = 2, binding = 6, rgba16f) uniform writeonly image2D sub_next;
// the reprojecting visibility pass's record (vis.frag.in), every method: object + 1, the surface point's position (x, y)
// in the earlier frame (warp: the keyframe), its view distance there (rrc, amss, stu: both distances as halves)
layout(set = 2, binding = 7, rgba32ui) uniform readonly uimage2D vis;
// the cache of the next frame: rrc variants, the other of two cache images (swapped per frame, so that decide can
// write it while its lookups read cache_rec); stu likewise (stu.comp.in writes it while its history test reads
// cache_rec); the other methods, cache_rec itself
layout(set = 2, binding = 8, VREUSE_REC_FORMAT) uniform writeonly uimage2D cache_next;
// amss: frames since each subsample of sub_prev / sub_next took its own sample (amss.comp.in)
layout(set = 2, binding = 9, r32ui) uniform readonly uimage2D age_prev;
layout(set = 2, binding = 10, r32ui) uniform writeonly uimage2D age_next;

const uint FLAG_SHADED = 1u, FLAG_HOLE = 2u;

#ifndef STU // (stu's record has no colour: these would read its two channels as a texel of four)
// The cache texel of a covered pixel: record (object + 1, view distance bits) and colour (halves, as rgba16f holds it).
uvec4 vreuse_pack(uvec2 rec, vec3 c) { return uvec4(rec, packHalf2x16(c.rg), packHalf2x16(vec2(c.b, 0.0))); }
vec3 vreuse_unpack_colour(uvec4 t) { return vec3(unpackHalf2x16(t.z), unpackHalf2x16(t.w).x); }

// The cache lookup of TAS-METHODS section 1 (the rule rrc uses): the four taps around f - 0.5, fractions quantised
// to 1/64 (a static view gives weights exactly 0 and 1: reuse is bit-exact), each tap valid when it holds the same
// object at a view distance within 2 %, invalid taps weighted 0 and the rest renormalised. False: a miss. f and
// dist: the pixel's surface point in the cache's frame (pixels) and its view distance there, as the reprojecting
// visibility pass records them (vis.frag.in), so no triangle is fetched per pixel.
bool vreuse_lookup_at(uint object, vec2 f, float dist, out vec3 colour)
{
	ivec2 size = imageSize(cache_rec);
	colour = vec3(0.0);
	if (any(lessThan(f, vec2(0.0))) || any(greaterThanEqual(f, vec2(size))))
		return false;
	vec2 g = f - 0.5;
	vec2 x0 = floor(g);
	vec2 fr = round((g - x0) * 64.0) / 64.0;
	x0 += step(1.0, fr);
	fr = fr - step(1.0, fr);
	float wsum = 0.0;
	vec3 acc = vec3(0.0);
	// the taps of positive weight lie among the first 1 or 2 when fr.y = 0 (reproj.glsl cache_lookup)
	int taps = fr.y > 0.0 ? 4 : (fr.x > 0.0 ? 2 : 1);
	for (int k = 0; k < taps; k++) {
		ivec2 o = ivec2(k & 1, k >> 1);
		ivec2 q = ivec2(x0) + o;
		float w = (o.x == 1 ? fr.x : 1.0 - fr.x) * (o.y == 1 ? fr.y : 1.0 - fr.y);
		if (w <= 0.0 || any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size)))
			continue;
		uvec4 rec = imageLoad(cache_rec, q);
		if (rec.x != object + 1u || abs(uintBitsToFloat(rec.y) - dist) > 0.02 * dist)
			continue;
		acc += w * vreuse_unpack_colour(rec);
		wsum += w;
	}
	if (wsum <= 0.0)
		return false;
	colour = wsum == 1.0 ? acc : acc / wsum;
	return true;
}
#endif

// Pull-push pyramid: level l is ceil(W / 2^l) x ceil(H / 2^l), stored one after the other from level 1 on (level 0,
// the frame itself, is never stored: decide.comp.in pulls levels 1 and 2 from it in registers).
ivec2 vreuse_level_size(uint l)
{
	ivec2 s = imageSize(flags);
	for (uint k = 0u; k < l; k++)
		s = (s + 1) / 2;
	return s;
}
uint vreuse_level_base(uint l) // l >= 1
{
	uint base = 0u;
	for (uint k = 1u; k < l; k++) {
		ivec2 s = vreuse_level_size(k);
		base += uint(s.x * s.y);
	}
	return base;
}
// The number of levels (down to 1x1).
uint vreuse_levels()
{
	ivec2 s = imageSize(flags);
	uint n = 1u;
	while (any(greaterThan(s, ivec2(1)))) {
		s = (s + 1) / 2;
		n++;
	}
	return n;
}
// A node of the pull ([S] sec. 3.3): the weight-averaged children a, b, c, d ((0,0), (1,0), (0,1), (1,1); an absent
// child is vec4(0) and adds zero), weight min(1, sum). Weights are 0 or 1 at every level (level 0 holds 0 or 1).
vec4 vreuse_pull4(vec4 a, vec4 b, vec4 c, vec4 d)
{
	vec4 sum = vec4(0.0);
	sum += vec4(a.rgb * a.a, a.a);
	sum += vec4(b.rgb * b.a, b.a);
	sum += vec4(c.rgb * c.a, c.a);
	sum += vec4(d.rgb * d.a, d.a);
	return sum.a > 0.0 ? vec4(sum.rgb / sum.a, min(1.0, sum.a)) : vec4(0.0);
}

#endif
