/* runs.c — per-run shading statistics from stats.csv / manifest.json (see metrics_runs.h). */
#include "taslab/metrics_runs.h"

#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "taslab/run.h"
#include "plot.h"

#define MAX_COLS 64

static int cmpd(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static int col_index(char cols[][48], int ncols, const char *name)
{
	for (int i = 0; i < ncols; i++)
		if (!strcmp(cols[i], name))
			return i;
	return -1;
}

static int summarise_one(const char *run, mtr_run_summary *s, double **gpu_ms, char *err, size_t err_size)
{
	char path[4096];
	memset(s, 0, sizeof *s);
	snprintf(s->path, sizeof s->path, "%s", run);
	snprintf(path, sizeof path, "%s/manifest.json", run);
	json_error_t je;
	json_t *m = json_load_file(path, 0, &je);
	json_t *in = json_object_get(m, "inputs");
	if (!in) {
		json_decref(m);
		snprintf(err, err_size, "%s: not a complete run (no manifest.json); render it first", run);
		return -1;
	}
	const char *fields[3] = {"method", "scene", "camera"};
	char *dst[3] = {s->method, s->scene, s->camera};
	size_t len[3] = {sizeof s->method, sizeof s->scene, sizeof s->camera};
	for (int k = 0; k < 3; k++) {
		const char *v = json_string_value(json_object_get(in, fields[k]));
		snprintf(dst[k], len[k], "%s", v ? v : "?");
	}
	s->threshold = json_number_value(json_object_get(in, "threshold"));
	json_decref(m);
	snprintf(path, sizeof path, "%s/stats.csv", run);
	FILE *f = fopen(path, "r");
	if (!f) {
		snprintf(err, err_size, "%s: %s", path, strerror(errno));
		return -1;
	}
	char line[8192], cols[MAX_COLS][48];
	int ncols = 0;
	if (!fgets(line, sizeof line, f)) {
		fclose(f);
		snprintf(err, err_size, "%s: empty", path);
		return -1;
	}
	for (char *save = NULL, *t = strtok_r(line, ",\n", &save); t && ncols < MAX_COLS; t = strtok_r(NULL, ",\n", &save))
		snprintf(cols[ncols++], sizeof cols[0], "%s", t);
	int c_reuse = col_index(cols, ncols, "reuse_fraction"), c_fs = col_index(cols, ncols, "fs_invocations");
	int c_cs = col_index(cols, ncols, "cs_invocations"), c_gpu = col_index(cols, ncols, "gpu_ms_total");
	int c_t[4] = {col_index(cols, ncols, "late"), col_index(cols, ncols, "early"), col_index(cols, ncols, "on_time"),
		      col_index(cols, ncols, "unchanged")};
	if (c_reuse < 0 || c_fs < 0 || c_cs < 0 || c_gpu < 0) {
		fclose(f);
		snprintf(err, err_size, "%s: missing columns (reuse_fraction, fs_invocations, cs_invocations, gpu_ms_total)", path);
		return -1;
	}
	double tally[4] = {0, 0, 0, 0}, inv = 0;
	int inv_seen = 0;
	size_t cap = 0;
	*gpu_ms = NULL;
	size_t ng = 0;
	while (fgets(line, sizeof line, f)) {
		double v[MAX_COLS];
		int have[MAX_COLS] = {0};
		int ci = 0;
		char *p = line;
		while (ci < ncols) { /* empty cells are allowed: not strtok */
			char *e = p;
			while (*e && *e != ',' && *e != '\n')
				e++;
			have[ci] = e > p;
			v[ci] = have[ci] ? strtod(p, NULL) : NAN;
			ci++;
			if (*e != ',')
				break;
			p = e + 1;
		}
		if (ci < ncols) {
			fclose(f);
			free(*gpu_ms);
			snprintf(err, err_size, "%s: row %zu has %d of %d columns", path, s->frames + 2, ci, ncols);
			return -1;
		}
		s->frames++;
		s->reuse_mean += v[c_reuse];
		if (have[c_fs] || have[c_cs]) {
			inv += (have[c_fs] ? v[c_fs] : 0) + (have[c_cs] ? v[c_cs] : 0);
			inv_seen = 1;
		}
		for (int k = 0; k < 4; k++)
			if (c_t[k] >= 0 && have[c_t[k]])
				tally[k] += v[c_t[k]];
		if (have[c_gpu]) {
			if (ng == cap) {
				cap = cap ? cap * 2 : 64;
				double *nn = realloc(*gpu_ms, cap * sizeof *nn);
				if (!nn) {
					fclose(f);
					free(*gpu_ms);
					snprintf(err, err_size, "out of memory");
					return -1;
				}
				*gpu_ms = nn;
			}
			(*gpu_ms)[ng++] = v[c_gpu];
		}
	}
	fclose(f);
	if (s->frames == 0) {
		free(*gpu_ms);
		snprintf(err, err_size, "%s: no frames", path);
		return -1;
	}
	s->reuse_mean /= (double)s->frames;
	s->invocations = inv_seen ? inv : NAN;
	if (ng) {
		qsort(*gpu_ms, ng, sizeof **gpu_ms, cmpd);
		s->gpu_ms_median = ng % 2 ? (*gpu_ms)[ng / 2] : 0.5 * ((*gpu_ms)[ng / 2 - 1] + (*gpu_ms)[ng / 2]);
	} else {
		s->gpu_ms_median = NAN;
	}
	s->late = c_t[0] >= 0 ? tally[0] : NAN;
	s->early = c_t[1] >= 0 ? tally[1] : NAN;
	s->on_time = c_t[2] >= 0 ? tally[2] : NAN;
	s->unchanged = c_t[3] >= 0 ? tally[3] : NAN;
	free(*gpu_ms);
	*gpu_ms = NULL;
	return 0;
}

int mtr_runs_summarise(const char *const *runs, size_t n, int baseline, mtr_run_summary *out, char *err, size_t err_size)
{
	for (size_t i = 0; i < n; i++) {
		double *g = NULL;
		if (summarise_one(runs[i], &out[i], &g, err, err_size))
			return -1;
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
	if (run_mkdirs(dir, err, err_size))
		return -1;
	snprintf(path, sizeof path, "%s/runs.csv", dir);
	FILE *f = fopen(path, "w");
	if (!f) {
		snprintf(err, err_size, "%s: %s", path, strerror(errno));
		return -1;
	}
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
	int bad = fclose(f) != 0;
	snprintf(path, sizeof path, "%s/runs.json", dir);
	bad |= json_dump_file(arr, path, JSON_INDENT(2)) != 0;
	json_decref(arr);
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
	f = fopen(path, "w");
	if (f) {
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
		bad |= fclose(f) != 0;
	} else {
		bad = 1;
	}
	if (bad) {
		snprintf(err, err_size, "%s: cannot write runs.csv / runs.json / table1.md", dir);
		return -1;
	}
	return 0;
}

int mtr_runs_plot(const mtr_run_summary *s, size_t n, const char *dir, char *err, size_t err_size)
{
	char path[4096];
	snprintf(path, sizeof path, "%s/runs.gp", dir);
	FILE *f = fopen(path, "w");
	if (!f) {
		snprintf(err, err_size, "%s: cannot write", path);
		return -1;
	}
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
	fclose(f);
	if (!methods[0]) {
		snprintf(err, err_size, "no non-ref runs: per-T plots skipped");
		return -1;
	}
	return mtr_gnuplot(path, err, err_size);
}
