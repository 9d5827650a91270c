/* cmd_scenes.c — `taslab scenes`: lists the built-in scenes with their camera paths. */
#include <dirent.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "taslab/scene.h"

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

static int scenes_main(void *opts, cli_ctx *ctx)
{
	(void)opts;
	const char *dir = cli_scenes_dir();
	DIR *d = opendir(dir);
	if (!d)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_INPUT, "cannot open the scenes folder %s (set TASLAB_SCENES)",
				dir);
	char *names[256];
	size_t n = 0;
	struct dirent *e;
	while ((e = readdir(d)) && n < 256) {
		size_t len = strlen(e->d_name);
		if (len > 5 && !strcmp(e->d_name + len - 5, ".json") && e->d_name[0] != '.')
			names[n++] = strdup(e->d_name);
	}
	closedir(d);
	qsort(names, n, sizeof names[0], cmp_str);
	int status = TL_OK;
	for (size_t i = 0; i < n; i++) {
		char path[4096], err[1024];
		scene *s = NULL;
		snprintf(path, sizeof path, "%s/%s", dir, names[i]);
		if (!names[i] || scene_load(path, &s, err, sizeof err)) {
			fprintf(stderr, "taslab scenes: %s\n", names[i] ? err : "out of memory");
			status = TL_ERR_INPUT;
			snprintf(ctx->err, sizeof ctx->err, "some scenes did not load (see above)");
		} else {
			printf("%s  (%.1f s at %g fps, %zu objects, %zu lights)\n", s->name, (double)s->duration_s,
			       (double)s->fps, s->object_count, s->light_count);
			for (size_t c = 0; c < s->camera_count; c++)
				printf("    camera %-16s %s\n", s->cameras[c].name, scene_camera_motion_name(s->cameras[c].motion));
			scene_destroy(&s);
		}
		free(names[i]);
	}
	return status;
}

const cli_command cli_cmd_scenes = {
	.name = "scenes",
	.summary = "list built-in scenes and their camera paths",
	.synopsis = "taslab scenes",
	.description = "Lists the built-in scenes (scenes/*.json, or $TASLAB_SCENES) with their duration, lights and\n"
		       "camera paths (stationary or moving), for 'taslab render --scene/--camera'.",
	.run = scenes_main,
};
