/* study_select.h (private) — trial selection: the one interface through which a participant's session advances.
 * It finds the participant behind a link code, the trial they are at (the lowest-index unanswered trial of the plan
 * sty_design made) and records the answer to it. The server's calls (study.h sty_next_trial, sty_answer) are built
 * on it, and a simulated observer (ARCHITECTURE.md "simulate"; issue 30.3) drives a study through the same calls, so
 * an adaptive selection replaces this interface's implementation (study_select.c) for both.
 *
 * Locking: the caller holds s->lock (study_internal.h) from the lookup to what it does with the result, so the
 * check of the current trial and the answer's INSERT are not interleaved with other server threads.
 * Errors: a tl_err code, one line in `err`. */
#ifndef TASLAB_STUDY_SELECT_H
#define TASLAB_STUDY_SELECT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "study_internal.h"

/* The trial a participant is at. */
typedef struct sty_pick {
	uint32_t index;              /* the trial's index in the participant's plan */
	uint32_t total, answered;    /* planned trials (retakes not counted), of them done (total - unanswered) */
	bool ref_first;              /* the reference is shown first (A) */
	bool break_before;
	bool done;                   /* every trial answered: total = answered, the other fields are unset */
	char kind[16];               /* test, catch, training */
	char ref_clip[TL_PATH_MAX], test_clip[TL_PATH_MAX]; /* relative to the stimulus folder */
} sty_pick;

/* The participant id behind a link code; -1 for an unknown code (or a failed query). */
int64_t sty_select_participant(sty *s, const char *code);

/* The participant's current trial: the lowest-index unanswered one (the page answers in order). Reads only. */
int sty_select_current(sty *s, int64_t pid, sty_pick *p, char *err, size_t err_size);

/* Stores the answer to trial `trial` in the caller's transaction (sty_answer's group commit makes it durable before
 * it is acknowledged; study_commit.c). Only the
 * current trial can be answered: TL_ERR_ARG for a later one, TL_ERR_CONFLICT for one answered already,
 * TL_ERR_NOTFOUND for a trial the plan does not have. `answer` (-2..2) and `rt_ms` (-1: not measured) are the
 * caller's to check (sty_answer does). */
int sty_select_answer(sty *s, int64_t pid, uint32_t trial, int64_t answer, int64_t rt_ms, char *err, size_t err_size);

#endif
