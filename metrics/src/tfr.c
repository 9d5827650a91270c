/* tfr.c — files and plots of the TFR analysis (see taslab/metrics_tfr.h). */
#include "taslab/metrics_tfr.h"

#include <errno.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "taslab/metrics.h"
#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"
#include "taslab/tl_json.h"

/* Every file goes through the atomic-write helper (tl_fs.h). */
typedef tl_atomic out_file;

static int open_file(out_file *o, const char *dir, const char *name, char *err, size_t err_size)
{
	char path[TL_PATH_MAX];
	snprintf(path, sizeof path, "%s/%s", dir, name);
	return tl_atomic_open(o, path, err, err_size);
}

static int close_file(out_file *o, char *err, size_t err_size) { return tl_atomic_commit(o, err, err_size); }

static int write_json(json_t *j, const char *dir, const char *name, char *err, size_t err_size)
{
	char path[TL_PATH_MAX];
	snprintf(path, sizeof path, "%s/%s", dir, name);
	int rc = tl_json_write(path, j, err, err_size);
	json_decref(j);
	return rc;
}

/* Plots: DIR/NAME.gp is written into the returned stream, then plot_run draws it (gnuplot). */
static FILE *plot_open(mtr_plot *p, const char *dir, const char *name)
{
	char script[TL_PATH_MAX], err[512];
	snprintf(script, sizeof script, "%s/%s.gp", dir, name);
	FILE *f = mtr_plot_begin(p, script, err, sizeof err);
	if (!f)
		fprintf(stderr, "taslab: %s\n", err);
	return f;
}

static void plot_run(mtr_plot *p)
{
	char err[512];
	if (mtr_plot_end(p, err, sizeof err))
		fprintf(stderr, "taslab: %s\n", err);
}

static json_t *meta_json(const analyze_result *frames, size_t n, const mtr_tfr_meta *m)
{
	json_t *fr = json_array(), *ts = json_array();
	for (size_t i = 0; i < n; i++)
		json_array_append_new(fr, json_integer(frames[i].frame));
	for (size_t i = 0; i < m->threshold_count; i++)
		json_array_append_new(ts, json_real(m->thresholds[i]));
	return json_pack("{s:s, s:s, s:s?, s:i, s:i, s:o, s:o, s:i, s:i, s:f}", "scene", m->scene, "camera", m->camera,
			 "device", m->device, "width", n ? (int)frames[0].width : 0, "height", n ? (int)frames[0].height : 0,
			 "frames", fr, "thresholds", ts, "history_frames", ANALYZE_HISTORY, "max_deadline_K", ANALYZE_K,
			 "seconds_per_analysis_frame", m->seconds_per_frame);
}

int mtr_tfr_write_coherence(const analyze_result *frames, size_t n, const mtr_tfr_meta *meta, const char *dir,
			    bool plots, char *err, size_t err_size)
{
	out_file o;
	size_t nT = meta->threshold_count;
	if (tl_mkdirs(dir, err, err_size))
		return TL_ERR_OUTPUT; /* a folder or file of DIR could not be written (issue 30.5) */
	uint64_t visible = 0, visible_prev = 0;
	for (size_t f = 0; f < n; f++)
		visible += frames[f].visible, visible_prev += frames[f].visible_prev;

	if (open_file(&o, dir, "coherence.csv", err, err_size))
		return TL_ERR_OUTPUT; /* a folder or file of DIR could not be written (issue 30.5) */
	fprintf(o.f, "T,k,unchanged_samples,visible_samples,fraction_unchanged\n");
	json_t *at120 = json_object();
	for (size_t i = 0; i < nT; i++)
		for (int k = 1; k <= ANALYZE_HISTORY; k++) {
			uint64_t u = 0;
			for (size_t f = 0; f < n; f++)
				u += frames[f].unchanged[i][k];
			double frac = visible ? (double)u / (double)visible : 0.0;
			fprintf(o.f, "%g,%d,%llu,%llu,%.6f\n", (double)meta->thresholds[i], k, (unsigned long long)u,
				(unsigned long long)visible, frac);
			if (k == ANALYZE_HISTORY) {
				char key[32];
				snprintf(key, sizeof key, "%g", (double)meta->thresholds[i]);
				json_object_set_new(at120, key, json_real(frac));
			}
		}
	if (close_file(&o, err, err_size)) {
		json_decref(at120);
		return TL_ERR_OUTPUT; /* a folder or file of DIR could not be written (issue 30.5) */
	}
	if (open_file(&o, dir, "coherence_frames.csv", err, err_size)) {
		json_decref(at120);
		return TL_ERR_OUTPUT; /* a folder or file of DIR could not be written (issue 30.5) */
	}
	fprintf(o.f, "frame,T,k,fraction_unchanged\n");
	for (size_t f = 0; f < n; f++)
		for (size_t i = 0; i < nT; i++)
			for (int k = 1; k <= ANALYZE_HISTORY; k++)
				fprintf(o.f, "%u,%g,%d,%.6f\n", frames[f].frame, (double)meta->thresholds[i], k,
					frames[f].visible ? (double)frames[f].unchanged[i][k] / (double)frames[f].visible : 0.0);
	if (close_file(&o, err, err_size) || open_file(&o, dir, "visibility.csv", err, err_size)) {
		json_decref(at120);
		return TL_ERR_OUTPUT; /* a folder or file of DIR could not be written (issue 30.5) */
	}
	fprintf(o.f, "frame,visible_samples,visible_at_previous,visibility_coherence\n");
	for (size_t f = 0; f < n; f++)
		fprintf(o.f, "%u,%llu,%llu,%.6f\n", frames[f].frame, (unsigned long long)frames[f].visible,
			(unsigned long long)frames[f].visible_prev,
			frames[f].visible ? (double)frames[f].visible_prev / (double)frames[f].visible : 0.0);
	if (close_file(&o, err, err_size)) {
		json_decref(at120);
		return TL_ERR_OUTPUT; /* a folder or file of DIR could not be written (issue 30.5) */
	}
	if (plots) {
		mtr_plot plot;
		FILE *g = plot_open(&plot, dir, "coherence");
		if (g) {
			fprintf(g, "set terminal pngcairo size 900,560\nset output '%s/coherence.png'\nset datafile separator ','\n"
				   "set title 'Temporal coherence of shading (TFR, cf. paper Fig. 4)'\nset xlabel 'frames k'\n"
				   "set ylabel 'samples unchanged for >= k frames'\nset yrange [0:1]\nset xrange [1:%d]\n"
				   "set key bottom left\nplot ",
				dir, ANALYZE_HISTORY);
			for (size_t i = 0; i < nT; i++)
				fprintf(g, "%s'%s/coherence.csv' using ($1==%g ? $2 : 1/0):5 with lines lw 2 title 'T = %g'",
					i ? ", " : "", dir, (double)meta->thresholds[i], (double)meta->thresholds[i]);
			fprintf(g, "\n");
			plot_run(&plot);
		}
	}
	json_t *j = meta_json(frames, n, meta);
	json_object_set_new(j, "fraction_unchanged_120", at120);
	json_object_set_new(j, "visibility_coherence", json_real(visible ? (double)visible_prev / (double)visible : 0.0));
	return write_json(j, dir, "coherence.json", err, err_size);
}

static void class_row(FILE *f, const uint64_t c[ANALYZE_CLASSES], int fractions)
{
	uint64_t total = 0;
	for (int k = 0; k < ANALYZE_CLASSES; k++)
		total += c[k];
	for (int k = 0; k < ANALYZE_CLASSES; k++)
		fprintf(f, ",%llu", (unsigned long long)c[k]);
	fprintf(f, ",%llu", (unsigned long long)total);
	if (fractions)
		for (int k = 0; k < ANALYZE_CLASSES; k++)
			fprintf(f, ",%.6f", total ? (double)c[k] / (double)total : 0.0);
	fputc('\n', f);
}

int mtr_tfr_write_predictors(const analyze_result *frames, size_t n, const mtr_tfr_meta *meta, const char *dir,
			     bool plots, char *err, size_t err_size)
{
	out_file o;
	size_t nT = meta->threshold_count;
	if (tl_mkdirs(dir, err, err_size) || open_file(&o, dir, "predictors.csv", err, err_size))
		return TL_ERR_OUTPUT; /* a folder or file of DIR could not be written (issue 30.5) */
	fprintf(o.f, "T,predictor,filtered,late,early,on_time,unchanged,samples,late_fraction,early_fraction,"
		     "on_time_fraction,unchanged_fraction\n");
	json_t *rows = json_array();
	for (size_t i = 0; i < nT; i++)
		for (int p = 0; p < ANALYZE_PREDICTORS; p++) {
			uint64_t c[ANALYZE_CLASSES] = {0};
			for (size_t f = 0; f < n; f++)
				for (int k = 0; k < ANALYZE_CLASSES; k++)
					c[k] += frames[f].classes[i][p][k];
			fprintf(o.f, "%g,%s,%d", (double)meta->thresholds[i], analyze_predictor_name(p % 3), p >= 3);
			class_row(o.f, c, 1);
			json_array_append_new(rows, json_pack("{s:f, s:s, s:b, s:I, s:I, s:I, s:I}", "T", (double)meta->thresholds[i],
							      "predictor", analyze_predictor_name(p % 3), "filtered", p >= 3,
							      "late", (json_int_t)c[0], "early", (json_int_t)c[1], "on_time",
							      (json_int_t)c[2], "unchanged", (json_int_t)c[3]));
		}
	if (close_file(&o, err, err_size) || open_file(&o, dir, "predictors_frames.csv", err, err_size)) {
		json_decref(rows);
		return TL_ERR_OUTPUT; /* a folder or file of DIR could not be written (issue 30.5) */
	}
	fprintf(o.f, "frame,T,predictor,filtered,late,early,on_time,unchanged,samples\n");
	for (size_t f = 0; f < n; f++)
		for (size_t i = 0; i < nT; i++)
			for (int p = 0; p < ANALYZE_PREDICTORS; p++) {
				fprintf(o.f, "%u,%g,%s,%d", frames[f].frame, (double)meta->thresholds[i],
					analyze_predictor_name(p % 3), p >= 3);
				class_row(o.f, frames[f].classes[i][p], 0);
			}
	if (close_file(&o, err, err_size)) {
		json_decref(rows);
		return TL_ERR_OUTPUT; /* a folder or file of DIR could not be written (issue 30.5) */
	}
	if (plots) {
		/* Stacked bars: one group per T, bars single/long/inst, unfiltered then filtered (Figs. 7, 9). */
		mtr_plot plot;
		FILE *g = plot_open(&plot, dir, "predictors");
		if (g) {
			fprintf(g, "set terminal pngcairo size 1200,560\nset output '%s/predictors.png'\nset datafile separator ','\n"
				   "set title 'Gradient predictors on TFR histories (cf. paper Figs. 7, 9): bars per T = single, long, inst; "
				   "unfiltered | filtered'\n"
				   "set style data histograms\nset style histogram rowstacked\nset style fill solid 0.9 border -1\n"
				   "set boxwidth 0.8\nset yrange [0:1]\nset ylabel 'fraction of samples'\nset key outside right\n"
				   "set xtics rotate by -60 font ',8'\n"
				   "plot '%s/predictors.csv' every ::1 using 9:xtic(sprintf('T%%s %%s%%s', strcol(1), strcol(2), "
				   "strcol(3) eq '1' ? '+f' : '')) title 'late' lc rgb '#d62728', '' every ::1 using 10 title 'early' "
				   "lc rgb '#ff9f1c', '' every ::1 using 11 title 'on time' lc rgb '#2ca02c', '' every ::1 using 12 "
				   "title 'unchanged' lc rgb '#bbbbbb'\n",
				dir, dir);
			plot_run(&plot);
		}
	}
	json_t *j = meta_json(frames, n, meta);
	json_object_set_new(j, "predictors", rows);
	return write_json(j, dir, "predictors.json", err, err_size);
}

int mtr_tfr_write_gradients(const analyze_result *r, const mtr_tfr_meta *meta, const char *dir, char *err,
			    size_t err_size)
{
	char sub[4096], path[4300];
	if (!r->gradients || !r->gradients_filtered) {
		snprintf(err, err_size, "no gradient images kept for frame %u", r->frame);
		return TL_ERR_INTERNAL; /* the caller did not ask analyze to keep them */
	}
	snprintf(sub, sizeof sub, "%s/gradients", dir);
	if (tl_mkdirs(sub, err, err_size))
		return TL_ERR_OUTPUT; /* a folder or file of DIR could not be written (issue 30.5) */
	size_t np = (size_t)r->width * r->height;
	float *map = malloc(np * sizeof *map);
	if (!map) {
		snprintf(err, err_size, "out of memory");
		return TL_ERR_NOMEM;
	}
	int rc = 0;
	for (size_t i = 0; i < meta->threshold_count && !rc; i++)
		for (int p = 0; p < ANALYZE_PREDICTORS && !rc; p++) {
			for (uint32_t y = 0; y < r->height; y++)
				for (uint32_t x = 0; x < r->width; x++) {
					float v;
					if (p < 3)
						v = r->gradients[((i * r->height + y) * r->width + x) * 4 + (size_t)p];
					else
						v = r->gradients_filtered[((i * r->filtered_height + y / 8) * r->filtered_width + x / 8) * 4 +
									  (size_t)(p - 3)];
					map[(size_t)y * r->width + x] = v;
				}
			snprintf(path, sizeof path, "%s/%06u_T%g_%s.png", sub, r->frame, (double)meta->thresholds[i],
				 analyze_predictor_name(p));
			rc = mtr_heatmap_write(path, map, r->width, r->height, meta->thresholds[i] / 4.0, err, err_size);
		}
	free(map);
	return rc;
}
