/* vbuf.h (private) — the compacted sample path of BASELINES.md section 0, shared by vref, the VRS methods
 * (casedge, castexel, mas, fovea, taas) and ads: per frame the ids pass (ids.h), then
 *   select   compute: decides per pixel and appends the samples to shade to a list (atomicAdd, one global atomic per
 *            workgroup), then a one-invocation pass writes the VkDispatchIndirectCommand of the list;
 *   shade    compute, indirect, workgroups of 64: the listed samples only (work is never launched for a sample not
 *            shaded), ref's shading at the sample's location with analytic texture gradients times its footprint;
 *   resolve  compute: per covered pixel the value of its sample (rate methods: a copy from the leader of its coarse
 *            pixel; ads: its own, shaded or interpolated) into the HDR target cleared to the sky;
 * then BLEND, display and readback as every method (the caller records those).
 * The rate methods read one rate per 16x16 tile from `rates` (w | h << 8), which the method fills (vref: 1x1 on
 * the host; VRS: on the GPU before the select). ads records select + shade once per refinement step.
 * Counters (host visible, zeroed by vbuf_record_begin): VBUF_C_*. */
#ifndef TASLAB_VBUF_H
#define TASLAB_VBUF_H

#include "ids.h"

enum {
	VBUF_C_SHADED = 5,       /* samples shaded, counted by the shade pass */
	VBUF_C_INTERPOLATED = 6, /* ads: pixels interpolated */
	VBUF_C_FILLED = 7,       /* pixels whose value is copied from another pixel's sample (resolve) */
	VBUF_C_LATE = 8,         /* --truth: covered pixels more than T from vref's shading */
	VBUF_C_LISTED = 9,       /* samples appended by the select passes of the frame */
	VBUF_C_METHOD = 10,      /* 10-15: free for the method's own shaders */
};

#define VBUF_TILE 16u
#define VBUF_RATE(w, h) ((uint32_t)(w) | (uint32_t)(h) << 8)

typedef struct vbuf_pass {
	bool ads;
	/* set by the caller before vbuf_init: --centroid (the shade pass samples at the mean of the primitive's pixel
	 * centres in the coarse pixel, BASELINES.md A7) and --truth (the truth pass, late pixels at more than truth_t
	 * code values from vref's shading, BASELINES.md section 0) */
	bool centroid, truth;
	float truth_t;
	ids_pass ids;
	vkdev_buffer objinfo, list, counters, rates;
	vkdev_image svals;           /* RGBA16F: shaded values at leader pixels (ads: and the interpolated ones) */
	vkdev_image sdisp;           /* ads: the display code values of svals' pixels (RG32UI, tas/disp.glsl) */
	uint32_t tiles_x, tiles_y;
	VkDescriptorSetLayout set_layout;
	VkDescriptorSet set;
	VkPipelineLayout layout;     /* sets 0 (scene) and 1 (this), push constants gpu_push */
	VkPipeline select, args, shade, resolve, ads_select, ads_display, truth_pipe;
	VkPipeline shade_last; /* ads: the shade of its last step, without the display values (vref's shade) */
} vbuf_pass;

/* `ads`: the ads select pass instead of the rate select; `shade_defs`: extra #defines of the shade pass. */
int vbuf_init(render *r, vbuf_pass *v, bool ads, char *err, size_t err_size);
void vbuf_finish(render *r, vbuf_pass *v);
/* Compiles a compute template against the path's set and layout (for methods adding passes that see it). */
int vbuf_make_compute(render *r, vbuf_pass *v, const char *path, const char *defs, VkPipeline *out, char *err,
		      size_t err_size);
/* Binds a compute pipeline of the path with push constants (slot, aux). */
void vbuf_bind(render *r, const vbuf_pass *v, VkCommandBuffer cmd, VkPipeline p, uint32_t slot, const uint32_t aux[4]);
/* A barrier between any compute, graphics, transfer and host accesses (between the path's passes). */
void vbuf_barrier(VkCommandBuffer cmd);

/* Zeroes the counters, makes the HDR target GENERAL (the resolve writes it as a storage image). */
void vbuf_record_begin(render *r, vbuf_pass *v, VkCommandBuffer cmd);
/* The rate select (vref, VRS) and its dispatch arguments. */
void vbuf_record_select(render *r, vbuf_pass *v, VkCommandBuffer cmd);
/* One ads step: its select (ads_select.comp.in: s, kind 0 level 0 / 1 diamond / 2 square, threshold S, edge guard),
 * dispatch arguments and indirect shade. Every step but the LAST also stores its pixels' display code values for the
 * later steps' variance (ads_display.comp.in, shade.comp.in with ADS); no step reads the last step's pixels. */
void vbuf_record_ads_step(render *r, vbuf_pass *v, VkCommandBuffer cmd, uint32_t s, uint32_t kind, float S,
			  bool edge_guard, bool last);
/* The indirect shade of the list the last select built. */
void vbuf_record_shade(render *r, vbuf_pass *v, VkCommandBuffer cmd, uint32_t slot);
/* The HDR target cleared to the sky and the resolve (the target stays GENERAL). */
void vbuf_record_resolve(render *r, vbuf_pass *v, VkCommandBuffer cmd);
/* With --truth the truth pass (truth.comp.in: counts VBUF_C_LATE); then, always, the HDR target made a colour
 * attachment again (for BLEND). */
void vbuf_record_truth(render *r, vbuf_pass *v, VkCommandBuffer cmd);
/* The end of a frame on the path, after the method's last pass and its timestamp: BLEND objects composited over the
 * HDR target (in COLOR_ATTACHMENT_OPTIMAL), display, readback, each closed by a timestamp. */
void vbuf_record_finish(render *r, VkCommandBuffer cmd);

#endif
