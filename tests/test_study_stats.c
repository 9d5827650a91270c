/* test_study_stats.c — the study's statistics against independent references:
 *  - R (tests/reference/study_reference.csv, written by study_reference.R from study_ratings.csv; R is not needed to
 *    run the test): per condition Q and its t.test CI and JND via qnorm (tolerance 1e-6: taslab prints 6 decimals);
 *    rm-ANOVA df, F and p from aov (relative 1e-6), Greenhouse-Geisser epsilon and p from anova.mlm(test =
 *    "Spherical") for every effect (epsilon 1e-4: R prints it with 4 decimals); post hoc paired t.test t (1e-6), p
 *    and Bonferroni p from p.adjust (relative 1e-5: taslab prints 6 significant digits); JOD point estimates (1e-6)
 *    and their 95% percentile-bootstrap interval over participants against R's bootstrap of the same statistic with
 *    its own generator (Monte Carlo tolerance, see JOD_BOOT_TOL);
 *  - observer screening against a hand-made table of catch-trial answers (test_screening): each participant's
 *    catch count, mean |answer|, "much better" count and flag (more than half of the catch answers |a| = 2), and
 *    that flagged observers' ratings leave the tally unless keep_flagged. */
#define _DEFAULT_SOURCE /* popen (test_study_util.h) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/study.h"
#include "test_study_util.h"

/* JOD bootstrap intervals: taslab (GSL's MT19937, seed 3) and R (set.seed(1)) each draw 20000 resamples of the
 * participants; their 2.5/97.5% percentiles differ by Monte Carlo error only. The JOD of a resample takes few values
 * (12 ratings per scene/path row, 72 pooled: p_ref on a grid of 1/24 or 1/144), so the two percentiles land on the
 * same or a neighbouring grid value, up to ~0.2 JOD apart where the steps are widest. Measured over the 28 rows x 2 ends: at
 * most 0.166 (seed 3), 0.155 (seeds 1, 2), 0.166 (seed 7); tolerance 0.25. With 200 resamples instead, 5 of 6 seeds
 * exceed it (up to 0.34): the check tells a converged bootstrap from a short one. */
#define JOD_BOOT_TOL 0.25

/* R's value of `kind` for T and key in the reference CSV (NaN when absent: the caller fails). */
static double r_value(const char *kind, const char *T, const char *key)
{
	const char *rk[3] = {kind, T, key};
	return tu_csv_lookup(REF_DIR "/study_reference.csv", rk, 3, 3);
}

static void check(const char *what, const char *T, const char *key, double got, double want, double tol)
{
	if (isnan(want))
		fail_msg("%s T=%s %s: no R value in study_reference.csv", what, T, key);
	if (!(fabs(want - got) <= tol))
		fail_msg("%s T=%s %s: ours %.9g, R %.9g (tolerance %g)", what, T, key, got, want, tol);
}

static void test_tally_vs_r(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_tally");
	char db[4096], res[4096], err[1024], p[4096];
	snprintf(db, sizeof db, "%s/s.db", dir);
	snprintf(res, sizeof res, "%s/out", dir);
	sty *s = created(db);
	size_t rows;
	if (sty_import_long(s, REF_DIR "/study_ratings.csv", &rows, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(rows, 144);
	commit(s);
	sty_tally_desc td = {.out = res, .bootstrap = 20000, .seed = 3, .no_plot = true};
	if (sty_tally(s, &td, err, sizeof err))
		fail_msg("%s", err);
	sty_close(&s);
	const char *Ts[2] = {"8", "16"}, *scenes[4] = {"calm", "dynamic", "moderate", "all"}, *cams[2] = {"still", "walk"};
	int checked = 0;
	double boot_max = 0;
	for (int t = 0; t < 2; t++)
		for (int sc = 0; sc < 4; sc++)
			for (int c = 0; c < (sc < 3 ? 2 : 1); c++) {
				const char *cam = sc < 3 ? cams[c] : "all";
				char k[64];
				snprintf(k, sizeof k, "%s/%s", scenes[sc], cam);
				const char *ours[5] = {"tfr", Ts[t], "", scenes[sc], cam}; /* tfr has no period */
				snprintf(p, sizeof p, "%s/conditions.csv", res);
				const char *kinds[4] = {"Q", "Q_lo", "Q_hi", "jnd"};
				int cols[4] = {6, 7, 8, 12};
				for (int q = 0; q < 4 && sc < 3; q++, checked++)
					check(kinds[q], Ts[t], k, tu_csv_lookup(p, ours, 5, cols[q]), r_value(kinds[q], Ts[t], k), 1e-6);
				snprintf(p, sizeof p, "%s/jod.csv", res);
				check("jod", Ts[t], k, tu_csv_lookup(p, ours, 5, 5), r_value("jod", Ts[t], k), 1e-6);
				for (int e = 0; e < 2; e++, checked++) {
					double got = tu_csv_lookup(p, ours, 5, 6 + e), want = r_value(e ? "jod_hi" : "jod_lo", Ts[t], k);
					check(e ? "jod_hi" : "jod_lo", Ts[t], k, got, want, JOD_BOOT_TOL);
					boot_max = fmax(boot_max, fabs(got - want));
				}
				checked++;
			}
	snprintf(p, sizeof p, "%s/anova.csv", res);
	const char *effects[3] = {"camera", "scene", "camera:scene"};
	for (int t = 0; t < 2; t++)
		for (int e = 0; e < 3; e++) {
			const char *ours[4] = {"tfr", Ts[t], "", effects[e]};
			const char *kinds[6] = {"df1", "df2", "F", "p", "p_gg", "epsilon_gg"};
			for (int q = 0; q < 6; q++, checked++) {
				double want = r_value(kinds[q], Ts[t], effects[e]);
				check(kinds[q], Ts[t], effects[e], tu_csv_lookup(p, ours, 4, 4 + q), want,
				      q == 5 ? 1e-4 : 1e-6 * fmax(1.0, fabs(want)));
			}
		}
	/* Post hoc: every pair of levels of each factor, in whichever order taslab writes it (R has both). */
	snprintf(p, sizeof p, "%s/posthoc.csv", res);
	const char *levels[2][3] = {{"stationary", "moving", NULL}, {"calm", "dynamic", "moderate"}};
	const char *factors[2] = {"camera", "scene"};
	for (int t = 0; t < 2; t++)
		for (int f = 0; f < 2; f++) {
			int pairs = 0;
			for (int a = 0; a < 3 && levels[f][a]; a++)
				for (int b = 0; b < 3 && levels[f][b]; b++) {
					const char *ours[6] = {"tfr", Ts[t], "", factors[f], levels[f][a], levels[f][b]};
					double tv = tu_csv_lookup(p, ours, 6, 6);
					if (a == b || isnan(tv))
						continue;
					char k[96];
					snprintf(k, sizeof k, "%s/%s/%s", factors[f], levels[f][a], levels[f][b]);
					check("posthoc t", Ts[t], k, tv, r_value("posthoc_t", Ts[t], k), 1e-6);
					check("posthoc df", Ts[t], k, tu_csv_lookup(p, ours, 6, 7), r_value("posthoc_df", Ts[t], k), 1e-9);
					const char *pk[2] = {"posthoc_p", "posthoc_p_bonferroni"};
					for (int q = 0; q < 2; q++) {
						double want = r_value(pk[q], Ts[t], k);
						check(pk[q], Ts[t], k, tu_csv_lookup(p, ours, 6, 8 + q), want, 1e-5 * want);
					}
					checked += 4;
					pairs++;
				}
			assert_int_equal(pairs, f == 0 ? 1 : 3); /* each unordered pair once */
		}
	fprintf(stderr, "%d statistics checked against R (JOD bootstrap ends at most %.4f from R's)\n", checked, boot_max);
}

/* One pair set (calm/still, stationary) with tfr@8 and tfr@16, small files as clips. */
static void make_calm_stimuli(const char *root)
{
	char p[4096];
	snprintf(p, sizeof p, "mkdir -p %s/calm-still/clips", root);
	assert_int_equal(system(p), 0);
	const char *clips[3] = {"ref", "tfr-T8", "tfr-T16"};
	for (int c = 0; c < 3; c++) {
		snprintf(p, sizeof p, "%s/calm-still/clips/%s.webm", root, clips[c]);
		FILE *f = fopen(p, "w");
		fprintf(f, "clip %s: 0123456789abcdefghijklmnopqrstuvwxyz", clips[c]);
		fclose(f);
	}
	snprintf(p, sizeof p, "%s/calm-still/pairs.json", root);
	FILE *f = fopen(p, "w");
	fputs("{\"taslab_pairs\": 1, \"scene\": \"calm\", \"camera\": \"still\", \"camera_motion\": \"stationary\", \"fps\": 60,"
	      " \"frames\": [0, 59], \"reference\": {\"clip\": \"clips/ref.webm\"}, \"conditions\": ["
	      "{\"method\": \"tfr\", \"T\": 8, \"clip\": \"clips/tfr-T8.webm\"},"
	      "{\"method\": \"tfr\", \"T\": 16, \"clip\": \"clips/tfr-T16.webm\"}]}",
	      f);
	fclose(f);
}

/* Observer screening (DESIGN section 7, README "Study"): four participants answer two catch trials (reference
 * against itself) and two test trials each from hand-made tables; the expected observers.csv rows are worked out by
 * hand from the rule "flagged when more than half of the catch answers are much better (|a| = 2)" and the
 * P.910-crowd rules (a catch answer outside -1..1; test answers' variance below 0.1). */
static void test_screening(void **state)
{
	(void)state;
	const char *dir0 = tu_tmpdir("study_screening");
	char dir[4096], stim[4200], db[4200], res[4300], p[4400], err[1024];
	snprintf(dir, sizeof dir, "%s", dir0);
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	make_calm_stimuli(stim);
	sty *s = created(db);
	sty_design_desc dd = {.stimuli = stim, .participants = 4, .seed = 5, .catch_trials = 2};
	sty_design_summary sm;
	if (sty_design(s, &dd, &sm, err, sizeof err))
		fail_msg("%s", err);
	commit(s);
	static const int catch_answers[4][2] = {{2, -2}, {-2, 0}, {0, -1}, {1, 2}};
	static const int test_answers[4][2] = {{1, 1}, {1, 1}, {0, 2}, {-1, 1}};
	/* participant,catch_n,catch_mean_abs_answer,catch_much_better,flagged — by hand from the table above: P001 has
	 * 2 of 2 much better (flagged), P002 exactly half (1 of 2: not more than half, kept). Then broken (none),
	 * rating_variance (sample variance of the two test answers: 0, 0, 2, 2) and the P.910-crowd flags: a catch answer
	 * much better (catch: P001, P002, P004), variance below 0.1 (P001, P002); no gold trials (gold_n, gold_wrong 0). */
	static const char *const expect[4] = {"P001,2,2.0000,2,1,0,0.0000,catch;variance,0,0",
					      "P002,2,1.0000,1,0,0,0.0000,catch;variance,0,0", "P003,2,0.5000,0,0,0,2.0000,,0,0",
					      "P004,2,1.5000,1,0,0,2.0000,catch,0,0"};
	char **codes = NULL;
	size_t ncodes = 0;
	if (sty_participant_codes(s, &codes, &ncodes, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(ncodes, 4);
	for (size_t i = 0; i < ncodes; i++) {
		int k = 0, tests = 0;
		sty_trial t;
		while (!sty_next_trial(s, codes[i], &t, err, sizeof err) && !t.done) {
			int catch_trial = !strcmp(t.kind, "catch");
			if (catch_trial)
				assert_true(k < 2);
			assert_true(catch_trial || tests < 2);
			int64_t a = catch_trial ? catch_answers[i][k++] : test_answers[i][tests];
			tests += !catch_trial;
			if (sty_answer(s, codes[i], t.index, a, 1000, err, sizeof err))
				fail_msg("%s", err);
		}
		assert_int_equal(k, 2);
		assert_int_equal(tests, 2);
		free(codes[i]);
	}
	free(codes);
	/* keep 0: the default (catch rule), 1: --keep-flagged, 2: --p910 (also the P.910-crowd flags left out) */
	for (int keep = 0; keep < 3; keep++) {
		snprintf(res, sizeof res, "%s/out%d", dir, keep);
		sty_tally_desc td = {.out = res, .bootstrap = 10, .seed = 3, .no_plot = true, .keep_flagged = keep == 1,
				     .p910 = keep == 2};
		if (sty_tally(s, &td, err, sizeof err))
			fail_msg("%s", err);
		snprintf(p, sizeof p, "%s/observers.csv", res);
		char *obs = tu_read_file(p, NULL);
		assert_non_null(obs);
		char want[512];
		snprintf(want, sizeof want, "participant,catch_n,catch_mean_abs_answer,catch_much_better,flagged,broken,"
			 "rating_variance,p910,gold_n,gold_wrong\n%s\n%s\n%s\n%s\n", expect[0], expect[1], expect[2], expect[3]);
		assert_string_equal(obs, want);
		free(obs);
		/* The flagged observer's ratings are left out (3 of 4 participants per condition) unless kept; with p910 also
		 * those the P.910-crowd screening flags (P003 alone is left). */
		snprintf(p, sizeof p, "%s/conditions.csv", res);
		const char *Ts[2] = {"8", "16"};
		for (int t = 0; t < 2; t++) {
			const char *key[5] = {"tfr", Ts[t], "", "calm", "still"};
			assert_int_equal((int)tu_csv_lookup(p, key, 5, 5), keep == 1 ? 4 : keep == 2 ? 1 : 3);
		}
	}
	sty_close(&s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_tally_vs_r),
		cmocka_unit_test(test_screening),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
