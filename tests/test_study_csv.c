/* test_study_csv.c — the study's ratings files (study_csv.c; the rest of the study in the other test_study*.c files):
 *  - import/export round trip and all-or-nothing validation with line numbers (test_import_export);
 *  - careless and hostile input (issue 12): import rules and CSV formulas (test_import_rules, test_export_formulas). */
#define _DEFAULT_SOURCE /* popen (test_study_util.h), symlink, link */
#include <math.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "taslab/study.h"
#include "test_study_util.h"

/* Issue 28's columns after issue 27's (study_csv.c TELEMETRY_HEADER). */
#define TELEMETRY_COLUMNS ",play_a_ms,play_b_ms,dropped_frames,total_frames,hidden,hidden_ms,hidden_play,fullscreen,broken," \
			  "retake_of"

static void test_import_export(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_io");
	char db[4096], exp[4096], bad[4096], err[1024];
	snprintf(db, sizeof db, "%s/s.db", dir);
	snprintf(exp, sizeof exp, "%s/export.csv", dir);
	sty *s = created(db);
	size_t rows;
	/* Issue 30.5: a file that is not there is an input error (was TL_ERR_ARG, "fix your command line"). */
	snprintf(bad, sizeof bad, "%s/no_such.csv", dir);
	assert_int_equal(sty_import_long(s, bad, &rows, err, sizeof err), TL_ERR_INPUT);
	assert_non_null(strstr(err, "no_such.csv: No such file or directory"));
	/* A bad row anywhere rejects the whole file, naming the line; nothing is imported. */
	snprintf(bad, sizeof bad, "%s/bad.csv", dir);
	char *src = tu_read_file(REF_DIR "/study_ratings.csv", NULL);
	assert_non_null(src);
	const char *cases[][2] = {{"P03,5,", "rating"}, {"P07,2,", "camera_motion"}, {"P10,11,", "answer"}};
	for (int i = 0; i < 3; i++) {
		char *copy = strdup(src), *at = strstr(copy, cases[i][0]);
		assert_non_null(at);
		char *lineend = strchr(at, '\n');
		size_t line = 1;
		for (char *c = copy; c < at; c++)
			line += *c == '\n';
		char row[256];
		if (i == 0)
			snprintf(row, sizeof row, "P03,5,moderate,walk,moving,tfr,8,,0,1,-1,900"); /* rating contradicts answer */
		else if (i == 1)
			snprintf(row, sizeof row, "P07,2,moderate,still,sideways,tfr,8,,1,0,0,900");
		else
			snprintf(row, sizeof row, "P10,11,dynamic,walk,moving,tfr,16,,0,3,3,900");
		FILE *f = fopen(bad, "w");
		fprintf(f, "%.*s%s%s", (int)(at - copy), copy, row, lineend);
		fclose(f);
		assert_int_equal(sty_import_long(s, bad, &rows, err, sizeof err), TL_ERR_INPUT); /* a malformed file */
		char want[64];
		snprintf(want, sizeof want, "bad.csv:%zu:", line);
		if (!strstr(err, want) || !strstr(err, cases[i][1]) || !strstr(err, "nothing imported"))
			fail_msg("message '%s' lacks '%s' / '%s'", err, want, cases[i][1]);
		free(copy);
	}
	assert_int_equal(sty_export_long(s, exp, err, sizeof err), 0);
	char *empty = tu_read_file(exp, NULL);
	assert_int_equal(tu_count_lines(empty), 1); /* header only: nothing was imported */
	free(empty);
	/* The good file imports; exporting gives the same bytes back, with issue 27's three columns: each row a test
	 * trial, answered at an unknown time ("imported"), completion unknown (empty); and issue 28's telemetry columns,
	 * empty (no telemetry, counted, a planned trial). */
	assert_int_equal(sty_import_long(s, REF_DIR "/study_ratings.csv", &rows, err, sizeof err), 0);
	assert_int_equal(sty_export_long(s, exp, err, sizeof err), 0);
	char *back = tu_read_file(exp, NULL);
	size_t want_size = strlen(src) * 2;
	char *want = malloc(want_size), *w = want;
	for (const char *line = src; *line;) {
		size_t len = strcspn(line, "\n");
		w += snprintf(w, want_size - (size_t)(w - want), "%.*s%s\n", (int)len, line,
			      line == src ? ",trial_type,answered_at,completed" TELEMETRY_COLUMNS : ",test,imported,,,,,,,,,,,");
		line += len + (line[len] == '\n');
	}
	assert_string_equal(back, want);
	free(want);
	free(back);
	/* pwcmp: ties become two rows. */
	snprintf(exp, sizeof exp, "%s/pwcmp.csv", dir);
	assert_int_equal(sty_export_pwcmp(s, exp, err, sizeof err), 0);
	char *pw = tu_read_file(exp, NULL);
	assert_true(strncmp(pw, "observer,scene,condition_A,condition_B,selected_A\n", 50) == 0);
	int ties = 0; /* rows whose rating (11th field) is 0 */
	for (const char *line = strchr(src, '\n'); line && line[1]; line = strchr(line + 1, '\n')) {
		const char *f = line + 1;
		for (int k = 0; k < 10; k++)
			f = strchr(f, ',') + 1;
		ties += f[0] == '0' && f[1] == ',';
	}
	assert_int_equal(tu_count_lines(pw), 1 + 144 + ties);
	free(pw);
	/* A second import into a used study is refused. */
	assert_int_not_equal(sty_import_long(s, REF_DIR "/study_ratings.csv", &rows, err, sizeof err), 0);
	free(src);
	sty_close(&s);
}

/* Issue 12.6: T exactly for methods with a threshold, period exactly for methods with a period (DESIGN section 4);
 * text cells that a spreadsheet would run are refused. */
static void test_import_rules(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_import_rules");
	char db[4096], csv[4096], err[1024];
	snprintf(csv, sizeof csv, "%s/r.csv", dir);
	const char *rows[][2] = {
		{"P1,0,calm,still,stationary,tfr,,,1,1,-1,5", "needs a threshold"},
		{"P1,0,calm,still,stationary,tarc-oracle,,,1,1,-1,5", "needs a threshold"},
		{"P1,0,calm,still,stationary,tasa,,,1,1,-1,5", "needs a threshold"},
		{"P1,0,calm,still,stationary,ref,8,,1,1,-1,5", "has no threshold"},
		{"P1,0,calm,still,stationary,sau,4,,1,1,-1,5", "has no threshold"},
		{"P1,0,calm,still,stationary,rrc,4,4,1,1,-1,5", "has no threshold"},
		{"P1,0,calm,still,stationary,rrc,,,1,1,-1,5", "method rrc needs a period"},
		{"P1,0,calm,still,stationary,sau,,,1,1,-1,5", "method sau needs a period"},
		{"P1,0,calm,still,stationary,tarc,8,4,1,1,-1,5", "method tarc has no period"},
		{"P1,0,calm,still,stationary,tfr,8,8,1,1,-1,5", "method tfr has no period"},
		{"P1,0,calm,still,stationary,sa,,2,1,1,-1,5", "method sa has no period"},
		{"P1,0,calm,still,stationary,ref,,1,1,1,-1,5", "method ref has no period"},
		{"P1,0,calm,still,stationary,rrc,,3,1,1,-1,5", "period '3'"},
		{"P1,0,calm,still,stationary,rrc,,16,1,1,-1,5", "period '16'"},
		{"P1,0,calm,still,stationary,rrc,,0,1,1,-1,5", "period '0'"},
		{"P1,0,calm,still,stationary,rrc,,-4,1,1,-1,5", "period '-4'"},
		{"P1,0,calm,still,stationary,rrc,, 4,1,1,-1,5", "period ' 4'"},
		{"P1,0,calm,still,stationary,rrc,,4.0,1,1,-1,5", "period '4.0'"},
		{"P1,0,calm,still,stationary,rrc,,4,1,1,-1", "expected 12 columns"},
		{"P1,0,calm,still,stationary,nosuch,8,,1,1,-1,5", "is not one of"},
		{"P1,0,calm,still,stationary,tfr,300,,1,1,-1,5", "T '300'"},
		{"P1,0,calm,still,stationary,tfr, 8,,1,1,-1,5", "T ' 8'"},
		{"=HYPERLINK(\"http://x\"),0,calm,still,stationary,tfr,8,,1,1,-1,5", "formula"},
		{"P1,0,=1+1,still,stationary,tfr,8,,1,1,-1,5", "formula"},
		{"P1,0,calm,+still,stationary,tfr,8,,1,1,-1,5", "formula"},
		{"P1,0,calm,-still,stationary,tfr,8,,1,1,-1,5", "formula"},
		{"@P1,0,calm,still,stationary,tfr,8,,1,1,-1,5", "formula"},
		{"\tP1,0,calm,still,stationary,tfr,8,,1,1,-1,5", "formula"},
		{"P1,+0,calm,still,stationary,tfr,8,,1,1,-1,5", "trial"},
		{"P1,0,calm,still,stationary,tfr,8,,1, 1,-1,5", "answer"},
	};
	for (size_t i = 0; i < sizeof rows / sizeof *rows; i++) {
		FILE *f = fopen(csv, "w");
		fprintf(f, "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms\n"
			   "P0,0,calm,still,stationary,tfr,8,,1,1,-1,5\n%s\n", rows[i][0]);
		fclose(f);
		snprintf(db, sizeof db, "%s/s%zu.db", dir, i);
		sty *s = created(db);
		size_t n;
		int rc = sty_import_long(s, csv, &n, err, sizeof err);
		if (!rc || !strstr(err, rows[i][1]) || !strstr(err, "r.csv:3:"))
			fail_msg("row '%s': rc %d, message '%s' (expected '%s')", rows[i][0], rc, err, rows[i][1]);
		sty_close(&s);
	}
	/* Files in the DESIGN section 7 layout without the period column (from before it) still import; as they
	 * cannot say a period, their rrc and sau rows are refused. */
	const char *old_header = "participant,trial,scene,camera,camera_motion,method,T,ref_first,answer,rating,rt_ms\n";
	const char *old_rows[][2] = {
		{"P1,0,calm,still,stationary,rrc,,1,1,-1,5", "method rrc needs a period"},
		{"P1,0,calm,still,stationary,sau,,1,1,-1,5", "method sau needs a period"},
		{"P1,0,calm,still,stationary,tfr,,1,1,-1,5", "needs a threshold"},
		{"P1,0,calm,still,stationary,tfr,8,,1,1,-1,5", "expected 11 columns"},
	};
	for (size_t i = 0; i < sizeof old_rows / sizeof *old_rows; i++) {
		FILE *f = fopen(csv, "w");
		fprintf(f, "%sP0,0,calm,still,stationary,tfr,8,1,1,-1,5\n%s\n", old_header, old_rows[i][0]);
		fclose(f);
		snprintf(db, sizeof db, "%s/o%zu.db", dir, i);
		sty *s = created(db);
		size_t n;
		int rc = sty_import_long(s, csv, &n, err, sizeof err);
		if (!rc || !strstr(err, old_rows[i][1]) || !strstr(err, "r.csv:3:"))
			fail_msg("old-layout row '%s': rc %d, message '%s' (expected '%s')", old_rows[i][0], rc, err, old_rows[i][1]);
		sty_close(&s);
	}
	FILE *f = fopen(csv, "w");
	fprintf(f, "%sP0,0,calm,still,stationary,tfr,8,1,1,-1,5\nP0,1,calm,still,stationary,sa,,0,1,1,\n", old_header);
	fclose(f);
	snprintf(db, sizeof db, "%s/old.db", dir);
	sty *s = created(db);
	size_t n;
	if (sty_import_long(s, csv, &n, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(n, 2);
	sty_close(&s);
	/* Every method with T and period as it has them imports, and rrc/4, rrc/8 stay two conditions. */
	f = fopen(csv, "w");
	fprintf(f, "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms\n"
		   "P0,0,calm,still,stationary,tfr,8,,1,1,-1,5\nP0,1,calm,still,stationary,sau,,1,0,1,1,\n"
		   "P0,2,calm,still,stationary,tasa-oracle,16,,0,-2,-2,86400000\nP0,3,calm,still,stationary,rrc,,4,0,1,1,7\n"
		   "P0,4,calm,still,stationary,rrc,,8,0,1,1,7\nP0,5,calm,still,stationary,sau,,2,0,1,1,7\n"
		   "P0,6,calm,still,stationary,sa,,,0,1,1,7\nP0,7,calm,still,stationary,ref,,,0,1,1,7\n");
	fclose(f);
	snprintf(db, sizeof db, "%s/good.db", dir);
	s = created(db);
	if (sty_import_long(s, csv, &n, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(n, 8);
	commit(s);
	sty_close(&s);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions"), 8);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE method = 'rrc' AND T IS NULL AND period IN (4, 8)"), 2);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE period IS NOT NULL AND method NOT IN ('rrc', 'sau')"), 0);
}

/* Issue 12.6: names from a design (pairs.json) that a spreadsheet would run are neutralised on export. */
static void test_export_formulas(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_formulas");
	char stim[4096], db[4096], err[1024], p[4200], res[4200];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(p, sizeof p, "mkdir -p %s/clips", stim);
	assert_int_equal(system(p), 0);
	const char *clips[2] = {"ref", "tfr8"};
	for (int c = 0; c < 2; c++) {
		snprintf(p, sizeof p, "%s/clips/%s.webm", stim, clips[c]);
		FILE *f = fopen(p, "w");
		fputs("clip", f);
		fclose(f);
	}
	snprintf(p, sizeof p, "%s/pairs.json", stim);
	FILE *f = fopen(p, "w");
	fputs("{\"taslab_pairs\": 1, \"scene\": \"=HYPERLINK(\\\"http://evil\\\",\\\"x\\\")\", \"camera\": \"@cam,1\","
	      " \"camera_motion\": \"moving\", \"fps\": 60, \"frames\": [0, 59], \"reference\": {\"clip\": \"clips/ref.webm\"},"
	      " \"conditions\": [{\"method\": \"tfr\", \"T\": 8, \"clip\": \"clips/tfr8.webm\"}]}", f);
	fclose(f);
	snprintf(db, sizeof db, "%s/s.db", dir);
	sty *s = created(db);
	sty_design_desc d = {.stimuli = stim, .participants = 2, .seed = 1};
	sty_design_summary sm;
	if (sty_design(s, &d, &sm, err, sizeof err))
		fail_msg("%s", err);
	commit(s);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	sty_trial t;
	for (size_t i = 0; i < n; i++) {
		assert_int_equal(sty_next_trial(s, codes[i], &t, err, sizeof err), 0);
		assert_int_equal(sty_answer(s, codes[i], t.index, 1, 700, err, sizeof err), 0);
	}
	free_codes(codes, n);
	snprintf(p, sizeof p, "%s/long.csv", dir);
	assert_int_equal(sty_export_long(s, p, err, sizeof err), 0);
	char *csv = tu_read_file(p, NULL);
	if (!strstr(csv, ",\"'=HYPERLINK(\"\"http://evil\"\",\"\"x\"\")\",\"'@cam,1\",moving,tfr,8,"))
		fail_msg("export not neutralised:\n%s", csv);
	free(csv);
	snprintf(p, sizeof p, "%s/pwcmp.csv", dir);
	assert_int_equal(sty_export_pwcmp(s, p, err, sizeof err), 0);
	csv = tu_read_file(p, NULL);
	if (!strstr(csv, ",\"'=HYPERLINK(\"\"http://evil\"\",\"\"x\"\")/@cam,1\","))
		fail_msg("pwcmp export not neutralised:\n%s", csv);
	free(csv);
	snprintf(res, sizeof res, "%s/tally", dir);
	sty_tally_desc td = {.out = res, .bootstrap = 10, .seed = 1, .keep_flagged = true};
	sty_tally(s, &td, err, sizeof err); /* two answers: statistics are mostly empty, the rows are there */
	snprintf(p, sizeof p, "%s/conditions.csv", res);
	csv = tu_read_file(p, NULL);
	if (csv && strstr(csv, ",=HYPERLINK"))
		fail_msg("tally not neutralised:\n%s", csv);
	free(csv);
	sty_close(&s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_import_export),
		cmocka_unit_test(test_import_rules),
		cmocka_unit_test(test_export_formulas),
	};
	return tu_finish(cmocka_run_group_tests(tests, NULL, NULL));
}
