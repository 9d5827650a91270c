/* render.h — the frame pipeline: renders frames of a scene with a rendering method on a Vulkan device.
 *
 * A `render` owns the GPU copy of a scene (geometry, materials, texture arrays), the shared passes
 * (shadow maps, depth pre-pass, forward shading, display encoding, readback) and one method's state.
 * Methods and their options come from the registry of method.h (ref, tfr; rrc, tarc, sa, sau, tasa plug
 * in the same way), sharing scene evaluation, shading code, the display transform and outputs (README
 * "Frame pipeline").
 *
 * Frames are rendered synchronously. `ref` renders any frame independently; methods with temporal state
 * (reuse) must be fed consecutive frames (a jump restarts their history). Determinism: same inputs on the
 * same device give identical results.
 *
 * Ownership: render_create borrows `dev`, `scene` and `colour` (they must outlive the render) and copies
 * the method configuration. Errors: negative tl_err, one line in `err`.
 */
#ifndef TASLAB_RENDER_H
#define TASLAB_RENDER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "taslab/colour.h"
#include "taslab/frame.h"
#include "taslab/method.h"
#include "taslab/scene.h"
#include "taslab/tl_error.h"
#include "taslab/vkdev.h"

#ifdef __cplusplus
extern "C" {
#endif


typedef struct render render;

/* How a stereo render records the raster pass both eyes of the atlas methods have (the visibility pass; STEREO.md
 * "Vulkan multiview"): ON one render pass with viewMask 0b11 into 2-layer attachments (VK_KHR_multiview, Vulkan 1.1's
 * optional multiview feature), OFF one pass per eye; AUTO the measured choice (README "Multiview"). The output is the
 * same either way. */
typedef enum render_multiview { RENDER_MULTIVIEW_AUTO = 0, RENDER_MULTIVIEW_ON, RENDER_MULTIVIEW_OFF } render_multiview;

typedef struct render_desc {
	const struct scene *scene;
	int camera;             /* index into scene->cameras */
	uint32_t width, height;
	float fps;              /* frame f is at t = f / fps; 0 = the scene's fps */
	const method_config *method; /* the method and its options (copied); NULL: ref */
	bool trivial_shading;   /* benchmark only: swap the shading for base colour output */
	bool decisions;         /* fill frame_image.decisions (methods with reuse decisions only) */
	bool rate_images;       /* fill frame_image.tile_rates (methods with tile rates only: method_info.tile_rates) */
	const struct colour *colour; /* display transform (borrowed); NULL: the built-in ACES default */
	/* Stereo (STEREO.md): views 2 renders a left (0) and a right (1) eye, each width x height, the eyes ipd metres
	 * apart along the camera's right axis (parallel axes); 0 or 1: mono. eye_shift (mono only): the camera moved
	 * that far along its right axis (-ipd/2: the left eye of a stereo run, for comparisons). */
	uint32_t views;
	float ipd, eye_shift;
	render_multiview multiview; /* stereo only (mono: AUTO) */
} render_desc;

/* The largest --ipd accepted, in metres (a human IPD is 0.054-0.074; larger values are hyperstereo, up to 1 m). */
#define RENDER_IPD_MAX 1.0f
/* --ipd when not given (metres; a common adult mean, [P] of STEREO.md) */
#define RENDER_STEREO_IPD_DEFAULT 0.063

int render_create(vkdev *dev, const render_desc *desc, render **out, char *err, size_t err_size);
void render_destroy(render **r);
/* Renders frame `frame` (time = frame / fps) and reads it back; img's pixels stay valid until the next
 * render_frame. */
int render_frame(render *r, uint32_t frame, frame_image *img, frame_stats *stats, char *err, size_t err_size);
/* Stereo: view v's image of the last render_frame (render_frame's `img` is view 0's, the left eye). Valid until the
 * next render_frame. Returns TL_ERR_ARG for a view the render does not have. In stereo, render_frame's statistics
 * are totals over both eyes, with the per-eye counts in the extra columns visible_samples_l/_r and
 * shaded_samples_l/_r (the atlas methods: the shaded texels of the blocks each eye sees; the shared ones count for
 * both eyes, the total once). */
int render_view_image(render *r, uint32_t v, frame_image *img);
uint32_t render_view_count(const render *r);
/* What the method derived from its options at creation (atlas size, density used, ...: manifest
 * inputs.method_derived); returns the count (<= max), 0 for methods that derive nothing. */
size_t render_derived(const render *r, run_option *out, size_t max);

/* ---- one run: render frames into a run folder (run.h) ---- */

/* Renders frames [first, end) of a scene/camera with a method into a run folder: render_create, then
 * render_frame + run_writer_frame per frame, then run_writer_finish. Fails on any Vulkan validation
 * message when the device has validation on. `progress` (may be NULL) is called after each frame. */
typedef struct render_run_desc {
	vkdev *dev;
	const struct scene *scene;
	const char *scene_path;
	int camera;
	const struct colour *colour;
	const method_config *method; /* NULL: ref */
	uint32_t first, end;
	uint32_t width, height;
	float fps;
	bool write_exr, write_png, trivial_shading;
	bool write_decisions;   /* RUN/decisions/ (render_desc.decisions) */
	bool write_rates;       /* RUN/rates/ (render_desc.rate_images) */
	uint32_t views;         /* 2: stereo (render_desc.views), frames/L, frames/R and sbs/ */
	float ipd;
	render_multiview multiview; /* render_desc.multiview */
	const char *out;
	const char *command_line;
	void (*progress)(void *user, uint32_t done, uint32_t total);
	void *user;
} render_run_desc;

int render_run(const render_run_desc *d, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
