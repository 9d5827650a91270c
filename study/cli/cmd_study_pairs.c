/* cmd_study_pairs.c — `taslab study pairs` (issue 27.13): a study's stimuli from a sweep's runs, one pairs.json set
 * per scene and camera path whose clips are the sweep's (study.h sty_pairs_from_sweep), instead of rendering them
 * again with `taslab pair`. */
#include <stdio.h>
#include <string.h>

#include "commands.h"
#include "taslab/study.h"

typedef struct study_pairs_opts {
	const char *sweep, *out, *variants;
} study_pairs_opts;

static const cli_opt study_pairs_options[] = {
	{.name = "sweep", .arg = "SWEEP", .help = "the sweep folder (holding sweep.json) whose runs give the clips",
	 .type = CLI_STRING, .offset = offsetof(study_pairs_opts, sweep)},
	{.name = "out", .arg = "DIR", .help = "new (or empty) folder for the sets: DIR/<scene>--<camera>/pairs.json and clips/",
	 .type = CLI_STRING, .offset = offsetof(study_pairs_opts, out)},
	{.name = "variants", .arg = "LIST",
	 .help = "the sweep's variants to rate against its ref (tokens such as tfr@8, or ids such as tfr-T8; default: every "
		 "variant but ref)",
	 .type = CLI_STRING, .offset = offsetof(study_pairs_opts, variants)},
	{0},
};

static int study_pairs_main(void *opts, cli_ctx *ctx)
{
	study_pairs_opts *o = opts;
	char buf[4096];
	const char *items[64];
	size_t n = 0, sets = 0;
	if (!o->sweep || !o->out)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG,
				"--sweep SWEEP and --out DIR are required (see 'taslab study pairs --help')");
	int rc = o->variants ? cli_split_list(o->variants, "--variants", buf, sizeof buf, items, 64, &n, ctx->err,
					      sizeof ctx->err)
			     : TL_OK;
	if (rc)
		return rc;
	sty_pairs_desc d = {.sweep = o->sweep, .out = o->out, .variants = items, .variant_count = n};
	if ((rc = sty_pairs_from_sweep(&d, &sets, ctx->err, sizeof ctx->err)))
		return rc;
	fprintf(stderr, "taslab: %zu set(s) from %s's clips in %s (next: taslab study design --db STUDY.db --stimuli %s "
			"--participants N)\n",
		sets, o->sweep, o->out, o->out);
	printf("%s\n", o->out);
	return TL_OK;
}

const cli_command cli_cmd_study_pairs = {
	.name = "study pairs",
	.summary = "study stimuli from a sweep's runs: one pairs.json set per scene and camera path, the sweep's own clips",
	.synopsis = "taslab study pairs --sweep SWEEP --out DIR [--variants LIST]",
	.description = "Writes DIR/<scene>--<camera>/pairs.json and clips/ (hard links to the sweep's clips, copies across "
		       "file systems) for\n  every scene and camera path of the sweep: the rated clips are the ones the "
		       "sweep measured, and\n  'taslab report SWEEP --study STUDY.db' checks that they are. Every run must be "
		       "complete.",
	.options = study_pairs_options,
	.opts_size = sizeof(study_pairs_opts),
	.run = study_pairs_main,
};
