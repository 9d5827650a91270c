/* commands.h — the options structs of the taslab commands (filled by cli_parse_command from each command's
 * table), for the commands themselves and for the parser tests. */
#ifndef TASLAB_CLI_COMMANDS_H
#define TASLAB_CLI_COMMANDS_H

#include "cli.h"
#include "taslab/method.h"

/* Method options given as --NAME [VALUE], applied to the chosen method after parsing. */
typedef struct cli_method_args {
	const char *name[16];
	const char *value[16]; /* NULL for flags */
	size_t n;
} cli_method_args;

/* The method options of every method as CLI options (--threshold, --max-age, ...), writing into a
 * cli_method_args field at `offset`. */
const cli_opt *cli_method_options(size_t offset);
/* --method M (a method or a variant token) plus the --NAME options into a checked configuration. */
int cli_method_config(const char *method, const cli_method_args *args, method_config *out, char *err, size_t err_size);

typedef struct render_opts {
	const char *method, *out;
	bool no_exr, no_png, trivial_shading, quiet, decisions, rate_images;
	cli_method_args margs;
	method_config config; /* from --method and the method options (validate) */
	bool stereo;          /* --stereo: both eyes (STEREO.md) */
	double ipd;           /* --ipd M (metres); negative until given */
	const char *multiview; /* --multiview auto|on|off (NULL until given) */
	int mv;                /* from it: render_multiview (validate) */
} render_opts;

typedef struct pair_opts {
	const char *variants, *out;
	method_config configs[32]; /* the parsed variants (validate) */
	size_t count;
	bool stereo;               /* --stereo: both eyes, side-by-side clips (STEREO.md) */
	double ipd;                /* --ipd M; negative until given */
} pair_opts;

typedef struct tonemap_opts {
	const char *out;
} tonemap_opts;

typedef struct clip_opts {
	const char *out;
	const char *eye; /* --eye L|R|sbs (stereo runs) */
} clip_opts;

typedef struct metrics_diff_opts {
	const char *ref, *test, *out, *format;
	bool heatmaps, plots;
	double heatmap_max;
	uint32_t threads;
} metrics_diff_opts;

typedef struct metrics_runs_opts {
	const char *out, *baseline;
} metrics_runs_opts;

typedef struct metrics_jnd_opts {
	uint64_t n, ref_preferred, ties; /* answer counts: whole numbers (ref_preferred UINT64_MAX: not given) */
	double confidence;
} metrics_jnd_opts;

typedef struct analyze_opts {
	const char *frames, *thresholds, *out;
	double step;
	bool images, no_plots, quiet;
	float T[8];
	size_t nT;
} analyze_opts;

typedef struct study_opts {
	const char *db, *stimuli, *out, *pwcmp, *base, *bind, *prior, *gold_variant, *model, *sweep;
	uint32_t participants, training, catch_trials, gold_trials, break_every, port, threads, bootstrap, trials;
	uint64_t seed;
	bool keep_flagged, adaptive, p910;
	/* serve's connection limits (0: the server's default; sty_server_desc) */
	uint32_t max_connections, max_per_client, max_reading, idle_timeout, head_timeout, body_timeout, send_timeout;
} study_opts;

/* A sweep setting as the command line gave it: the option parser's own types (CLI_STRING for lists and strings,
 * CLI_DOUBLE, CLI_UINT, CLI_SIZE, CLI_FLAG) write into it; all zero when not given (a number's range starts above 0). */
typedef union sweep_cli_value {
	const char *text;
	double number;
	uint32_t whole;
	uint32_t size[2];
	bool flag;
} sweep_cli_value;

#define SWEEP_CLI_KEYS_MAX 32

/* `taslab sweep` (cmd_sweep.c): the settings are the sweep key table's (output/sweep_keys.h), each also a key of the
 * sweep file; given options override the file's. */
typedef struct sweep_opts {
	sweep_cli_value keys[SWEEP_CLI_KEYS_MAX]; /* [i]: key i of sweep_keys() (cli_sweep_key_options) */
	bool slurm, slurm_dry_run, no_report, quiet, redo_damaged;
	const char *slurm_opts, *task;
} sweep_opts;

/* `taslab report` (cmd_report.c). */
typedef struct report_opts {
	const char *study, *jnd_metric;
	const char *model; /* --model MODEL.json: predicted thresholds beside the measured ones (study_model.h) */
	const char *mono; /* --mono MONO_SWEEP: a stereo sweep's speedups beside this mono sweep's */
	bool quiet;
} report_opts;

#endif
