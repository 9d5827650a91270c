/* cmd_analyze.c — `taslab analyze coherence|predictors`: TFR analysis of chosen frames (taslab/analyze.h)
 * written through the metrics module (taslab/metrics_tfr.h). DESIGN section 4, paper secs. 4.1 and 5. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "taslab/analyze.h"
#include "taslab/colour.h"
#include "taslab/metrics_tfr.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

#define MAX_FRAMES 1000

static void analyze_usage(FILE *out)
{
	fprintf(out,
		"usage: taslab analyze coherence|predictors --scene S --frames LIST --out DIR [options]\n\n"
		"Temporal forward rendering analysis (DESIGN section 4): every visible sample of an analysis frame t\n"
		"is shaded as it was k = 1..120 frames earlier (transforms, lights, camera, shadow maps at t - k),\n"
		"on the Vulkan device; outputs CSV/JSON for the figures and plots.\n"
		"  coherence   fraction of samples unchanged (d <= T) for >= k frames, k = 1..120, per T (paper\n"
		"              Fig. 4) and visibility coherence per frame (sec. 4.1): DIR/coherence.csv,\n"
		"              coherence_frames.csv, visibility.csv, coherence.json, coherence.png\n"
		"  predictors  single-frame, long-range and instantaneous (symmetric difference, our stand-in for\n"
		"              analytic derivatives) gradients, unfiltered and with the 8x8 + 9x9 spatial max filter,\n"
		"              classified late / early / on time / unchanged per T (Figs. 7, 9): DIR/predictors.csv,\n"
		"              predictors_frames.csv, predictors.json, predictors.png\n"
		"options:\n"
		"  --scene S          built-in scene name, scene .json or .gltf/.glb\n"
		"  --camera C         camera path (default: the scene's first)\n"
		"  --frames LIST      analysis frames: F, A:B (half-open) or A:B:STEP, comma-separated; inside the clip\n"
		"  --size WxH         frame size (default 480x270)\n"
		"  --fps F            frame rate (default: the scene's)\n"
		"  --thresholds LIST  T values in 8-bit code values, > 0 (default 2,4,8,16,32,64; at most 8)\n"
		"  --step H           predictors: instantaneous-derivative step in frames (default 0.125, max 0.5)\n"
		"  --images           predictors: gradient heatmaps like Fig. 8, DIR/gradients/FRAME_T<T>_<predictor>.png\n"
		"  --no-plots         skip the gnuplot plots\n"
		"  --device D, --validation, --ocio-config F, --display D, --view V, --quiet  as for taslab render\n");
}

static int analyze_run(int argc, char **argv)
{
	char err[1024], scene_path[4096];
	const char *what = argc > 1 ? argv[1] : NULL;
	const char *scene_arg = NULL, *camera = NULL, *frames_arg = NULL, *out = NULL, *device = NULL;
	const char *ocio = NULL, *display = NULL, *view = NULL, *size_arg = "480x270", *ts_arg = "2,4,8,16,32,64";
	double fps = 0, step = 0;
	bool images = false, plots = true, validation = false, quiet = false;
	if (what && (!strcmp(what, "--help") || !strcmp(what, "-h"))) {
		analyze_usage(stdout);
		return CLI_EXIT_OK;
	}
	if (!what || (strcmp(what, "coherence") && strcmp(what, "predictors"))) {
		fprintf(stderr, "taslab analyze: expected 'coherence' or 'predictors' (see 'taslab analyze --help')\n");
		return CLI_EXIT_USAGE;
	}
	for (int i = 2; i < argc; i++) {
		const char *a = argv[i], **dst = NULL;
		if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
			analyze_usage(stdout);
			return CLI_EXIT_OK;
		} else if (!strcmp(a, "--images")) {
			images = true;
		} else if (!strcmp(a, "--no-plots")) {
			plots = false;
		} else if (!strcmp(a, "--validation")) {
			validation = true;
		} else if (!strcmp(a, "--quiet")) {
			quiet = true;
		} else if (!strcmp(a, "--scene")) {
			dst = &scene_arg;
		} else if (!strcmp(a, "--camera")) {
			dst = &camera;
		} else if (!strcmp(a, "--frames")) {
			dst = &frames_arg;
		} else if (!strcmp(a, "--out")) {
			dst = &out;
		} else if (!strcmp(a, "--device")) {
			dst = &device;
		} else if (!strcmp(a, "--ocio-config")) {
			dst = &ocio;
		} else if (!strcmp(a, "--display")) {
			dst = &display;
		} else if (!strcmp(a, "--view")) {
			dst = &view;
		} else if (!strcmp(a, "--size")) {
			dst = &size_arg;
		} else if (!strcmp(a, "--thresholds")) {
			dst = &ts_arg;
		} else if (!strcmp(a, "--fps") || !strcmp(a, "--step")) {
			if (i + 1 >= argc) {
				fprintf(stderr, "taslab analyze: %s needs a value\n", a);
				return CLI_EXIT_USAGE;
			}
			int bad = !strcmp(a, "--fps") ? cli_parse_float(argv[++i], "--fps", 1, 1000, &fps, err, sizeof err)
						       : cli_parse_float(argv[++i], "--step", 1e-4, 0.5, &step, err, sizeof err);
			if (bad) {
				fprintf(stderr, "taslab analyze: %s\n", err);
				return CLI_EXIT_USAGE;
			}
		} else {
			fprintf(stderr, "taslab analyze: unknown option '%s' (see 'taslab analyze --help')\n", a);
			return CLI_EXIT_USAGE;
		}
		if (dst) {
			if (i + 1 >= argc) {
				fprintf(stderr, "taslab analyze: %s needs a value (see 'taslab analyze --help')\n", a);
				return CLI_EXIT_USAGE;
			}
			*dst = argv[++i];
		}
	}
	if (!scene_arg || !frames_arg || !out) {
		fprintf(stderr, "taslab analyze: --scene, --frames and --out are required (see 'taslab analyze --help')\n");
		return CLI_EXIT_USAGE;
	}
	uint32_t w, h;
	float ts[ANALYZE_MAX_T];
	size_t nT;
	if (cli_parse_size(size_arg, &w, &h, err, sizeof err) ||
	    cli_parse_float_list(ts_arg, "--thresholds: T", 1e-6, 255, ts, ANALYZE_MAX_T, &nT, err, sizeof err)) {
		fprintf(stderr, "taslab analyze: %s\n", err);
		return CLI_EXIT_USAGE;
	}
	scene *scn = NULL;
	vkdev *dev = NULL;
	colour *col = NULL;
	analyze *an = NULL;
	analyze_result *res = NULL;
	uint32_t *frames = NULL;
	size_t nf = 0;
	int status = CLI_EXIT_USAGE;
	if (cli_resolve_scene(scene_arg, scene_path, sizeof scene_path, err, sizeof err) ||
	    scene_load(scene_path, &scn, err, sizeof err))
		goto fail;
	int cam = camera ? scene_find_camera(scn, camera) : 0;
	if (cam < 0) {
		snprintf(err, sizeof err, "scene '%s' has no camera path '%s' (see 'taslab scenes')", scn->name, camera);
		goto fail;
	}
	float f = fps > 0 ? (float)fps : scn->fps;
	uint32_t end = (uint32_t)(scn->duration_s * f + 0.5f);
	frames = malloc(MAX_FRAMES * sizeof *frames);
	if (!frames || cli_parse_frame_list(frames_arg, end ? end : 1, frames, MAX_FRAMES, &nf, err, sizeof err))
		goto fail;
	colour_desc cd = {.config_path = ocio, .display = display, .view = view};
	if (colour_create(&cd, &col, err, sizeof err))
		goto fail;
	status = CLI_EXIT_FAILURE;
	vkdev_desc dd = {.device = device, .validation = validation};
	if (vkdev_create(&dd, &dev, err, sizeof err))
		goto fail;
	analyze_desc ad = {.scene = scn, .camera = cam, .width = w, .height = h, .fps = f, .thresholds = ts,
			   .threshold_count = nT, .inst_step = (float)step, .predictors = !strcmp(what, "predictors"),
			   .keep_gradients = images, .colour = col};
	if (analyze_create(dev, &ad, &an, err, sizeof err))
		goto fail;
	res = calloc(nf, sizeof *res);
	if (!res) {
		snprintf(err, sizeof err, "out of memory");
		goto fail;
	}
	mtr_tfr_meta meta = {.scene = scn->name, .camera = scn->cameras[cam].name, .device = dev->props.deviceName,
			     .thresholds = ts, .threshold_count = nT};
	struct timespec t0, t1;
	clock_gettime(CLOCK_MONOTONIC, &t0);
	for (size_t i = 0; i < nf; i++) {
		if (analyze_frame(an, frames[i], &res[i], err, sizeof err))
			goto fail;
		if (vkdev_validation_messages(dev)) {
			snprintf(err, sizeof err, "the Vulkan validation layer reported %u message(s)", vkdev_validation_messages(dev));
			goto fail;
		}
		if (images && mtr_tfr_write_gradients(&res[i], &meta, out, err, sizeof err))
			goto fail;
		if (!quiet)
			fprintf(stderr, "taslab analyze: frame %u (%zu/%zu)\n", frames[i], i + 1, nf);
	}
	clock_gettime(CLOCK_MONOTONIC, &t1);
	meta.seconds_per_frame = ((double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec)) / (double)nf;
	if (!strcmp(what, "coherence") ? mtr_tfr_write_coherence(res, nf, &meta, out, plots, err, sizeof err)
				       : mtr_tfr_write_predictors(res, nf, &meta, out, plots, err, sizeof err))
		goto fail;
	if (!quiet)
		fprintf(stderr, "taslab analyze: %zu frame(s), %.2f s per analysis frame -> %s\n", nf, meta.seconds_per_frame, out);
	status = CLI_EXIT_OK;
	goto done;
fail:
	fprintf(stderr, "taslab analyze: %s\n", err);
done:
	if (res)
		for (size_t i = 0; i < nf; i++)
			analyze_result_free(&res[i]);
	free(res);
	free(frames);
	analyze_destroy(&an);
	vkdev_destroy(&dev);
	colour_destroy(&col);
	scene_destroy(&scn);
	return status;
}

const cli_command cli_cmd_analyze = {"analyze", "TFR analysis: temporal coherence and gradient predictors (Figs. 4, 7-9)",
				     analyze_run, analyze_usage};
