/* cmd_study_model.c — `taslab study model` (issue 28): a metric-to-JND model from a tallied study and the sweep of its
 * clips, its leave-one-scene-out error, and predicted thresholds for a sweep nobody rated (study_model.h). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "commands.h"
#include "taslab/study_model.h"

typedef struct model_opts {
	const char *sweep, *tally, *out, *metric, *predict, *predict_out, *model;
} model_opts;

static const cli_opt model_options[] = {
	{.name = "sweep", .arg = "SWEEP", .help = "the sweep of the rated clips (its summary.csv)",
	 .type = CLI_STRING, .offset = offsetof(model_opts, sweep)},
	{.name = "tally", .arg = "DIR", .help = "the study's tally folder (jod.csv, thresholds.csv of 'study tally')",
	 .type = CLI_STRING, .offset = offsetof(model_opts, tally)},
	{.name = "out", .arg = "MODEL.json", .help = "the model (metric, fit, leave-one-scene-out error, predictions)",
	 .type = CLI_STRING, .offset = offsetof(model_opts, out)},
	{.name = "metric", .arg = "COLUMN", .help = "a numeric summary.csv column or exceed_T (default flip_mean; "
	 "e.g. maxrgb_p99, flicker_mean)", .type = CLI_STRING, .offset = offsetof(model_opts, metric)},
	{.name = "predict", .arg = "SWEEP2", .help = "predict t_jnd with a 95% interval for every scene x path x method "
	 "of this sweep", .type = CLI_STRING, .offset = offsetof(model_opts, predict)},
	{.name = "predict-out", .arg = "CSV", .help = "the predictions (default: MODEL-predictions.csv beside --out)",
	 .type = CLI_STRING, .offset = offsetof(model_opts, predict_out)},
	{.name = "model", .arg = "MODEL.json", .help = "predict from this saved model (no --sweep/--tally, no refit); "
	 "--out then writes a copy holding the new predictions", .type = CLI_STRING, .offset = offsetof(model_opts, model)},
	{0},
};

static int model_main(void *opts, cli_ctx *ctx)
{
	model_opts *o = opts;
	if (!o->model && (!o->sweep || !o->tally || !o->out))
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "need --sweep SWEEP, --tally DIR and --out MODEL.json "
				"(or --model MODEL.json --predict SWEEP2)");
	sty_model_desc d = {.sweep = o->sweep, .tally = o->tally, .out = o->out, .metric = o->metric,
			    .predict = o->predict, .predict_out = o->predict_out, .model = o->model};
	sty_model_summary s;
	int rc = sty_model_run(&d, &s, ctx->err, sizeof ctx->err);
	if (rc)
		return rc;
	if (o->model) {
		printf("model %s (metric at 1 JND = %g): %zu prediction(s) for %s\n", o->model, s.m_jnd, s.predictions,
		       o->predict);
		return TL_OK;
	}
	char rm[32] = "undefined (one scene)";
	if (isfinite(s.loso_rmse_log2))
		snprintf(rm, sizeof rm, "%.3f", s.loso_rmse_log2);
	printf("model %s: %s at 1 JND = %g from %zu conditions in %zu scene(s); leave-one-scene-out RMSE of log2 t_jnd %s "
	       "over %zu threshold(s)",
	       o->out, o->metric ? o->metric : "flip_mean", s.m_jnd, s.conditions, s.scenes, rm, s.loso_n);
	if (s.loso_open)
		printf(" (%zu more predicted outside the rendered range)", s.loso_open);
	if (o->predict)
		printf("; %zu prediction(s) for %s", s.predictions, o->predict);
	printf("\n");
	return TL_OK;
}

const cli_command cli_cmd_study_model = {
	.name = "study model",
	.summary = "metric-to-JND model: JOD of the rated conditions against a sweep metric; predicted thresholds",
	.synopsis = "taslab study model --sweep SWEEP --tally DIR --out MODEL.json [--metric COLUMN] [--predict SWEEP2] "
		    "[--predict-out CSV]\n"
		    "       taslab study model --model MODEL.json --predict SWEEP2 [--predict-out CSV] [--out MODEL2.json]",
	.description = "Fits -JOD of each rated condition (jod.csv) monotonically against log2 of a metric of the same "
		       "clip (summary.csv), reports the leave-one-scene-out RMSE of log2 t_jnd against thresholds.csv, and "
		       "with --predict writes t_jnd with a 95% interval for every series of T of another sweep. With --model, predicts from a saved model without refitting (the same predictions "
		       "as the fit that wrote it).",
	.options = model_options,
	.opts_size = sizeof(model_opts),
	.run = model_main,
};
