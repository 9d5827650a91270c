/* test_sweep_safety.c — `taslab sweep` against hostile paths and concurrent use (issue 31; DESIGN section 9), on
 * lavapipe with validation: the Slurm batch scripts carry paths as quoted shell words only (a folder named with quotes,
 * `$(…)`, spaces and '%' gives scripts that run as they should, which the test checks by running them), paths with
 * control characters are refused before anything is written, the dry run prints sbatch's arguments shell-quoted, a job
 * id that is not digits is refused before the report job is submitted (a fake sbatch on PATH records its calls), one
 * sweep at a time holds a folder, and `--out` naming something that is not a folder is bad input (exit 2). */
#define _GNU_SOURCE
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "test_util.h"

static char out[1 << 16];

#define COMMON "--scenes turntable --cameras orbit --size 48x32 --device lavapipe --validation"

/* `s` as one single-quoted shell word (written here independently of taslab's quoting). */
static const char *q(const char *s)
{
	static char buf[4][4096];
	static int k;
	char *o = buf[k++ % 4];
	size_t n = 0;
	o[n++] = '\'';
	for (; *s && n + 5 < sizeof buf[0]; s++) {
		if (*s == '\'') {
			memcpy(o + n, "'\\''", 4);
			n += 4;
		} else {
			o[n++] = *s;
		}
	}
	o[n++] = '\'';
	o[n] = 0;
	return o;
}

static int sh(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static int sh(const char *fmt, ...)
{
	char cmd[16384];
	va_list ap;
	va_start(ap, fmt);
	/* for every taslab of the line, the batch scripts' too (tu_run sets it for the first command only) */
	int n = snprintf(cmd, sizeof cmd, "export ASAN_OPTIONS=detect_leaks=0:quarantine_size_mb=8; ");
	vsnprintf(cmd + n, sizeof cmd - (size_t)n, fmt, ap);
	va_end(ap);
	return tu_run(cmd, out, sizeof out);
}

static void write_text(const char *path, const char *text, int mode)
{
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	fputs(text, f);
	fclose(f);
	chmod(path, (mode_t)mode);
}

/* A fake sbatch: appends its arguments (one per line, then "--") to $FAKE_SBATCH_LOG and prints $FAKE_SBATCH_REPLY. */
static void fake_sbatch(const char *dir, char *bin, size_t n)
{
	snprintf(bin, n, "%s/bin", dir);
	mkdir(bin, 0755);
	char p[4096];
	snprintf(p, sizeof p, "%s/sbatch", bin);
	write_text(p, "#!/bin/sh\nfor a in \"$@\"; do printf '%s\\n' \"$a\"; done >>\"$FAKE_SBATCH_LOG\"\n"
		      "echo -- >>\"$FAKE_SBATCH_LOG\"\nprintf '%s\\n' \"$FAKE_SBATCH_REPLY\"\n", 0755);
}

/* Issue 31.2: a newline in the sweep folder's path was written raw into `#SBATCH --output=…`; running the script ran
 * the rest of the line. Now: control characters are refused before the folder is touched, and every path in a
 * script is a quoted word — checked by running the generated runs.sh and report.sh from a folder whose name holds
 * quotes, $(…), spaces and '%'. */
static void test_slurm_scripts(void **state)
{
	(void)state;
	char dir[4096], sw[4096], p[4096], bin[4096], log[4096];
	snprintf(dir, sizeof dir, "%s", tu_tmpdir("sweep_slurm_paths"));
	/* a newline in --out, or in the folder of a sweep file whose "out" is relative */
	snprintf(sw, sizeof sw, "%s/a\ntouch %s/PWNED\nb", dir, dir);
	int st = sh("%s sweep " COMMON " --variants ref --frames 0:1 --out %s --slurm-dry-run", TASLAB_BINARY, q(sw));
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "control character (0x0a"))
		fail_msg("exit %d:\n%s", st, out);
	assert_false(tu_file_exists(sw));
	snprintf(p, sizeof p, "%s/x\ny", dir);
	mkdir(p, 0755);
	snprintf(p, sizeof p, "%s/x\ny/s.json", dir);
	write_text(p, "{\"scenes\": [\"turntable\"], \"cameras\": [\"orbit\"], \"variants\": [\"ref\"], \"frames\": \"0:1\", "
		      "\"size\": \"48x32\", \"device\": \"lavapipe\", \"out\": \"sw\"}", 0644);
	st = sh("%s sweep %s --slurm", TASLAB_BINARY, q(p));
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "control character"))
		fail_msg("exit %d:\n%s", st, out);
	snprintf(p, sizeof p, "%s/x\ny/sw", dir);
	assert_false(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/PWNED", dir);
	assert_false(tu_file_exists(p));

	/* quotes, $(…), spaces and '%' are fine: the dry run prints scripts that run */
	snprintf(sw, sizeof sw, "%s/it's $(touch PWNED) %%A 100%%", dir);
	st = sh("cd %s && %s sweep " COMMON " --variants ref --frames 0:1 --out %s --slurm-dry-run --slurm-opts "
		"\"--comment='a b' --time=5\"",
		q(dir), TASLAB_BINARY, q(sw));
	if (st)
		fail_msg("dry run failed (%d):\n%s", st, out);
	/* sbatch's arguments shell-quoted (issue 31.9): the option with a space is one quoted word */
	assert_non_null(strstr(out, " '--comment=a b' "));
	assert_null(strstr(out, "#SBATCH --output")); /* no path outside quotes */
	/* the scripts run as written: the array task renders run 0 into the folder, nothing else is executed */
	char runs_sh[4096], report_sh[4096];
	snprintf(runs_sh, sizeof runs_sh, "%s/slurm/runs.sh", sw);
	snprintf(report_sh, sizeof report_sh, "%s/slurm/report.sh", sw);
	st = sh("cd %s && SLURM_ARRAY_TASK_ID=0 bash %s", q(dir), q(runs_sh));
	if (st)
		fail_msg("runs.sh failed (%d):\n%s", st, out);
	snprintf(p, sizeof p, "%s/runs/turntable/orbit/ref/manifest.json", sw);
	assert_true(tu_file_exists(p));
	st = sh("cd %s && bash %s", q(dir), q(report_sh));
	if (st)
		fail_msg("report.sh failed (%d):\n%s", st, out);
	snprintf(p, sizeof p, "%s/report/index.html", sw);
	assert_true(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/PWNED", dir);
	assert_false(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/slurm/PWNED", sw);
	assert_false(tu_file_exists(p));

	/* submission through a fake sbatch: --output is an argument (the folder's '%' doubled: Slurm's pattern), the
	 * report depends on the array's id; a reply that is not a job id stops before the report job */
	fake_sbatch(dir, bin, sizeof bin);
	snprintf(log, sizeof log, "%s/sbatch.log", dir);
	char sw2[4096];
	snprintf(sw2, sizeof sw2, "%s/it's %%j", dir);
	st = sh("PATH=%s:$PATH FAKE_SBATCH_LOG=%s FAKE_SBATCH_REPLY=4711 %s sweep " COMMON
		" --variants ref --frames 0:1 --out %s --slurm",
		q(bin), q(log), TASLAB_BINARY, q(sw2));
	if (st)
		fail_msg("--slurm with a fake sbatch failed (%d):\n%s", st, out);
	char *calls = tu_read_file(log, NULL);
	char want[8192];
	snprintf(want, sizeof want, "--output=%s/it's %%%%j/slurm/logs/run-%%A_%%a.out\n", dir);
	if (!strstr(calls, want) || !strstr(calls, "--dependency=afterany:4711\n") || !strstr(calls, "report-%j.out\n"))
		fail_msg("sbatch was called with:\n%s", calls);
	free(calls);
	unlink(log);
	snprintf(sw2, sizeof sw2, "%s/sw3", dir);
	st = sh("PATH=%s:$PATH FAKE_SBATCH_LOG=%s FAKE_SBATCH_REPLY='Submitted batch job 12; rm -rf /' %s sweep " COMMON
		" --variants ref --frames 0:1 --out %s --slurm",
		q(bin), q(log), TASLAB_BINARY, q(sw2));
	if (st == 0 || tu_count_lines(out) != 1 || !strstr(out, "not a job id"))
		fail_msg("exit %d:\n%s", st, out);
	calls = tu_read_file(log, NULL);
	assert_non_null(calls);
	assert_null(strstr(calls, "--dependency")); /* the report job was not submitted */
	free(calls);
}

/* Issue 31.9: two identical sweeps on one folder rendered everything twice; `--out /dev/null` exited 1. */
static void test_lock_and_out(void **state)
{
	(void)state;
	char dir[4096], sw[4096], p[4096];
	snprintf(dir, sizeof dir, "%s", tu_tmpdir("sweep_lock"));
	snprintf(sw, sizeof sw, "%s/sw", dir);
	int st = sh("%s sweep " COMMON " --variants ref --frames 0:1 --out %s --slurm-dry-run", TASLAB_BINARY, q(sw));
	assert_int_equal(st, 0);
	/* another sweep holds the folder: refused, nothing rendered */
	snprintf(p, sizeof p, "%s/.taslab-lock", sw);
	int fd = open(p, O_RDWR | O_CREAT, 0644);
	assert_true(fd >= 0);
	assert_int_equal(flock(fd, LOCK_EX | LOCK_NB), 0);
	st = sh("%s sweep " COMMON " --variants ref --frames 0:1 --out %s", TASLAB_BINARY, q(sw));
	if (st == 0 || tu_count_lines(out) != 1 || !strstr(out, "in use by another 'taslab sweep'"))
		fail_msg("exit %d:\n%s", st, out);
	snprintf(p, sizeof p, "%s/runs", sw);
	assert_false(tu_file_exists(p));
	close(fd);
	st = sh("%s sweep " COMMON " --variants ref --frames 0:1 --out %s --quiet", TASLAB_BINARY, q(sw));
	if (st)
		fail_msg("exit %d:\n%s", st, out);
	assert_true(tu_file_exists(p));
	/* --out that exists and is not a folder is bad input: exit 2, for sweep and render alike */
	st = sh("%s sweep " COMMON " --variants ref --frames 0:1 --out /dev/null", TASLAB_BINARY);
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "/dev/null"))
		fail_msg("exit %d:\n%s", st, out);
	st = sh("%s render --scene turntable --size 8x8 --frames 0 --device lavapipe --out /dev/null", TASLAB_BINARY);
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "/dev/null"))
		fail_msg("exit %d:\n%s", st, out);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_slurm_scripts),
		cmocka_unit_test(test_lock_and_out),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
