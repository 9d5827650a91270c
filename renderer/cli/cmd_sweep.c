/* cmd_sweep.c — `taslab sweep` and `taslab report`: a threshold sweep rendered, scored and reported in one command,
 * on one machine (--jobs N) or a Slurm cluster (--slurm) (DESIGN section 9).
 *
 *   request (sweep file and/or options) --resolve--> spec --check against SWEEP/sweep.json--> plan
 *     --> runs (render + clip + metrics, one process each) --> summary.csv, table1.md, report/index.html
 *
 * Everything that can be wrong with the input (unknown scene, camera, variant or key, a missing ref, a folder that
 * holds another sweep) is found before anything is written: one line, exit 2, nothing rendered. */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sweep_cli.h"
#include "taslab/metrics.h"
#include "taslab/metrics_sweep.h"
#include "taslab/study_report.h"
#include "taslab/sweep_keys.h"
#include "taslab/tl_clock.h"
#include "taslab/tl_fs.h"

/* ------------------------------------------------------------------ the closing step */

/* The mono sweep of `taslab report --mono`: its spec and rows (malloc'ed). */
static int mono_rows(const sweep_spec *s, const char *mono_dir, sweep_spec **ms, mtr_sweep_row **rows, size_t *count,
		     char *err, size_t err_size)
{
	char path[TL_PATH_MAX + 32];
	if (!s->stereo)
		return tl_error(err, err_size, TL_ERR_ARG, "--mono: this sweep is not stereo (made without --stereo)");
	snprintf(path, sizeof path, "%s/sweep.json", mono_dir);
	if (!(*ms = calloc(1, sizeof **ms)))
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	int rc = tl_is_file(path) ? sweep_spec_read(path, *ms, err, err_size)
				  : tl_error(err, err_size, TL_ERR_ARG, "--mono %s is not a sweep folder (no sweep.json)", mono_dir);
	if (!rc && (*ms)->stereo)
		rc = tl_error(err, err_size, TL_ERR_ARG, "--mono %s is a stereo sweep: give a mono one", mono_dir);
	if (!rc && strcmp((*ms)->build_digest, s->build_digest))
		fprintf(stderr, "taslab report: note: --mono %s was made by another taslab build (build digest %s, this "
				"sweep's %s): its speedups are another build's\n",
			mono_dir, (*ms)->build_digest[0] ? (*ms)->build_digest : "none",
			s->build_digest[0] ? s->build_digest : "none");
	if (!rc)
		rc = mtr_sweep_collect(*ms, mono_dir, rows, count, err, err_size);
	return rc;
}

int cli_sweep_finish(const sweep_spec *s, const char *dir, const char *study, const char *model, const char *jnd_metric,
		     const char *mono_dir, bool report,
		     bool quiet, size_t *incomplete, char *report_path, size_t report_path_size, char *err, size_t err_size)
{
	size_t n = sweep_run_count(s);
	int rc = TL_OK;
	report_path[0] = 0;
	/* Comparisons (and clips) still missing for complete runs: a Slurm task whose ref run was not done yet, or a
	 * sweep interrupted between its steps. No device is needed for either. Only by the sweep's own build: another
	 * build's clips and metrics would sit beside the sweep's with nothing to tell them apart (the report itself only
	 * reads, so any build may write it). */
	char why0[1024];
	bool same_build = sweep_build_check(s, dir, why0, sizeof why0) == TL_OK;
	if (!same_build)
		fprintf(stderr, "taslab: note: missing clips and comparisons are not made: %s\n", why0);
	for (size_t i = 0; same_build && i < n && !rc; i++) {
		sweep_run r, ref;
		sweep_status st, ref_st;
		sweep_run_at(s, i, &r);
		char why[1024];
		sweep_run_status_checked(s, dir, &r, &st, why, sizeof why); /* damaged runs: reported before, not read */
		sweep_run_at(s, r.ref_index, &ref);
		if (!st.run || (st.clip && st.metrics))
			continue;
		sweep_run_status_checked(s, dir, &ref, &ref_st, why, sizeof why);
		if (!ref_st.run)
			continue;
		bool deferred;
		int trc = cli_sweep_task(s, dir, i, -1, "taslab report", &deferred, why, sizeof why);
		if (trc)
			fprintf(stderr, "taslab: run %zu: %s\n", i, why);
	}
	mtr_sweep_row *rows = NULL, *mrows = NULL;
	sweep_spec *ms = NULL;
	size_t count = 0, mcount = 0;
	if (mono_dir && (rc = mono_rows(s, mono_dir, &ms, &mrows, &mcount, err, err_size))) {
		free(ms);
		return rc;
	}
	if ((rc = mtr_sweep_collect(s, dir, &rows, &count, err, err_size))) {
		free(ms);
		free(mrows);
		return rc;
	}
	*incomplete = 0;
	for (size_t i = 0; i < count; i++)
		*incomplete += !(rows[i].status.run && rows[i].status.clip && rows[i].status.metrics);
	rc = mtr_sweep_write(s, dir, rows, count, err, err_size);
	if (!rc && report) {
		double t0 = tl_clock_s();
		sty_report_desc rd = {.dir = dir, .spec = s, .rows = rows, .count = count, .study = study, .model = model,
				      .jnd_metric = jnd_metric, .mono_dir = mono_dir, .mono_spec = ms, .mono_rows = mrows,
				      .mono_count = mcount};
		rc = sty_report_write(&rd, report_path, report_path_size, err, err_size);
		if (!rc && !quiet)
			fprintf(stderr, "taslab: report written in %.1f s\n", tl_clock_s() - t0);
	}
	free(rows);
	free(mrows);
	free(ms);
	return rc;
}

/* ------------------------------------------------------------------ sweep */

/* The options of the sweep alone; the settings (--scenes ... --jobs) are the sweep key table's, each also a key of the
 * sweep file (output/sweep_keys.h, cli_sweep_key_options). */
static const cli_opt sweep_options[] = {
	{.name = "slurm", .arg = NULL,
	 .help = "submit the incomplete runs as a Slurm job array (one task per run) and a dependent report job",
	 .type = CLI_FLAG, .offset = offsetof(sweep_opts, slurm)},
	{.name = "slurm-opts", .arg = "\"OPTS\"",
	 .help = "options passed to both sbatch calls (e.g. \"--partition=gpu --time=2:00:00\")",
	 .type = CLI_STRING, .offset = offsetof(sweep_opts, slurm_opts)},
	{.name = "slurm-dry-run", .arg = NULL,
	 .help = "print the batch scripts and sbatch commands instead of submitting",
	 .type = CLI_FLAG, .offset = offsetof(sweep_opts, slurm_dry_run)},
	{.name = "task", .arg = "I",
	 .help = "run only entry I of the plan (what each Slurm array task and local job runs)",
	 .type = CLI_STRING, .offset = offsetof(sweep_opts, task)},
	{.name = "redo-damaged", .arg = NULL,
	 .help = "render again the runs whose frames no longer match their manifest (missing, extra or mixed-size frames; "
		 "listed by every sweep), dropping their clips and metrics and the comparisons against a redone ref",
	 .type = CLI_FLAG, .offset = offsetof(sweep_opts, redo_damaged)},
	{.name = "no-report", .arg = NULL,
	 .help = "skip report/index.html (summary.csv and table1.md are still written)",
	 .type = CLI_FLAG, .offset = offsetof(sweep_opts, no_report)},
	{.name = "quiet", .arg = NULL,
	 .help = "no progress output",
	 .type = CLI_FLAG, .offset = offsetof(sweep_opts, quiet)},
	{0},
};

static const cli_opt *sweep_dynamic(void) { return cli_sweep_key_options(); }

static int sweep_validate(void *opts, cli_ctx *ctx)
{
	sweep_opts *o = opts;
	if (o->task) {
		uint64_t t;
		if (cli_parse_uint(o->task, "--task", 0, 1u << 30, &t, ctx->err, sizeof ctx->err))
			return TL_ERR_ARG;
		if (!ctx->npos)
			return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--task needs the sweep's SWEEP/sweep.json");
	}
	if ((o->slurm || o->slurm_dry_run) && o->task)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--slurm and --task exclude each other");
	if (o->slurm_opts && !o->slurm && !o->slurm_dry_run)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--slurm-opts goes with --slurm or --slurm-dry-run");
	if (!ctx->npos && !cli_sweep_opt_given(o, "scenes"))
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG,
				"give a sweep file or --scenes, --variants and --out (see 'taslab sweep --help')");
	return TL_OK;
}

/* A folder that exists, holds something and is not a sweep: refused, a sweep never mixes into other files. */
static bool foreign_folder(const char *dir)
{
	DIR *d = opendir(dir);
	if (!d)
		return false;
	struct dirent *e;
	bool other = false;
	while ((e = readdir(d)))
		if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..") && strcmp(e->d_name, ".taslab-lock"))
			other = true;
	closedir(d);
	return other;
}

/* Damaged runs (issue 31.8): a run with a manifest whose frames no longer match it (or the spec) is reported here,
 * once per sweep, and either rendered again (--redo-damaged: its manifest, clip and metrics go, and so do the
 * comparisons made against it when it is a ref run) or left out of every later step (counted as failed). */
static size_t damaged_runs(const sweep_spec *s, const char *dir, bool redo, char *err, size_t err_size)
{
	size_t n = sweep_run_count(s), damaged = 0;
	for (size_t i = 0; i < n; i++) {
		sweep_run r;
		sweep_status st;
		char why[1024], p[TL_PATH_MAX + 32];
		sweep_run_at(s, i, &r);
		sweep_run_status_checked(s, dir, &r, &st, why, sizeof why);
		if (!st.damaged)
			continue;
		damaged++;
		fprintf(stderr, "taslab sweep: %s/%s/%s is damaged: %s%s\n", s->scenes[r.scene].name,
			s->scenes[r.scene].cameras[r.camera].name, s->variants[r.variant].id, why,
			redo ? "; rendering it again" : " (--redo-damaged renders it again)");
		if (!redo)
			continue;
		for (size_t k = 0; k < n; k++) {
			sweep_run o;
			sweep_run_at(s, k, &o);
			if (k != i && !(r.is_ref && o.ref_index == i))
				continue;
			sweep_run_path(s, dir, &o, SWEEP_PATH_METRICS, p, sizeof p);
			strncat(p, "/summary.json", sizeof p - strlen(p) - 1);
			unlink(p);
		}
		sweep_run_path(s, dir, &r, SWEEP_PATH_CLIP, p, sizeof p);
		unlink(p);
		sweep_run_path(s, dir, &r, SWEEP_PATH_RUN, p, sizeof p);
		strncat(p, "/manifest.json", sizeof p - strlen(p) - 1);
		if (unlink(p) && errno != ENOENT)
			fprintf(stderr, "taslab sweep: %s: %s\n", p, strerror(errno));
	}
	(void)err, (void)err_size;
	return redo ? 0 : damaged;
}

/* Takes DIR/.taslab-lock (flock, exclusive, without waiting). TL_ERR_CONFLICT when another sweep holds it. */
static int lock_folder(const char *dir, int *fd, char *err, size_t err_size)
{
	char p[TL_PATH_MAX + 32];
	snprintf(p, sizeof p, "%s/.taslab-lock", dir);
	int rc = cli_sweep_flock(p, fd, err, err_size);
	if (rc == TL_ERR_CONFLICT)
		return tl_error(err, err_size, TL_ERR_CONFLICT,
				"%s is in use by another 'taslab sweep' (it holds %s): wait for it to finish, or stop it "
				"and run this again to resume",
				dir, p);
	return rc;
}

static int sweep_main(void *opts, cli_ctx *ctx)
{
	sweep_opts *o = opts;
	char *err = ctx->err;
	size_t err_size = sizeof ctx->err;
	sweep_request *req = calloc(1, sizeof *req);
	sweep_spec *spec = calloc(1, sizeof *spec), *old = calloc(1, sizeof *old);
	char dir[TL_PATH_MAX], path[TL_PATH_MAX + 32], what[512];
	int rc = req && spec && old ? TL_OK : tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	const char *file = ctx->npos ? ctx->pos[0] : NULL;
	bool resolved = false;
	int lock_fd = -1;
	if (!rc && file) {
		/* SWEEP/sweep.json (resolved): resume that sweep, in its folder */
		if (sweep_spec_read(file, spec, what, sizeof what) == 0) {
			resolved = true;
			const char *slash = strrchr(file, '/');
			snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - file) : 1, slash ? file : ".");
			if (cli_sweep_opts_change_spec(o)) /* options that change what is swept, or --out */
				rc = tl_error(err, err_size, TL_ERR_ARG,
					      "%s is a resolved sweep: options that change it cannot be added (write a sweep file)",
					      file);
			/* resumed (or one --task of it) by the build that started it: another build's runs are not mixed in */
			if (!rc)
				rc = sweep_build_check(spec, file, err, err_size);
		} else if (sweep_file_is_spec(file)) {
			/* a resolved sweep.json that does not read: its own reason, not the request reader's (issue 31.5) */
			rc = tl_error(err, err_size, TL_ERR_INPUT, "%s", what);
		} else {
			rc = sweep_request_read(file, req, err, err_size);
		}
	}
	if (!rc && o->task) { /* one run of the plan, in this process */
		if (!resolved)
			rc = tl_error(err, err_size, TL_ERR_ARG, "--task needs a resolved SWEEP/sweep.json, not %s", file);
		uint64_t t = 0;
		if (!rc)
			rc = cli_parse_uint(o->task, "--task", 0, sweep_run_count(spec) - 1, &t, err, err_size);
		const char *fd_env = getenv("TASLAB_SWEEP_PROGRESS_FD");
		bool deferred;
		if (!rc)
			rc = cli_sweep_task(spec, dir, (size_t)t, fd_env ? atoi(fd_env) : -1, ctx->command_line, &deferred, err,
					    err_size);
		goto done;
	}
	if (!rc) /* the settings given (resuming: only --jobs, checked above) */
		rc = cli_sweep_request_from_opts(o, req, err, err_size);
	if (!rc && !resolved) {
		if (!req->out[0])
			rc = tl_error(err, err_size, TL_ERR_ARG, "--out SWEEP is required (or \"out\" in the sweep file)");
		if (!rc)
			rc = cli_sweep_resolve(req, spec, err, err_size);
		snprintf(dir, sizeof dir, "%s", req->out);
	}
	if (rc)
		goto done;
	/* The folder: new, empty, or holding this very sweep. */
	snprintf(path, sizeof path, "%s/sweep.json", dir);
	struct stat sb;
	if (stat(dir, &sb) == 0 && !S_ISDIR(sb.st_mode)) { /* a file, /dev/null, a FIFO: bad input (issue 31.9) */
		rc = tl_error(err, err_size, TL_ERR_ARG, "--out %s exists and is not a folder (give a folder)", dir);
	} else if ((o->slurm || o->slurm_dry_run) && (rc = cli_sweep_slurm_check(dir, err, err_size))) {
		/* paths written into the batch scripts: checked before the folder is touched (issue 31.2) */
	} else if (tl_is_file(path)) {
		if ((rc = sweep_spec_read(path, old, err, err_size)))
			goto done;
		if (sweep_spec_compare(old, spec, what, sizeof what))
			rc = tl_error(err, err_size, TL_ERR_ARG,
				      "%s holds a different sweep (%s): use another --out, or 'taslab sweep %s' to resume it", dir,
				      what, path);
	} else if (foreign_folder(dir)) {
		rc = tl_error(err, err_size, TL_ERR_ARG, "%s exists and is not a sweep folder (no sweep.json): use another --out",
			      dir);
	}
	if (rc)
		goto done;
	/* One sweep at a time in a folder: two identical sweeps started together rendered every run twice (issue 31.9).
	 * flock is released when the process ends, however it ends; the run processes (--task) do not take it. Under the
	 * lock, a sweep.json written since the check above is compared again. */
	if ((rc = tl_mkdirs(dir, err, err_size)) || (rc = lock_folder(dir, &lock_fd, err, err_size)))
		goto done;
	if (!tl_is_file(path))
		rc = sweep_spec_write(path, spec, err, err_size);
	else if (!(rc = sweep_spec_read(path, old, err, err_size)) && sweep_spec_compare(old, spec, what, sizeof what))
		rc = tl_error(err, err_size, TL_ERR_ARG, "%s holds a different sweep (%s): use another --out", dir, what);
	if (rc)
		goto done;
	size_t n = sweep_run_count(spec);
	size_t damaged = damaged_runs(spec, dir, o->redo_damaged && !o->slurm_dry_run, err, err_size);
	if (o->slurm || o->slurm_dry_run) {
		rc = cli_sweep_slurm(spec, dir, o->slurm_opts, o->slurm_dry_run, err, err_size);
		goto done;
	}
	unsigned jobs = req->jobs ? req->jobs : 1;
	size_t failed = 0, incomplete = 0;
	double t0 = tl_clock_s();
	rc = cli_sweep_local(spec, dir, jobs, o->quiet, &failed, err, err_size);
	if (rc)
		goto done;
	char report[TL_PATH_MAX];
	if ((rc = cli_sweep_finish(spec, dir, NULL, NULL, NULL, NULL, !o->no_report, o->quiet, &incomplete, report, sizeof report, err,
				   err_size)))
		goto done;
	if (!o->quiet)
		fprintf(stderr, "taslab sweep: %zu of %zu runs complete in %.1f s -> %s/summary.csv, table1.md%s%s\n",
			n - incomplete, n, tl_clock_s() - t0, dir, report[0] ? ", " : "", report);
	printf("%s\n", report[0] ? report : path);
	if (incomplete && damaged)
		rc = tl_error(err, err_size, TL_ERR_INCOMPLETE,
			      "%zu of %zu runs failed or are incomplete, %zu of them damaged (listed above; their logs: %s/logs/): "
			      "run the same command again with --redo-damaged to render them again",
			      incomplete, n, damaged, dir);
	else if (incomplete)
		rc = tl_error(err, err_size, TL_ERR_INCOMPLETE,
			      "%zu of %zu runs failed or are incomplete (their logs: %s/logs/); run the same command again to "
			      "retry them",
			      incomplete, n, dir);
done:
	if (lock_fd >= 0)
		close(lock_fd);
	free(req);
	free(spec);
	free(old);
	return rc;
}

static void sweep_help(FILE *out)
{
	cli_sweep_keys_help(out);
	char keys[512];
	fprintf(out, "\nsweep file (JSON, or TOML when the name ends in .toml; options given on the command line override it):\n"
		     "  {\"scenes\": [\"calm\", \"moderate\"], \"cameras\": \"all\", \"variants\": [\"ref\", \"tfr@8\", \"rrc/4\"],\n"
		     "   \"methods\": [\"tarc\"], \"thresholds\": [4, 16], \"periods\": [4], \"frames\": \"0:300\",\n"
		     "   \"size\": \"960x540\", \"out\": \"sweeps/s1\", \"jobs\": 2}\n");
	cli_print_option(out, 0, "keys:", sweep_key_list(" ", keys, sizeof keys));
	fprintf(out, "  (lists as JSON/TOML lists; paths relative to the file's folder)\n"
		     "\nresume: run the same command again, or 'taslab sweep SWEEP/sweep.json': complete runs (manifest.json)\n"
		     "are kept, the rest is redone. Exit status 0 when every run completed, 1 when some failed.\n");
}

const cli_command cli_cmd_sweep = {
	.name = "sweep",
	.summary = "render, score and report a sweep of scenes x camera paths x variants (the main job)",
	.synopsis = "taslab sweep --scenes LIST --variants LIST --out SWEEP [options]\n"
		    "       taslab sweep SWEEP_FILE.json [options]      (a sweep file, or SWEEP/sweep.json to resume)",
	.description = "For every scene x camera path x variant: renders a run (SWEEP/runs/SCENE/CAMERA/ID/), its clip\n"
		       "(SWEEP/clips/), and its metrics against the ref run of the same scene and path (SWEEP/metrics/);\n"
		       "then SWEEP/summary.csv, SWEEP/table1.md and SWEEP/report/index.html (opens from disk). The\n"
		       "resolved sweep is written to SWEEP/sweep.json first. --jobs N runs N renders at a time; --slurm\n"
		       "submits a job array instead. Prints the report's path on stdout.",
	.options = sweep_options,
	.dynamic_options = sweep_dynamic,
	.opts_size = sizeof(sweep_opts),
	.validate = sweep_validate,
	.max_pos = 1,
	.pos_help = "SWEEP_FILE",
	.run = sweep_main,
	.help_extra = sweep_help,
};

/* ------------------------------------------------------------------ report */

static const cli_opt report_options[] = {
	{.name = "study", .arg = "STUDY.db",
	 .help = "add the study's Q, p_ref and JND per condition (method, T, period, scene, camera) beside the metrics",
	 .type = CLI_STRING, .offset = offsetof(report_opts, study)},
	{.name = "model", .arg = "MODEL.json",
	 .help = "a metric-to-JND model ('taslab study model --out'): its predicted t_jnd with a 95% interval beside "
		 "each measured threshold, and for every series of T of this sweep nobody rated",
	 .type = CLI_STRING, .offset = offsetof(report_opts, model)},
	{.name = "jnd-against", .arg = "COLUMN",
	 .help = "summary.csv column to plot the JND against (default flip_mean; e.g. maxrgb_p99, exceed_T, flicker_mean)",
	 .type = CLI_STRING, .offset = offsetof(report_opts, jnd_metric)},
	{.name = "mono", .arg = "MONO_SWEEP",
	 .help = "a stereo sweep's speedups and shaded samples beside this mono sweep's (same scenes, paths, variants, "
		 "frames, size per eye): SWEEP/stereo_vs_mono.csv and the report's Stereo section",
	 .type = CLI_STRING, .offset = offsetof(report_opts, mono)},
	{.name = "quiet", .arg = NULL,
	 .help = "no progress output",
	 .type = CLI_FLAG, .offset = offsetof(report_opts, quiet)},
	{0},
};

static int report_validate(void *opts, cli_ctx *ctx)
{
	report_opts *o = opts;
	if (o->jnd_metric && !sty_report_metric_known(o->jnd_metric))
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG,
				"--jnd-against: '%s' is not a numeric summary.csv column (e.g. flip_mean, maxrgb_p99, exceed_T)",
				o->jnd_metric);
	struct stat sb;
	if (o->study && stat(o->study, &sb))
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--study %s: %s", o->study, strerror(errno));
	if (o->study && !S_ISREG(sb.st_mode))
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG,
				"--study %s: not a regular file (%s); give the study's database (the --db of 'taslab study')",
				o->study, S_ISDIR(sb.st_mode) ? "a folder" : "a device or pipe");
	return TL_OK;
}

static int report_main(void *opts, cli_ctx *ctx)
{
	report_opts *o = opts;
	const char *dir = ctx->pos[0];
	char path[TL_PATH_MAX + 32], report[TL_PATH_MAX];
	sweep_spec *spec = calloc(1, sizeof *spec);
	if (!spec)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_NOMEM, "out of memory");
	snprintf(path, sizeof path, "%s/sweep.json", dir);
	size_t incomplete = 0;
	int rc = tl_is_file(path) ? sweep_spec_read(path, spec, ctx->err, sizeof ctx->err)
				  : tl_error(ctx->err, sizeof ctx->err, TL_ERR_INPUT, "%s is not a sweep folder (no sweep.json)", dir);
	if (!rc)
		rc = cli_sweep_finish(spec, dir, o->study, o->model, o->jnd_metric, o->mono, true, o->quiet, &incomplete, report, sizeof report,
				      ctx->err, sizeof ctx->err);
	if (!rc) {
		printf("%s\n", report);
		if (incomplete)
			rc = tl_error(ctx->err, sizeof ctx->err, TL_ERR_INCOMPLETE,
				      "report written, but %zu of %zu runs are incomplete (rerun 'taslab sweep %s')", incomplete,
				      sweep_run_count(spec), path);
	}
	free(spec);
	return rc;
}

const cli_command cli_cmd_report = {
	.name = "report",
	.summary = "rebuild a sweep's summary.csv, table1.md and report (optionally with a study's results)",
	.synopsis = "taslab report SWEEP [--study STUDY.db] [--model MODEL.json] [--jnd-against COLUMN] [--mono MONO_SWEEP]",
	.description = "Reads SWEEP/sweep.json, computes comparisons still missing for complete runs, and writes\n"
		       "SWEEP/summary.csv, SWEEP/table1.md and SWEEP/report/index.html. With --study, the study's tally\n"
		       "(Q, p_ref, JND with 95% intervals) is joined per condition and the JND plotted against a metric.\n"
		       "With --model (a saved 'taslab study model'), the predicted t_jnd is shown beside each measured\n"
		       "threshold, and alone for the series of T nobody rated.\n"
		       "Exit status 1 when runs of the sweep are incomplete (the report is written all the same).",
	.options = report_options,
	.opts_size = sizeof(report_opts),
	.validate = report_validate,
	.min_pos = 1,
	.max_pos = 1,
	.pos_help = "SWEEP (a sweep folder)",
	.run = report_main,
};
