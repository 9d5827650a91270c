// reproj.glsl - resources and helpers of the reverse-reprojection methods rrc and tarc
// (renderer/src/methods/reproj_cache.c; ../shared/TAS-METHODS.md sections 1-3). Needs tas/tas.glsl before it.
//
// Per-pixel cache, double-buffered ("input buffers are reprojected, altered values stored in the output
// buffers", paper sec. 6.1): colour = the value shown for the opaque surface (half float, what the HDR target
// stores), state = (object + 1, view distance bits, age | flags, gradient bits), and for tarc (KEEP_DISP) disp =
// the display code values of the colour, disp(h(s)) as the last shading computed them, so that reshading takes
// one display transform per sample instead of two (as tasa keeps them in its `shown` image), in fixed point in two
// 32-bit channels (disp_pack: R and G in 1/8192, B in 1/16384 code value, so d is within 6.2e-5 code values of the
// float's; an RGBA32F texel cost lavapipe four channel accesses per load and store, ~4 ms of the reproject pass and
// as much of the shading pass at 960x540, issue 32.1).
// Variants (compiled in with #define, never branched on at run time): TARC (else rrc), ORACLE (tarc's ideal
// variant), NEAREST (nearest-pixel lookup, else bilinear with per-tap validity).
#ifndef TASLAB_REPROJ_GLSL
#define TASLAB_REPROJ_GLSL

#if defined(TARC) && !defined(ORACLE)
#define KEEP_DISP 1 // the oracle compares exact display values of C' (its bound), rrc compares none
#endif

#ifdef PAYLOAD
// rrc --payload ([S] sec. 4.1, BASELINES A5): the cache keeps a payload, part of the shading, instead of the colour,
// 32 bits per channel: PAYLOAD_SHADOW the shadow factors of lights 0..7, two unorm16 per channel (packUnorm2x16);
// PAYLOAD_DIFFUSE the diffuse term's RGB (float bits). Decoded into two vec4 (a: factors 0-3 or the RGB, b: factors
// 4-7), resampled like the colour.
layout(set = 1, binding = 0, rgba32ui) uniform readonly uimage2D prev_colour;
layout(set = 1, binding = 2, rgba32ui) uniform uimage2D next_colour;
struct CacheValue {
	vec4 a, b;
};
CacheValue cache_decode(uvec4 u)
{
#ifdef PAYLOAD_SHADOW
	return CacheValue(vec4(unpackUnorm2x16(u.x), unpackUnorm2x16(u.y)), vec4(unpackUnorm2x16(u.z), unpackUnorm2x16(u.w)));
#else
	return CacheValue(vec4(uintBitsToFloat(u.xyz), 0.0), vec4(0.0));
#endif
}
uvec4 cache_encode(CacheValue v)
{
#ifdef PAYLOAD_SHADOW
	return uvec4(packUnorm2x16(v.a.xy), packUnorm2x16(v.a.zw), packUnorm2x16(v.b.xy), packUnorm2x16(v.b.zw));
#else
	return uvec4(floatBitsToUint(v.a.xyz), 0u);
#endif
}
CacheValue cache_zero() { return CacheValue(vec4(0.0), vec4(0.0)); }
CacheValue cache_load(ivec2 q) { return cache_decode(imageLoad(prev_colour, q)); }
CacheValue cache_mad(CacheValue acc, float w, CacheValue v) { return CacheValue(acc.a + w * v.a, acc.b + w * v.b); }
CacheValue cache_div(CacheValue v, float k) { return CacheValue(v.a / k, v.b / k); }
void cache_store(ivec2 px, CacheValue v) { imageStore(next_colour, px, cache_encode(v)); }
#else
layout(set = 1, binding = 0, rgba16f) uniform readonly image2D prev_colour;
layout(set = 1, binding = 2, rgba16f) uniform image2D next_colour;
#define CacheValue vec3
vec3 cache_zero() { return vec3(0.0); }
vec3 cache_load(ivec2 q) { return imageLoad(prev_colour, q).rgb; }
vec3 cache_mad(vec3 acc, float w, vec3 v) { return acc + w * v; }
vec3 cache_div(vec3 v, float k) { return v / k; }
void cache_store(ivec2 px, vec3 v) { imageStore(next_colour, px, vec4(v, 1.0)); }
#endif
layout(set = 1, binding = 1, rgba32ui) uniform readonly uimage2D prev_state;
layout(set = 1, binding = 3, rgba32ui) uniform uimage2D next_state;
// binding 4: none; binding 9: the pre-pass record (only in reproj/reproject.comp.in)
layout(set = 1, binding = 5, rgba32f) uniform readonly image2DArray filt_img; // F: 8x8 max + 9x9 max of G
layout(std430, set = 1, binding = 6) buffer Counters {
	uint covered; // opaque/masked samples (the reproject pass runs once per visible sample)
	uint shaded;  // samples whose shading ran this frame
	uint fresh;   // samples without a valid cache entry (new_units)
	uint late;    // --truth: reused samples more than T from their true shading
	uint forced;  // tarc: reshaded because new or in their second frame (not by the gradient)
	uint composed; // rrc --payload: samples whose shading the compose pass completed with the cached payload
	uint pad1, pad2;
} counters;
layout(set = 1, binding = 7, rg32ui) uniform readonly uimage2D prev_disp; // KEEP_DISP: disp of prev_colour
layout(set = 1, binding = 8, rg32ui) uniform uimage2D next_disp;          // KEEP_DISP: disp of next_colour

// COUNT(field): counters.field += 1 for this invocation. With TL_SUBGROUP (set when the device has ballot
// subgroup operations in the pass's stage: fragment, or compute for the screen-space reproject pass; lavapipe:
// subgroups of 8) the subgroup's active invocations are counted together, one atomic per subgroup by its lowest
// active invocation: subgroup operations act on the active invocations, so it may be used in divergent control
// flow. Helper invocations (derivatives of the shading pass's texture lookups on GPUs) may be active in subgroup
// operations but their atomics have no effect: they are left out (gl_HelperInvocation; llvmpipe has none and cannot
// compile it: TL_NO_HELPERS). On lavapipe an atomic is a loop over the lanes: one per fragment cost ~8 ms of the
// reproject pass and ~13 ms of the shading pass at 960x540.
#ifdef TL_SUBGROUP
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
#ifdef TL_NO_HELPERS
#define TL_LIVE true
#else
#define TL_LIVE (!gl_HelperInvocation)
#endif
#define COUNT(field)                                                                                               \
	{                                                                                                          \
		uvec4 live_ = subgroupBallot(TL_LIVE);                                                             \
		if (gl_SubgroupInvocationID == subgroupBallotFindLSB(live_))                                       \
			atomicAdd(counters.field, subgroupBallotBitCount(live_));                                  \
	}
#else
#define COUNT(field) atomicAdd(counters.field, 1u)
#endif

#include "tas/disp.glsl" // disp_pack, disp_unpack (KEEP_DISP)
#include "reproj/state_bits.glsl" // state.z: age, flags, decision

// Push constants: aux[0] previous slot; aux[1] flags; aux[2] frame number (in the pre-pass: the frame size, width |
// height << 16); aux[3] T (float bits).
const uint FLAG_HAVE_PREV = 1u;   // the previous frame was rendered: the cache is valid
const uint FLAG_FORCE = 2u;       // tarc --force-reshade (overhead measurement)
uint period() { return (pc.aux[1] >> 8) & 0xFFu; }   // rrc N
uint max_age() { return pc.aux[1] >> 16; }           // tarc K (0: none)

// h(x): the half-float value the HDR target and the cache store (TAS-METHODS section 0).
vec3 to_half(vec3 x)
{
	return vec3(unpackHalf2x16(packHalf2x16(x.rg)), unpackHalf2x16(packHalf2x16(vec2(x.b, 0.0))).x);
}

// Where the surface point was in the previous frame, in pixels (not rounded), from its clip position there
// (reproject.vert). False when behind the eye or outside the frame.
bool reproject_f(vec4 c, ivec2 size, out vec2 f)
{
	f = vec2(0.0);
	if (c.w <= 0.0)
		return false;
	f = (c.xy / c.w * 0.5 + 0.5) * vec2(size);
	return !(any(lessThan(f, vec2(0.0))) || any(greaterThanEqual(f, vec2(size))));
}

// The cache-miss test of a cache pixel (TAS-METHODS section 1): same object, view distances within 2% (the
// point lies between pixel centres, so depth varies across a pixel on slanted surfaces; the rule tfr uses).
bool cached_here(uvec4 rec, uint object, float dist)
{
	return rec.x == object + 1u && abs(uintBitsToFloat(rec.y) - dist) <= 0.02 * dist;
}

// ---- The pre-pass record (issue 32.1, lever 3). The depth pre-pass of rrc/tarc (reproj/prepass.frag.in) writes,
// for the sample it leaves visible, everything the lookup needs into one RGBA32UI attachment, so that the reprojection
// runs in screen space (reproj/reproject.comp.in) instead of rasterising the scene a second time:
//   x: bits 0..21 object + 1 (0: background), bits 22..31 bits 11..20 of the lookup position's y
//   y: the view distance now (float bits; the state's y), z: the view distance in the previous frame (float bits)
//   w: bits 0..20 the lookup position's x, bits 21..31 bits 0..10 of its y
// The lookup position per axis (21 bits): NEAREST floor(f); bilinear (x0 + 1) * 64 + the fraction in 64ths, i.e.
// exactly the quantities the lookup takes from f (TAS-METHODS section 1); all ones: no position (behind the eye or
// outside the frame). reproj_cache.c bounds the object count (2^22 - 2) and the frame size (32766).
const uint POS_NONE = 0x1FFFFFu;
const uint OBJECT_BITS_MASK = 0x3FFFFFu;

uvec4 prepass_record(uint object, vec4 prev_clip, float prev_dist, float cur_dist, ivec2 size)
{
	vec2 f;
	uvec2 p = uvec2(POS_NONE);
	if (reproject_f(prev_clip, size, f)) {
#ifdef NEAREST
		p = uvec2(ivec2(f));
#else
		vec2 g = f - 0.5;
		vec2 x0 = floor(g);
		vec2 fr = round((g - x0) * 64.0);
		x0 += step(64.0, fr); // a fraction rounded up to 1 moves to the next tap with fraction 0
		fr = fr - 64.0 * step(64.0, fr);
		p = uvec2(ivec2(x0) + 1) * 64u + uvec2(fr);
#endif
	}
	return uvec4((object + 1u) | (p.y >> 11) << 22, floatBitsToUint(cur_dist), floatBitsToUint(prev_dist),
		     p.x | (p.y & 0x7FFu) << 21);
}

uint record_object(uvec4 m) { return (m.x & OBJECT_BITS_MASK) - 1u; } // m.x & OBJECT_BITS_MASK != 0: covered
uvec2 record_position(uvec4 m) { return uvec2(m.w & POS_NONE, (m.w >> 21) | (m.x >> 22) << 11); }

// Cache lookup (TAS-METHODS section 1) at the lookup position p of the pre-pass record. Nearest: the pixel f
// falls in, one validity test. Bilinear: the four taps around f - 0.5 with fractions quantised to 1/64 (a static
// view then gives weights exactly 0 and 1, so reuse is bit-exact), each tap tested on its own (object and 2%
// view-distance match, `was_visible`), invalid taps weighted 0 and the rest renormalised; the discrete state comes
// from the valid tap with the largest weight (ties: the lowest tap). False: a cache miss.
// dist: the surface point's view distance in the previous frame.
// KEEP_DISP: disp = the cached display values of the tap the discrete state comes from (one tap, not four: on
// lavapipe every image load costs the same whatever its weight). Under a static view (weights 0 and 1) exactly
// disp(C'); under motion the display values of the last shading the state travelled with, not of the blend C'.
bool cache_lookup(uint object, uvec2 p, float dist, out CacheValue colour, out vec3 disp, out uvec4 state)
{
	ivec2 size = imageSize(prev_state);
	colour = cache_zero();
	disp = vec3(0.0);
	state = uvec4(0u);
	if (p.x == POS_NONE)
		return false;
#ifdef NEAREST
	ivec2 q = ivec2(p);
	uvec4 rec = imageLoad(prev_state, q);
	if (!cached_here(rec, object, dist))
		return false;
	colour = cache_load(q);
#ifdef KEEP_DISP
	disp = disp_unpack(imageLoad(prev_disp, q).xy);
#endif
	state = rec;
	return true;
#else
	ivec2 x0 = ivec2(p >> 6u) - 1;
	vec2 fr = vec2(p & 63u) / 64.0;
	float wsum = 0.0, wbest = -1.0;
	CacheValue acc = cache_zero();
	ivec2 qbest = ivec2(0);
	// Only taps of positive weight count: with both fractions 0 (a static view) tap 0 alone, with fr.y = 0 taps 0
	// and 1 (with fr.x = 0 < fr.y taps 0 and 2: all four are visited). The loop runs to that bound, not to 4, so
	// that SIMD groups whose lanes all lie on pixel centres skip the zero-weight taps' loads (lavapipe runs an if's
	// body for every lane, but leaves a loop once every lane has); the taps it visits and their order are
	// unchanged, so are the results.
	int taps = fr.y > 0.0 ? 4 : (fr.x > 0.0 ? 2 : 1);
	for (int k = 0; k < taps; k++) {
		ivec2 o = ivec2(k & 1, k >> 1);
		ivec2 q = x0 + o;
		float w = (o.x == 1 ? fr.x : 1.0 - fr.x) * (o.y == 1 ? fr.y : 1.0 - fr.y);
		if (w <= 0.0 || any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size)))
			continue;
		uvec4 rec = imageLoad(prev_state, q);
		if (!cached_here(rec, object, dist))
			continue;
		acc = cache_mad(acc, w, cache_load(q));
		wsum += w;
		if (w > wbest) {
			wbest = w;
			state = rec;
			qbest = q;
		}
	}
	if (wsum <= 0.0)
		return false;
	colour = wsum == 1.0 ? acc : cache_div(acc, wsum);
#ifdef KEEP_DISP
	disp = disp_unpack(imageLoad(prev_disp, qbest).xy);
#endif
	return true;
#endif
}

#endif
