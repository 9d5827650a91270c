/* cmd_study_simulate.c — `taslab study simulate` (issue 28): seeded simulated studies with a known psychometric
 * function through the design's trial choice and the tally's threshold fit (study_threshold.h sty_simulate). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "taslab/study.h"
#include "taslab/study_threshold.h"

typedef struct simulate_opts {
	const char *design, *t_levels, *out;
	uint32_t participants, trials, studies, jobs;
	double t_jnd, observer_sd, slope, lapse, ties;
	uint64_t seed;
} simulate_opts;

static const cli_opt simulate_options[] = {
	{.name = "design", .arg = "full|adaptive", .help = "full: every participant rates every level equally often; "
	 "adaptive: each trial's T chosen by QUEST+ from everyone's answers so far (default full)",
	 .type = CLI_STRING, .offset = offsetof(simulate_opts, design)},
	{.name = "participants", .arg = "P", .help = "participants per study (default 24)",
	 .type = CLI_UINT, .offset = offsetof(simulate_opts, participants), .lo = 1, .hi = 100000},
	{.name = "trials", .arg = "N", .help = "test trials per participant (full: a multiple of the levels; default: "
	 "one per level)", .type = CLI_UINT, .offset = offsetof(simulate_opts, trials), .lo = 1, .hi = 100000},
	{.name = "t-levels", .arg = "T,T,...", .help = "the rendered levels of T (default 2,4,8,16,32,64)",
	 .type = CLI_STRING, .offset = offsetof(simulate_opts, t_levels)},
	{.name = "t-jnd", .arg = "X", .help = "the median observer's threshold T (default 12)",
	 .type = CLI_DOUBLE, .offset = offsetof(simulate_opts, t_jnd), .lo = 1e-3, .hi = 1e6},
	{.name = "observer-sd", .arg = "S", .help = "SD of the observers' log2 thresholds (default 0.5)",
	 .type = CLI_DOUBLE, .offset = offsetof(simulate_opts, observer_sd), .lo = 0, .hi = STY_OBSERVER_SD_MAX},
	{.name = "slope", .arg = "B", .help = "slope of the psychometric function per log2 unit (probit; default 1.5)",
	 .type = CLI_DOUBLE, .offset = offsetof(simulate_opts, slope), .lo = STY_SLOPE_MIN, .hi = STY_SLOPE_MAX},
	{.name = "lapse", .arg = "L", .help = "lapse rate (default 0.02)",
	 .type = CLI_DOUBLE, .offset = offsetof(simulate_opts, lapse), .lo = 0, .hi = STY_LAPSE_MAX},
	{.name = "ties", .arg = "F", .help = "share of 'same' answers where nothing is seen (default 0.2)",
	 .type = CLI_DOUBLE, .offset = offsetof(simulate_opts, ties), .lo = 0, .hi = 1},
	{.name = "studies", .arg = "M", .help = "simulated studies (default 100)",
	 .type = CLI_UINT, .offset = offsetof(simulate_opts, studies), .lo = 1, .hi = 1000000},
	{.name = "seed", .arg = "K", .help = "seed (study k uses K + k, at most 4294967295; default 1)",
	 .type = CLI_U64, .offset = offsetof(simulate_opts, seed), .lo = 0, .hi = STY_SEED_MAX},
	{.name = "jobs", .arg = "N", .help = "studies fitted at a time (default: one per CPU; the output is the same for any N)",
	 .type = CLI_UINT, .offset = offsetof(simulate_opts, jobs), .lo = 1, .hi = 256},
	{.name = "out", .arg = "DIR", .help = "folder for simulation.csv (one row per study)",
	 .type = CLI_STRING, .offset = offsetof(simulate_opts, out)},
	{0},
};

static void simulate_defaults(void *opts, cli_setup_opts *setup)
{
	(void)setup;
	simulate_opts *o = opts;
	o->participants = 24;
	o->t_jnd = 12;
	o->observer_sd = 0.5;
	o->slope = 1.5;
	o->lapse = 0.02;
	o->ties = 0.2;
	o->studies = 100;
	o->seed = 1;
}

#define MAX_LEVELS 64

/* "2,4,8" into T[]; TL_ERR_ARG with one line for anything else. */
static int parse_levels(const char *s, double *T, size_t *n, char *err, size_t err_size)
{
	*n = 0;
	while (*s) {
		char *end;
		double v = strtod(s, &end);
		if (end == s || (*end && *end != ',') || !(v > 0) || !isfinite(v))
			return tl_error(err, err_size, TL_ERR_ARG, "--t-levels '%s': need numbers T > 0 separated by commas", s);
		if (*n == MAX_LEVELS)
			return tl_error(err, err_size, TL_ERR_ARG, "--t-levels: at most %d levels", MAX_LEVELS);
		T[(*n)++] = v;
		s = *end ? end + 1 : end;
		if (*end && !*s)
			return tl_error(err, err_size, TL_ERR_ARG, "--t-levels: a trailing comma");
	}
	return TL_OK;
}

static int simulate_main(void *opts, cli_ctx *ctx)
{
	simulate_opts *o = opts;
	double T[MAX_LEVELS];
	size_t n;
	int rc = parse_levels(o->t_levels ? o->t_levels : "2,4,8,16,32,64", T, &n, ctx->err, sizeof ctx->err);
	if (rc)
		return rc;
	const char *design = o->design ? o->design : "full";
	if (strcmp(design, "full") && strcmp(design, "adaptive"))
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--design '%s': full or adaptive", design);
	sty_sim_desc d = {.adaptive = !strcmp(design, "adaptive"), .participants = o->participants,
			  .trials = o->trials ? o->trials : (uint32_t)n, .T = T, .nlevels = n, .t_jnd = o->t_jnd,
			  .observer_sd = o->observer_sd, .slope = o->slope, .lapse = o->lapse, .ties = o->ties,
			  .studies = o->studies, .seed = o->seed, .out = o->out, .jobs = o->jobs};
	sty_sim_summary s;
	if ((rc = sty_simulate(&d, &s, ctx->err, sizeof ctx->err)))
		return rc;
	printf("design %s, %u studies, %u participants x %u trials = %u trials/study: RMSE of log2 t_jnd %.3f (bias %+.3f), "
	       "95%% interval covers the true t_jnd in %.1f%% (mean width %.2f octaves)%s%s%s\n",
	       design, s.studies, d.participants, d.trials, s.trials_total, s.rmse_log2, s.bias_log2, 100 * s.coverage,
	       s.mean_width_log2, o->out ? "; " : "", o->out ? o->out : "", o->out ? "/simulation.csv" : "");
	return TL_OK;
}

const cli_command cli_cmd_study_simulate = {
	.name = "study simulate",
	.summary = "seeded simulated studies: the threshold fit's RMSE and interval coverage, full vs adaptive design",
	.synopsis = "taslab study simulate [--design full|adaptive] [--participants P] [--trials N] [--t-levels 2,4,8,16,32,64] "
		    "[--t-jnd X] [--observer-sd S] [--slope B] [--lapse L] [--ties F] [--studies M] [--seed K] [--jobs N] [--out DIR]",
	.description = "Observers with a known psychometric function (log2 thresholds normal around --t-jnd with SD "
		       "--observer-sd) answer on the five-point scale; trials are chosen as 'study design' (full) or "
		       "'study serve' (adaptive) would, each study is fitted as 'study tally' fits thresholds.csv. Prints one "
		       "line (RMSE and bias of log2 t_jnd, coverage of the 95% interval); --out writes simulation.csv.",
	.options = simulate_options,
	.opts_size = sizeof(simulate_opts),
	.defaults = simulate_defaults,
	.run = simulate_main,
};
