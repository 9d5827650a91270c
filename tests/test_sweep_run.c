/* test_sweep_run.c — `taslab sweep` and `taslab report` as a user runs them (DESIGN section 9), on lavapipe with the
 * validation layer in every run: bad input gives one line and renders nothing; a tiny sweep writes its runs, clips,
 * metrics, summary.csv, table1.md and report, and every number of summary.csv is recomputed from the runs' stats.csv
 * and the metrics' summary.json (check_summary_numbers); a rerun redoes nothing; after a SIGKILL only the incomplete runs are
 * redone (manifest modification times of the complete ones unchanged); a failing run is reported, the others go on,
 * and the exit status says so; --slurm-dry-run prints the batch scripts; `report --study` joins a study's tally. */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "test_util.h"

static char out[1 << 16];

#define COMMON "--scenes turntable --cameras orbit --size 48x32 --device " TASLAB_TEST_DEVICE " --validation"

static int sweep(const char *args)
{
	char cmd[8192];
	snprintf(cmd, sizeof cmd, "%s sweep %s", TASLAB_BINARY, args);
	return tu_run(cmd, out, sizeof out);
}

static void expect_bad(const char *args, const char *needle, const char *must_not_exist)
{
	int st = sweep(args);
	if (st == 0 || tu_count_lines(out) != 1 || !strstr(out, needle))
		fail_msg("'taslab sweep %s' exited %d and printed:\n%s\nexpected one line containing '%s'", args, st, out, needle);
	if (must_not_exist)
		assert_false(tu_file_exists(must_not_exist));
}

static long long mtime_ns(const char *path)
{
	struct stat sb;
	if (stat(path, &sb))
		return -1;
	return (long long)sb.st_mtim.tv_sec * 1000000000LL + sb.st_mtim.tv_nsec;
}

static void mkdir_p(const char *path)
{
	char cmd[8192];
	snprintf(cmd, sizeof cmd, "mkdir -p '%s'", path);
	assert_int_equal(system(cmd), 0);
}

static void test_bad_input(void **state)
{
	(void)state;
	char dir[4096];
	snprintf(dir, sizeof dir, "%s", tu_tmpdir("sweep_bad"));
	char args[8192], sw[4096], file[4096], other[4096];
	snprintf(sw, sizeof sw, "%s/sw", dir);
	snprintf(args, sizeof args, "--scenes turntable,nowhere --variants ref --out %s", sw);
	expect_bad(args, "nowhere", sw);
	snprintf(args, sizeof args, "%s --cameras helicopter --variants ref --out %s", "--scenes turntable", sw);
	expect_bad(args, "helicopter", sw);
	snprintf(args, sizeof args, COMMON " --variants ref,nosuch@3 --out %s", sw);
	expect_bad(args, "unknown method 'nosuch'", sw);
	snprintf(args, sizeof args, COMMON " --variants tfr@8 --out %s", sw);
	expect_bad(args, "no ref", sw);
	snprintf(args, sizeof args, COMMON " --variants ref --frames 5:2 --out %s", sw);
	expect_bad(args, "--frames", sw);
	snprintf(file, sizeof file, "%s/s.json", dir);
	FILE *f = fopen(file, "w");
	fprintf(f, "{\"scenes\": [\"turntable\"], \"variants\": [\"ref\"], \"out\": \"sw\", \"treshold\": 8}\n");
	fclose(f);
	snprintf(args, sizeof args, "%s", file);
	expect_bad(args, "unknown key \"treshold\"", sw);
	/* issue 31.5: a resolved sweep.json that does not read reports its own reason (its frames), not what the
	 * request reader says of it ("device": must not be empty) */
	snprintf(file, sizeof file, "%s/broken/sweep.json", dir);
	snprintf(other, sizeof other, "%s/broken", dir);
	mkdir_p(other);
	f = fopen(file, "w");
	fprintf(f, "{\"taslab_sweep\": 1, \"scenes\": [{\"name\": \"t\", \"path\": \"/x\", \"frames\": [-6, -1], \"fps\": 60, "
		   "\"cameras\": [{\"name\": \"o\", \"motion\": \"moving\"}]}], \"variants\": [{\"variant\": \"ref\", "
		   "\"id\": \"ref\", \"method\": \"ref\", \"T\": null, \"period\": null}], \"size\": [4, 4], \"baseline\": "
		   "\"ref\", \"metrics\": \"all\", \"ppd\": 67, \"device\": \"\", \"validation\": false, \"ocio_config\": \"\", "
		   "\"display\": \"\", \"view\": \"\", \"display_transform\": \"d\"}\n");
	fclose(f);
	snprintf(args, sizeof args, "%s", file);
	expect_bad(args, "\"scenes.frames\": must be [first, end]", NULL);
	assert_int_equal(sweep(args), 2);
	snprintf(args, sizeof args, "%s --task 0", file);
	expect_bad(args, "\"scenes.frames\"", NULL);
	/* a folder that holds other files, or another sweep */
	snprintf(other, sizeof other, "%s/notes", dir);
	mkdir_p(other);
	snprintf(file, sizeof file, "%s/notes/x.txt", dir);
	f = fopen(file, "w");
	fclose(f);
	snprintf(args, sizeof args, COMMON " --variants ref --frames 0:1 --out %s", other);
	expect_bad(args, "not a sweep folder", NULL);
	snprintf(args, sizeof args, COMMON " --variants ref --frames 0:1 --out %s --slurm-dry-run", sw);
	assert_int_equal(sweep(args), 0); /* writes sweep.json and the scripts, submits nothing */
	assert_non_null(strstr(out, "#SBATCH --job-name=taslab-sweep"));
	assert_non_null(strstr(out, "--array=0"));
	assert_non_null(strstr(out, "--task \"$SLURM_ARRAY_TASK_ID\""));
	assert_non_null(strstr(out, "--dependency=afterany:"));
	snprintf(file, sizeof file, "%s/runs", sw);
	assert_false(tu_file_exists(file)); /* nothing rendered */
	snprintf(args, sizeof args, COMMON " --variants ref,tfr@8 --frames 0:1 --out %s", sw);
	expect_bad(args, "holds a different sweep (1 variants vs 2)", file);
}

/* ---- summary.csv recomputed from the run files (DESIGN section 9, README "summary.csv") ---- */

/* Splits a CSV line (no quoted cells in these files) in place into at most max cells; returns the count. */
static int split_csv(char *line, char **cell, int max)
{
	int n = 0;
	for (char *p = line; n < max;) {
		cell[n++] = p;
		char *c = strpbrk(p, ",\n");
		if (!c)
			break;
		int end = *c == '\n';
		*c = 0;
		if (end)
			break;
		p = c + 1;
	}
	return n;
}

static int col_index(char *const *head, int n, const char *name)
{
	for (int i = 0; i < n; i++)
		if (!strcmp(head[i], name))
			return i;
	fail_msg("no column %s", name);
	return -1;
}

/* Column sums, mean and median over a run's stats.csv (one row per frame). */
typedef struct run_totals {
	int frames;
	double shaded, reused, late, reuse_mean, gpu_median;
	int has_late;
} run_totals;

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static run_totals run_stats(const char *sw, const char *run, int period)
{
	char p[4096];
	snprintf(p, sizeof p, "%s/%s/stats.csv", sw, run);
	char *csv = tu_read_file(p, NULL);
	if (!csv)
		fail_msg("cannot read %s", p);
	char *save = NULL, *line = strtok_r(csv, "\n", &save), *head[64], *cell[64];
	int nh = split_csv(line, head, 64);
	int c_sh = col_index(head, nh, "shaded_samples"), c_re = col_index(head, nh, "reuse_fraction");
	int c_gpu = col_index(head, nh, "gpu_ms_total"), c_ru = col_index(head, nh, "reused_samples");
	int c_late = col_index(head, nh, "late_samples");
	run_totals t = {0};
	double gpu[1024];
	while ((line = strtok_r(NULL, "\n", &save))) {
		assert_int_equal(split_csv(line, cell, 64), nh);
		assert_true(t.frames < 1024);
		t.shaded += strtod(cell[c_sh], NULL);
		t.reused += strtod(cell[c_ru], NULL);
		t.reuse_mean += strtod(cell[c_re], NULL);
		gpu[t.frames++] = strtod(cell[c_gpu], NULL);
		if (cell[c_late][0])
			t.late += strtod(cell[c_late], NULL), t.has_late = 1;
	}
	free(csv);
	assert_true(t.frames > 0);
	t.reuse_mean /= t.frames;
	int n = t.frames; /* the frames' times, or with a period N the means of every N consecutive frames (metrics/runs.c:
			   * the amortised cost of a keyframe scheme), written over the times in place (window w reads w..) */
	if (period > 1 && n >= period) {
		for (int w = 0; w + period <= t.frames; w++) {
			double sum = 0;
			for (int k = w; k < w + period; k++)
				sum += gpu[k];
			gpu[w] = sum / period;
		}
		n = t.frames - period + 1;
	}
	qsort(gpu, (size_t)n, sizeof *gpu, cmp_double);
	t.gpu_median = n % 2 ? gpu[n / 2] : 0.5 * (gpu[n / 2 - 1] + gpu[n / 2]);
	return t;
}

/* The number after "key": in a flat JSON object (metrics summary.json); NaN when absent or null. */
static double json_number(const char *json, const char *key)
{
	char k[128];
	snprintf(k, sizeof k, "\"%s\":", key);
	const char *at = strstr(json, k);
	if (!at)
		return NAN;
	char *end;
	double v = strtod(at + strlen(k), &end);
	return end == at + strlen(k) ? NAN : v;
}

static void near(const char *what, const char *row, double got, double want, double tol)
{
	if (!(fabs(got - want) <= tol))
		fail_msg("summary.csv %s of %s: %.9g, recomputed from the run files %.9g (tolerance %g)", what, row, got, want, tol);
}

/* Every number of summary.csv recomputed from the runs' stats.csv and the metrics' summary.json: frames, reuse %
 * (mean reuse_fraction), shaded samples (sum) and per frame, reduction % against the baseline run's shaded samples,
 * median gpu_ms_total and speedup vs ref, every pooled metric, late samples and their share of the reused ones.
 * Tolerances: half a unit of the last printed decimal (summary.csv prints reuse/reduction/gpu ms/speedup with 4,
 * shaded_per_frame with 1), speedup and late % relative 1e-4 (ratios of stats.csv's 4-decimal values); metrics 1e-8
 * relative (printed with 9 significant digits from the same doubles). Returns the number of values checked. */
static int check_summary_numbers(const char *sw)
{
	char p[4096];
	snprintf(p, sizeof p, "%s/summary.csv", sw);
	char *csv = tu_read_file(p, NULL);
	assert_non_null(csv);
	char *rows[64], *save = NULL, *head[96];
	int nrows = 0;
	char *line = strtok_r(csv, "\n", &save);
	int nh = split_csv(line, head, 96);
	while ((line = strtok_r(NULL, "\n", &save)) && nrows < 64)
		rows[nrows++] = line;
	char *cells[64][96];
	for (int r = 0; r < nrows; r++)
		assert_int_equal(split_csv(rows[r], cells[r], 96), nh);
	int c_var = col_index(head, nh, "variant"), c_run = col_index(head, nh, "run"), c_base = col_index(head, nh, "baseline");
	int c_scene = col_index(head, nh, "scene"), c_cam = col_index(head, nh, "camera");
	int c_first_metric = col_index(head, nh, "maxrgb_mean"), c_late = col_index(head, nh, "late_samples");
	int checked = 0;
	/* half a unit of the 4th decimal, and a hair more: a recomputed value that is exactly a half-way case in decimal
	 * is not one in binary (119.31975 was printed as 119.3197 and then differed by 5.0000000001e-5) */
	const double half4 = 5e-5 * (1 + 1e-6);
	for (int r = 0; r < nrows; r++) {
		char **c = cells[r];
		const char *id = c[c_run];
		int c_period = col_index(head, nh, "period");
		run_totals t = run_stats(sw, id, atoi(c[c_period])), ref = {0}, base = {0};
		for (int q = 0; q < nrows; q++)
			if (!strcmp(cells[q][c_scene], c[c_scene]) && !strcmp(cells[q][c_cam], c[c_cam])) {
				if (!strcmp(cells[q][c_var], "ref"))
					ref = run_stats(sw, cells[q][c_run], atoi(cells[q][c_period]));
				if (!strcmp(cells[q][c_var], c[c_base]))
					base = run_stats(sw, cells[q][c_run], atoi(cells[q][c_period]));
			}
		assert_true(ref.frames > 0 && base.frames > 0);
		near("frames", id, strtod(c[col_index(head, nh, "frames")], NULL), t.frames, 0);
		near("reuse_percent", id, strtod(c[col_index(head, nh, "reuse_percent")], NULL), 100 * t.reuse_mean, half4);
		near("shaded_samples", id, strtod(c[col_index(head, nh, "shaded_samples")], NULL), t.shaded, 0);
		near("shaded_per_frame", id, strtod(c[col_index(head, nh, "shaded_per_frame")], NULL), t.shaded / t.frames, 0.05);
		near("reduction_percent", id, strtod(c[col_index(head, nh, "reduction_percent")], NULL),
		     100 * (1 - t.shaded / base.shaded), half4);
		near("gpu_ms_median", id, strtod(c[col_index(head, nh, "gpu_ms_median")], NULL), t.gpu_median, half4);
		double want = ref.gpu_median / t.gpu_median;
		near("speedup_vs_ref", id, strtod(c[col_index(head, nh, "speedup_vs_ref")], NULL), want, half4 + 1e-4 * want);
		checked += 7;
		/* the pooled metrics: every column from maxrgb_mean up to late_samples, from summary.json (ref: none) */
		char *json = NULL;
		if (strcmp(c[c_var], "ref")) {
			const char *slash = strrchr(id, '/');
			snprintf(p, sizeof p, "%s/metrics/%s/%s/%s/summary.json", sw, c[c_scene], c[c_cam], slash + 1);
			json = tu_read_file(p, NULL);
			if (!json)
				fail_msg("cannot read %s", p);
		}
		for (int k = c_first_metric; k < c_late; k++) {
			if (!json) {
				if (c[k][0])
					fail_msg("summary.csv: ref row has %s = %s", head[k], c[k]);
				continue;
			}
			double w = json_number(json, head[k]);
			if (isnan(w))
				fail_msg("%s: no %s in summary.json (summary.csv has '%s')", id, head[k], c[k]);
			near(head[k], id, strtod(c[k], NULL), w, 1e-8 * fmax(1.0, fabs(w)));
			checked++;
		}
		free(json);
		/* late samples (--truth) and their share of the reused samples */
		if (t.has_late && strcmp(c[c_var], "ref")) {
			near("late_samples", id, strtod(c[c_late], NULL), t.late, 0);
			near("late_percent", id, strtod(c[c_late + 1], NULL), 100 * t.late / t.reused, 1e-4 * fmax(1.0, 100 * t.late / t.reused));
			checked += 2;
		} else if (c[c_late][0] || c[c_late + 1][0]) {
			fail_msg("%s: late_samples '%s', late_percent '%s' without late samples in stats.csv", id, c[c_late], c[c_late + 1]);
		}
	}
	free(csv);
	return checked;
}

static void check_outputs(const char *sw, const char *const *ids, size_t n)
{
	char p[4096];
	const char *files[] = {"sweep.json", "summary.csv", "table1.md", "report/index.html"};
	for (size_t i = 0; i < 4; i++) {
		snprintf(p, sizeof p, "%s/%s", sw, files[i]);
		if (!tu_file_exists(p))
			fail_msg("%s missing", p);
	}
	for (size_t i = 0; i < n; i++) {
		snprintf(p, sizeof p, "%s/runs/turntable/orbit/%s/manifest.json", sw, ids[i]);
		assert_true(tu_file_exists(p));
		snprintf(p, sizeof p, "%s/clips/turntable/orbit/%s.webm", sw, ids[i]);
		assert_true(tu_file_exists(p));
		if (strcmp(ids[i], "ref")) {
			snprintf(p, sizeof p, "%s/metrics/turntable/orbit/%s/summary.json", sw, ids[i]);
			assert_true(tu_file_exists(p));
		}
	}
	snprintf(p, sizeof p, "%s/summary.csv", sw);
	char *csv = tu_read_file(p, NULL);
	assert_int_equal(tu_count_lines(csv), (int)n + 1);
	assert_true(strncmp(csv, "scene,camera,camera_motion,method,variant,T,period,frames,width,height,status,", 78) == 0);
	assert_null(strstr(csv, "missing"));
	assert_null(strstr(csv, "partial"));
	free(csv);
	fprintf(stderr, "%s: %d summary values recomputed from the run files\n", sw, check_summary_numbers(sw));
}

static void test_sweep_resume(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("sweep_run");
	char args[8192], sw[4096], p[4096];
	snprintf(sw, sizeof sw, "%s/sw", dir);
	/* warp/2 (a keyframe every 2nd frame): its speedup is the amortised cost's, which check_summary_numbers
	 * recomputes from the frames' times and the period (the plain median of frames 0-2 is a keyframe's time) */
	snprintf(args, sizeof args, COMMON " --variants ref,tfr@8,warp/2 --frames 0:3 --jobs 2 --out %s", sw);
	int st = sweep(args);
	if (st)
		fail_msg("sweep failed (%d):\n%s", st, out);
	const char *ids[] = {"ref", "tfr-T8", "warp-N2"};
	check_outputs(sw, ids, 3);
	snprintf(p, sizeof p, "%s/report/index.html", sw);
	assert_non_null(strstr(out, p)); /* the report's path on stdout */
	char *html = tu_read_file(p, NULL);
	assert_non_null(strstr(html, "plots/turntable--orbit--flip.svg"));
	assert_non_null(strstr(html, "../clips/turntable/orbit/tfr-T8.webm"));
	free(html);
	/* again: everything is complete, nothing is redone */
	snprintf(p, sizeof p, "%s/runs/turntable/orbit/tfr-T8/manifest.json", sw);
	long long before = mtime_ns(p);
	assert_int_equal(sweep(args), 0);
	assert_non_null(strstr(out, "3 complete, 0 to do"));
	assert_true(mtime_ns(p) == before);
	/* the resolved sweep.json resumes the same sweep; options that change it are refused */
	char spec[4096];
	snprintf(spec, sizeof spec, "%s/sweep.json --quiet", sw);
	assert_int_equal(sweep(spec), 0);
	snprintf(spec, sizeof spec, "%s/sweep.json --variants ref", sw);
	assert_int_not_equal(sweep(spec), 0);
	assert_non_null(strstr(out, "resolved sweep"));
}

/* --truth: the variants whose method can count late samples are rendered with --truth (their manifests say so),
 * summary.csv carries late_samples and late_percent for them (ref has neither, nor rrc-shadow/2, whose options exclude
 * --truth), and the report plots the late share against T and lists it per run. */
static void test_truth(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("sweep_truth");
	char args[8192], sw[4096], p[4096];
	snprintf(sw, sizeof sw, "%s/sw", dir);
	/* tfr reuses most samples from frame 1 on (tarc at 48x32 reshades everything: its 72x72-pixel filter footprint
	 * covers the frame) */
#define TRUTH_SWEEP COMMON " --variants ref,tfr@8,rrc-shadow/2 --frames 0:6 --out %s"
	snprintf(args, sizeof args, TRUTH_SWEEP " --truth", sw);
	int st = sweep(args);
	if (st)
		fail_msg("sweep failed (%d):\n%s", st, out);
	snprintf(p, sizeof p, "%s/runs/turntable/orbit/tfr-T8/manifest.json", sw);
	char *man = tu_read_file(p, NULL);
	assert_non_null(man);
	assert_non_null(strstr(man, "\"truth\": true"));
	free(man);
	snprintf(p, sizeof p, "%s/summary.csv", sw);
	char *csv = tu_read_file(p, NULL);
	assert_non_null(csv);
	const char *row = strstr(csv, "\nturntable,orbit,moving,tfr,tfr@8,");
	assert_non_null(row);
	/* the last three cells: late_samples (a count), late_percent (of the reused samples), run */
	const char *end = strstr(row, ",runs/turntable/orbit/tfr-T8\n");
	assert_non_null(end);
	const char *c = end - 1;
	while (c > row && *c != ',')
		c--;
	const char *c2 = c - 1;
	while (c2 > row && *c2 != ',')
		c2--;
	char *stop, *stop2;
	double late = strtod(c2 + 1, &stop), pct = strtod(c + 1, &stop2);
	assert_true(stop == c && stop2 == end && stop2 > c + 1); /* both cells filled */
	assert_true(late >= 0 && pct >= 0 && pct <= 100);
	assert_non_null(strstr(csv, ",,,runs/turntable/orbit/ref\n")); /* ref counts nothing */
	/* rrc --payload keeps no colour to count late ones against: rendered without --truth, not failed (its check) */
	assert_non_null(strstr(csv, ",,,runs/turntable/orbit/rrc-shadow-N2\n"));
	free(csv);
	snprintf(p, sizeof p, "%s/runs/turntable/orbit/rrc-shadow-N2/manifest.json", sw);
	man = tu_read_file(p, NULL);
	assert_non_null(man);
	assert_non_null(strstr(man, "\"truth\": false"));
	free(man);
	assert_true(check_summary_numbers(sw) > 0); /* late_samples and late_percent recomputed too */
	snprintf(p, sizeof p, "%s/report/plots/turntable--orbit--late.svg", sw);
	assert_true(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/report/index.html", sw);
	char *html = tu_read_file(p, NULL);
	assert_non_null(strstr(html, "late samples: reused more than T from their true shading"));
	free(html);
	/* the setting is part of the sweep: the same sweep without it into the same folder is refused */
	snprintf(args, sizeof args, TRUTH_SWEEP, sw);
	assert_int_equal(sweep(args), 2);
	assert_non_null(strstr(out, "truth on vs off"));
#undef TRUTH_SWEEP
}

/* Issue 26: the compacted-sample-path methods in a sweep beside TAS, and the matched-budget comparison. Each TAS
 * variant's partners are recomputed here from summary.csv (the setting of each other method with the nearest
 * shaded_per_frame, ties to the first) and must be the rows of table1.md's matched-budget table; the report has the
 * table and the plot of exceed_8 against shaded fraction, whose data has one block per method (not ref). */
static void test_matched_budget(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("sweep_matched");
	char args[8192], sw[4096], p[4096];
	snprintf(sw, sizeof sw, "%s/sw", dir);
	snprintf(args, sizeof args, COMMON " --variants ref,tasa@8,vref,casedge,ads@2,ads@16 --frames 0:3 --jobs 2 --out %s",
		 sw);
	int st = sweep(args);
	if (st)
		fail_msg("sweep failed (%d):\n%s", st, out);
	snprintf(p, sizeof p, "%s/summary.csv", sw);
	char *csv = tu_read_file(p, NULL);
	assert_non_null(csv);
	assert_null(strstr(csv, "missing"));
	assert_null(strstr(csv, "partial"));
	enum { MAXR = 8, MAXC = 160 };
	char *cells[MAXR][MAXC];
	int nr = 0, nc = 0;
	for (char *line = csv; line && *line && nr < MAXR; nr++) {
		char *next = strchr(line, '\n');
		int k = split_csv(line, cells[nr], MAXC);
		if (!nr)
			nc = k;
		line = next ? next + 1 : NULL;
	}
	assert_int_equal(nr, 7);
	int c_method = col_index(cells[0], nc, "method"), c_var = col_index(cells[0], nc, "variant"),
	    c_spf = col_index(cells[0], nc, "shaded_per_frame");
	assert_true(c_method >= 0 && c_var >= 0 && c_spf >= 0);
	int tas = -1;
	for (int r = 1; r < nr; r++)
		if (!strcmp(cells[r][c_var], "tasa@8"))
			tas = r;
	assert_true(tas > 0);
	double ts = strtod(cells[tas][c_spf], NULL);
	snprintf(p, sizeof p, "%s/table1.md", sw);
	char *md = tu_read_file(p, NULL);
	assert_non_null(md);
	const char *sec = strstr(md, "## Matched budget");
	assert_non_null(sec);
	char want[512];
	snprintf(want, sizeof want, "| turntable | orbit | tasa@8 | **TAS** |");
	assert_non_null(strstr(sec, want));
	const char *methods[] = {"vref", "casedge", "ads"};
	int rows = 0;
	for (size_t m = 0; m < 3; m++) {
		int best = -1;
		for (int r = 1; r < nr; r++)
			if (!strcmp(cells[r][c_method], methods[m]) &&
			    (best < 0 || fabs(strtod(cells[r][c_spf], NULL) - ts) < fabs(strtod(cells[best][c_spf], NULL) - ts)))
				best = r;
		assert_true(best > 0);
		snprintf(want, sizeof want, "| turntable | orbit | tasa@8 | %s |", cells[best][c_var]);
		if (!strstr(sec, want))
			fail_msg("table1.md has no row '%s' (tasa@8: %.1f shaded per frame):\n%s", want, ts, sec);
		rows++;
	}
	/* nothing else: ref is never matched, and one setting per method */
	int lines = 0;
	for (const char *q = strstr(sec, "| turntable | orbit | tasa@8 |"); q; q = strstr(q + 1, "| turntable | orbit | tasa@8 |"))
		lines++;
	assert_int_equal(lines, rows + 1);
	assert_null(strstr(sec, "| tasa@8 | ref |"));
	free(md);
	free(csv);
	/* the report: the table and the plot, its data one block per method other than ref */
	snprintf(p, sizeof p, "%s/report/index.html", sw);
	char *html = tu_read_file(p, NULL);
	assert_non_null(html);
	assert_non_null(strstr(html, "<h3>Matched budget</h3>"));
	assert_non_null(strstr(html, "<tr class=\"tas\"><td class=\"l\">tasa@8 (TAS)</td>"));
	assert_non_null(strstr(html, "<td class=\"l\">casedge</td>"));
	assert_non_null(strstr(html, "plots/turntable--orbit--budget.svg"));
	free(html);
	snprintf(p, sizeof p, "%s/report/plots/turntable--orbit--budget.svg", sw);
	assert_true(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/report/data/turntable--orbit--budget.csv", sw);
	char *data = tu_read_file(p, NULL);
	assert_non_null(data);
	const char *blocks[] = {"# ads\n", "# casedge\n", "# tasa\n", "# vref\n"};
	for (size_t b = 0; b < 4; b++)
		assert_non_null(strstr(data, blocks[b]));
	assert_null(strstr(data, "# ref\n"));
	assert_non_null(strstr(data, ",ads@2\n"));
	assert_non_null(strstr(data, ",ads@16\n"));
	free(data);
}

/* Starts `taslab sweep ARGS` in the background; returns its pid. */
static pid_t start(const char *args, const char *log)
{
	pid_t pid = fork();
	if (pid == 0) {
		char cmd[8192];
		snprintf(cmd, sizeof cmd, "%s exec %s sweep %s >%s 2>&1", tu_child_env(), TASLAB_BINARY, args, log);
		execl("/bin/sh", "sh", "-c", cmd, (char *)NULL);
		_exit(127);
	}
	return pid;
}

static void test_sigkill_resume(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("sweep_kill");
	char args[8192], sw[4096], ref_m[4096], rrc_m[4096], tfr_m[4096], rrc_f[4096], log[4096];
	snprintf(sw, sizeof sw, "%s/sw", dir);
	snprintf(log, sizeof log, "%s/first.log", dir);
	snprintf(args, sizeof args, COMMON " --variants ref,rrc/4,tfr@8 --frames 0:12 --jobs 1 --no-report --out %s", sw);
	snprintf(ref_m, sizeof ref_m, "%s/runs/turntable/orbit/ref/manifest.json", sw);
	snprintf(rrc_m, sizeof rrc_m, "%s/runs/turntable/orbit/rrc-N4/manifest.json", sw);
	snprintf(rrc_f, sizeof rrc_f, "%s/runs/turntable/orbit/rrc-N4/frames/000001.png", sw);
	snprintf(tfr_m, sizeof tfr_m, "%s/runs/turntable/orbit/tfr-T8/manifest.json", sw);
	pid_t pid = start(args, log);
	/* kill the sweep (the parent, as `kill -9` would) while the second run is rendering */
	struct timespec ts = {0, 10 * 1000 * 1000};
	int waited = 0;
	while (!(tu_file_exists(ref_m) && tu_file_exists(rrc_f)) && waited < 300 * 100) {
		nanosleep(&ts, NULL);
		waited++;
	}
	assert_true(tu_file_exists(rrc_f));
	kill(pid, SIGKILL);
	waitpid(pid, NULL, 0);
	sleep(1); /* the run's process dies with its parent (PR_SET_PDEATHSIG) */
	assert_true(tu_file_exists(ref_m));
	assert_false(tu_file_exists(rrc_m)); /* interrupted: not complete */
	assert_false(tu_file_exists(tfr_m));
	long long ref_before = mtime_ns(ref_m);
	/* nothing renders into the folder any more: the killed sweep's child is gone */
	char frames[4096];
	snprintf(frames, sizeof frames, "%s/runs/turntable/orbit/rrc-N4/frames/000011.png", sw);
	sleep(1);
	assert_false(tu_file_exists(frames));
	int st = sweep(args);
	if (st)
		fail_msg("resumed sweep failed (%d):\n%s", st, out);
	assert_non_null(strstr(out, "1 complete, 2 to do"));
	assert_true(mtime_ns(ref_m) == ref_before); /* the complete run was not redone */
	assert_true(tu_file_exists(rrc_m) && tu_file_exists(tfr_m));
	const char *ids[] = {"ref", "rrc-N4", "tfr-T8"};
	char p[4096];
	snprintf(p, sizeof p, "%s/report", sw);
	assert_false(tu_file_exists(p)); /* --no-report */
	for (size_t i = 0; i < 3; i++) {
		snprintf(p, sizeof p, "%s/runs/turntable/orbit/%s/manifest.json", sw, ids[i]);
		assert_true(tu_file_exists(p));
	}
}

static void test_failure_and_study(void **state)
{
	(void)state;
	char dir[4096];
	snprintf(dir, sizeof dir, "%s", tu_tmpdir("sweep_fail"));
	char args[8192], sw[4096], p[4096];
	snprintf(sw, sizeof sw, "%s/sw", dir);
	snprintf(args, sizeof args, COMMON " --variants ref,tfr@8,rrc/2 --frames 0:2 --out %s", sw);
	/* make one run fail: its run folder's place is taken by a file */
	char sweep_dir[4096];
	snprintf(sweep_dir, sizeof sweep_dir, "%s/runs/turntable/orbit", sw);
	snprintf(p, sizeof p, "--slurm-dry-run " COMMON " --variants ref,tfr@8,rrc/2 --frames 0:2 --out %s", sw);
	assert_int_equal(sweep(p), 0); /* writes sweep.json only */
	mkdir_p(sweep_dir);
	snprintf(p, sizeof p, "%s/rrc-N2", sweep_dir);
	FILE *f = fopen(p, "w");
	fclose(f);
	int st = sweep(args);
	assert_int_equal(st, 1); /* some runs failed */
	assert_non_null(strstr(out, "turntable/orbit/rrc-N2 failed"));
	assert_non_null(strstr(out, "1 of 3 runs failed or are incomplete"));
	snprintf(p, sizeof p, "%s/runs/turntable/orbit/tfr-T8/manifest.json", sw);
	assert_true(tu_file_exists(p)); /* the others went on */
	snprintf(p, sizeof p, "%s/summary.csv", sw);
	char *csv = tu_read_file(p, NULL);
	assert_non_null(strstr(csv, "rrc/2,,2,2,48,32,missing"));
	/* without --truth no late counts: the row ends in two empty cells before the run path */
	assert_non_null(strstr(csv, ",late_samples,late_percent,run\n"));
	assert_non_null(strstr(csv, ",,,runs/turntable/orbit/tfr-T8\n"));
	free(csv);

	/* a study of tfr@8 on this scene and path: report --study joins it per condition */
	char ratings[4096], db[4096];
	snprintf(ratings, sizeof ratings, "%s/ratings.csv", dir);
	snprintf(db, sizeof db, "%s/study.db", dir);
	f = fopen(ratings, "w");
	fprintf(f, "participant,trial,scene,camera,camera_motion,method,T,ref_first,answer,rating,rt_ms\n");
	const int answers[6] = {1, 0, -1, 2, 1, 0};
	for (int i = 0; i < 6; i++) /* ref second, answer +a: the reference preferred by a */
		fprintf(f, "P%d,0,turntable,orbit,moving,tfr,8,0,%d,%d,1500\n", i, answers[i], answers[i]);
	fclose(f);
	char cmd[8192];
	snprintf(cmd, sizeof cmd, "%s study import --db %s %s", TASLAB_BINARY, db, ratings);
	st = tu_run(cmd, out, sizeof out);
	if (st)
		fail_msg("study import failed: %s", out);
	/* a coherence analysis of this scene and path (as `taslab analyze coherence --out SW/analysis/turntable/orbit`
	 * writes it): the report draws its curves */
	char analysis[4096];
	snprintf(analysis, sizeof analysis, "%s/analysis/turntable/orbit", sw);
	mkdir_p(analysis);
	snprintf(p, sizeof p, "%s/coherence.csv", analysis);
	f = fopen(p, "w");
	fprintf(f, "T,k,unchanged_samples,visible_samples,fraction_unchanged\n");
	for (int T = 2; T <= 64; T *= 2)
		for (int k = 1; k <= 120; k++)
			fprintf(f, "%d,%d,%d,1000,%.4f\n", T, k, 1000 - k * 8 / T, (1000 - k * 8 / T) / 1000.0);
	fclose(f);
	snprintf(cmd, sizeof cmd, "%s report %s --study %s --jnd-against maxrgb_p99 --quiet", TASLAB_BINARY, sw, db);
	st = tu_run(cmd, out, sizeof out);
	assert_int_equal(st, 1); /* written, but a run is still missing */
	assert_non_null(strstr(out, "report written, but 1 of 3 runs are incomplete"));
	snprintf(p, sizeof p, "%s/report/data/study.csv", sw);
	csv = tu_read_file(p, NULL);
	assert_non_null(csv);
	/* p_ref = (3 preferring the reference + 2 ties / 2) / 6 = 4/6 */
	assert_non_null(strstr(csv, "turntable,orbit,tfr,tfr@8,8,,"));
	assert_non_null(strstr(csv, ",6,0.5,"));  /* n = 6, Q = mean rating 0.5 */
	assert_non_null(strstr(csv, ",0.666667,"));
	free(csv);
	snprintf(p, sizeof p, "%s/report/plots/jnd.svg", sw);
	assert_true(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/report/plots/turntable--orbit--coherence.svg", sw);
	assert_true(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/report/index.html", sw);
	char *html = tu_read_file(p, NULL);
	assert_non_null(strstr(html, "JND [95%]"));
	assert_non_null(strstr(html, "0.67 ["));
	free(html);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_bad_input),
		cmocka_unit_test(test_sweep_resume),
		cmocka_unit_test(test_truth),
		cmocka_unit_test(test_matched_budget),
		cmocka_unit_test(test_sigkill_resume),
		cmocka_unit_test(test_failure_and_study),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
