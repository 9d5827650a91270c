/* vbuf_family.h (private) — the frame of the methods on the compacted sample path (BASELINES.md section 0,
 * passes/vbuf.h): vref, the VRS rate methods and ads. A method file fills a vbuf_variant in its init and
 * uses VBUF_FRAME_OPS.
 *
 * Frame (state slot 0): shadow, ids, rate (rate methods: the method's tile rates; vref: none), select, shade,
 * resolve, truth (--truth only; left out of the frame time), blend, display, readback — ads: its select/shade rounds form the one "shade" interval. */
#ifndef TASLAB_VBUF_FAMILY_H
#define TASLAB_VBUF_FAMILY_H

#include <stddef.h>

#include "../passes/vbuf.h"

typedef struct vbuf_variant {
	bool ads;
	float S;            /* ads: the threshold (code values; < 0 shades everything) */
	uint32_t step;      /* ads: the initial grid step s0 (a power of two >= 2) */
	bool edge_guard;    /* ads: also shade where a neighbour shows another object or the background */
	bool force;         /* --force-reshade: every covered pixel a 1x1 sample (the path's overhead) */
	bool centroid;      /* --centroid: rate methods shade at the mean of the primitive's pixel centres */
	bool truth;         /* --truth: count late_samples, pixels more than truth_t code values from vref's shading */
	float truth_t;
	/* rate methods: called at init (after the path exists) and to record the rate pass before the select (NULL:
	 * the rates stay 1x1); `user` is theirs. */
	int (*rate_init)(render *r, vbuf_pass *p, void *user, char *err, size_t err_size);
	/* before recording frame `frame` (host state; a jump in frames starts over) */
	void (*rate_prepare)(render *r, vbuf_pass *p, void *user, uint32_t frame);
	void (*rate_record)(render *r, vbuf_pass *p, void *user, VkCommandBuffer cmd, uint32_t frame);
	/* after the resolve (the HDR target GENERAL, before BLEND): what the next frame's rate pass needs of this one */
	void (*rate_after)(render *r, vbuf_pass *p, void *user, VkCommandBuffer cmd, uint32_t frame);
	void (*rate_finish)(render *r, vbuf_pass *p, void *user);
	/* optional, rate methods: records the frame's ids pass in place of ids_pass_record (not with --force-reshade) */
	void (*ids_record)(render *r, vbuf_pass *p, void *user, VkCommandBuffer cmd, uint32_t frame);
	void *user;
} vbuf_variant;

int vbuf_family_init(render *r, const vbuf_variant *v, char *err, size_t err_size);
int vbuf_family_prepare(render *r, uint32_t frame, char *err, size_t err_size);
void vbuf_family_record(render *r, VkCommandBuffer cmd, uint32_t frame);
void vbuf_family_collect(render *r, frame_stats *st);
void vbuf_family_finish(render *r);
/* render --rate-images: the last frame's tile rates (frame_rate codes) from the path's rate buffer. */
const uint8_t *vbuf_family_tile_rates(render *r, uint32_t *tiles_x, uint32_t *tiles_y);
/* The path of a render of one of these methods (tests, method_debug.h). */
vbuf_pass *vbuf_family_pass(render *r);
void *vbuf_family_user(render *r);

extern const char *const vbuf_rate_passes[10];
extern const char *const vbuf_ads_passes[8];
extern const char *const vbuf_vrs_passes[11]; /* methods with rate_after */

/* The --truth options of every method of the family (TYPE has `bool truth; float truth_t;`). */
#define VBUF_TRUTH_OPTIONS(TYPE)                                                                                   \
	{.name = "truth", .help = "also shade every covered pixel as vref does and count those shown more than T from "    \
				  "it (late_samples; T = --truth-threshold)",                                           \
	 .type = METHOD_OPT_BOOL, .offset = offsetof(TYPE, truth)},                                                 \
	{.name = "truth-threshold", .arg = "T", .help = "with --truth: the T of late_samples, in code values",          \
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(TYPE, truth_t), .def = 8, .min = 0, .max = 255}

#define VBUF_FRAME_OPS                                                                                             \
	.prepare = vbuf_family_prepare, .record = vbuf_family_record, .collect = vbuf_family_collect,                \
	.finish = vbuf_family_finish, .tile_rates = vbuf_family_tile_rates

#endif
