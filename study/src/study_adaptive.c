/* study_adaptive.c — the adaptive choice of T (study_threshold.h sty_adapt; issue 28 "Adaptive design"): QUEST+
 * (Watson 2017, J. Vision 17(3):10): a posterior on a grid of psychometric parameters, updated by Bayes' rule after
 * every answer, and the next stimulus the one that minimises the expected entropy of the posterior after its answer.
 * Here the stimulus is one of the rendered levels of T, the posterior is over (theta, slope) of the psychometric
 * function of study_threshold.c with the lapse fixed at 0.02, the entropy is that of theta's marginal (the threshold
 * is what the study asks for; slope is a nuisance, as in QUEST+'s "parameter of interest"), and answers of all
 * participants of one method x scene x camera path are pooled. A "same" answer counts half (likelihood
 * sqrt(psi (1 - psi)), as the fit counts it); for the expected entropy an answer is a preference or not. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/study_threshold.h"

#define STEP 0.05
#define LAPSE 0.02
static const double SLOPES[] = {0.5, 1, 1.5, 2, 3, 4.5};
#define NSLOPE (sizeof SLOPES / sizeof *SLOPES)

struct sty_adapt {
	size_t nl, nt;       /* levels, theta grid points */
	double *x;           /* log2 T per level */
	double *theta;       /* nt */
	double *psi;         /* (nt x NSLOPE) x nl */
	double *logpost;     /* nt x NSLOPE */
};

sty_adapt *sty_adapt_new(const double *T, size_t nlevels)
{
	if (!nlevels)
		return NULL;
	sty_adapt *a = calloc(1, sizeof *a);
	if (!a)
		return NULL;
	double xmin = INFINITY, xmax = -INFINITY;
	for (size_t l = 0; l < nlevels; l++)
		xmin = fmin(xmin, log2(T[l])), xmax = fmax(xmax, log2(T[l]));
	a->nl = nlevels;
	a->nt = (size_t)lround((xmax - xmin + 2) / STEP) + 1;
	a->x = malloc(nlevels * sizeof *a->x);
	a->theta = malloc(a->nt * sizeof *a->theta);
	a->psi = malloc(a->nt * NSLOPE * nlevels * sizeof *a->psi);
	a->logpost = calloc(a->nt * NSLOPE, sizeof *a->logpost);
	if (!a->x || !a->theta || !a->psi || !a->logpost) {
		sty_adapt_free(&a);
		return NULL;
	}
	for (size_t l = 0; l < nlevels; l++)
		a->x[l] = log2(T[l]);
	for (size_t t = 0; t < a->nt; t++) {
		a->theta[t] = xmin - 1 + STEP * (double)t;
		for (size_t s = 0; s < NSLOPE; s++)
			for (size_t l = 0; l < nlevels; l++)
				a->psi[(t * NSLOPE + s) * nlevels + l] = sty_psychometric(a->x[l], a->theta[t], SLOPES[s], LAPSE);
	}
	return a;
}

void sty_adapt_prior(sty_adapt *a, double mean, double sd)
{
	for (size_t t = 0; t < a->nt; t++)
		for (size_t s = 0; s < NSLOPE; s++) {
			double z = (a->theta[t] - mean) / sd;
			a->logpost[t * NSLOPE + s] += -0.5 * z * z;
		}
}

void sty_adapt_update(sty_adapt *a, size_t level, double y)
{
	if (level >= a->nl)
		return;
	double mx = -INFINITY;
	for (size_t g = 0; g < a->nt * NSLOPE; g++) {
		double p = a->psi[g * a->nl + level];
		a->logpost[g] += y * log(p) + (1 - y) * log1p(-p);
		mx = fmax(mx, a->logpost[g]);
	}
	for (size_t g = 0; g < a->nt * NSLOPE; g++) /* keep the maximum at 0 */
		a->logpost[g] -= mx;
}

/* Entropy (nats) of theta's marginal of the weights w (nt x NSLOPE, any scale). */
static double theta_entropy(const sty_adapt *a, const double *w)
{
	double total = 0, h = 0;
	for (size_t t = 0; t < a->nt; t++) {
		double m = 0;
		for (size_t s = 0; s < NSLOPE; s++)
			m += w[t * NSLOPE + s];
		total += m;
		h -= m > 0 ? m * log(m) : 0;
	}
	return total > 0 ? h / total + log(total) : 0;
}

size_t sty_adapt_choose(const sty_adapt *a, double *entropy)
{
	size_t ng = a->nt * NSLOPE, best = 0;
	double *post = malloc(ng * sizeof *post), *w = malloc(ng * sizeof *w), best_h = INFINITY;
	if (!post || !w) {
		free(post);
		free(w);
		return 0;
	}
	double z = 0;
	for (size_t g = 0; g < ng; g++)
		z += post[g] = exp(a->logpost[g]);
	for (size_t g = 0; g < ng; g++)
		post[g] /= z;
	for (size_t l = 0; l < a->nl; l++) {
		double h = 0;
		for (int r = 0; r < 2; r++) { /* r = 1: the reference is preferred */
			double pr = 0;
			for (size_t g = 0; g < ng; g++) {
				double p = a->psi[g * a->nl + l];
				w[g] = post[g] * (r ? p : 1 - p);
				pr += w[g];
			}
			h += pr > 0 ? pr * theta_entropy(a, w) : 0;
		}
		if (entropy)
			entropy[l] = h;
		if (h < best_h - 1e-12)
			best_h = h, best = l;
	}
	free(post);
	free(w);
	return best;
}

double sty_adapt_theta_mean(const sty_adapt *a)
{
	double z = 0, m = 0;
	for (size_t t = 0; t < a->nt; t++)
		for (size_t s = 0; s < NSLOPE; s++) {
			double p = exp(a->logpost[t * NSLOPE + s]);
			z += p;
			m += p * a->theta[t];
		}
	return m / z;
}

void sty_adapt_free(sty_adapt **pa)
{
	if (!pa || !*pa)
		return;
	sty_adapt *a = *pa;
	free(a->x);
	free(a->theta);
	free(a->psi);
	free(a->logpost);
	free(a);
	*pa = NULL;
}
