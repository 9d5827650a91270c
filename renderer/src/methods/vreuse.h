/* vreuse.h (private) — temporal reuse on the compacted sample path (BASELINES.md A2, A6; passes/vbuf.h): the
 * survey's refresh patterns that a stencil cannot save on lavapipe (`rrc-random/N`, `rrc-interleaved/N`) and frame
 * extrapolation (`warp/N`). A per-pixel cache (colour as shown, object + 1 and view distance) of an earlier frame is
 * reverse-reprojected per pixel of frame t (the reprojecting visibility pass records where its surface point was);
 * the methods decide per pixel which samples to shade, the listed samples are shaded by the path's indirect shade,
 * the rest show the cache (bilinear with per-tap validity, TAS-METHODS section 1) or, for warp, are filled by
 * pull-push.
 *
 * Frame (rrc variants; state slot 0 = t, slot 1 = t-1): shadow, ids (one geometry pass writing the ids and the
 * reprojecting visibility record), decide (reproject, decide, append; the reused pixels' values and next-cache
 * texels; the dispatch arguments), shade (indirect, into the HDR target), resolve (indirect: the shaded pixels'
 * next-cache texels; the two caches swap per frame), truth (--truth only, vbuf_record_truth; left out of the frame
 * time), blend, display, readback.
 * Frame (warp; slot 1 = the keyframe): key frames are ref's shading after the visibility pass, which leaves ref's
 * depth (the pre-pass) and the record, then a store of the cache; other frames: ids (the visibility pass), warp
 * (reproject the keyframe), fill (pull-push into the holes); then truth
 * (--truth: this frame's ids, shadows on extrapolated frames, the truth pass), blend, display,
 * readback - no shading of opaque surfaces is launched.
 * Frame (amss; slot 1 = t-1): as the rrc variants, every covered pixel shaded once at the frame's sub-pixel offset;
 * the "resolve" interval combines it with the reprojected 2x2 sub-pixel buffer (amss.comp.in).
 * Frame (stu; slot 1 = t-1): the interleaved phase pixels shaded; the "resolve" interval holds the gradient and the
 * spatio-temporal combination of the others (stu.comp.in). */
#ifndef TASLAB_VREUSE_H
#define TASLAB_VREUSE_H

#include "../passes/vbuf.h"

typedef enum vreuse_mode { VREUSE_RRC_RANDOM = 1, VREUSE_RRC_INTERLEAVED, VREUSE_WARP, VREUSE_AMSS, VREUSE_STU } vreuse_mode;

typedef struct vreuse_variant {
	vreuse_mode mode;
	uint32_t period; /* N */
	uint32_t group;  /* rrc variants: 0 per pixel, 1 2x2, 2 4x2 */
	uint32_t buffers; /* amss: 1 or 4 */
	float alpha;      /* amss: the weight of the new sample */
	float bound;      /* amss: the signal-change bound E (0: off; amss.comp.in) */
	float blur_bound; /* amss: the resampling-blur bound B, pixels (0: off; amss.comp.in) */
	uint32_t age_limit; /* amss: frames a quadrant not due may go without its own sample (0: no limit) */
	bool truth;       /* --truth (not amss): count late_samples against vref's shading (vbuf truth pass) */
	float truth_t;
} vreuse_variant;

int vreuse_init(render *r, const vreuse_variant *v, char *err, size_t err_size);
int vreuse_prepare(render *r, uint32_t frame, char *err, size_t err_size);
void vreuse_record(render *r, VkCommandBuffer cmd, uint32_t frame);
void vreuse_collect(render *r, frame_stats *st);
void vreuse_finish(render *r);

extern const char *const vreuse_rrc_passes[9];
extern const char *const vreuse_warp_passes[10];

#define VREUSE_FRAME_OPS                                                                                           \
	.state_ring = 2, .prepare = vreuse_prepare, .record = vreuse_record, .collect = vreuse_collect, \
	.finish = vreuse_finish

#endif
