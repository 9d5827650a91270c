/* cmd_render.c — `taslab render`: renders a clip of a scene/camera path with a method into a run
 * folder (DESIGN section 5). Validates every argument and loads the scene before anything is
 * written, so bad input leaves no output behind. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "taslab/colour.h"
#include "taslab/render.h"
#include "taslab/run.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

static void render_usage(FILE *out)
{
	size_t n;
	const render_method_info *m = render_methods(&n);
	fprintf(out,
		"usage: taslab render --scene S [options]\n"
		"\n"
		"Renders frames of a scene along a camera path into a run folder:\n"
		"  RUN/frames/NNNNNN.exr (scene-linear, half), RUN/frames/NNNNNN.png (display 8-bit),\n"
		"  RUN/stats.csv (per frame), RUN/manifest.json (written last: the run is complete).\n"
		"\n"
		"options:\n"
		"  --scene S         built-in scene name (see taslab scenes), a scene .json file, or a .gltf/.glb\n"
		"  --camera C        camera path name (default: the scene's first)\n"
		"  --method M        rendering method (default: ref)\n"
		"  --threshold T     threshold in 8-bit code values for adaptive methods (default 8)\n"
		"  --max-age K       tfr: reshade samples at the latest at age K (1..119, default 119)\n"
		"  --frames A:B      frames A..B-1; also A (one frame), :B, A: (default: whole clip)\n"
		"  --size WxH        frame size (default 960x540)\n"
		"  --fps F           frame rate; frame f is at t = f/F (default: the scene's, usually 60)\n"
		"  --out RUN         output folder (default runs/SCENE-CAMERA-METHOD)\n"
		"  --device D        Vulkan device: index, name substring, or 'lavapipe' for the CPU\n"
		"                    (default: a GPU if present, else lavapipe)\n"
		"  --ocio-config F   OpenColorIO config for the display transform (default: $OCIO, else the\n"
		"                    built-in ACES 1.0 SDR-video output transform on an sRGB display)\n"
		"  --display D, --view V  display and view of that config (default: the config's defaults)\n"
		"  --validation      enable the Khronos validation layer; any message fails the run\n"
		"  --no-exr, --no-png  skip writing that frame format\n"
		"  --trivial-shading benchmark only: replace shading with base colour output\n"
		"  --quiet           no progress output\n"
		"\nmethods:\n");
	for (size_t i = 0; i < n; i++)
		fprintf(out, "  %-6s %s%s\n", m[i].name, m[i].summary, m[i].available ? "" : " [planned]");
}

static int need_value(int argc, char **argv, int *i, const char **inline_val, const char **out, char *err,
		      size_t err_size)
{
	if (*inline_val) {
		*out = *inline_val;
		return 0;
	}
	if (*i + 1 >= argc) {
		snprintf(err, err_size, "%s needs a value (see 'taslab render --help')", argv[*i]);
		return -1;
	}
	*out = argv[++*i];
	return 0;
}

int cli_render_parse(int argc, char **argv, cli_render_opts *o, char *err, size_t err_size)
{
	memset(o, 0, sizeof *o);
	o->method = "ref";
	o->width = 960;
	o->height = 540;
	o->threshold = 8.0;
	for (int i = 1; i < argc; i++) {
		char name[64];
		const char *arg = argv[i], *eq = strchr(arg, '=');
		if (strncmp(arg, "--", 2) != 0) {
			snprintf(err, err_size, "unexpected argument '%s' (options start with --; see 'taslab render --help')", arg);
			return -1;
		}
		size_t len = eq ? (size_t)(eq - arg) : strlen(arg);
		if (len >= sizeof name)
			len = sizeof name - 1;
		memcpy(name, arg, len);
		name[len] = 0;
		const char *iv = eq ? eq + 1 : NULL;
		int flag = 0;
		bool *fl = NULL;
		if (!strcmp(name, "--help") || !strcmp(name, "-h"))
			fl = &o->help;
		else if (!strcmp(name, "--validation"))
			fl = &o->validation;
		else if (!strcmp(name, "--no-exr"))
			fl = &o->no_exr;
		else if (!strcmp(name, "--no-png"))
			fl = &o->no_png;
		else if (!strcmp(name, "--trivial-shading"))
			fl = &o->trivial_shading;
		else if (!strcmp(name, "--quiet"))
			fl = &o->quiet;
		if (fl) {
			if (iv) {
				snprintf(err, err_size, "%s takes no value", name);
				return -1;
			}
			*fl = true;
			flag = 1;
		}
		if (flag)
			continue;
		if (!strcmp(name, "--scene")) {
			if (need_value(argc, argv, &i, &iv, &o->scene, err, err_size))
				return -1;
		} else if (!strcmp(name, "--camera")) {
			if (need_value(argc, argv, &i, &iv, &o->camera, err, err_size))
				return -1;
		} else if (!strcmp(name, "--method")) {
			if (need_value(argc, argv, &i, &iv, &o->method, err, err_size))
				return -1;
		} else if (!strcmp(name, "--out")) {
			if (need_value(argc, argv, &i, &iv, &o->out, err, err_size))
				return -1;
			if (!*o->out) {
				snprintf(err, err_size, "--out needs a folder name");
				return -1;
			}
		} else if (!strcmp(name, "--ocio-config")) {
			if (need_value(argc, argv, &i, &iv, &o->ocio_config, err, err_size))
				return -1;
		} else if (!strcmp(name, "--display")) {
			if (need_value(argc, argv, &i, &iv, &o->display, err, err_size))
				return -1;
		} else if (!strcmp(name, "--view")) {
			if (need_value(argc, argv, &i, &iv, &o->view, err, err_size))
				return -1;
		} else if (!strcmp(name, "--device")) {
			if (need_value(argc, argv, &i, &iv, &o->device, err, err_size))
				return -1;
		} else if (!strcmp(name, "--frames")) {
			if (need_value(argc, argv, &i, &iv, &o->frames, err, err_size))
				return -1;
			uint32_t a, b = 1u << 30;
			bool given;
			if (cli_parse_frames(o->frames, &a, &b, &given, err, err_size))
				return -1;
		} else if (!strcmp(name, "--size")) {
			const char *v;
			if (need_value(argc, argv, &i, &iv, &v, err, err_size) || cli_parse_size(v, &o->width, &o->height, err, err_size))
				return -1;
		} else if (!strcmp(name, "--fps")) {
			const char *v;
			if (need_value(argc, argv, &i, &iv, &v, err, err_size) ||
			    cli_parse_float(v, "--fps", 1, 1000, &o->fps, err, err_size))
				return -1;
		} else if (!strcmp(name, "--max-age")) {
			const char *v;
			if (need_value(argc, argv, &i, &iv, &v, err, err_size))
				return -1;
			char *end;
			double k = strtod(v, &end);
			if (*v == 0 || *end || k != (double)(long)k || k < 1) {
				snprintf(err, err_size, "--max-age: '%s' is not a whole number of frames >= 1", v);
				return -1;
			}
			if (k > RENDER_TFR_MAX_AGE) {
				snprintf(err, err_size, "--max-age %s: ages beyond K = %d are not kept (use 1..%d)", v,
					 RENDER_TFR_MAX_AGE, RENDER_TFR_MAX_AGE);
				return -1;
			}
			o->max_age = k;
		} else if (!strcmp(name, "--threshold")) {
			const char *v;
			if (need_value(argc, argv, &i, &iv, &v, err, err_size) ||
			    cli_parse_float(v, "--threshold", 1e-6, 255, &o->threshold, err, err_size))
				return -1;
		} else {
			snprintf(err, err_size, "unknown option '%s' (see 'taslab render --help')", name);
			return -1;
		}
	}
	if (!o->help && !o->scene) {
		snprintf(err, err_size, "--scene is required (e.g. --scene turntable; see 'taslab render --help')");
		return -1;
	}
	if (!o->help) {
		size_t n;
		const render_method_info *m = render_methods(&n);
		size_t i = 0;
		while (i < n && strcmp(m[i].name, o->method))
			i++;
		if (i == n) {
			snprintf(err, err_size, "unknown method '%s' (see 'taslab render --help' for the list)", o->method);
			return -1;
		}
		if (!m[i].available) {
			snprintf(err, err_size, "method '%s' is planned but not implemented yet (use --method ref)", o->method);
			return -1;
		}
	}
	return 0;
}

static double now_s(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct progress_state {
	int tty;
	double t0;
	char banner[512]; /* printed with the first progress report, once the run folder exists */
} progress_state;

static void progress(void *user, uint32_t done, uint32_t total)
{
	progress_state *ps = user;
	int tty = ps->tty;
	double elapsed = now_s() - ps->t0;
	if (done == 1)
		fputs(ps->banner, stderr);
	if (tty) {
		int width = 30, fill = (int)((double)done / total * width);
		fprintf(stderr, "\r[%.*s%*s] %u/%u frames, %.1f s", fill, "##############################", width - fill, "",
			done, total, elapsed);
		if (done == total)
			fputc('\n', stderr);
	} else if (done == total || done % 10 == 0) {
		fprintf(stderr, "taslab: rendered %u/%u frames (%.1f s)\n", done, total, elapsed);
	}
	fflush(stderr);
}

static int render_run(int argc, char **argv)
{
	char err[1024], scene_path[4096], out_default[512], cmdline[2048] = "";
	cli_render_opts o;
	scene *scn = NULL;
	vkdev *dev = NULL;
	colour *col = NULL;
	int status = CLI_EXIT_FAILURE;
	if (cli_render_parse(argc, argv, &o, err, sizeof err)) {
		fprintf(stderr, "taslab render: %s\n", err);
		return CLI_EXIT_USAGE;
	}
	if (o.help) {
		render_usage(stdout);
		return CLI_EXIT_OK;
	}
	for (int i = 0; i < argc; i++) {
		strncat(cmdline, i ? " " : "taslab ", sizeof cmdline - strlen(cmdline) - 1);
		strncat(cmdline, argv[i], sizeof cmdline - strlen(cmdline) - 1);
	}
	if (cli_resolve_scene(o.scene, scene_path, sizeof scene_path, err, sizeof err)) {
		fprintf(stderr, "taslab render: %s\n", err);
		return CLI_EXIT_USAGE;
	}
	if (scene_load(scene_path, &scn, err, sizeof err)) {
		fprintf(stderr, "taslab render: %s\n", err);
		return CLI_EXIT_USAGE;
	}
	int cam = o.camera ? scene_find_camera(scn, o.camera) : 0;
	if (cam < 0) {
		char names[512] = "";
		for (size_t i = 0; i < scn->camera_count; i++) {
			strncat(names, i ? ", " : "", sizeof names - strlen(names) - 1);
			strncat(names, scn->cameras[i].name, sizeof names - strlen(names) - 1);
		}
		fprintf(stderr, "taslab render: scene '%s' has no camera path '%s' (available: %s)\n", scn->name, o.camera, names);
		status = CLI_EXIT_USAGE;
		goto done;
	}
	float fps = o.fps > 0 ? (float)o.fps : scn->fps;
	uint32_t first = 0, end = (uint32_t)lround((double)scn->duration_s * fps);
	if (end < 1)
		end = 1;
	bool given;
	if (o.frames && cli_parse_frames(o.frames, &first, &end, &given, err, sizeof err)) {
		fprintf(stderr, "taslab render: %s\n", err);
		status = CLI_EXIT_USAGE;
		goto done;
	}
	const char *out = o.out;
	if (!out) {
		snprintf(out_default, sizeof out_default, "runs/%s-%s-%s", scn->name, scn->cameras[cam].name, o.method);
		out = out_default;
	}
	colour_desc cd = {.config_path = o.ocio_config, .display = o.display, .view = o.view};
	if (colour_create(&cd, &col, err, sizeof err)) {
		fprintf(stderr, "taslab render: %s\n", err);
		status = CLI_EXIT_USAGE;
		goto done;
	}
	vkdev_desc dd = {.device = o.device, .validation = o.validation};
	if (vkdev_create(&dd, &dev, err, sizeof err)) {
		fprintf(stderr, "taslab render: %s\n", err);
		goto done;
	}
	progress_state ps = {isatty(2), now_s(), ""};
	snprintf(ps.banner, sizeof ps.banner, "taslab: rendering %s/%s with %s on %s, frames %u..%u at %ux%u\n",
		 scn->name, scn->cameras[cam].name, o.method, dev->props.deviceName, first, end - 1, o.width, o.height);
	run_render_desc rr = {
		.dev = dev,
		.scene = scn,
		.scene_path = scene_path,
		.camera = cam,
		.colour = col,
		.method = o.method,
		.threshold = (float)o.threshold,
		.max_age = (uint32_t)o.max_age,
		.first = first,
		.end = end,
		.width = o.width,
		.height = o.height,
		.fps = fps,
		.write_exr = !o.no_exr,
		.write_png = !o.no_png,
		.trivial_shading = o.trivial_shading,
		.out = out,
		.command_line = cmdline,
		.progress = o.quiet ? NULL : progress,
		.user = &ps,
	};
	int rc = run_render(&rr, err, sizeof err);
	if (rc) {
		fprintf(stderr, "%staslab render: %s\n", ps.tty && !o.quiet ? "\n" : "", err);
		status = rc == RUN_ERR_OUTPUT ? CLI_EXIT_USAGE : CLI_EXIT_FAILURE;
		goto done;
	}
	if (!o.quiet)
		fprintf(stderr, "taslab: wrote %u frames to %s/frames (stats: %s/stats.csv)\n", end - first, out, out);
	printf("%s\n", out);
	status = CLI_EXIT_OK;
done:
	if (dev && dev->validation && vkdev_validation_messages(dev) && status == CLI_EXIT_OK)
		status = CLI_EXIT_FAILURE;
	vkdev_destroy(&dev);
	colour_destroy(&col);
	scene_destroy(&scn);
	return status;
}

const cli_command cli_cmd_render = {"render", "render a clip of a scene with a method into a run folder", render_run,
				    render_usage};
