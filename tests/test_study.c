/* test_study.c — the study command line and its outputs. The study's tests, one file per unit:
 *  - here: `taslab study` design/tally/import/export exit codes and one-line messages (test_cli); no output over the
 *    study's own files and no partial tally (issue 12, test_outputs_not_inputs);
 *  - test_study_csv.c: import/export, import rules, CSV formulas;
 *  - test_study_design.c: randomisation, new studies built aside, design's T/period rule, old schemas;
 *  - test_study_serve.c: the server, crash safety and careless or hostile clients (issue 12); test_study_http.c: slow
 *    and hostile HTTP clients (issue 31);
 *  - test_study_period.c: variants with a period through design, answers, export, import and tally;
 *  - test_study_stats.c: the statistics against R and the observer screening. */
#define _DEFAULT_SOURCE /* popen (test_study_util.h), symlink, link */
#include <math.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "taslab/study.h"
#include "test_study_util.h"

static char out[1 << 16];

static void test_cli(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_cli");
	char cmd[8192];
	snprintf(cmd, sizeof cmd, "%s study design --db %s/x.db --stimuli %s/nowhere --participants 2", TASLAB_BINARY, dir, dir);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	assert_int_equal(tu_count_lines(out), 1);
	snprintf(cmd, sizeof cmd, "%s study tally --db %s/missing.db --out %s/o", TASLAB_BINARY, dir, dir);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	assert_non_null(strstr(out, "no such study database"));
	snprintf(cmd, sizeof cmd, "%s study import --db %s/i.db %s/study_ratings.csv && %s study tally --db %s/i.db --out %s/t "
		 "--bootstrap 50 && %s study export --db %s/i.db --out %s/e.csv", TASLAB_BINARY, dir, REF_DIR, TASLAB_BINARY,
		 dir, dir, TASLAB_BINARY, dir, dir);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s", out);
	snprintf(cmd, sizeof cmd, "%s/t/anova.csv", dir);
	assert_true(tu_file_exists(cmd));
	/* the CLI describes every variant method name of the registry to the study, the -VALUE choices too (rrc-shadow,
	 * rrc-diffuse: rrc --payload), so ratings of them import; a method it does not know is refused */
	snprintf(cmd, sizeof cmd, "%s/payload.csv", dir);
	FILE *f = fopen(cmd, "w");
	assert_non_null(f);
	fprintf(f, "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms\n"
		   "P01,0,calm,still,stationary,rrc-shadow,,4,1,0,0,2000\nP01,1,calm,still,stationary,rrc-diffuse,,8,0,1,1,2100\n");
	fclose(f);
	snprintf(cmd, sizeof cmd, "%s study import --db %s/p.db %s/payload.csv", TASLAB_BINARY, dir, dir);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s", out);
	snprintf(cmd, sizeof cmd, "%s/bogus.csv", dir);
	f = fopen(cmd, "w");
	assert_non_null(f);
	fprintf(f, "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms\n"
		   "P01,0,calm,still,stationary,rrc-specular,,4,1,0,0,2000\n");
	fclose(f);
	snprintf(cmd, sizeof cmd, "study import --db %s/q.db %s/bogus.csv", dir, dir);
	tu_expect_cli_error(cmd, "rrc-specular");
}

/* Issue 12, data loss: no study command writes over the study (export --out S, --pwcmp S, the journal, a symlink or
 * hard link to S, a tally folder where S sits under an output's name), export's two files are checked before either
 * is written, and a tally that fails leaves no output: not an empty folder, not the tables written before a full
 * disk (the full-disk case needs root for a small tmpfs; skipped with a message otherwise). */
static void test_outputs_not_inputs(void **state)
{
	(void)state;
	const char *dir0 = tu_tmpdir("study_outputs");
	char dir[4096], db[4200], p[4300], q[4300], args[16384], cmd[16384];
	snprintf(dir, sizeof dir, "%s", dir0);
	snprintf(db, sizeof db, "%s/s.db", dir);
	snprintf(cmd, sizeof cmd, "%s study import --db %s %s/study_ratings.csv", TASLAB_BINARY, db, REF_DIR);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s", out);
	size_t len0, len1;
	char *before = tu_read_file(db, &len0);
	snprintf(p, sizeof p, "%s/link.db", dir);
	assert_int_equal(symlink("s.db", p), 0);
	snprintf(p, sizeof p, "%s/hard.db", dir);
	assert_int_equal(link(db, p), 0);
	const char *outs[] = {"%s/s.db", "%s/./s.db", "%s/link.db", "%s/hard.db", "%s/s.db-wal", "%s/s.db-shm"};
	for (size_t i = 0; i < sizeof outs / sizeof *outs; i++) {
		snprintf(p, sizeof p, outs[i], dir);
		snprintf(args, sizeof args, "study export --db %s --out %s", db, p);
		tu_expect_cli_error(args, "is the study database");
	}
	/* The database by another name, and --pwcmp: refused before the long file is written. */
	snprintf(args, sizeof args, "study export --db %s/link.db --out %s/s.db", dir, dir);
	tu_expect_cli_error(args, "is the study database");
	snprintf(args, sizeof args, "study export --db %s --out %s/long.csv --pwcmp %s", db, dir, db);
	tu_expect_cli_error(args, "is the study database");
	snprintf(args, sizeof args, "study export --db %s --out %s/both.csv --pwcmp %s/./both.csv", db, dir, dir);
	tu_expect_cli_error(args, "the same file");
	snprintf(p, sizeof p, "%s/long.csv", dir);
	assert_false(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/both.csv", dir);
	assert_false(tu_file_exists(p));
	/* A tally folder holding the study under one of the tally's file names. */
	snprintf(p, sizeof p, "%s/t", dir);
	mkdir(p, 0755);
	snprintf(q, sizeof q, "%s/t/conditions.csv", dir);
	snprintf(cmd, sizeof cmd, "cp %s %s", db, q);
	assert_int_equal(system(cmd), 0);
	snprintf(args, sizeof args, "study tally --db %s --out %s --bootstrap 10", q, p);
	tu_expect_cli_error(args, "is the study database");
	char *copy = tu_read_file(q, &len1);
	assert_true(len1 == len0 && !memcmp(copy, before, len0));
	free(copy);
	assert_int_equal(dir_entries(p), 1);
	char *after = tu_read_file(db, &len1);
	assert_true(len1 == len0 && !memcmp(after, before, len0));
	free(after);
	free(before);
	/* A tally that fails (a study without answers) leaves no folder behind. */
	snprintf(q, sizeof q, "%s/empty.db", dir);
	sty *s = created(q);
	commit(s);
	sty_close(&s);
	snprintf(args, sizeof args, "study tally --db %s --out %s/none --bootstrap 10", q, dir);
	tu_expect_cli_error(args, "no answered test trials");
	snprintf(p, sizeof p, "%s/none", dir);
	assert_false(tu_file_exists(p));
	/* A full disk halfway through: none of the tables appear. */
	snprintf(p, sizeof p, "%s/full", dir);
	mkdir(p, 0755);
	snprintf(cmd, sizeof cmd, "mount -t tmpfs -o size=8k tmpfs %s 2>/dev/null", p);
	if (!tu_require(geteuid() == 0 && system(cmd) == 0,
			"test_outputs_not_inputs: a tally on a full disk (needs root to mount an 8 KiB tmpfs on %s)", p))
		return;
	snprintf(cmd, sizeof cmd, "%s study tally --db %s --out %s/t --bootstrap 10", TASLAB_BINARY, db, p);
	int st = tu_run(cmd, out, sizeof out);
	int entries = dir_entries(p);
	snprintf(cmd, sizeof cmd, "umount %s", p);
	assert_int_equal(system(cmd), 0);
	if (st == 0 || tu_count_lines(out) != 1 || !strstr(out, "No space"))
		fail_msg("tally on a full disk: exit %d, printed:\n%s", st, out);
	assert_int_equal(entries, 0);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_cli),
		cmocka_unit_test(test_outputs_not_inputs),
	};
	return tu_finish(cmocka_run_group_tests(tests, NULL, NULL));
}
