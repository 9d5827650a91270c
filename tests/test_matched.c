/* test_matched.c — the matched-budget pairs (metrics_matched.h; BASELINES.md section 0 "Comparison") on a synthetic
 * summary: which runs are TAS, and for each TAS variant each other method at its nearest shaded samples per frame,
 * with the pairs worked out by hand below; and how the report's and table1.md's cells print a value
 * (mtr_fprint_shown, metrics_runs.h). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "taslab/metrics_matched.h"
#include "taslab/metrics_runs.h"
#include "test_util.h"

static void test_is_tas(void **state)
{
	(void)state;
	assert_true(mtr_match_is_tas("reprojection", true));  /* tarc */
	assert_true(mtr_match_is_tas("atlas", true));         /* tasa */
	assert_false(mtr_match_is_tas("reprojection", false)); /* rrc: a period, no T */
	assert_false(mtr_match_is_tas("atlas", false));       /* sa, sau */
	assert_false(mtr_match_is_tas("deferred", true));     /* ads@S: a threshold, but not TAS */
	assert_false(mtr_match_is_tas("forward", true));      /* tfr */
	assert_false(mtr_match_is_tas("rate", false));        /* vref, casedge, ... */
	assert_false(mtr_match_is_tas("reference", false));
	assert_false(mtr_match_is_tas(NULL, true));
}

static void test_pairs(void **state)
{
	(void)state;
	/* Two groups. Shaded samples per frame:
	 *  g1: ref 1000 (never matched); tarc@4 600, tasa@8 300 (TAS); vref 1000; ads@1 700, ads@2 450, ads@4 250;
	 *      casedge 520; fovea NAN (missing run: never matched); rrc/4 250.
	 *  g2: tarc@4 100 (TAS); ads@2 90 and ads@4 110 (a tie at distance 10: the first, ads@2); vref 200.
	 * Expected, TAS items in order, methods by their first item in the group:
	 *  tarc@4 (600): vref 1000, ads@1 (|700-600| = 100 < 150 of ads@2), casedge, rrc/4;
	 *  tasa@8 (300): vref 1000, ads@4 (|250-300| = 50 < 150), casedge, rrc/4;
	 *  g2 tarc@4 (100): ads@2 (tie, first), vref. */
	const mtr_match_item in[] = {
		{"g1", "ref", false, true, 1000},   /* 0 */
		{"g1", "tarc", true, false, 600},   /* 1 */
		{"g1", "vref", false, false, 1000}, /* 2 */
		{"g1", "ads", false, false, 700},   /* 3 */
		{"g1", "ads", false, false, 450},   /* 4 */
		{"g1", "ads", false, false, 250},   /* 5 */
		{"g1", "tasa", true, false, 300},   /* 6 */
		{"g1", "casedge", false, false, 520}, /* 7 */
		{"g1", "fovea", false, false, NAN}, /* 8 */
		{"g1", "rrc", false, false, 250},   /* 9 */
		{"g2", "ads", false, false, 90},    /* 10 */
		{"g2", "tarc", true, false, 100},   /* 11 */
		{"g2", "ads", false, false, 110},   /* 12 */
		{"g2", "vref", false, false, 200},  /* 13 */
	};
	const mtr_match_pair want[] = {{1, 2}, {1, 3}, {1, 7}, {1, 9}, {6, 2}, {6, 5}, {6, 7}, {6, 9}, {11, 10}, {11, 13}};
	const size_t nw = sizeof want / sizeof want[0];
	size_t n = sizeof in / sizeof in[0];
	assert_int_equal(mtr_match_budget(in, n, NULL, 0), nw);
	mtr_match_pair got[16];
	memset(got, 0xff, sizeof got);
	assert_int_equal(mtr_match_budget(in, n, got, 16), nw);
	for (size_t k = 0; k < nw; k++) {
		assert_int_equal(got[k].tas, want[k].tas);
		assert_int_equal(got[k].other, want[k].other);
	}
	/* a short buffer: the count is still all of them, the first `cap` written */
	mtr_match_pair two[2];
	assert_int_equal(mtr_match_budget(in, n, two, 2), nw);
	assert_int_equal(two[1].other, 3);
	/* nothing to match: no TAS, or no other method */
	assert_int_equal(mtr_match_budget(in + 2, 4, got, 16), 0);
	assert_int_equal(mtr_match_budget(in, 2, got, 16), 0);
}

/* Table cells drop the minus sign of a value that rounds to zero (ref's reuse is -0.0035 % where a coplanar pixel is
 * shaded twice: "-0.00 %" read as a defect), and keep every other sign. */
static void test_shown_zero(void **state)
{
	(void)state;
	char buf[256];
	FILE *f = fmemopen(buf, sizeof buf, "w");
	assert_non_null(f);
	mtr_fprint_shown(f, "%.2f %%|", -0.0035);
	mtr_fprint_shown(f, "%.2f %%|", -0.5);
	mtr_fprint_shown(f, "%.3f|", -0.004);
	mtr_fprint_shown(f, "%.0f|", -0.4);
	mtr_fprint_shown(f, "%.2f×|", -0.001);
	mtr_fprint_shown(f, "%.1f dB|", -10.04);
	mtr_fprint_shown(f, "%.2f|", 0.0);
	mtr_fprint_shown(f, "%.1f|", -INFINITY);
	fclose(f);
	assert_string_equal(buf, "0.00 %|-0.50 %|-0.004|0|0.00×|-10.0 dB|0.00|-inf|");
}

int main(void)
{
	const struct CMUnitTest tests[] = {cmocka_unit_test(test_is_tas), cmocka_unit_test(test_pairs),
					   cmocka_unit_test(test_shown_zero)};
	return tu_finish(cmocka_run_group_tests(tests, NULL, NULL));
}
