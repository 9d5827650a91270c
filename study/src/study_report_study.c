/* study_report_study.c — the study section of the sweep report (study_report.h; DESIGN section 9): the study's tally
 * (study_result.h, written into report/study/ as `taslab study tally` writes it), its conditions joined with the
 * runs per method, T, period, scene and camera (report/data/study.csv), and a plot of the JND against a chosen
 * metric. The conditions come from the tally's result, not from reading conditions.csv back (issue 30.3). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_internal.h"
#include "study_report_internal.h"
#include "taslab/metrics.h"
#include "taslab/study.h"
#include "taslab/study_result.h"
#include "taslab/tl_fs.h"

/* JND from p clamped half an observation from 0 and 1 (metrics.h, the study's convention). */
static double jnd_of(double p, double n)
{
	if (!isfinite(p) || !(n > 0))
		return NAN;
	double lo = 1 / (2 * n), hi = 1 - lo;
	return mtr_jnd_from_p(p < lo ? lo : p > hi ? hi : p);
}

/* A value as conditions.csv states it (6 decimals): the page and data/study.csv show the numbers of the tally's
 * file next to them, digit for digit. */
static double as_written(double v)
{
	char buf[64];
	snprintf(buf, sizeof buf, "%.6f", v);
	return strtod(buf, NULL);
}

int sty_rpt_study_load(const sty_report_desc *d, const char *out, sty_rpt_study *t, char *err, size_t err_size)
{
	sty *s = NULL;
	sty_result *r = NULL;
	memset(t, 0, sizeof *t);
	int rc = sty_open(d->study, &s, err, err_size);
	if (rc)
		return rc;
	sty_tally_desc td = {.out = out, .bootstrap = 200, .seed = 1, .no_plot = true};
	/* The join's premise first (issue 27.12): nothing of the study is written for a sweep of other clips. */
	if (!(rc = sty_rpt_study_check(s, d, d->study, t, err, err_size)) && !(rc = sty_tally_compute(s, &td, &r, err, err_size)))
		rc = sty_tally_write(s, r, &td, err, err_size);
	sty_close(&s);
	if (!rc && !(t->c = calloc(r->row_count + 1, sizeof *t->c)))
		rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	for (size_t i = 0; !rc && i < r->row_count; i++) {
		const sty_row *w = &r->rows[i];
		const sty_variant *v = &r->variants[w->variant];
		sty_rpt_cond *c = &t->c[t->n++];
		snprintf(c->method, sizeof c->method, "%s", v->method);
		snprintf(c->scene, sizeof c->scene, "%s", w->scene);
		snprintf(c->camera, sizeof c->camera, "%s", w->camera);
		c->T = v->T;
		c->period = v->period;
		c->n = (double)w->n;
		c->Q = isfinite(w->Q) ? as_written(w->Q) : NAN;
		c->Q_lo = isfinite(w->Q_lo) ? as_written(w->Q_lo) : NAN;
		c->Q_hi = isfinite(w->Q_hi) ? as_written(w->Q_hi) : NAN;
		c->p = as_written(w->j.p), c->p_lo = as_written(w->j.p_lo), c->p_hi = as_written(w->j.p_hi);
		/* the tally's JND; its interval maps the Wilson interval of p_ref (Phi^-1 is monotone) */
		c->jnd = as_written(w->j.jnd);
		c->jnd_lo = jnd_of(c->p_lo, c->n), c->jnd_hi = jnd_of(c->p_hi, c->n);
	}
	if (!rc && r->threshold_count) { /* the thresholds beside Fig. 3 (issue 28) */
		if (!(t->thr = malloc(r->threshold_count * sizeof *t->thr)))
			rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		else
			memcpy(t->thr, r->thresholds, r->threshold_count * sizeof *t->thr), t->nthr = r->threshold_count;
	}
	sty_result_free(&r);
	if (!rc)
		sty_rpt_study_missing(d, t);
	return rc;
}

void sty_rpt_study_free(sty_rpt_study *t)
{
	free(t->c);
	free(t->thr);
	free(t->pred);
	t->c = NULL;
	t->thr = NULL;
	t->pred = NULL;
	t->n = t->nthr = t->npred = 0;
}

int sty_rpt_model_load(const sty_report_desc *d, sty_rpt_study *t, char *err, size_t err_size)
{
	if (!d->model)
		return TL_OK;
	return sty_model_predict(d->model, d->dir, t->pred_metric, sizeof t->pred_metric, &t->pred, &t->npred, err,
				 err_size);
}

const sty_model_pred *sty_rpt_pred_of(const sty_rpt_study *t, const sty_threshold_row *h)
{
	return h->pooled ? NULL : sty_model_pred_find(t->pred, t->npred, h->method, h->period, h->scene, h->camera);
}

bool sty_rpt_pred_rated(const sty_rpt_study *t, const sty_model_pred *p)
{
	for (size_t i = 0; i < t->nthr; i++)
		if (sty_rpt_pred_of(t, &t->thr[i]) == p)
			return true;
	return false;
}

/* One row of data/thresholds.csv; the predicted cells as `study model --predict` writes them (%.4f). */
static void thr_line(FILE *f, const char *method, long period, const char *scene, const char *camera, size_t n,
		     const double m[3], const sty_model_pred *p)
{
	char c[2][200], b[64];
	fprintf(f, "%s,", sty_csv_cell(method, c[0], sizeof c[0]));
	if (period)
		fprintf(f, "%ld", period);
	fprintf(f, ",%s,%s,%zu", sty_csv_cell(scene, c[0], sizeof c[0]), sty_csv_cell(camera, c[1], sizeof c[1]), n);
	for (int k = 0; k < 3; k++)
		fprintf(f, ",%s", sty_num_cell(m[k], "%.4f", b, sizeof b));
	sty_model_pred_cells(f, p);
	fputc('\n', f);
}

int sty_rpt_thresholds_csv(const char *rdir, const sty_rpt_study *t, char *err, size_t err_size)
{
	if (!t->nthr && !t->npred)
		return TL_OK;
	char path[TL_PATH_MAX + 64];
	tl_atomic a;
	snprintf(path, sizeof path, "%s/data/thresholds.csv", rdir);
	int rc = tl_atomic_open(&a, path, err, err_size);
	if (rc)
		return rc;
	fprintf(a.f, "method,period,scene,camera,n,t_jnd,t_jnd_lo,t_jnd_hi,predicted_t_jnd,predicted_t_jnd_lo,"
		     "predicted_t_jnd_hi\n");
	for (size_t i = 0; i < t->nthr; i++) {
		const sty_threshold_row *h = &t->thr[i];
		double m[3] = {h->f.t_jnd, h->f.t_jnd_lo, h->f.t_jnd_hi};
		thr_line(a.f, h->method, h->period, h->scene, h->camera, h->f.n, m, sty_rpt_pred_of(t, h));
	}
	for (size_t i = 0; i < t->npred; i++) {
		const sty_model_pred *p = &t->pred[i];
		if (!sty_rpt_pred_rated(t, p))
			thr_line(a.f, p->method, p->period, p->scene, p->camera, 0, (double[3]){NAN, NAN, NAN}, p);
	}
	return tl_atomic_commit(&a, err, err_size);
}

const sty_rpt_cond *sty_rpt_study_find(const sty_rpt_study *t, const sweep_spec *s, const mtr_sweep_row *r)
{
	const sweep_variant *v = &s->variants[r->run.variant];
	const sweep_scene *sc = &s->scenes[r->run.scene];
	const sty_rpt_cond *hit = NULL;
	int hits = 0;
	for (size_t i = 0; i < t->n; i++) {
		const sty_rpt_cond *c = &t->c[i];
		if (strcmp(c->method, v->method) || strcmp(c->scene, sc->name) || strcmp(c->camera, sc->cameras[r->run.camera].name))
			continue;
		if (isfinite(v->T) != isfinite(c->T) || (isfinite(v->T) && fabs(v->T - c->T) > 1e-9))
			continue;
		if (c->period != v->period)
			continue;
		hit = c, hits++;
	}
	return hits == 1 ? hit : NULL;
}

/* The JND against the chosen metric, one point per condition with its interval; *drawn false when gnuplot did not
 * draw it (plots are optional), TL_ERR_OUTPUT when the script cannot be written. */
static int jnd_plot_draw(const char *rdir, const char *jnd_metric, bool *drawn, char *err, size_t err_size)
{
	mtr_plot plot;
	char gp[TL_PATH_MAX + 64], note[1024];
	snprintf(gp, sizeof gp, "%s/data/study.gp", rdir);
	FILE *f = mtr_plot_begin(&plot, gp, err, err_size);
	if (!f)
		return TL_ERR_OUTPUT;
	fprintf(f, "set terminal svg size 640,400 dynamic font 'sans,10' background rgb 'white'\n"
		   "set datafile separator ','\nset grid\nset key outside right noenhanced\n"
		   "set termoption noenhanced\nset output '%s/plots/jnd.svg'\n"
		   "set title 'JND against %s (one point per condition, 95%% intervals)'\n"
		   "set xlabel '%s'\nset ylabel 'JND'\nset arrow from graph 0, first 1 to graph 1, first 1 nohead dt 2\n"
		   "methods = system(\"tail -n +2 '%s/data/study.csv' | cut -d, -f3 | sort -u | tr '\\\\n' ' '\")\n"
		   "plot for [m in methods] '%s/data/study.csv' using (strcol(3) eq m ? $7 : 1/0):15:16:17 every ::1 "
		   "with yerrorbars pt 7 title m\n",
		rdir, jnd_metric, jnd_metric, rdir, rdir);
	*drawn = mtr_plot_end(&plot, note, sizeof note) == TL_OK;
	return TL_OK;
}

/* The paper's Fig. 3 (sec. 3): per method (and period), the pooled Q with its 95% interval and p_ref with its 95%
 * Wilson interval against T, the JND line at p_ref = 75% and chance at 50% — report/data/fig3.csv and
 * plots/fig3.svg. t->fig3 says whether it was drawn. */
static int fig3_files(const char *rdir, sty_rpt_study *t, char *err, size_t err_size)
{
	char path[TL_PATH_MAX + 64], series[2048] = "";
	tl_atomic a;
	snprintf(path, sizeof path, "%s/data/fig3.csv", rdir);
	int rc = tl_atomic_open(&a, path, err, err_size);
	if (rc)
		return rc;
	fprintf(a.f, "series,method,T,period,n,Q,Q_lo,Q_hi,p_ref_percent,p_ref_lo_percent,p_ref_hi_percent\n");
	t->fig3_points = 0;
	for (size_t i = 0; i < t->n; i++) {
		const sty_rpt_cond *c = &t->c[i];
		if (strcmp(c->scene, "all") || !isfinite(c->T))
			continue;
		char name[64];
		if (c->period)
			snprintf(name, sizeof name, "%s/%u", c->method, c->period);
		else
			snprintf(name, sizeof name, "%s", c->method);
		char key[80];
		snprintf(key, sizeof key, " %s ", name);
		if (!strstr(series, key) && strlen(series) + strlen(key) + 1 < sizeof series)
			strcat(series, key);
		fprintf(a.f, "%s,%s,%g,", name, c->method, c->T);
		if (c->period)
			fprintf(a.f, "%u", c->period);
		double vals[] = {c->n, c->Q, c->Q_lo, c->Q_hi, 100 * c->p, 100 * c->p_lo, 100 * c->p_hi};
		for (size_t q = 0; q < sizeof vals / sizeof vals[0]; q++) {
			fputc(',', a.f);
			if (isfinite(vals[q]))
				fprintf(a.f, "%.9g", vals[q]);
		}
		fputc('\n', a.f);
		t->fig3_points++;
	}
	if ((rc = tl_atomic_commit(&a, err, err_size)) || !t->fig3_points)
		return rc;
	mtr_plot plot;
	char gp[TL_PATH_MAX + 64], note[1024];
	snprintf(gp, sizeof gp, "%s/data/fig3.gp", rdir);
	FILE *f = mtr_plot_begin(&plot, gp, err, err_size);
	if (!f)
		return TL_ERR_OUTPUT;
	/* Undefined intervals (one participant) are empty cells: gnuplot draws the point without a bar. */
	fprintf(f, "set terminal svg size 960,400 dynamic font 'sans,11' background rgb 'white'\n"
		   "set datafile separator ','\nset datafile missing ''\nset termoption noenhanced\n"
		   "set output '%s/plots/fig3.svg'\nseries = '%s'\n"
		   "set multiplot layout 1,2 title 'Fig. 3: rated quality against the threshold T (pooled over scenes and "
		   "camera paths, 95%% intervals)'\n"
		   "set grid\nset logscale x 2\nset offsets graph 0.08, graph 0.08, 0, 0\nset key top left\n"
		   "set xlabel 'T (largest reused colour difference, 8-bit code values)'\n"
		   "set ylabel 'Q (0 = no difference, +2 = reference much better)'\nset yrange [-2<*<-0.5:0.5<*<2]\n"
		   "set arrow 1 from graph 0, first 0 to graph 1, first 0 nohead lc rgb '#888888'\n"
		   "plot for [m in series] '%s/data/fig3.csv' using (strcol(1) eq m ? $3 : 1/0):"
		   "(strcol(1) eq m ? $6 : 1/0):7:8 every ::1 with yerrorlines pt 7 title m\n"
		   "unset arrow 1\nset ylabel 'p_ref (%% choosing the reference)'\nset yrange [0:100]\n"
		   "set arrow 2 from graph 0, first 75 to graph 1, first 75 nohead dt 2 lc rgb '#c03030'\n"
		   "set label 2 '1 JND (75%%)' at graph 0.02, first 78 tc rgb '#c03030'\n"
		   "set arrow 3 from graph 0, first 50 to graph 1, first 50 nohead dt 3 lc rgb '#888888'\n"
		   "set label 3 'chance (50%%)' at graph 0.02, first 53 tc rgb '#666666'\n"
		   "plot for [m in series] '%s/data/fig3.csv' using (strcol(1) eq m ? $3 : 1/0):"
		   "(strcol(1) eq m ? $9 : 1/0):10:11 every ::1 with yerrorlines pt 7 title m\n"
		   "unset multiplot\n",
		rdir, series, rdir, rdir);
	t->fig3 = mtr_plot_end(&plot, note, sizeof note) == TL_OK;
	return TL_OK;
}

int sty_rpt_study_files(const sty_report_desc *d, const char *rdir, sty_rpt_study *t, bool *jnd_plot, char *err,
			size_t err_size)
{
	int frc = fig3_files(rdir, t, err, err_size);
	if (frc)
		return frc;
	const sweep_spec *s = d->spec;
	const char *jnd_metric = d->jnd_metric ? d->jnd_metric : "flip_mean";
	char path[TL_PATH_MAX + 64];
	tl_atomic a;
	*jnd_plot = false;
	snprintf(path, sizeof path, "%s/data/study.csv", rdir);
	int rc = tl_atomic_open(&a, path, err, err_size);
	if (rc)
		return rc;
	fprintf(a.f, "scene,camera,method,variant,T,period,%s,n,Q,Q_lo,Q_hi,p_ref,p_ref_lo,p_ref_hi,jnd,jnd_lo,jnd_hi\n",
		jnd_metric);
	for (size_t k = 0; k < d->count; k++) {
		const mtr_sweep_row *r = &d->rows[k];
		const sty_rpt_cond *c = sty_rpt_study_find(t, s, r);
		if (!c)
			continue;
		const sweep_variant *v = &s->variants[r->run.variant];
		double x = mtr_sweep_value(r, jnd_metric);
		fprintf(a.f, "%s,%s,%s,%s,", s->scenes[r->run.scene].name, s->scenes[r->run.scene].cameras[r->run.camera].name,
			v->method, v->variant);
		if (isfinite(v->T))
			fprintf(a.f, "%g", v->T);
		fputc(',', a.f);
		if (v->period)
			fprintf(a.f, "%u", v->period);
		double vals[] = {x, c->n, c->Q, c->Q_lo, c->Q_hi, c->p, c->p_lo, c->p_hi, c->jnd, c->jnd_lo, c->jnd_hi};
		for (size_t q = 0; q < sizeof vals / sizeof vals[0]; q++) {
			fputc(',', a.f);
			if (isfinite(vals[q]))
				fprintf(a.f, "%.9g", vals[q]);
		}
		fputc('\n', a.f);
		*jnd_plot |= isfinite(x) && isfinite(c->jnd);
	}
	if ((rc = tl_atomic_commit(&a, err, err_size)))
		return rc;
	return *jnd_plot ? jnd_plot_draw(rdir, jnd_metric, jnd_plot, err, err_size) : TL_OK;
}
