/* cmd_pair.c — `taslab pair`: paired study clips for one scene and camera path (DESIGN sections 5, 7):
 * renders the reference and each variant (METHOD or METHOD@T) into run folders, encodes their bit-exact
 * clips, an inspection clip per variant (reference | variant side by side), and pairs.json tying every clip
 * to its condition (scene, camera path and motion class, method, T). pairs.json is written last and
 * atomically: its presence means the set is complete. */
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "taslab/clip.h"
#include "taslab/colour.h"
#include "taslab/imageio.h"
#include "taslab/render.h"
#include "taslab/run.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

#define MAX_VARIANTS 64

static void pair_usage(FILE *out)
{
	fprintf(out,
		"usage: taslab pair --scene S --camera C --out DIR [--variants LIST] [options]\n\n"
		"Renders the reference (ref) and each variant of one scene and camera path, and writes\n"
		"  DIR/runs/NAME/        run folders (frames, stats.csv, manifest.json)\n"
		"  DIR/clips/NAME.webm   bit-exact lossless clips for the study\n"
		"  DIR/inspect/NAME.webm reference | variant side by side, for looking at the differences\n"
		"  DIR/pairs.json        the conditions (scene, camera, camera_motion, method, T) and their clips\n\n"
		"options:\n"
		"  --variants LIST   comma-separated METHOD or METHOD@T (e.g. tfr@2,tfr@4); default: ref (a catch\n"
		"                    pair, reference against itself); see 'taslab render --help' for the methods\n"
		"  --frames A:B, --size WxH, --fps F, --device D, --validation,\n"
		"  --ocio-config F, --display D, --view V   as for 'taslab render' (default size 960x540)\n");
}

typedef struct variant {
	char method[32];
	double T; /* NAN: method without threshold */
	char name[64];
} variant;

static int parse_variants(const char *list, variant *v, size_t *n, char *err, size_t err_size)
{
	char buf[2048];
	snprintf(buf, sizeof buf, "%s", list);
	*n = 0;
	for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
		if (*n == MAX_VARIANTS) {
			snprintf(err, err_size, "--variants: at most %d variants", MAX_VARIANTS);
			return -1;
		}
		variant *x = &v[(*n)++];
		char *at = strchr(tok, '@');
		x->T = NAN;
		if (at) {
			*at = 0;
			if (cli_parse_float(at + 1, "--variants threshold", 1e-6, 255, &x->T, err, err_size))
				return -1;
		}
		size_t nm;
		const render_method_info *m = render_methods(&nm);
		size_t i = 0;
		while (i < nm && strcmp(m[i].name, tok))
			i++;
		if (i == nm || !m[i].available) {
			snprintf(err, err_size, "--variants: %s method '%s' (available: ref, tfr; see 'taslab render --help')",
				 i == nm ? "unknown" : "not yet implemented", tok);
			return -1;
		}
		snprintf(x->method, sizeof x->method, "%s", tok);
		if (isnan(x->T) && !strcmp(tok, "tfr")) {
			snprintf(err, err_size, "--variants: tfr needs a threshold, e.g. tfr@8");
			return -1;
		}
		if (isnan(x->T))
			snprintf(x->name, sizeof x->name, "%s", tok);
		else
			snprintf(x->name, sizeof x->name, "%s-T%g", tok, x->T);
		for (size_t j = 0; j + 1 < *n; j++)
			if (!strcmp(v[j].name, x->name)) {
				snprintf(err, err_size, "--variants: '%s' is listed twice", x->name);
				return -1;
			}
	}
	if (*n == 0) {
		snprintf(err, err_size, "--variants is empty");
		return -1;
	}
	return 0;
}

/* reference | variant, side by side with a 2-pixel grey gap. */
static int inspect_clip(const char *ref_run, const char *var_run, uint32_t first, uint32_t end, float fps,
			const char *out, char *err, size_t err_size)
{
	clip_writer *w = NULL;
	uint8_t *a = NULL, *b = NULL, *sbs = NULL;
	int rc = -1;
	for (uint32_t f = first; f < end; f++) {
		char pa[4096], pb[4096];
		uint32_t wa, ha, wb, hb;
		snprintf(pa, sizeof pa, "%s/frames/%06u.png", ref_run, f);
		snprintf(pb, sizeof pb, "%s/frames/%06u.png", var_run, f);
		free(a);
		free(b);
		a = b = NULL;
		if (imageio_read_rgb8(pa, &wa, &ha, &a, err, err_size) || imageio_read_rgb8(pb, &wb, &hb, &b, err, err_size))
			goto done;
		if (wa != wb || ha != hb) {
			snprintf(err, err_size, "%s and %s differ in size", pa, pb);
			goto done;
		}
		uint32_t W = 2 * wa + 2;
		if (!w) {
			sbs = malloc((size_t)W * ha * 3);
			if (!sbs || clip_writer_create(out, W, ha, fps, &w, err, err_size))
				goto done;
		}
		for (uint32_t y = 0; y < ha; y++) {
			uint8_t *row = sbs + (size_t)y * W * 3;
			memcpy(row, a + (size_t)y * wa * 3, (size_t)wa * 3);
			memset(row + (size_t)wa * 3, 128, 6);
			memcpy(row + (size_t)(wa + 2) * 3, b + (size_t)y * wa * 3, (size_t)wa * 3);
		}
		if (clip_writer_frame(w, sbs, err, err_size))
			goto done;
	}
	rc = w ? clip_writer_finish(w, err, err_size) : -1;
done:
	clip_writer_destroy(&w);
	free(a);
	free(b);
	free(sbs);
	return rc;
}

static int pair_run(int argc, char **argv)
{
	char err[1024], scene_path[4096];
	const char *scene_arg = NULL, *camera = NULL, *out = NULL, *variants_arg = "ref", *frames = NULL, *device = NULL;
	uint32_t width = 960, height = 540;
	double fps_opt = 0;
	int validation = 0;
	colour_desc cd = {0};
	for (int i = 1; i < argc; i++) {
		const char *a = argv[i];
		const char **dst = NULL;
		if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
			pair_usage(stdout);
			return CLI_EXIT_OK;
		}
		if (!strcmp(a, "--validation")) {
			validation = 1;
			continue;
		}
		if (!strcmp(a, "--scene"))
			dst = &scene_arg;
		else if (!strcmp(a, "--camera"))
			dst = &camera;
		else if (!strcmp(a, "--out"))
			dst = &out;
		else if (!strcmp(a, "--variants"))
			dst = &variants_arg;
		else if (!strcmp(a, "--frames"))
			dst = &frames;
		else if (!strcmp(a, "--device"))
			dst = &device;
		else if (!strcmp(a, "--ocio-config"))
			dst = &cd.config_path;
		else if (!strcmp(a, "--display"))
			dst = &cd.display;
		else if (!strcmp(a, "--view"))
			dst = &cd.view;
		else if (strcmp(a, "--size") && strcmp(a, "--fps")) {
			fprintf(stderr, "taslab pair: unknown argument '%s' (see 'taslab pair --help')\n", a);
			return CLI_EXIT_USAGE;
		}
		if (i + 1 >= argc) {
			fprintf(stderr, "taslab pair: %s needs a value\n", a);
			return CLI_EXIT_USAGE;
		}
		if (dst) {
			*dst = argv[++i];
		} else if (!strcmp(a, "--size")) {
			if (cli_parse_size(argv[++i], &width, &height, err, sizeof err)) {
				fprintf(stderr, "taslab pair: %s\n", err);
				return CLI_EXIT_USAGE;
			}
		} else if (cli_parse_float(argv[++i], "--fps", 1, 1000, &fps_opt, err, sizeof err)) {
			fprintf(stderr, "taslab pair: %s\n", err);
			return CLI_EXIT_USAGE;
		}
	}
	variant vars[MAX_VARIANTS];
	size_t nvar = 0;
	if (!scene_arg || !out) {
		fprintf(stderr, "taslab pair: --scene and --out are required (see 'taslab pair --help')\n");
		return CLI_EXIT_USAGE;
	}
	if (parse_variants(variants_arg, vars, &nvar, err, sizeof err) ||
	    cli_resolve_scene(scene_arg, scene_path, sizeof scene_path, err, sizeof err)) {
		fprintf(stderr, "taslab pair: %s\n", err);
		return CLI_EXIT_USAGE;
	}
	scene *scn = NULL;
	colour *col = NULL;
	vkdev *dev = NULL;
	json_t *conds = NULL;
	int status = CLI_EXIT_USAGE;
	if (scene_load(scene_path, &scn, err, sizeof err)) {
		fprintf(stderr, "taslab pair: %s\n", err);
		return CLI_EXIT_USAGE;
	}
	int cam = camera ? scene_find_camera(scn, camera) : 0;
	if (cam < 0) {
		fprintf(stderr, "taslab pair: scene '%s' has no camera path '%s' (see 'taslab scenes')\n", scn->name, camera);
		goto done;
	}
	float fps = fps_opt > 0 ? (float)fps_opt : scn->fps;
	uint32_t first = 0, end = (uint32_t)lround((double)scn->duration_s * fps);
	bool given;
	if (frames && cli_parse_frames(frames, &first, &end, &given, err, sizeof err)) {
		fprintf(stderr, "taslab pair: %s\n", err);
		goto done;
	}
	if (colour_create(&cd, &col, err, sizeof err)) {
		fprintf(stderr, "taslab pair: %s\n", err);
		goto done;
	}
	char pairs_json[4096], sub[4096];
	snprintf(pairs_json, sizeof pairs_json, "%s/pairs.json", out);
	if (run_mkdirs(out, err, sizeof err) || (unlink(pairs_json) && errno != ENOENT)) {
		fprintf(stderr, "taslab pair: %s\n", err);
		goto done;
	}
	status = CLI_EXIT_FAILURE;
	vkdev_desc dd = {.device = device, .validation = validation};
	if (vkdev_create(&dd, &dev, err, sizeof err)) {
		fprintf(stderr, "taslab pair: %s\n", err);
		goto done;
	}
	snprintf(sub, sizeof sub, "%s/clips", out);
	if (run_mkdirs(sub, err, sizeof err)) {
		fprintf(stderr, "taslab pair: %s\n", err);
		goto done;
	}
	snprintf(sub, sizeof sub, "%s/inspect", out);
	if (run_mkdirs(sub, err, sizeof err)) {
		fprintf(stderr, "taslab pair: %s\n", err);
		goto done;
	}
	conds = json_array();
	/* Index -1 is the reference; then the variants. */
	for (int k = -1; k < (int)nvar; k++) {
		const char *name = k < 0 ? "ref" : vars[k].name, *method = k < 0 ? "ref" : vars[k].method;
		double T = k < 0 ? NAN : vars[k].T;
		char run[4096], clip[4096], inspect[4096], rel_run[256], rel_clip[256], rel_inspect[256];
		snprintf(rel_run, sizeof rel_run, "runs/%s", name);
		snprintf(rel_clip, sizeof rel_clip, "clips/%s.webm", name);
		snprintf(rel_inspect, sizeof rel_inspect, "inspect/%s.webm", name);
		snprintf(run, sizeof run, "%s/%s", out, rel_run);
		snprintf(clip, sizeof clip, "%s/%s", out, rel_clip);
		snprintf(inspect, sizeof inspect, "%s/%s", out, rel_inspect);
		/* A variant identical to the reference (a catch pair) reuses the reference's run and clip. */
		int same_as_ref = k >= 0 && !strcmp(method, "ref");
		if (!same_as_ref) {
			fprintf(stderr, "taslab: pair %s/%s: rendering %s (frames %u..%u, %ux%u)\n", scn->name,
				scn->cameras[cam].name, name, first, end - 1, width, height);
			run_render_desc rr = {.dev = dev, .scene = scn, .scene_path = scene_path, .camera = cam, .colour = col,
					      .method = method, .threshold = isnan(T) ? 0.0f : (float)T, .first = first,
					      .end = end, .width = width, .height = height, .fps = fps, .write_exr = true,
					      .write_png = true, .out = run, .command_line = "taslab pair"};
			uint32_t n;
			if (run_render(&rr, err, sizeof err) || clip_encode_run(run, clip, &n, err, sizeof err)) {
				fprintf(stderr, "taslab pair: %s: %s\n", name, err);
				goto done;
			}
		}
		if (k < 0)
			continue;
		const char *vr = same_as_ref ? "runs/ref" : rel_run, *vc = same_as_ref ? "clips/ref.webm" : rel_clip;
		char ref_run[4096], var_run[4096];
		snprintf(ref_run, sizeof ref_run, "%s/runs/ref", out);
		snprintf(var_run, sizeof var_run, "%s/%s", out, vr);
		if (inspect_clip(ref_run, var_run, first, end, fps, inspect, err, sizeof err)) {
			fprintf(stderr, "taslab pair: %s: %s\n", name, err);
			goto done;
		}
		json_array_append_new(conds, json_pack("{s:s, s:s, s:o, s:s, s:s, s:s}", "id", name, "method", method, "T",
						       isnan(T) ? json_null() : json_real(T), "run", vr, "clip", vc,
						       "inspect", rel_inspect));
	}
	json_t *m = json_pack("{s:i, s:s, s:s, s:s, s:s, s:f, s:[i,i], s:[i,i], s:s, s:{s:s, s:s}, s:O}", "taslab_pairs", 1,
			      "scene", scn->name, "scene_path", scene_path, "camera", scn->cameras[cam].name,
			      "camera_motion", scene_camera_motion_name(scn->cameras[cam].motion), "fps", (double)fps,
			      "frames", (int)first, (int)(end - 1), "size", (int)width, (int)height, "display_transform",
			      colour_name(col), "reference", "run", "runs/ref", "clip", "clips/ref.webm", "conditions", conds);
	char tmp[4096];
	snprintf(tmp, sizeof tmp, "%s/.pairs.json.tmp%ld", out, (long)getpid());
	if (!m || json_dump_file(m, tmp, JSON_INDENT(2)) || rename(tmp, pairs_json)) {
		unlink(tmp);
		json_decref(m);
		fprintf(stderr, "taslab pair: cannot write %s\n", pairs_json);
		goto done;
	}
	json_decref(m);
	fprintf(stderr, "taslab: %zu pair(s) in %s (pairs.json, clips/, inspect/)\n", nvar, out);
	printf("%s\n", pairs_json);
	status = CLI_EXIT_OK;
done:
	json_decref(conds);
	if (dev && validation && vkdev_validation_messages(dev) && status == CLI_EXIT_OK)
		status = CLI_EXIT_FAILURE;
	vkdev_destroy(&dev);
	colour_destroy(&col);
	scene_destroy(&scn);
	return status;
}

const cli_command cli_cmd_pair = {"pair", "render reference/variant clip pairs for a study, with pairs.json", pair_run,
				  pair_usage};
