/* cmd_study.c — `taslab study design|links|serve|tally|export|import` (study/). */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "taslab/study.h"
#include "taslab/study_serve.h"

static void study_usage(FILE *out)
{
	fprintf(out,
		"usage: taslab study <subcommand> --db STUDY.db [options]\n\n"
		"  design --stimuli DIR --participants N [--seed S] [--training K] [--catch K] [--break-every N]\n"
		"         randomised within-subject plan from the pairs.json sets in DIR (made by 'taslab pair')\n"
		"  links [--base URL]     participant links (default base http://127.0.0.1:8080)\n"
		"  serve [--port P] [--bind ADDR] [--threads N]   run the study in the browser (default 127.0.0.1:8080);\n"
		"         prints the admin token for /admin/export.csv?token=...; Ctrl-C stops it\n"
		"  tally --out DIR [--keep-flagged] [--bootstrap B] [--seed S]\n"
		"         conditions.csv, anova.csv, posthoc.csv, observers.csv, jod.csv, tables.md, fig3.png\n"
		"  export --out RATINGS.csv [--pwcmp PAIRS.csv]   long-format ratings (and pwcmp layout)\n"
		"  import RATINGS.csv     load a long-format file into a new study (validated; all or nothing)\n");
}

typedef struct opts {
	const char *db, *stimuli, *out, *pwcmp, *base, *bind, *file;
	double participants, seed, training, catch_trials, break_every, port, threads, bootstrap;
	int keep_flagged;
} opts;

static int parse(int argc, char **argv, opts *o, char *err, size_t err_size)
{
	memset(o, 0, sizeof *o);
	o->port = 8080;
	o->seed = 1;
	for (int i = 2; i < argc; i++) {
		const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
		const char **s = !strcmp(a, "--db") ? &o->db : !strcmp(a, "--stimuli") ? &o->stimuli : !strcmp(a, "--out") ? &o->out
				 : !strcmp(a, "--pwcmp") ? &o->pwcmp : !strcmp(a, "--base") ? &o->base : !strcmp(a, "--bind") ? &o->bind : NULL;
		double *d = !strcmp(a, "--participants") ? &o->participants : !strcmp(a, "--seed") ? &o->seed
			    : !strcmp(a, "--training") ? &o->training : !strcmp(a, "--catch") ? &o->catch_trials
			    : !strcmp(a, "--break-every") ? &o->break_every : !strcmp(a, "--port") ? &o->port
			    : !strcmp(a, "--threads") ? &o->threads : !strcmp(a, "--bootstrap") ? &o->bootstrap : NULL;
		if (!strcmp(a, "--keep-flagged")) {
			o->keep_flagged = 1;
		} else if (s && v) {
			*s = v;
			i++;
		} else if (d && v) {
			if (cli_parse_float(v, a, 0, 4294967295.0, d, err, err_size))
				return -1;
			i++;
		} else if (a[0] != '-' && !o->file) {
			o->file = a;
		} else {
			snprintf(err, err_size, "unexpected argument '%s' (see 'taslab study --help')", a);
			return -1;
		}
	}
	if (!o->db) {
		snprintf(err, err_size, "--db STUDY.db is required");
		return -1;
	}
	return 0;
}

static volatile sig_atomic_t stop_flag;
static void on_signal(int sig) { (void)sig; stop_flag = 1; }

static int study_run(int argc, char **argv)
{
	char err[1024];
	opts o;
	if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
		study_usage(argc < 2 ? stderr : stdout);
		return argc < 2 ? CLI_EXIT_USAGE : CLI_EXIT_OK;
	}
	const char *sub = argv[1];
	static const char *const subs[] = {"design", "links", "serve", "tally", "export", "import", NULL};
	int known = 0;
	for (const char *const *s = subs; *s; s++)
		known |= !strcmp(*s, sub);
	if (!known) {
		fprintf(stderr, "taslab study: unknown subcommand '%s' (see 'taslab study --help')\n", sub);
		return CLI_EXIT_USAGE;
	}
	if (parse(argc, argv, &o, err, sizeof err)) {
		fprintf(stderr, "taslab study %s: %s\n", sub, err);
		return CLI_EXIT_USAGE;
	}
	int create = !strcmp(sub, "design") || !strcmp(sub, "import");
	if (!strcmp(sub, "design") && (!o.stimuli || o.participants < 1)) {
		fprintf(stderr, "taslab study design: --stimuli DIR and --participants N are required\n");
		return CLI_EXIT_USAGE;
	}
	if ((!strcmp(sub, "tally") || !strcmp(sub, "export")) && !o.out) {
		fprintf(stderr, "taslab study %s: --out is required\n", sub);
		return CLI_EXIT_USAGE;
	}
	if (!strcmp(sub, "import") && !o.file) {
		fprintf(stderr, "taslab study import: give the ratings CSV file\n");
		return CLI_EXIT_USAGE;
	}
	sty *s = NULL;
	if (sty_open(o.db, create, &s, err, sizeof err)) {
		fprintf(stderr, "taslab study %s: %s\n", sub, err);
		return CLI_EXIT_USAGE;
	}
	int status = CLI_EXIT_OK;
	if (!strcmp(sub, "design")) {
		sty_design_desc d = {.stimuli = o.stimuli, .participants = (uint32_t)o.participants, .seed = (uint64_t)o.seed,
				     .training = (uint32_t)o.training, .catch_trials = (uint32_t)o.catch_trials,
				     .break_every = (uint32_t)o.break_every};
		sty_design_summary sm;
		if (sty_design(s, &d, &sm, err, sizeof err)) {
			fprintf(stderr, "taslab study design: %s\n", err);
			status = CLI_EXIT_USAGE;
		} else {
			printf("study %s: %u conditions from %u set(s), %u participants, %u trials each, %u break(s); "
			       "estimated session %.1f min\nlinks: taslab study links --db %s; run: taslab study serve --db %s\n",
			       o.db, sm.conditions, sm.sets, sm.participants, sm.trials_per_participant, sm.breaks, sm.session_minutes,
			       o.db, o.db);
		}
	} else if (!strcmp(sub, "links")) {
		char **codes;
		size_t n;
		if (sty_participant_codes(s, &codes, &n, err, sizeof err)) {
			fprintf(stderr, "taslab study links: %s\n", err);
			status = CLI_EXIT_FAILURE;
		} else {
			for (size_t i = 0; i < n; i++) {
				printf("P%03zu %s/p/%s\n", i + 1, o.base ? o.base : "http://127.0.0.1:8080", codes[i]);
				free(codes[i]);
			}
			free(codes);
		}
	} else if (!strcmp(sub, "serve")) {
		sty_server *sv = NULL;
		if (o.port > 65535 || sty_server_start(s, o.bind, (uint16_t)o.port, (unsigned)o.threads, &sv, err, sizeof err)) {
			fprintf(stderr, "taslab study serve: %s\n", o.port > 65535 ? "--port must be 0..65535" : err);
			status = CLI_EXIT_USAGE;
		} else {
			printf("listening on http://%s:%u\nadmin token %s (/admin/export.csv?token=...)\n", o.bind ? o.bind : "127.0.0.1",
			       sty_server_port(sv), sty_admin_token(s));
			fflush(stdout);
			struct sigaction sa = {.sa_handler = on_signal};
			sigaction(SIGINT, &sa, NULL);
			sigaction(SIGTERM, &sa, NULL);
			while (!stop_flag)
				pause();
			sty_server_stop(&sv);
			fprintf(stderr, "taslab study serve: stopped\n");
		}
	} else if (!strcmp(sub, "tally")) {
		sty_tally_desc t = {.out = o.out, .keep_flagged = o.keep_flagged, .bootstrap = (uint32_t)o.bootstrap,
				    .seed = (uint64_t)o.seed};
		if (sty_tally(s, &t, err, sizeof err)) {
			fprintf(stderr, "taslab study tally: %s\n", err);
			status = CLI_EXIT_FAILURE;
		} else {
			fprintf(stderr, "taslab: study statistics in %s (conditions.csv, anova.csv, posthoc.csv, observers.csv, "
					"jod.csv, tables.md, fig3.png)\n", o.out);
		}
	} else if (!strcmp(sub, "export")) {
		if (sty_export_long(s, o.out, err, sizeof err) || (o.pwcmp && sty_export_pwcmp(s, o.pwcmp, err, sizeof err))) {
			fprintf(stderr, "taslab study export: %s\n", err);
			status = CLI_EXIT_FAILURE;
		}
	} else {
		size_t rows;
		if (sty_import_long(s, o.file, &rows, err, sizeof err)) {
			fprintf(stderr, "taslab study import: %s\n", err);
			status = CLI_EXIT_USAGE;
		} else {
			fprintf(stderr, "taslab: imported %zu ratings into %s\n", rows, o.db);
		}
	}
	sty_close(&s);
	return status;
}

const cli_command cli_cmd_study = {"study", "pairwise-comparison studies: design, serve, tally, export/import", study_run,
				   study_usage};
