/* atlas_alloc.c — patches, block sizes and the block allocator of the shading-atlas methods (atlas_alloc.h;
 * TAS-METHODS section 4; [TAS] secs. 4.3, 6.2). Everything here is deterministic: the same scene and views give
 * the same patches, sizes and addresses. */
#include "atlas_alloc.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/tl_error.h"

/* ---- patches ---- */

typedef struct edge_slot {
	uint32_t a, b; /* sorted vertex pair; a = UINT32_MAX: empty */
	uint32_t tri[2];
	uint32_t n;
} edge_slot;

static uint64_t edge_hash(uint32_t a, uint32_t b) { return ((uint64_t)a * 0x9E3779B97F4A7C15ull) ^ ((uint64_t)b * 0xC2B2AE3D27D4EB4Full); }

static edge_slot *edge_find(edge_slot *t, size_t cap, uint32_t a, uint32_t b)
{
	if (a > b) {
		uint32_t x = a;
		a = b, b = x;
	}
	size_t i = (size_t)(edge_hash(a, b) & (cap - 1));
	while (t[i].a != UINT32_MAX && (t[i].a != a || t[i].b != b))
		i = (i + 1) & (cap - 1);
	if (t[i].a == UINT32_MAX)
		t[i].a = a, t[i].b = b;
	return &t[i];
}

/* Index position (0..2) of triangle t's vertex not on the edge {a, b}; -1 if t does not have that edge. */
static int unshared_pos(const uint32_t *ix, uint32_t a, uint32_t b)
{
	int on = 0, pos = -1;
	for (int k = 0; k < 3; k++) {
		if (ix[k] == a || ix[k] == b)
			on++;
		else
			pos = k;
	}
	return on == 2 ? pos : -1;
}

static bool degenerate(const uint32_t *ix) { return ix[0] == ix[1] || ix[1] == ix[2] || ix[0] == ix[2]; }

/* A and B (A the lower index) can form a patch: they share exactly the edge a1-a2 and B runs it the other way
 * (consistent winding), so b1 = a2 and b2 = a1. Returns A's and B's rotations. */
static bool pairable(const uint32_t *ia, const uint32_t *ib, int *ra, int *rb)
{
	if (degenerate(ia) || degenerate(ib))
		return false;
	for (int p = 0; p < 3; p++) {
		uint32_t a1 = ia[(p + 1) % 3], a2 = ia[(p + 2) % 3];
		int q = unshared_pos(ib, a1, a2);
		if (q < 0 || ib[q] == ia[p])
			continue;
		if (ib[(q + 1) % 3] == a2 && ib[(q + 2) % 3] == a1) {
			*ra = p, *rb = q;
			return true;
		}
	}
	return false;
}

static float edge_len2(const scene_mesh *m, uint32_t a, uint32_t b)
{
	const float *p = m->vertices[a].position, *q = m->vertices[b].position;
	float d[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]};
	return d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

static int build_mesh(const scene_mesh *m, atlas_patches *P, uint32_t tri_base, char *err, size_t err_size)
{
	uint32_t n = m->index_count / 3;
	int32_t *partner = malloc((size_t)n * sizeof *partner);
	int8_t *rot = malloc(n);
	size_t cap = 16;
	while (cap < (size_t)n * 6)
		cap <<= 1;
	edge_slot *edges = malloc(cap * sizeof *edges);
	if (!partner || !rot || !edges) {
		free(partner), free(rot), free(edges);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory building atlas patches");
	}
	for (uint32_t t = 0; t < n; t++)
		partner[t] = -1, rot[t] = 0;
	/* pass 1: quads as emitted (triangles 2k, 2k + 1 sharing a diagonal) */
	for (uint32_t t = 0; t + 1 < n; t += 2) {
		int ra, rb;
		if (pairable(m->indices + 3 * t, m->indices + 3 * (t + 1), &ra, &rb)) {
			partner[t] = (int32_t)(t + 1), partner[t + 1] = (int32_t)t;
			rot[t] = (int8_t)ra, rot[t + 1] = (int8_t)rb;
		}
	}
	/* pass 2: the remaining triangles, greedily in index order, across their longest shared edge */
	for (size_t i = 0; i < cap; i++)
		edges[i].a = UINT32_MAX, edges[i].n = 0;
	for (uint32_t t = 0; t < n; t++) {
		if (partner[t] >= 0 || degenerate(m->indices + 3 * t))
			continue;
		for (int k = 0; k < 3; k++) {
			edge_slot *e = edge_find(edges, cap, m->indices[3 * t + k], m->indices[3 * t + (k + 1) % 3]);
			if (e->n < 2)
				e->tri[e->n++] = t;
		}
	}
	for (uint32_t t = 0; t < n; t++) {
		if (partner[t] >= 0 || degenerate(m->indices + 3 * t))
			continue;
		const uint32_t *ia = m->indices + 3 * t;
		float best = -1.0f;
		int32_t bu = -1;
		int bra = 0, brb = 0;
		for (int k = 0; k < 3; k++) {
			edge_slot *e = edge_find(edges, cap, ia[k], ia[(k + 1) % 3]);
			for (uint32_t j = 0; j < e->n; j++) {
				uint32_t u = e->tri[j];
				int ra, rb;
				if (u == t || partner[u] >= 0)
					continue;
				uint32_t lo = t < u ? t : u, hi = t < u ? u : t;
				if (!pairable(m->indices + 3 * lo, m->indices + 3 * hi, &ra, &rb))
					continue;
				float len = edge_len2(m, ia[k], ia[(k + 1) % 3]);
				if (len > best || (len == best && (int32_t)u < bu)) {
					best = len, bu = (int32_t)u;
					bra = t < u ? ra : rb, brb = t < u ? rb : ra; /* rotations of t and u */
				}
			}
		}
		if (bu >= 0) {
			partner[t] = bu, partner[bu] = (int32_t)t;
			rot[t] = (int8_t)bra, rot[bu] = (int8_t)brb;
		}
	}
	/* patches in the order of their first triangle */
	for (uint32_t t = 0; t < n; t++) {
		if (partner[t] >= 0 && (uint32_t)partner[t] < t)
			continue; /* B of an earlier patch */
		uint32_t id = (uint32_t)(P->patch_total - P->mesh_patch_base[P->mesh_count]);
		const uint32_t *ix = m->indices + 3 * t;
		int r = partner[t] >= 0 ? rot[t] : 0;
		uint32_t *c = P->corners + 4 * P->patch_total;
		c[0] = ix[r], c[1] = ix[(r + 1) % 3], c[2] = ix[(r + 2) % 3];
		c[3] = ATLAS_SINGLE;
		P->tri_info[tri_base + t] = id << 3 | (uint32_t)r;
		if (partner[t] >= 0) {
			uint32_t u = (uint32_t)partner[t];
			c[3] = m->indices[3 * u + rot[u]];
			P->tri_info[tri_base + u] = id << 3 | 1u << 2 | (uint32_t)rot[u];
			P->paired++;
		}
		P->patch_total++;
	}
	free(partner), free(rot), free(edges);
	return TL_OK;
}

int atlas_patches_build(const scene *s, atlas_patches *P, char *err, size_t err_size)
{
	memset(P, 0, sizeof *P);
	size_t tris = 0;
	for (size_t i = 0; i < s->mesh_count; i++)
		tris += s->meshes[i].index_count / 3;
	if (tris >= (1u << 29))
		return tl_error(err, err_size, TL_ERR_UNSUPPORTED, "atlas: %zu triangles, at most 2^29", tris);
	P->mesh_patch_base = calloc(s->mesh_count + 1, sizeof *P->mesh_patch_base);
	P->mesh_tri_base = calloc(s->mesh_count + 1, sizeof *P->mesh_tri_base);
	P->corners = malloc((tris ? tris : 1) * 4 * sizeof *P->corners);
	P->tri_info = malloc((tris ? tris : 1) * sizeof *P->tri_info);
	if (!P->mesh_patch_base || !P->mesh_tri_base || !P->corners || !P->tri_info) {
		atlas_patches_free(P);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory building atlas patches");
	}
	uint32_t tri_base = 0;
	for (size_t i = 0; i < s->mesh_count; i++) {
		P->mesh_patch_base[i] = (uint32_t)P->patch_total;
		P->mesh_tri_base[i] = tri_base;
		P->mesh_count = i;
		int rc = build_mesh(&s->meshes[i], P, tri_base, err, err_size);
		if (rc) {
			atlas_patches_free(P);
			return rc;
		}
		tri_base += s->meshes[i].index_count / 3;
	}
	P->mesh_count = s->mesh_count;
	P->mesh_patch_base[s->mesh_count] = (uint32_t)P->patch_total;
	P->mesh_tri_base[s->mesh_count] = tri_base;
	P->tri_total = tri_base;
	return TL_OK;
}

void atlas_patches_free(atlas_patches *P)
{
	free(P->mesh_patch_base);
	free(P->mesh_tri_base);
	free(P->corners);
	free(P->tri_info);
	memset(P, 0, sizeof *P);
}

/* ---- block sizes ---- */

static float edge_px(const float *p, const float *q, uint32_t w, uint32_t h)
{
	const float eps = 1e-5f;
	float a[4], b[4];
	memcpy(a, p, sizeof a);
	memcpy(b, q, sizeof b);
	if (a[3] < eps && b[3] < eps)
		return 0.0f;
	if (a[3] < eps || b[3] < eps) { /* clip the edge to the near side */
		float *in = a[3] < eps ? b : a, *out = a[3] < eps ? a : b;
		float t = (eps - in[3]) / (out[3] - in[3]);
		for (int k = 0; k < 4; k++)
			out[k] = in[k] + t * (out[k] - in[k]);
	}
	float dx = (a[0] / a[3] - b[0] / b[3]) * 0.5f * (float)w, dy = (a[1] / a[3] - b[1] / b[3]) * 0.5f * (float)h;
	return sqrtf(dx * dx + dy * dy);
}

void atlas_edge_lengths(const float *clip, bool single, uint32_t width, uint32_t height, float *lu, float *lv)
{
	const float *c[4] = {clip, clip + 4, clip + 8, clip + 12};
	*lu = edge_px(c[1], c[0], width, height);
	*lv = edge_px(c[2], c[0], width, height);
	if (!single) {
		*lu = fmaxf(*lu, edge_px(c[3], c[2], width, height));
		*lv = fmaxf(*lv, edge_px(c[3], c[1], width, height));
	}
}

uint32_t atlas_level(float length, float rho, uint32_t lmax, uint32_t cur, bool *clamped)
{
	float x = log2f(rho * length + 1.0f);
	*clamped = false;
	if (cur && x > (float)cur - ATLAS_HYSTERESIS_BELOW && x <= (float)cur + ATLAS_HYSTERESIS_ABOVE)
		return cur;
	float c = ceilf(x);
	if (c > (float)lmax) {
		*clamped = true;
		return lmax;
	}
	return c < 1.0f ? 1u : (uint32_t)c;
}

/* ---- buddy over [0, 2^order): tree node value = 1 + log2 of the largest free block below it, 0 = none ---- */

typedef struct buddy {
	uint32_t order;
	uint8_t *tree; /* 2^(order + 1) - 1 nodes, root 0, children 2i + 1, 2i + 2 */
} buddy;

/* false when out of memory */
static bool buddy_init(buddy *b, uint32_t order)
{
	b->order = order;
	size_t n = ((size_t)2 << order) - 1;
	if (!(b->tree = malloc(n)))
		return false;
	for (size_t i = 0, d = 0, next = 1; i < n; i++) {
		if (i == next)
			d++, next = next * 2 + 1;
		b->tree[i] = (uint8_t)(order - d + 1);
	}
	return true;
}

static void buddy_update_up(buddy *b, size_t i, uint32_t node_order)
{
	while (i > 0) {
		i = (i - 1) / 2;
		node_order++;
		uint8_t l = b->tree[2 * i + 1], r = b->tree[2 * i + 2];
		b->tree[i] = l == node_order && r == node_order ? (uint8_t)(node_order + 1) : (l > r ? l : r);
	}
}

static bool buddy_alloc(buddy *b, uint32_t o, uint32_t *offset)
{
	if (o > b->order || b->tree[0] < o + 1)
		return false;
	size_t i = 0;
	uint32_t node_order = b->order;
	while (node_order > o) {
		i = b->tree[2 * i + 1] >= o + 1 ? 2 * i + 1 : 2 * i + 2; /* leftmost: lowest address */
		node_order--;
	}
	b->tree[i] = 0;
	*offset = (uint32_t)((i - (((size_t)1 << (b->order - o)) - 1)) << o);
	buddy_update_up(b, i, o);
	return true;
}

static void buddy_free(buddy *b, uint32_t offset, uint32_t o)
{
	size_t i = (offset >> o) + (((size_t)1 << (b->order - o)) - 1);
	b->tree[i] = (uint8_t)(o + 1);
	buddy_update_up(b, i, o);
}

static bool buddy_empty(const buddy *b) { return b->tree[0] == b->order + 1; }

/* ---- shelves ---- */

typedef struct shelf {
	uint32_t y, lh;
	buddy cols;
} shelf;

struct atlas_alloc {
	uint32_t lw_atlas, lh_atlas;
	buddy rows;
	shelf *shelves; /* sorted by y */
	size_t count, cap;
	uint64_t used;
};

static uint32_t log2u(uint32_t v)
{
	uint32_t l = 0;
	while ((1u << l) < v)
		l++;
	return l;
}

int atlas_alloc_create(uint32_t width, uint32_t height, atlas_alloc **out, char *err, size_t err_size)
{
	*out = NULL;
	if (width < 2 || height < 2 || (width & (width - 1)) || (height & (height - 1)) || width > 65536 || height > 65536)
		return tl_error(err, err_size, TL_ERR_ARG, "atlas %ux%u: sides must be powers of two in 2..65536", width, height);
	atlas_alloc *a = calloc(1, sizeof *a);
	if (!a || !buddy_init(&a->rows, log2u(height))) {
		free(a);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	a->lw_atlas = log2u(width);
	a->lh_atlas = log2u(height);
	*out = a;
	return TL_OK;
}

void atlas_alloc_destroy(atlas_alloc **pa)
{
	atlas_alloc *a = *pa;
	if (!a)
		return;
	for (size_t i = 0; i < a->count; i++)
		free(a->shelves[i].cols.tree);
	free(a->shelves);
	free(a->rows.tree);
	free(a);
	*pa = NULL;
}

bool atlas_alloc_block(atlas_alloc *a, uint32_t lw, uint32_t lh, uint32_t *x, uint32_t *y)
{
	if (lw > a->lw_atlas || lh > a->lh_atlas)
		return false;
	for (size_t i = 0; i < a->count; i++)
		if (a->shelves[i].lh == lh && buddy_alloc(&a->shelves[i].cols, lw, x)) {
			*y = a->shelves[i].y;
			a->used += (uint64_t)1 << (lw + lh);
			return true;
		}
	uint32_t sy;
	if (!buddy_alloc(&a->rows, lh, &sy))
		return false;
	if (a->count == a->cap) {
		size_t cap = a->cap ? a->cap * 2 : 16;
		shelf *n = realloc(a->shelves, cap * sizeof *n);
		if (!n) {
			buddy_free(&a->rows, sy, lh);
			return false;
		}
		a->shelves = n, a->cap = cap;
	}
	shelf s = {.y = sy, .lh = lh};
	if (!buddy_init(&s.cols, a->lw_atlas)) {
		buddy_free(&a->rows, sy, lh);
		return false;
	}
	size_t k = a->count++;
	while (k > 0 && a->shelves[k - 1].y > sy) {
		a->shelves[k] = a->shelves[k - 1];
		k--;
	}
	a->shelves[k] = s;
	buddy_alloc(&a->shelves[k].cols, lw, x);
	*y = sy;
	a->used += (uint64_t)1 << (lw + lh);
	return true;
}

void atlas_alloc_free(atlas_alloc *a, uint32_t x, uint32_t y, uint32_t lw, uint32_t lh)
{
	for (size_t i = 0; i < a->count; i++) {
		shelf *s = &a->shelves[i];
		if (s->y != y || s->lh != lh)
			continue;
		buddy_free(&s->cols, x, lw);
		a->used -= (uint64_t)1 << (lw + lh);
		if (buddy_empty(&s->cols)) {
			buddy_free(&a->rows, s->y, s->lh);
			free(s->cols.tree);
			memmove(s, s + 1, (a->count - i - 1) * sizeof *s);
			a->count--;
		}
		return;
	}
}

uint64_t atlas_alloc_used(const atlas_alloc *a) { return a->used; }
