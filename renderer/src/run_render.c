/* run_render.c — one run: render frames with a method and write them to a run folder (render.h, run.h). */
#include <math.h>
#include <stdio.h>

#include "taslab/colour.h"
#include "taslab/render.h"
#include "taslab/run.h"
#include "taslab/scene.h"
#include "taslab/tl_clock.h"
#include "taslab/vkdev.h"

int render_run(const render_run_desc *d, char *err, size_t err_size)
{
	int rc;
	render *r = NULL;
	run_writer *w = NULL;
	const scene *scn = d->scene;
	method_config ref;
	const method_config *mc = d->method;
	if (!mc && (rc = method_config_init(&ref, "ref", err, err_size)))
		return rc;
	if (!mc)
		mc = &ref;
	render_desc rd = {
		.scene = scn,
		.camera = d->camera,
		.width = d->width,
		.height = d->height,
		.fps = d->fps,
		.method = mc,
		.trivial_shading = d->trivial_shading,
		.decisions = d->write_decisions,
		.rate_images = d->write_rates,
		.colour = d->colour,
		.views = d->views,
		.ipd = d->ipd,
		.multiview = d->multiview,
	};
	if ((rc = render_create(d->dev, &rd, &r, err, err_size)))
		goto done;
	char name[64], variant[96];
	method_config_name(mc, name, sizeof name);
	method_config_variant(mc, variant, sizeof variant);
	run_option opts[RUN_MAX_OPTIONS], derived[RUN_MAX_OPTIONS];
	size_t nopt = method_config_run_options(mc, opts, RUN_MAX_OPTIONS);
	size_t nderived = render_derived(r, derived, RUN_MAX_OPTIONS);
	char api[32];
	snprintf(api, sizeof api, "%u.%u.%u", VK_API_VERSION_MAJOR(d->dev->props.apiVersion),
		 VK_API_VERSION_MINOR(d->dev->props.apiVersion), VK_API_VERSION_PATCH(d->dev->props.apiVersion));
	char scene_hex[SCENE_DIGEST_HEX], colour_hex[COLOUR_DIGEST_HEX];
	scene_digest(scn, scene_hex);
	colour_hex[0] = 0;
	if (d->colour)
		colour_digest(d->colour, colour_hex);
	run_method_facts facts; /* what metrics and studies need to know of the method (issue 30.1) */
	method_facts(mc->method, &facts);
	run_info info = {
		.scene_digest = scene_hex,
		.colour_digest = colour_hex[0] ? colour_hex : NULL,
		.scene_name = scn->name,
		.scene_path = d->scene_path,
		.camera = scn->cameras[d->camera].name,
		.camera_motion = scene_camera_motion_name(scn->cameras[d->camera].motion),
		.method = name,
		.variant = variant,
		.threshold = method_config_threshold(mc),
		.period = method_config_period(mc),
		.facts = facts,
		.options = opts,
		.option_count = nopt,
		.derived = derived,
		.derived_count = nderived,
		.ocio_version = colour_library_version(),
		.vulkan_api = api,
		.device = d->dev->props.deviceName,
		.driver = d->dev->driver_info,
		.first_frame = d->first,
		.last_frame = d->end - 1,
		.width = d->width,
		.height = d->height,
		.fps = d->fps,
		.validation = d->dev->validation,
		.write_exr = d->write_exr,
		.write_png = d->write_png,
		.write_decisions = d->write_decisions,
		.write_rates = d->write_rates,
		.command_line = d->command_line,
		.display_transform = d->colour ? colour_name(d->colour) : NULL,
		.views = d->views > 1 ? d->views : 1,
		.ipd = d->ipd,
	};
	if ((rc = run_writer_create(d->out, &info, &w, err, err_size)))
		goto done;
	double t0 = tl_clock_s();
	for (uint32_t f = d->first; f < d->end; f++) {
		frame_image img;
		frame_stats st;
		char why[1024];
		frame_image eyes[2];
		if ((rc = render_frame(r, f, &img, &st, why, sizeof why)) ||
		    (d->views > 1 && ((rc = render_view_image(r, 0, &eyes[0])) || (rc = render_view_image(r, 1, &eyes[1])) ||
				      (rc = run_writer_frame_views(w, eyes, 2, &st, why, sizeof why)))) ||
		    (d->views < 2 && (rc = run_writer_frame(w, &img, &st, why, sizeof why)))) {
			snprintf(err, err_size, "frame %u: %s", f, why);
			goto done;
		}
		if (d->dev->validation && vkdev_validation_messages(d->dev)) {
			rc = tl_error(err, err_size, TL_ERR_VALIDATION,
				      "%u Vulkan validation message(s) at frame %u (printed above); run not completed",
				      vkdev_validation_messages(d->dev), f);
			goto done;
		}
		if (d->progress)
			d->progress(d->user, f - d->first + 1, d->end - d->first);
	}
	rc = run_writer_finish(w, tl_clock_s() - t0, err, err_size);
done:
	run_writer_destroy(&w);
	render_destroy(&r);
	return rc;
}
