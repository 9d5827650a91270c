/* cmd_analyze.c — `taslab analyze coherence|predictors`: TFR analysis of chosen frames (taslab/analyze.h)
 * written through the metrics module (taslab/metrics_tfr.h). DESIGN section 4, paper secs. 4.1 and 5.
 * `taslab analyze reuse-model SWEEP`: the survey's models of reuse (eqs. 5-7) fitted to a sweep
 * (taslab/reuse_model.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "taslab/analyze.h"
#include "taslab/colour.h"
#include "taslab/metrics_tfr.h"
#include "taslab/reuse_model.h"
#include "taslab/scene.h"
#include "taslab/tl_clock.h"
#include "taslab/tl_fs.h"
#include "taslab/vkdev.h"

#define MAX_FRAMES 1000

static const cli_opt analyze_options[] = {
	{.name = "out", .arg = "DIR",
	 .help = "output folder",
	 .type = CLI_STRING, .offset = offsetof(analyze_opts, out)},
	{.name = "thresholds", .arg = "LIST",
	 .help = "T values in 8-bit code values, > 0 (default 2,4,8,16,32,64; at most 8)",
	 .type = CLI_STRING, .offset = offsetof(analyze_opts, thresholds)},
	{.name = "step", .arg = "H",
	 .help = "predictors: instantaneous-derivative step in frames (default 0.125, max 0.5)",
	 .type = CLI_DOUBLE, .offset = offsetof(analyze_opts, step), .lo = 1e-4, .hi = 0.5},
	{.name = "images", .arg = NULL,
	 .help = "predictors: gradient heatmaps like Fig. 8 (DIR/gradients/)",
	 .type = CLI_FLAG, .offset = offsetof(analyze_opts, images)},
	{.name = "no-plots", .arg = NULL,
	 .help = "skip the gnuplot plots",
	 .type = CLI_FLAG, .offset = offsetof(analyze_opts, no_plots)},
	{.name = "quiet", .arg = NULL,
	 .help = "no progress output",
	 .type = CLI_FLAG, .offset = offsetof(analyze_opts, quiet)},
	{0},
};

static void analyze_defaults(void *opts, cli_setup_opts *setup)
{
	((analyze_opts *)opts)->thresholds = "2,4,8,16,32,64";
	setup->size[0] = 480;
	setup->size[1] = 270;
}

static int analyze_validate(void *opts, cli_ctx *ctx)
{
	analyze_opts *o = opts;
	if (!ctx->setup_opts.frames || !o->out)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG,
				"--scene, --frames and --out are required (see 'taslab %s --help')", ctx->name);
	/* --out is checked before minutes of analysis: not a file (the scene, the OCIO config, an earlier result), and
	 * analyze_main makes sure it can take files before the first frame. */
	if (tl_is_file(o->out))
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--out %s is a file (give a folder)", o->out);
	return cli_parse_float_list(o->thresholds, "--thresholds: T", 1e-6, 255, o->T, ANALYZE_MAX_T, &o->nT, ctx->err,
				    sizeof ctx->err);
}

static int analyze_main(void *opts, cli_ctx *ctx)
{
	analyze_opts *o = opts;
	cli_setup *s = &ctx->setup;
	char *err = ctx->err;
	size_t err_size = sizeof ctx->err;
	bool predictors = !strcmp(ctx->name, "analyze predictors");
	analyze *an = NULL;
	analyze_result *res = NULL;
	uint32_t *frames = malloc(MAX_FRAMES * sizeof *frames);
	size_t nf = 0;
	int rc = frames ? TL_OK : tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	if (!rc)
		rc = cli_parse_frame_list(ctx->setup_opts.frames, s->end, frames, MAX_FRAMES, &nf, err, err_size);
	/* Before the analysis, not after it: the folder exists or can be made, and takes files (a read-only file
	 * system, /proc, missing permissions fail here in a second instead of after minutes). */
	if (!rc)
		rc = tl_check_out_dir(o->out, "--out", err, err_size);
	analyze_desc ad = {.scene = s->scene, .camera = s->camera, .width = s->width, .height = s->height, .fps = s->fps,
			   .thresholds = o->T, .threshold_count = o->nT, .inst_step = (float)o->step,
			   .predictors = predictors, .keep_gradients = o->images, .colour = s->colour};
	if (!rc)
		rc = analyze_create(s->dev, &ad, &an, err, err_size);
	if (!rc && !(res = calloc(nf, sizeof *res)))
		rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	mtr_tfr_meta meta = {.scene = s->scene->name, .camera = s->scene->cameras[s->camera].name,
			     .device = s->dev->props.deviceName, .thresholds = o->T, .threshold_count = o->nT};
	double t0 = tl_clock_s();
	for (size_t i = 0; !rc && i < nf; i++) {
		if ((rc = analyze_frame(an, frames[i], &res[i], err, err_size)))
			break;
		if (vkdev_validation_messages(s->dev)) {
			rc = tl_error(err, err_size, TL_ERR_VALIDATION, "the Vulkan validation layer reported %u message(s)",
				      vkdev_validation_messages(s->dev));
			break;
		}
		if (o->images && (rc = mtr_tfr_write_gradients(&res[i], &meta, o->out, err, err_size)))
			break;
		if (!o->quiet)
			fprintf(stderr, "taslab analyze: frame %u (%zu/%zu)\n", frames[i], i + 1, nf);
	}
	if (!rc) {
		meta.seconds_per_frame = (tl_clock_s() - t0) / (double)nf;
		rc = predictors ? mtr_tfr_write_predictors(res, nf, &meta, o->out, !o->no_plots, err, err_size)
				: mtr_tfr_write_coherence(res, nf, &meta, o->out, !o->no_plots, err, err_size);
	}
	if (!rc && !o->quiet)
		fprintf(stderr, "taslab analyze: %zu frame(s), %.2f s per analysis frame -> %s\n", nf, meta.seconds_per_frame,
			o->out);
	if (res)
		for (size_t i = 0; i < nf; i++)
			analyze_result_free(&res[i]);
	free(res);
	free(frames);
	analyze_destroy(&an);
	return rc;
}

#define ANALYZE_OPTIONS                                                                                            \
	.options = analyze_options, .opts_size = sizeof(analyze_opts), .defaults = analyze_defaults,               \
	.validate = analyze_validate, .needs = CLI_NEED_SCENE | CLI_NEED_FRAME_LIST | CLI_NEED_COLOUR | CLI_NEED_DEVICE, \
	.run = analyze_main

static const cli_command analyze_coherence = {
	.name = "analyze coherence",
	.summary = "temporal coherence of shading (Fig. 4) and visibility coherence (sec. 4.1)",
	.synopsis = "taslab analyze coherence --scene S --frames LIST --out DIR [options]",
	.description = "Every visible sample of an analysis frame t is shaded as it was k = 1..120 frames earlier\n"
		       "(transforms, lights, camera, shadow maps at t - k) on the Vulkan device. Writes the fraction of\n"
		       "samples unchanged (d <= T) for >= k frames per T: DIR/coherence.csv, coherence_frames.csv,\n"
		       "visibility.csv, coherence.json, coherence.png. --frames: F, A:B or A:B:STEP, comma-separated.",
	ANALYZE_OPTIONS,
};

static const cli_command analyze_predictors = {
	.name = "analyze predictors",
	.summary = "gradient predictors late / early / on time (Figs. 7-9)",
	.synopsis = "taslab analyze predictors --scene S --frames LIST --out DIR [options]",
	.description = "Single-frame, long-range and instantaneous (symmetric difference, our stand-in for analytic\n"
		       "derivatives) gradients, unfiltered and with the 8x8 + 9x9 spatial max filter, classified late /\n"
		       "early / on time / unchanged per T: DIR/predictors.csv, predictors_frames.csv, predictors.json,\n"
		       "predictors.png. --frames: F, A:B or A:B:STEP, comma-separated.",
	ANALYZE_OPTIONS,
};

typedef struct reuse_opts {
	const char *out, *error;
} reuse_opts;

static const cli_opt reuse_options[] = {
	{.name = "out", .arg = "DIR", .help = "output folder (default: the sweep's folder)",
	 .type = CLI_STRING, .offset = offsetof(reuse_opts, out)},
	{.name = "error", .arg = "KEY", .help = "the error of eq. 5: a number of each run's metrics summary.json "
						"(default maxrgb_mean; e.g. flip_mean, exceed_8)",
	 .type = CLI_STRING, .offset = offsetof(reuse_opts, error)},
	{0},
};

static void reuse_defaults(void *opts, cli_setup_opts *setup)
{
	(void)setup;
	((reuse_opts *)opts)->error = "maxrgb_mean";
}

static int reuse_main(void *opts, cli_ctx *ctx)
{
	reuse_opts *o = opts;
	char *err = ctx->err;
	size_t err_size = sizeof ctx->err;
	const char *arg = ctx->pos[0];
	char dir[TL_PATH_MAX], spec_path[TL_PATH_MAX + 16];
	/* SWEEP or SWEEP/sweep.json */
	size_t len = strlen(arg);
	if (len >= 11 && !strcmp(arg + len - 11, "/sweep.json"))
		snprintf(dir, sizeof dir, "%.*s", (int)(len - 11), arg);
	else
		snprintf(dir, sizeof dir, "%s", arg);
	snprintf(spec_path, sizeof spec_path, "%s/sweep.json", dir);
	if (!tl_is_file(spec_path))
		return tl_error(err, err_size, TL_ERR_ARG, "%s: not a sweep (no sweep.json)", arg);
	sweep_spec *spec = calloc(1, sizeof *spec);
	if (!spec)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	const char *out = o->out ? o->out : dir;
	size_t groups = 0;
	int rc = sweep_spec_read(spec_path, spec, err, err_size);
	if (!rc && tl_is_file(out))
		rc = tl_error(err, err_size, TL_ERR_ARG, "--out %s is a file (give a folder)", out);
	if (!rc)
		rc = tl_check_out_dir(out, "--out", err, err_size);
	if (!rc)
		rc = mtr_reuse_model(spec, dir, o->error, out, &groups, err, err_size);
	if (!rc)
		printf("%s/reuse_model.md\n", out);
	if (!rc)
		fprintf(stderr, "taslab analyze: %zu scene / path / method group(s) fitted -> %s/reuse_model.csv\n", groups,
			out);
	free(spec);
	return rc;
}

static const cli_command analyze_reuse_model = {
	.name = "analyze reuse-model",
	.summary = "the survey's error, cost and hit-rate models of reuse (eqs. 5-7) fitted to a sweep",
	.synopsis = "taslab analyze reuse-model SWEEP [--out DIR] [--error KEY]",
	.description = "For every scene, camera path and method with a refresh period in SWEEP (rrc/N, rrc-shadow/N,\n"
		       "rrc-diffuse/N, rrc-random/N, rrc-interleaved/N, sau/N, stu/N, warp/N; dn = N), fits [S] eq. 5\n"
		       "eps(dn) = alpha (1 - exp(-lambda (dn - 1))) to the runs' clip-mean error, eq. 6\n"
		       "H A_hit + M A_miss + c = dt to every frame after the first (hits = reused samples, misses =\n"
		       "shaded samples, dt = GPU ms), and eq. 7's hit rate\n"
		       "h(dn) = mu (1 - 1/dn). Writes DIR/reuse_model.csv and reuse_model.md (default DIR: SWEEP) and\n"
		       "prints the .md's path. Sweep the method at two or more periods > 1 for eq. 5.",
	.options = reuse_options,
	.opts_size = sizeof(reuse_opts),
	.defaults = reuse_defaults,
	.min_pos = 1,
	.max_pos = 1,
	.pos_help = "SWEEP",
	.run = reuse_main,
};

static const cli_command *const analyze_subs[] = {&analyze_coherence, &analyze_predictors, &analyze_reuse_model, NULL};

const cli_command cli_cmd_analyze = {
	.name = "analyze",
	.summary = "TFR analysis: coherence, gradient predictors (Figs. 4, 7-9); models of reuse ([S] eqs. 5-7)",
	.synopsis = "taslab analyze coherence|predictors --scene S --frames LIST --out DIR [options]\n"
		    "taslab analyze reuse-model SWEEP [--out DIR] [--error KEY]",
	.subcommands = analyze_subs,
};
