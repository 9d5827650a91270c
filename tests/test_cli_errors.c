/* test_cli_errors.c — the taslab binary as a user runs it: bad input gives one line on stderr and a
 * non-zero exit and leaves no manifest.json; a good run completes with validation on and is
 * byte-for-byte reproducible (PNG and EXR, rendered a second apart); analyze refuses an --out that takes no files before it starts;
 * without the OpenImageIO module (taslab_oiio.so) an EXR write fails with one line naming it, and PNG-only work runs. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "test_util.h"

static char out[65536];

static void expect_failure(const char *args, const char *needle, const char *run_dir)
{
	char cmd[8192], manifest[4096];
	snprintf(cmd, sizeof cmd, "%s render --validation %s", TASLAB_BINARY, args);
	int st = tu_run(cmd, out, sizeof out);
	if (st == 0)
		fail_msg("'%s' succeeded; expected failure", cmd);
	if (tu_count_lines(out) != 1 || !strstr(out, needle))
		fail_msg("'%s' printed:\n%s\nexpected one line containing '%s'", cmd, out, needle);
	snprintf(manifest, sizeof manifest, "%s/manifest.json", run_dir);
	assert_false(tu_file_exists(manifest));
}

static void test_bad_inputs(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("cli_errors");
	char args[8192], run[4096], bad[4096];
	snprintf(run, sizeof run, "%s/run", dir);

	snprintf(args, sizeof args, "--scene %s/missing.json --out %s", dir, run);
	expect_failure(args, "missing.json", run);
	assert_false(tu_file_exists(run)); /* nothing created */

	snprintf(bad, sizeof bad, "%s/malformed.json", dir);
	FILE *f = fopen(bad, "w");
	fputs("{\"taslab_scene\": 1, \"name\": \"x\",\n  \"objects\": [ }\n", f);
	fclose(f);
	snprintf(args, sizeof args, "--scene %s --out %s", bad, run);
	expect_failure(args, "malformed.json:2", run);

	snprintf(args, sizeof args, "--scene turntable --method nosuch --out %s", run);
	expect_failure(args, "unknown method 'nosuch'", run);
	/* issue 31.9: the variant's T and --threshold both given rendered T = 16 under the name tarc@8 */
	snprintf(args, sizeof args, "--scene turntable --method tarc@8 --threshold 16 --out %s", run);
	expect_failure(args, "--threshold conflicts with --method tarc@8", run);
	snprintf(args, sizeof args, "--scene turntable --method tasa-oracle-oracle@8 --out %s", run);
	expect_failure(args, "'-oracle' is given twice", run);
	snprintf(args, sizeof args, "--scene turntable --size 4294967297x1 --out %s", run);
	expect_failure(args, "--size '4294967297x1' is not WIDTHxHEIGHT", run);
	snprintf(args, sizeof args, "--scene turntable --frames 1073741823:1073741825 --out %s", run);
	expect_failure(args, "--frames '1073741823:1073741825' is not A:B", run);
	snprintf(args, sizeof args, "--scene turntable --size 0x10 --out %s", run);
	expect_failure(args, "--size", run);
	snprintf(args, sizeof args, "--scene turntable --size 96x54 --frames 9:3 --out %s", run);
	expect_failure(args, "--frames", run);
	snprintf(args, sizeof args, "--scene turntable --camera helicopter --out %s", run);
	expect_failure(args, "available: orbit, overview", run);
	snprintf(args, sizeof args, "--scene no_such_builtin --out %s", run);
	expect_failure(args, "no_such_builtin", run);
	assert_false(tu_file_exists(run));

	/* A glTF whose buffer is missing. */
	snprintf(bad, sizeof bad, "%s/broken.gltf", dir);
	f = fopen(bad, "w");
	fputs("{\"asset\": {\"version\": \"2.0\"}, \"buffers\": [{\"uri\": \"absent.bin\", \"byteLength\": 4}]}", f);
	fclose(f);
	snprintf(args, sizeof args, "--scene %s --out %s", bad, run);
	expect_failure(args, "absent.bin", run);
	assert_false(tu_file_exists(run));

	/* Unwritable output: a folder cannot be created under a regular file. */
	snprintf(bad, sizeof bad, "%s/a_file", dir);
	f = fopen(bad, "w");
	fclose(f);
	snprintf(run, sizeof run, "%s/a_file/run", dir);
	snprintf(args, sizeof args, "--scene turntable --size 32x18 --frames 0 --device " TASLAB_TEST_DEVICE " --out %s", run);
	expect_failure(args, "a_file", run);
	/* a storage buffer past the device's range (lavapipe: 128 MiB): the sample list at 4096x4160 is 130 MiB; until
	 * 2026-11-27 such a buffer was created and bound anyway, and a shader read past the range is undefined */
	snprintf(run, sizeof run, "%s/run", dir);
	snprintf(args, sizeof args,
		 "--scene turntable --method vref --size 4096x4160 --frames 0 --device " TASLAB_TEST_DEVICE " --out %s", run);
	expect_failure(args,
		       "vbuf sample list needs 130.0 MiB at 4096x4160, more than this device's storage buffer range (128.0 MiB)",
		       run);
}

static void render_ok(const char *run)
{
	char cmd[8192];
	snprintf(cmd, sizeof cmd,
		 "%s render --scene turntable --camera orbit --size 64x36 --frames 20:22 --device " TASLAB_TEST_DEVICE " --validation "
		 "--quiet --out %s", TASLAB_BINARY, run);
	int st = tu_run(cmd, out, sizeof out);
	if (st != 0)
		fail_msg("'%s' failed (%d):\n%s", cmd, st, out);
}

static void test_good_run_reproducible(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("cli_good");
	char a[4096], b[4096], p[4096], q[4096];
	snprintf(a, sizeof a, "%s/a", dir);
	snprintf(b, sizeof b, "%s/b", dir);
	render_ok(a);
	sleep(1); /* a wall-clock stamp in a file (EXR DateTime) would now differ */
	render_ok(b);
	snprintf(p, sizeof p, "%s/manifest.json", a);
	assert_true(tu_file_exists(p));
	char *manifest = tu_read_file(p, NULL);
	assert_non_null(strstr(manifest, "\"method\": \"ref\""));
	assert_non_null(strstr(manifest, "llvmpipe"));
	free(manifest);
	snprintf(p, sizeof p, "%s/stats.csv", a);
	char *csv = tu_read_file(p, NULL);
	assert_non_null(csv);
	assert_int_equal(tu_count_lines(csv), 3); /* header + 2 frames */
	assert_true(strncmp(csv, "frame,time_s,visible_samples,shaded_samples,visible_units,shaded_units,new_units,"
				 "reuse_fraction,fs_invocations,cs_invocations,gpu_ms_total,gpu_ms_shadow", 128) == 0);
	free(csv);
	for (int fr = 20; fr <= 21; fr++) {
		size_t la, lb;
		snprintf(p, sizeof p, "%s/frames/%06d.png", a, fr);
		snprintf(q, sizeof q, "%s/frames/%06d.png", b, fr);
		char *x = tu_read_file(p, &la), *y = tu_read_file(q, &lb);
		assert_non_null(x);
		assert_non_null(y);
		assert_int_equal(la, lb);
		assert_memory_equal(x, y, la); /* same inputs, same device: same PNG bytes */
		free(x);
		free(y);
		/* EXRs too (issue 12: OpenImageIO stamped the wall-clock time as DateTime into every EXR) */
		snprintf(p, sizeof p, "%s/frames/%06d.exr", a, fr);
		snprintf(q, sizeof q, "%s/frames/%06d.exr", b, fr);
		x = tu_read_file(p, &la), y = tu_read_file(q, &lb);
		assert_non_null(x);
		assert_non_null(y);
		assert_int_equal(la, lb);
		assert_memory_equal(x, y, la);
		free(x);
		free(y);
	}
	/* A re-run into the same folder first removes the old manifest; a failing re-run leaves none. */
	char cmd[8192];
	snprintf(cmd, sizeof cmd, "%s render --scene turntable --size 64x36 --frames 0 --device no-such-gpu --out %s",
		 TASLAB_BINARY, a);
	assert_int_not_equal(tu_run(cmd, out, sizeof out), 0);
	snprintf(p, sizeof p, "%s/manifest.json", a);
	assert_true(tu_file_exists(p)); /* device selection fails before the run folder is touched */
}

/* Issue 12: analyze checks that --out can take files before it analyses anything (it used to fail only when writing
 * the results, after minutes). /proc/self is a folder that takes no files, for root too. */
static void test_analyze_out_first(void **state)
{
	(void)state;
	tu_expect_cli_error("analyze coherence --scene turntable --size 32x18 --frames 10,20 --device " TASLAB_TEST_DEVICE " --no-plots "
			    "--out /proc/self", "--out /proc/self: cannot write there");
	tu_expect_cli_error("analyze predictors --scene turntable --size 32x18 --frames 10 --device " TASLAB_TEST_DEVICE " --no-plots "
			    "--out /proc/self/taslab", "/proc/self/taslab");
}

static void test_help_and_version(void **state)
{
	(void)state;
	char cmd[8192];
	snprintf(cmd, sizeof cmd, "%s --version", TASLAB_BINARY);
	assert_int_equal(tu_run(cmd, out, sizeof out), 0);
	assert_non_null(strstr(out, "taslab "));
	snprintf(cmd, sizeof cmd, "%s render --help", TASLAB_BINARY);
	assert_int_equal(tu_run(cmd, out, sizeof out), 0);
	assert_non_null(strstr(out, "--scene"));
	assert_non_null(strstr(out, "tasa"));
	snprintf(cmd, sizeof cmd, "%s scenes", TASLAB_BINARY);
	assert_int_equal(tu_run(cmd, out, sizeof out), 0);
	assert_non_null(strstr(out, "turntable"));
	assert_non_null(strstr(out, "orbit "));
	assert_non_null(strstr(out, "stationary"));
	snprintf(cmd, sizeof cmd, "%s frobnicate", TASLAB_BINARY);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	assert_non_null(strstr(out, "unknown command"));
}

/* The OpenImageIO module is loaded only for EXR and non-PNG images (imageio_oiio.h): pointed at a missing file, a
 * render that writes EXR stops with one line saying what to do and leaves no manifest; PNG-only rendering and
 * metrics diff on the PNGs need nothing from it. */
static void test_oiio_module(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("cli_oiio");
	char cmd[8192], p[4096];
	const char *env = "TASLAB_OIIO_MODULE=/nonexistent/taslab_oiio.so";
	snprintf(cmd, sizeof cmd, "%s %s render --scene turntable --size 32x18 --frames 20 --device " TASLAB_TEST_DEVICE " --quiet --out %s/exr",
		 env, TASLAB_BINARY, dir);
	int st = tu_run(cmd, out, sizeof out);
	if (st == 0 || tu_count_lines(out) != 1 || !strstr(out, "000020.exr") || !strstr(out, "TASLAB_OIIO_MODULE") ||
	    !strstr(out, "/nonexistent/taslab_oiio.so"))
		fail_msg("'%s' gave %d:\n%s\nexpected one line naming the EXR and TASLAB_OIIO_MODULE", cmd, st, out);
	snprintf(p, sizeof p, "%s/exr/manifest.json", dir);
	assert_false(tu_file_exists(p));
	for (int i = 0; i < 2; i++) {
		snprintf(cmd, sizeof cmd,
			 "%s %s render --scene turntable --size 32x18 --frames 20:22 --device " TASLAB_TEST_DEVICE " --no-exr --quiet %s "
			 "--out %s/png%d",
			 env, TASLAB_BINARY, i ? "--trivial-shading" : "", dir, i);
		st = tu_run(cmd, out, sizeof out);
		if (st != 0)
			fail_msg("'%s' failed (%d):\n%s", cmd, st, out);
	}
	snprintf(cmd, sizeof cmd, "%s %s metrics diff --ref %s/png0/frames --test %s/png1/frames --out %s/diff", env,
		 TASLAB_BINARY, dir, dir, dir);
	st = tu_run(cmd, out, sizeof out);
	if (st != 0)
		fail_msg("'%s' failed (%d):\n%s", cmd, st, out);
	snprintf(p, sizeof p, "%s/diff/summary.json", dir);
	assert_true(tu_file_exists(p));
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_bad_inputs),
		cmocka_unit_test(test_good_run_reproducible),
		cmocka_unit_test(test_analyze_out_first),
		cmocka_unit_test(test_help_and_version),
		cmocka_unit_test(test_oiio_module),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
