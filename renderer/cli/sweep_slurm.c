#define _XOPEN_SOURCE 700 /* realpath */
/* sweep_slurm.c — `taslab sweep --slurm`: the incomplete runs of a sweep as a Slurm job array (one task per run:
 * render + clip + metrics, `taslab sweep SWEEP/sweep.json --task $SLURM_ARRAY_TASK_ID`) and a report job that
 * depends on the array (afterany: it also runs when some tasks failed, and reports them). Both read and write the
 * same run folders as a local sweep, so a sweep can start on one and finish on the other (DESIGN section 9).
 * Assumes a file system shared by the submitting host and the nodes, at the same paths. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "sweep_cli.h"
#include "taslab/tl_fs.h"

#define MAX_ARGS 64

/* --slurm-opts "…" split into words: whitespace separates, '…' and "…" quote (no escapes). */
static int split_words(const char *s, char *buf, size_t buf_size, char **words, size_t *n, char *err, size_t err_size)
{
	size_t k = 0, o = 0;
	*n = 0;
	while (*s) {
		while (*s == ' ' || *s == '\t' || *s == '\n')
			s++;
		if (!*s)
			break;
		if (*n == MAX_ARGS - 8)
			return tl_error(err, err_size, TL_ERR_ARG, "--slurm-opts: too many words");
		words[(*n)++] = buf + o;
		while (*s && *s != ' ' && *s != '\t' && *s != '\n') {
			if (*s == '\'' || *s == '"') {
				char q = *s++;
				while (*s && *s != q && o + 1 < buf_size)
					buf[o++] = *s++;
				if (*s != q)
					return tl_error(err, err_size, TL_ERR_ARG, "--slurm-opts: unbalanced %c", q);
				s++;
			} else if (o + 1 < buf_size) {
				buf[o++] = *s++;
			} else {
				return tl_error(err, err_size, TL_ERR_ARG, "--slurm-opts: too long");
			}
		}
		if (o >= buf_size) /* an empty quoted word ('') right at the end of a full buffer */
			return tl_error(err, err_size, TL_ERR_ARG, "--slurm-opts: too long");
		buf[o++] = 0;
		k++;
	}
	(void)k;
	return TL_OK;
}

/* Shell single-quoting for the batch scripts and the dry run's sbatch command lines: inside '…' the shell expands
 * nothing, and a ' is written as '\''. Words of only safe characters are written as they are. */
static void sq(FILE *f, const char *s)
{
	if (*s && strspn(s, "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-+=.,:/@%") == strlen(s)) {
		fputs(s, f);
		return;
	}
	fputc('\'', f);
	for (; *s; s++)
		if (*s == '\'')
			fputs("'\\''", f);
		else
			fputc(*s, f);
	fputc('\'', f);
}

/* A path that will be written into a batch script or a #SBATCH-style option: control characters are refused (issue
 * 31.2: a newline in the sweep folder's path, written into `#SBATCH --output=…`, ran the rest of the line as a command
 * when the script was run). */
static int script_path_ok(const char *what, const char *path, char *err, size_t err_size)
{
	for (const unsigned char *p = (const unsigned char *)path; *p; p++)
		if (*p < 0x20 || *p == 0x7f)
			return tl_error(err, err_size, TL_ERR_ARG,
					"%s holds a control character (0x%02x at byte %zu): it would be written into the Slurm "
					"batch scripts; use a path without one",
					what, *p, (size_t)(p - (const unsigned char *)path));
		else if (*p == '\\') /* sbatch --output: a backslash turns the %a pattern off, every task one log */
			return tl_error(err, err_size, TL_ERR_ARG,
					"%s holds a backslash (byte %zu): Slurm's --output would then not expand the task's "
					"number, so every task would write one log; use a path without one",
					what, (size_t)(p - (const unsigned char *)path));
	return TL_OK;
}

int cli_sweep_slurm_check(const char *dir, char *err, size_t err_size)
{
	char self[TL_PATH_MAX], cwd[TL_PATH_MAX];
	int rc = script_path_ok("the sweep folder's path", dir, err, err_size);
	if (!rc && dir[0] != '/' && getcwd(cwd, sizeof cwd))
		rc = script_path_ok("the current folder's path (the sweep folder is relative to it)", cwd, err, err_size);
	if (!rc)
		rc = cli_sweep_self(self, sizeof self, err, err_size);
	if (!rc)
		rc = script_path_ok("the taslab binary's path", self, err, err_size);
	return rc;
}

/* sbatch's --output pattern for `path`: a '%' of the path is written "%%" (Slurm's filename pattern). */
static void output_opt(char *out, size_t n, const char *dir, const char *file)
{
	size_t len = (size_t)snprintf(out, n, "--output=");
	for (const char *p = dir; *p && len + 3 < n; p++) {
		if (*p == '%')
			out[len++] = '%';
		out[len++] = *p;
	}
	snprintf(out + len, n - len, "/slurm/logs/%s", file);
}

/* Runs argv, returns its exit status; stdout into out (first line). */
static int run_capture(char **argv, char *out, size_t n, char *err, size_t err_size)
{
	int pfd[2];
	if (pipe(pfd))
		return tl_error(err, err_size, TL_ERR_OUTPUT, "pipe: %s", strerror(errno));
	pid_t pid = fork();
	if (pid < 0)
		return tl_error(err, err_size, TL_ERR_OUTPUT, "fork: %s", strerror(errno));
	if (pid == 0) {
		dup2(pfd[1], 1);
		close(pfd[0]);
		close(pfd[1]);
		execvp(argv[0], argv);
		_exit(127);
	}
	close(pfd[1]);
	size_t len = 0;
	ssize_t got;
	while ((got = read(pfd[0], out + len, n - 1 - len)) > 0 && len + (size_t)got < n - 1)
		len += (size_t)got;
	if (got > 0)
		len += (size_t)got;
	out[len] = 0;
	close(pfd[0]);
	int status;
	waitpid(pid, &status, 0);
	char *nl = strchr(out, '\n');
	if (nl)
		*nl = 0;
	if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
		return tl_error(err, err_size, TL_ERR_UNSUPPORTED, "%s not found: is Slurm installed here (sbatch on PATH)?",
				argv[0]);
	if (!WIFEXITED(status) || WEXITSTATUS(status))
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s failed (exit %d): %s", argv[0],
				WIFEXITED(status) ? WEXITSTATUS(status) : -1, out);
	return TL_OK;
}

static int write_script(const char *path, const char *kind, const char *self, const char *dir, const char *body_arg,
			char *err, size_t err_size)
{
	tl_atomic a;
	int rc = tl_atomic_open(&a, path, err, err_size);
	if (rc)
		return rc;
	FILE *f = a.f;
	(void)dir;
	/* No path in a comment or #SBATCH line (the log files' --output is an sbatch argument): every path in the script
	 * is a single-quoted shell word. */
	fprintf(f, "#!/bin/bash\n# taslab sweep: %s (written by 'taslab sweep --slurm'; DESIGN section 9)\n", kind);
	if (!strcmp(kind, "runs")) {
		fprintf(f, "#SBATCH --job-name=taslab-sweep\n");
		fprintf(f, "# one array task per run: render + clip + metrics of run $SLURM_ARRAY_TASK_ID of the plan\n");
		fprintf(f, "exec ");
		sq(f, self);
		fprintf(f, " sweep ");
		sq(f, body_arg);
		fprintf(f, " --task \"$SLURM_ARRAY_TASK_ID\"\n");
	} else {
		fprintf(f, "#SBATCH --job-name=taslab-report\n");
		fprintf(f, "# after the runs (afterany): missing comparisons, summary.csv, table1.md, report/index.html\n");
		fprintf(f, "exec ");
		sq(f, self);
		fprintf(f, " report ");
		sq(f, body_arg);
		fputc('\n', f);
	}
	return tl_atomic_commit(&a, err, err_size);
}

int cli_sweep_slurm(const sweep_spec *s, const char *dir, const char *slurm_opts, bool dry_run, char *err,
		    size_t err_size)
{
	char self[TL_PATH_MAX], adir[TL_PATH_MAX], path[TL_PATH_MAX], runs_sh[TL_PATH_MAX], report_sh[TL_PATH_MAX];
	int rc = cli_sweep_slurm_check(dir, err, err_size);
	if (!rc)
		rc = cli_sweep_self(self, sizeof self, err, err_size);
	if (rc)
		return rc;
	char *abs = realpath(dir, NULL);
	if (!abs)
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: %s", dir, strerror(errno));
	snprintf(adir, sizeof adir, "%s", abs);
	free(abs);
	if ((rc = script_path_ok("the sweep folder's path", adir, err, err_size)))
		return rc;
	char run_out[TL_PATH_MAX + 64], report_out[TL_PATH_MAX + 64];
	output_opt(run_out, sizeof run_out, adir, "run-%A_%a.out");
	output_opt(report_out, sizeof report_out, adir, "report-%j.out");
	/* the array: incomplete runs only (a sweep started locally finishes on the cluster) */
	size_t n = sweep_run_count(s), todo = 0;
	size_t cap = 16 * n + 64;
	char *array = calloc(cap, 1);
	if (!array)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	size_t len = 0;
	/* (damaged runs, listed by the sweep, are left out: --redo-damaged has dropped their manifests when asked) */
	char *todo_run = calloc(n + 1, 1);
	if (!todo_run) {
		free(array);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	for (size_t i = 0; i < n; i++) {
		sweep_run r;
		sweep_status st;
		char why[16];
		sweep_run_at(s, i, &r);
		sweep_run_status_checked(s, dir, &r, &st, why, sizeof why);
		todo_run[i] = !st.damaged && !(st.run && st.clip && st.metrics);
	}
	for (size_t i = 0; i < n;) {
		if (!todo_run[i]) {
			i++;
			continue;
		}
		size_t j = i + 1; /* a range of consecutive incomplete runs */
		while (j < n && todo_run[j])
			j++;
		len += (size_t)snprintf(array + len, cap - len, j - i > 1 ? "%s%zu-%zu" : "%s%zu", len ? "," : "", i, j - 1);
		todo += j - i;
		i = j;
	}
	free(todo_run);
	char words_buf[4096];
	char *words[MAX_ARGS];
	size_t nw = 0;
	rc = slurm_opts ? split_words(slurm_opts, words_buf, sizeof words_buf, words, &nw, err, err_size) : TL_OK;
	snprintf(path, sizeof path, "%s/slurm/logs", adir);
	if (!rc)
		rc = tl_mkdirs(path, err, err_size);
	snprintf(runs_sh, sizeof runs_sh, "%s/slurm/runs.sh", adir);
	snprintf(report_sh, sizeof report_sh, "%s/slurm/report.sh", adir);
	char spec[TL_PATH_MAX];
	snprintf(spec, sizeof spec, "%s/sweep.json", adir);
	if (!rc)
		rc = write_script(runs_sh, "runs", self, adir, spec, err, err_size);
	if (!rc)
		rc = write_script(report_sh, "report", self, adir, adir, err, err_size);
	if (rc) {
		free(array);
		return rc;
	}
	char array_opt[64 + 16 * 64];
	snprintf(array_opt, sizeof array_opt, "--array=%s", array);
	if (strlen(array) > 16 * 64) /* very fragmented: one range over everything, complete runs return at once */
		snprintf(array_opt, sizeof array_opt, "--array=0-%zu", n - 1);
	char *argv[MAX_ARGS + 8];
	size_t a = 0;
	argv[a++] = "sbatch";
	argv[a++] = "--parsable";
	argv[a++] = array_opt;
	argv[a++] = run_out;
	for (size_t k = 0; k < nw; k++)
		argv[a++] = words[k];
	argv[a++] = runs_sh;
	argv[a] = NULL;
	if (dry_run) {
		for (int which = 0; which < 2; which++) {
			char *text = NULL;
			size_t tl;
			if (tl_read_file(which ? report_sh : runs_sh, 1u << 20, &text, &tl, err, err_size) == 0) {
				printf("# ---- %s\n%s", which ? report_sh : runs_sh, text);
				free(text);
			}
		}
		/* shell-quoted, so the lines can be pasted into a shell as they are (issue 31.9) */
		printf("# ---- submission (%zu of %zu runs)\n", todo, n);
		if (todo)
			for (size_t k = 0; k < a; k++) {
				fputs(k ? " " : "", stdout);
				sq(stdout, argv[k]);
			}
		else
			printf("# nothing to render: every run is complete");
		printf("\nsbatch --parsable%s ", todo ? " --dependency=afterany:\"$JOBID\"" : "");
		sq(stdout, report_out);
		for (size_t k = 0; k < nw; k++) {
			fputc(' ', stdout);
			sq(stdout, words[k]);
		}
		fputc(' ', stdout);
		sq(stdout, report_sh);
		fputc('\n', stdout);
		free(array);
		return TL_OK;
	}
	char out[1024], jobid[64], dep[128];
	if (todo) {
		if ((rc = run_capture(argv, out, sizeof out, err, err_size))) {
			free(array);
			return rc;
		}
		snprintf(jobid, sizeof jobid, "%.*s", (int)strcspn(out, ";"), out); /* "ID" or "ID;cluster" */
		/* the id goes into the report job's --dependency: digits only (issue 31.9) */
		if (!jobid[0] || strspn(jobid, "0123456789") != strlen(jobid) || strcspn(out, ";") >= sizeof jobid) {
			char shown[80];
			size_t k = 0;
			for (; out[k] && k < sizeof shown - 1 && k < 60; k++)
				shown[k] = (unsigned char)out[k] < 0x20 || out[k] == 0x7f ? '?' : out[k];
			shown[k] = 0;
			free(array);
			return tl_error(err, err_size, TL_ERR_OUTPUT,
					"sbatch printed '%s', not a job id (digits, with --parsable): the array may be submitted; "
					"check squeue before submitting again",
					shown);
		}
		fprintf(stderr, "taslab sweep: submitted %zu run(s) as Slurm job array %s\n", todo, jobid);
	}
	a = 0;
	argv[a++] = "sbatch";
	argv[a++] = "--parsable";
	if (todo) {
		snprintf(dep, sizeof dep, "--dependency=afterany:%s", jobid);
		argv[a++] = dep;
	}
	argv[a++] = report_out;
	for (size_t k = 0; k < nw; k++)
		argv[a++] = words[k];
	argv[a++] = report_sh;
	argv[a] = NULL;
	free(array);
	if ((rc = run_capture(argv, out, sizeof out, err, err_size)))
		return rc;
	fprintf(stderr, "taslab sweep: report job %.*s; when it is done: %s/report/index.html (logs: %s/slurm/logs/)\n",
		(int)strcspn(out, ";"), out, adir, adir);
	printf("%s/report/index.html\n", adir);
	return TL_OK;
}
