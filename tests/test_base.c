/* test_base.c — the base layer: error codes and messages, mkdir -p, the atomic-write helper, temp-file
 * cleanup (live writers keep their files, killed ones do not), sets of files committed together, output-folder
 * checks, path checks, JSON files. */
#include <dirent.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "taslab/tl_buf.h"
#include "taslab/tl_clock.h"
#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"
#include "taslab/tl_json.h"
#include "taslab/tl_parse.h"
#include "test_util.h"

static int count_entries(const char *dir)
{
	DIR *d = opendir(dir);
	int n = 0;
	struct dirent *e;
	while (d && (e = readdir(d)))
		n += e->d_name[0] != '.' || (strcmp(e->d_name, ".") && strcmp(e->d_name, ".."));
	if (d)
		closedir(d);
	return n;
}

static void test_errors(void **state)
{
	(void)state;
	char err[64];
	/* Every code has its own description; exit statuses: 2 for the user's input, 1 for the rest. */
	for (int a = TL_ERR_MIN; a <= 0; a++)
		for (int b = TL_ERR_MIN; b < a; b++)
			assert_string_not_equal(tl_strerror(a), tl_strerror(b));
	assert_string_equal(tl_strerror(-100), "unknown error");
	assert_int_equal(tl_exit_status(TL_OK), 0);
	assert_int_equal(tl_exit_status(TL_ERR_ARG), 2);
	assert_int_equal(tl_exit_status(TL_ERR_INPUT), 2);
	assert_int_equal(tl_exit_status(TL_ERR_VULKAN), 1);
	assert_int_equal(tl_exit_status(TL_ERR_OUTPUT), 1);
	assert_int_equal(tl_error(err, sizeof err, TL_ERR_INPUT, "%s: %d", "x", 7), TL_ERR_INPUT);
	assert_string_equal(err, "x: 7");
	assert_int_equal(tl_error(err, 4, TL_ERR_ARG, "truncated message"), TL_ERR_ARG);
	assert_string_equal(err, "tru");
}

static void test_mkdirs(void **state)
{
	(void)state;
	char err[512], p[4096];
	const char *d = tu_tmpdir("base_mkdirs");
	snprintf(p, sizeof p, "%s/a/b/c", d);
	assert_int_equal(tl_mkdirs(p, err, sizeof err), TL_OK);
	assert_true(tl_is_dir(p));
	assert_int_equal(tl_mkdirs(p, err, sizeof err), TL_OK); /* exists: fine */
	snprintf(p, sizeof p, "%s/file", d);
	FILE *f = fopen(p, "w");
	fclose(f);
	snprintf(p, sizeof p, "%s/file/sub", d);
	assert_int_equal(tl_mkdirs(p, err, sizeof err), TL_ERR_ARG); /* the caller's choice: bad input, exit 2 (issue 31.9) */
	assert_non_null(strstr(err, "not a folder"));
}

static void test_atomic_write(void **state)
{
	(void)state;
	char err[512], p[4096];
	const char *d = tu_tmpdir("base_atomic");
	snprintf(p, sizeof p, "%s/out.txt", d);
	/* Committed: the content is there, no temporary file is left. */
	tl_atomic a;
	assert_int_equal(tl_atomic_open(&a, p, err, sizeof err), TL_OK);
	assert_false(tu_file_exists(p)); /* nothing under the final name until the commit */
	fprintf(a.f, "hello\n");
	assert_int_equal(tl_atomic_commit(&a, err, sizeof err), TL_OK);
	char *text = tu_read_file(p, NULL);
	assert_string_equal(text, "hello\n");
	free(text);
	assert_int_equal(count_entries(d), 1);
	/* Aborted: the old content stays, the temporary file is gone. */
	assert_int_equal(tl_atomic_open(&a, p, err, sizeof err), TL_OK);
	fprintf(a.f, "replacement\n");
	tl_atomic_abort(&a);
	text = tu_read_file(p, NULL);
	assert_string_equal(text, "hello\n");
	free(text);
	assert_int_equal(count_entries(d), 1);
	/* Detached (writers that take a file name). */
	assert_int_equal(tl_atomic_open(&a, p, err, sizeof err), TL_OK);
	assert_int_equal(tl_atomic_detach(&a, err, sizeof err), TL_OK);
	FILE *f = fopen(a.tmp, "w");
	fputs("by name\n", f);
	fclose(f);
	assert_int_equal(tl_atomic_commit(&a, err, sizeof err), TL_OK);
	text = tu_read_file(p, NULL);
	assert_string_equal(text, "by name\n");
	free(text);
	/* Two writers at once get different temporary names. */
	tl_atomic b;
	assert_int_equal(tl_atomic_open(&a, p, err, sizeof err), TL_OK);
	assert_int_equal(tl_atomic_open(&b, p, err, sizeof err), TL_OK);
	assert_string_not_equal(a.tmp, b.tmp);
	tl_atomic_abort(&a);
	tl_atomic_abort(&b);
	/* A missing folder is an output error with the path. */
	snprintf(p, sizeof p, "%s/missing/out.txt", d);
	assert_int_equal(tl_atomic_open(&a, p, err, sizeof err), TL_ERR_OUTPUT);
	assert_non_null(strstr(err, "missing/out.txt"));
	assert_non_null(strstr(err, "does not exist (create it first)")); /* said, not "No such file or directory" */
	assert_int_equal(tl_write_file("", "x", 1, err, sizeof err), TL_ERR_ARG);
}

/* A write that fails at flush (a full disk) is reported and leaves nothing: needs a tiny tmpfs, so only as
 * root; /dev/full cannot stand in because the helper writes next to the final name. */
static void test_atomic_full_disk(void **state)
{
	(void)state;
	char err[512], p[4096], cmd[4200];
	const char *base = getenv("TASLAB_TMP");
	snprintf(cmd, sizeof cmd, "umount '%s/base_full' 2>/dev/null", base ? base : "/tmp/taslab-tests");
	if (geteuid() == 0 && system(cmd)) { /* a mount left by an interrupted earlier run is gone now */
	}
	const char *d = tu_tmpdir("base_full");
	if (!tu_require(geteuid() == 0, "test_atomic_full_disk: a write to a full disk (needs root to mount a 64 KiB tmpfs)"))
		skip();
	snprintf(cmd, sizeof cmd, "mount -t tmpfs -o size=64k tmpfs %s 2>/dev/null", d);
	if (!tu_require(system(cmd) == 0, "test_atomic_full_disk: a write to a full disk (cannot mount a tmpfs on %s)", d))
		skip();
	snprintf(p, sizeof p, "%s/big.bin", d);
	size_t n = 1 << 20;
	char *data = calloc(1, n);
	assert_int_equal(tl_write_file(p, data, n, err, sizeof err), TL_ERR_OUTPUT);
	assert_non_null(strstr(err, "No space"));
	assert_false(tu_file_exists(p));
	assert_int_equal(count_entries(d), 0); /* the temporary file is gone too */
	free(data);
	snprintf(cmd, sizeof cmd, "umount %s", d);
	assert_int_equal(system(cmd), 0);
}

static void test_clean_temps(void **state)
{
	(void)state;
	char p[4096], err[512];
	const char *d = tu_tmpdir("base_clean");
	const char *names[] = {".a.png.tmp.Ab12Cd", ".stats.csv.tmp.xyzXYZ", "keep.tmp.abcdef", ".keep.tmp.abc", "plain"};
	for (size_t i = 0; i < 5; i++) {
		snprintf(p, sizeof p, "%s/%s", d, names[i]);
		fclose(fopen(p, "w"));
	}
	assert_int_equal(tl_fs_clean_temps(d), 2);
	assert_int_equal(count_entries(d), 3);
	/* A writer that is still running keeps its temporary file, detached or not; one SIGKILLed midway loses it. */
	tl_atomic live, detached;
	snprintf(p, sizeof p, "%s/live.csv", d);
	assert_int_equal(tl_atomic_open(&live, p, err, sizeof err), TL_OK);
	snprintf(p, sizeof p, "%s/detached.png", d);
	assert_int_equal(tl_atomic_open(&detached, p, err, sizeof err), TL_OK);
	assert_int_equal(tl_atomic_detach(&detached, err, sizeof err), TL_OK);
	int ready[2];
	assert_int_equal(pipe(ready), 0);
	pid_t child = fork();
	if (child == 0) {
		tl_atomic a;
		snprintf(p, sizeof p, "%s/killed.webm", d);
		if (tl_atomic_open(&a, p, err, sizeof err) == TL_OK && tl_atomic_detach(&a, err, sizeof err) == TL_OK)
			(void)!write(ready[1], "x", 1);
		pause();
		_exit(0);
	}
	char c;
	assert_int_equal(read(ready[0], &c, 1), 1);
	assert_int_equal(tl_fs_clean_temps(d), 0); /* the child is alive: its file stays */
	assert_int_equal(count_entries(d), 6);
	kill(child, SIGKILL);
	waitpid(child, NULL, 0);
	snprintf(p, sizeof p, "%s/x", d);
	assert_int_equal(tl_fs_clean_temps_beside(p), 1);
	assert_int_equal(count_entries(d), 5);
	assert_int_equal(tl_atomic_commit(&live, err, sizeof err), TL_OK);
	assert_int_equal(tl_atomic_commit(&detached, err, sizeof err), TL_OK);
	assert_int_equal(count_entries(d), 5); /* plain, keep.tmp.abcdef, .keep.tmp.abc, live.csv, detached.png */
	close(ready[0]);
	close(ready[1]);
}

/* Fails unless the files f0.txt and f1.txt of `d` hold `text`. */
static void expect_set_contents(const char *d, const char *text)
{
	char p[4096];
	for (int i = 0; i < 2; i++) {
		snprintf(p, sizeof p, "%s/f%d.txt", d, i);
		char *t = tu_read_file(p, NULL);
		assert_string_equal(t, text);
		free(t);
	}
}

/* A set appears together: nothing under a final name before the commit, all after it; an abort leaves the old files. */
static void test_atomic_set(void **state)
{
	(void)state;
	char p[4096], err[512];
	const char *d = tu_tmpdir("base_set");
	tl_atomic set[3] = {0};
	for (int i = 0; i < 2; i++) {
		snprintf(p, sizeof p, "%s/f%d.txt", d, i);
		assert_int_equal(tl_write_file(p, "old", 3, err, sizeof err), TL_OK);
		assert_int_equal(tl_atomic_open(&set[i], p, err, sizeof err), TL_OK);
		fputs("new", set[i].f);
	}
	tl_atomic_abort_set(set, 3);
	assert_int_equal(count_entries(d), 2);
	expect_set_contents(d, "old");
	for (int i = 0; i < 2; i++) {
		snprintf(p, sizeof p, "%s/f%d.txt", d, i);
		assert_int_equal(tl_atomic_open(&set[i], p, err, sizeof err), TL_OK);
		fputs("new", set[i].f);
	}
	assert_int_equal(tl_atomic_detach(&set[1], err, sizeof err), TL_OK); /* detached members commit too */
	assert_int_equal(tl_atomic_commit_set(set, 3, err, sizeof err), TL_OK); /* set[2] zeroed: skipped */
	assert_int_equal(count_entries(d), 2);
	expect_set_contents(d, "new");
}

/* An output folder is checked before the work: created when missing, refused when it cannot take a file
 * (/proc/self exists as a folder but takes no files, for root too). */
static void test_check_out_dir(void **state)
{
	(void)state;
	char p[4096], err[512];
	const char *d = tu_tmpdir("base_outdir");
	snprintf(p, sizeof p, "%s/a/b", d);
	assert_int_equal(tl_check_out_dir(p, "--out", err, sizeof err), TL_OK);
	assert_true(tl_is_dir(p));
	assert_int_equal(count_entries(p), 0); /* the probe is gone */
	assert_int_equal(tl_check_out_dir("/proc/self", "--out", err, sizeof err), TL_ERR_OUTPUT);
	assert_non_null(strstr(err, "--out /proc/self: cannot write there"));
	snprintf(p, sizeof p, "%s/file", d);
	assert_int_equal(tl_write_file(p, "x", 1, err, sizeof err), TL_OK);
	snprintf(p, sizeof p, "%s/file/sub", d);
	assert_int_equal(tl_check_out_dir(p, "--out", err, sizeof err), TL_ERR_ARG);
	assert_int_equal(tl_check_out_dir("/dev/null", "--out", err, sizeof err), TL_ERR_ARG);
}

/* tl_parse.h, the one number parser (issue 31.5): nothing wraps at 2^32 or 2^64, digits only, ranges checked. */
static void test_parse(void **state)
{
	(void)state;
	char why[256];
	uint64_t v;
	const char *e;
	assert_int_equal(tl_parse_u64_prefix("18446744073709551615x", &e, &v), TL_OK);
	assert_true(v == UINT64_MAX && *e == 'x');
	assert_int_equal(tl_parse_u64_prefix("18446744073709551616", &e, &v), TL_ERR_ARG);
	assert_int_equal(tl_parse_u64_prefix("-1", &e, &v), TL_ERR_ARG);
	assert_int_equal(tl_parse_u64_prefix(" 1", &e, &v), TL_ERR_ARG);
	assert_int_equal(tl_parse_uint("256", 1, 256, &v, why, sizeof why), TL_OK);
	assert_int_equal(tl_parse_uint("257", 1, 256, &v, why, sizeof why), TL_ERR_ARG);
	assert_string_equal(why, "must be a whole number in [1, 256]");
	assert_int_equal(tl_parse_uint("1e2", 1, 256, &v, why, sizeof why), TL_ERR_ARG);
	uint32_t w, h, a, b;
	bool given;
	assert_int_equal(tl_parse_size("16384X1", &w, &h, why, sizeof why), TL_OK);
	assert_true(w == 16384 && h == 1);
	const char *bad_sizes[] = {"4294967297x1", "1x4294967297", "0x5", "16385x1", "+5x5", "5x5 ", "5x", "x5", "5*5", ""};
	for (size_t i = 0; i < sizeof bad_sizes / sizeof bad_sizes[0]; i++)
		if (tl_parse_size(bad_sizes[i], &w, &h, why, sizeof why) != TL_ERR_ARG)
			fail_msg("size '%s' accepted", bad_sizes[i]);
	b = 300;
	assert_int_equal(tl_parse_frames("10:", &a, &b, &given, why, sizeof why), TL_OK);
	assert_true(a == 10 && b == 300 && !given);
	assert_int_equal(tl_parse_frames("1073741823", &a, &b, &given, why, sizeof why), TL_OK);
	assert_true(a == TL_FRAME_MAX - 1 && b == TL_FRAME_MAX && given);
	const char *bad_frames[] = {"4294967290:4294967295", "1073741824", "0:1073741825", "5:5", "9:3", "-1:3", "1:2:3", ""};
	for (size_t i = 0; i < sizeof bad_frames / sizeof bad_frames[0]; i++) {
		b = 300;
		if (tl_parse_frames(bad_frames[i], &a, &b, &given, why, sizeof why) != TL_ERR_ARG)
			fail_msg("frames '%s' accepted", bad_frames[i]);
	}
}

static void test_paths(void **state)
{
	(void)state;
	char a[4096], b[4096];
	const char *d = tu_tmpdir("base_paths");
	snprintf(a, sizeof a, "%s/run", d);
	mkdir(a, 0777);
	snprintf(b, sizeof b, "%s/run/frames/000000.png", d); /* need not exist */
	assert_true(tl_path_inside(b, a));
	snprintf(b, sizeof b, "%s/run/../run/x", d);
	assert_true(tl_path_inside(b, a));
	snprintf(b, sizeof b, "%s/runs/x", d);
	assert_false(tl_path_inside(b, a)); /* a prefix is not a parent */
	snprintf(b, sizeof b, "%s/run/.", d);
	assert_true(tl_same_file(a, b));
	assert_false(tl_same_file(a, d));
	/* The same file whether it exists yet or not. */
	snprintf(a, sizeof a, "%s/run/new.csv", d);
	snprintf(b, sizeof b, "%s/run/../run/./new.csv", d);
	assert_true(tl_same_path(a, b));
	snprintf(b, sizeof b, "%s/run/new.csv2", d);
	assert_false(tl_same_path(a, b));
}

static void test_json(void **state)
{
	(void)state;
	char err[512], p[4096];
	const char *d = tu_tmpdir("base_json");
	snprintf(p, sizeof p, "%s/x.json", d);
	json_t *j = json_pack("{s:i, s:s}", "b", 2, "a", "text");
	assert_int_equal(tl_json_write(p, j, err, sizeof err), TL_OK);
	json_decref(j);
	char *text = tu_read_file(p, NULL);
	assert_true(strstr(text, "\"a\"") < strstr(text, "\"b\"")); /* sorted keys: deterministic files */
	free(text);
	json_t *r = NULL;
	assert_int_equal(tl_json_read(p, &r, err, sizeof err), TL_OK);
	assert_int_equal(json_integer_value(json_object_get(r, "b")), 2);
	json_decref(r);
	/* Malformed, too deep, duplicate keys: input errors naming the file. */
	/* ... and a control character in the quoted input stays out of the one-line message (fuzz_sweep) */
	const char *bad[] = {"{\"a\": }", "{\"a\": 1, \"a\": 2}", "\"\\\n", NULL};
	char deep[400];
	memset(deep, '[', 300);
	deep[300] = 0;
	for (int i = 0; i < 4; i++) {
		FILE *f = fopen(p, "w");
		fputs(bad[i] ? bad[i] : deep, f);
		fclose(f);
		assert_int_equal(tl_json_read(p, &r, err, sizeof err), TL_ERR_INPUT);
		assert_non_null(strstr(err, "x.json"));
		assert_null(strchr(err, '\n'));
	}
	assert_true(tl_clock_s() > 0);
}

/* tl_buf: appends and formatted appends grow the text past the first allocation, byte for byte. */
static void test_buf(void **state)
{
	(void)state;
	tl_buf b = {0};
	assert_int_equal(tl_buf_append(&b, "ab", 1), 0);
	for (int i = 0; i < 3000; i++)
		assert_int_equal(tl_buf_printf(&b, "%03d,", i % 1000), 0);
	assert_false(b.failed);
	assert_int_equal(b.len, 1 + 3000 * 4);
	assert_int_equal(strlen(b.s), b.len);
	assert_memory_equal(b.s, "a000,001,", 9);
	assert_string_equal(b.s + b.len - 4, "999,");
	assert_int_equal(tl_buf_append(&b, "xyz", 2), 0);
	assert_string_equal(b.s + b.len - 6, "999,xy");
	free(b.s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_errors),	   cmocka_unit_test(test_mkdirs), cmocka_unit_test(test_atomic_write),
		cmocka_unit_test(test_atomic_full_disk), cmocka_unit_test(test_clean_temps), cmocka_unit_test(test_paths), cmocka_unit_test(test_parse),
		cmocka_unit_test(test_json), cmocka_unit_test(test_atomic_set), cmocka_unit_test(test_check_out_dir), cmocka_unit_test(test_buf),
	};
	return tu_finish(cmocka_run_group_tests(tests, NULL, NULL));
}
