/* test_study_period.c — variants with a period (DESIGN section 4) through the whole study: rrc/4, rrc/8 and tarc@8
 * stay distinct conditions through design, answers, export, import and tally (test_period_conditions). Design's and
 * import's T/period rules are in test_study_design.c and test_study_csv.c. */
#define _DEFAULT_SOURCE /* popen (test_study_util.h), symlink, link */
#include <math.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "taslab/study.h"
#include "taslab/pairs.h"
#include "test_study_util.h"

/* The variants of the period tests: rrc/4 and rrc/8 differ only by period, tarc@8 has a threshold. `base` is the
 * reference-relative rating the simulated participants give (plus 0 or 1, see period_rating). */
static const struct {
	const char *id, *method, *variant;
	double T;
	uint32_t period;
	int base;
} period_variants[3] = {
	{"rrc-N4", "rrc", "rrc/4", NAN, 4, -1}, {"rrc-N8", "rrc", "rrc/8", NAN, 8, 1}, {"tarc-T8", "tarc", "tarc@8", 8, 0, 0}};

/* Participant p's rating of variant v in set k: base + (p + k) % 2, so each participant's mean over the two sets is
 * base + 0.5 (pooled Q: rrc/4 -0.5, rrc/8 1.5, tarc@8 0.5; rrc/4 and rrc/8 merged would give 0.5). */
static int period_rating(int v, int p, int k) { return period_variants[v].base + (p + k) % 2; }

/* Two sets of scene calm (path still: stationary, walk: moving), each with rrc/4, rrc/8 and tarc@8, written by the
 * pairs.json writer `taslab pair` uses; small files as clips. */
static void make_period_stimuli(const char *root)
{
	const char *sets[2][3] = {{"calm-still", "still", "stationary"}, {"calm-walk", "walk", "moving"}};
	char p[4096], err[1024];
	for (int k = 0; k < 2; k++) {
		snprintf(p, sizeof p, "mkdir -p %s/%s/clips", root, sets[k][0]);
		assert_int_equal(system(p), 0);
		pairs_condition c[3];
		memset(c, 0, sizeof c);
		for (int v = 0; v <= 3; v++) {
			const char *id = v < 3 ? period_variants[v].id : "ref";
			snprintf(p, sizeof p, "%s/%s/clips/%s.webm", root, sets[k][0], id);
			FILE *f = fopen(p, "w");
			fprintf(f, "clip %s of %s", id, sets[k][0]);
			fclose(f);
			if (v == 3)
				break;
			snprintf(c[v].id, sizeof c[v].id, "%s", id);
			snprintf(c[v].method, sizeof c[v].method, "%s", period_variants[v].method);
			snprintf(c[v].variant, sizeof c[v].variant, "%s", period_variants[v].variant);
			c[v].T = period_variants[v].T;
			c[v].period = period_variants[v].period;
			snprintf(c[v].clip, sizeof c[v].clip, "clips/%s.webm", id);
		}
		pairs_set set = {.fps = 60, .first_frame = 0, .last_frame = 59, .width = 16, .height = 16, .conditions = c,
				 .count = 3};
		snprintf(set.scene, sizeof set.scene, "calm");
		snprintf(set.camera, sizeof set.camera, "%s", sets[k][1]);
		snprintf(set.camera_motion, sizeof set.camera_motion, "%s", sets[k][2]);
		snprintf(set.ref_clip, sizeof set.ref_clip, "clips/ref.webm");
		snprintf(set.ref_run, sizeof set.ref_run, "runs/ref");
		snprintf(p, sizeof p, "%s/%s/pairs.json", root, sets[k][0]);
		if (pairs_write(p, &set, err, sizeof err))
			fail_msg("%s", err);
	}
}

/* Lines of `text` containing `needle`. */
static int count_lines_with2(const char *text, const char *needle, const char *also)
{
	int n = 0;
	for (const char *l = text; l && *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : NULL) {
		const char *e = strchr(l, '\n'), *hit = strstr(l, needle), *hit2 = also ? strstr(l, also) : l;
		n += hit && (!e || hit < e) && hit2 && (!e || hit2 < e);
	}
	return n;
}

static int count_lines_with(const char *text, const char *needle) { return count_lines_with2(text, needle, NULL); }

/* The first line of a file. */
static void first_line(const char *path, char *line, size_t n)
{
	FILE *f = fopen(path, "r");
	line[0] = 0;
	if (f && fgets(line, (int)n, f))
		line[strcspn(line, "\n")] = 0;
	if (f)
		fclose(f);
}

/* Checks a tally of the period study in `res`: one row per variant (rrc/4 and rrc/8 apart) in conditions.csv with
 * the expected pooled Q, an ANOVA, post hoc and JOD row per variant, and period right after T in every CSV. */
static void check_period_tally(const char *res)
{
	char p[4200], line[512];
	const char *heads[6][2] = {
		{"conditions.csv", "method,T,period,scene,camera,n,Q,Q_lo,Q_hi,p_ref,p_ref_lo,p_ref_hi,jnd"},
		{"anova.csv", "method,T,period,effect,df1,df2,F,p,p_gg,epsilon_gg,note"},
		{"posthoc.csv", "method,T,period,factor,level_1,level_2,t,df,p,p_bonferroni"},
		{"jod.csv", "method,T,period,scene,camera,jod,jod_lo,jod_hi,participants"},
		{"fig3.csv", "method,T,period,Q,Q_lo,Q_hi,p_ref_percent,p_ref_lo_percent,p_ref_hi_percent"},
		{"observers.csv", "participant,catch_n,catch_mean_abs_answer,catch_much_better,flagged,broken,rating_variance,p910,"
				  "gold_n,gold_wrong"},
	};
	for (int i = 0; i < 6; i++) {
		snprintf(p, sizeof p, "%s/%s", res, heads[i][0]);
		first_line(p, line, sizeof line);
		assert_string_equal(line, heads[i][1]);
	}
	const char *keys[3][3] = {{"rrc", "", "4"}, {"rrc", "", "8"}, {"tarc", "8", ""}};
	for (int v = 0; v < 3; v++) {
		const char *pooled[5] = {keys[v][0], keys[v][1], keys[v][2], "all", "all"};
		const char *still[5] = {keys[v][0], keys[v][1], keys[v][2], "calm", "still"};
		const char *effect[4] = {keys[v][0], keys[v][1], keys[v][2], "camera"};
		snprintf(p, sizeof p, "%s/conditions.csv", res);
		double Q = tu_csv_lookup(p, pooled, 5, 6), n = tu_csv_lookup(p, pooled, 5, 5);
		if (!(fabs(Q - (period_variants[v].base + 0.5)) < 1e-9) || n != 8)
			fail_msg("%s: pooled Q %g over %g ratings, expected %g over 8", period_variants[v].variant, Q, n,
				 period_variants[v].base + 0.5);
		assert_true(tu_csv_lookup(p, still, 5, 5) == 4);
		snprintf(p, sizeof p, "%s/anova.csv", res);
		assert_true(tu_csv_lookup(p, effect, 4, 4) == 1); /* df1 of Camera: its own ANOVA per variant */
		snprintf(p, sizeof p, "%s/posthoc.csv", res);
		assert_false(isnan(tu_csv_lookup(p, effect, 4, 8)));
		snprintf(p, sizeof p, "%s/jod.csv", res);
		assert_false(isnan(tu_csv_lookup(p, pooled, 5, 5)));
	}
	snprintf(p, sizeof p, "%s/conditions.csv", res);
	char *csv = tu_read_file(p, NULL);
	assert_int_equal(tu_count_lines(csv), 1 + 3 * 3); /* per variant: 2 sets + pooled */
	free(csv);
	snprintf(p, sizeof p, "%s/anova.csv", res);
	csv = tu_read_file(p, NULL);
	assert_int_equal(tu_count_lines(csv), 1 + 3);
	free(csv);
	snprintf(p, sizeof p, "%s/conditions.json", res);
	csv = tu_read_file(p, NULL);
	assert_non_null(strstr(csv, "\"period\": 4"));
	assert_non_null(strstr(csv, "\"period\": 8"));
	free(csv);
}

/* rrc/4, rrc/8 and tarc@8 in one set are distinct conditions from design through answers, export, import and
 * tally (DESIGN section 4: T and period their own columns). */
static void test_period_conditions(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_period");
	char stim[4096], db[4096], db2[4096], err[1024], exp[4200], exp2[4200], pw[4200], res[4200], res2[4200];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	snprintf(db2, sizeof db2, "%s/imported.db", dir);
	make_period_stimuli(stim);
	/* Design: 3 variants x 2 sets, plus the 2 catch pairs; the period stored as given, NULL for the others. */
	sty *s = created(db);
	sty_design_desc d = {.stimuli = stim, .participants = 4, .seed = 11, .training = 1, .catch_trials = 2};
	sty_design_summary sm;
	if (sty_design(s, &d, &sm, err, sizeof err))
		fail_msg("%s", err);
	commit(s);
	assert_int_equal(sm.conditions, 8);
	assert_int_equal(sm.trials_per_participant, 1 + 6 + 2);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE method = 'rrc' AND T IS NULL AND period = 4"), 2);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE method = 'rrc' AND T IS NULL AND period = 8"), 2);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE method = 'tarc' AND T = 8 AND period IS NULL"), 2);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE method = 'ref' AND is_catch AND period IS NULL"), 2);
	assert_int_equal(db_count(db, "SELECT count(DISTINCT method || '/' || ifnull(T, '') || '/' || ifnull(period, '') || '/'"
				      " || camera) FROM conditions WHERE NOT is_catch"), 6);
	/* Answers: the simulated participants tell the clips apart by what they serve (sty_clip_file). */
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	assert_int_equal(n, 4);
	for (size_t pi = 0; pi < n; pi++) {
		sty_trial t;
		for (;;) {
			assert_int_equal(sty_next_trial(s, codes[pi], &t, err, sizeof err), 0);
			if (t.done)
				break;
			char a[4096], b[4096];
			assert_int_equal(sty_clip_file(s, t.clip_a, a, sizeof a, err, sizeof err), 0);
			assert_int_equal(sty_clip_file(s, t.clip_b, b, sizeof b, err, sizeof err), 0);
			int ref_first = strstr(a, "/ref.webm") != NULL, answer = 0;
			const char *test = ref_first ? b : a;
			if (!strcmp(t.kind, "test")) {
				int v = 0;
				while (v < 3 && !strstr(test, period_variants[v].id))
					v++;
				assert_true(v < 3);
				int r = period_rating(v, (int)pi, strstr(test, "calm-walk") != NULL);
				answer = ref_first ? -r : r;
			}
			assert_int_equal(sty_answer(s, codes[pi], t.index, answer, 800, err, sizeof err), 0);
		}
	}
	free_codes(codes, n);
	/* Export: T and period in their own columns; 4 participants x 2 sets per variant. */
	snprintf(exp, sizeof exp, "%s/ratings.csv", dir);
	snprintf(pw, sizeof pw, "%s/pwcmp.csv", dir);
	assert_int_equal(sty_export_long(s, exp, err, sizeof err), 0);
	assert_int_equal(sty_export_pwcmp(s, pw, err, sizeof err), 0);
	char *csv = tu_read_file(exp, NULL);
	const char *head = "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms,"
			   "trial_type,answered_at,completed,play_a_ms,play_b_ms,dropped_frames,total_frames,hidden,hidden_ms,"
			   "hidden_play,fullscreen,broken,retake_of\n";
	assert_int_equal(strncmp(csv, head, strlen(head)), 0);
	/* every answered trial (issue 27.9): 6 test, 2 catch and 1 training trial per participant, all completed */
	assert_int_equal(tu_count_lines(csv), 1 + 4 * 9);
	assert_int_equal(count_lines_with(csv, ",test,"), 4 * 6);
	assert_int_equal(count_lines_with(csv, ",catch,"), 4 * 2);
	assert_int_equal(count_lines_with(csv, ",training,"), 4);
	assert_int_equal(count_lines_with(csv, "Z,1,,,,,,,,,,\n"), 4 * 9); /* no telemetry: sty_answer */
	assert_int_equal(count_lines_with2(csv, ",rrc,,4,", ",test,"), 8);
	assert_int_equal(count_lines_with2(csv, ",rrc,,8,", ",test,"), 8);
	assert_int_equal(count_lines_with2(csv, ",tarc,8,,", ",test,"), 8);
	free(csv);
	char *pwc = tu_read_file(pw, NULL);
	assert_true(count_lines_with(pwc, ",rrc_N4,") + count_lines_with(pwc, ",rrc_N4\n") >= 8);
	assert_true(count_lines_with(pwc, "rrc_N8,") >= 8);
	assert_true(count_lines_with(pwc, "tarc_T8,") >= 8);
	assert_int_equal(count_lines_with(pwc, ",rrc,"), 0);
	free(pwc);
	snprintf(res, sizeof res, "%s/tally", dir);
	sty_tally_desc td = {.out = res, .bootstrap = 50, .seed = 1, .no_plot = true};
	if (sty_tally(s, &td, err, sizeof err))
		fail_msg("%s", err);
	sty_close(&s);
	check_period_tally(res);
	/* Import of the export: the same conditions and the same bytes back, and the same statistics. */
	s = created(db2);
	size_t rows;
	if (sty_import_long(s, exp, &rows, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(rows, 36);
	commit(s);
	assert_int_equal(db_count(db2, "SELECT count(*) FROM conditions"), 8); /* with the two catch pairs */
	assert_int_equal(db_count(db2, "SELECT count(*) FROM trials WHERE kind = 'catch'"), 8);
	assert_int_equal(db_count(db2, "SELECT count(*) FROM answers WHERE at LIKE '20%Z'"), 36);
	assert_int_equal(db_count(db2, "SELECT count(DISTINCT ifnull(period, 0)) FROM conditions WHERE method = 'rrc'"), 2);
	snprintf(exp2, sizeof exp2, "%s/ratings2.csv", dir);
	assert_int_equal(sty_export_long(s, exp2, err, sizeof err), 0);
	char *x1 = tu_read_file(exp, NULL), *x2 = tu_read_file(exp2, NULL);
	assert_string_equal(x1, x2);
	free(x1), free(x2);
	snprintf(res2, sizeof res2, "%s/tally2", dir);
	td.out = res2;
	if (sty_tally(s, &td, err, sizeof err))
		fail_msg("%s", err);
	sty_close(&s);
	check_period_tally(res2);
	/* the screening too: the catch trials came along (issue 27.9) */
	const char *same[3] = {"conditions.csv", "anova.csv", "observers.csv"};
	for (int i = 0; i < 3; i++) {
		char pa[4300], pb[4300];
		snprintf(pa, sizeof pa, "%s/%s", res, same[i]);
		snprintf(pb, sizeof pb, "%s/%s", res2, same[i]);
		x1 = tu_read_file(pa, NULL), x2 = tu_read_file(pb, NULL);
		assert_string_equal(x1, x2);
		free(x1), free(x2);
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_period_conditions),
	};
	return tu_finish(cmocka_run_group_tests(tests, NULL, NULL));
}
