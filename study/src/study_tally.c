/* study_tally.c — the statistics of a study (paper sec. 3, Fig. 3 and its footnotes, sec. 7.2; DESIGN section 7).
 *
 * Per condition: Q = mean reference-relative rating with a 95% t interval over participants (each participant's
 * mean rating in that condition is one observation); p_ref = (n_ref + n_tie/2)/n over ratings with a Wilson
 * interval; JND from p_ref (metrics module). Rows per (method, T, period, scene, camera) and pooled (scene = camera =
 * all). A variant is method x T x period (DESIGN section 4: rrc/4 and rrc/8 are two), and every grouping below is
 * per variant; every CSV carries T and period in their own columns right after method.
 * Repeated-measures ANOVA per variant (method, T, period): factors Camera (motion class) x Scene, dependent variable each
 * participant's mean rating per cell, participants with every cell only; Greenhouse-Geisser epsilon from the
 * covariance of orthonormal contrast scores. Post hoc: paired t tests between levels, Bonferroni-adjusted.
 * Observer screening: a participant whose answers on catch trials (identical clips) are "much better" (|a| = 2)
 * on more than half of them is flagged and left out unless keep_flagged.
 * Thurstone Case V: conditions are only ever compared with their reference, so the maximum-likelihood Case V
 * scale with the reference fixed at 0 is closed-form, JOD = -Phi^-1(p_ref)/Phi^-1(0.75) (1 JOD = 75% preference);
 * its 95% interval comes from a bootstrap over participants. */
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_rng.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "study_internal.h"
#include "taslab/metrics.h"
#include "taslab/tl_fs.h"
#include "taslab/tl_json.h"

/* ------------------------------------------------------------------ repeated-measures ANOVA */

/* Orthonormal Helmert contrasts of k levels: k x (k-1), column j contrasts level j+1 with levels 0..j. */
static void helmert(size_t k, double *c)
{
	for (size_t j = 0; j + 1 < k; j++) {
		double norm = sqrt((double)((j + 1) * (j + 2)));
		for (size_t i = 0; i < k; i++)
			c[i * (k - 1) + j] = i <= j ? 1.0 / norm : i == j + 1 ? -(double)(j + 1) / norm : 0.0;
	}
}

/* One effect from the n x m matrix of contrast scores z (m = effect df). */
static void effect_from_scores(const double *z, size_t n, size_t m, sty_anova_effect *e)
{
	memset(e, 0, sizeof *e);
	e->df1 = (double)m;
	e->df2 = (double)((n - 1) * m);
	if (m == 0 || n < 2) {
		e->F = e->p = e->epsilon_gg = e->p_gg = NAN;
		return;
	}
	double *mean = calloc(m, sizeof *mean), *S = calloc(m * m, sizeof *S);
	for (size_t i = 0; i < n; i++)
		for (size_t j = 0; j < m; j++)
			mean[j] += z[i * m + j] / (double)n;
	double ss_eff = 0, ss_err = 0;
	for (size_t j = 0; j < m; j++)
		ss_eff += (double)n * mean[j] * mean[j];
	for (size_t i = 0; i < n; i++)
		for (size_t j = 0; j < m; j++) {
			double dj = z[i * m + j] - mean[j];
			ss_err += dj * dj;
			for (size_t k = 0; k < m; k++)
				S[j * m + k] += dj * (z[i * m + k] - mean[k]) / (double)(n - 1);
		}
	e->F = (ss_eff / e->df1) / (ss_err / e->df2);
	e->p = gsl_cdf_fdist_Q(e->F, e->df1, e->df2);
	/* Greenhouse-Geisser: epsilon = tr(S)^2 / (m tr(S S)), S the covariance of orthonormal contrast scores. */
	double tr = 0, tr2 = 0;
	for (size_t j = 0; j < m; j++) {
		tr += S[j * m + j];
		for (size_t k = 0; k < m; k++)
			tr2 += S[j * m + k] * S[k * m + j];
	}
	e->epsilon_gg = tr2 > 0 ? fmin(1.0, tr * tr / ((double)m * tr2)) : 1.0;
	e->p_gg = gsl_cdf_fdist_Q(e->F, e->epsilon_gg * e->df1, e->epsilon_gg * e->df2);
	free(mean);
	free(S);
}

int sty_rm_anova2(const double *y, size_t n, size_t a, size_t b, sty_anova_effect out[3])
{
	if (n < 2 || a < 1 || b < 1)
		return TL_ERR_ARG;
	size_t cells = a * b;
	double *ca = calloc(a * (a > 1 ? a - 1 : 1), sizeof *ca), *cb = calloc(b * (b > 1 ? b - 1 : 1), sizeof *cb);
	size_t ma = a - 1, mb = b - 1;
	double *M[3];
	size_t m[3] = {ma, mb, ma * mb};
	if (!ca || !cb)
		return TL_ERR_ARG;
	helmert(a, ca);
	helmert(b, cb);
	/* Cell contrast matrices: A = C_A (x) 1_b/sqrt(b), B = 1_a/sqrt(a) (x) C_B, AB = C_A (x) C_B. */
	for (int e = 0; e < 3; e++)
		M[e] = calloc(cells * (m[e] ? m[e] : 1), sizeof **M);
	for (size_t i = 0; i < a; i++)
		for (size_t j = 0; j < b; j++) {
			size_t cell = i * b + j;
			for (size_t p = 0; p < ma; p++)
				M[0][cell * ma + p] = ca[i * ma + p] / sqrt((double)b);
			for (size_t q = 0; q < mb; q++)
				M[1][cell * mb + q] = cb[j * mb + q] / sqrt((double)a);
			for (size_t p = 0; p < ma; p++)
				for (size_t q = 0; q < mb; q++)
					M[2][cell * ma * mb + p * mb + q] = ca[i * ma + p] * cb[j * mb + q];
		}
	for (int e = 0; e < 3; e++) {
		double *z = calloc(n * (m[e] ? m[e] : 1), sizeof *z);
		for (size_t s = 0; s < n; s++)
			for (size_t k = 0; k < m[e]; k++)
				for (size_t c = 0; c < cells; c++)
					z[s * m[e] + k] += y[s * cells + c] * M[e][c * m[e] + k];
		effect_from_scores(z, n, m[e], &out[e]);
		free(z);
		free(M[e]);
	}
	free(ca);
	free(cb);
	return TL_OK;
}

/* ------------------------------------------------------------------ data */

typedef struct obs {
	int64_t participant;
	int cond; /* index into conds */
	int rating;
} obs;

typedef struct condk {
	char method[32], scene[64], camera[64], motion[16];
	double T;        /* NAN: none */
	uint32_t period; /* 0: none */
} condk;

/* Same variant: method, T and period. */
static int same_variant(const condk *a, const condk *b)
{
	return !strcmp(a->method, b->method) && ((isnan(a->T) && isnan(b->T)) || a->T == b->T) && a->period == b->period;
}

/* Variant order of the outputs: method, then T, then period (none first). */
static int cmp_variant(const void *pa, const void *pb)
{
	const condk *a = pa, *b = pb;
	int c = strcmp(a->method, b->method);
	if (c)
		return c;
	if (isnan(a->T) != isnan(b->T))
		return isnan(a->T) ? -1 : 1;
	if (!isnan(a->T) && a->T != b->T)
		return a->T < b->T ? -1 : 1;
	return (a->period > b->period) - (a->period < b->period);
}

typedef struct data {
	obs *o;
	size_t n;
	condk *c;
	size_t nc;
	int64_t *flagged;
	size_t nflagged;
	int64_t max_pid;
} data;

static int find_cond(data *d, const condk *k)
{
	for (size_t i = 0; i < d->nc; i++)
		if (same_variant(&d->c[i], k) && !strcmp(d->c[i].scene, k->scene) && !strcmp(d->c[i].camera, k->camera))
			return (int)i;
	condk *nc = realloc(d->c, (d->nc + 1) * sizeof *nc);
	if (!nc)
		return -1;
	d->c = nc;
	d->c[d->nc] = *k;
	return (int)d->nc++;
}

static int is_flagged(const data *d, int64_t pid)
{
	for (size_t i = 0; i < d->nflagged; i++)
		if (d->flagged[i] == pid)
			return 1;
	return 0;
}

static int load(sty *s, const sty_tally_desc *td, data *d, FILE *observers, char *err, size_t err_size)
{
	memset(d, 0, sizeof *d);
	sqlite3_stmt *st;
	/* Screening from catch trials. */
	if (sqlite3_prepare_v2(s->db,
			       "SELECT p.id, p.label, count(a.answer), avg(abs(a.answer)), sum(abs(a.answer) = 2)"
			       " FROM participants p LEFT JOIN trials t ON t.participant = p.id AND t.kind = 'catch'"
			       " LEFT JOIN answers a ON a.participant = t.participant AND a.idx = t.idx GROUP BY p.id ORDER BY p.id",
			       -1, &st, NULL))
		return sty_db_fail(s, err, err_size, "tally");
	fprintf(observers, "participant,catch_n,catch_mean_abs_answer,catch_much_better,flagged\n");
	while (sqlite3_step(st) == SQLITE_ROW) {
		int64_t pid = sqlite3_column_int64(st, 0);
		int n = sqlite3_column_int(st, 2), strong = sqlite3_column_int(st, 4);
		int flag = n > 0 && 2 * strong > n;
		char label[160];
		fprintf(observers, "%s,%d,", sty_csv_cell((const char *)sqlite3_column_text(st, 1), label, sizeof label), n);
		if (n)
			fprintf(observers, "%.4f", sqlite3_column_double(st, 3));
		fprintf(observers, ",%d,%d\n", strong, flag);
		if (flag && !td->keep_flagged) {
			int64_t *nf = realloc(d->flagged, (d->nflagged + 1) * sizeof *nf);
			if (nf) {
				d->flagged = nf;
				d->flagged[d->nflagged++] = pid;
			}
		}
	}
	sqlite3_finalize(st);
	if (sqlite3_prepare_v2(s->db,
			       "SELECT a.participant, c.method, c.T, c.scene, c.camera, c.camera_motion, t.ref_first, a.answer, c.period"
			       " FROM answers a JOIN trials t ON t.participant = a.participant AND t.idx = a.idx"
			       " JOIN conditions c ON c.id = t.condition WHERE t.kind = 'test' ORDER BY a.participant, t.idx",
			       -1, &st, NULL))
		return sty_db_fail(s, err, err_size, "tally");
	while (sqlite3_step(st) == SQLITE_ROW) {
		int64_t pid = sqlite3_column_int64(st, 0);
		if (is_flagged(d, pid))
			continue;
		condk k;
		memset(&k, 0, sizeof k);
		snprintf(k.method, sizeof k.method, "%s", sqlite3_column_text(st, 1));
		k.T = sqlite3_column_type(st, 2) == SQLITE_NULL ? NAN : sqlite3_column_double(st, 2);
		snprintf(k.scene, sizeof k.scene, "%s", sqlite3_column_text(st, 3));
		snprintf(k.camera, sizeof k.camera, "%s", sqlite3_column_text(st, 4));
		snprintf(k.motion, sizeof k.motion, "%s", sqlite3_column_text(st, 5));
		k.period = sqlite3_column_type(st, 8) == SQLITE_NULL ? 0 : (uint32_t)sqlite3_column_int64(st, 8);
		int ci = find_cond(d, &k);
		obs *no = realloc(d->o, (d->n + 1) * sizeof *no);
		if (ci < 0 || !no) {
			sqlite3_finalize(st);
			snprintf(err, err_size, "out of memory");
			return TL_ERR_ARG;
		}
		d->o = no;
		int answer = sqlite3_column_int(st, 7);
		d->o[d->n++] = (obs){pid, ci, sqlite3_column_int(st, 6) ? -answer : answer};
		d->max_pid = pid > d->max_pid ? pid : d->max_pid;
	}
	sqlite3_finalize(st);
	if (d->n == 0) {
		snprintf(err, err_size, "%s: no answered test trials to tally%s", s->path,
			 d->nflagged ? " (all observers were flagged; --keep-flagged keeps them)" : "");
		return TL_ERR_ARG;
	}
	return TL_OK;
}

/* Selection of observations for a summary row. */
typedef struct sel {
	const condk *mt;        /* the variant: method, T and period */
	const char *scene, *camera, *motion; /* NULL: any */
} sel;

static int match(const data *d, const obs *o, const sel *s)
{
	const condk *c = &d->c[o->cond];
	return same_variant(c, s->mt) && (!s->scene || !strcmp(c->scene, s->scene)) &&
	       (!s->camera || !strcmp(c->camera, s->camera)) && (!s->motion || !strcmp(c->motion, s->motion));
}

/* Per-participant mean ratings of a selection; returns the number of participants (pm, has sized max_pid+1). */
static size_t participant_means(const data *d, const sel *s, double *pm, int *has, const int *use)
{
	double *sum = calloc((size_t)d->max_pid + 1, sizeof *sum);
	int *cnt = calloc((size_t)d->max_pid + 1, sizeof *cnt);
	size_t np = 0;
	for (size_t i = 0; i < d->n; i++)
		if ((!use || use[d->o[i].participant]) && match(d, &d->o[i], s)) {
			sum[d->o[i].participant] += d->o[i].rating * (use ? use[d->o[i].participant] : 1);
			cnt[d->o[i].participant] += use ? use[d->o[i].participant] : 1;
		}
	for (int64_t p = 0; p <= d->max_pid; p++) {
		has[p] = cnt[p] > 0;
		pm[p] = has[p] ? sum[p] / cnt[p] : NAN;
		np += has[p];
	}
	free(sum);
	free(cnt);
	return np;
}

typedef struct row_stats {
	size_t n, participants;
	double Q, Q_lo, Q_hi;
	mtr_jnd j;
} row_stats;

/* `use`: bootstrap multiplicity per participant (NULL: everyone once). */
static int row_compute(const data *d, const sel *s, const int *use, row_stats *r)
{
	memset(r, 0, sizeof *r);
	double n_ref = 0, n_tie = 0, n = 0;
	for (size_t i = 0; i < d->n; i++)
		if ((!use || use[d->o[i].participant]) && match(d, &d->o[i], s)) {
			double w = use ? use[d->o[i].participant] : 1;
			n += w;
			n_ref += d->o[i].rating > 0 ? w : 0;
			n_tie += d->o[i].rating == 0 ? w : 0;
		}
	if (n == 0)
		return -1;
	r->n = (size_t)n;
	double *pm = malloc(((size_t)d->max_pid + 1) * sizeof *pm);
	int *has = malloc(((size_t)d->max_pid + 1) * sizeof *has);
	size_t np = participant_means(d, s, pm, has, use);
	double mean = 0, var = 0;
	size_t k = 0;
	for (int64_t p = 0; p <= d->max_pid; p++)
		if (has[p]) {
			int w = use ? use[p] : 1;
			for (int t = 0; t < w; t++, k++) {
				double dlt = pm[p] - mean;
				mean += dlt / (double)(k + 1);
				var += dlt * (pm[p] - mean);
			}
		}
	r->participants = k;
	r->Q = mean;
	if (k > 1) {
		double se = sqrt(var / (double)(k - 1) / (double)k);
		double t = gsl_cdf_tdist_Pinv(0.975, (double)(k - 1));
		r->Q_lo = mean - t * se;
		r->Q_hi = mean + t * se;
	} else {
		r->Q_lo = r->Q_hi = NAN;
	}
	(void)np;
	mtr_jnd_from_counts(n_ref, n_tie, n, 0.95, &r->j);
	free(pm);
	free(has);
	return 0;
}

static void csv_num(FILE *f, double v, const char *fmt)
{
	if (isfinite(v))
		fprintf(f, fmt, v);
}

static void T_str(const condk *c, char *buf, size_t n)
{
	if (isnan(c->T))
		buf[0] = 0;
	else
		snprintf(buf, n, "%g", c->T);
}

static void period_str(const condk *c, char *buf, size_t n)
{
	if (!c->period)
		buf[0] = 0;
	else
		snprintf(buf, n, "%u", c->period);
}

static json_t *period_json(const condk *c) { return c->period ? json_integer(c->period) : json_null(); }

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

/* Distinct values of scene (field 0) or motion (field 1) among the conditions of one variant. */
static size_t levels(const data *d, const condk *mt, int field, char lv[][64], size_t max)
{
	size_t n = 0;
	for (size_t i = 0; i < d->nc; i++) {
		if (!same_variant(&d->c[i], mt))
			continue;
		const char *v = field ? d->c[i].motion : d->c[i].scene;
		int seen = 0;
		for (size_t k = 0; k < n; k++)
			seen |= !strcmp(lv[k], v);
		if (!seen && n < max)
			snprintf(lv[n++], 64, "%s", v);
	}
	char *ptr[32];
	for (size_t k = 0; k < n; k++)
		ptr[k] = lv[k];
	qsort(ptr, n, sizeof *ptr, cmp_str);
	char tmp[32][64];
	for (size_t k = 0; k < n; k++)
		snprintf(tmp[k], 64, "%s", ptr[k]);
	for (size_t k = 0; k < n; k++)
		snprintf(lv[k], 64, "%s", tmp[k]);
	if (field) { /* stationary before moving */
		for (size_t k = 0; k + 1 < n; k++)
			if (!strcmp(lv[k], "moving") && !strcmp(lv[k + 1], "stationary")) {
				snprintf(lv[k], 64, "stationary");
				snprintf(lv[k + 1], 64, "moving");
			}
	}
	return n;
}

static void paired_t(const double *x, const double *y, size_t n, double *t, double *df, double *p)
{
	double mean = 0, m2 = 0;
	for (size_t i = 0; i < n; i++) {
		double dlt = (x[i] - y[i]) - mean;
		mean += dlt / (double)(i + 1);
		m2 += dlt * ((x[i] - y[i]) - mean);
	}
	*df = (double)n - 1;
	double sd = n > 1 ? sqrt(m2 / (double)(n - 1)) : NAN;
	*t = sd > 0 ? mean / (sd / sqrt((double)n)) : (mean == 0 ? 0 : INFINITY * mean);
	*p = isfinite(*t) ? 2 * gsl_cdf_tdist_Q(fabs(*t), *df) : 0;
}

/* Every file a tally writes into its folder (fig3.png is gnuplot's, drawn from fig3.gp and fig3.csv). */
static const char *const TALLY_FILES[] = {"observers.csv", "conditions.csv", "anova.csv", "posthoc.csv", "jod.csv",
					  "tables.md", "fig3.csv", "conditions.json", "anova.json", "fig3.gp", "fig3.png"};
#define TALLY_SET 9 /* the first nine are written as one set (tl_atomic_commit_set) */

int sty_tally(sty *s, const sty_tally_desc *td, char *err, size_t err_size)
{
	char path[4200];
	data d;
	int rc = TL_ERR_ARG;
	/* Outputs over inputs: no file of the tally may be the study database or its journal (a --db kept in the --out
	 * folder under one of these names), checked before anything is written. */
	for (size_t k = 0; k < sizeof TALLY_FILES / sizeof *TALLY_FILES; k++) {
		snprintf(path, sizeof path, "%s/%s", td->out, TALLY_FILES[k]);
		if ((rc = sty_check_output(s, path, err, err_size)))
			return rc;
	}
	/* The files appear together or not at all: every one is written to its temporary file, and they are renamed
	 * into place only when all are complete (a full disk, a failed query: the folder keeps what it had; a folder
	 * made for this tally is removed again). */
	bool made_dir = !tl_is_dir(td->out);
	if ((rc = tl_mkdirs(td->out, err, err_size)))
		return rc;
	tl_fs_clean_temps(td->out);
	tl_atomic outs[TALLY_SET] = {0};
	snprintf(path, sizeof path, "%s/observers.csv", td->out);
	if ((rc = tl_atomic_open(&outs[0], path, err, err_size))) {
		if (made_dir)
			rmdir(td->out);
		return rc;
	}
	rc = load(s, td, &d, outs[0].f, err, err_size);
	if (rc) {
		tl_atomic_abort_set(outs, TALLY_SET);
		if (made_dir)
			rmdir(td->out);
		free(d.o), free(d.c), free(d.flagged);
		return rc;
	}
	/* Distinct variants (method, T, period), sorted by method, T and period. */
	condk *mts = NULL;
	size_t nmt = 0;
	for (size_t i = 0; i < d.nc; i++) {
		int seen = 0;
		for (size_t k = 0; k < nmt; k++)
			seen |= same_variant(&mts[k], &d.c[i]);
		if (!seen) {
			condk *nm = realloc(mts, (nmt + 1) * sizeof *nm);
			if (!nm) {
				rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
				goto done;
			}
			mts = nm;
			mts[nmt++] = d.c[i];
		}
	}
	if (nmt)
		qsort(mts, nmt, sizeof *mts, cmp_variant);
	FILE *fc = NULL, *fa = NULL, *fp = NULL, *fj = NULL, *fmd = NULL, *ff = NULL, *fcj = NULL, *faj = NULL;
	FILE **files[TALLY_SET] = {NULL, &fc, &fa, &fp, &fj, &fmd, &ff, &fcj, &faj};
	for (int k = 1; k < TALLY_SET; k++) {
		snprintf(path, sizeof path, "%s/%s", td->out, TALLY_FILES[k]);
		if ((rc = tl_atomic_open(&outs[k], path, err, err_size)))
			goto close;
		*files[k] = outs[k].f;
	}
	rc = TL_ERR_ARG;
	json_t *jc = json_array(), *ja = json_array();
	fprintf(fc, "method,T,period,scene,camera,n,Q,Q_lo,Q_hi,p_ref,p_ref_lo,p_ref_hi,jnd\n");
	fprintf(fa, "method,T,period,effect,df1,df2,F,p,p_gg,epsilon_gg\n");
	fprintf(fp, "method,T,period,factor,level_1,level_2,t,df,p,p_bonferroni\n");
	fprintf(fj, "method,T,period,scene,camera,jod,jod_lo,jod_hi,participants\n");
	fprintf(ff, "method,T,period,Q,Q_lo,Q_hi,p_ref_percent,p_ref_lo_percent,p_ref_hi_percent\n");
	char methods[1024] = "";
	fprintf(fmd, "# Study results\n\n## Conditions\n\n| method | T | period | scene | camera | n | Q [95%% CI] | p_ref [95%% CI] | JND |\n"
		     "|---|---|---|---|---|---|---|---|---|\n");
	gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
	gsl_rng_set(rng, (unsigned long)(td->seed ? td->seed : 1));
	uint32_t B = td->bootstrap ? td->bootstrap : 1000;
	int *use = calloc((size_t)d.max_pid + 1, sizeof *use);
	int64_t *pids = calloc((size_t)d.max_pid + 1, sizeof *pids);
	double *boot = calloc(B, sizeof *boot);
	for (size_t m = 0; m < nmt; m++) {
		/* cm: the method as a CSV cell (sty_csv_cell: no spreadsheet formulas); TP: the T and period cells. */
		char Ts[32], Ps[16], TP[64], cm[80];
		T_str(&mts[m], Ts, sizeof Ts);
		period_str(&mts[m], Ps, sizeof Ps);
		snprintf(TP, sizeof TP, "%s,%s", Ts, Ps);
		sty_csv_cell(mts[m].method, cm, sizeof cm);
		/* Rows: every (scene, camera) of this method/T, then pooled. */
		for (size_t i = 0; i <= d.nc; i++) {
			sel sl = {&mts[m], NULL, NULL, NULL};
			if (i < d.nc) {
				if (!same_variant(&d.c[i], &mts[m]))
					continue;
				sl.scene = d.c[i].scene;
				sl.camera = d.c[i].camera;
			}
			row_stats r;
			if (row_compute(&d, &sl, NULL, &r))
				continue;
			const char *sc = sl.scene ? sl.scene : "all", *ca = sl.camera ? sl.camera : "all";
			char csc[160], cca[160];
			sty_csv_cell(sc, csc, sizeof csc);
			sty_csv_cell(ca, cca, sizeof cca);
			fprintf(fc, "%s,%s,%s,%s,%zu,", cm, TP, csc, cca, r.n);
			csv_num(fc, r.Q, "%.6f"), fputc(',', fc);
			csv_num(fc, r.Q_lo, "%.6f"), fputc(',', fc);
			csv_num(fc, r.Q_hi, "%.6f"), fputc(',', fc);
			fprintf(fc, "%.6f,%.6f,%.6f,%.6f\n", r.j.p, r.j.p_lo, r.j.p_hi, r.j.jnd);
			if (i == d.nc && !isnan(mts[m].T)) { /* pooled row: one point of the Fig. 3 plot */
				fprintf(ff, "%s,%s,%.6f,", cm, TP, r.Q);
				csv_num(ff, r.Q_lo, "%.6f"), fputc(',', ff);
				csv_num(ff, r.Q_hi, "%.6f");
				fprintf(ff, ",%.4f,%.4f,%.4f\n", 100 * r.j.p, 100 * r.j.p_lo, 100 * r.j.p_hi);
				if (!strstr(methods, mts[m].method) && strlen(methods) + strlen(mts[m].method) + 2 < sizeof methods)
					strcat(strcat(methods, methods[0] ? " " : ""), mts[m].method);
			}
			fprintf(fmd, "| %s | %s | %s | %s | %s | %zu | %.2f [%.2f, %.2f] | %.1f%% [%.1f, %.1f] | %.2f |\n", mts[m].method,
				Ts, Ps, sc, ca, r.n, r.Q, r.Q_lo, r.Q_hi, 100 * r.j.p, 100 * r.j.p_lo, 100 * r.j.p_hi, r.j.jnd);
			json_array_append_new(jc, json_pack("{s:s, s:o, s:o, s:s, s:s, s:I, s:f, s:o, s:o, s:f, s:f, s:f, s:f}",
							    "method", mts[m].method, "T",
							    isnan(mts[m].T) ? json_null() : json_real(mts[m].T), "period",
							    period_json(&mts[m]), "scene", sc, "camera", ca, "n", (json_int_t)r.n, "Q", r.Q, "Q_lo",
							    isfinite(r.Q_lo) ? json_real(r.Q_lo) : json_null(), "Q_hi",
							    isfinite(r.Q_hi) ? json_real(r.Q_hi) : json_null(), "p_ref", r.j.p,
							    "p_ref_lo", r.j.p_lo, "p_ref_hi", r.j.p_hi, "jnd", r.j.jnd));
			/* JOD with a bootstrap over the participants of this row. */
			size_t np = 0;
			for (size_t o = 0; o < d.n; o++)
				if (match(&d, &d.o[o], &sl)) {
					int seen = 0;
					for (size_t q = 0; q < np && !seen; q++)
						seen = pids[q] == d.o[o].participant;
					if (!seen)
						pids[np++] = d.o[o].participant;
				}
			for (uint32_t b = 0; b < B; b++) {
				memset(use, 0, ((size_t)d.max_pid + 1) * sizeof *use);
				for (size_t q = 0; q < np; q++)
					use[pids[gsl_rng_uniform_int(rng, np)]]++;
				row_stats rb;
				boot[b] = row_compute(&d, &sl, use, &rb) ? NAN : -rb.j.jnd;
			}
			float *bf = malloc(B * sizeof *bf);
			size_t nb = 0;
			for (uint32_t b = 0; b < B; b++)
				if (isfinite(boot[b]))
					bf[nb++] = (float)boot[b];
			double lo = nb ? mtr_percentile(bf, nb, 2.5) : NAN, hi = nb ? mtr_percentile(bf, nb, 97.5) : NAN;
			free(bf);
			fprintf(fj, "%s,%s,%s,%s,%.6f,", cm, TP, csc, cca, -r.j.jnd);
			csv_num(fj, lo, "%.6f"), fputc(',', fj);
			csv_num(fj, hi, "%.6f");
			fprintf(fj, ",%zu\n", np);
			if (i == d.nc)
				break;
		}
		/* ANOVA: Camera (motion) x Scene, cell means per participant, complete participants only. */
		char sc_lv[32][64], mo_lv[32][64];
		size_t nsc = levels(&d, &mts[m], 0, sc_lv, 32), nmo = levels(&d, &mts[m], 1, mo_lv, 32);
		size_t cells = nsc * nmo;
		double *cell = calloc(((size_t)d.max_pid + 1) * cells, sizeof *cell);
		int *complete = calloc((size_t)d.max_pid + 1, sizeof *complete);
		double *pm = malloc(((size_t)d.max_pid + 1) * sizeof *pm);
		int *has = malloc(((size_t)d.max_pid + 1) * sizeof *has);
		for (int64_t p = 0; p <= d.max_pid; p++)
			complete[p] = 1;
		for (size_t a = 0; a < nmo; a++)
			for (size_t b = 0; b < nsc; b++) {
				sel sl = {&mts[m], sc_lv[b], NULL, mo_lv[a]};
				participant_means(&d, &sl, pm, has, NULL);
				for (int64_t p = 0; p <= d.max_pid; p++) {
					complete[p] &= has[p];
					cell[(size_t)p * cells + a * nsc + b] = pm[p];
				}
			}
		size_t n = 0;
		double *y = malloc(((size_t)d.max_pid + 1) * cells * sizeof *y);
		for (int64_t p = 0; p <= d.max_pid; p++)
			if (complete[p]) {
				memcpy(y + n * cells, cell + (size_t)p * cells, cells * sizeof *y);
				n++;
			}
		sty_anova_effect eff[3];
		const char *enames[3] = {"camera", "scene", "camera:scene"};
		if (n >= 2 && !sty_rm_anova2(y, n, nmo, nsc, eff)) {
			for (int e = 0; e < 3; e++) {
				if (!(eff[e].df1 > 0))
					continue; /* a factor with one level has no effect to test */
				fprintf(fa, "%s,%s,%s,%g,%g,%.6f,%.6g,%.6g,%.6f\n", cm, TP, enames[e], eff[e].df1, eff[e].df2,
					eff[e].F, eff[e].p, eff[e].p_gg, eff[e].epsilon_gg);
				json_array_append_new(ja, json_pack("{s:s, s:o, s:o, s:s, s:f, s:f, s:f, s:f, s:f, s:f, s:I}",
								    "method", mts[m].method, "T",
								    isnan(mts[m].T) ? json_null() : json_real(mts[m].T), "period",
								    period_json(&mts[m]), "effect",
								    enames[e], "df1", eff[e].df1, "df2", eff[e].df2, "F", eff[e].F, "p",
								    eff[e].p, "p_gg", eff[e].p_gg, "epsilon_gg", eff[e].epsilon_gg,
								    "participants", (json_int_t)n));
			}
			/* Post hoc: paired t tests between levels of each factor (means over the other factor). */
			for (int f = 0; f < 2; f++) {
				size_t nl = f == 0 ? nmo : nsc;
				double ncmp = (double)nl * (double)(nl - 1) / 2;
				double *xl = calloc(n * nl, sizeof *xl);
				for (size_t i = 0; i < n; i++)
					for (size_t a = 0; a < nmo; a++)
						for (size_t b = 0; b < nsc; b++)
							xl[i * nl + (f == 0 ? a : b)] += y[i * cells + a * nsc + b] / (double)(f == 0 ? nsc : nmo);
				double *u = malloc(n * sizeof *u), *v = malloc(n * sizeof *v);
				for (size_t l1 = 0; l1 < nl; l1++)
					for (size_t l2 = l1 + 1; l2 < nl; l2++) {
						for (size_t i = 0; i < n; i++)
							u[i] = xl[i * nl + l1], v[i] = xl[i * nl + l2];
						double t, df, p;
						paired_t(u, v, n, &t, &df, &p);
						char l1c[160], l2c[160];
						fprintf(fp, "%s,%s,%s,%s,%s,%.6f,%g,%.6g,%.6g\n", cm, TP, f == 0 ? "camera" : "scene",
							sty_csv_cell(f == 0 ? mo_lv[l1] : sc_lv[l1], l1c, sizeof l1c),
							sty_csv_cell(f == 0 ? mo_lv[l2] : sc_lv[l2], l2c, sizeof l2c), t, df, p,
							fmin(1.0, p * ncmp));
					}
				free(u);
				free(v);
				free(xl);
			}
		}
		free(cell);
		free(complete);
		free(pm);
		free(has);
		free(y);
	}
	gsl_rng_free(rng);
	free(use);
	free(pids);
	free(boot);
	fprintf(fmd, "\nQ: mean reference-relative rating (+2 = reference much better); p_ref: share of answers preferring "
		     "the reference (ties count half); JND = Phi^-1(p_ref)/Phi^-1(0.75).\n");
	rc = TL_OK;
	if (tl_json_dump(fcj, jc) || tl_json_dump(faj, ja))
		rc = tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write the JSON tables", td->out);
	json_decref(jc);
	json_decref(ja);
close:
	if (rc == TL_OK)
		rc = tl_atomic_commit_set(outs, TALLY_SET, err, err_size);
	/* A plot of an earlier tally must not stand beside these tables when this one is not drawn. */
	snprintf(path, sizeof path, "%s/fig3.png", td->out);
	if (rc == TL_OK)
		unlink(path);
	if (rc == TL_OK && !td->no_plot) {
		/* Fig. 3 style plot: pooled Q with its CI and p_ref against T per method, the 1-JND line (p = 75%). */
		snprintf(path, sizeof path, "%s/fig3.gp", td->out);
		mtr_plot plot;
		char note[512];
		FILE *g = mtr_plot_begin(&plot, path, note, sizeof note);
		if (g) {
			fprintf(g,
				"set datafile separator ','\nset terminal pngcairo size 960,540 font 'sans,10' noenhanced\n"
				"set output '%s/fig3.png'\nset grid\nset logscale x 2\nset xlabel 'threshold T'\n"
				"set offsets graph 0.06, graph 0.06, 0, 0\nset key outside right top\n"
				"set title 'Quality Q (+2 = reference much better) and preference for the reference, pooled over scenes and cameras'\n"
				"set ylabel 'Q [95%% CI]'\nset y2label 'p_ref (%%)'\n"
				"set yrange [-2:2]; set y2range [0:100]; set ytics nomirror; set y2tics\n"
				"set arrow from graph 0, second 75 to graph 1, second 75 nohead dt 2\n"
				"set label '1 JND (p_ref = 75%%)' at graph 0.02, second 77\n"
				"methods = '%s'\n"
				"plot for [m in methods] '%s/fig3.csv' using (strcol(1) eq m ? $2 : 1/0):4:5:6 every ::1 with yerrorlines "
				"title 'Q '.m, for [m in methods] '' using (strcol(1) eq m ? $2 : 1/0):7 every ::1 axes x1y2 "
				"with linespoints dt 3 title 'p_ref '.m\n",
				td->out, methods, td->out);
			if (mtr_plot_end(&plot, note, sizeof note))
				fprintf(stderr, "taslab study: note: %s; fig3.png not drawn\n", note);
		}
	}
done:
	if (rc) {
		tl_atomic_abort_set(outs, TALLY_SET);
		if (made_dir)
			rmdir(td->out); /* only when empty: a folder made for this tally holds nothing now */
	}
	free(mts);
	free(d.o);
	free(d.c);
	free(d.flagged);
	return rc;
}
