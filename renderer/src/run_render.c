/* run_render.c — one run: render frames with a method and write them to a run folder (run.h). */
#include <stdio.h>
#include <time.h>

#include "taslab/colour.h"
#include "taslab/render.h"
#include "taslab/run.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

static double now_s(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int run_render(const run_render_desc *d, char *err, size_t err_size)
{
	int rc = -1;
	render *r = NULL;
	run_writer *w = NULL;
	const scene *scn = d->scene;
	render_desc rd = {
		.scene = scn,
		.camera = d->camera,
		.width = d->width,
		.height = d->height,
		.fps = d->fps,
		.method = d->method,
		.threshold = d->threshold,
		.max_age = d->max_age,
		.trivial_shading = d->trivial_shading,
		.colour = d->colour,
	};
	if (render_create(d->dev, &rd, &r, err, err_size))
		goto done;
	run_info info = {
		.scene_name = scn->name,
		.scene_path = d->scene_path,
		.camera = scn->cameras[d->camera].name,
		.camera_motion = scene_camera_motion_name(scn->cameras[d->camera].motion),
		.method = d->method,
		.device = d->dev->props.deviceName,
		.driver = d->dev->driver_info,
		.threshold = d->threshold,
		.first_frame = d->first,
		.last_frame = d->end - 1,
		.width = d->width,
		.height = d->height,
		.fps = d->fps,
		.validation = d->dev->validation,
		.write_exr = d->write_exr,
		.write_png = d->write_png,
		.command_line = d->command_line,
		.display_transform = d->colour ? colour_name(d->colour) : NULL,
	};
	if (run_writer_create(d->out, &info, &w, err, err_size)) {
		rc = RUN_ERR_OUTPUT;
		goto done;
	}
	double t0 = now_s();
	for (uint32_t f = d->first; f < d->end; f++) {
		render_image img;
		render_stats st;
		char why[1024];
		if (render_frame(r, f, &img, &st, why, sizeof why) || run_writer_frame(w, &img, &st, why, sizeof why)) {
			snprintf(err, err_size, "frame %u: %s", f, why);
			goto done;
		}
		if (d->dev->validation && vkdev_validation_messages(d->dev)) {
			snprintf(err, err_size, "%u Vulkan validation message(s) at frame %u (printed above); run not completed",
				 vkdev_validation_messages(d->dev), f);
			goto done;
		}
		if (d->progress)
			d->progress(d->user, f - d->first + 1, d->end - d->first);
	}
	if (run_writer_finish(w, now_s() - t0, err, err_size))
		goto done;
	rc = 0;
done:
	run_writer_destroy(&w);
	render_destroy(&r);
	return rc;
}
