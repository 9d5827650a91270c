/* study_threshold_rows.c — the rows of thresholds.csv (study_threshold_rows.h; issue 28): per method x period x scene x
 * camera path with at least two levels of T, then pooled over scenes and paths (scene = camera = all), each fitted by
 * sty_threshold_fit (study_threshold.c). Rows come in method, period order, each method's (scene, camera) rows sorted
 * by scene and camera, then its pooled row. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "study_internal.h"
#include "study_threshold_rows.h"

static int cmp_group(const sty_trating *a, const sty_trating *b, bool pooled)
{
	int c = strcmp(a->method, b->method);
	if (c)
		return c;
	if (a->period != b->period)
		return a->period < b->period ? -1 : 1;
	if (pooled)
		return 0;
	if ((c = strcmp(a->scene, b->scene)))
		return c;
	return strcmp(a->camera, b->camera);
}

static int cmp_rating(const void *pa, const void *pb) { return cmp_group(pa, pb, false); }

/* Fits records t[0..n) into a new row of r (no row when fewer than two levels). */
static int add_row(const sty_trating *t, size_t n, bool pooled, sty_result *r, char *err, size_t err_size)
{
	sty_tobs *o = malloc(n * sizeof *o);
	if (!o)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	size_t levels = 0;
	for (size_t i = 0; i < n; i++) {
		o[i] = (sty_tobs){.participant = t[i].participant, .T = t[i].T, .y = t[i].y};
		levels += i == 0 || t[i].T != t[0].T; /* more than one distinct value is all that matters here */
	}
	int rc = TL_OK;
	if (levels >= 2) {
		sty_threshold_row *nr = realloc(r->thresholds, (r->threshold_count + 1) * sizeof *nr);
		if (!nr) {
			free(o);
			return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		}
		r->thresholds = nr;
		sty_threshold_row *row = &nr[r->threshold_count];
		memset(row, 0, sizeof *row);
		snprintf(row->method, sizeof row->method, "%s", t[0].method);
		row->period = t[0].period;
		row->pooled = pooled;
		snprintf(row->scene, sizeof row->scene, "%s", pooled ? "all" : t[0].scene);
		snprintf(row->camera, sizeof row->camera, "%s", pooled ? "all" : t[0].camera);
		if (!(rc = sty_threshold_fit(o, n, &row->f, err, err_size)))
			r->threshold_count++;
	}
	free(o);
	return rc;
}

int sty_thresholds_compute(sty_trating *t, size_t n, sty_result *r, char *err, size_t err_size)
{
	if (!n)
		return TL_OK;
	qsort(t, n, sizeof *t, cmp_rating);
	int rc = TL_OK;
	for (size_t m0 = 0; m0 < n && !rc;) { /* one method x period */
		size_t m1 = m0;
		while (m1 < n && !cmp_group(&t[m0], &t[m1], true))
			m1++;
		for (size_t g0 = m0; g0 < m1 && !rc;) {
			size_t g1 = g0;
			while (g1 < m1 && !cmp_group(&t[g0], &t[g1], false))
				g1++;
			rc = add_row(t + g0, g1 - g0, false, r, err, err_size);
			g0 = g1;
		}
		if (!rc)
			rc = add_row(t + m0, m1 - m0, true, r, err, err_size);
		m0 = m1;
	}
	return rc;
}

/* The study's one convention (sty_num_cell, issue 27.10): inf as "inf", undefined as an empty cell. */
static void num(FILE *f, double v)
{
	char b[64];
	fprintf(f, ",%s", sty_num_cell(v, "%.6f", b, sizeof b));
}

static void write_rows(FILE *f, const sty_result *r, const sty_model_pred *pred, size_t npred, bool predicted)
{
	fprintf(f, "method,period,scene,camera,n,t_jnd,t_jnd_lo,t_jnd_hi,log2_t_jnd,slope,lapse,observer_sd,levels,"
		   "participants%s\n", predicted ? ",predicted_t_jnd,predicted_t_jnd_lo,predicted_t_jnd_hi" : "");
	for (size_t i = 0; i < r->threshold_count; i++) {
		const sty_threshold_row *w = &r->thresholds[i];
		char cm[80], csc[160], cca[160], ps[16] = "";
		if (w->period)
			snprintf(ps, sizeof ps, "%u", w->period);
		fprintf(f, "%s,%s,%s,%s,%zu", sty_csv_cell(w->method, cm, sizeof cm), ps, sty_csv_cell(w->scene, csc, sizeof csc),
			sty_csv_cell(w->camera, cca, sizeof cca), w->f.n);
		num(f, w->f.t_jnd), num(f, w->f.t_jnd_lo), num(f, w->f.t_jnd_hi), num(f, w->f.theta);
		num(f, w->f.slope), num(f, w->f.lapse), num(f, w->f.observer_sd);
		fprintf(f, ",%zu,%zu", w->f.levels, w->f.participants);
		if (predicted) /* as `report --model` meets them: pooled rows have none */
			sty_model_pred_cells(f, w->pooled ? NULL : sty_model_pred_find(pred, npred, w->method, w->period, w->scene,
										     w->camera));
		fputc('\n', f);
	}
}

void sty_write_thresholds(FILE *f, const sty_result *r) { write_rows(f, r, NULL, 0, false); }

void sty_write_thresholds_predicted(FILE *f, const sty_result *r, const sty_model_pred *pred, size_t npred)
{
	write_rows(f, r, pred, npred, true);
}
