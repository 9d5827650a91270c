/* test_study_gold.c — gold trials (issue 28, P.910-crowd screening; README "Telemetry and screening"):
 *  - test_gold_design: `design --gold K` gives every participant K gold trials, each the reference against its set's
 *    strongest degradation (the largest T: tfr@16 in the four test sets) kept apart from the test conditions; with
 *    --gold-variant the named condition; an unknown id and --gold-variant without --gold are one line each; a design
 *    with gold trials plans its test and catch trials as one without them would not have to, but `study add` plans
 *    new participants exactly like `design` would have;
 *  - test_gold_screening: four participants answer hand-made tables (seeded design); observers.csv's rows are worked
 *    out by hand from P.910-crowd's gold rule (a gold answer more than one step from "reference much better" fails)
 *    together with the catch and variance rules; a broken playback's gold answer is not counted; gold answers never
 *    enter the conditions' statistics; `tally --p910` leaves the gold-flagged participant out; export -> import keeps
 *    trial_type gold and gives the same observers.csv. */
#define _DEFAULT_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/study.h"
#include "taslab/study_status.h"
#include "test_study_util.h"

static sty *design_with(const char *dir, const char *name, uint32_t gold, const char *variant, int want_rc)
{
	char db[4200], stim[4200], err[1024] = "";
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/%s", dir, name);
	sty *s = created(db);
	sty_design_desc d = {.stimuli = stim, .participants = 4, .seed = 9, .catch_trials = 1, .gold_trials = gold,
			     .gold_variant = variant};
	sty_design_summary sm;
	int rc = sty_design(s, &d, &sm, err, sizeof err);
	if (rc != want_rc)
		fail_msg("design: rc %d (want %d): %s", rc, want_rc, err);
	if (rc) {
		assert_null(strchr(err, '\n'));
		assert_true(strlen(err) > 10);
		sty_close(&s);
		return NULL;
	}
	commit(s);
	assert_int_equal(sm.trials_per_participant, 8 + 1 + gold);
	return s;
}

static void test_gold_design(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_gold_design");
	char stim[4200], db[4200], q[512];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	sty *s = design_with(dir, "g.db", 2, NULL, TL_OK);
	snprintf(db, sizeof db, "%s/g.db", dir);
	/* one gold condition per set (4), each tfr@16 of its set with the set's reference; 8 test + 4 catch + 4 gold */
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE is_catch = 2"), 4);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE is_catch = 2 AND method = 'tfr' AND T = 16"
				      " AND test_clip LIKE '%/clips/tfr-T16.webm' AND ref_clip LIKE '%/clips/ref.webm'"
				      " AND substr(test_clip, 1, instr(test_clip, '/')) = substr(ref_clip, 1, instr(ref_clip, '/'))"),
			 4);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE is_catch = 0"), 8);
	for (int p = 1; p <= 4; p++) {
		snprintf(q, sizeof q, "SELECT count(*) FROM trials t JOIN conditions c ON c.id = t.condition WHERE"
			 " t.participant = %d AND t.kind = 'gold' AND c.is_catch = 2", p);
		assert_int_equal(db_count(db, q), 2);
		snprintf(q, sizeof q, "SELECT count(*) FROM trials t JOIN conditions c ON c.id = t.condition WHERE"
			 " t.participant = %d AND t.kind = 'test' AND c.is_catch = 0", p);
		assert_int_equal(db_count(db, q), 8);
	}
	/* `study add`: participants 5 and 6 get the plans a design of 6 would have given them, gold trials included */
	uint32_t first = 0;
	char err[1024];
	if (sty_add_participants(s, 2, &first, err, sizeof err))
		fail_msg("%s", err);
	commit(s);
	assert_int_equal(first, 5);
	sty_close(&s);
	char db6[4200];
	snprintf(db6, sizeof db6, "%s/g6.db", dir);
	sty *s6 = created(db6);
	sty_design_desc d6 = {.stimuli = stim, .participants = 6, .seed = 9, .catch_trials = 1, .gold_trials = 2};
	sty_design_summary sm;
	if (sty_design(s6, &d6, &sm, err, sizeof err))
		fail_msg("%s", err);
	commit(s6);
	sty_close(&s6);
	char plan[2][8192];
	for (int k = 0; k < 2; k++) {
		snprintf(q, sizeof q, "SELECT group_concat(idx || ':' || condition || ':' || ref_first || ':' || kind, ' ') FROM"
			 " (SELECT * FROM trials WHERE participant >= 5 ORDER BY participant, idx)");
		sqlite3 *h;
		sqlite3_stmt *st;
		assert_int_equal(sqlite3_open_v2(k ? db6 : db, &h, SQLITE_OPEN_READONLY, NULL), SQLITE_OK);
		assert_int_equal(sqlite3_prepare_v2(h, q, -1, &st, NULL), SQLITE_OK);
		assert_int_equal(sqlite3_step(st), SQLITE_ROW);
		snprintf(plan[k], sizeof plan[k], "%s", (const char *)sqlite3_column_text(st, 0));
		sqlite3_finalize(st);
		sqlite3_close(h);
	}
	assert_non_null(strstr(plan[0], ":gold"));
	assert_string_equal(plan[0], plan[1]);
	/* --gold-variant names the condition; an id no set has, or the option without --gold, is one line */
	s = design_with(dir, "v.db", 1, "tfr-T8", TL_OK);
	snprintf(db, sizeof db, "%s/v.db", dir);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE is_catch = 2 AND T = 8"), 4);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE is_catch = 2"), 4);
	sty_close(&s);
	assert_null(design_with(dir, "x.db", 1, "tfr-T99", TL_ERR_INPUT));
	assert_null(design_with(dir, "y.db", 0, "tfr-T8", TL_ERR_ARG));
}

/* observers.csv of a tally of `s` into dir/name (keep: 0 default, 1 --keep-flagged, 2 --p910); n of tfr@16 calm/still
 * and pooled into n16[0..1]. */
static char *tally_observers(sty *s, const char *dir, const char *name, int keep, double n16[2])
{
	char res[4300], p[4400], err[1024];
	snprintf(res, sizeof res, "%s/%s", dir, name);
	sty_tally_desc td = {.out = res, .bootstrap = 10, .seed = 3, .no_plot = true, .keep_flagged = keep == 1,
			     .p910 = keep == 2};
	if (sty_tally(s, &td, err, sizeof err))
		fail_msg("%s", err);
	snprintf(p, sizeof p, "%s/conditions.csv", res);
	const char *k1[5] = {"tfr", "16", "", "calm", "still"}, *k2[5] = {"tfr", "16", "", "all", "all"};
	n16[0] = tu_csv_lookup(p, k1, 5, 5);
	n16[1] = tu_csv_lookup(p, k2, 5, 5);
	snprintf(p, sizeof p, "%s/observers.csv", res);
	char *obs = tu_read_file(p, NULL);
	assert_non_null(obs);
	return obs;
}

static void test_gold_screening(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_gold_screening");
	char stim[4200], db[4200], q[512], err[1024];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	make_stimuli(stim);
	sty *s = design_with(dir, "s.db", 2, NULL, TL_OK);
	/* Hand-made answers. Gold answers are reference-relative (+2: reference much better; sent as the page would,
	 * by the trial's order); P004's first gold answer comes from a broken playback (not counted). Test answers are
	 * raw: alternately -1, 1 (sample variance 8/7 = 1.1429), P004 1 throughout (variance 0). */
	static const int gold_r[4][2] = {{2, 1}, {2, 0}, {-2, 2}, {-2, 2}};
	static const int catch_a[4] = {0, 1, -2, 0};
	char **codes = NULL;
	size_t ncodes = 0;
	if (sty_participant_codes(s, &codes, &ncodes, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(ncodes, 4);
	int broken_idx = -1;
	for (size_t i = 0; i < ncodes; i++) {
		int g = 0, tests = 0;
		sty_trial t;
		while (!sty_next_trial(s, codes[i], &t, err, sizeof err) && !t.done) {
			int64_t a;
			if (!strcmp(t.kind, "gold")) {
				assert_true(g < 2);
				snprintf(q, sizeof q, "SELECT ref_first FROM trials WHERE participant = %zu AND idx = %u", i + 1, t.index);
				long long rf = db_count(db, q);
				assert_true(rf == 0 || rf == 1);
				if (i == 3 && g == 0)
					broken_idx = (int)t.index;
				a = rf ? -gold_r[i][g] : gold_r[i][g];
				g++;
			} else if (!strcmp(t.kind, "catch")) {
				a = catch_a[i];
			} else {
				assert_string_equal(t.kind, "test");
				a = i == 3 ? 1 : tests % 2 ? 1 : -1;
				tests++;
			}
			if (sty_answer(s, codes[i], t.index, a, 1000, err, sizeof err))
				fail_msg("%s", err);
		}
		assert_int_equal(g, 2);
		assert_int_equal(tests, 8);
	}
	free_codes(codes, ncodes);
	commit(s);
	sty_close(&s);
	/* the server's verdict on P004's first gold answer (what sty_telemetry_store writes for a hidden playback) */
	assert_true(broken_idx >= 0);
	sqlite3 *h;
	assert_int_equal(sqlite3_open(db, &h), SQLITE_OK);
	snprintf(q, sizeof q, "UPDATE answers SET broken = 'hidden' WHERE participant = 4 AND idx = %d", broken_idx);
	assert_int_equal(sqlite3_exec(h, q, NULL, NULL, NULL), SQLITE_OK);
	sqlite3_close(h);
	assert_int_equal(sty_open(db, &s, err, sizeof err), 0);
	/* By hand: P001 gold 2, 1 (both within one step of +2), catch 0: passes. P002 gold 0 is two steps away: gold.
	 * P003 gold -2: gold; its catch answer -2 ("much better" for identical clips): catch, and flagged by the catch
	 * rule (1 of 1 catch answers). P004: the broken -2 left out, gold 2 counted (gold_n 1); straightlining: variance. */
	const char *want = "participant,catch_n,catch_mean_abs_answer,catch_much_better,flagged,broken,rating_variance,p910,"
			   "gold_n,gold_wrong\n"
			   "P001,1,0.0000,0,0,0,1.1429,,2,0\n"
			   "P002,1,1.0000,0,0,0,1.1429,gold,2,1\n"
			   "P003,1,2.0000,1,1,0,1.1429,catch;gold,2,1\n"
			   "P004,1,0.0000,0,0,1,0.0000,variance,1,0\n";
	/* n of tfr@16 calm/still and pooled: one test answer per participant and set (gold answers, which are tfr@16 too,
	 * never count): default leaves out P003 (catch rule), --keep-flagged none, --p910 all but P001 */
	static const double want_n[3][2] = {{3, 12}, {4, 16}, {1, 4}};
	char *obs[3];
	for (int keep = 0; keep < 3; keep++) {
		char name[16];
		double n16[2];
		snprintf(name, sizeof name, "out%d", keep);
		obs[keep] = tally_observers(s, dir, name, keep, n16);
		assert_string_equal(obs[keep], want);
		assert_true(n16[0] == want_n[keep][0]);
		assert_true(n16[1] == want_n[keep][1]);
		free(obs[keep]);
	}
	/* export -> import: trial_type gold survives, and so does the screening */
	char csv[4300], db2[4300];
	snprintf(csv, sizeof csv, "%s/export.csv", dir);
	assert_int_equal(sty_export_long(s, csv, err, sizeof err), 0);
	char *text = tu_read_file(csv, NULL);
	assert_non_null(text);
	size_t golds = 0;
	for (const char *p = text; (p = strstr(p, ",gold,")); p++)
		golds++;
	assert_int_equal(golds, 8);
	free(text);
	snprintf(db2, sizeof db2, "%s/back.db", dir);
	sty *s2 = created(db2);
	size_t rows;
	if (sty_import_long(s2, csv, &rows, err, sizeof err))
		fail_msg("%s", err);
	commit(s2);
	assert_int_equal(db_count(db2, "SELECT count(*) FROM trials WHERE kind = 'gold'"), 8);
	double n16[2];
	char *back = tally_observers(s2, dir, "back", 2, n16);
	assert_string_equal(back, want);
	assert_true(n16[1] == 4);
	free(back);
	sty_close(&s2);
	sty_close(&s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_gold_design),
		cmocka_unit_test(test_gold_screening),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
