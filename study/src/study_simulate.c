/* study_simulate.c — seeded simulated studies (study_threshold.h sty_simulate; issue 28 "Simulator"): observers with a
 * known psychometric function answer on the five-point scale, trials are chosen by the full design or by the adaptive
 * choice (sty_adapt, the code `study serve` uses for --adaptive studies), every study is fitted by
 * sty_threshold_fit (the code `study tally` uses for thresholds.csv), and the fits are compared with the truth:
 * RMSE and bias of log2 t_jnd, coverage of the 95% interval.
 *
 * Observers: participant i has log2 threshold log2 t_jnd + u_i, u_i ~ N(0, observer_sd^2); at level T they prefer the
 * reference with p = sty_psychometric(log2 T, log2 t_jnd + u_i, slope, lapse). Ties: P(same) = ties * (1 - |2p - 1|),
 * the rest split so that P(ref) + P(same)/2 = p (the tally's p_ref is unchanged); a preference is "much better" with
 * probability |2p - 1|. Participants come one after another (a lab study); in the adaptive design each trial's T is
 * chosen from the answers of everyone so far.
 *
 * Studies are independent (study k is seeded with seed + k), so they run on d->jobs threads, each taking the next
 * study number; the rows and the summary are written in study order afterwards: the output does not depend on the
 * number of threads. */
#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "taslab/study.h"
#include "taslab/study_threshold.h"
#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"

/* One five-point rating (+2 = reference much better) of an observer whose p_ref is p. */
static int rate(gsl_rng *r, double p, double ties)
{
	double tie = ties * (1 - fabs(2 * p - 1)), u = gsl_rng_uniform(r);
	int sign = u < p - tie / 2 ? 1 : u < p + tie / 2 ? 0 : -1;
	if (!sign)
		return 0;
	return sign * (gsl_rng_uniform(r) < fabs(2 * p - 1) ? 2 : 1);
}

/* y of a rating as the tally counts it: preference for the reference 1, same 0.5, the other clip 0. */
static double y_of(int rating) { return rating > 0 ? 1 : rating == 0 ? 0.5 : 0; }

/* One study: the trials into o (participants x trials), then the fit. */
static int one_study(const sty_sim_desc *d, uint64_t seed, sty_tobs *o, sty_tfit *fit, char *err, size_t err_size)
{
	gsl_rng *r = gsl_rng_alloc(gsl_rng_mt19937);
	sty_adapt *a = d->adaptive ? sty_adapt_new(d->T, d->nlevels) : NULL;
	size_t *plan = malloc(d->trials * sizeof *plan);
	int rc = TL_OK;
	if (!r || !plan || (d->adaptive && !a)) {
		rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		goto done;
	}
	gsl_rng_set(r, (unsigned long)(seed * 2654435761ull + 12345));
	double theta = log2(d->t_jnd);
	size_t n = 0;
	for (uint32_t i = 0; i < d->participants; i++) {
		double ti = theta + (d->observer_sd > 0 ? gsl_ran_gaussian(r, d->observer_sd) : 0);
		if (!d->adaptive) {
			for (uint32_t k = 0; k < d->trials; k++)
				plan[k] = k % d->nlevels;
			gsl_ran_shuffle(r, plan, d->trials, sizeof *plan);
		}
		for (uint32_t k = 0; k < d->trials; k++) {
			size_t l = d->adaptive ? sty_adapt_choose(a, NULL) : plan[k];
			double p = sty_psychometric(log2(d->T[l]), ti, d->slope, d->lapse);
			double y = y_of(rate(r, p, d->ties));
			if (a)
				sty_adapt_update(a, l, y);
			o[n++] = (sty_tobs){.participant = i, .T = d->T[l], .y = y};
		}
	}
	rc = sty_threshold_fit(o, n, fit, err, err_size);
done:
	gsl_rng_free(r);
	sty_adapt_free(&a);
	free(plan);
	return rc;
}

/* The studies shared by the threads: each takes the next study number and fits it into fits[k]. */
typedef struct sim_work {
	const sty_sim_desc *d;
	sty_tfit *fits;
	atomic_uint next, done;
	atomic_int failed;      /* a study failed (its code in rc, its message in err: the first only) */
	int rc;
	pthread_mutex_t lock;   /* err and the progress line */
	char err[512];
} sim_work;

static void *sim_worker(void *arg)
{
	sim_work *w = arg;
	const sty_sim_desc *d = w->d;
	sty_tobs *o = malloc((size_t)d->participants * d->trials * sizeof *o);
	char err[512];
	for (;;) {
		unsigned k = atomic_fetch_add(&w->next, 1);
		if (k >= d->studies || atomic_load(&w->failed))
			break;
		int rc = o ? one_study(d, d->seed + k, o, &w->fits[k], err, sizeof err)
			   : tl_error(err, sizeof err, TL_ERR_NOMEM, "out of memory");
		pthread_mutex_lock(&w->lock);
		if (rc && !atomic_exchange(&w->failed, 1))
			w->rc = rc, snprintf(w->err, sizeof w->err, "%s", err);
		unsigned n = atomic_fetch_add(&w->done, 1) + 1;
		if (!rc && !d->quiet && d->studies >= 20 && n % (d->studies / 10) == 0)
			fprintf(stderr, "taslab study simulate: %u of %u studies\n", n, d->studies);
		pthread_mutex_unlock(&w->lock);
		if (rc)
			break;
	}
	free(o);
	return NULL;
}

static void csv_num(FILE *f, double v)
{
	if (isnan(v))
		return;
	fprintf(f, "%.6g", v); /* inf as "inf", as conditions.csv and thresholds.csv write it */
}

int sty_simulate(const sty_sim_desc *d, sty_sim_summary *sum, char *err, size_t err_size)
{
	memset(sum, 0, sizeof *sum);
	if (d->nlevels < 2 || !d->T)
		return tl_error(err, err_size, TL_ERR_ARG, "--t-levels needs at least two levels of T");
	for (size_t l = 0; l < d->nlevels; l++) {
		if (!(d->T[l] > 0) || !isfinite(d->T[l]))
			return tl_error(err, err_size, TL_ERR_ARG, "--t-levels: %g is not a T > 0", d->T[l]);
		for (size_t k = 0; k < l; k++)
			if (d->T[k] == d->T[l])
				return tl_error(err, err_size, TL_ERR_ARG, "--t-levels: %g is given twice", d->T[l]);
	}
	if (d->participants < 1 || d->trials < 1 || d->studies < 1)
		return tl_error(err, err_size, TL_ERR_ARG, "--participants, --trials and --studies must be at least 1");
	if (d->seed > STY_SEED_MAX - (d->studies - 1)) /* study k is seeded with seed + k */
		return tl_error(err, err_size, TL_ERR_ARG,
				"--seed %llu with %u --studies: the last study's seed would pass %u (GSL's mt19937 keeps 32 bits "
				"of a seed); use a smaller --seed", (unsigned long long)d->seed, d->studies, STY_SEED_MAX);
	if (!d->adaptive && d->trials % d->nlevels)
		return tl_error(err, err_size, TL_ERR_ARG, "--design full: --trials %u is not a multiple of the %zu levels (every "
				"participant rates every level equally often)", d->trials, d->nlevels);
	if (!(d->t_jnd > 0) || !isfinite(d->t_jnd))
		return tl_error(err, err_size, TL_ERR_ARG, "--t-jnd must be a T > 0");
	if (!(d->observer_sd >= 0 && d->observer_sd <= STY_OBSERVER_SD_MAX))
		return tl_error(err, err_size, TL_ERR_ARG, "--observer-sd must be 0..%g (log2 units)", STY_OBSERVER_SD_MAX);
	if (!(d->slope >= STY_SLOPE_MIN && d->slope <= STY_SLOPE_MAX))
		return tl_error(err, err_size, TL_ERR_ARG, "--slope must be %g..%g (per log2 unit)", STY_SLOPE_MIN, STY_SLOPE_MAX);
	if (!(d->lapse >= 0 && d->lapse <= STY_LAPSE_MAX))
		return tl_error(err, err_size, TL_ERR_ARG, "--lapse must be 0..%g", STY_LAPSE_MAX);
	if (!(d->ties >= 0 && d->ties <= 1))
		return tl_error(err, err_size, TL_ERR_ARG, "--ties must be 0..1");
	if ((uint64_t)d->participants * d->trials > 10000000u)
		return tl_error(err, err_size, TL_ERR_ARG, "--participants x --trials above 10,000,000 trials per study");
	tl_atomic out = {0};
	int rc = TL_OK;
	if (d->out && ((rc = tl_mkdirs(d->out, err, err_size)))) /* the folder first: no long run that cannot write */
		return rc;
	if (d->out) {
		char path[TL_PATH_MAX + 32];
		snprintf(path, sizeof path, "%s/simulation.csv", d->out);
		if ((rc = tl_atomic_open(&out, path, err, err_size)))
			return rc;
		fprintf(out.f, "study,design,trials,t_jnd_true,t_jnd,t_jnd_lo,t_jnd_hi,log2_t_jnd,slope,lapse,observer_sd\n");
	}
	sim_work w = {.d = d, .fits = calloc(d->studies, sizeof *w.fits)};
	if (!w.fits || pthread_mutex_init(&w.lock, NULL)) {
		free(w.fits);
		tl_atomic_abort(&out);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	long cpus = sysconf(_SC_NPROCESSORS_ONLN);
	unsigned jobs = d->jobs ? d->jobs : cpus > 0 ? (unsigned)cpus : 1;
	jobs = jobs > d->studies ? d->studies : jobs > 256 ? 256 : jobs;
	pthread_t th[256];
	unsigned started = 0;
	for (unsigned j = 1; j < jobs; j++) /* this thread is the first worker; fewer threads if the system says no */
		if (!pthread_create(&th[started], NULL, sim_worker, &w))
			started++;
	sim_worker(&w);
	for (unsigned j = 0; j < started; j++)
		pthread_join(th[j], NULL);
	pthread_mutex_destroy(&w.lock);
	if (atomic_load(&w.failed))
		rc = tl_error(err, err_size, w.rc, "%s", w.err);
	double truth = log2(d->t_jnd), se = 0, bias = 0, width = 0;
	uint32_t covered = 0;
	for (uint32_t k = 0; k < d->studies && !rc; k++) {
		const sty_tfit f = w.fits[k];
		se += (f.theta - truth) * (f.theta - truth);
		bias += f.theta - truth;
		width += f.theta_hi - f.theta_lo;
		covered += f.t_jnd_lo <= d->t_jnd && d->t_jnd <= f.t_jnd_hi;
		sum->infinite += f.t_jnd == 0 || isinf(f.t_jnd);
		if (out.f) {
			fprintf(out.f, "%u,%s,%u,%.6g,", k, d->adaptive ? "adaptive" : "full", d->participants * d->trials, d->t_jnd);
			csv_num(out.f, f.t_jnd), fputc(',', out.f);
			csv_num(out.f, f.t_jnd_lo), fputc(',', out.f);
			csv_num(out.f, f.t_jnd_hi);
			fprintf(out.f, ",%.6f,%.6f,%.6f,%.6f\n", f.theta, f.slope, f.lapse, f.observer_sd);
		}
	}
	free(w.fits);
	if (!rc && out.f)
		rc = tl_atomic_commit(&out, err, err_size);
	tl_atomic_abort(&out);
	if (rc)
		return rc;
	sum->studies = d->studies;
	sum->trials_total = d->participants * d->trials;
	sum->rmse_log2 = sqrt(se / d->studies);
	sum->bias_log2 = bias / d->studies;
	sum->coverage = (double)covered / d->studies;
	sum->mean_width_log2 = width / d->studies;
	return TL_OK;
}
