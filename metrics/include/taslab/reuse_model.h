/* reuse_model.h — the survey's empirical models of reuse ([S] = papers/002, sec. 4.1, eqs. 5-7; BASELINES.md A5),
 * fitted to a sweep's runs of the methods with a refresh period Δn (`rrc/N`, `rrc-random/N`, `rrc-interleaved/N`,
 * `sau/N`, `stu/N`, `warp/N`: any method with a /N period; Δn = N):
 *   eq. 5  ε(Δn) = α (1 − e^(−λ (Δn − 1)))     the error of reusing a value over Δn frames (a clip's mean of a metric)
 *   eq. 6  H_i A_hit + M_i A_miss + c = Δt_i   per frame i: hits (reused samples), misses (shaded samples), GPU time
 *   eq. 7  r(Δn) = h(Δn) A_hit + (1 − h(Δn)) A_miss,  h(Δn) = μ (1 − 1/Δn)   the cost of a sample, the hit rate
 * [S] fits them per cached intermediate value ("payload") over a training sequence; here the payload is the whole
 * shaded colour, and one fit is made per scene, camera path and method (its runs at every N of the sweep). */
#ifndef TASLAB_REUSE_MODEL_H
#define TASLAB_REUSE_MODEL_H

#include <stdbool.h>
#include <stddef.h>

#include "taslab/sweep.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mtr_eq5 {
	double alpha, lambda; /* NAN unless ok */
	double rmse;          /* of the fit, in the metric's unit */
	bool ok;              /* false with fewer than two distinct Δn > 1 (α and λ are then not both determined) */
} mtr_eq5;

/* Least squares over λ (for a given λ, α has a closed form), λ in [1e-4, 1e3]. Points with Δn < 1 are ignored. */
void mtr_fit_eq5(const double *dn, const double *eps, size_t n, mtr_eq5 *out);

typedef struct mtr_eq6 {
	double a_hit, a_miss; /* ms per sample (NAN unless three_terms: see below) */
	double miss_minus_hit; /* ms per sample: A_miss − A_hit, always determined when ok */
	double c;             /* ms per frame (with !three_terms: c + A_hit·mean(H + M), the cost of a frame of hits) */
	double r2;            /* of the fit */
	size_t frames;
	bool ok;              /* at least 4 frames, misses that vary, and (where V varies) hits not in proportion to
			       * misses, as they are at a single period */
	/* false when H + M (the visible samples) hardly varies over the frames (coefficient of variation < 2 %): then
	 * H = V − M and eq. 6 has two unknowns, not three; the fit is Δt = c' + M (A_miss − A_hit) */
	bool three_terms;
} mtr_eq6;

void mtr_fit_eq6(const double *hits, const double *misses, const double *dt, size_t n, mtr_eq6 *out);

/* μ of eq. 7's hit-rate model h(Δn) = μ (1 − 1/Δn), least squares over the points with Δn > 1; NAN when none. */
double mtr_fit_hit_rate(const double *dn, const double *rate, size_t n);

/* One run of a group: its period and clip means over the frames after its first. */
typedef struct mtr_reuse_point {
	size_t variant; /* index into the spec's variants */
	double dn, eps, hit_rate, ms, visible;
} mtr_reuse_point;

/* One scene, camera path and method (the variant token without its "/N" period) with its fits. */
typedef struct mtr_reuse_group {
	size_t scene, camera;
	char name[SWEEP_NAME_MAX];
	mtr_reuse_point pts[SWEEP_MAX_VARIANTS];
	size_t np;
	mtr_eq5 e5;
	mtr_eq6 e6;
	double mu;
} mtr_reuse_group;

/* The groups of the sweep in DIR with complete runs (and metrics) at one or more periods, fitted; *groups is
 * malloc'ed (NULL and *n = 0 when there are none). ε is the clip mean `error_key` of each run's summary.json;
 * TL_ERR_INPUT when it is not a number there. */
int mtr_reuse_fit(const sweep_spec *s, const char *dir, const char *error_key, mtr_reuse_group **groups, size_t *n,
		  char *err, size_t err_size);
/* What the fitted models predict at Δn: eq. 5's error, eq. 7's hit rate, eqs. 6 + 7's frame time (ms) for a frame of
 * `visible` samples; NAN where the group's fit is not determined. */
double mtr_reuse_eps(const mtr_reuse_group *g, double dn);
double mtr_reuse_hit_rate(const mtr_reuse_group *g, double dn);
double mtr_reuse_ms(const mtr_reuse_group *g, double dn, double visible);
/* OUT/reuse_model.csv and OUT/reuse_model.md of the groups (atomically, both or neither). */
int mtr_reuse_write(const sweep_spec *s, const char *dir, const char *error_key, const mtr_reuse_group *g, size_t n,
		    const char *out_dir, char *err, size_t err_size);

/* Fits the three models for every scene, camera path and method of the sweep in DIR that has complete runs at
 * one or more periods, with ε the clip mean `error_key` of each run's metrics summary.json (e.g. "maxrgb_mean",
 * "flip_mean", "exceed_8"); each run's first frame (a full shading, with the first frame's costs) is left out of
 * eq. 6 and of the hit rate. Writes OUT/reuse_model.csv (one row per run: measured and modelled error, hit rate and
 * cost per sample, with its group's parameters) and OUT/reuse_model.md. *groups: the number of groups fitted.
 * TL_ERR_INPUT when the sweep has no complete run of a method with a period, or `error_key` is not a number. */
int mtr_reuse_model(const sweep_spec *s, const char *dir, const char *error_key, const char *out_dir, size_t *groups,
		    char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
