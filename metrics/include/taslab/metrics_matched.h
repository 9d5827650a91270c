/* metrics_matched.h — the matched-budget comparison of a sweep (BASELINES.md section 0 "Comparison"; issue 26):
 * for each TAS variant (a method that takes a threshold T and reuses shading: family reprojection or atlas —
 * tarc, tasa, ...) each other method (every non-TAS method but the reference: vref, ads, the VRS methods, rrc, sa,
 * sau, tfr, ...) at its setting with the nearest clip-mean shaded samples per frame, in the same scene and camera
 * path. Ties go to the setting first in the input order. Pure: no files, no Vulkan. */
#ifndef TASLAB_METRICS_MATCHED_H
#define TASLAB_METRICS_MATCHED_H

#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* One run as the matching sees it. */
typedef struct mtr_match_item {
	const char *group;   /* scene and camera path: runs match only within a group */
	const char *method;  /* the method (its settings are the items of the same method) */
	bool tas;            /* a TAS variant (mtr_match_is_tas) */
	bool reference;      /* the reference: never matched */
	double shaded;       /* clip-mean shaded samples per frame; NAN: not available (never matched) */
} mtr_match_item;

/* A pair: item `tas` and the matched item `other`. */
typedef struct mtr_match_pair {
	size_t tas, other;
} mtr_match_pair;

/* Whether a method is TAS by its manifest facts: takes a threshold and its family is reprojection or atlas. */
bool mtr_match_is_tas(const char *family, bool takes_threshold);

/* Pairs in order: TAS items in input order, for each the other methods in order of their first item. Writes at most
 * `cap` pairs to `out` (may be NULL with cap 0) and returns how many there are in all. */
size_t mtr_match_budget(const mtr_match_item *in, size_t n, mtr_match_pair *out, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
