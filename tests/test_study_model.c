/* test_study_model.c — the metric-to-JND model (issue 28; study_model.c, `taslab study model`):
 *  - test_isotonic / test_t_at: the pool-adjacent-violators fit and the threshold of a clip series against values
 *    computed by hand (exact to 1e-12);
 *  - test_model_simulated: a simulated study whose thresholds follow a metric. Eight rated scenes: a clip's metric is
 *    c_s * T^0.8 (summary.csv of a sweep written here) and scene s's median observer has t_jnd_s where the metric
 *    reaches M_STAR = 0.05, i.e. t_jnd_s = (M_STAR / c_s)^(1/0.8), the reference values of this test (closed form of
 *    the generator, independent of the model's code); 24 simulated observers (log2 threshold SD 0.5, probit slope 1.5,
 *    lapse 0.02, 20% ties at chance) rate every T = 2..64 of every scene; the ratings are imported and tallied as
 *    `study import` / `study tally` do. Targets: the leave-one-scene-out RMSE of log2 t_jnd against the tally's
 *    measured thresholds <= 0.5 (issue 28), the metric at 1 JND within 2^(0.5 * 0.8) of M_STAR, and for four scenes
 *    nobody rated (a second sweep) the predicted t_jnd within 0.5 octave of the true one, its 95% interval holding it;
 *  - test_model_simulated also predicts again from the saved model.json (`study model --model --predict`, no refit):
 *    the predictions file is byte-identical to the fit's, and --out's copy holds the same predictions;
 *  - test_model_bad_input: a missing jod.csv and an unknown metric column are one line each (exit-2 codes); a model
 *    file that is not JSON, an old one (no "format"), a malformed member, --model with --sweep or without --predict:
 *    one line, exit 2. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/study.h"
#include "taslab/study_model.h"
#include "taslab/study_threshold.h"
#include "test_study_util.h"

#define M_STAR 0.05
#define K_EXP 0.8
#define NLEV 6
static const double LEVELS[NLEV] = {2, 4, 8, 16, 32, 64};

static void test_isotonic(void **state)
{
	(void)state;
	/* (0, 2, 1, 3) equal weights: 2 and 1 pool to 1.5; (3, 1) with weights (1, 3): (3 + 3) / 4 = 1.5 */
	double y[] = {0, 2, 1, 3}, w[] = {1, 1, 1, 1}, f[4];
	sty_isotonic(y, w, 4, f);
	double want[] = {0, 1.5, 1.5, 3};
	for (int i = 0; i < 4; i++)
		assert_true(fabs(f[i] - want[i]) < 1e-12);
	double y2[] = {3, 1, 2}, w2[] = {1, 3, 1}, f2[3];
	sty_isotonic(y2, w2, 3, f2); /* 3,1 -> 1.5 (w 4); then 2 > 1.5 stays */
	assert_true(fabs(f2[0] - 1.5) < 1e-12 && fabs(f2[1] - 1.5) < 1e-12 && fabs(f2[2] - 2) < 1e-12);
}

static void test_t_at(void **state)
{
	(void)state;
	double T[] = {2, 4, 8}, m[] = {0.005, 0.01, 0.04};
	/* 0.02 lies halfway between 0.01 and 0.04 in log2: T = 2^(2 + 0.5) */
	assert_true(fabs(sty_model_t_at(T, m, 3, 0.02) - exp2(2.5)) < 1e-12);
	assert_true(sty_model_t_at(T, m, 3, 0.001) == 0);       /* above at the smallest T */
	assert_true(isinf(sty_model_t_at(T, m, 3, 0.5)));       /* never reached */
}

/* splitmix64 and a normal deviate: the simulated observers */
static uint64_t rng_state;
static double uniform(void)
{
	uint64_t z = (rng_state += 0x9e3779b97f4a7c15ULL);
	z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
	z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
	z ^= z >> 31;
	return ((double)(z >> 11) + 0.5) / 9007199254740992.0;
}
static double normal(void) { return sqrt(-2 * log(uniform())) * cos(6.283185307179586 * uniform()); }

/* scene s's true log2 threshold: rated scenes 0..7 spread over 2.3..5.1 octaves, unrated 100.. between them */
static double true_log2_t(int s) { return s < 100 ? 2.3 + 0.4 * s : 2.5 + 0.7 * (s - 100); }
static double metric_of(int s, double T) { return M_STAR * pow(T / exp2(true_log2_t(s)), K_EXP); }

static void write_sweep(const char *dir, int first, int count)
{
	char path[4096];
	snprintf(path, sizeof path, "mkdir -p '%s'", dir);
	assert_int_equal(system(path), 0);
	snprintf(path, sizeof path, "%s/summary.csv", dir);
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	fprintf(f, "scene,camera,camera_motion,method,variant,T,period,status,maxrgb_p99,flip_mean,exceed_2\n");
	for (int s = first; s < first + count; s++) {
		fprintf(f, "s%d,c0,moving,ref,ref,,,complete,,,\n", s);
		for (int i = 0; i < NLEV; i++) /* maxrgb_p99 also follows the threshold; exceed_2 is there for exceed_T */
			fprintf(f, "s%d,c0,moving,tfr,tfr@%g,%g,,complete,%.9g,%.9g,%.9g\n", s, LEVELS[i], LEVELS[i],
				100 * metric_of(s, LEVELS[i]), metric_of(s, LEVELS[i]), 0.5);
	}
	fclose(f);
}

static void simulate_ratings(const char *csv)
{
	FILE *f = fopen(csv, "w");
	assert_non_null(f);
	fprintf(f, "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms\n");
	rng_state = 28;
	for (int p = 1; p <= 24; p++) {
		double u = 0.5 * normal();
		int trial = 1;
		for (int s = 0; s < 8; s++)
			for (int i = 0; i < NLEV; i++) {
				double psi = sty_psychometric(log2(LEVELS[i]), true_log2_t(s) + u, 1.5, 0.02);
				double same = 0.2 * (1 - fabs(2 * psi - 1)), r = uniform();
				int rating = r < psi - same / 2 ? 1 : r < psi + same / 2 ? 0 : -1;
				int ref_first = uniform() < 0.5;
				fprintf(f, "P%03d,%d,s%d,c0,moving,tfr,%g,,%d,%d,%d,3000\n", p, trial++, s, LEVELS[i], ref_first,
					ref_first ? -rating : rating, rating);
			}
	}
	fclose(f);
}

static void test_model_simulated(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_model");
	char path[4096], db[4096], tally[4096], sweep[4096], sweep2[4096], err[1024];
	double theta_chk, sd_chk;
	snprintf(path, sizeof path, "%s/ratings.csv", dir);
	snprintf(db, sizeof db, "%s/study.db", dir);
	snprintf(tally, sizeof tally, "%s/tally", dir);
	snprintf(sweep, sizeof sweep, "%s/sweep", dir);
	snprintf(sweep2, sizeof sweep2, "%s/unrated", dir);
	simulate_ratings(path);
	write_sweep(sweep, 0, 8);
	write_sweep(sweep2, 100, 4);
	sty *s = created(db);
	size_t rows;
	if (sty_import_long(s, path, &rows, err, sizeof err))
		fail_msg("%s", err);
	commit(s);
	assert_int_equal(rows, 24 * 8 * NLEV);
	sty_tally_desc td = {.out = tally, .bootstrap = 50, .seed = 1, .no_plot = true};
	if (sty_tally(s, &td, err, sizeof err))
		fail_msg("%s", err);
	sty_close(&s);

	/* tables.md lists the measured thresholds as thresholds.csv states them */
	char tpath[4200], want[256];
	snprintf(tpath, sizeof tpath, "%s/thresholds.csv", tally);
	const char *key[4] = {"tfr", "", "s0", "c0"};
	snprintf(want, sizeof want, "| tfr |  | s0 | c0 | %d | %.2f [", 24 * NLEV, tu_csv_lookup(tpath, key, 4, 5));
	snprintf(tpath, sizeof tpath, "%s/tables.md", tally);
	char *md = tu_read_file(tpath, NULL);
	assert_non_null(md);
	assert_non_null(strstr(md, "## Thresholds (T at 1 JND)"));
	assert_non_null(strstr(md, want));
	free(md);

	char model[4096], pred[4096];
	snprintf(model, sizeof model, "%s/model.json", dir);
	snprintf(pred, sizeof pred, "%s/pred.csv", dir);
	sty_model_desc d = {.sweep = sweep, .tally = tally, .out = model, .predict = sweep2, .predict_out = pred};
	sty_model_summary sm;
	if (sty_model_run(&d, &sm, err, sizeof err))
		fail_msg("%s", err);
	printf("# model: %zu conditions, %zu scenes, metric at 1 JND %.4f (generator %.4f), LOSO RMSE of log2 t_jnd %.3f "
	       "over %zu (open %zu)\n", sm.conditions, sm.scenes, sm.m_jnd, M_STAR, sm.loso_rmse_log2, sm.loso_n,
	       sm.loso_open);
	assert_int_equal(sm.conditions, 8 * NLEV);
	assert_int_equal(sm.scenes, 8);
	assert_true(sm.loso_n >= 7);
	assert_true(sm.loso_rmse_log2 <= 0.5);
	assert_true(fabs(log2(sm.m_jnd / M_STAR)) <= 0.5 * K_EXP);
	assert_int_equal(sm.predictions, 4);

	/* the predictions file against the generator's thresholds */
	FILE *f = fopen(pred, "r");
	assert_non_null(f);
	char line[512];
	assert_non_null(fgets(line, sizeof line, f));
	assert_string_equal(line, "method,period,scene,camera,t_jnd,t_jnd_lo,t_jnd_hi,levels\n");
	for (int k = 0; k < 4; k++) {
		int sc;
		double t, lo, hi;
		assert_non_null(fgets(line, sizeof line, f));
		assert_int_equal(sscanf(line, "tfr,,s%d,c0,%lf,%lf,%lf,6", &sc, &t, &lo, &hi), 4);
		double truth = exp2(true_log2_t(sc));
		printf("# unrated s%d: predicted t_jnd %.2f [%.2f, %.2f], true %.2f\n", sc, t, lo, hi, truth);
		assert_int_equal(sc, 100 + k);
		assert_true(fabs(log2(t / truth)) <= 0.5);
		assert_true(lo <= truth && truth <= hi && lo < t && t < hi);
	}
	fclose(f);

	/* a saved model predicts what the fit that wrote it did, byte for byte (issue 28: --model, no refit) */
	char pred2[4200], model2[4200], args[16384], out[4096];
	snprintf(pred2, sizeof pred2, "%s/pred-saved.csv", dir);
	snprintf(model2, sizeof model2, "%s/model2.json", dir);
	snprintf(args, sizeof args, "%s study model --model %s --predict %s --predict-out %s --out %s", TASLAB_BINARY, model,
		 sweep2, pred2, model2);
	if (tu_run(args, out, sizeof out))
		fail_msg("%s", out);
	assert_non_null(strstr(out, "4 prediction(s)"));
	size_t na, nb;
	char *pa = tu_read_file(pred, &na), *pb = tu_read_file(pred2, &nb);
	assert_non_null(pa);
	assert_non_null(pb);
	if (na != nb || memcmp(pa, pb, na))
		fail_msg("predictions from the saved model differ from the fit's:\n%s---\n%s", pa, pb);
	free(pa), free(pb);
	double th2, sd2;
	assert_int_equal(sty_model_prior(model2, "tfr", 0, "s101", "c0", &th2, &sd2, err, sizeof err), 1);
	assert_int_equal(sty_model_prior(model, "tfr", 0, "s101", "c0", &theta_chk, &sd_chk, err, sizeof err), 1);
	assert_true(th2 == theta_chk && sd2 == sd_chk);
	sty_model_pred *q = NULL;
	size_t nq = 0;
	char metric[64];
	if (sty_model_predict(model, sweep2, metric, sizeof metric, &q, &nq, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(nq, 4);
	assert_string_equal(metric, "flip_mean");
	assert_true(!strcmp(q[1].scene, "s101") && fabs(log2(q[1].t_jnd) - theta_chk) < 1e-6);
	free(q);

	/* the model as an adaptive design's prior: the prediction and the leave-one-scene-out SD */
	double theta, sd;
	assert_int_equal(sty_model_prior(model, "tfr", 0, "s101", "c0", &theta, &sd, err, sizeof err), 1);
	assert_true(fabs(theta - true_log2_t(101)) <= 0.5 && fabs(sd - sm.loso_rmse_log2) < 1e-6);
	assert_int_equal(sty_model_prior(model, "tfr", 0, "s7", "c0", &theta, &sd, err, sizeof err), 0);

	/* another metric of the same clips: maxrgb_p99 is 100x flip_mean here, the same thresholds */
	sty_model_desc d2 = {.sweep = sweep, .tally = tally, .out = model, .metric = "maxrgb_p99"};
	sty_model_summary s2;
	if (sty_model_run(&d2, &s2, err, sizeof err))
		fail_msg("%s", err);
	assert_true(fabs(s2.m_jnd / sm.m_jnd - 100) < 1e-6 && fabs(s2.loso_rmse_log2 - sm.loso_rmse_log2) < 1e-9);
}

static void test_model_bad_input(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_model_bad");
	char sweep[4096], err[1024];
	snprintf(sweep, sizeof sweep, "%s/sweep", dir);
	write_sweep(sweep, 0, 2);
	sty_model_desc d = {.sweep = sweep, .tally = dir, .out = NULL};
	sty_model_summary sm;
	assert_int_equal(sty_model_run(&d, &sm, err, sizeof err), TL_ERR_INPUT);
	assert_non_null(strstr(err, "jod.csv"));
	assert_null(strchr(err, '\n'));
	d.metric = "no_such_metric";
	assert_int_equal(sty_model_run(&d, &sm, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "no_such_metric"));
	/* the command: one line, non-zero exit */
	char args[8192];
	snprintf(args, sizeof args, "study model --sweep %s --tally %s --out %s/m.json", sweep, dir, dir);
	tu_expect_cli_error(args, "jod.csv");
	snprintf(args, sizeof args, "study model --sweep %s --tally %s", sweep, dir);
	tu_expect_cli_error(args, "--out");

	/* saved models (--model): bad or old files, bad combinations: one line naming the problem, exit 2 */
	static const struct {
		const char *text, *needle;
	} bad[] = {
		{"{\"format\": \"taslab study model 1\", \"metric\": ", "not a model"},
		{"[1, 2]", "not a JSON object"},
		{"{\"metric\": \"flip_mean\", \"metric_at_1jnd\": 0.05, \"interval_half_width_log2\": 0.5, "
		 "\"leave_one_scene_out\": {\"rmse_log2_t_jnd\": 0.25}}", "written before --model"},
		{"{\"format\": \"taslab study model 9\"}", "another \"format\""},
		{"{\"format\": \"taslab study model 1\", \"metric\": \"flip_mean\", \"metric_at_1jnd\": \"0.05\", "
		 "\"interval_half_width_log2\": 0.5, \"leave_one_scene_out\": {\"rmse_log2_t_jnd\": 0.25}}",
		 "\"metric_at_1jnd\""},
		{"{\"format\": \"taslab study model 1\", \"metric\": \"flip_mean\", \"metric_at_1jnd\": 0.05, "
		 "\"interval_half_width_log2\": -1, \"leave_one_scene_out\": {\"rmse_log2_t_jnd\": 0.25}}",
		 "\"interval_half_width_log2\""},
		{"{\"format\": \"taslab study model 1\", \"metric\": \"flip_mean\", \"metric\": \"flicker_mean\"}",
		 "not a model"},
		/* a raw newline in an unterminated string, which jansson quotes in its message (found by fuzz_model) */
		{"{\"format\": \"taslab study model 1\", \"metric\": \"\\\n", "not a model"},
		{"", "not a model"},
	};
	char mpath[4200], out[4096];
	snprintf(mpath, sizeof mpath, "%s/bad-model.json", dir);
	for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
		FILE *f = fopen(mpath, "w");
		assert_non_null(f);
		fputs(bad[i].text, f);
		fclose(f);
		snprintf(args, sizeof args, "%s study model --model %s --predict %s --predict-out %s/p.csv", TASLAB_BINARY,
			 mpath, sweep, dir);
		int st = tu_run(args, out, sizeof out);
		if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, bad[i].needle) || !strstr(out, mpath))
			fail_msg("model %zu: exit %d, want 2 and one line naming the file with '%s':\n%s", i, st, bad[i].needle,
				 out);
	}
	/* the same reader for an adaptive design's --prior: one line naming the option and the file */
	char perr[8192];
	double th, sd;
	assert_int_equal(sty_model_prior(mpath, "tfr", 0, "s101", "c0", &th, &sd, perr, sizeof perr), TL_ERR_ARG);
	if (strncmp(perr, "--prior: not a model: ", 22) || !strstr(perr, mpath) || strchr(perr, '\n'))
		fail_msg("--prior on a file that is not JSON: %s", perr);
	char p2[4200];
	snprintf(p2, sizeof p2, "%s/p.csv", dir);
	assert_false(tu_file_exists(p2));
	snprintf(args, sizeof args, "study model --model %s --sweep %s --predict %s --predict-out %s", mpath, sweep, sweep, p2);
	tu_expect_cli_error(args, "no --sweep or --tally");
	snprintf(args, sizeof args, "study model --model %s --out %s/m2.json", mpath, dir);
	tu_expect_cli_error(args, "needs --predict SWEEP2");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_isotonic),
		cmocka_unit_test(test_t_at),
		cmocka_unit_test(test_model_simulated),
		cmocka_unit_test(test_model_bad_input),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
