/* runs.c — per-run shading statistics from stats.csv / manifest.json (see metrics_runs.h). */
#include "taslab/metrics_runs.h"

#include <errno.h>
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

static int summarise_one(const char *run, mtr_run_summary *s, char *err, size_t err_size)
{
	memset(s, 0, sizeof *s);
	snprintf(s->path, sizeof s->path, "%s", run);
	run_manifest m;
	run_stats st;
	int rc = run_manifest_read(run, &m, err, err_size);
	if (rc || (rc = run_stats_read(run, &st, err, err_size)))
		return rc;
	snprintf(s->method, sizeof s->method, "%s", m.method);
	snprintf(s->scene, sizeof s->scene, "%s", m.scene);
	snprintf(s->camera, sizeof s->camera, "%s", m.camera);
	s->threshold = m.threshold;
	int c_reuse = run_stats_col(&st, "reuse_fraction"), c_gpu = run_stats_col(&st, "gpu_ms_total");
	int c_fs = run_stats_col(&st, "fs_invocations"), c_cs = run_stats_col(&st, "cs_invocations");
	static const char *const tally_cols[4] = {"late", "early", "on_time", "unchanged"};
	if (c_reuse < 0 || c_fs < 0 || c_cs < 0 || c_gpu < 0 || st.rows == 0) {
		run_stats_free(&st);
		return tl_error(err, err_size, TL_ERR_INPUT,
				"%s/stats.csv: no frames, or missing columns (reuse_fraction, fs_invocations, cs_invocations, "
				"gpu_ms_total)", run);
	}
	double tally[4] = {0, 0, 0, 0}, inv = 0;
	int inv_seen = 0, have_tally[4];
	for (int k = 0; k < 4; k++)
		have_tally[k] = run_stats_col(&st, tally_cols[k]) >= 0;
	double *gpu_ms = malloc(st.rows * sizeof *gpu_ms);
	size_t ng = 0;
	if (!gpu_ms) {
		run_stats_free(&st);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	for (size_t r = 0; r < st.rows; r++) {
		const double *v = st.values + r * st.cols;
		s->frames++;
		s->reuse_mean += isfinite(v[c_reuse]) ? v[c_reuse] : 0.0;
		if (isfinite(v[c_fs]) || isfinite(v[c_cs])) {
			inv += (isfinite(v[c_fs]) ? v[c_fs] : 0) + (isfinite(v[c_cs]) ? v[c_cs] : 0);
			inv_seen = 1;
		}
		for (int k = 0; k < 4; k++) {
			double t = run_stats_get(&st, r, tally_cols[k]);
			if (isfinite(t))
				tally[k] += t;
		}
		if (isfinite(v[c_gpu]))
			gpu_ms[ng++] = v[c_gpu];
	}
	run_stats_free(&st);
	s->reuse_mean /= (double)s->frames;
	s->invocations = inv_seen ? inv : NAN;
	if (ng) {
		qsort(gpu_ms, ng, sizeof *gpu_ms, cmpd);
		s->gpu_ms_median = ng % 2 ? gpu_ms[ng / 2] : 0.5 * (gpu_ms[ng / 2 - 1] + gpu_ms[ng / 2]);
	} else {
		s->gpu_ms_median = NAN;
	}
	free(gpu_ms);
	s->late = have_tally[0] ? tally[0] : NAN;
	s->early = have_tally[1] ? tally[1] : NAN;
	s->on_time = have_tally[2] ? tally[2] : NAN;
	s->unchanged = have_tally[3] ? tally[3] : NAN;
	return TL_OK;
}

int mtr_runs_summarise(const char *const *runs, size_t n, int baseline, mtr_run_summary *out, char *err, size_t err_size)
{
	for (size_t i = 0; i < n; i++) {
		int rc = summarise_one(runs[i], &out[i], err, err_size);
		if (rc)
			return rc;
	}
	if (baseline < 0)
		for (size_t i = 0; i < n && baseline < 0; i++)
			if (!strcmp(out[i].method, "ref"))
				baseline = (int)i;
	for (size_t i = 0; i < n; i++) {
		out[i].invocation_reduction = baseline >= 0 && out[baseline].invocations > 0
						      ? 1.0 - out[i].invocations / out[baseline].invocations
						      : NAN;
		out[i].speedup_vs_ref = NAN;
		for (size_t r = 0; r < n; r++)
			if (!strcmp(out[r].method, "ref") && !strcmp(out[r].scene, out[i].scene) &&
			    !strcmp(out[r].camera, out[i].camera)) {
				out[i].speedup_vs_ref = out[r].gpu_ms_median / out[i].gpu_ms_median;
				break;
			}
	}
	return 0;
}

static void num(FILE *f, double v, const char *fmt)
{
	if (isfinite(v))
		fprintf(f, fmt, v);
}

static json_t *jnum(double v) { return isfinite(v) ? json_real(v) : json_null(); }

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
	fprintf(f, "run,scene,camera,method,T,frames,reuse_percent,invocations,invocation_reduction_percent,gpu_ms_median,"
		   "speedup_vs_ref,late,early,on_time,unchanged\n");
	json_t *arr = json_array();
	for (size_t i = 0; i < n; i++) {
		const mtr_run_summary *r = &s[i];
		fprintf(f, "%s,%s,%s,%s,%g,%zu,", r->path, r->scene, r->camera, r->method, r->threshold, r->frames);
		num(f, 100 * r->reuse_mean, "%.4f");
		fputc(',', f);
		num(f, r->invocations, "%.0f");
		fputc(',', f);
		num(f, 100 * r->invocation_reduction, "%.4f");
		fputc(',', f);
		num(f, r->gpu_ms_median, "%.4f");
		fputc(',', f);
		num(f, r->speedup_vs_ref, "%.4f");
		double t[4] = {r->late, r->early, r->on_time, r->unchanged};
		for (int k = 0; k < 4; k++)
			fputc(',', f), num(f, t[k], "%.0f");
		fputc('\n', f);
		json_array_append_new(arr, json_pack("{s:s, s:s, s:s, s:s, s:f, s:I, s:o, s:o, s:o, s:o, s:o, s:o, s:o, s:o, s:o}",
						     "run", r->path, "scene", r->scene, "camera", r->camera, "method", r->method,
						     "T", r->threshold, "frames", (json_int_t)r->frames, "reuse", jnum(r->reuse_mean),
						     "invocations", jnum(r->invocations), "invocation_reduction",
						     jnum(r->invocation_reduction), "gpu_ms_median", jnum(r->gpu_ms_median),
						     "speedup_vs_ref", jnum(r->speedup_vs_ref), "late", jnum(r->late), "early",
						     jnum(r->early), "on_time", jnum(r->on_time), "unchanged", jnum(r->unchanged)));
	}
	rc = tl_atomic_commit(&csv, err, err_size);
	snprintf(path, sizeof path, "%s/runs.json", dir);
	if (!rc)
		rc = tl_json_write(path, arr, err, err_size);
	json_decref(arr);
	if (rc)
		return rc;
	/* Table 1 layout: shader-invocation reduction (%) per method (rows) and T (columns). */
	double ts[32];
	int nt = 0;
	for (size_t i = 0; i < n; i++) {
		int seen = 0;
		for (int k = 0; k < nt; k++)
			seen |= ts[k] == s[i].threshold;
		if (!seen && nt < 32 && strcmp(s[i].method, "ref"))
			ts[nt++] = s[i].threshold;
	}
	qsort(ts, (size_t)nt, sizeof *ts, cmpd);
	snprintf(path, sizeof path, "%s/table1.md", dir);
	if ((rc = tl_atomic_open(&md, path, err, err_size)))
		return rc;
	f = md.f;
	{
		fprintf(f, "Shader invocations, reduction against the baseline (%%), per method and threshold T (cf. paper Table 1)\n\n| method |");
		for (int k = 0; k < nt; k++)
			fprintf(f, " T = %g |", ts[k]);
		fprintf(f, "\n|---|");
		for (int k = 0; k < nt; k++)
			fprintf(f, "---|");
		fprintf(f, "\n");
		for (size_t i = 0; i < n; i++) {
			int first = 1;
			for (size_t j = 0; j < i; j++)
				first &= strcmp(s[j].method, s[i].method) != 0;
			if (!first || !strcmp(s[i].method, "ref"))
				continue;
			fprintf(f, "| %s |", s[i].method);
			for (int k = 0; k < nt; k++) {
				double v = NAN;
				for (size_t j = 0; j < n; j++)
					if (!strcmp(s[j].method, s[i].method) && s[j].threshold == ts[k])
						v = s[j].invocation_reduction;
				if (isfinite(v))
					fprintf(f, " %.1f |", 100 * v);
				else
					fprintf(f, " – |");
			}
			fprintf(f, "\n");
		}
	}
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
	/* Per-T summaries: reuse and invocation reduction against T, one line per method (from runs.csv). */
	char methods[2048] = "";
	for (size_t i = 0; i < n; i++) {
		int first = strcmp(s[i].method, "ref") != 0;
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
		"set output '%s/reduction.png'\nset title 'shader invocations: reduction against the baseline'\n"
		"set ylabel 'reduction (%%)'\n"
		"plot for [m in methods] '%s/runs.csv' using (strcol(4) eq m ? $5 : 1/0):9 every ::1 with linespoints title m\n"
		"set output '%s/reuse.png'\nset title 'shading reuse'\nset ylabel 'reuse (%%)'\n"
		"plot for [m in methods] '%s/runs.csv' using (strcol(4) eq m ? $5 : 1/0):7 every ::1 with linespoints title m\n"
		"set output '%s/speedup.png'\nset title 'speedup against ref (median GPU frame time)'\nset ylabel 'speedup (x)'\n"
		"plot for [m in methods] '%s/runs.csv' using (strcol(4) eq m ? $5 : 1/0):11 every ::1 with linespoints title m\n",
		methods, dir, dir, dir, dir, dir, dir);
	if (!methods[0]) {
		tl_atomic_abort(&plot.file);
		return tl_error(err, err_size, TL_ERR_UNSUPPORTED, "no non-ref runs: per-T plots skipped");
	}
	return mtr_plot_end(&plot, err, err_size);
}
