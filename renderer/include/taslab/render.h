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

typedef struct render_desc {
	const struct scene *scene;
	int camera;             /* index into scene->cameras */
	uint32_t width, height;
	float fps;              /* frame f is at t = f / fps; 0 = the scene's fps */
	const method_config *method; /* the method and its options (copied); NULL: ref */
	bool trivial_shading;   /* benchmark only: swap the shading for base colour output */
	bool decisions;         /* fill frame_image.decisions (methods with reuse decisions only) */
	const struct colour *colour; /* display transform (borrowed); NULL: the built-in ACES default */
} render_desc;

int render_create(vkdev *dev, const render_desc *desc, render **out, char *err, size_t err_size);
void render_destroy(render **r);
/* Renders frame `frame` (time = frame / fps) and reads it back; img's pixels stay valid until the next
 * render_frame. */
int render_frame(render *r, uint32_t frame, frame_image *img, frame_stats *stats, char *err, size_t err_size);
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
