/* setup.c — the setup shared by commands that declare CLI_NEED_SCENE / _COLOUR / _DEVICE (cli.h): done once
 * here instead of in every command. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "taslab/colour.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

int cli_setup_run(unsigned needs, const cli_setup_opts *o, cli_setup *s, char *err, size_t err_size)
{
	int rc;
	memset(s, 0, sizeof *s);
	s->width = o->size[0];
	s->height = o->size[1];
	if (needs & CLI_NEED_SCENE) {
		if ((rc = cli_resolve_scene(o->scene, s->scene_path, sizeof s->scene_path, err, err_size)) ||
		    (rc = scene_load(s->scene_path, &s->scene, err, err_size)))
			return rc;
		const scene *scn = s->scene;
		s->camera = o->camera ? scene_find_camera(scn, o->camera) : 0;
		if (s->camera < 0) {
			char names[512] = "";
			for (size_t i = 0; i < scn->camera_count; i++) {
				strncat(names, i ? ", " : "", sizeof names - strlen(names) - 1);
				strncat(names, scn->cameras[i].name, sizeof names - strlen(names) - 1);
			}
			return tl_error(err, err_size, TL_ERR_ARG, "scene '%s' has no camera path '%s' (available: %s)", scn->name,
					o->camera, names);
		}
		s->fps = o->fps > 0 ? (float)o->fps : scn->fps;
		s->first = 0;
		s->end = (uint32_t)lround((double)scn->duration_s * s->fps);
		if (s->end < 1)
			s->end = 1;
		bool given;
		if (o->frames && !(needs & CLI_NEED_FRAME_LIST) &&
		    (rc = cli_parse_frames(o->frames, &s->first, &s->end, &given, err, err_size)))
			return rc;
	}
	if (needs & CLI_NEED_COLOUR) {
		colour_desc cd = {.config_path = o->ocio_config, .display = o->display, .view = o->view};
		if ((rc = colour_create(&cd, &s->colour, err, err_size)))
			return rc;
	}
	if (needs & CLI_NEED_DEVICE) {
		vkdev_desc dd = {.device = o->device, .validation = o->validation};
		VkResult vr = vkdev_create(&dd, &s->dev, err, err_size);
		if (vr)
			return TL_ERR_VULKAN;
	}
	return TL_OK;
}

void cli_setup_free(cli_setup *s)
{
	vkdev_destroy(&s->dev);
	colour_destroy(&s->colour);
	scene_destroy(&s->scene);
}
