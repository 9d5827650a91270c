/* sweep.c — per-run comparisons of a sweep and its summary.csv / table1.md (metrics_sweep.h, DESIGN section 9). */
#include "taslab/metrics_sweep.h"

#include <jansson.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/metrics.h"
#include "taslab/metrics_diff.h"
#include "taslab/metrics_flip.h"
#include "taslab/tl_fs.h"
#include "taslab/tl_json.h"

int mtr_sweep_metrics(const sweep_spec *s, const char *dir, const sweep_run *r, int threads, char *err,
		      size_t err_size)
{
	if (r->is_ref)
		return TL_OK;
	sweep_run ref;
	char ref_dir[TL_PATH_MAX], run_dir[TL_PATH_MAX], out[TL_PATH_MAX];
	if (sweep_run_at(s, r->ref_index, &ref))
		return tl_error(err, err_size, TL_ERR_INTERNAL, "sweep plan: no ref run for run %zu", r->index);
	sweep_run_path(s, dir, &ref, SWEEP_PATH_RUN, ref_dir, sizeof ref_dir);
	sweep_run_path(s, dir, r, SWEEP_PATH_RUN, run_dir, sizeof run_dir);
	sweep_run_path(s, dir, r, SWEEP_PATH_METRICS, out, sizeof out);
	int rc = tl_mkdirs(out, err, err_size);
	if (rc)
		return rc;
	/* DESIGN section 6 metrics on the display PNGs, as `taslab metrics diff` computes them. */
	const mtr_option_value options[] = {{"ppd", s->ppd > 0 ? s->ppd : MTR_FLIP_PPD_DEFAULT}};
	mtr_diff_desc d = {.ref = ref_dir, .test = run_dir, .out = out, .format = MTR_FORMAT_PNG, .threads = threads,
			   .metrics = s->metrics[0] ? s->metrics : "all", .options = options, .option_count = 1};
	mtr_diff_result res;
	return mtr_diff_run(&d, &res, err, err_size);
}

/* The frame with the largest maxrgb_p99 in DIR/frames.csv (the metrics module's own file); false when there is none. */
static bool worst_frame(const char *dir, uint32_t *frame)
{
	char path[TL_PATH_MAX], line[4096], err[256];
	snprintf(path, sizeof path, "%s/frames.csv", dir);
	char *text = NULL;
	size_t len;
	if (tl_read_file(path, 64u << 20, &text, &len, err, sizeof err))
		return false;
	int col = -1, found = -1;
	double best = -1;
	char *save = NULL;
	for (char *l = strtok_r(text, "\n", &save); l; l = strtok_r(NULL, "\n", &save)) {
		snprintf(line, sizeof line, "%s", l);
		int c = 0;
		double v = NAN;
		long f = -1;
		for (char *p = line;; c++) {
			char *e = strchr(p, ',');
			if (e)
				*e = 0;
			if (col < 0 && !strcmp(p, "maxrgb_p99"))
				found = c;
			else if (col >= 0 && c == 0)
				f = strtol(p, NULL, 10);
			else if (col >= 0 && c == col && *p)
				v = strtod(p, NULL);
			if (!e)
				break;
			p = e + 1;
		}
		if (col < 0) {
			if (found < 0)
				break;
			col = found;
			continue;
		}
		if (f >= 0 && isfinite(v) && v > best)
			best = v, *frame = (uint32_t)f;
	}
	free(text);
	return best >= 0;
}

static int read_metrics(const char *dir, mtr_sweep_row *row, char *err, size_t err_size)
{
	char path[TL_PATH_MAX];
	snprintf(path, sizeof path, "%s/summary.json", dir);
	json_t *j;
	int rc = tl_json_read(path, &j, err, err_size);
	if (rc)
		return rc;
	for (int c = 0; c < MTR_SWEEP_MAX_COLUMNS && mtr_column_name(c); c++) {
		json_t *v = json_object_get(j, mtr_column_name(c));
		row->metric[c] = json_is_number(v) ? json_number_value(v) : NAN;
	}
	json_decref(j);
	worst_frame(dir, &row->worst_frame);
	return TL_OK;
}

int mtr_sweep_collect(const sweep_spec *s, const char *dir, mtr_sweep_row **rows_out, size_t *n_out, char *err,
		      size_t err_size)
{
	size_t n = sweep_run_count(s), nc = 0;
	mtr_sweep_row *rows = calloc(n ? n : 1, sizeof *rows);
	char **paths = calloc(n ? n : 1, sizeof *paths);
	mtr_run_summary *sums = calloc(n ? n : 1, sizeof *sums);
	size_t *which = calloc(n ? n : 1, sizeof *which);
	int rc = rows && paths && sums && which ? TL_OK : tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	for (size_t i = 0; !rc && i < n; i++) {
		mtr_sweep_row *row = &rows[i];
		sweep_run_at(s, i, &row->run);
		char why[1024];
		sweep_run_status_checked(s, dir, &row->run, &row->status, why, sizeof why); /* a damaged run is not read */
		for (int c = 0; c < MTR_SWEEP_MAX_COLUMNS; c++)
			row->metric[c] = NAN;
		const sweep_scene *sc = &s->scenes[row->run.scene];
		row->worst_frame = sc->first + (sc->end - sc->first) / 2;
		if (!row->status.run)
			continue;
		if (!(paths[nc] = malloc(TL_PATH_MAX))) {
			rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
			break;
		}
		sweep_run_path(s, dir, &row->run, SWEEP_PATH_RUN, paths[nc], TL_PATH_MAX);
		which[nc++] = i;
		if (!row->run.is_ref && row->status.metrics) {
			char mdir[TL_PATH_MAX];
			sweep_run_path(s, dir, &row->run, SWEEP_PATH_METRICS, mdir, sizeof mdir);
			rc = read_metrics(mdir, row, err, err_size);
		}
	}
	/* Reductions against the baseline and speedups against ref, matched per scene/path/frames/size. */
	if (!rc && nc)
		rc = mtr_runs_summarise((const char *const *)paths, nc, strcmp(s->baseline, "auto") ? s->baseline : NULL,
					sums, err, err_size);
	for (size_t k = 0; !rc && k < nc; k++)
		rows[which[k]].summary = sums[k];
	for (size_t k = 0; paths && k < nc; k++)
		free(paths[k]);
	free(paths);
	free(sums);
	free(which);
	if (rc) {
		free(rows);
		return rc;
	}
	*rows_out = rows;
	*n_out = n;
	return TL_OK;
}

static int metric_index(const char *name)
{
	for (int c = 0; c < MTR_SWEEP_MAX_COLUMNS && mtr_column_name(c); c++)
		if (!strcmp(mtr_column_name(c), name))
			return c;
	return -1; /* local sentinel: no such column (an index, not an error) */
}

double mtr_sweep_value(const mtr_sweep_row *row, const char *column)
{
	const mtr_run_summary *m = &row->summary;
	if (!strcmp(column, "exceed_T")) {
		char name[32];
		double T = m->threshold;
		if (!isfinite(T) || T != floor(T))
			return NAN;
		snprintf(name, sizeof name, "exceed_%.0f", T);
		int c = metric_index(name);
		return c >= 0 ? row->metric[c] : NAN;
	}
	int c = metric_index(column);
	if (c >= 0)
		return row->metric[c];
	if (!row->status.run)
		return NAN;
	if (!strcmp(column, "T"))
		return m->threshold;
	if (!strcmp(column, "period"))
		return m->period ? m->period : NAN;
	if (!strcmp(column, "frames"))
		return (double)m->frames;
	if (!strcmp(column, "reuse_percent"))
		return 100 * m->reuse_mean;
	if (!strcmp(column, "reduction_percent"))
		return 100 * m->reduction;
	if (!strcmp(column, "speedup_vs_ref"))
		return m->speedup_vs_ref;
	if (!strcmp(column, "gpu_ms_median"))
		return m->gpu_ms_median;
	if (!strcmp(column, "shaded_samples"))
		return m->shaded_samples;
	if (!strcmp(column, "shaded_fraction"))
		return m->visible_samples > 0 ? m->shaded_samples / m->visible_samples : NAN;
	if (!strcmp(column, "shaded_per_frame"))
		return m->frames ? m->shaded_samples / (double)m->frames : NAN;
	if (!strcmp(column, "late_samples"))
		return m->late_samples;
	if (!strcmp(column, "late_percent"))
		return m->reused_samples > 0 ? 100 * m->late_samples / m->reused_samples : NAN;
	return NAN;
}

int mtr_sweep_matched(const sweep_spec *s, const mtr_sweep_row *rows, size_t n, mtr_match_pair **pairs, size_t *np,
		      char *err, size_t err_size)
{
	*pairs = NULL;
	*np = 0;
	mtr_match_item *in = calloc(n ? n : 1, sizeof *in);
	char(*group)[160] = calloc(n ? n : 1, sizeof *group);
	if (!in || !group) {
		free(in);
		free(group);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	for (size_t i = 0; i < n; i++) {
		const mtr_sweep_row *r = &rows[i];
		const sweep_scene *sc = &s->scenes[r->run.scene];
		snprintf(group[i], sizeof group[i], "%s/%s", sc->name, sc->cameras[r->run.camera].name);
		in[i] = (mtr_match_item){.group = group[i], .method = s->variants[r->run.variant].method,
					 .tas = mtr_match_is_tas(r->summary.facts.family, r->summary.facts.takes_threshold),
					 .reference = r->run.is_ref || r->summary.facts.reference,
					 .shaded = r->status.run ? mtr_sweep_value(r, "shaded_per_frame") : NAN};
	}
	size_t count = mtr_match_budget(in, n, NULL, 0);
	mtr_match_pair *p = count ? calloc(count, sizeof *p) : NULL;
	int rc = !count || p ? TL_OK : tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	if (!rc && count)
		mtr_match_budget(in, n, p, count);
	free(in);
	free(group);
	if (rc)
		return rc;
	*pairs = p;
	*np = count;
	return TL_OK;
}

/* A Markdown cell: the value or "–". */
static void md_cell(FILE *f, double v, const char *fmt)
{
	fputs(" | ", f);
	if (isfinite(v))
		fprintf(f, fmt, v);
	else
		fputs("–", f);
}

/* One row of the matched-budget table. */
static void md_matched_row(FILE *f, const sweep_spec *s, const mtr_sweep_row *t, const mtr_sweep_row *r)
{
	const sweep_scene *sc = &s->scenes[r->run.scene];
	fprintf(f, "| %s | %s | %s | %s", sc->name, sc->cameras[r->run.camera].name, s->variants[t->run.variant].variant,
		t == r ? "**TAS**" : s->variants[r->run.variant].variant);
	md_cell(f, 100 * mtr_sweep_value(r, "shaded_fraction"), "%.2f");
	md_cell(f, mtr_sweep_value(r, "shaded_per_frame"), "%.1f");
	md_cell(f, mtr_sweep_value(r, "exceed_8"), "%.6f");
	md_cell(f, mtr_sweep_value(r, "flip_mean"), "%.5f");
	md_cell(f, mtr_sweep_value(r, "flicker_mean"), "%.4f");
	md_cell(f, mtr_sweep_value(r, "gpu_ms_median"), "%.3f");
	fputs(" |\n", f);
}

/* Appends the matched-budget section to the Table 1 file at `path` (rewritten atomically). */
static int write_matched(const sweep_spec *s, const char *path, const mtr_sweep_row *rows, size_t n, char *err,
			 size_t err_size)
{
	mtr_match_pair *p;
	size_t np;
	int rc = mtr_sweep_matched(s, rows, n, &p, &np, err, err_size);
	if (rc)
		return rc;
	char *text = NULL;
	size_t len = 0;
	tl_atomic a;
	if ((rc = tl_read_file(path, 64u << 20, &text, &len, err, err_size)) ||
	    (rc = tl_atomic_open(&a, path, err, err_size))) {
		free(text);
		free(p);
		return rc;
	}
	fwrite(text, 1, len, a.f);
	fprintf(a.f, "\n## Matched budget\n\nFor each TAS variant, each other method at the setting with the nearest "
		     "clip-mean shaded samples per frame (same scene and camera path; BASELINES.md section 0). Differences "
		     "are against ref. Shaded samples are each method's own count; a cache of a partial payload counts the "
		     "payloads it evaluates and completes the shading of every sample each frame besides (its "
		     "composed_samples): compare its GPU ms.\n\n");
	if (!np)
		fprintf(a.f, "No TAS variant with another method to match in this sweep.\n");
	else
		fprintf(a.f, "| scene | camera | TAS variant | matched | shaded %% | shaded / frame | exceed_8 | FLIP | "
			     "flicker | GPU ms |\n|---|---|---|---|--:|--:|--:|--:|--:|--:|\n");
	for (size_t k = 0; k < np; k++) {
		if (!k || p[k].tas != p[k - 1].tas)
			md_matched_row(a.f, s, &rows[p[k].tas], &rows[p[k].tas]);
		md_matched_row(a.f, s, &rows[p[k].tas], &rows[p[k].other]);
	}
	free(text);
	free(p);
	return tl_atomic_commit(&a, err, err_size);
}

static void cell(FILE *f, double v, const char *fmt)
{
	fputc(',', f);
	if (isfinite(v))
		fprintf(f, fmt, v);
}

int mtr_sweep_write(const sweep_spec *s, const char *dir, const mtr_sweep_row *rows, size_t n, char *err,
		    size_t err_size)
{
	char path[TL_PATH_MAX];
	tl_atomic a;
	snprintf(path, sizeof path, "%s/summary.csv", dir);
	int rc = tl_atomic_open(&a, path, err, err_size);
	if (rc)
		return rc;
	FILE *f = a.f;
	static const char *const before[] = {"reuse_percent", "shaded_samples", "shaded_per_frame", "reduction_percent"};
	static const char *const after[] = {"late_samples", "late_percent"};
	fprintf(f, "scene,camera,camera_motion,method,variant,T,period,frames,width,height,status");
	for (size_t k = 0; k < 4; k++)
		fprintf(f, ",%s", before[k]);
	fprintf(f, ",baseline,gpu_ms_median,speedup_vs_ref");
	int ncol = 0;
	for (; ncol < MTR_SWEEP_MAX_COLUMNS && mtr_column_name(ncol); ncol++)
		if (mtr_column_where(ncol) & 2u)
			fprintf(f, ",%s", mtr_column_name(ncol));
	for (size_t k = 0; k < sizeof after / sizeof after[0]; k++)
		fprintf(f, ",%s", after[k]);
	fprintf(f, ",run\n");
	for (size_t i = 0; i < n; i++) {
		const mtr_sweep_row *r = &rows[i];
		const sweep_scene *sc = &s->scenes[r->run.scene];
		const sweep_variant *v = &s->variants[r->run.variant];
		const char *status = r->status.damaged ? "damaged"
				     : !r->status.run  ? "missing"
				     : r->status.clip && r->status.metrics ? "complete" : "partial";
		fprintf(f, "%s,%s,%s,%s,%s", sc->name, sc->cameras[r->run.camera].name, sc->cameras[r->run.camera].motion,
			v->method, v->variant);
		cell(f, v->T, "%g");
		cell(f, v->period ? v->period : NAN, "%.0f");
		fprintf(f, ",%u,%u,%u,%s", sc->end - sc->first, s->width, s->height, status);
		cell(f, mtr_sweep_value(r, "reuse_percent"), "%.4f");
		cell(f, mtr_sweep_value(r, "shaded_samples"), "%.0f");
		cell(f, mtr_sweep_value(r, "shaded_per_frame"), "%.1f");
		cell(f, mtr_sweep_value(r, "reduction_percent"), "%.4f");
		fprintf(f, ",%s", r->status.run ? r->summary.baseline : "");
		cell(f, mtr_sweep_value(r, "gpu_ms_median"), "%.4f");
		cell(f, mtr_sweep_value(r, "speedup_vs_ref"), "%.4f");
		for (int c = 0; c < ncol; c++)
			if (mtr_column_where(c) & 2u)
				cell(f, r->metric[c], "%.9g");
		for (size_t k = 0; k < sizeof after / sizeof after[0]; k++)
			cell(f, mtr_sweep_value(r, after[k]), k == 1 ? "%.4f" : "%.0f");
		char run[TL_PATH_MAX];
		sweep_run_path(s, ".", &r->run, SWEEP_PATH_RUN, run, sizeof run);
		fprintf(f, ",%s\n", run + 2); /* relative to the sweep folder */
	}
	if ((rc = tl_atomic_commit(&a, err, err_size)))
		return rc;
	/* Table 1 over the complete runs. */
	mtr_run_summary *sums = calloc(n ? n : 1, sizeof *sums);
	if (!sums)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	size_t m = 0;
	for (size_t i = 0; i < n; i++)
		if (rows[i].status.run)
			sums[m++] = rows[i].summary;
	snprintf(path, sizeof path, "%s/table1.md", dir);
	rc = mtr_runs_write_table1(path, sums, m, err, err_size);
	free(sums);
	return rc ? rc : write_matched(s, path, rows, n, err, err_size);
}
