/* test_sweep_safety.c — `taslab sweep` against hostile paths and concurrent use (issue 31; DESIGN section 9), on
 * lavapipe with validation: the Slurm batch scripts carry paths as quoted shell words only (a folder named with quotes,
 * `$(…)`, spaces and '%' gives scripts that run as they should, which the test checks by running them), paths with
 * control characters are refused before anything is written, the dry run prints sbatch's arguments shell-quoted, a job
 * id that is not digits is refused before the report job is submitted (a fake sbatch on PATH records its calls), one
 * sweep at a time holds a folder, and `--out` naming something that is not a folder is bad input (exit 2). */
#define _GNU_SOURCE
#include <errno.h>
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

#define COMMON "--scenes turntable --cameras orbit --size 48x32 --device " TASLAB_TEST_DEVICE " --validation"

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
	/* tu_run exports the child environment (leak detection on) for every command of the line, the batch scripts'
	 * taslab processes too */
	vsnprintf(cmd, sizeof cmd, fmt, ap);
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
	/* a backslash: sbatch's --output would not expand %a, so every array task would write one log */
	snprintf(sw, sizeof sw, "%s/a\\b", dir);
	st = sh("%s sweep " COMMON " --variants ref --frames 0:1 --out %s --slurm-dry-run", TASLAB_BINARY, q(sw));
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "holds a backslash"))
		fail_msg("exit %d:\n%s", st, out);
	assert_false(tu_file_exists(sw));
	/* --slurm-opts: a word filling the parser's 4096-byte buffer, then an empty quoted word, wrote its terminator one
	 * byte past the buffer (AddressSanitizer: stack-buffer-overflow); now "too long" */
	char opts[4200];
	memset(opts, 'x', 4095);
	snprintf(opts + 4095, sizeof opts - 4095, " ''");
	snprintf(sw, sizeof sw, "%s/opts", dir);
	st = sh("%s sweep " COMMON " --variants ref --frames 0:1 --out %s --slurm-dry-run --slurm-opts \"%s\"",
		TASLAB_BINARY, q(sw), opts); /* (only x, a space and two quotes: safe inside double quotes) */
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "--slurm-opts: too long"))
		fail_msg("exit %d:\n%s", st, out);

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
	/* a second process for one run (--task I by hand beside the sweep's own, a Slurm task requeued while the first
	 * still runs) is refused while the first holds the run's lock: nothing rendered */
	snprintf(p, sizeof p, "%s/.taslab-locks", sw);
	assert_true(mkdir(p, 0755) == 0 || errno == EEXIST);
	snprintf(p, sizeof p, "%s/.taslab-locks/0", sw);
	int tfd = open(p, O_RDWR | O_CREAT, 0644);
	assert_true(tfd >= 0);
	assert_int_equal(flock(tfd, LOCK_EX | LOCK_NB), 0);
	st = sh("%s sweep %s/sweep.json --task 0", TASLAB_BINARY, q(sw));
	if (st != 1 || tu_count_lines(out) != 1 || !strstr(out, "another process is doing this run"))
		fail_msg("--task 0 while another holds its lock: exit %d:\n%s", st, out);
	close(tfd);
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
	st = sh("%s render --scene turntable --size 8x8 --frames 0 --device " TASLAB_TEST_DEVICE " --out /dev/null", TASLAB_BINARY);
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "/dev/null"))
		fail_msg("exit %d:\n%s", st, out);
}

static long long mtime_ns(const char *path)
{
	struct stat sb;
	if (stat(path, &sb))
		return -1;
	return (long long)sb.st_mtim.tv_sec * 1000000000LL + sb.st_mtim.tv_nsec;
}

static int count_in(const char *text, const char *needle)
{
	int n = 0;
	for (const char *p = text; (p = strstr(p, needle)); p += strlen(needle))
		n++;
	return n;
}

/* Issue 31.8: a run with a manifest but a missing, extra or mixed-size frame failed every rerun while the sweep never
 * re-rendered it, and the sweep died in its report step (exit 2, no path); tonemap made a gapped PNG sequence and
 * exited 0. Now the sweep lists a damaged run once, leaves it out of the report (status "damaged"), and
 * --redo-damaged renders it again; clip, tonemap and metrics diff refuse a run that does not match its manifest. */
static void test_damaged_runs(void **state)
{
	(void)state;
	char dir[4096], sw[4096], args[8192], run[4096], ref[4096], p[4096], q2[4096];
	snprintf(dir, sizeof dir, "%s", tu_tmpdir("sweep_damaged"));
	snprintf(sw, sizeof sw, "%s/sw", dir);
	snprintf(args, sizeof args, COMMON " --variants ref,tfr@8 --frames 0:3 --out %s", q(sw));
	int st = sh("%s sweep %s --quiet", TASLAB_BINARY, args);
	if (st)
		fail_msg("sweep failed (%d):\n%s", st, out);
	snprintf(run, sizeof run, "%s/runs/turntable/orbit/tfr-T8", sw);
	snprintf(ref, sizeof ref, "%s/runs/turntable/orbit/ref", sw);
	/* a missing frame (its clip and metrics gone too, as after a crash between steps) */
	snprintf(p, sizeof p, "%s/frames/000001.png", run);
	assert_int_equal(unlink(p), 0);
	snprintf(p, sizeof p, "%s/clips/turntable/orbit/tfr-T8.webm", sw);
	unlink(p);
	snprintf(p, sizeof p, "%s/metrics/turntable/orbit/tfr-T8/summary.json", sw);
	unlink(p);
	st = sh("%s sweep %s", TASLAB_BINARY, args);
	if (st != 1 || count_in(out, "000001.png is missing") != 1 || count_in(out, "is damaged") != 1 ||
	    !strstr(out, "--redo-damaged"))
		fail_msg("exit %d (want 1, the damage listed once):\n%s", st, out);
	snprintf(p, sizeof p, "%s/report/index.html", sw);
	assert_non_null(strstr(out, p)); /* the report is written, and its path printed */
	snprintf(p, sizeof p, "%s/summary.csv", sw);
	char *csv = tu_read_file(p, NULL);
	assert_non_null(strstr(csv, ",damaged,"));
	free(csv);
	/* every command that reads a run checks it against its manifest */
	st = sh("%s tonemap %s --out %s/tm", TASLAB_BINARY, q(run), q(dir));
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "000001.png is missing"))
		fail_msg("tonemap: exit %d:\n%s", st, out);
	snprintf(p, sizeof p, "%s/tm", dir);
	assert_false(tu_file_exists(p));
	st = sh("%s clip %s --out %s/c.webm", TASLAB_BINARY, q(run), q(dir));
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "000001.png is missing"))
		fail_msg("clip: exit %d:\n%s", st, out);
	/* an extra frame and a frame of another size, in the ref run */
	snprintf(p, sizeof p, "%s/frames/000002.exr", ref);
	snprintf(q2, sizeof q2, "%s/frames/000007.exr", ref);
	assert_int_equal(sh("cp %s %s", q(p), q(q2)), 0);
	st = sh("%s tonemap %s --out %s/tm", TASLAB_BINARY, q(ref), q(dir));
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "000007.exr: not a frame of this run"))
		fail_msg("tonemap: exit %d:\n%s", st, out);
	unlink(q2);
	st = sh("%s render --scene turntable --size 8x8 --frames 2 --device " TASLAB_TEST_DEVICE " --no-exr --quiet --out %s/small",
		TASLAB_BINARY, q(dir));
	assert_int_equal(st, 0);
	snprintf(p, sizeof p, "%s/small/frames/000002.png", dir);
	snprintf(q2, sizeof q2, "%s/frames/000002.png", ref);
	assert_int_equal(sh("cp %s %s", q(p), q(q2)), 0);
	st = sh("%s tonemap %s --out %s/tm", TASLAB_BINARY, q(ref), q(dir));
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "000002.png: size 8x8 differs from the run's 48x32"))
		fail_msg("tonemap: exit %d:\n%s", st, out);
	st = sh("%s metrics diff --ref %s --test %s --out %s/diff", TASLAB_BINARY, q(ref), q(ref), q(dir));
	if (st != 2 || !strstr(out, "8x8"))
		fail_msg("metrics diff: exit %d:\n%s", st, out);
	/* --redo-damaged renders both again (the ref's comparisons are redone against the new ref) */
	snprintf(p, sizeof p, "%s/manifest.json", ref);
	long long before = mtime_ns(p);
	st = sh("%s sweep %s --redo-damaged", TASLAB_BINARY, args);
	if (st || count_in(out, "is damaged") != 2 || !strstr(out, "rendering it again"))
		fail_msg("--redo-damaged: exit %d:\n%s", st, out);
	assert_true(mtime_ns(p) != before);
	snprintf(p, sizeof p, "%s/summary.csv", sw);
	csv = tu_read_file(p, NULL);
	assert_null(strstr(csv, ",damaged,"));
	assert_int_equal(count_in(csv, ",complete,"), 2);
	free(csv);
	st = sh("%s tonemap %s --out %s/tm", TASLAB_BINARY, q(run), q(dir));
	if (st)
		fail_msg("tonemap of the repaired run: exit %d:\n%s", st, out);
	st = sh("%s sweep %s", TASLAB_BINARY, args);
	if (st || strstr(out, "is damaged") || !strstr(out, "2 complete, 0 to do"))
		fail_msg("exit %d:\n%s", st, out);
}

/* Issue 31.4: the sweep's identity and the manifests held the scene and the OpenColorIO config by path only: after an
 * edit of the scene (or of a LUT the config uses) and one deleted manifest, the rerun rendered that run from the new
 * inputs and compared it with the old reference. Now both record content digests: the same request is a different
 * sweep, a resumed sweep.json refuses to render from changed inputs, and a run whose manifest holds other digests
 * than the sweep's is damaged (--redo-damaged renders it from the sweep's inputs once they are back). */
static void test_changed_inputs(void **state)
{
	(void)state;
	char dir[4096], sw[4096], args[8192], p[4096], scn[4096], ocio[4096], man[4096], spec[4096];
	snprintf(dir, sizeof dir, "%s", tu_tmpdir("sweep_inputs"));
	snprintf(scn, sizeof scn, "%s/t.json", dir);
	snprintf(ocio, sizeof ocio, "%s/ocio", dir);
	assert_int_equal(sh("cp %s/scenes/turntable.json %s && cp -r %s/tests/data/ocio_lut %s", TASLAB_SOURCE_DIR, q(scn),
			    TASLAB_SOURCE_DIR, q(ocio)), 0);
	snprintf(sw, sizeof sw, "%s/sw", dir);
	snprintf(args, sizeof args,
		 "--scenes %s --cameras orbit --size 48x32 --device " TASLAB_TEST_DEVICE " --variants ref,tfr@8 --frames 0:2 --no-report "
		 "--ocio-config %s/config.ocio --display sRGB --view Graded --out %s",
		 q(scn), q(ocio), q(sw));
	int st = sh("%s sweep %s --quiet", TASLAB_BINARY, args);
	if (st)
		fail_msg("sweep failed (%d):\n%s", st, out);
	snprintf(man, sizeof man, "%s/runs/turntable/orbit/tfr-T8/manifest.json", sw);
	snprintf(spec, sizeof spec, "%s/sweep.json", sw);
	/* the manifest records the digests the sweep holds */
	char *m = tu_read_file(man, NULL), *j = tu_read_file(spec, NULL);
	const char *d = strstr(j, "\"digest\": \"");
	assert_non_null(d);
	char want[64];
	snprintf(want, sizeof want, "\"scene_digest\": \"%.16s\"", d + 11);
	assert_non_null(strstr(m, want));
	free(m), free(j);
	/* an edit of the scene, one manifest deleted */
	assert_int_equal(sh("sed -i 's/\"exposure\": 1.6/\"exposure\": 2.5/' %s && grep -q '\"exposure\": 2.5' %s", q(scn), q(scn)), 0);
	unlink(man);
	st = sh("%s sweep %s", TASLAB_BINARY, args);
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "turntable: the scene file or its assets changed"))
		fail_msg("the same request after an edit: exit %d:\n%s", st, out);
	st = sh("%s sweep %s", TASLAB_BINARY, q(spec));
	if (st != 1 || !strstr(out, "changed since the sweep was resolved"))
		fail_msg("resuming sweep.json after an edit: exit %d:\n%s", st, out);
	assert_false(tu_file_exists(man)); /* nothing rendered from the new scene into the old sweep */
	/* a run made from the edited scene (here: by hand, into the sweep's folder) is damaged, not complete */
	snprintf(p, sizeof p, "%s/runs/turntable/orbit/tfr-T8", sw);
	st = sh("%s render --scene %s --camera orbit --method tfr@8 --size 48x32 --frames 0:2 --device " TASLAB_TEST_DEVICE " --quiet "
		"--ocio-config %s/config.ocio --display sRGB --view Graded --out %s",
		TASLAB_BINARY, q(scn), q(ocio), q(p));
	assert_int_equal(st, 0);
	st = sh("%s sweep %s", TASLAB_BINARY, q(spec));
	if (st != 1 || !strstr(out, "is damaged") || !strstr(out, "made from other inputs"))
		fail_msg("a run of the edited scene: exit %d:\n%s", st, out);
	/* the scene back as it was: the run is redone from it */
	assert_int_equal(sh("sed -i 's/\"exposure\": 2.5/\"exposure\": 1.6/' %s", q(scn)), 0);
	st = sh("%s sweep %s --redo-damaged", TASLAB_BINARY, q(spec));
	if (st)
		fail_msg("--redo-damaged with the inputs back: exit %d:\n%s", st, out);
	/* a LUT of the config rewritten under the same name */
	assert_int_equal(sh("sed -i '5s/.*/0.250000 0.000000 0.000000/' %s/grade.cube", q(ocio)), 0);
	unlink(man);
	st = sh("%s sweep %s", TASLAB_BINARY, args);
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "the OpenColorIO config or one of its LUTs changed"))
		fail_msg("the same request after a LUT edit: exit %d:\n%s", st, out);
	st = sh("%s sweep %s", TASLAB_BINARY, q(spec));
	if (st != 1 || !strstr(out, "the OpenColorIO config or one of its LUTs changed since the sweep was resolved"))
		fail_msg("resuming after a LUT edit: exit %d:\n%s", st, out);
	assert_false(tu_file_exists(man));
}

/* Review finding (2026-11-27): a sweep resumed by a newer taslab kept the runs the older one made (the manifests held
 * only the project's version), so one sweep could mix two builds' frames. Now sweep.json and every manifest record
 * the build's digest (the executable's bytes): another build - here the same binary with one byte appended, which
 * still runs - is refused on resume, on the same request and for one --task, and a run it made is damaged. */
static void test_other_build(void **state)
{
	(void)state;
	char dir[4096], sw[4096], args[8192], other[4096], man[4096], spec[4096], run[4096];
	snprintf(dir, sizeof dir, "%s", tu_tmpdir("sweep_build"));
	snprintf(sw, sizeof sw, "%s/sw", dir);
	snprintf(other, sizeof other, "%s/other/taslab", dir); /* named taslab: tests/lsan_pin.c pins its driver */
	snprintf(args, sizeof args, COMMON " --variants ref,tfr@8 --frames 0:2 --no-report --quiet --out %s", q(sw));
	int st = sh("%s sweep %s", TASLAB_BINARY, args);
	if (st)
		fail_msg("sweep failed (%d):\n%s", st, out);
	snprintf(man, sizeof man, "%s/runs/turntable/orbit/tfr-T8/manifest.json", sw);
	snprintf(run, sizeof run, "%s/runs/turntable/orbit/tfr-T8", sw);
	snprintf(spec, sizeof spec, "%s/sweep.json", sw);
	/* the build is recorded: sweep.json and the manifest hold the digest --version prints */
	assert_int_equal(sh("%s --version", TASLAB_BINARY), 0);
	const char *b = strstr(out, "(build ");
	assert_non_null(b);
	char digest[17], want[64];
	snprintf(digest, sizeof digest, "%.16s", b + 7);
	char *j = tu_read_file(spec, NULL), *m = tu_read_file(man, NULL);
	snprintf(want, sizeof want, "\"build_digest\": \"%s\"", digest);
	assert_non_null(strstr(j, want));
	snprintf(want, sizeof want, "\"build\": \"%s\"", digest);
	assert_non_null(strstr(m, want));
	free(j), free(m);
	/* another build: one byte more */
	assert_int_equal(sh("mkdir -p %s/other && cp %s %s && printf 'x' >> %s && %s --version", q(dir), TASLAB_BINARY,
			    q(other), q(other), q(other)), 0);
	if (strstr(out, digest))
		fail_msg("the other binary has the same build digest:\n%s", out);
	unlink(man);
	st = sh("%s sweep %s", q(other), q(spec));
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "was started by another taslab build"))
		fail_msg("resuming with another build: exit %d:\n%s", st, out);
	st = sh("%s sweep %s --task 1", q(other), q(spec));
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "was started by another taslab build"))
		fail_msg("one --task with another build: exit %d:\n%s", st, out);
	st = sh("%s sweep %s", q(other), args);
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "holds a different sweep (another taslab build"))
		fail_msg("the same request with another build: exit %d:\n%s", st, out);
	assert_false(tu_file_exists(man)); /* nothing rendered by the other build into the sweep */
	/* a run the other build made (by hand, into the sweep's folder) is damaged, not complete */
	st = sh("%s render --scene turntable --camera orbit --method tfr@8 --size 48x32 --frames 0:2 --device "
		TASLAB_TEST_DEVICE " --quiet --out %s", q(other), q(run));
	if (st)
		fail_msg("render by the other build: exit %d:\n%s", st, out);
	st = sh("%s sweep %s", TASLAB_BINARY, q(spec));
	if (st != 1 || !strstr(out, "is damaged") || !strstr(out, "rendered by another taslab build"))
		fail_msg("a run of the other build: exit %d:\n%s", st, out);
	/* the build that started it resumes it */
	st = sh("%s sweep %s --redo-damaged", TASLAB_BINARY, q(spec));
	if (st || !strstr(out, "2 of 2 runs complete") || !tu_file_exists(man))
		fail_msg("--redo-damaged by the sweep's build: exit %d:\n%s", st, out);
	/* the report by another build reads only: a missing clip is not made by it, but by the sweep's build */
	char clip[4096];
	snprintf(clip, sizeof clip, "%s/clips/turntable/orbit/tfr-T8.webm", sw);
	assert_true(tu_file_exists(clip));
	unlink(clip);
	st = sh("%s report %s", q(other), q(sw));
	if (!strstr(out, "missing clips and comparisons are not made") || tu_file_exists(clip))
		fail_msg("report by another build: exit %d:\n%s", st, out);
	st = sh("%s report %s", TASLAB_BINARY, q(sw));
	if (st || !tu_file_exists(clip))
		fail_msg("report by the sweep's build: exit %d:\n%s", st, out);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_slurm_scripts),
		cmocka_unit_test(test_lock_and_out),
		cmocka_unit_test(test_damaged_runs),
		cmocka_unit_test(test_changed_inputs),
		cmocka_unit_test(test_other_build),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
