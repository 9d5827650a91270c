/* study_adaptive_db.h (private) — the adaptive design's state in the study database (study_adaptive_db.c, issue 28).
 * The caller holds s->lock and an open transaction (sty_next_trial's), as for every read-check-write sequence. */
#ifndef TASLAB_STUDY_ADAPTIVE_DB_H
#define TASLAB_STUDY_ADAPTIVE_DB_H

#include <stdint.h>

#include "study_internal.h"

/* Creates the adaptive_trials table (sty_design with adaptive). */
int sty_adaptive_schema(sty *s, char *err, size_t err_size);
/* Plans trial idx of participant pid as an adaptive trial of the group of condition grp (TL_ERR_DB; the design
 * reports it with the rest of its transaction). */
int sty_adaptive_plan(sty *s, int64_t pid, int64_t idx, int64_t grp);
/* The condition QUEST+ chooses for the group of condition `grp` from every answer in the group so far. */
/* A group's prior (issue 28 "--prior"): theta ~ N(theta, sd^2) in log2 T, stored for the group's condition `grp`. */
int sty_adaptive_set_prior(sty *s, int64_t grp, double theta, double sd);
int sty_adaptive_choice(sty *s, int64_t grp, int64_t *condition, char *err, size_t err_size);
/* If participant pid's current trial is an adaptive one not chosen yet, chooses its T and stores it. A no-op for
 * other trials and for studies that are not adaptive. */
int sty_adaptive_resolve(sty *s, int64_t pid, char *err, size_t err_size);

#endif
