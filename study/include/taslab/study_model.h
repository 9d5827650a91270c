/* study_model.h — a metric-to-JND model (issue 28 "Metric -> JND model"; README "Thresholds"): the reference-relative
 * JOD of each rated condition of a study (`study tally`'s jod.csv) against a metric of the same clips in a sweep
 * (SWEEP/summary.csv: flip_mean, exceed_T, maxrgb_p99, flicker_mean, any numeric column), fitted monotone, checked by
 * leaving one scene out, and used to predict the JND threshold t_jnd of every scene x camera path x method of a sweep
 * nobody rated.
 *
 * The model: d = -JOD (the quality drop in JND units; 1 JND = p_ref 0.75, DESIGN section 7) is a non-decreasing
 * function of x = log2 metric, fitted by weighted isotonic regression (pool adjacent violators; weights = the
 * condition's participants) and read between the pooled blocks' centres by linear interpolation (flat beyond them).
 * m_jnd is the metric at which the fit first reaches d = 1. A clip series (the levels of T of one scene x camera x
 * method x period) has t_jnd where its metric first reaches m_jnd, interpolated linearly in log2 T and log2 metric
 * between the rendered levels; inf when it stays below m_jnd up to the largest T, 0 when it is above at the smallest.
 * Leave-one-scene-out: for each rated scene the model is fitted without that scene's conditions and predicts the
 * measured thresholds (thresholds.csv, finite ones) of its series; the error is RMSE of log2 t_jnd. The 95% interval of
 * a prediction is t_jnd * 2^(+-1.96 * that RMSE) (open — 0, inf — without a leave-one-scene-out error).
 *
 * Errors: a tl_err code, one line in `err`. */
#ifndef TASLAB_STUDY_MODEL_H
#define TASLAB_STUDY_MODEL_H

#include <stddef.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sty_model_desc {
	const char *sweep;       /* folder holding summary.csv of the rated clips */
	const char *tally;       /* folder holding jod.csv and thresholds.csv (`study tally --out`) */
	const char *metric;      /* a numeric summary.csv column or exceed_T (NULL: flip_mean) */
	const char *out;         /* MODEL.json (NULL: none) */
	const char *predict;     /* a sweep folder to predict (NULL: none) */
	const char *predict_out; /* its predictions.csv (NULL: MODEL.json's name with -predictions.csv) */
	const char *model;       /* a saved MODEL.json to predict from (no fit: sweep and tally NULL; predict set) */
} sty_model_desc;

/* MODEL.json's "format": a model file without it (written before --model) or with another is refused by --model. */
#define STY_MODEL_FORMAT "taslab study model 1"

/* One predicted threshold: a series of T (at least two levels) of a sweep. */
typedef struct sty_model_pred {
	char method[32], scene[160], camera[160];
	long period;             /* 0: none */
	double t_jnd, t_jnd_lo, t_jnd_hi; /* inf / 0 beyond the rendered range, as thresholds.csv writes them */
	size_t levels;
} sty_model_pred;

typedef struct sty_model_summary {
	size_t conditions;       /* rated conditions joined with a metric value */
	size_t scenes;           /* distinct scenes among them */
	double m_jnd;            /* the metric at 1 JND (inf: the fit never reaches 1 JND) */
	size_t loso_n;           /* measured thresholds predicted with one scene left out (finite predictions) */
	size_t loso_open;        /* of those series, predictions that were 0 or inf (left out of the RMSE) */
	double loso_rmse_log2;   /* NAN when loso_n is 0 */
	size_t predictions;      /* rows of the predictions file */
} sty_model_summary;

/* Fits, checks and (with d->predict) predicts; writes d->out and the predictions file atomically. TL_ERR_ARG or
 * TL_ERR_INPUT for a missing or unreadable file, an unknown metric column, or fewer than two joined conditions.
 * The fit predicts with m_jnd and the interval as MODEL.json states them (8 significant digits), so that
 * d->model (a saved model, no fit) predicts byte for byte what the fit that wrote it did; with d->model, d->out is a
 * copy of that model holding the new predictions, and a file that is not a model of this format is TL_ERR_ARG with
 * one line. */
int sty_model_run(const sty_model_desc *d, sty_model_summary *s, char *err, size_t err_size);

/* The predicted thresholds of every series of T of `sweep` (its summary.csv) from a saved model; `metric` (may be
 * NULL) receives the model's metric. *out is malloc'ed. TL_ERR_ARG (one line) for a file that is not a model. */
int sty_model_predict(const char *model_json, const char *sweep, char *metric, size_t metric_size, sty_model_pred **out,
		      size_t *n, char *err, size_t err_size);

/* The prediction in p[0..n) for a series (method, period 0: none, scene, camera), or NULL: how a measured threshold
 * meets its prediction (`report --model`, `tally --model`). */
const sty_model_pred *sty_model_pred_find(const sty_model_pred *p, size_t n, const char *method, long period,
					  const char *scene, const char *camera);
/* The three cells ",t_jnd,t_jnd_lo,t_jnd_hi" of a prediction (p NULL: empty) as the predictions file writes them
 * (%.4f; inf and 0 for open ends): the predicted columns of `report --model`'s and `tally --model`'s thresholds.csv. */
void sty_model_pred_cells(FILE *f, const sty_model_pred *p);

/* Weighted isotonic (non-decreasing) regression of y[0..n) in the given order (pool adjacent violators): fit[i] is
 * the weighted mean of i's pooled block. Weights > 0. */
void sty_isotonic(const double *y, const double *w, size_t n, double *fit);

/* The t_jnd at which a series' metric m[0..n) at levels T[0..n) (ascending) first reaches m_jnd, as above. */
double sty_model_t_at(const double *T, const double *m, size_t n, double m_jnd);

/* The prior of an adaptive design (issue 28 "--prior"): the prediction for (method, period, scene, camera) in a
 * MODEL.json written with --predict, as log2 t_jnd and its SD (the leave-one-scene-out RMSE). 1 when found,
 * 0 when the model holds no finite prediction for it, < 0 (a tl_err code, `err` set) when the file is unreadable. */
int sty_model_prior(const char *model_json, const char *method, long period, const char *scene, const char *camera,
		    double *theta, double *sd, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
