/* test_study_facts.c — issue 30.1: the study module knows no method by name. A design takes what it needs of a
 * method (reference, T, period) from pairs.json's method_facts and reference.method, so a method the study has never
 * heard of is accepted as the file describes it and a condition contradicting its facts is refused; import checks a
 * ratings file against the methods the caller describes (sty_describe_method; `taslab study` describes its
 * registry), and the pwcmp export names the reference by the described reference's name. */
#include <math.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/pairs.h"
#include "taslab/study.h"
#include "test_study_util.h"

/* A set in DIR: ref.webm and x.webm, one condition of method `method` (facts `f`, NULL: none written) with T and
 * period; the reference's method "ref" when `ref_method`. */
static void write_set(const char *dir, const char *method, const run_method_facts *f, double T, uint32_t period,
		      bool ref_method)
{
	char p[4300], err[1024];
	snprintf(p, sizeof p, "mkdir -p %s", dir);
	assert_int_equal(system(p), 0);
	const char *clips[2] = {"ref.webm", "x.webm"};
	for (int c = 0; c < 2; c++) {
		snprintf(p, sizeof p, "%s/%s", dir, clips[c]);
		FILE *fp = fopen(p, "w");
		fputs("clip", fp);
		fclose(fp);
	}
	pairs_condition c = {.T = T, .period = period};
	if (f)
		c.facts = *f;
	snprintf(c.id, sizeof c.id, "cond-%s", method);
	snprintf(c.method, sizeof c.method, "%s", method);
	snprintf(c.variant, sizeof c.variant, "%s", method);
	snprintf(c.clip, sizeof c.clip, "x.webm");
	pairs_set set = {.fps = 60, .last_frame = 59, .width = 16, .height = 16, .conditions = &c, .count = 1};
	snprintf(set.scene, sizeof set.scene, "calm");
	snprintf(set.camera, sizeof set.camera, "still");
	snprintf(set.camera_motion, sizeof set.camera_motion, "stationary");
	snprintf(set.ref_clip, sizeof set.ref_clip, "ref.webm");
	snprintf(set.ref_run, sizeof set.ref_run, "runs/ref");
	if (ref_method)
		snprintf(set.ref_method, sizeof set.ref_method, "ref");
	snprintf(p, sizeof p, "%s/pairs.json", dir);
	if (pairs_write(p, &set, err, sizeof err))
		fail_msg("%s", err);
}

static int count(const char *db, const char *sql)
{
	sqlite3 *h;
	sqlite3_stmt *st;
	assert_int_equal(sqlite3_open_v2(db, &h, SQLITE_OPEN_READONLY, NULL), SQLITE_OK);
	assert_int_equal(sqlite3_prepare_v2(h, sql, -1, &st, NULL), SQLITE_OK);
	int n = sqlite3_step(st) == SQLITE_ROW ? sqlite3_column_int(st, 0) : -1;
	sqlite3_finalize(st);
	sqlite3_close(h);
	return n;
}

/* A study that was told of no method (sty_create alone): everything comes from the files. */
static sty *bare(const char *db)
{
	char err[1024];
	sty *s = NULL;
	if (sty_create(db, &s, err, sizeof err))
		fail_msg("%s", err);
	return s;
}

static void test_design_from_files(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_facts_design");
	char stim[4200], db[4200], err[1024];
	run_method_facts warp = {.known = true, .family = "reprojection", .baseline = "ref", .takes_threshold = true};
	/* "warp" is no method of taslab's: the file's facts make it a condition with a threshold; catch trials use the
	 * reference's method named by the file. */
	snprintf(stim, sizeof stim, "%s/ok", dir);
	write_set(stim, "warp", &warp, 8, 0, true);
	snprintf(db, sizeof db, "%s/ok.db", dir);
	sty *s = bare(db);
	sty_design_desc d = {.stimuli = stim, .participants = 2, .seed = 1, .catch_trials = 1};
	sty_design_summary sm;
	if (sty_design(s, &d, &sm, err, sizeof err))
		fail_msg("%s", err);
	commit(s);
	sty_close(&s);
	assert_int_equal(count(db, "SELECT count(*) FROM conditions WHERE method = 'warp' AND T = 8 AND NOT is_catch"), 1);
	assert_int_equal(count(db, "SELECT count(*) FROM conditions WHERE method = 'ref' AND is_catch"), 1);
	/* Conditions that contradict their facts are refused, naming the condition. */
	const struct {
		const char *method;
		run_method_facts f;
		double T;
		uint32_t period;
		const char *why;
	} bad[] = {
		{"warp", warp, NAN, 0, "method warp needs a threshold"},
		{"warp", warp, 8, 4, "method warp has no period"},
		{"stu", {.known = true, .family = "reprojection", .baseline = "ref", .takes_period = true}, 8, 4,
		 "method stu has no threshold"},
		{"stu", {.known = true, .family = "reprojection", .baseline = "ref", .takes_period = true}, NAN, 0,
		 "method stu needs a period"},
		{"warp", {.known = false}, 8, 0, "is not one of"}, /* no facts in the file, none described */
	};
	for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
		snprintf(stim, sizeof stim, "%s/bad%zu", dir, i);
		write_set(stim, bad[i].method, bad[i].f.known ? &bad[i].f : NULL, bad[i].T, bad[i].period, true);
		snprintf(db, sizeof db, "%s/bad%zu.db", dir, i);
		s = bare(db);
		d.stimuli = stim;
		int rc = sty_design(s, &d, &sm, err, sizeof err);
		if (rc != TL_ERR_INPUT || !strstr(err, bad[i].why) || !strstr(err, "'cond-"))
			fail_msg("%s: rc %d, '%s' (expected '%s')", bad[i].method, rc, err, bad[i].why);
		sty_close(&s);
	}
	/* A set from before reference.method cannot add catch trials: make it again. */
	snprintf(stim, sizeof stim, "%s/old", dir);
	write_set(stim, "warp", &warp, 8, 0, false);
	snprintf(db, sizeof db, "%s/old.db", dir);
	s = bare(db);
	d.stimuli = stim;
	assert_int_not_equal(sty_design(s, &d, &sm, err, sizeof err), 0);
	assert_non_null(strstr(err, "taslab pair"));
	sty_close(&s);
}

static void test_import_described(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_facts_import");
	char csv[4200], db[4200], pw[4200], err[1024];
	snprintf(csv, sizeof csv, "%s/r.csv", dir);
	FILE *f = fopen(csv, "w");
	fputs("participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms\n"
	      "P0,0,calm,still,stationary,warp,8,,1,1,-1,5\nP0,1,calm,still,stationary,tfr,8,,0,1,1,5\n", f);
	fclose(f);
	/* Not described: refused. */
	snprintf(db, sizeof db, "%s/a.db", dir);
	sty *s = created(db);
	size_t n;
	assert_int_equal(sty_import_long(s, csv, &n, err, sizeof err), TL_ERR_INPUT);
	assert_non_null(strstr(err, "method 'warp' is not one of"));
	sty_close(&s);
	/* Described by the caller (as `taslab study` describes its registry): imported, and the rule applies. */
	run_method_facts warp = {.known = true, .family = "reprojection", .baseline = "ref", .takes_threshold = true};
	snprintf(db, sizeof db, "%s/b.db", dir);
	s = created(db);
	assert_int_equal(sty_describe_method(s, "warp", &warp, err, sizeof err), TL_OK);
	assert_non_null(sty_method_facts(s, "warp"));
	if (sty_import_long(s, csv, &n, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(n, 2);
	/* pwcmp names the reference by the described reference's name */
	snprintf(pw, sizeof pw, "%s/pw.csv", dir);
	assert_int_equal(sty_export_pwcmp(s, pw, err, sizeof err), TL_OK);
	char *text = tu_read_file(pw, NULL);
	assert_non_null(strstr(text, "P0,calm/still,ref,warp_T8,0\n"));
	free(text);
	sty_close(&s);
	f = fopen(csv, "w");
	fputs("participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms\n"
	      "P0,0,calm,still,stationary,warp,,,1,1,-1,5\n", f);
	fclose(f);
	snprintf(db, sizeof db, "%s/c.db", dir);
	s = created(db);
	assert_int_equal(sty_describe_method(s, "warp", &warp, err, sizeof err), TL_OK);
	assert_int_equal(sty_import_long(s, csv, &n, err, sizeof err), TL_ERR_INPUT);
	assert_non_null(strstr(err, "method warp needs a threshold"));
	sty_close(&s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_design_from_files),
		cmocka_unit_test(test_import_described),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
