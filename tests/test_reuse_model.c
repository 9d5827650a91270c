/* test_reuse_model.c — the survey's models of reuse ([S] sec. 4.1, eqs. 5-7; metrics/reuse_model.c):
 *  - the fits recover known parameters from exact synthetic data (eq. 5's α and λ, eq. 6's A_hit, A_miss and c, and
 *    A_miss − A_hit and c + A_hit·V when hits + misses is constant, eq. 7's μ), and refuse what does not determine
 *    them (one period, three frames, misses that do not vary);
 *  - `taslab analyze reuse-model` on a real sweep (rrc/2, /4, /8 at 48x32): the error column is each run's
 *    summary.json value, the hit rate is recomputed here from each run's stats.csv (frames after the first), rrc's
 *    μ is 1 within the misses of a moving path, the sweep's report shows the same fits (and a sweep without a method
 *    with a period none), and bad input is one line and a non-zero exit. */
#define _GNU_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/reuse_model.h"
#include "test_util.h"

static void test_eq5(void **state)
{
	(void)state;
	const double dn[] = {1, 2, 3, 4, 8, 16}, alpha = 2.5, lambda = 0.3;
	double eps[6];
	for (int i = 0; i < 6; i++)
		eps[i] = alpha * (1.0 - exp(-lambda * (dn[i] - 1.0)));
	mtr_eq5 f;
	mtr_fit_eq5(dn, eps, 6, &f);
	assert_true(f.ok);
	assert_true(fabs(f.alpha - alpha) < 1e-6 * alpha);
	assert_true(fabs(f.lambda - lambda) < 1e-6 * lambda);
	assert_true(f.rmse < 1e-6);
	/* a fast saturation (λ = 20) and a nearly linear one (λ = 0.001) */
	const double lambdas[] = {20.0, 0.001};
	for (int k = 0; k < 2; k++) {
		for (int i = 0; i < 6; i++)
			eps[i] = 0.7 * (1.0 - exp(-lambdas[k] * (dn[i] - 1.0)));
		mtr_fit_eq5(dn, eps, 6, &f);
		assert_true(f.ok);
		if (fabs(f.alpha * (1.0 - exp(-f.lambda * 15.0)) - eps[5]) > 1e-6 || f.rmse > 1e-6)
			fail_msg("λ = %g: α %g λ %g rmse %g", lambdas[k], f.alpha, f.lambda, f.rmse);
	}
	/* noise: least squares, not interpolation */
	const double noisy[] = {0.0, 0.8, 1.5, 1.9, 2.6, 2.4};
	mtr_fit_eq5(dn, noisy, 6, &f);
	assert_true(f.ok && f.rmse > 0.01 && f.rmse < 0.3);
	/* one period > 1 (and Δn = 1) does not determine both */
	const double dn1[] = {1, 4, 4};
	mtr_fit_eq5(dn1, eps, 3, &f);
	assert_false(f.ok);
	assert_true(isnan(f.alpha));
}

static void test_eq6(void **state)
{
	(void)state;
	/* hits and misses varying independently, the visible samples too */
	double h[12], m[12], t[12];
	for (int i = 0; i < 12; i++) {
		h[i] = 1000.0 + 300.0 * (i % 4);
		m[i] = 200.0 + 150.0 * (i % 3) + 10.0 * i;
		t[i] = 0.002 * h[i] + 0.01 * m[i] + 5.0;
	}
	mtr_eq6 f;
	mtr_fit_eq6(h, m, t, 12, &f);
	assert_true(f.ok && f.three_terms);
	assert_true(fabs(f.a_hit - 0.002) < 1e-9 && fabs(f.a_miss - 0.01) < 1e-9 && fabs(f.c - 5.0) < 1e-6);
	assert_true(fabs(f.r2 - 1.0) < 1e-9);
	/* every pixel a hit or a miss (H + M = V): two unknowns, not three */
	for (int i = 0; i < 12; i++) {
		m[i] = 200.0 + 97.0 * (i % 5);
		h[i] = 4000.0 - m[i];
		t[i] = 0.002 * h[i] + 0.01 * m[i] + 5.0;
	}
	mtr_fit_eq6(h, m, t, 12, &f);
	assert_true(f.ok);
	assert_false(f.three_terms);
	assert_true(isnan(f.a_hit) && isnan(f.a_miss));
	assert_true(fabs(f.miss_minus_hit - 0.008) < 1e-9);
	assert_true(fabs(f.c - (5.0 + 0.002 * 4000.0)) < 1e-6);
	/* hits in proportion to misses (a single period) while V varies: not determined either way */
	for (int i = 0; i < 12; i++) {
		m[i] = 200.0 + 97.0 * (i % 5);
		h[i] = 0.5 * m[i];
		t[i] = 0.002 * h[i] + 0.01 * m[i] + 5.0;
	}
	mtr_fit_eq6(h, m, t, 12, &f);
	assert_false(f.ok);
	/* too few frames; misses that never change */
	mtr_fit_eq6(h, m, t, 3, &f);
	assert_false(f.ok);
	for (int i = 0; i < 12; i++)
		m[i] = 500.0;
	mtr_fit_eq6(h, m, t, 12, &f);
	assert_false(f.ok);
}

static void test_hit_rate(void **state)
{
	(void)state;
	const double dn[] = {1, 2, 4, 8};
	double r[4];
	for (int i = 0; i < 4; i++)
		r[i] = 0.9 * (1.0 - 1.0 / dn[i]);
	assert_true(fabs(mtr_fit_hit_rate(dn, r, 4) - 0.9) < 1e-12);
	assert_true(isnan(mtr_fit_hit_rate(dn, r, 1)));
}

static char out[1 << 16];

#define sh(...) tu_runf(out, sizeof out, __VA_ARGS__)

/* The value of `key` in a flat JSON file (summary.json). */
static double json_number(const char *path, const char *key)
{
	char *text = tu_read_file(path, NULL), pat[128];
	assert_non_null(text);
	snprintf(pat, sizeof pat, "\"%s\": ", key);
	const char *p = strstr(text, pat);
	double v = p ? strtod(p + strlen(pat), NULL) : NAN;
	free(text);
	return v;
}

/* Σ reused / Σ (reused + shaded) over the rows after the first of RUN/stats.csv. */
static double hit_rate_of(const char *run)
{
	char path[4096];
	snprintf(path, sizeof path, "%s/stats.csv", run);
	char *text = tu_read_file(path, NULL);
	assert_non_null(text);
	int col_r = -1, col_s = -1, row = 0;
	double sr = 0, sv = 0;
	char *save = NULL;
	for (char *l = strtok_r(text, "\n", &save); l; l = strtok_r(NULL, "\n", &save), row++) {
		char *save2 = NULL;
		int c = 0;
		double r = NAN, s = NAN;
		for (char *f = strtok_r(l, ",", &save2); f; f = strtok_r(NULL, ",", &save2), c++) {
			if (row == 0) {
				col_r = strcmp(f, "reused_samples") ? col_r : c;
				col_s = strcmp(f, "shaded_samples") ? col_s : c;
			} else if (c == col_r) {
				r = atof(f);
			} else if (c == col_s) {
				s = atof(f);
			}
		}
		if (row >= 2) /* the header, then frame 0 (left out), then the others */
			sr += r, sv += r + s;
	}
	free(text);
	assert_true(col_r >= 0 && col_s >= 0);
	return sr / sv;
}

static void test_cli(void **state)
{
	(void)state;
	char dir[4096], sw[4096], p[4096], run[4096];
	snprintf(dir, sizeof dir, "%s", tu_tmpdir("reuse_model"));
	snprintf(sw, sizeof sw, "%s/sw", dir);
	int st = sh("%s sweep --scenes turntable --cameras orbit --size 48x32 --device " TASLAB_TEST_DEVICE
		    " --variants ref,rrc/2,rrc/4,rrc/8 --frames 0:9 --no-report --quiet --out %s",
		    TASLAB_BINARY, sw);
	if (st)
		fail_msg("sweep: exit %d:\n%s", st, out);
	st = sh("%s analyze reuse-model %s --out %s/model", TASLAB_BINARY, sw, dir);
	if (st || !strstr(out, "reuse_model.md"))
		fail_msg("analyze reuse-model: exit %d:\n%s", st, out);
	snprintf(p, sizeof p, "%s/model/reuse_model.csv", dir);
	char *csv = tu_read_file(p, NULL);
	assert_non_null(csv);
	/* one row per period, each error the run's summary.json value, each hit rate its stats.csv's */
	const int periods[] = {2, 4, 8};
	double mu = NAN;
	for (int k = 0; k < 3; k++) {
		char head[64];
		snprintf(head, sizeof head, "\nturntable,orbit,rrc,%d,maxrgb_mean,", periods[k]);
		const char *row = strstr(csv, head);
		if (!row)
			fail_msg("no row for rrc/%d:\n%s", periods[k], csv);
		double e, em, hr;
		assert_int_equal(sscanf(row + strlen(head), "%lf,%lf,%lf", &e, &em, &hr), 3);
		snprintf(p, sizeof p, "%s/metrics/turntable/orbit/rrc-N%d/summary.json", sw, periods[k]);
		double want = json_number(p, "maxrgb_mean");
		if (fabs(e - want) > 1e-5 * fmax(1.0, want))
			fail_msg("rrc/%d: error %g, summary.json %g", periods[k], e, want);
		snprintf(run, sizeof run, "%s/runs/turntable/orbit/rrc-N%d", sw, periods[k]);
		double hw = hit_rate_of(run);
		if (fabs(hr - hw) > 2e-6)
			fail_msg("rrc/%d: hit rate %g, stats.csv %g", periods[k], hr, hw);
		/* μ (column 15) is the group's: the same on every row */
		const char *c = row + 1;
		for (int n = 0; n < 14 && c; n++)
			c = strchr(c, ',') ? strchr(c, ',') + 1 : NULL;
		assert_non_null(c);
		double m = atof(c);
		assert_true(isnan(mu) || m == mu);
		mu = m;
	}
	/* the .md: one section per group, with the parameters and a row per period */
	snprintf(p, sizeof p, "%s/model/reuse_model.md", dir);
	char *md = tu_read_file(p, NULL);
	assert_non_null(md);
	if (!strstr(md, "## turntable / orbit / rrc\n") || !strstr(md, "eq. 5: α = ") || !strstr(md, "eq. 7: μ = ") ||
	    !strstr(md, "\n| 2 | ") || !strstr(md, "\n| 4 | ") || !strstr(md, "\n| 8 | "))
		fail_msg("reuse_model.md:\n%s", md);
	free(md);
	/* the sweep's report shows the same fits (report/data/reuse_model.csv holds the same rows) */
	st = sh("%s report %s", TASLAB_BINARY, sw);
	if (st)
		fail_msg("report: exit %d:\n%s", st, out);
	snprintf(p, sizeof p, "%s/report/data/reuse_model.csv", sw);
	char *rcsv = tu_read_file(p, NULL);
	assert_non_null(rcsv);
	assert_string_equal(rcsv, csv);
	free(rcsv);
	snprintf(p, sizeof p, "%s/report/index.html", sw);
	char *html = tu_read_file(p, NULL);
	assert_non_null(html);
	assert_non_null(strstr(html, "<h3>Models of reuse"));
	assert_non_null(strstr(html, "<b>rrc</b>: eq. 5"));
	free(html);
	free(csv);
	/* rrc refreshes 1/N of its tiles per frame, and shades the misses of the moving path on top: μ just under 1 */
	if (!(mu > 0.8 && mu <= 1.0))
		fail_msg("rrc's μ %g", mu);
	/* a run whose metric is null (not computed) is left out of eq. 5, not an error; the default --out is SWEEP */
	snprintf(p, sizeof p, "%s/metrics/turntable/orbit/rrc-N8/summary.json", sw);
	assert_int_equal(sh("sed -i 's/\"maxrgb_mean\": [0-9.e+-]*/\"maxrgb_mean\": null/' %s && grep -q "
			    "'\"maxrgb_mean\": null' %s", p, p), 0);
	st = sh("%s analyze reuse-model %s", TASLAB_BINARY, sw);
	if (st)
		fail_msg("a null metric: exit %d:\n%s", st, out);
	snprintf(p, sizeof p, "%s/reuse_model.csv", sw);
	csv = tu_read_file(p, NULL);
	assert_non_null(csv);
	assert_non_null(strstr(csv, "\nturntable,orbit,rrc,8,maxrgb_mean,,")); /* its error empty */
	free(csv);
	/* bad input: not a sweep, an unknown error key, a sweep without a method with a period */
	st = sh("%s analyze reuse-model %s", TASLAB_BINARY, dir);
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, "not a sweep"))
		fail_msg("not a sweep: exit %d:\n%s", st, out);
	st = sh("%s analyze reuse-model %s --out %s/model --error nosuch", TASLAB_BINARY, sw, dir);
	if (st == 0 || tu_count_lines(out) != 1 || !strstr(out, "--error nosuch: not a number"))
		fail_msg("unknown key: exit %d:\n%s", st, out);
	st = sh("%s sweep --scenes turntable --cameras orbit --size 48x32 --device " TASLAB_TEST_DEVICE
		" --variants ref,tfr@8 --frames 0:3 --no-report --quiet --out %s/sw2",
		TASLAB_BINARY, dir);
	assert_int_equal(st, 0);
	st = sh("%s analyze reuse-model %s/sw2", TASLAB_BINARY, dir);
	if (st == 0 || tu_count_lines(out) != 1 || !strstr(out, "no complete run of a method with a period"))
		fail_msg("no period: exit %d:\n%s", st, out);
	snprintf(p, sizeof p, "%s/sw2/reuse_model.csv", dir);
	assert_false(tu_file_exists(p)); /* nothing that looks complete */
	/* its report has no such section */
	assert_int_equal(sh("%s report %s/sw2", TASLAB_BINARY, dir), 0);
	snprintf(p, sizeof p, "%s/sw2/report/index.html", dir);
	html = tu_read_file(p, NULL);
	assert_non_null(html);
	assert_null(strstr(html, "Models of reuse"));
	free(html);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_eq5),
		cmocka_unit_test(test_eq6),
		cmocka_unit_test(test_hit_rate),
		cmocka_unit_test(test_cli),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
