/* render.h — the frame pipeline: renders frames of a scene with a rendering method.
 *
 * A `render` owns the GPU copy of a scene (geometry, materials, texture arrays), the shared passes
 * (shadow maps, depth pre-pass, forward shading, display encoding, readback) and one method's
 * state. Methods are entries of a table (render_methods()): `ref` today; tfr, rrc, tarc, sa, sau
 * and tasa plug in as further entries sharing scene evaluation, shading code, the display
 * transform and outputs (see the README section "Frame pipeline").
 *
 * Frames are rendered synchronously and independently of each other for `ref`; methods with
 * temporal state (reuse) must be fed consecutive frames. Determinism: same inputs on the same
 * device give identical results.
 *
 * Ownership: render_create borrows `dev` and `scn` (both must outlive the render).
 */
#ifndef TASLAB_RENDER_H
#define TASLAB_RENDER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "taslab/colour.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

#ifdef __cplusplus
extern "C" {
#endif

#define RENDER_MAX_PASSES 8
#define RENDER_TFR_MAX_AGE 119 /* K: TFR keeps shading inputs of up to 119 past frames (paper sec. 5) */

typedef struct render render;

typedef struct render_method_info {
	const char *name;
	const char *summary;
	bool available; /* false: planned, listed for --help, rejected by render_create */
} render_method_info;

/* The method table, `count` entries. */
const render_method_info *render_methods(size_t *count);

typedef struct render_desc {
	const struct scene *scene;
	int camera;             /* index into scene->cameras */
	uint32_t width, height;
	float fps;              /* frame f is at t = f / fps; 0 = the scene's fps */
	const char *method;     /* name from render_methods() */
	float threshold;        /* T in 8-bit code values, for methods that use one */
	uint32_t max_age;       /* tfr: K, the largest age before a forced reshade (1..119; 0 = 119) */
	bool trivial_shading;   /* benchmark only: swap the shading for base colour output */
	const struct colour *colour; /* display transform (borrowed); NULL: the built-in ACES default */
} render_desc;

/* Per-frame statistics (DESIGN section 5, stats.csv). -1 means "not applicable / not available". */
typedef struct render_stats {
	uint32_t frame;
	double time_s;
	int64_t visible_samples, shaded_samples;
	int64_t reused_samples;                 /* visible samples shown from earlier shading */
	int64_t visible_units, shaded_units, new_units;
	int64_t fs_invocations, cs_invocations; /* pipeline statistics over the method's shading passes */
	double gpu_ms_total;
	uint32_t pass_count;
	const char *pass_names[RENDER_MAX_PASSES];
	double gpu_ms[RENDER_MAX_PASSES]; /* negative when timestamps are unavailable */
} render_stats;

/* A frame read back from the device. Pointers stay valid until the next render_frame. */
typedef struct render_image {
	uint32_t width, height;
	const uint16_t *hdr_rgba_half; /* scene-linear radiance * exposure, alpha = coverage; tightly packed */
	const uint8_t *display_rgba;   /* display-referred 8-bit, tightly packed */
} render_image;

enum {
	RENDER_OK = 0,
	RENDER_ERR_ARG = -1,    /* bad description (unknown method, size, camera) */
	RENDER_ERR_VULKAN = -2, /* a Vulkan call failed */
	RENDER_ERR_NOMEM = -3,
};

int render_create(vkdev *dev, const render_desc *desc, render **out, char *err, size_t err_size);
void render_destroy(render **r);
/* Renders frame `frame` (time = frame / fps) and reads it back. */
int render_frame(render *r, uint32_t frame, render_image *img, render_stats *stats, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
