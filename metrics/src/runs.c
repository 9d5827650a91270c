/* runs.c — per-run shading statistics from stats.csv / manifest.json (see metrics_runs.h). */
#include "taslab/metrics_runs.h"

#include <errno.h>
#include <stdbool.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "taslab/metrics.h"
#include "taslab/run.h"
#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"
#include "taslab/tl_json.h"


static int cmpd(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* Sum of a column over the rows; NAN when the column is absent or every cell empty. */
static double column_sum(const run_stats *st, const char *name)
{
	int c = run_stats_col(st, name);
	double sum = 0;
	int seen = 0;
	for (size_t r = 0; c >= 0 && r < st->rows; r++) {
		double v = st->values[r * st->cols + (size_t)c];
		if (isfinite(v))
			sum += v, seen = 1;
	}
	return seen ? sum : NAN;
}

static int summarise_one(const char *run, mtr_run_summary *s, char *err, size_t err_size)
{
	memset(s, 0, sizeof *s);
	snprintf(s->path, sizeof s->path, "%s", run);
	run_manifest m;
	run_stats st;
	int rc = run_manifest_read(run, &m, err, err_size);
	if (!rc && !m.facts.known) /* made before the manifest said what it is (issue 30.1): no baseline can be found */
		return tl_error(err, err_size, TL_ERR_INPUT,
				"%s/manifest.json: no inputs.method_facts (made by an older taslab); render the run again", run);
	if (rc || (rc = run_stats_read(run, &st, err, err_size)))
		return rc;
	snprintf(s->method, sizeof s->method, "%s", m.method);
	s->facts = m.facts;
	snprintf(s->variant, sizeof s->variant, "%s", m.variant[0] ? m.variant : m.method);
	snprintf(s->scene, sizeof s->scene, "%s", m.scene);
	snprintf(s->camera, sizeof s->camera, "%s", m.camera);
	snprintf(s->camera_motion, sizeof s->camera_motion, "%s", m.camera_motion);
	s->threshold = m.threshold;
	s->period = m.period;
	s->width = m.width;
	s->height = m.height;
	s->first_frame = m.first_frame;
	int c_reuse = run_stats_col(&st, "reuse_fraction"), c_gpu = run_stats_col(&st, "gpu_ms_total");
	int c_shaded = run_stats_col(&st, "shaded_samples"), c_vis = run_stats_col(&st, "visible_samples");
	if (c_reuse < 0 || c_gpu < 0 || c_shaded < 0 || c_vis < 0 || st.rows == 0) {
		run_stats_free(&st);
		return tl_error(err, err_size, TL_ERR_INPUT,
				"%s/stats.csv: no frames, or missing columns (visible_samples, shaded_samples, reuse_fraction, "
				"gpu_ms_total)", run);
	}
	double *gpu_ms = malloc(st.rows * sizeof *gpu_ms);
	if (!gpu_ms) {
		run_stats_free(&st);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	size_t ng = 0;
	for (size_t r = 0; r < st.rows; r++) {
		const double *v = st.values + r * st.cols;
		s->frames++;
		s->reuse_mean += isfinite(v[c_reuse]) ? v[c_reuse] : 0.0;
		if (isfinite(v[c_gpu]))
			gpu_ms[ng++] = v[c_gpu];
	}
	/* A variant with a period N (warp/N shades a keyframe every N frames and extrapolates the others, rrc/N, sau/N,
	 * stu/N spread their refresh) costs per frame what N consecutive frames cost together / N: its frame time is the
	 * median over every window of N consecutive timed frames of the window's mean (the amortised cost). The plain
	 * median would be an extrapolated frame's time (warp/4 read 8.95x ref at 240x135). Frames are in order here;
	 * a run with an untimed frame (or no memory for the windows) keeps the plain median. */
	size_t N = m.period > 1 ? m.period : 1;
	double *win = N > 1 && ng == st.rows && ng >= N ? malloc(ng * sizeof *win) : NULL; /* every frame timed */
	if (win) {
		size_t nw = ng - N + 1;
		for (size_t w = 0; w < nw; w++) {
			double sum = 0;
			for (size_t k = w; k < w + N; k++)
				sum += gpu_ms[k];
			win[w] = sum / (double)N;
		}
		memcpy(gpu_ms, win, nw * sizeof *win);
		free(win);
		ng = nw;
	}
	s->reuse_mean /= (double)s->frames;
	s->visible_samples = column_sum(&st, "visible_samples");
	s->shaded_samples = column_sum(&st, "shaded_samples");
	s->allocated_samples = column_sum(&st, "allocated_samples");
	s->fs_invocations = column_sum(&st, "fs_invocations");
	s->reused_samples = column_sum(&st, "reused_samples");
	s->late_samples = column_sum(&st, "late_samples");
	run_stats_free(&st);
	if (ng) {
		qsort(gpu_ms, ng, sizeof *gpu_ms, cmpd);
		s->gpu_ms_median = ng % 2 ? gpu_ms[ng / 2] : 0.5 * (gpu_ms[ng / 2 - 1] + gpu_ms[ng / 2]);
	} else {
		s->gpu_ms_median = NAN;
	}
	free(gpu_ms);
	return TL_OK;
}

/* Same scene, camera path, frames and size: runs whose counts and times can be compared. */
static bool same_clip(const mtr_run_summary *a, const mtr_run_summary *b)
{
	return !strcmp(a->scene, b->scene) && !strcmp(a->camera, b->camera) && a->first_frame == b->first_frame &&
	       a->frames == b->frames && a->width == b->width && a->height == b->height;
}

int mtr_runs_summarise(const char *const *runs, size_t n, const char *baseline, mtr_run_summary *out, char *err,
		       size_t err_size)
{
	for (size_t i = 0; i < n; i++) {
		int rc = summarise_one(runs[i], &out[i], err, err_size);
		if (rc)
			return rc;
	}
	for (size_t i = 0; i < n; i++) {
		out[i].reduction = out[i].speedup_vs_ref = NAN;
		/* Default baseline: the one the run's manifest names when its run is there (sa for the atlas methods: Table 1
		 * is "reduction to SA"), else the reference run (issue 30.1: the manifests say which, not method names). */
		const char *base = baseline;
		for (size_t r = 0; !base && r < n; r++)
			if (same_clip(&out[r], &out[i]) && !strcmp(out[r].variant, out[i].facts.baseline))
				base = out[i].facts.baseline;
		for (size_t r = 0; !base && r < n; r++)
			if (same_clip(&out[r], &out[i]) && out[r].facts.reference)
				base = out[r].variant;
		for (size_t r = 0; r < n; r++) {
			if (!same_clip(&out[r], &out[i]))
				continue;
			if (base && !isfinite(out[i].reduction) && !strcmp(out[r].variant, base) && out[r].shaded_samples > 0) {
				out[i].reduction = 1.0 - out[i].shaded_samples / out[r].shaded_samples;
				snprintf(out[i].baseline, sizeof out[i].baseline, "%s", base);
			}
			if (!isfinite(out[i].speedup_vs_ref) && out[r].facts.reference)
				out[i].speedup_vs_ref = out[r].gpu_ms_median / out[i].gpu_ms_median;
		}
	}
	return 0;
}

static void num(FILE *f, double v, const char *fmt)
{
	if (isfinite(v))
		fprintf(f, fmt, v);
}

void mtr_fprint_shown(FILE *f, const char *fmt, double v)
{
	char buf[64];
	snprintf(buf, sizeof buf, fmt, v);
	/* a rounded zero: only a sign, zeros, a point and the format's own text (no other digit); -inf keeps its sign */
	bool zero = buf[0] == '-' && isfinite(v);
	for (const char *c = buf + 1; zero && *c; c++)
		zero = !(*c >= '1' && *c <= '9');
	fputs(zero ? buf + 1 : buf, f);
}

static json_t *jnum(double v) { return isfinite(v) ? json_real(v) : json_null(); }

/* runs.csv columns, in order (mtr_runs_plot finds its columns here by name). */
static const char *const csv_columns[] = {
	"run", "scene", "camera", "camera_motion", "method", "variant", "T", "period", "frames", "width", "height",
	"visible_samples", "shaded_samples", "allocated_samples", "reuse_percent", "reduction_percent", "baseline",
	"fs_invocations", "gpu_ms_median", "speedup_vs_ref", "reused_samples", "late_samples", "late_percent", NULL};

static int csv_column(const char *name)
{
	for (int i = 0; csv_columns[i]; i++)
		if (!strcmp(csv_columns[i], name))
			return i + 1; /* gnuplot counts from 1 */
	return 0;
}

static void write_table1(FILE *f, const mtr_run_summary *s, size_t n)
{
	fprintf(f, "# Shaded samples and their reduction against the baseline (cf. paper Table 1)\n\n"
		   "Shaded samples are the methods' own counts of samples whose shading ran (DESIGN section 5), per "
		   "frame; the reduction is 1 - shaded / baseline's shaded over the same frames.\n");
	for (size_t g = 0; g < n; g++) {
		bool first = true;
		for (size_t j = 0; j < g; j++)
			first &= !same_clip(&s[j], &s[g]);
		if (!first)
			continue;
		fprintf(f, "\n## %s / %s (%s), %ux%u, %zu frames from %u\n\n", s[g].scene, s[g].camera, s[g].camera_motion,
			s[g].width, s[g].height, s[g].frames, s[g].first_frame);
		fprintf(f, "| variant | shaded samples per frame | reduction | reuse | speedup vs ref |\n|---|---:|---:|---:|---:|\n");
		for (size_t i = g; i < n; i++) {
			if (!same_clip(&s[i], &s[g]))
				continue;
			fprintf(f, "| %s | %.0f | ", s[i].variant, s[i].shaded_samples / (double)s[i].frames);
			if (isfinite(s[i].reduction))
				mtr_fprint_shown(f, "%.2f %%", 100 * s[i].reduction), fprintf(f, " vs %s", s[i].baseline);
			else
				fprintf(f, "–");
			fputs(" | ", f), mtr_fprint_shown(f, "%.2f %%", 100 * s[i].reuse_mean), fputs(" | ", f);
			if (isfinite(s[i].speedup_vs_ref))
				fprintf(f, "%.2fx", s[i].speedup_vs_ref);
			else
				fprintf(f, "–");
			fprintf(f, " |\n");
		}
	}
}

int mtr_runs_write(const mtr_run_summary *s, size_t n, const char *dir, char *err, size_t err_size)
{
	char path[4096];
	tl_atomic csv, md;
	int rc = tl_mkdirs(dir, err, err_size);
	if (rc)
		return rc;
	snprintf(path, sizeof path, "%s/runs.csv", dir);
	if ((rc = tl_atomic_open(&csv, path, err, err_size)))
		return rc;
	FILE *f = csv.f;
	for (int c = 0; csv_columns[c]; c++)
		fprintf(f, "%s%s", c ? "," : "", csv_columns[c]);
	fputc('\n', f);
	json_t *arr = json_array();
	for (size_t i = 0; i < n; i++) {
		const mtr_run_summary *r = &s[i];
		double late_pct = r->reused_samples > 0 ? 100 * r->late_samples / r->reused_samples : NAN;
		fprintf(f, "%s,%s,%s,%s,%s,%s,", r->path, r->scene, r->camera, r->camera_motion, r->method, r->variant);
		num(f, r->threshold, "%g");
		fputc(',', f);
		if (r->period)
			fprintf(f, "%u", r->period);
		fprintf(f, ",%zu,%u,%u,", r->frames, r->width, r->height);
		num(f, r->visible_samples, "%.0f"), fputc(',', f);
		num(f, r->shaded_samples, "%.0f"), fputc(',', f);
		num(f, r->allocated_samples, "%.0f"), fputc(',', f);
		num(f, 100 * r->reuse_mean, "%.4f"), fputc(',', f);
		num(f, 100 * r->reduction, "%.4f"), fprintf(f, ",%s,", r->baseline);
		num(f, r->fs_invocations, "%.0f"), fputc(',', f);
		num(f, r->gpu_ms_median, "%.4f"), fputc(',', f);
		num(f, r->speedup_vs_ref, "%.4f"), fputc(',', f);
		num(f, r->reused_samples, "%.0f"), fputc(',', f);
		num(f, r->late_samples, "%.0f"), fputc(',', f);
		num(f, late_pct, "%.4f");
		fputc('\n', f);
		json_t *o = json_pack("{s:s, s:s, s:s, s:s, s:s, s:s, s:o, s:o, s:I, s:[i,i]}", "run", r->path, "scene", r->scene,
				      "camera", r->camera, "camera_motion", r->camera_motion, "method", r->method, "variant",
				      r->variant, "T", jnum(r->threshold), "period",
				      r->period ? json_integer(r->period) : json_null(), "frames", (json_int_t)r->frames, "size",
				      (int)r->width, (int)r->height);
		const struct {
			const char *k;
			double v;
		} nums[] = {{"visible_samples", r->visible_samples}, {"shaded_samples", r->shaded_samples},
			    {"allocated_samples", r->allocated_samples}, {"reuse", r->reuse_mean},
			    {"reduction", r->reduction}, {"fs_invocations", r->fs_invocations},
			    {"gpu_ms_median", r->gpu_ms_median}, {"speedup_vs_ref", r->speedup_vs_ref},
			    {"reused_samples", r->reused_samples}, {"late_samples", r->late_samples}};
		for (size_t k = 0; o && k < sizeof nums / sizeof nums[0]; k++)
			json_object_set_new(o, nums[k].k, jnum(nums[k].v));
		if (o)
			json_object_set_new(o, "baseline", r->baseline[0] ? json_string(r->baseline) : json_null());
		json_array_append_new(arr, o);
	}
	rc = tl_atomic_commit(&csv, err, err_size);
	snprintf(path, sizeof path, "%s/runs.json", dir);
	if (!rc)
		rc = tl_json_write(path, arr, err, err_size);
	json_decref(arr);
	if (rc)
		return rc;
	snprintf(path, sizeof path, "%s/table1.md", dir);
	if ((rc = tl_atomic_open(&md, path, err, err_size)))
		return rc;
	write_table1(md.f, s, n);
	return tl_atomic_commit(&md, err, err_size);
}

int mtr_runs_write_table1(const char *path, const mtr_run_summary *s, size_t n, char *err, size_t err_size)
{
	tl_atomic md;
	int rc = tl_atomic_open(&md, path, err, err_size);
	if (rc)
		return rc;
	write_table1(md.f, s, n);
	return tl_atomic_commit(&md, err, err_size);
}

int mtr_runs_plot(const mtr_run_summary *s, size_t n, const char *dir, char *err, size_t err_size)
{
	char path[4096];
	mtr_plot plot;
	snprintf(path, sizeof path, "%s/runs.gp", dir);
	FILE *f = mtr_plot_begin(&plot, path, err, err_size);
	if (!f)
		return TL_ERR_OUTPUT;
	/* Per-T summaries: reduction, reuse and speedup against T, one line per method with a threshold (runs.csv). */
	int M = csv_column("method"), T = csv_column("T");
	char methods[2048] = "";
	for (size_t i = 0; i < n; i++) {
		int first = isfinite(s[i].threshold);
		for (size_t j = 0; j < i; j++)
			first &= strcmp(s[j].method, s[i].method) != 0;
		if (first && strlen(methods) + strlen(s[i].method) + 2 < sizeof methods) {
			strcat(methods, methods[0] ? " " : "");
			strcat(methods, s[i].method);
		}
	}
	fprintf(f,
		"set datafile separator ','\nset terminal pngcairo size 960,540 font 'sans,10'\nset grid\n"
		"set key outside right top\nset logscale x 2\nset xlabel 'threshold T (code values)'\n"
		"methods = '%s'\n"
		"set output '%s/reduction.png'\nset title 'shaded samples: reduction against the baseline'\n"
		"set ylabel 'reduction (%%)'\n"
		"plot for [m in methods] '%s/runs.csv' using (strcol(%d) eq m ? $%d : 1/0):%d every ::1 with linespoints title m\n"
		"set output '%s/reuse.png'\nset title 'shading reuse'\nset ylabel 'reuse (%%)'\n"
		"plot for [m in methods] '%s/runs.csv' using (strcol(%d) eq m ? $%d : 1/0):%d every ::1 with linespoints title m\n"
		"set output '%s/speedup.png'\nset title 'speedup against ref (median GPU frame time)'\nset ylabel 'speedup (x)'\n"
		"plot for [m in methods] '%s/runs.csv' using (strcol(%d) eq m ? $%d : 1/0):%d every ::1 with linespoints title m\n",
		methods, dir, dir, M, T, csv_column("reduction_percent"), dir, dir, M, T, csv_column("reuse_percent"), dir, dir,
		M, T, csv_column("speedup_vs_ref"));
	if (!methods[0]) {
		tl_atomic_abort(&plot.file);
		return tl_error(err, err_size, TL_ERR_UNSUPPORTED, "no runs of a method with a threshold: per-T plots skipped");
	}
	return mtr_plot_end(&plot, err, err_size);
}
