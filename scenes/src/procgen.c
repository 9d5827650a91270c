/* procgen.c — procedural meshes (parametric surfaces) and textures (see procgen.h). */
#include "procgen.h"
#include "taslab/texture.h"
#include "taslab/tl_error.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- mesh builder */

typedef struct builder {
	scene_vertex *v;
	uint32_t nv, cap_v;
	uint32_t *idx;
	uint32_t ni, cap_i;
	int oom;
} builder;

static uint32_t b_vertex(builder *b, tlm_vec3 p, tlm_vec3 n, float u, float v, tlm_vec3 t, float w)
{
	if (b->nv == b->cap_v) {
		uint32_t cap = b->cap_v ? b->cap_v * 2 : 256;
		scene_vertex *nvp = realloc(b->v, cap * sizeof *nvp);
		if (!nvp) {
			b->oom = 1;
			return 0;
		}
		b->v = nvp;
		b->cap_v = cap;
	}
	scene_vertex *x = &b->v[b->nv];
	*x = (scene_vertex){{p.x, p.y, p.z}, {n.x, n.y, n.z}, {u, v}, {t.x, t.y, t.z, w}};
	return b->nv++;
}

static void b_index(builder *b, uint32_t i)
{
	if (b->ni == b->cap_i) {
		uint32_t cap = b->cap_i ? b->cap_i * 2 : 512;
		uint32_t *n = realloc(b->idx, cap * sizeof *n);
		if (!n) {
			b->oom = 1;
			return;
		}
		b->idx = n;
		b->cap_i = cap;
	}
	b->idx[b->ni++] = i;
}

static tlm_vec3 vpos(const builder *b, uint32_t i)
{
	return tlm_v3(b->v[i].position[0], b->v[i].position[1], b->v[i].position[2]);
}

/* Emits a triangle wound counter-clockwise as seen from the side its vertex normals face. */
static void b_triangle(builder *b, uint32_t i0, uint32_t i1, uint32_t i2)
{
	if (b->oom)
		return;
	tlm_vec3 fn = tlm_v3_cross(tlm_v3_sub(vpos(b, i1), vpos(b, i0)), tlm_v3_sub(vpos(b, i2), vpos(b, i0)));
	if (tlm_v3_length(fn) < 1e-12f)
		return; /* degenerate (pole) */
	const float *n0 = b->v[i0].normal;
	if (fn.x * n0[0] + fn.y * n0[1] + fn.z * n0[2] < 0.0f) {
		uint32_t t = i1;
		i1 = i2;
		i2 = t;
	}
	b_index(b, i0);
	b_index(b, i1);
	b_index(b, i2);
}

/* A parametric patch: fn(u, v) gives position and normal; tangent = normalised dP/du,
 * bitangent sign chosen so that cross(N, T) * w points along decreasing texture v (glTF). */
typedef void (*patch_fn)(const void *ctx, float u, float v, tlm_vec3 *p, tlm_vec3 *n);

static void b_patch(builder *b, patch_fn fn, const void *ctx, int nu, int nv, float su, float sv)
{
	uint32_t base = b->nv;
	const float e = 1e-3f;
	for (int j = 0; j <= nv; j++)
		for (int i = 0; i <= nu; i++) {
			float u = (float)i / (float)nu, v = (float)j / (float)nv;
			tlm_vec3 p, n, pu0, pu1, pv0, pv1, dummy;
			fn(ctx, u, v, &p, &n);
			fn(ctx, fminf(u + e, 1.0f), v, &pu1, &dummy);
			fn(ctx, fmaxf(u - e, 0.0f), v, &pu0, &dummy);
			fn(ctx, u, fminf(v + e, 1.0f), &pv1, &dummy);
			fn(ctx, u, fmaxf(v - e, 0.0f), &pv0, &dummy);
			tlm_vec3 dpu = tlm_v3_sub(pu1, pu0), dpv = tlm_v3_sub(pv1, pv0);
			/* Gram-Schmidt against the normal; at poles dP/du vanishes: use a stable fallback. */
			tlm_vec3 t = tlm_v3_sub(dpu, tlm_v3_scale(n, tlm_v3_dot(n, dpu)));
			if (tlm_v3_length(t) < 1e-7f) {
				tlm_vec3 ref = fabsf(n.y) < 0.9f ? tlm_v3(0, 1, 0) : tlm_v3(1, 0, 0);
				t = tlm_v3_cross(ref, n);
			}
			t = tlm_v3_normalize_or(t, tlm_v3(1, 0, 0));
			float w = tlm_v3_dot(tlm_v3_cross(n, t), dpv) > 0.0f ? -1.0f : 1.0f;
			b_vertex(b, p, n, u * su, v * sv, t, w);
		}
	for (int j = 0; j < nv; j++)
		for (int i = 0; i < nu; i++) {
			uint32_t a = base + (uint32_t)(j * (nu + 1) + i);
			uint32_t c = a + (uint32_t)(nu + 1);
			b_triangle(b, a, a + 1, c);
			b_triangle(b, a + 1, c + 1, c);
		}
}

typedef struct quad_ctx {
	tlm_vec3 origin, eu, ev, n;
} quad_ctx;

static void quad_fn(const void *c, float u, float v, tlm_vec3 *p, tlm_vec3 *n)
{
	const quad_ctx *q = c;
	*p = tlm_v3_add(q->origin, tlm_v3_add(tlm_v3_scale(q->eu, u), tlm_v3_scale(q->ev, v)));
	*n = q->n;
}

typedef struct sphere_ctx {
	float r;
} sphere_ctx;

static void sphere_fn(const void *c, float u, float v, tlm_vec3 *p, tlm_vec3 *n)
{
	const sphere_ctx *s = c;
	float phi = u * 2.0f * TLM_PI, th = v * TLM_PI;
	*n = tlm_v3(sinf(th) * cosf(phi), cosf(th), -sinf(th) * sinf(phi));
	*p = tlm_v3_scale(*n, s->r);
}

typedef struct cyl_ctx {
	float r, h;
} cyl_ctx;

static void cyl_fn(const void *c, float u, float v, tlm_vec3 *p, tlm_vec3 *n)
{
	const cyl_ctx *s = c;
	float phi = u * 2.0f * TLM_PI;
	*n = tlm_v3(cosf(phi), 0.0f, -sinf(phi));
	*p = tlm_v3(s->r * n->x, s->h * (0.5f - v), s->r * n->z);
}

typedef struct disk_ctx {
	float r, y, up;
} disk_ctx;

static void disk_fn(const void *c, float u, float v, tlm_vec3 *p, tlm_vec3 *n)
{
	const disk_ctx *s = c;
	float phi = u * 2.0f * TLM_PI * s->up, rr = s->r * v;
	*p = tlm_v3(rr * cosf(phi), s->y, -rr * sinf(phi));
	*n = tlm_v3(0.0f, s->up, 0.0f);
}

typedef struct torus_ctx {
	float R, r;
} torus_ctx;

static void torus_fn(const void *c, float u, float v, tlm_vec3 *p, tlm_vec3 *n)
{
	const torus_ctx *s = c;
	float phi = u * 2.0f * TLM_PI, th = v * 2.0f * TLM_PI;
	tlm_vec3 radial = tlm_v3(cosf(phi), 0.0f, -sinf(phi));
	*n = tlm_v3_add(tlm_v3_scale(radial, cosf(th)), tlm_v3(0.0f, sinf(th), 0.0f));
	*p = tlm_v3_add(tlm_v3_scale(radial, s->R), tlm_v3_scale(*n, s->r));
}

const char *procgen_mesh_kinds(void) { return "plane, box, sphere, cylinder, torus"; }

int procgen_mesh(const procgen_mesh_desc *d, scene_mesh *out, char *why, size_t why_size)
{
	builder b = {0};
	int seg = d->segments > 0 ? d->segments : 32, rings = d->rings > 0 ? d->rings : 16;
	float uvs = d->uv_scale > 0.0f ? d->uv_scale : 1.0f;
	if (seg > 1024 || rings > 1024) {
		snprintf(why, why_size, "segments and rings must be at most 1024");
		return TL_ERR_INPUT;
	}
	if (!strcmp(d->kind, "plane")) {
		/* Plane in XZ facing +Y, centred at the origin. */
		if (!(d->size.x > 0 && d->size.z > 0)) {
			snprintf(why, why_size, "plane size must be positive [x, y, z] (y unused)");
			return TL_ERR_INPUT;
		}
		int nsub = d->segments > 0 ? d->segments : 8;
		quad_ctx q = {{-0.5f * d->size.x, 0, -0.5f * d->size.z}, {d->size.x, 0, 0}, {0, 0, d->size.z}, {0, 1, 0}};
		b_patch(&b, quad_fn, &q, nsub, nsub, d->size.x * uvs, d->size.z * uvs);
	} else if (!strcmp(d->kind, "box")) {
		tlm_vec3 s = d->size;
		if (!(s.x > 0 && s.y > 0 && s.z > 0)) {
			snprintf(why, why_size, "box size must be three positive numbers");
			return TL_ERR_INPUT;
		}
		tlm_vec3 h = tlm_v3_scale(s, 0.5f);
		/* Each face: origin at its corner, edges eu, ev spanning it, outward normal. */
		quad_ctx f[6] = {
			{{h.x, -h.y, h.z}, {0, 0, -s.z}, {0, s.y, 0}, {1, 0, 0}},
			{{-h.x, -h.y, -h.z}, {0, 0, s.z}, {0, s.y, 0}, {-1, 0, 0}},
			{{-h.x, h.y, h.z}, {s.x, 0, 0}, {0, 0, -s.z}, {0, 1, 0}},
			{{-h.x, -h.y, -h.z}, {s.x, 0, 0}, {0, 0, s.z}, {0, -1, 0}},
			{{-h.x, -h.y, h.z}, {s.x, 0, 0}, {0, s.y, 0}, {0, 0, 1}},
			{{h.x, -h.y, -h.z}, {-s.x, 0, 0}, {0, s.y, 0}, {0, 0, -1}},
		};
		/* 2 x 2 quads per face; with `segments`, quads of side max(size) / segments (large walls subdivided
		 * so that the shading atlas can size their patches, [TAS] sec. 7.4) */
		float cell = fmaxf(s.x, fmaxf(s.y, s.z)) / (float)(d->segments > 0 ? d->segments : 1);
		for (int i = 0; i < 6; i++) {
			float lu = tlm_v3_length(f[i].eu), lv = tlm_v3_length(f[i].ev);
			int nu = d->segments > 0 ? (int)fmaxf(1.0f, ceilf(lu / cell - 1e-4f)) : 2;
			int nv = d->segments > 0 ? (int)fmaxf(1.0f, ceilf(lv / cell - 1e-4f)) : 2;
			b_patch(&b, quad_fn, &f[i], nu, nv, lu * uvs, lv * uvs);
		}
	} else if (!strcmp(d->kind, "sphere")) {
		if (!(d->radius > 0)) {
			snprintf(why, why_size, "sphere radius must be positive");
			return TL_ERR_INPUT;
		}
		sphere_ctx s = {d->radius};
		b_patch(&b, sphere_fn, &s, seg, rings, 2.0f * uvs, uvs);
	} else if (!strcmp(d->kind, "cylinder")) {
		if (!(d->radius > 0 && d->height > 0)) {
			snprintf(why, why_size, "cylinder radius and height must be positive");
			return TL_ERR_INPUT;
		}
		cyl_ctx c = {d->radius, d->height};
		b_patch(&b, cyl_fn, &c, seg, 1, 2.0f * uvs, uvs);
		disk_ctx top = {d->radius, 0.5f * d->height, 1.0f}, bot = {d->radius, -0.5f * d->height, -1.0f};
		/* caps: triangle fans, or with `rings` concentric rings (a large cap's slices would otherwise be long
		 * slivers, which the shading atlas must give large blocks) */
		int cap_rings = d->rings > 0 ? d->rings : 1;
		b_patch(&b, disk_fn, &top, seg, cap_rings, uvs, uvs);
		b_patch(&b, disk_fn, &bot, seg, cap_rings, uvs, uvs);
	} else if (!strcmp(d->kind, "torus")) {
		if (!(d->radius > 0 && d->tube_radius > 0 && d->tube_radius < d->radius)) {
			snprintf(why, why_size, "torus needs 0 < tube_radius < radius");
			return TL_ERR_INPUT;
		}
		torus_ctx t = {d->radius, d->tube_radius};
		b_patch(&b, torus_fn, &t, seg, rings, 4.0f * uvs, uvs);
	} else {
		snprintf(why, why_size, "unknown mesh type '%s' (use one of: %s)", d->kind, procgen_mesh_kinds());
		return TL_ERR_INPUT;
	}
	if (b.oom) {
		free(b.v);
		free(b.idx);
		snprintf(why, why_size, "out of memory");
		return TL_ERR_NOMEM;
	}
	out->vertices = b.v;
	out->vertex_count = b.nv;
	out->indices = b.idx;
	out->index_count = b.ni;
	tlm_vec3 lo = tlm_v3(1e30f, 1e30f, 1e30f), hi = tlm_v3(-1e30f, -1e30f, -1e30f);
	for (uint32_t i = 0; i < b.nv; i++) {
		const float *p = b.v[i].position;
		lo = tlm_v3(fminf(lo.x, p[0]), fminf(lo.y, p[1]), fminf(lo.z, p[2]));
		hi = tlm_v3(fmaxf(hi.x, p[0]), fmaxf(hi.y, p[1]), fmaxf(hi.z, p[2]));
	}
	out->bounds_min = lo;
	out->bounds_max = hi;
	return 0;
}

/* ---------------------------------------------------------------- textures */

procgen_pattern procgen_pattern_from_string(const char *s)
{
	static const char *names[] = {NULL, "flat", "checker", "bricks", "noise", "stripes"};
	for (int i = 1; i < PROCGEN_PATTERN_COUNT; i++)
		if (s && !strcmp(s, names[i]))
			return (procgen_pattern)i;
	return PROCGEN_PATTERN_INVALID;
}

procgen_output procgen_output_from_string(const char *s)
{
	static const char *names[] = {NULL, "color", "normal", "metal_rough", "occlusion"};
	for (int i = 1; i < PROCGEN_OUTPUT_COUNT; i++)
		if (s && !strcmp(s, names[i]))
			return (procgen_output)i;
	return PROCGEN_OUTPUT_INVALID;
}

/* 32-bit integer hash (lowbias32 by C. Wellons) -> [0, 1). */
static float hash01(uint32_t x)
{
	x ^= x >> 16;
	x *= 0x7feb352dU;
	x ^= x >> 15;
	x *= 0x846ca68bU;
	x ^= x >> 16;
	return (float)(x >> 8) * (1.0f / 16777216.0f);
}

static float lattice(int x, int y, int period, uint32_t seed)
{
	x = ((x % period) + period) % period;
	y = ((y % period) + period) % period;
	return hash01((uint32_t)x * 73856093u ^ (uint32_t)y * 19349663u ^ seed * 83492791u);
}

/* Tileable value noise with smoothstep interpolation. */
static float value_noise(float u, float v, int period, uint32_t seed)
{
	float x = u * (float)period, y = v * (float)period;
	int x0 = (int)floorf(x), y0 = (int)floorf(y);
	float fx = x - (float)x0, fy = y - (float)y0;
	fx = fx * fx * (3 - 2 * fx);
	fy = fy * fy * (3 - 2 * fy);
	float a = lattice(x0, y0, period, seed), b = lattice(x0 + 1, y0, period, seed);
	float c = lattice(x0, y0 + 1, period, seed), d = lattice(x0 + 1, y0 + 1, period, seed);
	return (a + (b - a) * fx) + ((c + (d - c) * fx) - (a + (b - a) * fx)) * fy;
}

static float pattern_value(const procgen_texture_desc *d, float u, float v)
{
	float sc = d->scale > 0.0f ? d->scale : 4.0f;
	switch (d->pattern) {
	case PROCGEN_PATTERN_CHECKER:
		return (float)(((int)floorf(u * sc) + (int)floorf(v * sc)) & 1);
	case PROCGEN_PATTERN_BRICKS: {
		/* `sc` rows of bricks twice as wide as high; odd rows offset by half a brick. */
		float y = v * sc, row = floorf(y);
		float x = u * sc * 0.5f + (((int)row & 1) ? 0.5f : 0.0f), col = floorf(x);
		float fy = y - row, fx = (x - col) * 2.0f; /* brick-height units */
		const float mortar = 0.08f, bevel = 0.06f;
		float ex = fminf(fx, 2.0f - fx), ey = fminf(fy, 1.0f - fy);
		float edge = fminf(ex, ey);
		float h = tlm_smoothstep(mortar, mortar + bevel, edge);
		int cx = (int)col % (int)fmaxf(1.0f, sc * 0.5f);
		float var = 0.8f + 0.2f * hash01((uint32_t)cx * 2654435761u ^ (uint32_t)row * 40503u ^ d->seed);
		return h * var;
	}
	case PROCGEN_PATTERN_NOISE: {
		float s = 0.0f, amp = 0.5f, norm = 0.0f;
		int period = (int)fmaxf(1.0f, sc);
		for (int o = 0; o < 5; o++) {
			s += amp * value_noise(u, v, period, d->seed + (uint32_t)o * 101u);
			norm += amp;
			amp *= 0.5f;
			period *= 2;
		}
		return s / norm;
	}
	case PROCGEN_PATTERN_STRIPES:
		return 0.5f + 0.5f * sinf(2.0f * TLM_PI * u * sc);
	default:
		return 0.0f;
	}
}

#define to_u8 tex_unorm8

static float srgb_encode(float l) { return tex_linear_to_srgb(tlm_clampf(l, 0.0f, 1.0f)); }

int procgen_texture(const procgen_texture_desc *d, uint32_t size, uint8_t *rgba)
{
	float *h = NULL;
	if (d->output == PROCGEN_OUTPUT_NORMAL) {
		h = malloc((size_t)size * size * sizeof *h);
		if (!h)
			return TL_ERR_NOMEM;
	}
	for (uint32_t y = 0; y < size; y++)
		for (uint32_t x = 0; x < size; x++) {
			float u = ((float)x + 0.5f) / (float)size, v = ((float)y + 0.5f) / (float)size;
			float p = pattern_value(d, u, v);
			uint8_t *o = &rgba[((size_t)y * size + x) * 4];
			switch (d->output) {
			case PROCGEN_OUTPUT_COLOR:
				/* Endpoint colours are linear; stored sRGB-encoded as glTF base colour textures are. */
				for (int c = 0; c < 3; c++)
					o[c] = to_u8(srgb_encode(d->a[c] + (d->b[c] - d->a[c]) * p));
				o[3] = to_u8(d->a[3] + (d->b[3] - d->a[3]) * p);
				break;
			case PROCGEN_OUTPUT_METAL_ROUGH:
				o[0] = 255;
				o[1] = to_u8(d->a[0] + (d->b[0] - d->a[0]) * p); /* roughness */
				o[2] = to_u8(d->a[1] + (d->b[1] - d->a[1]) * p); /* metallic */
				o[3] = 255;
				break;
			case PROCGEN_OUTPUT_OCCLUSION:
				o[0] = o[1] = o[2] = to_u8(d->a[0] + (d->b[0] - d->a[0]) * p);
				o[3] = 255;
				break;
			default:
				if (h)
					h[(size_t)y * size + x] = p;
				break;
			}
		}
	if (h) {
		/* Tangent-space normal from central differences of the height field (wrapping):
		 * n = normalize(-s dh/du, +s dh/dv, 1); +Y of the map points along decreasing v (glTF). */
		float s = (d->strength > 0.0f ? d->strength : 1.0f);
		for (uint32_t y = 0; y < size; y++)
			for (uint32_t x = 0; x < size; x++) {
				uint32_t xm = (x + size - 1) % size, xp = (x + 1) % size;
				uint32_t ym = (y + size - 1) % size, yp = (y + 1) % size;
				float du = (h[(size_t)y * size + xp] - h[(size_t)y * size + xm]) * 0.5f;
				float dv = (h[(size_t)yp * size + x] - h[(size_t)ym * size + x]) * 0.5f;
				tlm_vec3 n = tlm_v3_normalize_or(tlm_v3(-s * du, s * dv, 1.0f), tlm_v3(0, 0, 1));
				uint8_t *o = &rgba[((size_t)y * size + x) * 4];
				o[0] = to_u8(n.x * 0.5f + 0.5f);
				o[1] = to_u8(n.y * 0.5f + 0.5f);
				o[2] = to_u8(n.z * 0.5f + 0.5f);
				o[3] = 255;
			}
		free(h);
	}
	return 0;
}
