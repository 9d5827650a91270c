/* study_tally.c — the statistics of a study, computed into a sty_result (paper sec. 3, Fig. 3 and its footnotes,
 * sec. 7.2; DESIGN section 7).
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
 * its 95% interval comes from a bootstrap over participants.
 *
 * The tally is computed as a value (study_result.h, issue 30.3): sty_tally_compute fills a sty_result, which the
 * tally's files (study_tally_write.c), the sweep report and next the threshold fit and the simulator share. */
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_internal.h"
#include "taslab/metrics.h"
#include "taslab/study_result.h"
#include "study_threshold_rows.h"

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

#define STY_SS_ZERO 1e-18 /* a sum of squares of ratings (-2..2) this small is rounding error (see below) */

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
	/* No error variance: F is undefined (NaN) when the effect has none either (every participant's contrast scores
	 * are 0: identical cells), infinite with p = 0 when it has (issue 27.10: one NaN convention, no 0/0 printed).
	 * Ratings lie in -2..2, so sums of squares below STY_SS_ZERO are the contrasts' rounding, not variance. */
	if (ss_err < STY_SS_ZERO)
		ss_err = 0;
	if (ss_eff < STY_SS_ZERO)
		ss_eff = 0;
	if (ss_err > 0)
		e->F = (ss_eff / e->df1) / (ss_err / e->df2);
	else
		e->F = ss_eff > 0 ? INFINITY : NAN;
	e->p = isnan(e->F) ? NAN : isinf(e->F) ? 0.0 : gsl_cdf_fdist_Q(e->F, e->df1, e->df2);
	/* Greenhouse-Geisser: epsilon = tr(S)^2 / (m tr(S S)), S the covariance of orthonormal contrast scores; 1 by
	 * definition for one contrast, undefined when S is 0. */
	double tr = 0, tr2 = 0;
	for (size_t j = 0; j < m; j++) {
		tr += S[j * m + j];
		for (size_t k = 0; k < m; k++)
			tr2 += S[j * m + k] * S[k * m + j];
	}
	e->epsilon_gg = m == 1 ? 1.0 : ss_err > 0 && tr2 > 0 ? fmin(1.0, tr * tr / ((double)m * tr2)) : NAN;
	e->p_gg = isnan(e->F) || isnan(e->epsilon_gg) ? NAN
		  : isinf(e->F)                         ? 0.0
							: gsl_cdf_fdist_Q(e->F, e->epsilon_gg * e->df1, e->epsilon_gg * e->df2);
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
	if (!ca || !cb) {
		free(ca);
		free(cb);
		return TL_ERR_NOMEM;
	}
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
		return -1; /* local sentinel: out of memory (an index otherwise; the caller reports TL_ERR_NOMEM) */
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

/* Reads the answered test trials into `d` (observers flagged by the screening left out unless keep_flagged) and
 * the screening of every participant into res->observers. */
static int load(sty *s, const sty_tally_desc *td, data *d, sty_result *res, char *err, size_t err_size)
{
	memset(d, 0, sizeof *d);
	sqlite3_stmt *st;
	/* Screening from catch trials (answers of broken playbacks left out: study_telemetry.h), and the P.910-crowd
	 * screening (study_result.h, as the P.910-crowd toolkit applies it): a hidden-reference (catch) answer outside
	 * -1..1; a gold answer (reference-relative) more than one step from "reference much better"; the test answers'
	 * sample variance below 0.1 is straightlining. The test answers are the raw ones the participant chose (A much
	 * better .. B much better). */
	if (sqlite3_prepare_v2(s->db,
			       "SELECT p.id, p.label, count(a.answer), avg(abs(a.answer)), sum(abs(a.answer) = 2),"
			       " (SELECT count(*) FROM answers b WHERE b.participant = p.id AND b.broken IS NOT NULL),"
			       " (SELECT count(*) || ',' || coalesce(sum(b.answer), 0) || ',' || coalesce(sum(b.answer * b.answer), 0)"
			       "  FROM answers b JOIN trials u ON u.participant = b.participant AND u.idx = b.idx"
			       "  WHERE b.participant = p.id AND u.kind = 'test' AND b.broken IS NULL)"
			       " , (SELECT count(*) || ',' || coalesce(sum(abs(CASE WHEN u.ref_first THEN -b.answer"
			       "  ELSE b.answer END - ?1) > ?2), 0)"
			       "  FROM answers b JOIN trials u ON u.participant = b.participant AND u.idx = b.idx"
			       "  WHERE b.participant = p.id AND u.kind = 'gold' AND b.broken IS NULL)"
			       " FROM participants p LEFT JOIN trials t ON t.participant = p.id AND t.kind = 'catch'"
			       " LEFT JOIN answers a ON a.participant = t.participant AND a.idx = t.idx AND a.broken IS NULL"
			       " GROUP BY p.id ORDER BY p.id",
			       -1, &st, NULL))
		return sty_db_fail(s, err, err_size, "tally");
	sqlite3_bind_int(st, 1, STY_P910_GOLD_ANSWER);
	sqlite3_bind_int(st, 2, STY_P910_GOLD_TOLERANCE);
	while (sqlite3_step(st) == SQLITE_ROW) {
		int64_t pid = sqlite3_column_int64(st, 0);
		int n = sqlite3_column_int(st, 2), strong = sqlite3_column_int(st, 4);
		int flag = n > 0 && 2 * strong > n;
		long long tn = 0, sx = 0, sxx = 0;
		if (sscanf((const char *)sqlite3_column_text(st, 6), "%lld,%lld,%lld", &tn, &sx, &sxx) != 3)
			tn = 0;
		sty_observer *no = realloc(res->observers, (res->observer_count + 1) * sizeof *no);
		if (!no) {
			sqlite3_finalize(st);
			return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		}
		res->observers = no;
		sty_observer *ob = &no[res->observer_count++];
		memset(ob, 0, sizeof *ob);
		ob->participant = pid;
		snprintf(ob->label, sizeof ob->label, "%s", (const char *)sqlite3_column_text(st, 1));
		ob->catch_n = n;
		ob->catch_mean_abs = n ? sqlite3_column_double(st, 3) : NAN;
		ob->catch_much_better = strong;
		ob->flagged = flag;
		ob->broken = sqlite3_column_int(st, 5);
		ob->rating_variance = tn >= 2 ? ((double)sxx - (double)sx * (double)sx / (double)tn) / (double)(tn - 1) : NAN;
		if (sscanf((const char *)sqlite3_column_text(st, 7), "%d,%d", &ob->gold_n, &ob->gold_wrong) != 2)
			ob->gold_n = ob->gold_wrong = 0;
		ob->p910 = (strong > 0 ? STY_P910_CATCH : 0u) | (ob->gold_wrong > 0 ? STY_P910_GOLD : 0u) |
			   (tn >= 2 && ob->rating_variance < STY_P910_MIN_VARIANCE ? STY_P910_VARIANCE : 0u);
		if ((flag || (td->p910 && ob->p910)) && !td->keep_flagged) {
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
			       " JOIN conditions c ON c.id = t.condition WHERE t.kind = 'test' AND a.broken IS NULL ORDER BY a.participant, t.idx",
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
			return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
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
		return -1; /* local sentinel: no rating in the selection (row_of: no row) */
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
		/* The t interval intersected with the rating scale -2..2 (issue 27.11): Q lies on the scale, so cutting
		 * off the part outside it keeps the interval's coverage and stops it running past +-2 with few observers. */
		double se = sqrt(var / (double)(k - 1) / (double)k);
		double t = gsl_cdf_tdist_Pinv(0.975, (double)(k - 1));
		r->Q_lo = fmax(-2.0, mean - t * se);
		r->Q_hi = fmin(2.0, mean + t * se);
	} else {
		r->Q_lo = r->Q_hi = NAN;
	}
	(void)np;
	mtr_jnd_from_counts(n_ref, n_tie, n, 0.95, &r->j);
	free(pm);
	free(has);
	return 0;
}

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
	double sd = n > 1 ? (m2 < STY_SS_ZERO ? 0.0 : sqrt(m2 / (double)(n - 1))) : NAN;
	/* Identical differences: t is undefined (NaN) when they are all 0, infinite (p = 0) otherwise — never 0 and 1. */
	if (sd > 0)
		*t = mean / (sd / sqrt((double)n));
	else
		*t = n < 2 || fabs(mean) < 1e-9 ? NAN : mean > 0 ? INFINITY : -INFINITY;
	*p = isnan(*t) ? NAN : isinf(*t) ? 0.0 : 2 * gsl_cdf_tdist_Q(fabs(*t), *df);
}

/* ------------------------------------------------------------------ the tally as a value */

/* The distinct variants (method, T, period) of the data, sorted by method, T and period. */
static int variants_of(const data *d, condk **out, size_t *n)
{
	condk *mts = NULL;
	size_t nmt = 0;
	for (size_t i = 0; i < d->nc; i++) {
		int seen = 0;
		for (size_t k = 0; k < nmt; k++)
			seen |= same_variant(&mts[k], &d->c[i]);
		if (!seen) {
			condk *nm = realloc(mts, (nmt + 1) * sizeof *nm);
			if (!nm) {
				free(mts);
				return TL_ERR_NOMEM;
			}
			mts = nm;
			mts[nmt++] = d->c[i];
		}
	}
	if (nmt)
		qsort(mts, nmt, sizeof *mts, cmp_variant);
	*out = mts;
	*n = nmt;
	return TL_OK;
}

/* The bootstrap state shared by every row: one generator drawn in row order, so intervals depend on the seed only. */
typedef struct boot_state {
	gsl_rng *rng;
	uint32_t B;
	int *use;       /* multiplicity per participant id */
	int64_t *pids;  /* the participants of the row */
	double *boot;   /* the B resampled JODs */
} boot_state;

/* The row of selection `sl` (variant m of the result): Q, p_ref, JND, and JOD with a bootstrap over the participants
 * of this row. Returns 1 when the selection holds no rating (no row), 0, or TL_ERR_NOMEM. */
static int row_of(const data *d, const sel *sl, size_t m, boot_state *bs, sty_row *row)
{
	row_stats r;
	if (row_compute(d, sl, NULL, &r))
		return 1;
	memset(row, 0, sizeof *row);
	row->variant = m;
	row->pooled = !sl->scene;
	snprintf(row->scene, sizeof row->scene, "%s", sl->scene ? sl->scene : "all");
	snprintf(row->camera, sizeof row->camera, "%s", sl->camera ? sl->camera : "all");
	row->n = r.n;
	row->Q = r.Q, row->Q_lo = r.Q_lo, row->Q_hi = r.Q_hi;
	row->j = r.j;
	size_t np = 0;
	for (size_t o = 0; o < d->n; o++)
		if (match(d, &d->o[o], sl)) {
			int seen = 0;
			for (size_t q = 0; q < np && !seen; q++)
				seen = bs->pids[q] == d->o[o].participant;
			if (!seen)
				bs->pids[np++] = d->o[o].participant;
		}
	for (uint32_t b = 0; b < bs->B; b++) {
		memset(bs->use, 0, ((size_t)d->max_pid + 1) * sizeof *bs->use);
		for (size_t q = 0; q < np; q++)
			bs->use[bs->pids[gsl_rng_uniform_int(bs->rng, np)]]++;
		row_stats rb;
		bs->boot[b] = row_compute(d, sl, bs->use, &rb) ? NAN : -rb.j.jnd;
	}
	float *bf = malloc(bs->B * sizeof *bf);
	if (!bf)
		return TL_ERR_NOMEM;
	size_t nb = 0;
	for (uint32_t b = 0; b < bs->B; b++)
		if (isfinite(bs->boot[b]))
			bf[nb++] = (float)bs->boot[b];
	row->jod = -r.j.jnd + 0.0; /* + 0.0: no "-0" where p_ref is one half */
	row->jod_lo = nb ? mtr_percentile(bf, nb, 2.5) : NAN;
	row->jod_hi = nb ? mtr_percentile(bf, nb, 97.5) : NAN;
	row->participants = np;
	free(bf);
	return 0;
}

/* The ANOVA of variant m (Camera (motion) x Scene, cell means per participant, complete participants only) and the
 * post hoc paired t tests between levels of each factor (means over the other factor), appended to `res`. */
static int anova_of(const data *d, const condk *mt, size_t m, sty_result *res)
{
	char sc_lv[32][64], mo_lv[32][64];
	size_t nsc = levels(d, mt, 0, sc_lv, 32), nmo = levels(d, mt, 1, mo_lv, 32);
	size_t cells = nsc * nmo;
	int rc = TL_OK;
	double *cell = calloc(((size_t)d->max_pid + 1) * cells, sizeof *cell);
	int *complete = calloc((size_t)d->max_pid + 1, sizeof *complete);
	double *pm = malloc(((size_t)d->max_pid + 1) * sizeof *pm);
	int *has = malloc(((size_t)d->max_pid + 1) * sizeof *has);
	double *y = malloc(((size_t)d->max_pid + 1) * cells * sizeof *y);
	if (!cell || !complete || !pm || !has || !y) {
		rc = TL_ERR_NOMEM;
		goto done;
	}
	for (int64_t p = 0; p <= d->max_pid; p++)
		complete[p] = 1;
	for (size_t a = 0; a < nmo; a++)
		for (size_t b = 0; b < nsc; b++) {
			sel sl = {mt, sc_lv[b], NULL, mo_lv[a]};
			participant_means(d, &sl, pm, has, NULL);
			for (int64_t p = 0; p <= d->max_pid; p++) {
				complete[p] &= has[p];
				cell[(size_t)p * cells + a * nsc + b] = pm[p];
			}
		}
	size_t n = 0;
	for (int64_t p = 0; p <= d->max_pid; p++)
		if (complete[p]) {
			memcpy(y + n * cells, cell + (size_t)p * cells, cells * sizeof *y);
			n++;
		}
	sty_anova_effect eff[3];
	static const char *const enames[3] = {"camera", "scene", "camera:scene"};
	/* Why a variant has no ANOVA, said instead of an empty table (issue 27.10). */
	char *note = res->variants[m].anova_note;
	size_t note_size = sizeof res->variants[m].anova_note;
	if (nsc < 2 && nmo < 2) {
		snprintf(note, note_size, "one scene (%s) and one camera motion (%s): no factor with two levels to compare",
			 nsc ? sc_lv[0] : "none", nmo ? mo_lv[0] : "none");
		goto done;
	}
	if (n < 2) {
		snprintf(note, note_size, "%zu participant(s) rated all %zu cells (%zu scene(s) x %zu camera motion(s)); "
					  "a repeated-measures ANOVA needs two",
			 n, cells, nsc, nmo);
		goto done;
	}
	if (sty_rm_anova2(y, n, nmo, nsc, eff))
		goto done;
	for (int e = 0; e < 3; e++) {
		if (!(eff[e].df1 > 0))
			continue; /* a factor with one level has no effect to test */
		if (isnan(eff[e].F) && !note[0])
			snprintf(note, note_size, "identical cells: every participant's %s contrasts are 0 (no variance), so F "
						  "and p are undefined",
				 enames[e]);
		sty_anova_row *na = realloc(res->anova, (res->anova_count + 1) * sizeof *na);
		if (!na) {
			rc = TL_ERR_NOMEM;
			goto done;
		}
		res->anova = na;
		na[res->anova_count++] = (sty_anova_row){.variant = m, .effect = enames[e], .e = eff[e], .participants = n,
							 .note = isnan(eff[e].F) ? "identical cells: no variance (F undefined)"
										 : NULL};
	}
	for (int f = 0; f < 2 && !rc; f++) {
		size_t nl = f == 0 ? nmo : nsc;
		double ncmp = (double)nl * (double)(nl - 1) / 2;
		double *xl = calloc(n * nl, sizeof *xl), *u = malloc(n * sizeof *u), *v = malloc(n * sizeof *v);
		if (!xl || !u || !v)
			rc = TL_ERR_NOMEM;
		for (size_t i = 0; !rc && i < n; i++)
			for (size_t a = 0; a < nmo; a++)
				for (size_t b = 0; b < nsc; b++)
					xl[i * nl + (f == 0 ? a : b)] += y[i * cells + a * nsc + b] / (double)(f == 0 ? nsc : nmo);
		for (size_t l1 = 0; !rc && l1 < nl; l1++)
			for (size_t l2 = l1 + 1; !rc && l2 < nl; l2++) {
				for (size_t i = 0; i < n; i++)
					u[i] = xl[i * nl + l1], v[i] = xl[i * nl + l2];
				sty_posthoc_row *np = realloc(res->posthoc, (res->posthoc_count + 1) * sizeof *np);
				if (!np) {
					rc = TL_ERR_NOMEM;
					break;
				}
				res->posthoc = np;
				sty_posthoc_row *ph = &np[res->posthoc_count++];
				memset(ph, 0, sizeof *ph);
				ph->variant = m;
				ph->factor = f == 0 ? "camera" : "scene";
				snprintf(ph->level_1, sizeof ph->level_1, "%s", f == 0 ? mo_lv[l1] : sc_lv[l1]);
				snprintf(ph->level_2, sizeof ph->level_2, "%s", f == 0 ? mo_lv[l2] : sc_lv[l2]);
				paired_t(u, v, n, &ph->t, &ph->df, &ph->p);
				ph->p_bonferroni = isnan(ph->p) ? NAN : fmin(1.0, ph->p * ncmp);
			}
		free(u);
		free(v);
		free(xl);
	}
done:
	free(cell);
	free(complete);
	free(pm);
	free(has);
	free(y);
	return rc;
}

/* The threshold fits (issue 28, study_threshold_rows.h): every rating of a variant with a threshold T as a record. */
static int thresholds_of(const data *d, sty_result *res, char *err, size_t err_size)
{
	sty_trating *t = malloc((d->n ? d->n : 1) * sizeof *t);
	size_t n = 0;
	if (!t)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	for (size_t i = 0; i < d->n; i++) {
		const condk *c = &d->c[d->o[i].cond];
		if (isnan(c->T))
			continue;
		t[n++] = (sty_trating){.method = c->method, .scene = c->scene, .camera = c->camera, .period = c->period,
				       .T = c->T, .participant = d->o[i].participant,
				       .y = d->o[i].rating > 0 ? 1 : d->o[i].rating == 0 ? 0.5 : 0};
	}
	int rc = sty_thresholds_compute(t, n, res, err, err_size);
	free(t);
	return rc;
}

int sty_tally_compute(sty *s, const sty_tally_desc *td, sty_result **out, char *err, size_t err_size)
{
	*out = NULL;
	if (td->seed > STY_SEED_MAX)
		return tl_error(err, err_size, TL_ERR_ARG, "--seed %llu: at most %u (GSL's mt19937 keeps 32 bits of a seed)",
				(unsigned long long)td->seed, STY_SEED_MAX);
	sty_result *res = calloc(1, sizeof *res);
	if (!res)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	data d;
	condk *mts = NULL;
	size_t nmt = 0;
	boot_state bs = {0};
	int rc = load(s, td, &d, res, err, err_size);
	if (rc)
		goto done;
	res->left_out = d.nflagged;
	if ((rc = variants_of(&d, &mts, &nmt)))
		goto nomem;
	/* at most one row per condition and a pooled row per variant */
	res->variants = calloc(nmt ? nmt : 1, sizeof *res->variants);
	res->rows = calloc(d.nc + nmt, sizeof *res->rows);
	bs.rng = gsl_rng_alloc(gsl_rng_mt19937);
	bs.B = td->bootstrap ? td->bootstrap : 1000;
	bs.use = calloc((size_t)d.max_pid + 1, sizeof *bs.use);
	bs.pids = calloc((size_t)d.max_pid + 1, sizeof *bs.pids);
	bs.boot = calloc(bs.B, sizeof *bs.boot);
	if (!res->variants || !res->rows || !bs.rng || !bs.use || !bs.pids || !bs.boot)
		goto nomem;
	gsl_rng_set(bs.rng, (unsigned long)(td->seed ? td->seed : 1));
	for (size_t m = 0; m < nmt; m++) {
		sty_variant *v = &res->variants[res->variant_count++];
		snprintf(v->method, sizeof v->method, "%s", mts[m].method);
		v->T = mts[m].T;
		v->period = mts[m].period;
		/* Rows: every (scene, camera) of this variant, then pooled. */
		for (size_t i = 0; i <= d.nc; i++) {
			sel sl = {&mts[m], NULL, NULL, NULL};
			if (i < d.nc) {
				if (!same_variant(&d.c[i], &mts[m]))
					continue;
				sl.scene = d.c[i].scene;
				sl.camera = d.c[i].camera;
			}
			int r = row_of(&d, &sl, m, &bs, &res->rows[res->row_count]);
			if (r < 0)
				goto nomem;
			res->row_count += r == 0;
		}
		if (anova_of(&d, &mts[m], m, res))
			goto nomem;
	}
	rc = thresholds_of(&d, res, err, err_size);
	goto done;
nomem:
	rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
done:
	gsl_rng_free(bs.rng);
	free(bs.use);
	free(bs.pids);
	free(bs.boot);
	free(mts);
	free(d.o);
	free(d.c);
	free(d.flagged);
	if (rc)
		sty_result_free(&res);
	*out = res;
	return rc;
}

void sty_result_free(sty_result **pr)
{
	if (!pr || !*pr)
		return;
	sty_result *r = *pr;
	free(r->variants);
	free(r->rows);
	free(r->anova);
	free(r->posthoc);
	free(r->observers);
	free(r->thresholds);
	free(r);
	*pr = NULL;
}
