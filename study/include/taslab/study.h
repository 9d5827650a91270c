/* study.h — pairwise-comparison studies (paper sec. 3 and 7.2; DESIGN section 7): a randomised
 * within-subject design stored in SQLite, answers, export/import of ratings, and the statistics.
 *
 * One study = one SQLite database file (mode 0600: it holds the admin token and the participants' link codes).
 * Conditions come from `taslab pair` sets (pairs.json) found in a stimulus folder; clip paths are stored
 * relative to that folder. Participants never see those paths: each trial's two clips get random 128-bit names
 * (sty_next_trial), so the page cannot tell which clip is the reference (the study stays blind).
 * Every participant rates every condition against the reference of the same scene and camera path.
 * A condition is method x T x period x scene x camera path (T and period as the method has them, DESIGN
 * section 4: rrc/4 and rrc/8 are two conditions); the conditions table stores period NULL for "none".
 * Studies made before the period column are brought up to date when opened (the column is added, NULL); one
 * that holds rrc or sau conditions (whose period was never stored) is refused by sty_open.
 *
 * Rating convention (DESIGN section 7): the participant answers a in {-2..+2} for the clips as shown
 * (A first, B second; + = second clip better). The reference-relative rating is r = +a when the reference
 * was second, r = -a when it was first; r = +2 means "reference much better".
 *
 * A new study is built in a temporary file next to its name and appears under that name only when
 * sty_commit succeeds (tl_fs.h atomic-write pattern), so a failed design or import leaves nothing behind
 * and an existing study is never overwritten.
 *
 * Errors: a tl_err code, one line in `err`. Ownership: sty_create or sty_open / sty_close.
 */
#ifndef TASLAB_STUDY_H
#define TASLAB_STUDY_H

#include "taslab/run.h"
#include "taslab/tl_error.h"
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sty sty;


/* Longest accepted reaction time (24 h, the same bound for answers and imports): anything longer is not a
 * reaction time but a broken or hostile client. */
#define STY_RT_MS_MAX 86400000

/* Opens an existing study database: TL_ERR_INPUT when `path` is not an existing taslab study file, or is an
 * older study whose rrc/sau conditions have no period. */
int sty_open(const char *path, sty **out, char *err, size_t err_size);
/* Starts a new study that will be stored at `path`. `path` must name a file: "", ":memory:" and "file:"
 * URIs are refused (TL_ERR_ARG: SQLite would keep them in memory or elsewhere). An existing `path` (or a
 * leftover PATH-wal / PATH-shm / PATH-journal of a deleted study) is refused with TL_ERR_CONFLICT: a study is
 * never overwritten. The database is built in a temporary file in the same folder (mode 0600); sty_commit
 * moves it into place, sty_close without a commit deletes it. */
int sty_create(const char *path, sty **out, char *err, size_t err_size);
/* Makes a study from sty_create appear at its path (fsync, rename, fsync of the folder) and reopens it
 * there; a no-op for a study from sty_open. TL_ERR_CONFLICT if `path` appeared in the meantime. */
int sty_commit(sty *s, char *err, size_t err_size);
/* Closes the study; an uncommitted new study is deleted. Accepts NULL, nulls the pointer. */
void sty_close(sty **s);
/* The stimulus folder recorded at design time ("" for imported studies). */
const char *sty_stimuli(const sty *s);
/* The database file this study was opened from. */
const char *sty_path(const sty *s);
/* The admin token for export endpoints (random, created with the study). */
const char *sty_admin_token(const sty *s);
/* The base URL the study was last served on ("http://127.0.0.1:8080"), "" if never; `taslab study links`
 * uses it as the default base. sty_set_served_url stores it (the server does so when it starts listening). */
const char *sty_served_url(const sty *s);
int sty_set_served_url(sty *s, const char *url, char *err, size_t err_size);

/* The study module knows no method by name (issue 30.1): what it needs of a method (whether it is the reference,
 * whether it takes a threshold T or a period N) comes from the files — pairs.json's conditions[].method_facts (run.h)
 * — or from the caller, which describes the methods of taslab's registry (method.h method_facts; the `taslab study`
 * command does so for every variant method name, tarc-oracle included). `study import` checks a ratings file's
 * T and period columns against these descriptions, and a design falls back on them for sets made before pairs.json
 * recorded method_facts. A later description of a name replaces the earlier; TL_ERR_ARG when STY_MAX_METHODS names
 * are described already or the name is too long. */
#define STY_MAX_METHODS 128
int sty_describe_method(sty *s, const char *method, const run_method_facts *facts, char *err, size_t err_size);
/* The description of `method`, or NULL when none was given. */
const run_method_facts *sty_method_facts(const sty *s, const char *method);
/* The name of the described reference method (run_method_facts.reference), or NULL. */
const char *sty_reference_method(const sty *s);
/* A period is 1, 2, 4 or 8 (`--period`, variants rrc/4, sau/8). */
bool sty_period_valid(long period);

/* The largest seed (study design, tally's bootstrap, study simulate): GSL's mt19937 keeps the low 32 bits of its seed,
 * so a larger seed would silently repeat a smaller one's draws. */
#define STY_SEED_MAX 4294967295u

typedef struct sty_design_desc {
	const char *stimuli;      /* folder with pairs.json sets (DIR/pairs.json and DIR/<set>/pairs.json) */
	uint32_t participants;
	uint64_t seed;
	uint32_t training;        /* training trials at the start of each session (not analysed) */
	uint32_t catch_trials;    /* reference-vs-reference trials mixed in (observer screening) */
	uint32_t gold_trials;     /* gold trials mixed in (P.910-crowd screening): the reference against a variant whose
				   * answer is known, "reference much better" (each set's largest T or period, or gold_variant) */
	const char *gold_variant; /* the gold condition's pairs.json id in every set (e.g. "tfr-T64"); NULL: the largest */
	uint32_t break_every;     /* a break before every N-th trial (0: none) */
	double answer_s;          /* assumed answer time per trial for the session-length estimate (default 4) */
	double gap_s;             /* grey gap between the clips (default 0.5) */
	bool adaptive;            /* issue 28: `trials` test trials per participant, each T chosen when shown (QUEST+) */
	uint32_t trials;          /* with adaptive only */
	const char *prior;        /* with adaptive: a MODEL.json with predictions (study_model.h) as each group's prior */
} sty_design_desc;

typedef struct sty_design_summary {
	uint32_t conditions, sets, participants, trials_per_participant, breaks;
	uint32_t groups, priors;  /* adaptive: groups (method x period x scene x camera) and those with a model prior */
	double session_minutes;   /* estimate: trials x (2 clips + gap + answer) + 30 s per break */
} sty_design_summary;

/* Creates conditions, participants (unguessable link codes) and per-participant trial plans. The plan is a
 * pure function of the seed: trial order shuffled per participant; in-pair order random per participant with
 * participants 2k and 2k+1 seeing complementary orders, so every pair is shown in both orders.
 * Adaptive (issue 28): each participant gets d->trials test trials, each aimed at a method x period x scene x camera
 * path in turn (plus the training and catch trials); a trial's T is chosen when it is first shown, by QUEST+ on every
 * participant's answers in that group so far (study_threshold.h sty_adapt), and stored (sty_next_trial). */
int sty_design(sty *s, const sty_design_desc *d, sty_design_summary *out, char *err, size_t err_size);

/* Participant link codes, in participant order; *codes is malloc'ed (free each, then the array). */
int sty_participant_codes(sty *s, char ***codes, size_t *n, char *err, size_t err_size);

/* One trial as the participant page needs it. */
typedef struct sty_trial {
	uint32_t index, total, answered;
	char clip_a[48], clip_b[48];   /* opaque clip names ("<32 hex digits>.webm"), served as /clips/<name> */
	char kind[16];                 /* test, catch, gold, training */
	bool break_before;
	bool stereo;                   /* the study's clips show both eyes side by side (pairs.json "display": "stereo") */
	bool done;                     /* all trials answered (the other fields are unset) */
} sty_trial;

/* The participant's current trial: the lowest-index unanswered one. Its two clips get random 128-bit names the
 * first time it is asked for (stored before returning, so a reload shows the same names); names are per
 * trial and side, so the reference's name never recurs across trials. TL_ERR_NOTFOUND for an unknown code. */
int sty_next_trial(sty *s, const char *code, sty_trial *t, char *err, size_t err_size);
/* The clip behind an opaque name from sty_next_trial: its path relative to the stimulus folder.
 * TL_ERR_NOTFOUND for any other name. */
int sty_clip_file(sty *s, const char *name, char *rel, size_t rel_size, char *err, size_t err_size);
/* Stores an answer durably (committed before returning). Rule: a participant answers the current trial only
 * (the one sty_next_trial returns; the page answers in order), so an answer to a trial not yet shown is
 * TL_ERR_ARG. TL_ERR_CONFLICT if that trial was answered already (a retried request), TL_ERR_NOTFOUND for an
 * unknown participant or trial, TL_ERR_ARG for an answer outside -2..2 or rt_ms outside 0..STY_RT_MS_MAX
 * (rt_ms = -1: not measured). */
int sty_answer(sty *s, const char *code, uint32_t trial, int64_t answer, int64_t rt_ms, char *err, size_t err_size);

/* Long-format ratings CSV (DESIGN section 7 plus the period column of DESIGN section 4, right after T, and issue 27's
 * three last columns):
 * participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms,trial_type,answered_at,
 * completed — every answered trial (trial_type test, catch or training; answered_at the answer's UTC time; completed 1
 * when the participant answered their whole plan, 0 if not, empty when unknown); T and period empty where the method
 * has none.
 * Text cells are written so that a spreadsheet cannot run them (OWASP "CSV injection"): a cell starting with
 * = + - @ TAB or CR gets a leading ', and a cell holding , " CR or LF is quoted (RFC 4180). The same holds for
 * every CSV the study module writes. */
int sty_export_long(sty *s, const char *path, char *err, size_t err_size);
/* pwcmp layout (pw_scale_table defaults): observer,scene,condition_A,condition_B,selected_A — one row per
 * answer, condition names: the reference's method name (ref; sty_reference_method, else TL_ERR_INTERNAL),
 * METHOD_T<T> (tfr_T8, tarc-oracle_T8), METHOD_N<period> (rrc_N4) or METHOD
 * (sa); a tie ("same") is written as two rows, one for each side. */
int sty_export_pwcmp(sty *s, const char *path, char *err, size_t err_size);
/* Both exports at once (either path may be NULL): every output is checked (sty_check_output, and the two are not
 * the same file) before anything is written, and the two files are committed together or not at all. */
int sty_export(sty *s, const char *long_path, const char *pwcmp_path, char *err, size_t err_size);
/* TL_ERR_ARG when writing `path` would write over the study's own files: the database or its SQLite journals
 * (-wal, -shm, -journal), by any spelling, symlink or hard link. Every study command with an --out checks its
 * outputs with it before writing anything. */
int sty_check_output(const sty *s, const char *path, char *err, size_t err_size);
/* Imports a long-format ratings file into a new study (sty_create; a study that holds participants is refused);
 * validates every row first and imports nothing if any row is bad (the message names the line). The header is
 * the one sty_export_long writes, the same without its last three columns (every row a test trial, answered at
 * "imported", completion unknown), or the DESIGN section 7 header without period either (files from before the period
 * column: every period is then empty). Rules beyond the column types: method is a DESIGN section 4 name; T is
 * given exactly for methods with a threshold (tfr, tarc, tasa and -oracle forms; 0 < T <= 255) and empty for
 * the others; period is given exactly for rrc and sau (1, 2, 4 or 8) and empty for the others; text cells
 * (participant, scene, camera, method) may not start with = + - @ (spreadsheet formulas) nor hold quotes or
 * control characters. Returns TL_OK; TL_ERR_INPUT when the file cannot be read or is malformed; TL_ERR_ARG when
 * the study already holds participants; TL_ERR_DB; TL_ERR_NOMEM. */
int sty_import_long(sty *s, const char *path, size_t *rows, char *err, size_t err_size);

/* Statistics into DIR: conditions.csv, anova.csv (DESIGN section 7), posthoc.csv, observers.csv, jod.csv,
 * tables as JSON and Markdown, and a Fig. 3 style plot (gnuplot). Every CSV with a method column has T and
 * period columns right after it (DESIGN section 4); statistics are per method x T x period. The statistics as a
 * value, without files, and the files from such a value: study_result.h. */
typedef struct sty_tally_desc {
	const char *out;
	bool keep_flagged;        /* keep observers flagged by the catch-trial screening (and by P.910's with p910) */
	bool p910;                /* also leave out observers flagged by the P.910-crowd screening (study_result.h) */
	uint32_t bootstrap;       /* bootstrap resamples for JOD intervals (default 1000) */
	uint64_t seed;            /* bootstrap seed */
	bool no_plot;             /* skip the Fig. 3 plot (gnuplot; tests and fuzzing) */
	const char *model;        /* issue 28: a saved MODEL.json (study_model.h) whose predicted t_jnd for `sweep`'s series
				   * thresholds.csv and tables.md show beside the measured ones (as `report --model`) */
	const char *sweep;        /* with model: the sweep whose clips were rated (its summary.csv) */
} sty_tally_desc;

int sty_tally(sty *s, const sty_tally_desc *d, char *err, size_t err_size);

/* Study stimuli from a sweep's runs (issue 27.13): `taslab study pairs --sweep SWEEP --out DIR`. One pairs.json set
 * per scene x camera path of the sweep in DIR/<scene>--<camera>/, whose clips are the sweep's clips (hard links;
 * copies across file systems) of the listed variants (tokens such as "tfr@8" or ids such as "tfr-T8"; none: every
 * variant but ref), with the sweep's folder, each clip's run and the runs' input digests recorded (pairs.h), so
 * `study design --stimuli DIR` rates exactly the clips the sweep measured and `taslab report SWEEP --study` can
 * check it. Every run must be complete with its clip; `out` must be new or empty. *sets: the sets written.
 * Errors: TL_ERR_INPUT (not a sweep, an incomplete run, a folder in the way), TL_ERR_ARG (a variant the sweep lacks),
 * TL_ERR_OUTPUT, TL_ERR_NOMEM; one line in `err`. */
typedef struct sty_pairs_desc {
	const char *sweep;
	const char *out;
	const char *const *variants;
	size_t variant_count;
} sty_pairs_desc;
int sty_pairs_from_sweep(const sty_pairs_desc *d, size_t *sets, char *err, size_t err_size);

/* Repeated-measures ANOVA on a complete n x (a x b) table of cell means (subject-major, factor A major):
 * effects A, B and A:B with F, dfs, p, and Greenhouse-Geisser epsilon and corrected p. Exposed for tests. Returns
 * TL_OK, TL_ERR_ARG (fewer than 2 subjects or an empty factor) or TL_ERR_NOMEM. */
typedef struct sty_anova_effect {
	double df1, df2, F, p, epsilon_gg, p_gg;
} sty_anova_effect;
int sty_rm_anova2(const double *y, size_t n, size_t a, size_t b, sty_anova_effect out[3]);

#ifdef __cplusplus
}
#endif
#endif
