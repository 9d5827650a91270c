/* study_report_internal.h (private) — what the sections of the sweep report (study_report.h) share. The report is
 * split by section (issue 30.3): study_report.c gathers the groups and writes the files in order; the plots and
 * images of a group (study_report_plots.c), the study joined per condition (study_report_study.c) and the page
 * (study_report_page.c) each have their own file. */
#ifndef TASLAB_STUDY_REPORT_INTERNAL_H
#define TASLAB_STUDY_REPORT_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "taslab/metrics_sweep.h"
#include "taslab/reuse_model.h"
#include "taslab/study_report.h"
#include "taslab/study.h"
#include "taslab/study_model.h"
#include "taslab/study_result.h"
#include "taslab/sweep.h"

#define STY_RPT_HEAT_MAX 32.0 /* heatmap colour scale: 0..32 code values (T = 8..16 differences stay visible) */

/* A plot against T of one summary column. */
typedef struct sty_rpt_plot {
	const char *column, *name, *title, *ylabel;
	bool logy;
} sty_rpt_plot;

#define STY_RPT_PLOT_COUNT 8
extern const sty_rpt_plot sty_rpt_plots[STY_RPT_PLOT_COUNT];

/* A run of a group with its variant. */
typedef struct sty_rpt_row {
	const mtr_sweep_row *r;
	const sweep_variant *v;
} sty_rpt_row;

/* One scene x camera path: its runs sorted by method, T and period, the ref run, what was drawn. */
typedef struct sty_rpt_group {
	size_t scene, cam;
	sty_rpt_row rows[SWEEP_MAX_VARIANTS];
	size_t n;
	const mtr_sweep_row *ref;
	bool drawn[STY_RPT_PLOT_COUNT];
	bool plots_ok;
	bool coherence;
	bool budget;    /* plots/<stem>--budget.svg was drawn */
	const mtr_reuse_group *reuse; /* this group's fits of the survey's models of reuse (reuse_model.h), or NULL */
	size_t nreuse;
} sty_rpt_group;

/* One study condition as the tally states it in conditions.csv (6 decimals), with the JND interval. */
typedef struct sty_rpt_cond {
	char method[32], scene[64], camera[64];
	double T;          /* NAN: none */
	unsigned period;   /* 0: none */
	double n, Q, Q_lo, Q_hi, p, p_lo, p_hi, jnd, jnd_lo, jnd_hi;
} sty_rpt_cond;

/* A study's conditions, from its tally, and what its join with the sweep says (issue 27.12). */
typedef struct sty_rpt_study {
	sty_rpt_cond *c;
	size_t n;
	char unchecked[2048];  /* why (part of) the stimuli could not be checked against the runs; "" when all were */
	char missing[4096];    /* the study's conditions no run of the sweep has ("tfr@32 calm/walk; ..."), joined */
	size_t missing_count;
	bool fig3;             /* plots/fig3.svg was drawn */
	size_t fig3_points;    /* pooled conditions with a T (Fig. 3's points) */
	sty_threshold_row *thr; /* the tally's thresholds (issue 28), shown beside Fig. 3 */
	size_t nthr;
	sty_model_pred *pred;   /* a model's predicted thresholds for this sweep's series (report --model), or NULL */
	size_t npred;
	char pred_metric[64];   /* the model's metric */
} sty_rpt_study;

/* ---- study_report.c */
/* File-name stem of a scene/camera group: SCENE--CAMERA. */
void sty_rpt_stem(const sweep_spec *s, size_t scene, size_t cam, char *out, size_t n);
/* A value as a table cell (<td>…</td>, mtr_fprint_shown), "–" when not available. */
void sty_rpt_cell(FILE *f, double v, const char *fmt);

/* ---- study_report_plots.c */
/* Orders a group's runs by method, then T (none first), then period (qsort). */
int sty_rpt_cmp_row(const void *a, const void *b);
/* Writes report/data/<stem>.csv and its gnuplot script and draws the group's plots; `drawn[k]` says whether plot k
 * has anything to draw. TL_ERR_UNSUPPORTED without gnuplot. */
int sty_rpt_group_plots(const char *rdir, const char *stem, sty_rpt_row *g, size_t ng, bool drawn[], char *err,
			size_t err_size);
/* Fig. 4 from an analysis folder's coherence.csv. */
int sty_rpt_coherence_plot(const char *csv, const char *svg, const char *gp, char *err, size_t err_size);
/* Thumbnails of the ref (ref_png, may be NULL) and the run at frame f and their max-RGB difference heatmap
 * (heat_png, may be NULL). */
int sty_rpt_run_images(const char *run_dir, const char *ref_dir, uint32_t f, const char *ref_png, const char *run_png,
		       const char *heat_png, char *err, size_t err_size);

/* ---- study_report_budget.c */
/* report/data/<stem>--budget.csv and the plot of exceed_8 against shaded fraction, one curve per method (not the
 * reference) over its settings; *drawn says whether it was drawn. TL_ERR_UNSUPPORTED without gnuplot. */
int sty_rpt_budget_plot(const char *rdir, const char *stem, const sty_rpt_group *g, bool *drawn, char *err,
			size_t err_size);
/* The group's matched-budget section: the plot and the table of the pairs `p` (mtr_sweep_matched over d->rows)
 * whose TAS run is in the group. */
void sty_rpt_budget_html(FILE *f, const sty_report_desc *d, const sty_rpt_group *g, const char *stem,
			 const mtr_match_pair *p, size_t np);
/* The group's models of reuse ([S] eqs. 5-7): a table per method with a period; nothing when it has none. */
void sty_rpt_reuse_html(FILE *f, const sty_report_desc *d, const sty_rpt_group *g);

/* ---- study_report_study.c */
/* Checks the study d->study against the sweep (sty_rpt_study_check), tallies it into `out` (the tally's files) and
 * keeps its conditions; the conditions no run has are listed in t->missing. TL_ERR_INPUT (one line) when its
 * stimuli are not the sweep's runs. */
int sty_rpt_study_load(const sty_report_desc *d, const char *out, sty_rpt_study *t, char *err, size_t err_size);

/* The predicted thresholds of d->model (sty_model_predict) for every series of T of the sweep into t->pred; TL_OK
 * without a model. TL_ERR_ARG (one line) for a file that is not a model. */
int sty_rpt_model_load(const sty_report_desc *d, sty_rpt_study *t, char *err, size_t err_size);
/* The prediction for a measured threshold row (same method, period, scene, camera; NULL for pooled rows or none), and
 * whether a prediction has a measured row. */
const sty_model_pred *sty_rpt_pred_of(const sty_rpt_study *t, const sty_threshold_row *h);
bool sty_rpt_pred_rated(const sty_rpt_study *t, const sty_model_pred *p);
/* report/data/thresholds.csv: the measured thresholds with the model's prediction beside each, then the predictions
 * nobody rated (n 0, measured cells empty); nothing without thresholds or a model. */
int sty_rpt_thresholds_csv(const char *rdir, const sty_rpt_study *t, char *err, size_t err_size);

/* ---- study_report_check.c */
/* The stimuli of the open study `s` (named `db`) against the sweep d: TL_ERR_INPUT with one line when a set differs
 * (frames, size, fps, display transform, scene or colour digest, a clip that is not the sweep's); what could not be
 * checked goes to t->unchecked. */
int sty_rpt_study_check(sty *s, const sty_report_desc *d, const char *db, sty_rpt_study *t, char *err,
			size_t err_size);
/* Fills t->missing and t->missing_count: the study's (scene, camera) conditions without a run in d. */
void sty_rpt_study_missing(const sty_report_desc *d, sty_rpt_study *t);
void sty_rpt_study_free(sty_rpt_study *t);
/* The study condition of a run: same method, T, period, scene and camera; NULL when none (or not one). */
const sty_rpt_cond *sty_rpt_study_find(const sty_rpt_study *t, const sweep_spec *s, const mtr_sweep_row *r);
/* report/data/study.csv (the study joined with the runs), Fig. 3 (data/fig3.csv, plots/fig3.svg) and the JND plot against d->jnd_metric; *jnd_plot says
 * whether the plot was drawn. */
int sty_rpt_study_files(const sty_report_desc *d, const char *rdir, sty_rpt_study *t, bool *jnd_plot, char *err,
			size_t err_size);

/* ---- study_report_page.c */
/* Writes report/index.html (the page) into `path`. */
/* study_report_stereo.c: SWEEP/stereo_vs_mono.csv (with d->mono_spec; TL_OK without) and the page's "Stereo"
 * section (a stereo sweep only). */
int sty_rpt_stereo_csv(const sty_report_desc *d, char *err, size_t err_size);
void sty_rpt_page_stereo(FILE *f, const sty_report_desc *d);
int sty_rpt_page_write(const sty_report_desc *d, const char *path, const sty_rpt_group *gi, size_t ng,
		       const sty_rpt_study *study, bool gnuplot_note, bool jnd_plot, char *err, size_t err_size);

#endif
