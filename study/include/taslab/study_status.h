/* study_status.h — a running study at a glance (issue 27.8): per participant answered/total, last activity, done,
 * restarts and the catch-trial screening; per condition n, p_ref and Q so far (the tally's statistics,
 * study_result.h, computed on the answers so far). `taslab study status --db` prints it; the server's /admin/status
 * sends it as JSON to the live status page (/status).
 * Reads only: it works on a study that a server is serving. Errors: a tl_err code, one line in `err`. */
#ifndef TASLAB_STUDY_STATUS_H
#define TASLAB_STUDY_STATUS_H

#include <stdio.h>

#include "taslab/study.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The status as one JSON object (malloc'ed text in *json):
 *   {"study": path, "participants_total": n, "completed": k, "answers": a, "trials": t, "note": "" or why there are no
 *    condition statistics yet,
 *    "participants": [{"label", "answered", "total", "done", "last_activity" (ISO 8601 UTC or null), "restarts",
 *                      "flagged" (null until a test trial is answered)}],
 *    "conditions": [{"method", "T" (null: none), "period" (null: none), "scene", "camera" ("all": pooled), "n",
 *                    "p_ref", "Q", "Q_lo", "Q_hi" (null where undefined)}]} */
int sty_status_json(sty *s, char **json, char *err, size_t err_size);
/* The same as text tables. */
int sty_status_print(sty *s, FILE *f, char *err, size_t err_size);

/* Adds `count` participants to a designed study (issue 27.7): their plans come from the study's seed, its conditions
 * and the training, catch and break settings its plans have, exactly as `design` would have made participants
 * N+1.. N+count; existing participants, their plans and answers are not touched. TL_ERR_ARG for a study without a
 * design (an imported one) or a bad count; *first = the new participants' first number (1-based). */
int sty_add_participants(sty *s, uint32_t count, uint32_t *first, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
