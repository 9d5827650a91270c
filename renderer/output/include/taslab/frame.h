/* frame.h — what a rendered frame is once it leaves the renderer: its pixels and its statistics
 * (DESIGN section 5, the rows of stats.csv). Plain data, no Vulkan: the run writer (run.h) and the
 * renderer (render.h) share these types. */
#ifndef TASLAB_FRAME_H
#define TASLAB_FRAME_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FRAME_MAX_PASSES 12 /* timed passes per frame (gpu_ms_<pass> columns) */
#define FRAME_MAX_EXTRA 12  /* method-specific columns (cpu_ms_<step>, atlas counters, ...) */

/* Per-frame statistics (stats.csv). Counts of -1 mean "not applicable / not available" (empty cells). */
typedef struct frame_stats {
	uint32_t frame;
	double time_s;
	int64_t visible_samples, shaded_samples;
	int64_t reused_samples;                 /* samples shown from earlier shading */
	int64_t allocated_samples;              /* atlas methods: texels allocated to visible blocks */
	int64_t late_samples;                   /* --truth: reused samples more than T from the truth */
	int64_t visible_units, shaded_units, new_units;
	int64_t fs_invocations, cs_invocations; /* pipeline statistics over the method's shading passes */
	double gpu_ms_total;
	uint32_t pass_count;
	const char *pass_names[FRAME_MAX_PASSES];
	double gpu_ms[FRAME_MAX_PASSES];        /* negative when timestamps are unavailable */
	uint32_t extra_count;                   /* further columns, named by the method; NAN = empty */
	const char *extra_names[FRAME_MAX_EXTRA];
	double extra[FRAME_MAX_EXTRA];
} frame_stats;

/* Per-pixel reuse decision of a reuse method for the opaque sample of a pixel (`render --decisions`,
 * RUN/decisions/NNNNNN.png; TAS-METHODS section 9 checks them pixel by pixel). */
typedef enum frame_decision {
	FRAME_DECISION_NONE = 0,      /* no opaque sample (background; BLEND surfaces are not counted) */
	FRAME_DECISION_REUSED = 1,    /* shown from earlier shading */
	FRAME_DECISION_NEW = 2,       /* shaded: no valid cache entry (first frame, disocclusion, cache miss) */
	FRAME_DECISION_SECOND = 3,    /* shaded: second frame after becoming visible (paper sec. 6 step 1) */
	FRAME_DECISION_PREDICTED = 4, /* shaded: predicted change beyond T (oracle: true change beyond T) */
	FRAME_DECISION_SCHEDULED = 5, /* shaded on a schedule: rrc tile refresh, --max-age, --force-reshade */
	FRAME_DECISION_LATE = 6,      /* reused, and more than T from its true shading (--truth): late_samples */
	FRAME_DECISION_COUNT
} frame_decision;

/* The shading rate of a 16x16 tile of a VRS method (`render --rate-images`, RUN/rates/NNNNNN.png), w x h pixels per
 * shading, in ascending shading density (BASELINES.md A7's palette; the default palette uses 4x4, 2x2 and 1x1). */
typedef enum frame_rate {
	FRAME_RATE_4X4 = 0,
	FRAME_RATE_4X2 = 1,
	FRAME_RATE_2X4 = 2,
	FRAME_RATE_2X2 = 3,
	FRAME_RATE_2X1 = 4,
	FRAME_RATE_1X2 = 5,
	FRAME_RATE_1X1 = 6,
	FRAME_RATE_COUNT
} frame_rate;

/* A frame's pixels. Pointers are borrowed (the renderer's: valid until its next frame). */
typedef struct frame_image {
	uint32_t width, height;
	const uint16_t *hdr_rgba_half; /* scene-linear radiance * exposure, alpha = coverage; tightly packed */
	const uint8_t *display_rgba;   /* display-referred 8-bit, tightly packed */
	const uint8_t *decisions;      /* one frame_decision per pixel; NULL unless requested and supported */
	const uint8_t *tile_rates;     /* one frame_rate per 16x16 tile, tiles_x x tiles_y, row-major; NULL unless
					  requested (render_desc.rate_images) */
	uint32_t tiles_x, tiles_y;
} frame_image;

#ifdef __cplusplus
}
#endif
#endif
