/* test_study_sweep.c — a study rated on a sweep's own clips and joined back to it (issue 27.12, 27.13):
 *  - `taslab study pairs --sweep` makes one pairs.json set per scene and camera path whose clips are the sweep's
 *    clips byte for byte (bad input: an unknown variant, the reference, a folder in the way: one line, exit 2);
 *  - `taslab report SWEEP --study` joins the study (data/study.csv: one row per rated run, Q and p_ref as the tally's
 *    conditions.csv states them), draws Fig. 3 (data/fig3.csv: the pooled rows of the tally, one per T) and says on
 *    stderr and on the page which of the study's conditions no run has;
 *  - it refuses (one line, exit 2, nothing of the study written) a study whose stimuli are not the sweep's runs:
 *    another size, other frames, another display transform, a clip that is not the sweep's.
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

	/* the join: two rated runs, the tfr@32 condition said to have none, Fig. 3 */
	snprintf(args, sizeof args, "report %s --study %s", sw, db);
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
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_study_on_sweep),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
