/* study_threshold_rows.h (private) — thresholds.csv from a study's ratings (issue 28): the tally (study_tally.c) hands
 * every rated test trial of a method with a threshold T as one record; the threshold module groups them per method x
 * period x scene x camera path (and pooled: scene = camera = all), fits each group with at least two levels of T
 * (sty_threshold_fit) into sty_result.thresholds, and writes them (sty_write_thresholds). */
#ifndef TASLAB_STUDY_THRESHOLD_ROWS_H
#define TASLAB_STUDY_THRESHOLD_ROWS_H

#include <stdint.h>
#include <stdio.h>

#include "taslab/study_model.h"
#include "taslab/study_result.h"

typedef struct sty_trating {
	const char *method, *scene, *camera; /* borrowed from the caller for the call */
	uint32_t period;                     /* 0: none */
	double T;
	int64_t participant;
	double y;                            /* 1: reference preferred, 0.5: same, 0: the other clip */
} sty_trating;

/* Fits every group of the n records (any order; reordered) into r->thresholds. TL_ERR_NOMEM. */
int sty_thresholds_compute(sty_trating *t, size_t n, sty_result *r, char *err, size_t err_size);

/* thresholds.csv: method,period,scene,camera,n,t_jnd,t_jnd_lo,t_jnd_hi,log2_t_jnd,slope,lapse,observer_sd,levels,
 * participants (inf and 0 for open ends, as every CSV of the tally writes infinity). */
void sty_write_thresholds(FILE *f, const sty_result *r);
/* The same with a model's predictions (`tally --model`, npred may be 0): predicted_t_jnd,predicted_t_jnd_lo,
 * predicted_t_jnd_hi after the columns above (empty for pooled rows and series without a prediction). */
void sty_write_thresholds_predicted(FILE *f, const sty_result *r, const sty_model_pred *pred, size_t npred);

#endif
