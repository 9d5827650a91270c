/* study_threshold.c — the psychometric fit of the JND threshold in log T (study_threshold.h; issue 28, DESIGN
 * section 7 "Thresholds"; the TAS paper's Fig. 3: p_ref against T, 1 JND at p_ref = 0.75).
 *
 * Model (study_threshold.h): a 2AFC-style psychometric function with guess rate 1/2 and a lapse rate (Wichmann &
 * Hill 2001), a cumulative normal in log2 T, and random observer effects on the threshold (a GLMM; the observer
 * variability psignifit 4 models with a beta-binomial term, Schuett et al. 2016, here as a per-participant shift so
 * that a participant's trials at different T are correlated as they are in a within-subject study). The marginal
 * likelihood integrates each participant's shift by Gauss-Hermite quadrature; data are aggregated per participant
 * and level first (sum of y and count), so a likelihood costs participants x levels x nodes evaluations.
 * Maximisation: GSL's Nelder-Mead simplex on (theta, log slope, logit lapse, logit observer SD), restarted once;
 * the interval: profile likelihood of theta, each point maximised over the three nuisance parameters. */
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_integration.h>
#include <gsl/gsl_multimin.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/study_threshold.h"
#include "taslab/tl_error.h"

#define NODES 24          /* Gauss-Hermite nodes for the observer shift */
#define CHI2_95 3.841458820694124 /* chi-square(1) 0.95 quantile */
#define SEARCH_OCTAVES 3.0 /* theta is searched up to 3 octaves beyond the rendered range */
#define MAX_LEVELS 64     /* distinct T of one fit (T is an integer 1..255 in practice; the fit refuses more) */

static double Phi(double z) { return 0.5 * erfc(-z * M_SQRT1_2); }

double sty_psychometric(double x, double theta, double slope, double lapse)
{
	double z0 = gsl_cdf_ugaussian_Pinv(0.25 / (0.5 - lapse));
	return 0.5 + (0.5 - lapse) * Phi(slope * (x - theta) + z0);
}

/* The data of one fit: per participant (row) and level (column) the number of trials and the sum of y. */
typedef struct model {
	size_t np, nl;
	double *x;         /* log2 T of the levels */
	double *n, *k;     /* np x nl */
	double node[NODES], log_weight[NODES]; /* standard normal quadrature (weights sum to 1), their logs */
	double xmin, xmax;
	double theta_fixed; /* the profile's theta (NAN: free) */
} model;

/* Nuisance parameters from the unconstrained vector. */
static double slope_of(double b) { return exp(fmin(fmax(b, log(STY_SLOPE_MIN)), log(STY_SLOPE_MAX))); }
static double lapse_of(double a) { return STY_LAPSE_MAX / (1 + exp(-a)); }
static double sd_of(double c) { return STY_OBSERVER_SD_MAX / (1 + exp(-c)); }

/* The marginal log-likelihood at (theta, slope, lapse, sd). p depends on the level and the quadrature node only, so
 * log p and log(1 - p) are tabulated once per call and every participant sums them with their counts. */
static double loglik(const model *m, double theta, double slope, double lapse, double sd)
{
	double z0 = gsl_cdf_ugaussian_Pinv(0.25 / (0.5 - lapse)), ll = 0;
	double lp1[NODES * MAX_LEVELS], lp0[NODES * MAX_LEVELS];
	for (int q = 0; q < NODES; q++)
		for (size_t l = 0; l < m->nl; l++) {
			double p = 0.5 + (0.5 - lapse) * Phi(slope * (m->x[l] - theta - sd * m->node[q]) + z0);
			p = fmin(fmax(p, 1e-12), 1 - 1e-12);
			lp1[q * m->nl + l] = log(p);
			lp0[q * m->nl + l] = log1p(-p);
		}
	for (size_t i = 0; i < m->np; i++) {
		double lp[NODES], mx = -INFINITY;
		const double *n = m->n + i * m->nl, *k = m->k + i * m->nl;
		for (int q = 0; q < NODES; q++) {
			double s = m->log_weight[q];
			for (size_t l = 0; l < m->nl; l++)
				s += k[l] * lp1[q * m->nl + l] + (n[l] - k[l]) * lp0[q * m->nl + l];
			lp[q] = s;
			mx = fmax(mx, s);
		}
		double sum = 0;
		for (int q = 0; q < NODES; q++)
			sum += exp(lp[q] - mx);
		ll += mx + log(sum);
	}
	return ll;
}

/* Negative log-likelihood for the simplex: v = (theta, b, a, c), or (b, a, c) with theta fixed. Outside the search
 * range theta is held at the bound and penalised, so the simplex stays inside. */
static double negll(const gsl_vector *v, void *params)
{
	const model *m = params;
	size_t o = isnan(m->theta_fixed) ? 1 : 0;
	double theta = o ? gsl_vector_get(v, 0) : m->theta_fixed, pen = 0;
	double lo = m->xmin - SEARCH_OCTAVES, hi = m->xmax + SEARCH_OCTAVES;
	if (theta < lo || theta > hi) {
		double t = fmin(fmax(theta, lo), hi);
		pen = 1e3 * (theta - t) * (theta - t);
		theta = t;
	}
	double b = gsl_vector_get(v, o), a = gsl_vector_get(v, o + 1), c = gsl_vector_get(v, o + 2);
	/* slope_of clamps b to the slope's bounds; beyond them the flat likelihood is tilted back (lapse and SD are bounded
	 * by their logistic maps; the simplex may walk far out on those, where the likelihood is flat) */
	double bb = fmin(fmax(b, log(STY_SLOPE_MIN)), log(STY_SLOPE_MAX));
	pen += (b - bb) * (b - bb);
	return -loglik(m, theta, slope_of(b), lapse_of(a), sd_of(c)) + pen;
}

/* Minimises from `start` (size dim); returns the minimum, leaves the minimiser in `start`. */
static double minimise(model *m, double *start, size_t dim, const double *steps, int restarts)
{
	const gsl_multimin_fminimizer_type *T = gsl_multimin_fminimizer_nmsimplex2;
	gsl_multimin_fminimizer *s = gsl_multimin_fminimizer_alloc(T, dim);
	gsl_vector *x = gsl_vector_alloc(dim), *ss = gsl_vector_alloc(dim);
	double best = INFINITY;
	if (!s || !x || !ss)
		goto done;
	for (int r = 0; r <= restarts; r++) {
		for (size_t i = 0; i < dim; i++) {
			gsl_vector_set(x, i, start[i]);
			gsl_vector_set(ss, i, steps[i] * (r ? 0.5 : 1));
		}
		gsl_multimin_function f = {.n = dim, .f = negll, .params = m};
		gsl_multimin_fminimizer_set(s, &f, x, ss);
		for (int it = 0; it < 2000; it++) {
			if (gsl_multimin_fminimizer_iterate(s))
				break;
			if (gsl_multimin_test_size(gsl_multimin_fminimizer_size(s), 1e-4) == GSL_SUCCESS)
				break;
		}
		best = s->fval;
		for (size_t i = 0; i < dim; i++)
			start[i] = gsl_vector_get(s->x, i);
	}
done:
	gsl_vector_free(x);
	gsl_vector_free(ss);
	gsl_multimin_fminimizer_free(s);
	return best;
}

/* The profile deviance at theta: 2 (max loglik - max over nuisance at theta); `nuis` is the warm start, updated. */
static double profile(model *m, double theta, double *nuis, double best)
{
	static const double steps[3] = {0.4, 1.0, 1.0};
	/* two starts: the neighbour's optimum (warm) and the fit's usual start (slope 1.5, lapse 0.02, SD 0.3); the
	 * likelihood in the nuisance parameters can have two modes (a steep curve with a lapse or a shallow one) */
	double fresh[3] = {log(1.5), log(0.02 / (STY_LAPSE_MAX - 0.02)), log(0.3 / (STY_OBSERVER_SD_MAX - 0.3))};
	m->theta_fixed = theta;
	double v = minimise(m, nuis, 3, steps, 0), w = minimise(m, fresh, 3, steps, 0);
	m->theta_fixed = NAN;
	if (w < v) {
		memcpy(nuis, fresh, sizeof fresh);
		v = w;
	}
	return 2 * (v - best);
}

/* One end of the profile interval: walks from theta_hat in direction dir (+1/-1) until the deviance passes CHI2_95,
 * then bisects. Returns the end, or the search bound when the deviance never gets there (*open = true). */
static double interval_end(model *m, double theta_hat, const double *nuis_hat, double best, int dir, bool *open)
{
	double bound = dir > 0 ? m->xmax + SEARCH_OCTAVES : m->xmin - SEARCH_OCTAVES;
	double nuis[3] = {nuis_hat[0], nuis_hat[1], nuis_hat[2]}, prev = theta_hat, step = 0.25;
	*open = false;
	for (;;) {
		double t = prev + dir * step;
		if (dir * (t - bound) > 0)
			t = bound;
		double save[3] = {nuis[0], nuis[1], nuis[2]};
		double d = profile(m, t, nuis, best);
		if (d >= CHI2_95) {
			double a = prev, b = t; /* deviance below at a, above at b */
			memcpy(nuis, save, sizeof save);
			for (int it = 0; it < 6; it++) {
				double mid = 0.5 * (a + b), nm[3] = {nuis[0], nuis[1], nuis[2]};
				if (profile(m, mid, nm, best) >= CHI2_95)
					b = mid;
				else
					a = mid, memcpy(nuis, nm, sizeof nm);
			}
			return 0.5 * (a + b);
		}
		if (t == bound) {
			*open = true;
			return bound;
		}
		prev = t;
		step = fmin(step * 1.5, 1.0);
	}
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static int cmp_pid(const void *a, const void *b)
{
	int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
	return (x > y) - (x < y);
}

/* Index of v in the sorted array a[n] (present by construction). */
static size_t find_double(const double *a, size_t n, double v)
{
	size_t lo = 0, hi = n;
	while (hi - lo > 1) {
		size_t mid = (lo + hi) / 2;
		if (a[mid] <= v)
			lo = mid;
		else
			hi = mid;
	}
	return lo;
}

static size_t find_pid(const int64_t *a, size_t n, int64_t v)
{
	size_t lo = 0, hi = n;
	while (hi - lo > 1) {
		size_t mid = (lo + hi) / 2;
		if (a[mid] <= v)
			lo = mid;
		else
			hi = mid;
	}
	return lo;
}

/* Distinct sorted values in place; returns their number. */
static size_t uniq_double(double *a, size_t n)
{
	qsort(a, n, sizeof *a, cmp_double);
	size_t k = 0;
	for (size_t i = 0; i < n; i++)
		if (!k || a[i] != a[k - 1])
			a[k++] = a[i];
	return k;
}

static size_t uniq_pid(int64_t *a, size_t n)
{
	qsort(a, n, sizeof *a, cmp_pid);
	size_t k = 0;
	for (size_t i = 0; i < n; i++)
		if (!k || a[i] != a[k - 1])
			a[k++] = a[i];
	return k;
}

static bool quadrature(model *m)
{
	gsl_integration_fixed_workspace *w = gsl_integration_fixed_alloc(gsl_integration_fixed_hermite, NODES, 0, 0.5, 0, 0);
	if (!w)
		return false;
	const double *x = gsl_integration_fixed_nodes(w), *wt = gsl_integration_fixed_weights(w);
	double sum = 0;
	for (int q = 0; q < NODES; q++)
		sum += wt[q];
	for (int q = 0; q < NODES; q++) {
		m->node[q] = x[q];
		m->log_weight[q] = log(wt[q] / sum);
	}
	gsl_integration_fixed_free(w);
	return true;
}

int sty_threshold_fit(const sty_tobs *o, size_t n, sty_tfit *fit, char *err, size_t err_size)
{
	memset(fit, 0, sizeof *fit);
	for (size_t i = 0; i < n; i++)
		if (!(o[i].T > 0) || !isfinite(o[i].T) || !(o[i].y == 0 || o[i].y == 0.5 || o[i].y == 1))
			return tl_error(err, err_size, TL_ERR_ARG, "threshold fit: trial %zu has T %g and answer %g (need T > 0 "
					"and 0, 0.5 or 1)", i, o[i].T, o[i].y);
	model m = {.theta_fixed = NAN};
	double *lv = malloc((n ? n : 1) * sizeof *lv);
	int64_t *pids = malloc((n ? n : 1) * sizeof *pids);
	int rc = TL_OK;
	if (!lv || !pids) {
		rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		goto done;
	}
	for (size_t i = 0; i < n; i++)
		lv[i] = o[i].T, pids[i] = o[i].participant;
	m.nl = uniq_double(lv, n);
	m.np = uniq_pid(pids, n);
	if (m.nl > MAX_LEVELS) {
		rc = tl_error(err, err_size, TL_ERR_ARG, "threshold fit: %zu levels of T; at most %d", m.nl, MAX_LEVELS);
		goto done;
	}
	if (m.nl < 2) {
		rc = tl_error(err, err_size, TL_ERR_ARG, "threshold fit: %zu level(s) of T; a threshold needs at least two", m.nl);
		goto done;
	}
	m.x = malloc(m.nl * sizeof *m.x);
	m.n = calloc(m.np * m.nl, sizeof *m.n);
	m.k = calloc(m.np * m.nl, sizeof *m.k);
	if (!m.x || !m.n || !m.k || !quadrature(&m)) {
		rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		goto done;
	}
	for (size_t l = 0; l < m.nl; l++)
		m.x[l] = log2(lv[l]);
	for (size_t i = 0; i < n; i++) {
		size_t p = find_pid(pids, m.np, o[i].participant), l = find_double(lv, m.nl, o[i].T);
		m.n[p * m.nl + l] += 1;
		m.k[p * m.nl + l] += o[i].y;
	}
	m.xmin = m.x[0];
	m.xmax = m.x[m.nl - 1];
	/* Start: the best theta on a grid (slope 1.5, lapse 0.02, SD 0.3), then the simplex over all four. */
	double a0 = log(0.02 / (STY_LAPSE_MAX - 0.02)), c0 = log(0.3 / (STY_OBSERVER_SD_MAX - 0.3));
	double best_t = m.xmin, best_ll = -INFINITY;
	for (double t = m.xmin - SEARCH_OCTAVES; t <= m.xmax + SEARCH_OCTAVES + 1e-9; t += 0.25) {
		double ll = loglik(&m, t, 1.5, 0.02, 0.3);
		if (ll > best_ll)
			best_ll = ll, best_t = t;
	}
	double v[4] = {best_t, log(1.5), a0, c0};
	static const double steps[4] = {0.5, 0.4, 1.0, 1.0};
	double best = minimise(&m, v, 4, steps, 1);
	double theta = fmin(fmax(v[0], m.xmin - SEARCH_OCTAVES), m.xmax + SEARCH_OCTAVES);
	double nuis[3] = {v[1], v[2], v[3]};
	bool open_lo, open_hi;
	fit->theta_lo = interval_end(&m, theta, nuis, best, -1, &open_lo);
	fit->theta_hi = interval_end(&m, theta, nuis, best, +1, &open_hi);
	fit->n = n;
	fit->levels = m.nl;
	fit->participants = m.np;
	fit->t_min = lv[0];
	fit->t_max = lv[m.nl - 1];
	fit->theta = theta;
	fit->slope = slope_of(v[1]);
	fit->lapse = lapse_of(v[2]);
	fit->observer_sd = sd_of(v[3]);
	fit->loglik = -best;
	/* The range rule (study_threshold.h). */
	fit->t_jnd = theta > m.xmax ? INFINITY : theta < m.xmin ? 0 : exp2(theta);
	fit->t_jnd_lo = open_lo || fit->t_jnd == 0 ? 0 : exp2(fmin(fit->theta_lo, theta));
	fit->t_jnd_hi = open_hi || isinf(fit->t_jnd) ? INFINITY : exp2(fmax(fit->theta_hi, theta));
	if (fit->t_jnd > 0 && isfinite(fit->t_jnd)) { /* an estimate inside the range lies inside its interval */
		fit->t_jnd_lo = fmin(fit->t_jnd_lo, fit->t_jnd);
		fit->t_jnd_hi = fmax(fit->t_jnd_hi, fit->t_jnd);
	}
done:
	free(lv);
	free(pids);
	free(m.x);
	free(m.n);
	free(m.k);
	return rc;
}
