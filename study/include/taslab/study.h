/* study.h — pairwise-comparison studies (paper sec. 3 and 7.2; DESIGN section 7): a randomised
 * within-subject design stored in SQLite, answers, export/import of ratings, and the statistics.
 *
 * One study = one SQLite database. Conditions come from `taslab pair` sets (pairs.json) found in a
 * stimulus folder; clip paths are stored relative to that folder, and only files inside it are ever served.
 * Every participant rates every condition against the reference of the same scene and camera path.
 *
 * Rating convention (DESIGN section 7): the participant answers a in {-2..+2} for the clips as shown
 * (A first, B second; + = second clip better). The reference-relative rating is r = +a when the reference
 * was second, r = -a when it was first; r = +2 means "reference much better".
 *
 * Errors: negative return, one line in `err`. Ownership: sty_open / sty_close.
 */
#ifndef TASLAB_STUDY_H
#define TASLAB_STUDY_H

#include "taslab/tl_error.h"
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sty sty;


/* Opens (creating the schema when `create`) a study database. */
int sty_open(const char *path, bool create, sty **out, char *err, size_t err_size);
void sty_close(sty **s);
/* The stimulus folder recorded at design time ("" for imported studies). */
const char *sty_stimuli(const sty *s);
/* The database file this study was opened from. */
const char *sty_path(const sty *s);
/* The admin token for export endpoints (random, created with the study). */
const char *sty_admin_token(const sty *s);

typedef struct sty_design_desc {
	const char *stimuli;      /* folder with pairs.json sets (DIR/pairs.json and DIR/<set>/pairs.json) */
	uint32_t participants;
	uint64_t seed;
	uint32_t training;        /* training trials at the start of each session (not analysed) */
	uint32_t catch_trials;    /* reference-vs-reference trials mixed in (observer screening) */
	uint32_t break_every;     /* a break before every N-th trial (0: none) */
	double answer_s;          /* assumed answer time per trial for the session-length estimate (default 4) */
	double gap_s;             /* grey gap between the clips (default 0.5) */
} sty_design_desc;

typedef struct sty_design_summary {
	uint32_t conditions, sets, participants, trials_per_participant, breaks;
	double session_minutes;   /* estimate: trials x (2 clips + gap + answer) + 30 s per break */
} sty_design_summary;

/* Creates conditions, participants (unguessable link codes) and per-participant trial plans. The plan is a
 * pure function of the seed: trial order shuffled per participant; in-pair order random per participant with
 * participants 2k and 2k+1 seeing complementary orders, so every pair is shown in both orders. */
int sty_design(sty *s, const sty_design_desc *d, sty_design_summary *out, char *err, size_t err_size);

/* Participant link codes, in participant order; *codes is malloc'ed (free each, then the array). */
int sty_participant_codes(sty *s, char ***codes, size_t *n, char *err, size_t err_size);

/* One trial as the participant page needs it. */
typedef struct sty_trial {
	uint32_t index, total, answered;
	char clip_a[512], clip_b[512]; /* paths relative to the stimulus folder */
	char kind[16];                 /* test, catch, training */
	bool break_before;
	bool done;                     /* all trials answered (the other fields are unset) */
} sty_trial;

int sty_next_trial(sty *s, const char *code, sty_trial *t, char *err, size_t err_size);
/* Stores an answer durably (committed before returning). TL_ERR_CONFLICT if that trial was answered,
 * TL_ERR_NOTFOUND for an unknown participant or trial, TL_ERR_ARG for an answer outside -2..2. */
int sty_answer(sty *s, const char *code, uint32_t trial, int answer, int64_t rt_ms, char *err, size_t err_size);

/* Long-format ratings CSV (DESIGN section 7):
 * participant,trial,scene,camera,camera_motion,method,T,ref_first,answer,rating,rt_ms  (test trials only). */
int sty_export_long(sty *s, const char *path, char *err, size_t err_size);
/* pwcmp layout (pw_scale_table defaults): observer,scene,condition_A,condition_B,selected_A — one row per
 * answer, condition names "ref" and METHOD_T<T>; a tie ("same") is written as two rows, one for each side. */
int sty_export_pwcmp(sty *s, const char *path, char *err, size_t err_size);
/* Imports a long-format ratings file into an empty or import-only study; validates every row first and
 * imports nothing if any row is bad (the message names the line). */
int sty_import_long(sty *s, const char *path, size_t *rows, char *err, size_t err_size);

/* Statistics into DIR: conditions.csv, anova.csv (DESIGN section 7), posthoc.csv, observers.csv, jod.csv,
 * tables as JSON and Markdown, and a Fig. 3 style plot (gnuplot). */
typedef struct sty_tally_desc {
	const char *out;
	bool keep_flagged;        /* keep observers flagged by the catch-trial screening */
	uint32_t bootstrap;       /* bootstrap resamples for JOD intervals (default 1000) */
	uint64_t seed;            /* bootstrap seed */
} sty_tally_desc;

int sty_tally(sty *s, const sty_tally_desc *d, char *err, size_t err_size);

/* Repeated-measures ANOVA on a complete n x (a x b) table of cell means (subject-major, factor A major):
 * effects A, B and A:B with F, dfs, p, and Greenhouse-Geisser epsilon and corrected p. Exposed for tests. */
typedef struct sty_anova_effect {
	double df1, df2, F, p, epsilon_gg, p_gg;
} sty_anova_effect;
int sty_rm_anova2(const double *y, size_t n, size_t a, size_t b, sty_anova_effect out[3]);

#ifdef __cplusplus
}
#endif
#endif
