/* test_study_design.c — the study database and its design (the rest of the study in the other test_study*.c files):
 *  - randomisation: reproducible from the seed, every pair in both orders (exactly half each for even N)
 *    (test_randomisation);
 *  - new studies built aside and never overwriting (issue 12.5, test_create_refuses);
 *  - design's T/period rule on pairs.json (DESIGN section 4, test_design_period_rule; import's in test_study_csv.c);
 *    studies made before the period column (test_old_study_schema). */
#define _DEFAULT_SOURCE /* popen (test_study_util.h), symlink, link */
#include <math.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "taslab/pairs.h"
#include "taslab/study.h"
#include "test_study_util.h"

static char out[1 << 16];

static char *plan_dump(const char *db)
{
	sqlite3 *h;
	sqlite3_open(db, &h);
	sqlite3_stmt *st;
	sqlite3_prepare_v2(h, "SELECT participant, idx, condition, ref_first, kind, break_before FROM trials ORDER BY 1, 2", -1,
			   &st, NULL);
	size_t cap = 1 << 16, len = 0;
	char *buf = calloc(cap, 1);
	while (sqlite3_step(st) == SQLITE_ROW && len + 64 < cap)
		len += (size_t)snprintf(buf + len, cap - len, "%d %d %d %d %s %d\n", sqlite3_column_int(st, 0),
					sqlite3_column_int(st, 1), sqlite3_column_int(st, 2), sqlite3_column_int(st, 3),
					sqlite3_column_text(st, 4), sqlite3_column_int(st, 5));
	sqlite3_finalize(st);
	sqlite3_close(h);
	return buf;
}

static void test_randomisation(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_design");
	char stim[4096], a[4096], b[4096], c[4096];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s1 = designed(dir, "a.db", 42, 10, &sm), *s2 = designed(dir, "b.db", 42, 10, &sm), *s3 = designed(dir, "c.db", 43, 10, &sm);
	/* 8 test conditions + 4 catch pairs; 1 training + 8 tests + 2 catch trials each. */
	assert_int_equal(sm.conditions, 12);
	assert_int_equal(sm.trials_per_participant, 11);
	assert_true(sm.session_minutes > 11 * 2 / 60.0);
	sty_close(&s1), sty_close(&s2), sty_close(&s3);
	snprintf(a, sizeof a, "%s/a.db", dir);
	snprintf(b, sizeof b, "%s/b.db", dir);
	snprintf(c, sizeof c, "%s/c.db", dir);
	char *pa = plan_dump(a), *pb = plan_dump(b), *pc = plan_dump(c);
	assert_string_equal(pa, pb);          /* same seed, same plan */
	assert_string_not_equal(pa, pc);      /* another seed, another plan */
	/* Balance: each test condition is shown reference-first to exactly half of the 10 participants, and trial
	 * orders differ between participants. */
	sqlite3 *h;
	sqlite3_open(a, &h);
	sqlite3_stmt *st;
	sqlite3_prepare_v2(h, "SELECT condition, sum(ref_first), count(*) FROM trials WHERE kind = 'test' GROUP BY condition", -1,
			   &st, NULL);
	int conds = 0;
	while (sqlite3_step(st) == SQLITE_ROW) {
		assert_int_equal(sqlite3_column_int(st, 2), 10);
		assert_int_equal(sqlite3_column_int(st, 1), 5);
		conds++;
	}
	sqlite3_finalize(st);
	assert_int_equal(conds, 8);
	sqlite3_prepare_v2(h, "SELECT count(DISTINCT o) FROM (SELECT group_concat(condition) AS o FROM"
			      " (SELECT participant, condition FROM trials ORDER BY participant, idx) GROUP BY participant)", -1, &st, NULL);
	assert_int_equal(sqlite3_step(st), SQLITE_ROW);
	assert_true(sqlite3_column_int(st, 0) >= 9); /* 10 participants, (essentially) all orders distinct */
	sqlite3_finalize(st);
	sqlite3_close(h);
	free(pa), free(pb), free(pc);
}

/* Issue 12.5: design/import refuse non-file names and existing databases, build aside and leave nothing behind
 * on failure; design refuses sets whose clips are missing. */
static void test_create_refuses(void **state)
{
	(void)state;
	const char *dir0 = tu_tmpdir("study_create");
	char dir[4096], stim[4096], db[4200], dbs[4200], err[1024], cmd[16384], bad[4200], p[4200];
	snprintf(dir, sizeof dir, "%s", dir0);
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	snprintf(dbs, sizeof dbs, "%s/dbs", dir);
	mkdir(dbs, 0755);
	sty *s = NULL;
	const char *names[] = {"", ":memory:", "file:x.db?mode=memory"};
	for (int i = 0; i < 3; i++) {
		assert_int_equal(sty_create(names[i], &s, err, sizeof err), TL_ERR_ARG);
		assert_null(s);
		assert_int_not_equal(sty_open(names[i], &s, err, sizeof err), 0);
	}
	snprintf(cmd, sizeof cmd, "cd %s && %s study design --db :memory: --stimuli %s --participants 2", dbs, TASLAB_BINARY, stim);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	assert_non_null(strstr(out, "not a file name"));
	assert_null(strstr(out, "conditions"));
	/* A design that fails (a missing clip) leaves nothing, not even a temporary file. */
	snprintf(p, sizeof p, "%s/dyn-walk/clips/tfr-T16.webm", stim);
	assert_int_equal(unlink(p), 0);
	snprintf(db, sizeof db, "%s/a.db", dbs);
	snprintf(cmd, sizeof cmd, "%s study design --db %s --stimuli %s --participants 2", TASLAB_BINARY, db, stim);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	assert_non_null(strstr(out, "tfr-T16.webm does not exist"));
	assert_int_equal(dir_entries(dbs), 0);
	s = created(db);
	sty_design_desc d = {.stimuli = stim, .participants = 2, .seed = 1};
	sty_design_summary sm;
	assert_int_equal(sty_design(s, &d, &sm, err, sizeof err), TL_ERR_INPUT);
	sty_close(&s);
	assert_int_equal(dir_entries(dbs), 0);
	FILE *f = fopen(p, "w");
	fputs("clip tfr-T16 again", f);
	fclose(f);
	/* A failed import leaves nothing either. */
	snprintf(bad, sizeof bad, "%s/bad.csv", dir);
	f = fopen(bad, "w");
	fputs("participant,trial,scene,camera,camera_motion,method,T,ref_first,answer,rating,rt_ms\nP1,0,calm,still,stationary,tfr,8,1,3,-3,5\n", f);
	fclose(f);
	snprintf(cmd, sizeof cmd, "%s study import --db %s %s", TASLAB_BINARY, db, bad);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	assert_int_equal(dir_entries(dbs), 0);
	/* A good design appears; a second design or an import onto it is refused and changes nothing. */
	snprintf(cmd, sizeof cmd, "%s study design --db %s --stimuli %s --participants 2", TASLAB_BINARY, db, stim);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s", out);
	assert_true(tu_file_exists(db));
	char *before = plan_dump(db);
	snprintf(cmd, sizeof cmd, "%s study design --db %s --stimuli %s --participants 3 --seed 9", TASLAB_BINARY, db, stim);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2); /* bad input (issue 27.7: was 1), naming 'study add' */
	assert_non_null(strstr(out, "never overwritten"));
	assert_non_null(strstr(out, "study add"));
	snprintf(cmd, sizeof cmd, "%s study import --db %s %s/study_ratings.csv", TASLAB_BINARY, db, REF_DIR);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	char *after = plan_dump(db);
	assert_string_equal(before, after);
	free(before);
	free(after);
	assert_int_equal(sty_create(db, &s, err, sizeof err), TL_ERR_CONFLICT);
	/* A leftover -wal of a deleted study would be applied to a new one by SQLite: refused. */
	snprintf(p, sizeof p, "%s/b.db-wal", dbs);
	f = fopen(p, "w");
	fputs("stale", f);
	fclose(f);
	snprintf(p, sizeof p, "%s/b.db", dbs);
	assert_int_equal(sty_create(p, &s, err, sizeof err), TL_ERR_CONFLICT);
	assert_non_null(strstr(err, "-wal"));
	/* Uncommitted: closing removes the new study and its temporary files. */
	snprintf(p, sizeof p, "%s/c.db", dbs);
	s = created(p);
	sty_close(&s);
	assert_false(tu_file_exists(p));
	assert_int_equal(dir_entries(dbs), 2); /* a.db, b.db-wal */
}

/* Design applies the import rule to pairs.json: period exactly for rrc and sau (1, 2, 4, 8), T exactly for the
 * methods with a threshold. */
static void test_design_period_rule(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_design_period");
	const struct {
		const char *method;
		double T;
		uint32_t period;
		const char *why;
	} bad[] = {
		{"rrc", NAN, 0, "method rrc needs a period"},   {"sau", NAN, 0, "method sau needs a period"},
		{"tarc", 8, 4, "method tarc has no period"},    {"tarc-oracle", 8, 8, "method tarc-oracle has no period"},
		{"sa", NAN, 2, "method sa has no period"},      {"rrc", NAN, 3, "period 3 is not"},
		{"rrc", NAN, 16, "period 16 is not"},    {"rrc", 8, 4, "method rrc has no threshold"},
		{"tasa", NAN, 0, "method tasa needs a threshold"},
	};
	char err[1024];
	for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
		char stim[4200], p[4300], db[4200];
		snprintf(stim, sizeof stim, "%s/stim%zu", dir, i);
		snprintf(p, sizeof p, "mkdir -p %s", stim);
		assert_int_equal(system(p), 0);
		const char *clips[2] = {"ref.webm", "x.webm"};
		for (int c = 0; c < 2; c++) {
			snprintf(p, sizeof p, "%s/%s", stim, clips[c]);
			FILE *f = fopen(p, "w");
			fputs("clip", f);
			fclose(f);
		}
		pairs_condition c = {.T = bad[i].T, .period = bad[i].period};
		snprintf(c.id, sizeof c.id, "cond%zu", i);
		snprintf(c.method, sizeof c.method, "%s", bad[i].method);
		snprintf(c.variant, sizeof c.variant, "%s", bad[i].method);
		snprintf(c.clip, sizeof c.clip, "x.webm");
		pairs_set set = {.fps = 60, .last_frame = 59, .width = 16, .height = 16, .conditions = &c, .count = 1};
		snprintf(set.scene, sizeof set.scene, "calm");
		snprintf(set.camera, sizeof set.camera, "still");
		snprintf(set.camera_motion, sizeof set.camera_motion, "stationary");
		snprintf(set.ref_clip, sizeof set.ref_clip, "ref.webm");
		snprintf(set.ref_run, sizeof set.ref_run, "runs/ref");
		snprintf(p, sizeof p, "%s/pairs.json", stim);
		if (pairs_write(p, &set, err, sizeof err))
			fail_msg("%s", err);
		snprintf(db, sizeof db, "%s/s%zu.db", dir, i);
		sty *s = created(db);
		sty_design_desc d = {.stimuli = stim, .participants = 2, .seed = 1};
		sty_design_summary sm;
		int rc = sty_design(s, &d, &sm, err, sizeof err);
		char id[32];
		snprintf(id, sizeof id, "'cond%zu'", i);
		if (rc != TL_ERR_INPUT || !strstr(err, bad[i].why) || !strstr(err, id) || strchr(err, '\n'))
			fail_msg("%s T %g period %u: rc %d, '%s' (expected '%s')", bad[i].method, bad[i].T, bad[i].period, rc, err,
				 bad[i].why);
		sty_close(&s);
		assert_false(tu_file_exists(db));
	}
}

/* Studies made before the period column: opened, the column is added (NULL), and they work on; one holding rrc or
 * sau conditions (period never stored) is refused with one line. */
static void test_old_study_schema(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_old_schema");
	char stim[4096], db[4096], err[1024], p[4200], cmd[16384];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	for (int with_rrc = 0; with_rrc < 2; with_rrc++) {
		sty_design_summary sm;
		char name[16];
		snprintf(name, sizeof name, "old%d.db", with_rrc);
		snprintf(db, sizeof db, "%s/%s", dir, name);
		sty *s = designed(dir, name, 5, 2, &sm);
		char **codes;
		size_t n;
		assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
		sty_trial t;
		for (int k = 0; k < 3; k++) {
			assert_int_equal(sty_next_trial(s, codes[0], &t, err, sizeof err), 0);
			assert_int_equal(sty_answer(s, codes[0], t.index, 1, 900, err, sizeof err), 0);
		}
		free_codes(codes, n);
		sty_close(&s);
		/* The conditions table as studies had it before: no period column (an rrc condition in the second). */
		sqlite3 *h;
		assert_int_equal(sqlite3_open(db, &h), SQLITE_OK);
		char *msg = NULL;
		const char *sql = with_rrc ? "ALTER TABLE conditions DROP COLUMN period; UPDATE conditions SET method = 'rrc', T = NULL"
					     " WHERE id = (SELECT min(id) FROM conditions WHERE method = 'tfr')"
					   : "ALTER TABLE conditions DROP COLUMN period";
		if (sqlite3_exec(h, sql, NULL, NULL, &msg) != SQLITE_OK)
			fail_msg("%s", msg);
		sqlite3_close(h);
		assert_int_equal(db_count(db, "SELECT count(*) FROM pragma_table_info('conditions') WHERE name = 'period'"), 0);
		int rc = sty_open(db, &s, err, sizeof err);
		if (with_rrc) {
			assert_int_equal(rc, TL_ERR_INPUT);
			assert_null(s);
			if (!strstr(err, "without a period") || strchr(err, '\n'))
				fail_msg("%s", err);
			snprintf(cmd, sizeof cmd, "%s study export --db %s --out %s/x.csv", TASLAB_BINARY, db, dir);
			assert_int_equal(tu_run(cmd, out, sizeof out), 2);
			if (tu_count_lines(out) != 1 || !strstr(out, "without a period"))
				fail_msg("expected one line, got:\n%s", out);
			continue;
		}
		if (rc)
			fail_msg("%s", err);
		sty_close(&s);
		assert_int_equal(db_count(db, "SELECT count(*) FROM pragma_table_info('conditions') WHERE name = 'period'"), 1);
		snprintf(p, sizeof p, "%s/old.csv", dir);
		snprintf(cmd, sizeof cmd, "%s study export --db %s --out %s && %s study tally --db %s --out %s/t --bootstrap 20",
			 TASLAB_BINARY, db, p, TASLAB_BINARY, db, dir);
		if (tu_run(cmd, out, sizeof out))
			fail_msg("%s", out);
		char *csv = tu_read_file(p, NULL);
		const char *head = "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,";
		assert_int_equal(strncmp(csv, head, strlen(head)), 0);
		free(csv);
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_randomisation),
		cmocka_unit_test(test_create_refuses),
		cmocka_unit_test(test_design_period_rule),
		cmocka_unit_test(test_old_study_schema),
	};
	return tu_finish(cmocka_run_group_tests(tests, NULL, NULL));
}
