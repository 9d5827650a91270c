/* test_study_tables.c — issue 27.10 and 27.11: one convention for undefined values in every tally output, the reason
 * for a missing ANOVA, the tables of tables.md, Q intervals that stay on the rating scale, and the report plots' key
 * (a canvas that grows with it, 32 distinct line types: test_plot_preamble).
 *
 * References:
 *  - Q intervals: R 4.x, t.test(x)$conf.int cut to [-2, 2] (the values are in the test; tolerance 1e-6, as
 *    conditions.csv prints 6 decimals): x = (2, 2, 1): mean 1.666667, raw [0.232449090, 3.100884243] -> [0.232449, 2];
 *    x = (2, 1): raw [-4.853102368, 7.853102368] -> [-2, 2]; x = (1, 0, -1, 0): [-1.299228264, 1.299228264] (inside).
 *  - undefined and infinite statistics by hand: identical cells give 0/0 (F, t undefined: empty cells, JSON null);
 *    a constant non-zero difference gives an error variance of 0 and an effect variance above 0 (F, t infinite:
 *    "inf", p = 0);
 *  - tables.md's ANOVA row against R's F (tests/reference/study_reference.csv, aov; 3 decimals as tables.md prints). */
#define _DEFAULT_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/metrics.h"
#include "test_study_util.h"

static char out[65536];

/* Writes a ratings file (DESIGN section 7 long format, ref_first 0 so rating = answer): rows "P,scene,camera,T,r". */
static void write_ratings(const char *path, const char *const *rows, size_t n)
{
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	fprintf(f, "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms\n");
	for (size_t i = 0; i < n; i++) {
		char p[16], sc[32], ca[32], T[8];
		int r;
		assert_int_equal(sscanf(rows[i], "%15[^,],%31[^,],%31[^,],%7[^,],%d", p, sc, ca, T, &r), 5);
		fprintf(f, "%s,%zu,%s,%s,%s,tfr,%s,,0,%d,%d,1000\n", p, i, sc, ca, strcmp(ca, "walk") ? "stationary" : "moving",
			T, r, r);
	}
	fclose(f);
}

/* Imports `rows` into a new study in dir/name.db and tallies it into dir/name (the command line, as a user would);
 * returns the tally's output (stdout and stderr). */
static const char *import_tally(const char *dir, const char *name, const char *const *rows, size_t n)
{
	char csv[4200], cmd[16384];
	snprintf(csv, sizeof csv, "%s/%s.csv", dir, name);
	write_ratings(csv, rows, n);
	snprintf(cmd, sizeof cmd, "%s study import --db %s/%s.db %s && %s study tally --db %s/%s.db --out %s/%s --bootstrap 50",
		 TASLAB_BINARY, dir, name, csv, TASLAB_BINARY, dir, name, dir, name);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s", out);
	return out;
}

/* No output of the tally spells an undefined value "nan" or "-nan" (issue 27.10: one convention). */
static void no_nan_text(const char *res)
{
	const char *files[] = {"conditions.csv", "anova.csv", "posthoc.csv", "jod.csv", "fig3.csv", "observers.csv",
			       "thresholds.csv", "conditions.json", "anova.json", "tables.md"};
	for (size_t i = 0; i < sizeof files / sizeof *files; i++) {
		char p[4400];
		snprintf(p, sizeof p, "%s/%s", res, files[i]);
		char *t = tu_read_file(p, NULL);
		assert_non_null(t);
		for (char *c = t; *c; c++)
			*c = (char)(*c >= 'A' && *c <= 'Z' ? *c - 'A' + 'a' : *c);
		if (strstr(t, "nan"))
			fail_msg("%s spells an undefined value 'nan':\n%s", p, t);
		free(t);
	}
}

static char *read_res(const char *res, const char *file)
{
	char p[4400];
	snprintf(p, sizeof p, "%s/%s", res, file);
	char *t = tu_read_file(p, NULL);
	if (!t)
		fail_msg("%s missing", p);
	return t;
}

static void check_near(const char *what, double got, double want)
{
	if (!(fabs(got - want) <= 1e-6))
		fail_msg("%s: ours %.9g, R %.9g (tolerance 1e-6)", what, got, want);
}

/* One scene and one camera path: no ANOVA, said once on stderr, in anova.csv/json and tables.md; Q intervals cut to
 * the scale (R values above). */
static void test_one_scene(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_tables_one");
	static const char *const rows[] = {"P01,calm,still,8,2", "P02,calm,still,8,2", "P03,calm,still,8,1",
					   "P01,calm,still,16,2", "P02,calm,still,16,1", "P01,calm,still,4,1",
					   "P02,calm,still,4,0",  "P03,calm,still,4,-1", "P04,calm,still,4,0"};
	const char *log = import_tally(dir, "one", rows, sizeof rows / sizeof *rows);
	char res[4200];
	snprintf(res, sizeof res, "%s/one", dir);
	/* stderr: one line for every variant */
	const char *line = strstr(log, "no ANOVA");
	assert_non_null(line);
	assert_non_null(strstr(log, "taslab study: no ANOVA for any variant: one scene (calm) and one camera motion (stationary)"));
	assert_null(strstr(line + 1, "no ANOVA"));
	char *anova = read_res(res, "anova.csv");
	assert_string_equal(anova,
			    "method,T,period,effect,df1,df2,F,p,p_gg,epsilon_gg,note\n"
			    "tfr,4,,,,,,,,,one scene (calm) and one camera motion (stationary): no factor with two levels to compare\n"
			    "tfr,8,,,,,,,,,one scene (calm) and one camera motion (stationary): no factor with two levels to compare\n"
			    "tfr,16,,,,,,,,,one scene (calm) and one camera motion (stationary): no factor with two levels to compare\n");
	free(anova);
	char *js = read_res(res, "anova.json");
	assert_non_null(strstr(js, "\"effect\": null"));
	assert_non_null(strstr(js, "\"note\": \"one scene (calm)"));
	free(js);
	char *md = read_res(res, "tables.md");
	assert_non_null(strstr(md, "None: no variant could be analysed"));
	assert_non_null(strstr(md, "- tfr T=8: no ANOVA: one scene (calm) and one camera motion (stationary)"));
	const char *sections[] = {"## Conditions", "## Repeated-measures ANOVA", "## Post hoc paired t tests", "## Observers",
				  "## JOD"};
	for (size_t i = 0; i < 5; i++)
		if (!strstr(md, sections[i]))
			fail_msg("tables.md lacks '%s':\n%s", sections[i], md);
	/* Q of (2,2,1) and (2,1) and (1,0,-1,0) with the t interval cut to -2..2 (R, see the top) */
	char p[4400];
	snprintf(p, sizeof p, "%s/conditions.csv", res);
	const char *k8[5] = {"tfr", "8", "", "calm", "still"}, *k16[5] = {"tfr", "16", "", "calm", "still"};
	const char *k4[5] = {"tfr", "4", "", "calm", "still"};
	check_near("Q T=8", tu_csv_lookup(p, k8, 5, 6), 1.666666667);
	check_near("Q_lo T=8", tu_csv_lookup(p, k8, 5, 7), 0.232449090);
	check_near("Q_hi T=8 (R 3.100884 cut to 2)", tu_csv_lookup(p, k8, 5, 8), 2.0);
	check_near("Q_lo T=16 (R -4.853102 cut to -2)", tu_csv_lookup(p, k16, 5, 7), -2.0);
	check_near("Q_hi T=16 (R 7.853102 cut to 2)", tu_csv_lookup(p, k16, 5, 8), 2.0);
	check_near("Q_lo T=4", tu_csv_lookup(p, k4, 5, 7), -1.299228264);
	check_near("Q_hi T=4", tu_csv_lookup(p, k4, 5, 8), 1.299228264);
	assert_non_null(strstr(md, "| tfr | 8 |  | calm | still | 3 | 1.67 [0.23, 2.00] |"));
	free(md);
	no_nan_text(res);
}

/* Every cell identical (F and t are 0/0) and a constant non-zero difference between scenes (error variance 0:
 * F and t infinite, p = 0): undefined as empty cells / null with the reason beside them, infinite as inf. */
static void test_undefined_and_infinite(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_tables_undef");
	static const char *const same[] = {
		"P01,calm,still,8,1", "P01,calm,walk,8,1", "P01,dyn,still,8,1", "P01,dyn,walk,8,1",
		"P02,calm,still,8,1", "P02,calm,walk,8,1", "P02,dyn,still,8,1", "P02,dyn,walk,8,1",
		"P03,calm,still,8,1", "P03,calm,walk,8,1", "P03,dyn,still,8,1", "P03,dyn,walk,8,1",
	};
	const char *log = import_tally(dir, "same", same, sizeof same / sizeof *same);
	assert_non_null(strstr(log, "taslab study: tfr T=8: ANOVA incomplete: identical cells"));
	char res[4200];
	snprintf(res, sizeof res, "%s/same", dir);
	char *anova = read_res(res, "anova.csv");
	assert_non_null(strstr(anova, "tfr,8,,camera,1,2,,,,1.000000,identical cells: no variance (F undefined)\n"));
	assert_non_null(strstr(anova, "tfr,8,,scene,1,2,,,,1.000000,identical cells: no variance (F undefined)\n"));
	free(anova);
	char *ph = read_res(res, "posthoc.csv");
	assert_non_null(strstr(ph, "tfr,8,,camera,stationary,moving,,2,,\n"));
	free(ph);
	char *js = read_res(res, "anova.json");
	assert_non_null(strstr(js, "\"F\": null"));
	assert_null(strstr(js, "\"F\": 0"));
	free(js);
	no_nan_text(res);

	/* calm rated 1, dyn 0 by everyone: the scene contrast is the same non-zero value for every participant */
	static const char *const diff[] = {
		"P01,calm,still,8,1", "P01,calm,walk,8,1", "P01,dyn,still,8,0", "P01,dyn,walk,8,0",
		"P02,calm,still,8,1", "P02,calm,walk,8,1", "P02,dyn,still,8,0", "P02,dyn,walk,8,0",
		"P03,calm,still,8,1", "P03,calm,walk,8,1", "P03,dyn,still,8,0", "P03,dyn,walk,8,0",
	};
	import_tally(dir, "diff", diff, sizeof diff / sizeof *diff);
	snprintf(res, sizeof res, "%s/diff", dir);
	anova = read_res(res, "anova.csv");
	assert_non_null(strstr(anova, "tfr,8,,scene,1,2,inf,0,0,1.000000,\n"));
	free(anova);
	ph = read_res(res, "posthoc.csv");
	assert_non_null(strstr(ph, "tfr,8,,scene,calm,dyn,inf,2,0,0\n"));
	free(ph);
	js = read_res(res, "anova.json");
	assert_non_null(strstr(js, "\"F\": \"inf\""));
	free(js);
	char *md = read_res(res, "tables.md");
	assert_non_null(strstr(md, "| tfr | 8 |  | scene | 1 | 2 | inf | 0 |"));
	assert_non_null(strstr(md, "| tfr | 8 |  | camera | 1 | 2 | – | – |"));
	free(md);
	no_nan_text(res);
}

/* tables.md of the R reference study holds the ANOVA with R's F and the observers and JOD tables. */
static void test_tables_vs_r(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_tables_r");
	char cmd[16384], res[4200];
	snprintf(res, sizeof res, "%s/t", dir);
	snprintf(cmd, sizeof cmd, "%s study import --db %s/r.db %s/study_ratings.csv && %s study tally --db %s/r.db --out %s "
		 "--bootstrap 50", TASLAB_BINARY, dir, REF_DIR, TASLAB_BINARY, dir, res);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s", out);
	assert_null(strstr(out, "no ANOVA"));
	char *md = read_res(res, "tables.md");
	const char *effects[3] = {"camera", "scene", "camera:scene"}, *Ts[2] = {"8", "16"};
	for (int t = 0; t < 2; t++)
		for (int e = 0; e < 3; e++) {
			const char *key[3] = {"F", Ts[t], effects[e]};
			double F = tu_csv_lookup(REF_DIR "/study_reference.csv", key, 3, 3);
			assert_false(isnan(F));
			char row[256];
			snprintf(row, sizeof row, "| tfr | %s |  | %s | ", Ts[t], effects[e]);
			const char *at = strstr(md, row);
			if (!at)
				fail_msg("tables.md has no ANOVA row '%s'", row);
			char want[32];
			snprintf(want, sizeof want, "| %.3f |", F);
			const char *eol = strchr(at, '\n');
			const char *hit = strstr(at, want);
			if (!hit || hit > eol)
				fail_msg("tables.md ANOVA row for T=%s %s lacks R's F %s: %.*s", Ts[t], effects[e], want,
					 (int)(eol - at), at);
		}
	assert_non_null(strstr(md, "| P01 | 0 | – | 0 | no |")); /* imported: no catch trials, mean undefined */
	assert_non_null(strstr(md, "| tfr | 8 |  | all | all | "));
	assert_non_null(strstr(md, "## Post hoc paired t tests (Bonferroni)\n\n| method |"));
	free(md);
	no_nan_text(res);
}

/* A sweep of every method lists twenty-odd lines in a plot's key: the canvas must grow by a key row per three entries
 * (the plot area keeps its height) and the first 32 lines must differ in colour or in dash and point type. */
static void test_plot_preamble(void **state)
{
	(void)state;
	char *buf = NULL;
	size_t len = 0;
	FILE *f = open_memstream(&buf, &len);
	assert_non_null(f);
	mtr_plot_svg_preamble(f, 22);
	fclose(f);
	assert_non_null(strstr(buf, "set terminal svg size 460,370 ")); /* 250 + 15 x 8 rows of three */
	char seen[32][48];
	for (int k = 1; k <= 32; k++) {
		char key[32];
		snprintf(key, sizeof key, "set linetype %d lc rgb '", k);
		const char *at = strstr(buf, key);
		assert_non_null(at);
		at += strlen(key);
		const char *nl = strchr(at, '\n');
		assert_non_null(nl);
		snprintf(seen[k - 1], sizeof seen[k - 1], "%.*s", (int)(nl - at), at); /* colour, dash, point */
		for (int j = 0; j < k - 1; j++)
			assert_string_not_equal(seen[j], seen[k - 1]);
	}
	free(buf);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_one_scene),
		cmocka_unit_test(test_undefined_and_infinite),
		cmocka_unit_test(test_tables_vs_r),
		cmocka_unit_test(test_plot_preamble),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
