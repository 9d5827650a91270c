/* run.h — a run folder (DESIGN section 5): frames/NNNNNN.exr + .png, stats.csv, manifest.json.
 *
 * Completeness protocol: run_writer_create deletes any manifest.json left in the folder, every file
 * is written under a temporary name and renamed into place, and manifest.json is written last
 * (run_writer_finish). A folder with a manifest.json is therefore a complete run; one without is not.
 */
#ifndef TASLAB_RUN_H
#define TASLAB_RUN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "taslab/render.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct run_info {
	const char *scene_name, *scene_path, *camera, *camera_motion, *method, *device, *driver;
	float threshold;
	uint32_t first_frame, last_frame; /* inclusive */
	uint32_t width, height;
	float fps;
	bool validation;
	bool write_exr, write_png;
	const char *command_line;
	const char *display_transform; /* colour_name() of the view transform used for the PNGs */
} run_info;

typedef struct run_writer run_writer;

int run_writer_create(const char *dir, const run_info *info, run_writer **out, char *err, size_t err_size);
/* Writes the frame's EXR and PNG and appends its stats.csv row. */
int run_writer_frame(run_writer *w, const render_image *img, const render_stats *st, char *err, size_t err_size);
/* Closes stats.csv and writes manifest.json (atomically) with totals. */
int run_writer_finish(run_writer *w, double wall_s, char *err, size_t err_size);
/* Frees the writer; an unfinished run leaves no manifest.json. */
void run_writer_destroy(run_writer **w);

/* Renders frames [first, end) of a scene/camera with a method into a run folder: render_create, then
 * render_frame + run_writer_frame per frame, then run_writer_finish. Fails on any Vulkan validation
 * message when the device has validation on. `progress` (may be NULL) is called after each frame. */
typedef struct run_render_desc {
	struct vkdev *dev;
	const struct scene *scene;
	const char *scene_path;
	int camera;
	const struct colour *colour;
	const char *method;
	float threshold;
	uint32_t max_age; /* tfr: K (0 = RENDER_TFR_MAX_AGE) */
	uint32_t first, end;
	uint32_t width, height;
	float fps;
	bool write_exr, write_png, trivial_shading;
	const char *out;
	const char *command_line;
	void (*progress)(void *user, uint32_t done, uint32_t total);
	void *user;
} run_render_desc;

enum { RUN_ERR_OUTPUT = -2 /* the run folder could not be created or written */ };
int run_render(const run_render_desc *d, char *err, size_t err_size);

/* Creates a directory and its parents (like mkdir -p). */
int run_mkdirs(const char *path, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
