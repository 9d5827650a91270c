/* cmd_study.c — `taslab study design|add|links|serve|status|tally|export|import` (study/; `simulate`:
 * cmd_study_simulate.c; `pairs`: cmd_study_pairs.c). */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "commands.h"
#include "taslab/method.h"
#include "taslab/study.h"
#include "taslab/study_serve.h"
#include "taslab/study_status.h"

static const cli_opt db_option[] = {
	{.name = "db", .arg = "STUDY.db",
	 .help = "the study database (an SQLite file; design and import create it and never overwrite one)",
	 .type = CLI_STRING, .offset = offsetof(study_opts, db)},
	{0},
};

static const cli_opt design_options[] = {
	{.type = CLI_INCLUDE, .include = db_option},
	{.name = "stimuli", .arg = "DIR",
	 .help = "folder holding the pairs.json sets (made by 'taslab pair'), or sets one level below",
	 .type = CLI_STRING, .offset = offsetof(study_opts, stimuli)},
	{.name = "participants", .arg = "N",
	 .help = "participants to plan for (1..10000)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, participants), .lo = 1, .hi = 10000},
	{.name = "seed", .arg = "S",
	 .help = "seed of the randomisation (0..4294967295, default 1)",
	 .type = CLI_U64, .offset = offsetof(study_opts, seed), .lo = 0, .hi = STY_SEED_MAX},
	{.name = "training", .arg = "K",
	 .help = "training trials at the start, not analysed (0..100)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, training), .lo = 0, .hi = 100},
	{.name = "catch", .arg = "K",
	 .help = "catch trials (reference against itself) for observer screening (0..100)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, catch_trials), .lo = 0, .hi = 100},
	{.name = "gold", .arg = "K",
	 .help = "gold trials (the reference against a strongly degraded variant: answer known) for P.910-crowd screening "
		 "(0..100)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, gold_trials), .lo = 0, .hi = 100},
	{.name = "gold-variant", .arg = "ID",
	 .help = "with --gold: the gold condition's pairs.json id in every set (default: each set's largest T or period)",
	 .type = CLI_STRING, .offset = offsetof(study_opts, gold_variant)},
	{.name = "break-every", .arg = "N",
	 .help = "a break after every N trials (0: none)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, break_every), .lo = 0, .hi = 10000},
	{.name = "adaptive", .arg = NULL,
	 .help = "choose each trial's T when it is shown (QUEST+ on everyone's answers so far; needs --trials)",
	 .type = CLI_FLAG, .offset = offsetof(study_opts, adaptive)},
	{.name = "trials", .arg = "N",
	 .help = "with --adaptive: test trials per participant (1..10000)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, trials), .lo = 1, .hi = 10000},
	{.name = "prior", .arg = "MODEL.json",
	 .help = "with --adaptive: each group's prior on t_jnd from 'study model --predict' of the stimuli's sweep",
	 .type = CLI_STRING, .offset = offsetof(study_opts, prior)},
	{0},
};

static const cli_opt add_options[] = {
	{.type = CLI_INCLUDE, .include = db_option},
	{.name = "participants", .arg = "N",
	 .help = "participants to add (1..10000), planned from the study's seed like the first ones",
	 .type = CLI_UINT, .offset = offsetof(study_opts, participants), .lo = 1, .hi = 10000},
	{0},
};

static const cli_opt links_options[] = {
	{.type = CLI_INCLUDE, .include = db_option},
	{.name = "base", .arg = "URL",
	 .help = "base of the links (default: the address the study was last served on, else http://127.0.0.1:8080)",
	 .type = CLI_STRING, .offset = offsetof(study_opts, base)},
	{0},
};

static const cli_opt serve_options[] = {
	{.type = CLI_INCLUDE, .include = db_option},
	{.name = "port", .arg = "P",
	 .help = "TCP port (default 8080; 0: any free port, printed)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, port), .lo = 0, .hi = 65535},
	{.name = "bind", .arg = "ADDR",
	 .help = "address to listen on (default 127.0.0.1)",
	 .type = CLI_STRING, .offset = offsetof(study_opts, bind)},
	{.name = "threads", .arg = "N",
	 .help = "server threads (1..64, default 4)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, threads), .lo = 1, .hi = 64},
	{.name = "max-connections", .arg = "N",
	 .help = "connections in all (16..100000, default 1024)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, max_connections), .lo = 16, .hi = 100000},
	{.name = "max-per-client", .arg = "N",
	 .help = "connections per client address (1..100000; default: no cap, a lab behind one NAT or proxy is one address)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, max_per_client), .lo = 1, .hi = 100000},
	{.name = "max-reading", .arg = "N",
	 .help = "connections reading a request at once; a new one beyond closes the one reading longest (default: half of --max-connections)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, max_reading), .lo = 1, .hi = 100000},
	{.name = "idle-timeout", .arg = "S",
	 .help = "seconds before an idle connection is closed (1..3600, default 15)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, idle_timeout), .lo = 1, .hi = 3600},
	{.name = "head-timeout", .arg = "S",
	 .help = "seconds a request head may take, however slowly it trickles (1..3600, default 10)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, head_timeout), .lo = 1, .hi = 3600},
	{.name = "body-timeout", .arg = "S",
	 .help = "seconds a request body may take after its head (1..3600, default 10)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, body_timeout), .lo = 1, .hi = 3600},
	{.name = "send-timeout", .arg = "S",
	 .help = "seconds a reply (a clip) may take to send, however slowly it is read (1..3600, default 120, the page's own limit per clip)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, send_timeout), .lo = 1, .hi = 3600},
	{0},
};

static const cli_opt tally_options[] = {
	{.type = CLI_INCLUDE, .include = db_option},
	{.name = "out", .arg = "DIR", .help = "output folder", .type = CLI_STRING, .offset = offsetof(study_opts, out)},
	{.name = "keep-flagged", .arg = NULL,
	 .help = "keep observers flagged by the catch-trial screening",
	 .type = CLI_FLAG, .offset = offsetof(study_opts, keep_flagged)},
	{.name = "p910", .arg = NULL,
	 .help = "also leave out observers the P.910-crowd screening flags (a catch answer 'much better', a gold answer not "
		 "'reference better', answer variance < 0.1)",
	 .type = CLI_FLAG, .offset = offsetof(study_opts, p910)},
	{.name = "model", .arg = "MODEL.json",
	 .help = "with --sweep: the model's predicted t_jnd beside each measured one (thresholds.csv, tables.md)",
	 .type = CLI_STRING, .offset = offsetof(study_opts, model)},
	{.name = "sweep", .arg = "SWEEP",
	 .help = "with --model: the sweep whose clips were rated (the model predicts from its summary.csv)",
	 .type = CLI_STRING, .offset = offsetof(study_opts, sweep)},
	{.name = "bootstrap", .arg = "B",
	 .help = "bootstrap resamples for the JOD intervals (1..100000, default 2000)",
	 .type = CLI_UINT, .offset = offsetof(study_opts, bootstrap), .lo = 1, .hi = 100000},
	{.name = "seed", .arg = "S",
	 .help = "seed of the bootstrap (0..4294967295, default 1)",
	 .type = CLI_U64, .offset = offsetof(study_opts, seed), .lo = 0, .hi = STY_SEED_MAX},
	{0},
};

static const cli_opt export_options[] = {
	{.type = CLI_INCLUDE, .include = db_option},
	{.name = "out", .arg = "RATINGS.csv",
	 .help = "long-format ratings (DESIGN section 7)",
	 .type = CLI_STRING, .offset = offsetof(study_opts, out)},
	{.name = "pwcmp", .arg = "PAIRS.csv",
	 .help = "also the pwcmp layout",
	 .type = CLI_STRING, .offset = offsetof(study_opts, pwcmp)},
	{0},
};

static void study_defaults(void *opts, cli_setup_opts *setup)
{
	(void)setup;
	study_opts *o = opts;
	o->port = 8080;
	o->seed = 1;
}

static int study_validate(void *opts, cli_ctx *ctx)
{
	study_opts *o = opts;
	const char *sub = strrchr(ctx->name, ' ') + 1;
	char *err = ctx->err;
	size_t n = sizeof ctx->err;
	if (!o->db)
		return tl_error(err, n, TL_ERR_ARG, "--db STUDY.db is required (see 'taslab %s --help')", ctx->name);
	if (!strcmp(sub, "add") && !o->participants)
		return tl_error(err, n, TL_ERR_ARG, "--participants N is required");
	if (!strcmp(sub, "design") && (!o->stimuli || !o->participants))
		return tl_error(err, n, TL_ERR_ARG, "--stimuli DIR and --participants N are required");
	if ((!strcmp(sub, "tally") || !strcmp(sub, "export")) && !o->out)
		return tl_error(err, n, TL_ERR_ARG, "--out is required");
	return TL_OK;
}

static volatile sig_atomic_t stop_flag;
static void on_signal(int sig) { (void)sig; stop_flag = 1; }

/* The methods of taslab's registry, described to the study (issue 30.1: the study module knows no method by name):
 * every method and every "-FLAG", "-NAMEvalue" and "-VALUE" form of it (method_dash_forms: tarc-oracle, ref-ssaa2,
 * rrc-shadow), the variant method names a ratings file or pairs.json carries. */
static int describe_methods(sty *s, char *err, size_t err_size)
{
	size_t n;
	const method_info *const *m = method_list(&n);
	int rc = TL_OK;
	for (size_t i = 0; i < n && !rc; i++) {
		run_method_facts f;
		method_facts(m[i], &f);
		rc = sty_describe_method(s, m[i]->name, &f, err, err_size);
		char forms[METHOD_DASH_FORMS_MAX][METHOD_DASH_FORM_B];
		size_t k = method_dash_forms(m[i], forms, METHOD_DASH_FORMS_MAX);
		for (size_t j = 0; j < k && j < METHOD_DASH_FORMS_MAX && !rc; j++) {
			char name[96];
			snprintf(name, sizeof name, "%s-%s", m[i]->name, forms[j]);
			rc = sty_describe_method(s, name, &f, err, err_size);
		}
	}
	return rc;
}

static int study_main(void *opts, cli_ctx *ctx)
{
	study_opts *o = opts, ov = *o;
	const char *sub = strrchr(ctx->name, ' ') + 1;
	char *err = ctx->err;
	size_t err_size = sizeof ctx->err;
	/* design and import build a new study in a temporary file and move it into place only on success
	 * (sty_create/sty_commit): a failure leaves nothing behind, and an existing study is refused. */
	int create = !strcmp(sub, "design") || !strcmp(sub, "import");
	sty *s = NULL;
	int rc = create ? sty_create(o->db, &s, err, err_size) : sty_open(o->db, &s, err, err_size);
	if (rc == TL_ERR_CONFLICT) { /* an existing study: bad input (exit 2), and how to grow one (issue 27.7) */
		size_t len = strlen(err);
		snprintf(err + len, err_size - len, "%s", !strcmp(sub, "design") ? "; to add participants to it: taslab study "
					     "add --db STUDY.db --participants N" : "");
		return TL_ERR_ARG;
	}
	if (rc)
		return rc;
	if ((rc = describe_methods(s, err, err_size))) {
		sty_close(&s);
		return rc;
	}
	if (!strcmp(sub, "design")) {
		sty_design_desc d = {.stimuli = ov.stimuli, .participants = ov.participants, .seed = ov.seed,
				     .training = ov.training, .catch_trials = ov.catch_trials, .gold_trials = ov.gold_trials,
				     .gold_variant = ov.gold_variant, .break_every = ov.break_every,
				     .adaptive = ov.adaptive, .trials = ov.trials, .prior = ov.prior};
		sty_design_summary sm;
		if (!(rc = sty_design(s, &d, &sm, err, err_size)) && !(rc = sty_commit(s, err, err_size))) {
			printf("study %s: %u conditions from %u set(s), %u participants, %u trials each, %u break(s); "
			       "estimated session %.1f min\nlinks: taslab study links --db %s; run: taslab study serve --db %s\n",
			       ov.db, sm.conditions, sm.sets, sm.participants, sm.trials_per_participant, sm.breaks, sm.session_minutes,
			       ov.db, ov.db);
			if (ov.prior)
				printf("prior: %s predicts t_jnd for %u of %u adaptive group(s) (the others start uniform)\n",
				       ov.prior, sm.priors, sm.groups);
		}
	} else if (!strcmp(sub, "add")) {
		uint32_t first;
		if (!(rc = sty_add_participants(s, ov.participants, &first, err, err_size)))
			printf("study %s: added participants P%03u..P%03u (their links: taslab study links --db %s)\n", ov.db, first,
			       first + ov.participants - 1, ov.db);
	} else if (!strcmp(sub, "status")) {
		rc = sty_status_print(s, stdout, err, err_size);
	} else if (!strcmp(sub, "links")) {
		char **codes;
		size_t n;
		/* The base: --base, else the URL the server last listened on (stored by 'study serve'), else the default
		 * address of 'study serve'. */
		const char *base = ov.base ? ov.base : sty_served_url(s)[0] ? sty_served_url(s) : "http://127.0.0.1:8080";
		if (!ov.base && strstr(base, "://0.0.0.0:"))
			fprintf(stderr, "taslab study links: the server listened on all addresses (0.0.0.0); give --base "
					"http://HOST:PORT with an address participants can reach\n");
		if (!(rc = sty_participant_codes(s, &codes, &n, err, err_size))) {
			for (size_t i = 0; i < n; i++) {
				printf("P%03zu %s/p/%s\n", i + 1, base, codes[i]);
				free(codes[i]);
			}
			free(codes);
		}
	} else if (!strcmp(sub, "serve")) {
		sty_server *sv = NULL;
		sty_server_desc sd = {.bind = ov.bind, .port = (uint16_t)ov.port, .threads = ov.threads,
				      .max_connections = ov.max_connections, .max_per_client = ov.max_per_client,
				      .max_reading = ov.max_reading, .timeout_s = ov.idle_timeout,
				      .head_timeout_s = ov.head_timeout, .body_timeout_s = ov.body_timeout,
				      .send_timeout_s = ov.send_timeout};
		if (!(rc = sty_server_start(s, &sd, &sv, err, err_size))) {
			printf("listening on %s\nadmin token %s (send it as the header 'Authorization: Bearer TOKEN' to "
			       "/admin/status, /admin/export.csv and /admin/export-pwcmp.csv)\nstatus page %s/status#%s\n",
			       sty_served_url(s), sty_admin_token(s), sty_served_url(s), sty_admin_token(s));
			fflush(stdout);
			struct sigaction sa = {.sa_handler = on_signal};
			sigaction(SIGINT, &sa, NULL);
			sigaction(SIGTERM, &sa, NULL);
			while (!stop_flag)
				pause();
			sty_server_stats st = sty_server_get_stats(sv);
			sty_server_stop(&sv);
			if (st.answers)
				fprintf(stderr, "taslab study serve: %llu answers acknowledged in %llu commits; the server's time per "
						"answer p50 %.2f ms, p99 %.2f ms (complete request to reply queued, its durable commit "
						"included)\n", (unsigned long long)st.answers, (unsigned long long)st.commits,
					st.answer_ms_p50, st.answer_ms_p99);
			fprintf(stderr, "taslab study serve: stopped\n");
		}
	} else if (!strcmp(sub, "tally")) {
		sty_tally_desc t = {.out = ov.out, .keep_flagged = ov.keep_flagged, .p910 = ov.p910, .bootstrap = ov.bootstrap,
				    .model = ov.model, .sweep = ov.sweep,
				    .seed = ov.seed};
		if (!(rc = sty_tally(s, &t, err, err_size))) {
			fprintf(stderr, "taslab: study statistics in %s (conditions.csv, anova.csv, posthoc.csv, observers.csv, "
					"jod.csv, thresholds.csv, tables.md, fig3.png)\n", ov.out);
		}
	} else if (!strcmp(sub, "export")) {
		/* Both files are checked before either is written (not the database, not each other) and appear together. */
		rc = sty_export(s, ov.out, ov.pwcmp, err, err_size);
	} else {
		size_t rows;
		if (!(rc = sty_import_long(s, ctx->pos[0], &rows, err, err_size)) && !(rc = sty_commit(s, err, err_size))) {
			fprintf(stderr, "taslab: imported %zu ratings into %s\n", rows, ov.db);
		}
	}
	sty_close(&s);
	return rc;
}

#define STUDY_SUB .opts_size = sizeof(study_opts), .defaults = study_defaults, .validate = study_validate, .run = study_main

static const cli_command study_design = {
	.name = "study design",
	.summary = "randomised within-subject plan from the pairs.json sets of a stimulus folder",
	.synopsis = "taslab study design --db STUDY.db --stimuli DIR --participants N [--seed S] [--training K] [--catch K] "
		    "[--gold K [--gold-variant ID]] [--break-every N] [--adaptive --trials N [--prior MODEL.json]]",
	.options = design_options,
	STUDY_SUB,
};
static const cli_command study_add = {
	.name = "study add",
	.summary = "add participants to a designed study (seeded plans; existing participants untouched)",
	.synopsis = "taslab study add --db STUDY.db --participants N",
	.options = add_options,
	STUDY_SUB,
};
static const cli_command study_status = {
	.name = "study status",
	.summary = "participants' progress and the conditions' n, p_ref and Q so far (also while serving)",
	.synopsis = "taslab study status --db STUDY.db",
	.options = db_option,
	STUDY_SUB,
};
static const cli_command study_links = {
	.name = "study links",
	.summary = "one unguessable link per participant",
	.synopsis = "taslab study links --db STUDY.db [--base URL]",
	.options = links_options,
	STUDY_SUB,
};
static const cli_command study_serve = {
	.name = "study serve",
	.summary = "run the study in the browser (prints the admin token; Ctrl-C stops it)",
	.synopsis = "taslab study serve --db STUDY.db [--port P] [--bind ADDR] [--threads N] [--max-connections N] ...",
	.options = serve_options,
	STUDY_SUB,
};
static const cli_command study_tally = {
	.name = "study tally",
	.summary = "Q, p_ref, JND, RM-ANOVA, post hoc tests, screening, JOD, Fig. 3",
	.synopsis = "taslab study tally --db STUDY.db --out DIR [--keep-flagged] [--p910] [--model MODEL.json --sweep SWEEP] "
		    "[--bootstrap B] [--seed S]",
	.description = "Writes conditions.csv, anova.csv, posthoc.csv, observers.csv, jod.csv, thresholds.csv, tables.md, "
		       "fig3.png.",
	.options = tally_options,
	STUDY_SUB,
};
static const cli_command study_export = {
	.name = "study export",
	.summary = "long-format ratings CSV (and the pwcmp layout)",
	.synopsis = "taslab study export --db STUDY.db --out RATINGS.csv [--pwcmp PAIRS.csv]",
	.options = export_options,
	STUDY_SUB,
};
static const cli_command study_import = {
	.name = "study import",
	.summary = "load a long-format ratings file into a new study database (validated; all or nothing)",
	.synopsis = "taslab study import --db STUDY.db RATINGS.csv",
	.options = db_option,
	.min_pos = 1,
	.max_pos = 1,
	.pos_help = "RATINGS.csv",
	STUDY_SUB,
};

extern const cli_command cli_cmd_study_simulate; /* cmd_study_simulate.c (issue 28) */
extern const cli_command cli_cmd_study_pairs;    /* cmd_study_pairs.c (issue 27.13) */
extern const cli_command cli_cmd_study_model;    /* cmd_study_model.c (issue 28) */
static const cli_command *const study_subs[] = {&cli_cmd_study_pairs, &study_design, &study_add, &study_links,
						&study_serve, &study_status, &study_tally, &study_export,
						&study_import, &cli_cmd_study_simulate, &cli_cmd_study_model, NULL};

const cli_command cli_cmd_study = {
	.name = "study",
	.summary = "pairwise-comparison studies: pairs, design, add, serve, status, tally, export/import",
	.synopsis = "taslab study <subcommand> --db STUDY.db [options]",
	.subcommands = study_subs,
};
