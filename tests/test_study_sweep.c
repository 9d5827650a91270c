/* test_study_sweep.c — a study rated on a sweep's own clips and joined back to it (issue 27.12, 27.13):
 *  - `taslab study pairs --sweep` makes one pairs.json set per scene and camera path whose clips are the sweep's
 *    clips byte for byte (bad input: an unknown variant, the reference, a folder in the way: one line, exit 2);
 *  - `taslab report SWEEP --study` joins the study (data/study.csv: one row per rated run, Q and p_ref as the tally's
 *    conditions.csv states them), draws Fig. 3 (data/fig3.csv: the pooled rows of the tally, one per T) and says on
 *    stderr and on the page which of the study's conditions no run has;
 *  - it refuses (one line, exit 2, nothing of the study written) a study whose stimuli are not the sweep's runs:
 *    another size, other frames, another display transform, a clip that is not the sweep's.
 *  - with --model (issue 28) it shows the model's predicted t_jnd with its interval beside the measured one (the model's
 *    own predictions file, cell for cell, in data/thresholds.csv, and 2^3.5 [8, 16] for a model whose metric at 1 JND
 *    lies halfway in log2 between tfr@8's and tfr@16's flip_mean, half width 0.5 octave), and without a study the
 *    prediction alone ("not rated"); a file that is not a model is one line, exit 2; `study tally --model --sweep`
 *    puts the same predictions beside the tally's thresholds (thresholds.csv, tables.md).
 * The sweep is tiny (48x32, two frames, ref, tfr@8, tfr@16 on the tests' device, lavapipe, with validation) so the test stays short. */
#define _DEFAULT_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "test_study_util.h"

#ifndef TASLAB_TEST_DEVICE /* the tests' device (tests/CMakeLists.txt, issue 32.5), lavapipe where it is not set */
#define TASLAB_TEST_DEVICE "lavapipe"
#endif

static char out[65536];
static char dir[4096], sw[4200], stim[4200], set[4300], db[4200];

static int run_cli(const char *args)
{
	char cmd[16384];
	snprintf(cmd, sizeof cmd, "%s %s", TASLAB_BINARY, args);
	return tu_run(cmd, out, sizeof out);
}

/* The one line a refused command printed must hold `needle`. */
static void expect_refused(const char *args, int code, const char *needle)
{
	int rc = run_cli(args);
	if (rc != code || tu_count_lines(out) != 1 || !strstr(out, needle))
		fail_msg("'%s': exit %d (want %d), want one line with '%s':\n%s", args, rc, code, needle, out);
}

/* Replaces the first `from` in file `path` by `to`. */
static void edit(const char *path, const char *from, const char *to)
{
	char *t = tu_read_file(path, NULL);
	assert_non_null(t);
	char *at = strstr(t, from);
	if (!at)
		fail_msg("%s holds no '%s'", path, from);
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	fprintf(f, "%.*s%s%s", (int)(at - t), t, to, at + strlen(from));
	fclose(f);
	free(t);
}

static void file_copy(const char *from, const char *to)
{
	size_t n;
	char *t = tu_read_file(from, &n);
	assert_non_null(t);
	unlink(to);
	FILE *f = fopen(to, "wb");
	assert_non_null(f);
	fwrite(t, 1, n, f);
	fclose(f);
	free(t);
}

static int same_bytes(const char *a, const char *b)
{
	size_t na, nb;
	char *x = tu_read_file(a, &na), *y = tu_read_file(b, &nb);
	int same = x && y && na == nb && !memcmp(x, y, na);
	free(x);
	free(y);
	return same;
}

/* Two participants answer every trial (test trials +1 or -1 by participant, catch trials 0). */
static void answer_all(void)
{
	char err[1024], **codes = NULL;
	size_t n = 0;
	sty *s = NULL;
	if (sty_open(db, &s, err, sizeof err) || sty_participant_codes(s, &codes, &n, err, sizeof err))
		fail_msg("%s", err);
	for (size_t i = 0; i < n; i++) {
		sty_trial t;
		while (!sty_next_trial(s, codes[i], &t, err, sizeof err) && !t.done)
			if (sty_answer(s, codes[i], t.index, strcmp(t.kind, "test") ? 0 : i ? -1 : 1, 1000, err, sizeof err))
				fail_msg("%s", err);
		free(codes[i]);
	}
	free(codes);
	sty_close(&s);
}

/* A numeric cell of SWEEP/summary.csv: the column named `col` in the row of `variant`. */
static double summary_value(const char *variant, const char *col)
{
	char path[4300], *fld[256];
	snprintf(path, sizeof path, "%s/summary.csv", sw);
	char *t = tu_read_file(path, NULL), *save = NULL;
	assert_non_null(t);
	int vc = -1, cc = -1, row = 0;
	double v = NAN;
	for (char *line = strtok_r(t, "\n", &save); line; line = strtok_r(NULL, "\n", &save), row++) {
		int n = 0;
		for (char *c = line; n < 256;) {
			fld[n++] = c;
			if (!(c = strchr(c, ',')))
				break;
			*c++ = 0;
		}
		for (int k = 0; !row && k < n; k++) {
			vc = strcmp(fld[k], "variant") ? vc : k;
			cc = strcmp(fld[k], col) ? cc : k;
		}
		if (row && vc >= 0 && cc >= 0 && cc < n && !strcmp(fld[vc], variant))
			v = strtod(fld[cc], NULL);
	}
	free(t);
	return v;
}

/* The predicted thresholds (issue 28): a model whose metric at 1 JND is halfway in log2 between tfr@8's and
 * tfr@16's flip_mean, predicted for this sweep by `study model --model --predict` (model.json, pred.csv). */
static void write_model(char *model, size_t n, char *pred, size_t pn)
{
	char hand[4300], args[16384];
	double m8 = summary_value("tfr@8", "flip_mean"), m16 = summary_value("tfr@16", "flip_mean");
	if (!(m8 > 0 && m16 > m8))
		fail_msg("flip_mean of tfr@8 %g and tfr@16 %g: want 0 < tfr@8 < tfr@16", m8, m16);
	snprintf(hand, sizeof hand, "%s/hand.json", dir);
	snprintf(model, n, "%s/model.json", dir);
	snprintf(pred, pn, "%s/pred.csv", dir);
	FILE *f = fopen(hand, "w");
	assert_non_null(f);
	fprintf(f, "{\"format\": \"taslab study model 1\", \"metric\": \"flip_mean\", \"metric_at_1jnd\": %.8g, "
		   "\"interval_half_width_log2\": 0.5, \"leave_one_scene_out\": {\"rmse_log2_t_jnd\": 0.2551, \"n\": 1, "
		   "\"open\": 0}, \"conditions\": 2, \"scenes\": 1}\n", sqrt(m8 * m16));
	fclose(f);
	snprintf(args, sizeof args, "study model --model %s --predict %s --out %s --predict-out %s", hand, sw, model, pred);
	if (run_cli(args))
		fail_msg("%s", out);
}

/* data/thresholds.csv's predicted cells of tfr turntable/orbit are pred.csv's, and 2^3.5 [8, 16]. */
static void check_predicted(const char *pred, double n_want)
{
	char p[4300];
	snprintf(p, sizeof p, "%s/report/data/thresholds.csv", sw);
	const char *k[4] = {"tfr", "", "turntable", "orbit"};
	for (int c = 0; c < 3; c++) {
		double got = tu_csv_lookup(p, k, 4, 8 + c), want = tu_csv_lookup(pred, k, 4, 4 + c);
		double truth = exp2(3.5 + 0.5 * (c == 0 ? 0 : c == 1 ? -1 : 1));
		if (!(got == want) || !(fabs(got - truth) < 2e-4))
			fail_msg("data/thresholds.csv predicted cell %d: %g, the model's %g, expected %g", c, got, want, truth);
	}
	assert_true(tu_csv_lookup(p, k, 4, 4) == n_want);
}

static void test_study_on_sweep(void **state)
{
	(void)state;
	snprintf(dir, sizeof dir, "%s", tu_tmpdir("study_sweep"));
	snprintf(sw, sizeof sw, "%s/sw", dir);
	snprintf(stim, sizeof stim, "%s/stim", dir);
	snprintf(set, sizeof set, "%s/turntable--orbit", stim);
	snprintf(db, sizeof db, "%s/s.db", dir);
	char args[16384], p[4600], q[4600];
	snprintf(args, sizeof args, "sweep --scenes turntable --cameras orbit --size 48x32 --device " TASLAB_TEST_DEVICE " --validation "
				    "--variants ref,tfr@8,tfr@16 --frames 0:2 --jobs 2 --no-report --out %s", sw);
	if (run_cli(args))
		fail_msg("%s", out);

	/* bad input: one line, exit 2, nothing made */
	snprintf(args, sizeof args, "study pairs --sweep %s --out %s --variants tfr@4", sw, stim);
	expect_refused(args, 2, "--variants: 'tfr@4' is not a variant of");
	assert_non_null(strstr(out, "tfr@8, tfr@16"));
	snprintf(args, sizeof args, "study pairs --sweep %s --out %s --variants ref", sw, stim);
	expect_refused(args, 2, "other than its reference");
	snprintf(args, sizeof args, "study pairs --sweep %s --out %s", sw, sw);
	expect_refused(args, 2, "is not empty");
	snprintf(args, sizeof args, "study pairs --sweep %s/runs --out %s", sw, stim);
	expect_refused(args, 2, "not a sweep folder");
	assert_false(tu_file_exists(stim));

	/* the sets: the sweep's clips, byte for byte */
	snprintf(args, sizeof args, "study pairs --sweep %s --out %s", sw, stim);
	if (run_cli(args))
		fail_msg("%s", out);
	const char *ids[3] = {"ref", "tfr-T8", "tfr-T16"};
	for (int i = 0; i < 3; i++) {
		snprintf(p, sizeof p, "%s/clips/%s.webm", set, ids[i]);
		snprintf(q, sizeof q, "%s/clips/turntable/orbit/%s.webm", sw, ids[i]);
		if (!same_bytes(p, q))
			fail_msg("%s is not the sweep's clip %s", p, q);
	}
	snprintf(p, sizeof p, "%s/pairs.json", set);
	char *pj = tu_read_file(p, NULL);
	assert_non_null(strstr(pj, "\"sweep_run\": \"runs/turntable/orbit/tfr-T8\""));
	assert_non_null(strstr(pj, "\"size\": [\n    48,\n    32\n  ]"));
	free(pj);
	/* a condition the sweep lacks (tfr@32, its clip a copy of the reference's) */
	snprintf(q, sizeof q, "%s/clips/tfr-T32.webm", set);
	snprintf(args, sizeof args, "%s/clips/ref.webm", set);
	file_copy(args, q);
	edit(p, "\"conditions\": [", "\"conditions\": [{\"T\": 32, \"clip\": \"clips/tfr-T32.webm\", \"id\": \"tfr-T32\", "
				     "\"method\": \"tfr\", \"variant\": \"tfr@32\", \"method_facts\": {\"baseline\": \"ref\", "
				     "\"family\": \"forward\", \"reference\": false, \"takes_period\": false, "
				     "\"takes_threshold\": true}},");

	char err[1024];
	sty *s = created(db);
	sty_design_desc dd = {.stimuli = stim, .participants = 2, .seed = 3, .catch_trials = 1};
	sty_design_summary sm;
	if (sty_design(s, &dd, &sm, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(sm.conditions, 4); /* tfr@8, tfr@16, tfr@32 and the catch pair */
	commit(s);
	sty_close(&s);
	answer_all();

	/* the join: two rated runs, the tfr@32 condition said to have none, Fig. 3; with a model's predictions */
	char model[4300], pred[4300];
	write_model(model, sizeof model, pred, sizeof pred);
	snprintf(args, sizeof args, "report %s --study %s --model %s", sw, db, model);
	if (run_cli(args))
		fail_msg("%s", out);
	if (!strstr(out, "1 condition(s) of the study have no run in this sweep and are not joined: tfr@32 turntable/orbit"))
		fail_msg("the report does not say which condition has no run:\n%s", out);
	snprintf(p, sizeof p, "%s/report/data/study.csv", sw);
	char *csv = tu_read_file(p, NULL);
	assert_non_null(csv);
	assert_int_equal(tu_count_lines(csv), 3);
	free(csv);
	snprintf(q, sizeof q, "%s/report/study/conditions.csv", sw);
	snprintf(p, sizeof p, "%s/report/data/fig3.csv", sw);
	const char *Ts[3] = {"8", "16", "32"};
	for (int t = 0; t < 3; t++) {
		const char *fk[3] = {"tfr", "tfr", Ts[t]}, *ck[5] = {"tfr", Ts[t], "", "all", "all"};
		double Q = tu_csv_lookup(p, fk, 3, 5), want = tu_csv_lookup(q, ck, 5, 6);
		double pr = tu_csv_lookup(p, fk, 3, 8), pw = 100 * tu_csv_lookup(q, ck, 5, 9);
		if (isnan(Q) || !(fabs(Q - want) < 1e-9) || !(fabs(pr - pw) < 1e-6))
			fail_msg("fig3.csv T=%s: Q %g p_ref %g%%, the tally's %g and %g%%", Ts[t], Q, pr, want, pw);
	}
	snprintf(p, sizeof p, "%s/report/index.html", sw);
	char *html = tu_read_file(p, NULL);
	assert_non_null(strstr(html, "Fig. 3: quality against T"));
	/* the thresholds beside it (issue 28): the pooled row as the tally's thresholds.csv states it */
	snprintf(q, sizeof q, "%s/report/study/thresholds.csv", sw);
	const char *tk[4] = {"tfr", "", "all", "all"};
	double tj = tu_csv_lookup(q, tk, 4, 5);
	char trow[128];
	snprintf(trow, sizeof trow, isinf(tj) ? "<td>all</td><td>all</td><td>%d</td><td>inf [" :
		 "<td>all</td><td>all</td><td>%d</td><td>%.2f [", (int)tu_csv_lookup(q, tk, 4, 4), tj);
	assert_non_null(strstr(html, "Thresholds (T at 1 JND)"));
	if (!strstr(html, trow))
		fail_msg("the report's thresholds lack '%s'", trow);
	/* the predicted threshold beside the measured one (issue 28: report --model), the pooled row without one */
	const char *sk[4] = {"tfr", "", "turntable", "orbit"};
	double n_rated = tu_csv_lookup(q, sk, 4, 4);
	tj = tu_csv_lookup(q, sk, 4, 5);
	snprintf(trow, sizeof trow, isinf(tj) ? "<td>turntable</td><td>orbit</td><td>%d</td><td>inf [" :
		 "<td>turntable</td><td>orbit</td><td>%d</td><td>%.2f [", (int)n_rated, tj);
	char *at = strstr(html, trow);
	if (!at || !strstr(at, "]</td><td>11.31 [8.00, 16.00]</td></tr>") ||
	    strstr(at, "</tr>") < strstr(at, "11.31 [8.00, 16.00]"))
		fail_msg("the report's thresholds lack the prediction beside '%s'", trow);
	assert_non_null(strstr(html, "</td><td>–</td></tr>")); /* the pooled row: no prediction */
	check_predicted(pred, n_rated);
	/* the same beside the tally's own thresholds (issue 28: tally --model, the report's code): thresholds.csv's
	 * predicted cells are the model's predictions file's, the pooled row has none, tables.md shows them */
	snprintf(args, sizeof args, "study tally --db %s --out %s/tally --bootstrap 10 --model %s --sweep %s", db, dir, model, sw);
	if (run_cli(args))
		fail_msg("%s", out);
	snprintf(p, sizeof p, "%s/tally/thresholds.csv", dir);
	for (int c = 0; c < 3; c++) {
		double got = tu_csv_lookup(p, sk, 4, 14 + c), want = tu_csv_lookup(pred, sk, 4, 4 + c);
		if (!(got == want) || !(fabs(got - exp2(3.5 + 0.5 * (c == 0 ? 0 : c == 1 ? -1 : 1))) < 2e-4))
			fail_msg("tally thresholds.csv predicted cell %d: %g, the model's %g", c, got, want);
		assert_true(isnan(tu_csv_lookup(p, tk, 4, 14 + c)));
	}
	assert_true(tu_csv_lookup(p, sk, 4, 5) == tu_csv_lookup(q, sk, 4, 5)); /* the measured t_jnd as before */
	snprintf(p, sizeof p, "%s/tally/tables.md", dir);
	char *md = tu_read_file(p, NULL);
	assert_non_null(md);
	if (!strstr(md, "| predicted t_jnd [95%] |") || !strstr(md, "| 11.31 [8.00, 16.00] |\n"))
		fail_msg("tables.md lacks the prediction:\n%s", md);
	free(md);
	snprintf(args, sizeof args, "study tally --db %s --out %s/tally2 --model %s", db, dir, model);
	expect_refused(args, 2, "--model needs --sweep");
	snprintf(args, sizeof args, "study tally --db %s --out %s/tally2 --model %s --sweep %s", db, dir, db, sw);
	expect_refused(args, 2, "not a model");
	assert_non_null(strstr(html, "no run in this sweep and are not joined: tfr@32 turntable/orbit"));
	assert_non_null(strstr(html, "were checked against this sweep"));
	int plotted = strstr(html, "plots/fig3.svg") != NULL;
	free(html);
	if (system("command -v gnuplot >/dev/null") == 0) {
		snprintf(p, sizeof p, "%s/report/plots/fig3.svg", sw);
		assert_true(plotted && tu_file_exists(p));
	}

	/* stimuli that are not the sweep's runs: refused with one line, exit 2 */
	snprintf(p, sizeof p, "%s/pairs.json", set);
	snprintf(args, sizeof args, "report %s --study %s", sw, db);
	edit(p, "\"size\": [\n    48,", "\"size\": [\n    64,");
	expect_refused(args, 2, "are not this sweep's runs: size 64x32 (the sweep's 48x32)");
	edit(p, "\"size\": [\n    64,", "\"size\": [\n    48,");
	edit(p, "\"frames\": [\n    0,\n    1\n  ]", "\"frames\": [\n    0,\n    2\n  ]");
	expect_refused(args, 2, "are not this sweep's runs: frames 0..2 (the sweep's 0..1)");
	edit(p, "\"frames\": [\n    0,\n    2\n  ]", "\"frames\": [\n    0,\n    1\n  ]");
	edit(p, "\"display_transform\": \"", "\"display_transform\": \"Rec.709 ");
	expect_refused(args, 2, "are not this sweep's runs: display transform 'Rec.709 ");
	edit(p, "\"display_transform\": \"Rec.709 ", "\"display_transform\": \"");
	/* a clip other than the sweep's (another render, or a run redone since) */
	snprintf(q, sizeof q, "%s/clips/tfr-T8.webm", set);
	snprintf(args, sizeof args, "%s/clips/tfr-T16.webm", set);
	file_copy(args, q);
	snprintf(args, sizeof args, "report %s --study %s", sw, db);
	expect_refused(args, 2, "clip clips/tfr-T8.webm is not the sweep's clip of tfr@8");
	snprintf(p, sizeof p, "%s/clips/turntable/orbit/tfr-T8.webm", sw);
	file_copy(p, q);
	if (run_cli(args))
		fail_msg("the restored study is refused:\n%s", out);

	/* a sweep nobody rated: the predictions alone; a file that is not a model: one line, exit 2 */
	snprintf(args, sizeof args, "report %s --model %s", sw, model);
	if (run_cli(args))
		fail_msg("%s", out);
	snprintf(p, sizeof p, "%s/report/index.html", sw);
	html = tu_read_file(p, NULL);
	if (!strstr(html, "<td>turntable</td><td>orbit</td><td>0</td><td>not rated</td>"
			  "<td>11.31 [8.00, 16.00]</td></tr>"))
		fail_msg("the report of an unrated sweep lacks the prediction alone");
	free(html);
	check_predicted(pred, 0);
	snprintf(args, sizeof args, "report %s --study %s --model %s", sw, db, db);
	expect_refused(args, 2, "not a model");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_study_on_sweep),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
