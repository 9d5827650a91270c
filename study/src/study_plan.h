/* study_plan.h (private) — the per-participant trial plans of a design (study_plan.c): used by sty_design for a new
 * study and by sty_add_participants (study_status.h) for participants added later, so that participant k's plan is
 * the same whenever it is made. Errors: a tl_err code, one line in `err`. */
#ifndef TASLAB_STUDY_PLAN_H
#define TASLAB_STUDY_PLAN_H

#include <stddef.h>
#include <stdint.h>

#include "study_internal.h"

typedef struct sty_plan_params {
	uint64_t seed;
	uint32_t training, catch_trials, gold_trials, break_every;
	/* adaptive designs (issue 28): `trials` test trials aimed in turn at the groups (each a test condition index
	 * representing method x period x scene x camera), the T chosen when shown (study_adaptive_db.c) */
	bool adaptive;
	uint32_t trials;
	const size_t *groups;
	size_t ngroups;
} sty_plan_params;

/* Inserts participants first+1 .. first+count (labels P001.., random link codes) with their plans over the conditions
 * with ids 1..nc (is_catch[i], condition i+1's role: 0 test, 1 a reference-vs-reference pair, 2 gold). Participant k's plan is a function of
 * the seed, k and the conditions only. The caller holds a transaction. *per = trials per participant, *breaks =
 * breaks in each plan. */
int sty_plan_participants(sty *s, const int *is_catch, size_t nc, const sty_plan_params *pp, uint32_t first,
			  uint32_t count, uint32_t *per, uint32_t *breaks, char *err, size_t err_size);

#endif
