/* study_result.h — a study's statistics as values (issue 30.3): what `taslab study tally` computes, computed once
 * and shared by everything that shows or uses it — the tally's files (sty_tally_write: CSV, JSON, Markdown, the
 * Fig. 3 plot), the sweep report (study_report.h), and next a threshold fit and a simulated observer. A new study
 * output is a writer of this struct, not a second pass over the database or a reader of conditions.csv.
 *
 * The statistics (paper sec. 3, Fig. 3, sec. 7.2; DESIGN section 7; study_tally.c says how each is computed):
 * per variant (method x T x period, DESIGN section 4) and per (scene, camera) of it plus pooled: Q with a 95% t
 * interval, p_ref with a Wilson interval, JND, and JOD with a bootstrap interval over participants; per variant a
 * repeated-measures ANOVA (camera motion x scene) and Bonferroni-adjusted post hoc paired t tests; per participant
 * the catch-trial screening.
 *
 * Undefined values (issue 27.10) are NAN in the result and written one way by every output: an empty CSV cell, JSON
 * null, "–" in Markdown and on the report's page; infinite ones (F or t with no error variance) as inf / -inf (JSON:
 * the strings "inf", "-inf"). Why a value is undefined is said beside it (sty_variant.anova_note, row notes).
 *
 * Ownership: sty_tally_compute allocates the result; sty_result_free releases it.
 * Errors: a tl_err code, one line in `err`. */
#ifndef TASLAB_STUDY_RESULT_H
#define TASLAB_STUDY_RESULT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "taslab/metrics.h"
#include "taslab/study.h"
#include "taslab/study_threshold.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A variant: method x T x period (DESIGN section 4: rrc/4 and rrc/8 are two). */
typedef struct sty_variant {
	char method[32];
	double T;        /* NAN: the method has no threshold */
	uint32_t period; /* 0: the method has no period */
	char anova_note[192]; /* why its ANOVA is missing or has undefined F (one scene and camera motion, fewer than
			       * two complete participants, identical cells); "" when it has a complete one */
} sty_variant;

/* The statistics of one variant in one scene and camera path, or pooled over all of them. */
typedef struct sty_row {
	size_t variant;              /* index into sty_result.variants */
	char scene[64], camera[64];  /* "all" and "all" in the pooled row */
	bool pooled;
	size_t n;                    /* ratings */
	size_t participants;         /* participants with a rating here (the JOD bootstrap resamples them) */
	double Q, Q_lo, Q_hi;        /* mean reference-relative rating, 95% t interval cut to -2..2 (NAN below two participants) */
	mtr_jnd j;                   /* p_ref with its 95% Wilson interval, JND (metrics.h) */
	double jod, jod_lo, jod_hi;  /* JOD = -JND and its 95% bootstrap interval (NAN when no resample has one) */
} sty_row;

/* One effect of a variant's repeated-measures ANOVA (factors camera motion x scene). */
typedef struct sty_anova_row {
	size_t variant;
	const char *effect;          /* "camera", "scene" or "camera:scene" (static strings) */
	sty_anova_effect e;
	size_t participants;         /* participants with every cell (the ones analysed) */
	const char *note;            /* NULL, or why F is undefined (a static string) */
} sty_anova_row;

/* One post hoc paired t test between two levels of a factor (means over the other factor). */
typedef struct sty_posthoc_row {
	size_t variant;
	const char *factor;          /* "camera" or "scene" (static strings) */
	char level_1[64], level_2[64];
	double t, df, p, p_bonferroni;
} sty_posthoc_row;

/* A participant's catch-trial screening (reference against itself). */
typedef struct sty_observer {
	int64_t participant;         /* the database id */
	char label[160];
	int catch_n;                 /* catch trials answered */
	double catch_mean_abs;       /* mean |answer| over them (NAN when none) */
	int catch_much_better;       /* answers with |a| = 2 */
	bool flagged;                /* more than half of them |a| = 2 */
	int broken;                  /* answers stored from broken playbacks (not counted; README "Telemetry") */
	double rating_variance;      /* sample variance of the counted test answers (NAN: fewer than two) */
	int gold_n;                  /* gold trials answered (counted answers: broken playbacks left out) */
	int gold_wrong;              /* of them, answers more than STY_P910_GOLD_TOLERANCE from the known answer */
	unsigned p910;               /* P.910-crowd screening flags: STY_P910_CATCH | _GOLD | _VARIANCE (0: passed) */
} sty_observer;

/* P.910-crowd screening (README "Telemetry and screening"; the P.910-crowd toolkit's result parser, github.com/
 * microsoft/P.910 src/assets_master_script/result_parser_template.cfg): CATCH, a hidden-reference (catch) answer
 * outside -1..1 (the known answer 0 missed by more than one step); GOLD, a gold trial's reference-relative answer
 * more than STY_P910_GOLD_TOLERANCE from the known STY_P910_GOLD_ANSWER (the toolkit's [gold_question] variance: 1;
 * a session is used only when its gold questions are answered correctly, [accept_and_use] gold_standard_bigger_equal);
 * VARIANCE, the test answers' sample variance below STY_P910_MIN_VARIANCE (the same answer throughout). */
#define STY_P910_CATCH 1u
#define STY_P910_VARIANCE 2u
#define STY_P910_GOLD 4u
#define STY_P910_MIN_VARIANCE 0.1
#define STY_P910_GOLD_ANSWER 2    /* reference much better */
#define STY_P910_GOLD_TOLERANCE 1

/* The JND threshold of a method (x period) in one scene and camera path, or pooled over them (issue 28; thresholds.csv):
 * the psychometric fit of study_threshold.h over the rated levels of T (at least two). */
typedef struct sty_threshold_row {
	char method[32];
	uint32_t period;             /* 0: none */
	char scene[64], camera[64];  /* "all" and "all" in the pooled row */
	bool pooled;
	sty_tfit f;
} sty_threshold_row;

/* The tally. Rows come per variant: its (scene, camera) rows in the order of their first answer, then its pooled
 * row; anova and posthoc rows per variant in variant order. */
typedef struct sty_result {
	sty_variant *variants;       /* sorted by method, then T, then period (none first) */
	size_t variant_count;
	sty_row *rows;
	size_t row_count;
	sty_anova_row *anova;
	size_t anova_count;
	sty_posthoc_row *posthoc;
	size_t posthoc_count;
	sty_observer *observers;     /* every participant, in id order */
	size_t observer_count;
	sty_threshold_row *thresholds; /* per method x period: its (scene, camera) rows by name, then pooled */
	size_t threshold_count;
	size_t left_out;             /* flagged participants whose ratings were left out (0 with keep_flagged) */
} sty_result;

/* Computes the tally of `s` (d->keep_flagged, d->bootstrap, d->seed; d->out is not used): nothing is written.
 * TL_ERR_ARG when the study has no answered test trial (after screening). */
int sty_tally_compute(sty *s, const sty_tally_desc *d, sty_result **out, char *err, size_t err_size);

/* Writes the tally files of `r` into d->out (study.h sty_tally lists them; d->no_plot skips the plot): every output
 * is checked against the study's own files first (sty_check_output), and the files appear together or not at all.
 * sty_tally is sty_tally_compute followed by this. */
int sty_tally_write(sty *s, const sty_result *r, const sty_tally_desc *d, char *err, size_t err_size);

/* Writes to `f` why variants have no ANOVA (or one with undefined F): one line when every variant has none for the
 * same reason (one scene and camera path), else one line per such variant; nothing when all have one. sty_tally
 * writes them to stderr. */
void sty_tally_notes(const sty_result *r, FILE *f);

/* Accepts NULL, nulls the pointer. */
void sty_result_free(sty_result **r);

#ifdef __cplusplus
}
#endif
#endif
