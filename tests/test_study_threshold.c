/* test_study_threshold.c — the threshold fit, thresholds.csv, the adaptive choice of T and the simulator (issue 28):
 *  - test_fit_vs_r: sty_threshold_fit on three seeded data sets (tests/reference/threshold_data.csv) against an
 *    independent implementation of the same model in R (threshold_reference.R: its own Gauss-Hermite nodes, optim's
 *    L-BFGS-B from four starts, uniroot on the profile; threshold_reference.csv). Tolerances: maximised
 *    log-likelihood 0.01 (both optimisers stop at about 1e-4 of the optimum's size), log2 t_jnd 0.02 octave where
 *    the maximum is unique (set 1; set 2's likelihood has a plateau between two levels: each estimate inside the
 *    other's interval), interval ends 0.03 octave (our bisection stops at 1/64 of its last step); set 3 (t_jnd 200
 *    with levels 2..64) must be inf with an open upper end.
 *  - test_tally_thresholds: a study imported from set 1 and set 3 as two scenes; thresholds.csv has one row per scene
 *    and the pooled row, the scene rows equal to direct fits of the same trials (1e-6), set 3's inf.
 *  - test_adapt: QUEST+ on answers drawn from a known observer puts the next trial at a level next to the threshold,
 *    and its posterior mean near it; a prior moves the first choice.
 *  - test_simulate: small seeded simulations of both designs (coverage, RMSE against wide bounds: 40 studies; the
 *    README's figures come from scripts/bench_thresholds.sh with 500), same seed → same simulation.csv, bad input. */
#define _DEFAULT_SOURCE /* popen (test_study_util.h) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/study_threshold.h"
#include "test_study_util.h"

/* Set `set` of threshold_data.csv (set,participant,T,y). */
static size_t load_set(int set, sty_tobs *o, size_t max)
{
	FILE *f = fopen(REF_DIR "/threshold_data.csv", "r");
	assert_non_null(f);
	char line[256];
	size_t n = 0;
	assert_non_null(fgets(line, sizeof line, f)); /* header */
	while (fgets(line, sizeof line, f)) {
		int s;
		long long p;
		double T, y;
		assert_int_equal(sscanf(line, "%d,%lld,%lf,%lf", &s, &p, &T, &y), 4);
		if (s == set && n < max)
			o[n++] = (sty_tobs){.participant = p, .T = T, .y = y};
	}
	fclose(f);
	return n;
}

static double ref_value(int set, int col)
{
	char k[8];
	snprintf(k, sizeof k, "%d", set);
	const char *key[1] = {k};
	return tu_csv_lookup(REF_DIR "/threshold_reference.csv", key, 1, col);
}

static void test_fit_vs_r(void **state)
{
	(void)state;
	static sty_tobs o[1000];
	char err[256];
	for (int set = 1; set <= 3; set++) {
		size_t n = load_set(set, o, 1000);
		assert_true(n > 50);
		sty_tfit f;
		if (sty_threshold_fit(o, n, &f, err, sizeof err))
			fail_msg("%s", err);
		double theta = ref_value(set, 1), lo = ref_value(set, 2), hi = ref_value(set, 3), ll = ref_value(set, 4);
		printf("set %d: theta %.4f (R %.4f) [%.4f, %.4f] (R [%.4f, %.4f]) loglik %.5f (R %.5f) slope %.3f lapse %.4f "
		       "sd %.3f t_jnd %g [%g, %g]\n", set, f.theta, theta, f.theta_lo, f.theta_hi, lo, hi, f.loglik, ll, f.slope,
		       f.lapse, f.observer_sd, f.t_jnd, f.t_jnd_lo, f.t_jnd_hi);
		assert_true(fabs(f.loglik - ll) <= 0.01);
		if (set < 3) {
			/* set 1: a unique maximum; set 2's is a plateau (slope at 13 per octave: a step between two levels, any
			 * theta between them as likely), so there both estimates must lie inside the other's interval */
			assert_true(set == 1 ? fabs(f.theta - theta) <= 0.02 : theta >= f.theta_lo && theta <= f.theta_hi &&
					       f.theta >= lo && f.theta <= hi);
			assert_true(fabs(f.theta_lo - lo) <= 0.03);
			assert_true(isinf(hi) ? isinf(f.t_jnd_hi) : fabs(f.theta_hi - hi) <= 0.03);
			assert_true(isfinite(f.t_jnd) && f.t_jnd_lo <= f.t_jnd && f.t_jnd <= f.t_jnd_hi);
			assert_true(fabs(log2(f.t_jnd) - f.theta) < 1e-12);
		} else { /* p_ref below 0.75 up to T = 64: inf, and the interval's upper end open */
			assert_true(theta > 6);
			assert_true(isinf(f.t_jnd) && isinf(f.t_jnd_hi));
			assert_true(isinf(lo) ? f.t_jnd_lo == 0 : fabs(log2(f.t_jnd_lo) - lo) <= 0.03);
		}
	}
	/* Bad input is refused with one line. */
	sty_tobs bad[2] = {{1, 8, 1}, {1, 8, 0}};
	sty_tfit f;
	assert_int_equal(sty_threshold_fit(bad, 2, &f, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "at least two"));
	bad[1] = (sty_tobs){1, 16, 0.7};
	assert_int_equal(sty_threshold_fit(bad, 2, &f, err, sizeof err), TL_ERR_ARG);
}

static void test_tally_thresholds(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_threshold");
	char csv[4096], db[4096], res[4096], p[4200], err[1024];
	snprintf(csv, sizeof csv, "%s/ratings.csv", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	snprintf(res, sizeof res, "%s/out", dir);
	static sty_tobs o1[1000], o3[1000];
	size_t n1 = load_set(1, o1, 1000), n3 = load_set(3, o3, 1000);
	FILE *f = fopen(csv, "w");
	fprintf(f, "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms\n");
	/* set 1 as scene calm, set 3 as scene dynamic (other participants); half the trials with the reference first
	 * (answer = -rating), a preference as "slightly" (1) and "much" (2) alternately */
	for (int s = 0; s < 2; s++)
		for (size_t i = 0; i < (s ? n3 : n1); i++) {
			const sty_tobs *t = s ? &o3[i] : &o1[i];
			int r = t->y == 1 ? 1 + (int)(i % 2) : t->y == 0 ? -1 - (int)(i % 2) : 0, rf = (int)(i / 2 % 2);
			fprintf(f, "%s%02lld,%zu,%s,still,stationary,tfr,%g,,%d,%d,%d,1000\n", s ? "Q" : "P", (long long)t->participant,
				i, s ? "dynamic" : "calm", t->T, rf, rf ? -r : r, r);
		}
	fclose(f);
	sty *st = created(db);
	size_t rows;
	if (sty_import_long(st, csv, &rows, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(rows, n1 + n3);
	commit(st);
	sty_tally_desc td = {.out = res, .bootstrap = 10, .seed = 1, .no_plot = true};
	if (sty_tally(st, &td, err, sizeof err))
		fail_msg("%s", err);
	sty_close(&st);
	snprintf(p, sizeof p, "%s/thresholds.csv", res);
	char *text = tu_read_file(p, NULL);
	assert_non_null(text);
	assert_int_equal(tu_count_lines(text), 4); /* header, calm, dynamic, all */
	assert_true(!strncmp(text, "method,period,scene,camera,n,t_jnd,t_jnd_lo,t_jnd_hi,", 52));
	free(text);
	sty_tfit f1, f3;
	assert_int_equal(sty_threshold_fit(o1, n1, &f1, err, sizeof err), TL_OK);
	assert_int_equal(sty_threshold_fit(o3, n3, &f3, err, sizeof err), TL_OK);
	const char *calm[4] = {"tfr", "", "calm", "still"}, *dyn[4] = {"tfr", "", "dynamic", "still"},
		   *all[4] = {"tfr", "", "all", "all"};
	assert_int_equal((int)tu_csv_lookup(p, calm, 4, 4), (int)n1);
	assert_true(fabs(tu_csv_lookup(p, calm, 4, 5) - f1.t_jnd) < 1e-6 * f1.t_jnd);
	assert_true(fabs(tu_csv_lookup(p, calm, 4, 6) - f1.t_jnd_lo) < 1e-6 * f1.t_jnd);
	assert_true(fabs(tu_csv_lookup(p, calm, 4, 7) - f1.t_jnd_hi) < 1e-6 * f1.t_jnd_hi);
	assert_true(isinf(tu_csv_lookup(p, dyn, 4, 5)) && isinf(tu_csv_lookup(p, dyn, 4, 7)));
	assert_true(fabs(tu_csv_lookup(p, dyn, 4, 6) - f3.t_jnd_lo) < 1e-6 * fmax(1, f3.t_jnd_lo));
	assert_int_equal((int)tu_csv_lookup(p, all, 4, 4), (int)(n1 + n3));
	double pooled = tu_csv_lookup(p, all, 4, 5); /* two populations pooled: somewhere above calm's */
	assert_true(pooled > f1.t_jnd);
}

static void test_adapt(void **state)
{
	(void)state;
	const double T[6] = {2, 4, 8, 16, 32, 64};
	sty_adapt *a = sty_adapt_new(T, 6);
	assert_non_null(a);
	size_t first = sty_adapt_choose(a, NULL);
	/* An observer with t_jnd 12, slope 1.5, lapse 0.02 answering with the expected proportions: 40 answers per level
	 * (p * 40 preferences rounded to halves). */
	for (size_t l = 0; l < 6; l++) {
		double p = sty_psychometric(log2(T[l]), log2(12), 1.5, 0.02);
		int k2 = (int)lround(p * 80); /* preferences in halves */
		for (int i = 0; i < 40; i++)
			sty_adapt_update(a, l, 2 * i + 2 <= k2 ? 1 : 2 * i + 1 == k2 ? 0.5 : 0);
	}
	assert_true(fabs(sty_adapt_theta_mean(a) - log2(12)) < 0.2);
	double h[6];
	size_t next = sty_adapt_choose(a, h);
	printf("first choice T=%g, after 240 answers T=%g (expected entropies %.3f %.3f %.3f %.3f %.3f %.3f)\n", T[first],
	       T[next], h[0], h[1], h[2], h[3], h[4], h[5]);
	assert_true(T[next] == 8 || T[next] == 16); /* the levels around the threshold tell most about it */
	assert_true(h[next] < h[0] && h[next] < h[5]);
	sty_adapt_free(&a);
	/* A prior far up (t_jnd ~ 64) moves the first choice up. */
	a = sty_adapt_new(T, 6);
	sty_adapt_prior(a, 6, 0.3);
	assert_true(sty_adapt_choose(a, NULL) > first);
	sty_adapt_free(&a);
	assert_null(a);
}

static void test_simulate(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_simulate");
	char out1[4096], out2[4096], p[4200], err[256];
	snprintf(out1, sizeof out1, "%s/a", dir);
	snprintf(out2, sizeof out2, "%s/b", dir);
	const double T[6] = {2, 4, 8, 16, 32, 64};
	sty_sim_desc d = {.participants = 24, .trials = 6, .T = T, .nlevels = 6, .t_jnd = 12, .observer_sd = 0.5,
			  .slope = 1.5, .lapse = 0.02, .ties = 0.2, .studies = 40, .seed = 1, .out = out1, .quiet = true,
			  .jobs = 3};
	sty_sim_summary full, adaptive, again;
	if (sty_simulate(&d, &full, err, sizeof err))
		fail_msg("%s", err);
	d.adaptive = true;
	d.trials = 3; /* half the trials */
	if (sty_simulate(&d, &adaptive, err, sizeof err))
		fail_msg("%s", err);
	printf("full: RMSE %.3f bias %+.3f coverage %.3f; adaptive (half): RMSE %.3f bias %+.3f coverage %.3f\n",
	       full.rmse_log2, full.bias_log2, full.coverage, adaptive.rmse_log2, adaptive.bias_log2, adaptive.coverage);
	/* 40 studies: a 95% interval covers in 38 +- 1.4 of them; below 32 is a broken interval (p < 1e-3) */
	assert_true(full.coverage >= 0.8 && adaptive.coverage >= 0.8);
	assert_true(full.rmse_log2 < 0.6 && adaptive.rmse_log2 < 0.6);
	assert_int_equal(full.trials_total, 144);
	assert_int_equal(adaptive.trials_total, 72);
	/* the same seed: the same studies, byte for byte. Study k is seeded with seed + k whatever the count, so a replay
	 * of the first 8 studies must equal the first 8 rows (a quarter of the time of a full replay); the runs above
	 * used three threads, the replay one: the rows come in study order whatever the threads */
	d.out = out2;
	d.studies = 8;
	d.jobs = 1;
	if (sty_simulate(&d, &again, err, sizeof err))
		fail_msg("%s", err);
	d.studies = 40;
	snprintf(p, sizeof p, "%s/simulation.csv", out1);
	char *a = tu_read_file(p, NULL);
	snprintf(p, sizeof p, "%s/simulation.csv", out2);
	char *b = tu_read_file(p, NULL);
	assert_non_null(a);
	assert_non_null(b);
	assert_int_equal(tu_count_lines(b), 9);
	assert_int_equal(strncmp(a, b, strlen(b)), 0);
	assert_int_equal(tu_count_lines(a), 41);
	assert_true(!strncmp(a, "study,design,trials,t_jnd_true,t_jnd,t_jnd_lo,t_jnd_hi", 53));
	free(a);
	free(b);
	d.adaptive = false; /* the full design needs every level equally often */
	d.trials = 7;
	assert_int_equal(sty_simulate(&d, &again, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "multiple"));
	tu_expect_cli_error("study simulate --t-levels 2,4,x", "--t-levels");
	tu_expect_cli_error("study simulate --design half", "--design");
	tu_expect_cli_error("study simulate --t-levels 8", "two levels");
	/* seeds: GSL's mt19937 keeps 32 bits, so study k's seed + k must stay below 2^32 (else it repeats a small seed) */
	d.trials = 8;
	d.seed = STY_SEED_MAX;
	d.studies = 2;
	assert_int_equal(sty_simulate(&d, &again, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "--seed 4294967295 with 2 --studies"));
	tu_expect_cli_error("study simulate --seed 4294967296", "--seed");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_fit_vs_r),
		cmocka_unit_test(test_tally_thresholds),
		cmocka_unit_test(test_adapt),
		cmocka_unit_test(test_simulate),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
