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
#define FRAME_MAX_EXTRA 8   /* method-specific columns (cpu_ms_<step>, atlas counters, ...) */

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

/* A frame's pixels. Pointers are borrowed (the renderer's: valid until its next frame). */
typedef struct frame_image {
	uint32_t width, height;
	const uint16_t *hdr_rgba_half; /* scene-linear radiance * exposure, alpha = coverage; tightly packed */
	const uint8_t *display_rgba;   /* display-referred 8-bit, tightly packed */
} frame_image;

#ifdef __cplusplus
}
#endif
#endif
