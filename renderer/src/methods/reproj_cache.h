/* reproj_cache.h (private) — the per-pixel reprojection cache shared by rrc and tarc (TAS-METHODS sections
 * 1-3): double-buffered cache images, the reproject / mark / shade / truth passes and their counters. The
 * method files (rrc.c, tarc.c) declare the options and choose the variant. */
#ifndef TASLAB_REPROJ_CACHE_H
#define TASLAB_REPROJ_CACHE_H

#include "../passes/passes.h"

typedef struct reproj_variant {
	bool tarc;        /* else rrc */
	bool oracle;      /* tarc's ideal variant */
	bool nearest;     /* nearest-pixel lookup (else bilinear with per-tap validity) */
	bool truth;       /* --truth: count late samples among the reused ones */
	bool force;       /* tarc --force-reshade: decide to reshade everything (overhead measurement) */
	uint32_t period;  /* rrc N */
	uint32_t max_age; /* tarc K (0: none) */
	float threshold;  /* tarc T; rrc: the T late samples are counted against with --truth */
	uint32_t payload; /* rrc --payload: REPROJ_PAYLOAD_* */
} reproj_variant;

/* rrc --payload ([S] sec. 4.1, BASELINES A5): what the cache keeps. COLOUR: the shaded colour (rrc as the paper has it).
 * SHADOW: the shadow factors of lights 0..7; DIFFUSE: the diffuse term. The rest of the shading runs every frame. */
enum { REPROJ_PAYLOAD_COLOUR = 0, REPROJ_PAYLOAD_SHADOW, REPROJ_PAYLOAD_DIFFUSE };

int reproj_init(render *r, const reproj_variant *v, char *err, size_t err_size);
int reproj_prepare(render *r, uint32_t frame, char *err, size_t err_size);
void reproj_record(render *r, VkCommandBuffer cmd, uint32_t frame);
void reproj_collect(render *r, frame_stats *st);
const uint8_t *reproj_decisions(render *r);
void reproj_finish(render *r);

#endif
