/* study_threshold.h — the JND threshold of a method as a function of T (issue 28; DESIGN section 7 "Thresholds and
 * adaptive designs"; the TAS paper's Fig. 3 asks "up to which T is reuse invisible?"), the adaptive choice of T
 * (QUEST+, Watson 2017) and a simulated observer that checks both.
 *
 * The psychometric function (README "Thresholds"): x = log2 T, an observer with threshold shift u prefers the
 * reference (ties count half, DESIGN section 7) with probability
 *     psi(x) = 1/2 + (1/2 - lapse) * Phi(slope * (x - theta - u) + z0),  z0 = Phi^-1(1/4 / (1/2 - lapse)),
 * so psi = 0.75 at x = theta + u for every lapse: theta is log2 t_jnd of the median observer. Observer variability:
 * u ~ N(0, observer_sd^2) per participant, shared by all their trials (random observer effects, integrated out by
 * 24-point Gauss-Hermite quadrature). Guess rate 1/2: an observer who sees nothing has no preference.
 * The fit maximises the marginal likelihood (ties as half a preference: a tie contributes sqrt(psi (1 - psi)));
 * the 95% interval is the profile-likelihood interval of theta (deviance <= chi2(1) 0.95 = 3.841), which always
 * contains the estimate.
 *
 * Errors: a tl_err code, one line in `err`. */
#ifndef TASLAB_STUDY_THRESHOLD_H
#define TASLAB_STUDY_THRESHOLD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Bounds of the nuisance parameters (the fit's parameter space). */
#define STY_LAPSE_MAX 0.1
#define STY_OBSERVER_SD_MAX 3.0
#define STY_SLOPE_MIN 0.1
#define STY_SLOPE_MAX 20.0

/* One rated trial of a threshold fit: participant (any id), T > 0, and y = 1 (reference preferred), 0.5 (same), 0. */
typedef struct sty_tobs {
	int64_t participant;
	double T;
	double y;
} sty_tobs;

/* A threshold fit. t_jnd = 2^theta when theta lies in the rendered range [T_min, T_max]; inf when the fitted
 * p_ref of the median observer stays below 0.75 up to T_max (theta > log2 T_max), 0 when it is above 0.75 already at
 * T_min. An interval end the profile does not reach within 3 octaves beyond the rendered range is open: t_jnd_hi =
 * inf, t_jnd_lo = 0; an estimate of inf (0) opens that end too, so the interval always contains the estimate. */
typedef struct sty_tfit {
	size_t n;                        /* trials */
	size_t levels;                   /* distinct T */
	size_t participants;
	double t_min, t_max;             /* the rendered range */
	double t_jnd, t_jnd_lo, t_jnd_hi;
	double theta;                    /* log2 t_jnd before the range rule (finite: the search is bounded) */
	double theta_lo, theta_hi;       /* log2 of the interval before the range rule (the search bounds when open) */
	double slope, lapse, observer_sd; /* the maximum-likelihood nuisance parameters */
	double loglik;                   /* the maximised marginal log-likelihood */
} sty_tfit;

/* The model's p_ref at x = log2 T for an observer with threshold theta (shift included). */
double sty_psychometric(double x, double theta, double slope, double lapse);

/* Fits the model to n trials (at least two distinct T; TL_ERR_ARG otherwise, or for T <= 0 or y not 0, 0.5, 1). */
int sty_threshold_fit(const sty_tobs *o, size_t n, sty_tfit *fit, char *err, size_t err_size);

/* ------------------------------------------------------------------ adaptive choice of T (QUEST+) */

/* The pooled posterior over (theta, slope) of one method x scene x camera path, on a grid: theta from log2 T_min - 1
 * to log2 T_max + 1 in steps of 0.05, slope in {0.5, 1, 1.5, 2, 3, 4.5}; lapse fixed at 0.02, observers pooled (the
 * fit above then models them). Uniform prior unless a prior centre is given (sty_adapt_prior). */
typedef struct sty_adapt sty_adapt;

/* A posterior for the rendered levels T[0..nlevels-1] (> 0, any order). NULL when out of memory or no level. */
sty_adapt *sty_adapt_new(const double *T, size_t nlevels);
/* A normal prior on theta (log2 units), e.g. a model's prediction (issue 28 "--prior"). */
void sty_adapt_prior(sty_adapt *a, double theta_mean, double theta_sd);
/* Bayes update with one answer y in {0, 0.5, 1} at level index `level`. */
void sty_adapt_update(sty_adapt *a, size_t level, double y);
/* The level minimising the expected entropy of theta's marginal posterior after one more answer (QUEST+); ties go to
 * the lower level. `entropy` (may be NULL) receives each level's expected entropy. */
size_t sty_adapt_choose(const sty_adapt *a, double *entropy);
/* Posterior mean of theta (log2 units). */
double sty_adapt_theta_mean(const sty_adapt *a);
void sty_adapt_free(sty_adapt **a);

/* ------------------------------------------------------------------ simulated studies */

typedef struct sty_sim_desc {
	bool adaptive;             /* else the full design: every participant rates every level trials/levels times */
	uint32_t participants;
	uint32_t trials;           /* test trials per participant (full: a multiple of the number of levels) */
	const double *T;           /* the rendered levels */
	size_t nlevels;
	double t_jnd;              /* the median observer's threshold */
	double observer_sd;        /* SD of the observers' log2 thresholds */
	double slope, lapse;       /* the psychometric function (sty_psychometric) */
	double ties;               /* share of "same" answers where p_ref = 1/2 (fewer as it grows, p_ref kept) */
	uint32_t studies;
	uint64_t seed;
	const char *out;           /* folder for simulation.csv (NULL: none) */
	bool quiet;                /* no progress on stderr */
	unsigned jobs;             /* threads (0: one per online CPU); the output does not depend on it */
} sty_sim_desc;

typedef struct sty_sim_summary {
	uint32_t studies;
	uint32_t trials_total;         /* test trials of one study (all participants) */
	double rmse_log2;              /* RMSE of theta (log2 t_jnd before the range rule) against the truth */
	double bias_log2;              /* mean of theta - truth */
	double coverage;               /* share of studies whose interval holds the true t_jnd */
	double mean_width_log2;        /* mean interval width (log2 units; open ends at the search bounds) */
	uint32_t infinite;             /* studies whose t_jnd was written inf or 0 */
} sty_sim_summary;

/* Runs d->studies seeded studies (study k uses seed d->seed + k): simulated observers answer on the five-point scale
 * (ties as d->ties says), trials chosen as the design does (full: the shuffled plan; adaptive: sty_adapt_choose on
 * the answers so far, pooled over participants who take turns trial by trial), each study fitted with
 * sty_threshold_fit. Writes d->out/simulation.csv (study,design,trials,t_jnd_true,t_jnd,t_jnd_lo,t_jnd_hi,...).
 * TL_ERR_ARG for a bad description. */
int sty_simulate(const sty_sim_desc *d, sty_sim_summary *sum, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
