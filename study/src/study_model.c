/* study_model.c — the metric-to-JND model (study_model.h; issue 28): jod.csv joined with a sweep's summary.csv per
 * method, T, period, scene and camera path, a weighted isotonic fit of the JOD drop on log2 metric, its
 * leave-one-scene-out error on the measured thresholds (thresholds.csv), and predictions for another sweep. */
#include <errno.h>
#include <limits.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_internal.h"
#include "taslab/study_model.h"
#include "taslab/tl_json.h"

#define KEY_LEN 160
#define MAX_COLS 256
#define NO_COL (-1) /* csv_col: no such column */

/* ------------------------------------------------------------------ a small CSV reader (RFC 4180 quotes) */

typedef struct csv_table {
	char *text;           /* the file, cells cut in place */
	char **cell;          /* rows x cols */
	size_t rows, cols;    /* rows without the header */
	char *head[MAX_COLS];
} csv_table;

static void csv_free(csv_table *t)
{
	free(t->text);
	free(t->cell);
	memset(t, 0, sizeof *t);
}

/* Splits one record at *p into cells (at most MAX_COLS); returns the count, advances *p past the line end. */
static size_t csv_record(char **p, char **cells)
{
	size_t n = 0;
	char *s = *p;
	for (;;) {
		char *out = s, *start = s;
		if (*s == '"') {
			s++;
			while (*s) {
				if (*s == '"' && s[1] == '"')
					*out++ = '"', s += 2;
				else if (*s == '"') {
					s++;
					break;
				} else
					*out++ = *s++;
			}
			while (*s && *s != ',' && *s != '\n' && *s != '\r')
				s++;
		} else {
			while (*s && *s != ',' && *s != '\n' && *s != '\r')
				out++, s++;
		}
		char end = *s;
		*out = '\0';
		if (n < MAX_COLS)
			cells[n++] = start;
		if (end == ',') {
			s++;
			continue;
		}
		if (end == '\r') /* the terminator may have overwritten it: look at the saved character */
			s++;
		if (end == '\n' || (end == '\r' && *s == '\n'))
			s++;
		break;
	}
	*p = s;
	return n;
}

static int csv_load(const char *path, csv_table *t, char *err, size_t err_size)
{
	memset(t, 0, sizeof *t);
	FILE *f = fopen(path, "rb");
	if (!f)
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: %s", path, strerror(errno));
	size_t cap = 1 << 16, len = 0;
	t->text = malloc(cap + 1);
	for (size_t got; t->text && (got = fread(t->text + len, 1, cap - len, f)) > 0;) {
		len += got;
		if (len == cap) {
			char *nt = realloc(t->text, 2 * cap + 1);
			if (!nt)
				free(t->text);
			t->text = nt, cap *= 2;
		}
	}
	fclose(f);
	if (!t->text)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	t->text[len] = '\0';
	char *p = t->text;
	t->cols = csv_record(&p, t->head);
	if (!len || t->cols < 2) {
		csv_free(t);
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: not a CSV table with a header", path);
	}
	size_t lines = 1;
	for (char *q = p; *q; q++)
		lines += *q == '\n';
	if (!(t->cell = calloc(lines * t->cols, sizeof *t->cell))) {
		csv_free(t);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	char *cells[MAX_COLS];
	while (*p) {
		size_t n = csv_record(&p, cells);
		if (n == 1 && !cells[0][0])
			continue; /* an empty line */
		if (n != t->cols) {
			size_t row = t->rows + 2, cols = t->cols;
			csv_free(t);
			return tl_error(err, err_size, TL_ERR_INPUT, "%s line %zu: %zu cells, the header has %zu", path, row, n,
					cols);
		}
		memcpy(t->cell + t->rows++ * t->cols, cells, n * sizeof *cells);
	}
	return TL_OK;
}

static int csv_col(const csv_table *t, const char *name)
{
	for (size_t i = 0; i < t->cols; i++)
		if (!strcmp(t->head[i], name))
			return (int)i;
	return NO_COL;
}

static const char *csv_at(const csv_table *t, size_t row, int col) { return col < 0 ? "" : t->cell[row * t->cols + col]; }

/* A numeric cell: empty -> NAN, inf/-inf, else a number (NAN when unparsable). */
static double num(const char *s)
{
	if (!*s)
		return NAN;
	char *end;
	double v = strtod(s, &end);
	return *end ? NAN : v;
}

static int need_cols(const csv_table *t, const char *path, const char *const *names, int *idx, char *err, size_t err_size)
{
	for (size_t i = 0; names[i]; i++)
		if ((idx[i] = csv_col(t, names[i])) < 0)
			return tl_error(err, err_size, TL_ERR_INPUT, "%s: no column '%s'", path, names[i]);
	return TL_OK;
}

/* ------------------------------------------------------------------ series of a sweep */

/* One clip of a sweep: a scene x camera x method x period series point (T, metric). */
typedef struct clip_pt {
	char scene[KEY_LEN], camera[KEY_LEN], method[32];
	long period;   /* 0: none */
	double T;      /* NAN: none */
	double m;      /* the metric */
} clip_pt;

static bool same_series(const clip_pt *a, const clip_pt *b)
{
	return !strcmp(a->scene, b->scene) && !strcmp(a->camera, b->camera) && !strcmp(a->method, b->method) &&
	       a->period == b->period;
}

static int cmp_clip(const void *pa, const void *pb)
{
	const clip_pt *a = pa, *b = pb;
	int c;
	if ((c = strcmp(a->scene, b->scene)) || (c = strcmp(a->camera, b->camera)) || (c = strcmp(a->method, b->method)))
		return c;
	if (a->period != b->period)
		return a->period < b->period ? -1 : 1;
	return (a->T > b->T) - (a->T < b->T);
}

/* The metric of summary.csv's row: column `metric`, or exceed_<T> at the row's own T for exceed_T. */
static double row_metric(const csv_table *t, size_t r, const char *metric, int col, double T)
{
	if (strcmp(metric, "exceed_T"))
		return num(csv_at(t, r, col));
	if (!(T > 0) || T != floor(T))
		return NAN;
	char name[32];
	snprintf(name, sizeof name, "exceed_%.0f", T);
	return num(csv_at(t, r, csv_col(t, name)));
}

/* The complete runs of SWEEP/summary.csv with a finite metric, sorted by series and T. */
static int load_sweep(const char *dir, const char *metric, clip_pt **out, size_t *n, char *err, size_t err_size)
{
	char path[4096];
	snprintf(path, sizeof path, "%s/summary.csv", dir);
	csv_table t;
	int rc = csv_load(path, &t, err, err_size);
	if (rc)
		return rc;
	static const char *const names[] = {"scene", "camera", "method", "T", "period", "status", NULL};
	int c[6];
	int mc = csv_col(&t, metric);
	if ((rc = need_cols(&t, path, names, c, err, err_size)))
		goto done;
	if (strcmp(metric, "exceed_T") && mc < 0) {
		rc = tl_error(err, err_size, TL_ERR_ARG, "metric %s: %s has no such column (flip_mean, exceed_T, "
			      "maxrgb_p99, flicker_mean or another numeric column)", metric, path);
		goto done;
	}
	*n = 0;
	if (!(*out = calloc(t.rows + 1, sizeof **out))) {
		rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		goto done;
	}
	for (size_t r = 0; r < t.rows; r++) {
		clip_pt *p = &(*out)[*n];
		p->T = num(csv_at(&t, r, c[3]));
		p->m = row_metric(&t, r, metric, mc, p->T);
		double per = num(csv_at(&t, r, c[4]));
		if (strcmp(csv_at(&t, r, c[5]), "complete") || !isfinite(p->m))
			continue; /* incomplete runs and the reference runs (no difference metrics) */
		snprintf(p->scene, sizeof p->scene, "%s", csv_at(&t, r, c[0]));
		snprintf(p->camera, sizeof p->camera, "%s", csv_at(&t, r, c[1]));
		snprintf(p->method, sizeof p->method, "%s", csv_at(&t, r, c[2]));
		p->period = isfinite(per) ? (long)per : 0;
		(*n)++;
	}
	qsort(*out, *n, sizeof **out, cmp_clip);
done:
	csv_free(&t);
	return rc;
}

/* ------------------------------------------------------------------ the fit */

void sty_isotonic(const double *y, const double *w, size_t n, double *fit)
{
	/* blocks on a stack: value, weight, length */
	double *bv = malloc((n + 1) * sizeof *bv), *bw = malloc((n + 1) * sizeof *bw);
	size_t *bl = malloc((n + 1) * sizeof *bl), k = 0;
	if (!bv || !bw || !bl) {
		free(bv), free(bw), free(bl);
		for (size_t i = 0; i < n; i++)
			fit[i] = NAN;
		return;
	}
	for (size_t i = 0; i < n; i++) {
		bv[k] = y[i], bw[k] = w[i], bl[k] = 1, k++;
		while (k > 1 && bv[k - 2] > bv[k - 1]) {
			double W = bw[k - 2] + bw[k - 1];
			bv[k - 2] = (bv[k - 2] * bw[k - 2] + bv[k - 1] * bw[k - 1]) / W;
			bw[k - 2] = W, bl[k - 2] += bl[k - 1], k--;
		}
	}
	for (size_t b = 0, i = 0; b < k; b++)
		for (size_t j = 0; j < bl[b]; j++)
			fit[i++] = bv[b];
	free(bv), free(bw), free(bl);
}

/* A rated condition joined with its metric. */
typedef struct cond {
	const clip_pt *clip;
	double x;      /* log2 metric */
	double d;      /* -JOD */
	double w;      /* participants */
} cond;

static int cmp_cond(const void *pa, const void *pb)
{
	const cond *a = pa, *b = pb;
	return (a->x > b->x) - (a->x < b->x);
}

/* The isotonic fit of the conditions except scene `skip` (NULL: none): knots (block centre x, block value d) and
 * the metric at which it first reaches d = 1 (inf: never; the smallest knot's metric when it starts above). */
typedef struct fit {
	double *kx, *kd;
	size_t k;
	double m_jnd;
} fit;

static int fit_model(const cond *c, size_t n, const char *skip, fit *f, char *err, size_t err_size)
{
	memset(f, 0, sizeof *f);
	cond *s = malloc((n + 1) * sizeof *s);
	double *y = calloc(n + 1, sizeof *y), *w = calloc(n + 1, sizeof *w), *fv = malloc((n + 1) * sizeof *fv);
	f->kx = malloc((n + 1) * sizeof *f->kx), f->kd = malloc((n + 1) * sizeof *f->kd);
	if (!s || !y || !w || !fv || !f->kx || !f->kd) {
		free(s), free(y), free(w), free(fv), free(f->kx), free(f->kd);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	size_t m = 0;
	for (size_t i = 0; i < n; i++)
		if (!skip || strcmp(c[i].clip->scene, skip))
			s[m++] = c[i];
	qsort(s, m, sizeof *s, cmp_cond);
	for (size_t i = 0; i < m; i++)
		y[i] = s[i].d, w[i] = s[i].w;
	sty_isotonic(y, w, m, fv);
	/* knots: each block's weighted centre in x (equal fitted values form one block) */
	for (size_t i = 0; i < m;) {
		double sx = 0, sw = 0;
		size_t j = i;
		for (; j < m && fv[j] == fv[i]; j++)
			sx += s[j].x * s[j].w, sw += s[j].w;
		f->kx[f->k] = sx / sw, f->kd[f->k] = fv[i], f->k++;
		i = j;
	}
	f->m_jnd = INFINITY;
	for (size_t i = 0; i < f->k; i++) {
		if (f->kd[i] < 1)
			continue;
		double x = f->kx[i];
		if (i > 0)
			x = f->kx[i - 1] + (1 - f->kd[i - 1]) / (f->kd[i] - f->kd[i - 1]) * (f->kx[i] - f->kx[i - 1]);
		f->m_jnd = exp2(x);
		break;
	}
	free(s), free(y), free(w), free(fv);
	return TL_OK;
}

static void fit_free(fit *f)
{
	free(f->kx), free(f->kd);
	memset(f, 0, sizeof *f);
}

double sty_model_t_at(const double *T, const double *m, size_t n, double m_jnd)
{
	if (n < 2 || !isfinite(m_jnd))
		return n >= 2 ? INFINITY : NAN;
	double lj = log2(m_jnd);
	/* metrics of 0 (identical clips) are far below any threshold: a floor keeps the logarithm finite */
	double lm0 = log2(fmax(m[0], 1e-12));
	if (lm0 >= lj)
		return 0;
	for (size_t i = 1; i < n; i++) {
		double lm1 = log2(fmax(m[i], 1e-12));
		if (lm1 >= lj) {
			double x0 = log2(T[i - 1]), x1 = log2(T[i]);
			return exp2(x0 + (lj - lm0) / (lm1 - lm0) * (x1 - x0));
		}
		lm0 = lm1;
	}
	return INFINITY;
}

/* Series [i, j) of sorted clips: their t_jnd for m_jnd (NAN when the series has no T). */
static double series_t(const clip_pt *p, size_t i, size_t j, double m_jnd)
{
	double T[64], m[64];
	size_t n = 0;
	for (size_t k = i; k < j && n < 64; k++)
		if (p[k].T > 0)
			T[n] = p[k].T, m[n] = p[k].m, n++;
	return sty_model_t_at(T, m, n, m_jnd);
}

/* ------------------------------------------------------------------ the run */

typedef struct measured {
	char method[32], scene[KEY_LEN], camera[KEY_LEN];
	long period;
	double t;
} measured;

typedef struct model {
	clip_pt *clips;
	size_t nclips;
	cond *c;
	size_t n;
	measured *meas;
	size_t nmeas;
} model;

static void model_free(model *m)
{
	free(m->clips), free(m->c), free(m->meas);
	memset(m, 0, sizeof *m);
}

static int load_tally(const char *dir, model *m, char *err, size_t err_size)
{
	char path[4096];
	snprintf(path, sizeof path, "%s/jod.csv", dir);
	csv_table t;
	int rc = csv_load(path, &t, err, err_size);
	if (rc)
		return rc;
	static const char *const jn[] = {"method", "T", "period", "scene", "camera", "jod", "participants", NULL};
	int c[7];
	if (!(rc = need_cols(&t, path, jn, c, err, err_size)) && !(m->c = calloc(t.rows + 1, sizeof *m->c)))
		rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	for (size_t r = 0; !rc && r < t.rows; r++) {
		double T = num(csv_at(&t, r, c[1])), per = num(csv_at(&t, r, c[2])), jod = num(csv_at(&t, r, c[5]));
		double w = num(csv_at(&t, r, c[6]));
		long period = isfinite(per) ? (long)per : 0;
		if (!isfinite(jod) || !(w > 0))
			continue;
		for (size_t k = 0; k < m->nclips; k++) { /* the clip of this condition (pooled rows match none) */
			const clip_pt *p = &m->clips[k];
			if (strcmp(p->method, csv_at(&t, r, c[0])) || p->period != period || strcmp(p->scene, csv_at(&t, r, c[3])) ||
			    strcmp(p->camera, csv_at(&t, r, c[4])) || !(p->T == T || (isnan(p->T) && isnan(T))))
				continue;
			if (p->m > 0)
				m->c[m->n++] = (cond){.clip = p, .x = log2(p->m), .d = -jod, .w = w};
			break;
		}
	}
	csv_free(&t);
	if (rc)
		return rc;
	snprintf(path, sizeof path, "%s/thresholds.csv", dir);
	if ((rc = csv_load(path, &t, err, err_size)))
		return rc;
	static const char *const tn[] = {"method", "period", "scene", "camera", "t_jnd", NULL};
	if (!(rc = need_cols(&t, path, tn, c, err, err_size)) && !(m->meas = calloc(t.rows + 1, sizeof *m->meas)))
		rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	for (size_t r = 0; !rc && r < t.rows; r++) {
		double tj = num(csv_at(&t, r, c[4])), per = num(csv_at(&t, r, c[1]));
		if (!(tj > 0) || !isfinite(tj) || !strcmp(csv_at(&t, r, c[2]), "all"))
			continue; /* open thresholds and the pooled rows */
		measured *q = &m->meas[m->nmeas++];
		snprintf(q->method, sizeof q->method, "%s", csv_at(&t, r, c[0]));
		snprintf(q->scene, sizeof q->scene, "%s", csv_at(&t, r, c[2]));
		snprintf(q->camera, sizeof q->camera, "%s", csv_at(&t, r, c[3]));
		q->period = isfinite(per) ? (long)per : 0;
		q->t = tj;
	}
	csv_free(&t);
	return rc;
}

static json_t *num_json(double v) { return isnan(v) ? json_null() : isinf(v) ? json_string(v > 0 ? "inf" : "-inf") : json_real(v); }

static int write_json_atomic(json_t *root, const char *path, char *err, size_t err_size)
{
	char tmp[4200];
	snprintf(tmp, sizeof tmp, "%s.tmp", path);
	if (json_dump_file(root, tmp, JSON_INDENT(1) | JSON_REAL_PRECISION(8)) || rename(tmp, path)) {
		remove(tmp);
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write", path);
	}
	return TL_OK;
}

/* Leave-one-scene-out: each rated scene's measured thresholds predicted by the model fitted without it. */
static int loso(const model *m, json_t *rows, sty_model_summary *s, char *err, size_t err_size)
{
	double sse = 0;
	for (size_t q = 0; q < m->nmeas; q++) {
		const measured *e = &m->meas[q];
		fit f;
		int rc = fit_model(m->c, m->n, e->scene, &f, err, err_size);
		if (rc)
			return rc;
		double tp = NAN;
		for (size_t i = 0; i < m->nclips;) {
			size_t j = i + 1;
			while (j < m->nclips && same_series(&m->clips[i], &m->clips[j]))
				j++;
			const clip_pt *p = &m->clips[i];
			if (!strcmp(p->method, e->method) && p->period == e->period && !strcmp(p->scene, e->scene) &&
			    !strcmp(p->camera, e->camera))
				tp = series_t(m->clips, i, j, f.m_jnd);
			i = j;
		}
		fit_free(&f);
		if (isnan(tp))
			continue; /* the sweep has no series for it */
		if (isfinite(tp) && tp > 0) {
			double e2 = log2(tp) - log2(e->t);
			sse += e2 * e2, s->loso_n++;
		} else
			s->loso_open++;
		json_array_append_new(rows, json_pack("{s:s, s:o, s:s, s:s, s:o, s:o}", "method", e->method, "period",
						      e->period ? json_integer(e->period) : json_null(), "scene", e->scene,
						      "camera", e->camera, "t_jnd_measured", num_json(e->t),
						      "t_jnd_predicted", num_json(tp)));
	}
	s->loso_rmse_log2 = s->loso_n ? sqrt(sse / (double)s->loso_n) : NAN;
	return TL_OK;
}

/* The predictions for every series of T (at least two levels) of `sweep`: t_jnd where the sweep's `metric` reaches
 * m_jnd, with t_jnd * 2^(+-half) (open without `half`). *out is malloc'ed. */
static int predict_rows(const char *sweep, const char *metric, double m_jnd, double half, sty_model_pred **out,
			size_t *count, char *err, size_t err_size)
{
	clip_pt *p = NULL;
	size_t n = 0;
	*out = NULL, *count = 0;
	int rc = load_sweep(sweep, metric, &p, &n, err, err_size);
	if (rc)
		return rc;
	if (!(*out = calloc(n + 1, sizeof **out))) {
		free(p);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	for (size_t i = 0; i < n;) {
		size_t j = i + 1;
		while (j < n && same_series(&p[i], &p[j]))
			j++;
		size_t levels = 0;
		for (size_t k = i; k < j; k++)
			levels += p[k].T > 0;
		if (levels >= 2) {
			double t = series_t(p, i, j, m_jnd);
			double lo = isfinite(half) && isfinite(t) && t > 0 ? t * exp2(-half) : 0;
			double hi = isfinite(half) && isfinite(t) && t > 0 ? t * exp2(half) : INFINITY;
			if (t == 0)
				hi = isfinite(half) ? p[i].T * exp2(half) : INFINITY; /* above m_jnd at the smallest T */
			if (isinf(t) && isfinite(half))
				lo = p[j - 1].T * exp2(-half);
			sty_model_pred *q = &(*out)[(*count)++];
			snprintf(q->method, sizeof q->method, "%s", p[i].method);
			snprintf(q->scene, sizeof q->scene, "%s", p[i].scene);
			snprintf(q->camera, sizeof q->camera, "%s", p[i].camera);
			q->period = p[i].period;
			q->t_jnd = t, q->t_jnd_lo = lo, q->t_jnd_hi = hi, q->levels = levels;
		}
		i = j;
	}
	free(p);
	return TL_OK;
}

const sty_model_pred *sty_model_pred_find(const sty_model_pred *p, size_t n, const char *method, long period,
					  const char *scene, const char *camera)
{
	for (size_t i = 0; i < n; i++)
		if (!strcmp(p[i].method, method) && p[i].period == period && !strcmp(p[i].scene, scene) &&
		    !strcmp(p[i].camera, camera))
			return &p[i];
	return NULL;
}

void sty_model_pred_cells(FILE *f, const sty_model_pred *p)
{
	char b[64];
	double q[3] = {p ? p->t_jnd : NAN, p ? p->t_jnd_lo : NAN, p ? p->t_jnd_hi : NAN};
	for (int k = 0; k < 3; k++)
		fprintf(f, ",%s", sty_num_cell(q[k], "%.4f", b, sizeof b));
}

/* Writes the predictions file (atomically) and appends them to `preds` (MODEL.json's "predictions"). */
static int write_predictions(const char *csv, const sty_model_pred *q, size_t n, json_t *preds, char *err,
			     size_t err_size)
{
	char tmp[4200];
	snprintf(tmp, sizeof tmp, "%s.tmp", csv);
	FILE *f = fopen(tmp, "w");
	if (!f)
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: %s", csv, strerror(errno));
	fprintf(f, "method,period,scene,camera,t_jnd,t_jnd_lo,t_jnd_hi,levels\n");
	for (size_t i = 0; i < n; i++) {
		char b[3][64], sc[KEY_LEN + 8], ca[KEY_LEN + 8], pe[32];
		snprintf(pe, sizeof pe, "%ld", q[i].period);
		fprintf(f, "%s,%s,%s,%s,%s,%s,%s,%zu\n", q[i].method, q[i].period ? pe : "",
			sty_csv_cell(q[i].scene, sc, sizeof sc), sty_csv_cell(q[i].camera, ca, sizeof ca),
			sty_num_cell(q[i].t_jnd, "%.4f", b[0], sizeof b[0]), sty_num_cell(q[i].t_jnd_lo, "%.4f", b[1], sizeof b[1]),
			sty_num_cell(q[i].t_jnd_hi, "%.4f", b[2], sizeof b[2]), q[i].levels);
		json_array_append_new(preds, json_pack("{s:s, s:o, s:s, s:s, s:o, s:o, s:o}", "method", q[i].method, "period",
						       q[i].period ? json_integer(q[i].period) : json_null(), "scene",
						       q[i].scene, "camera", q[i].camera, "t_jnd", num_json(q[i].t_jnd),
						       "t_jnd_lo", num_json(q[i].t_jnd_lo), "t_jnd_hi", num_json(q[i].t_jnd_hi)));
	}
	if (fclose(f) || rename(tmp, csv)) {
		remove(tmp);
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write", csv);
	}
	return TL_OK;
}

/* MODEL.json's numbers are written with 8 significant digits (write_json_atomic): the fit predicts with the values
 * as the file states them, so a saved model (--model) predicts exactly what the fit that wrote it did. */
static double as_stored(double v)
{
	if (!isfinite(v))
		return v;
	char b[64];
	snprintf(b, sizeof b, "%.8g", v);
	return strtod(b, NULL);
}

/* The predictions file: --predict-out, else MODEL.json's name with -predictions.csv. */
static void predictions_path(const sty_model_desc *d, char *csv, size_t size)
{
	if (d->predict_out) {
		snprintf(csv, size, "%s", d->predict_out);
		return;
	}
	size_t len = d->out ? strlen(d->out) : 0;
	if (len > 5 && !strcmp(d->out + len - 5, ".json"))
		len -= 5;
	snprintf(csv, size, "%.*s-predictions.csv", (int)len, d->out ? d->out : "model");
}

/* A saved model: what prediction needs from MODEL.json (the file's own JSON kept for --out). */
typedef struct saved {
	json_t *root;
	char metric[64];
	double m_jnd, half, rmse;
	json_int_t conditions, scenes, loso_n, loso_open;
} saved;

/* A number of MODEL.json as num_json writes it: a JSON number, "inf"/"-inf", or null (NAN; only where `null_ok`). */
static bool json_num(json_t *v, bool null_ok, double *out)
{
	const char *s = json_string_value(v);
	if (json_is_number(v))
		*out = json_number_value(v);
	else if (s && (!strcmp(s, "inf") || !strcmp(s, "-inf")))
		*out = s[0] == '-' ? -INFINITY : INFINITY;
	else if (null_ok && json_is_null(v))
		*out = NAN;
	else
		return false;
	return true;
}

/* MODEL.json read for option opt (--model, --prior) through tl_json_read: bounded in size and depth, regular files
 * only, and jansson's quote of the input made one line (a raw newline in a string was quoted into the message: found
 * by fuzz_model, 2026-11-27). TL_ERR_ARG with one line ("OPT: not a model: FILE: why") when it is not JSON. */
static int model_json_read(const char *opt, const char *path, json_t **root, char *err, size_t err_size)
{
	char why[PATH_MAX + 512]; /* tl_json_read's message names the file first */
	if (tl_json_read(path, root, why, sizeof why))
		return tl_error(err, err_size, TL_ERR_ARG, "%s: not a model: %s", opt, why);
	return TL_OK;
}

/* Reads and checks MODEL.json (`study model --out`). TL_ERR_ARG with one line naming the file and what is wrong:
 * not JSON, another format (a model written before --model, whose stored numbers are not the ones it predicted
 * with), or a missing or malformed member. */
static int model_load(const char *path, saved *m, char *err, size_t err_size)
{
	memset(m, 0, sizeof *m);
	int rc = model_json_read("--model", path, &m->root, err, err_size);
	if (rc)
		return rc;
	const char *why = NULL;
	json_t *r = m->root, *lo = json_object_get(r, "leave_one_scene_out");
	const char *format = json_string_value(json_object_get(r, "format"));
	const char *metric = json_string_value(json_object_get(r, "metric"));
	if (!json_is_object(r))
		why = "not a JSON object";
	else if (!format)
		why = "no \"format\": not a model of 'taslab study model', or one written before --model (fit it again "
		      "with --sweep --tally --out)";
	else if (strcmp(format, STY_MODEL_FORMAT))
		why = "another \"format\" than \"" STY_MODEL_FORMAT "\" (fit it again with --sweep --tally --out)";
	else if (!metric || !metric[0] || strlen(metric) >= sizeof m->metric || strchr(metric, '\n'))
		why = "\"metric\" is not a column name";
	else if (!json_num(json_object_get(r, "metric_at_1jnd"), false, &m->m_jnd) || !(m->m_jnd > 0))
		why = "\"metric_at_1jnd\" is not a positive number or \"inf\"";
	else if (!json_num(json_object_get(r, "interval_half_width_log2"), true, &m->half) || m->half < 0 ||
		 (isinf(m->half)))
		why = "\"interval_half_width_log2\" is not a number >= 0 or null";
	else if (!json_is_object(lo) || !json_num(json_object_get(lo, "rmse_log2_t_jnd"), true, &m->rmse))
		why = "no \"leave_one_scene_out\" error";
	if (why) {
		json_decref(m->root), m->root = NULL;
		return tl_error(err, err_size, TL_ERR_ARG, "--model %s: %s", path, why);
	}
	snprintf(m->metric, sizeof m->metric, "%s", metric);
	m->conditions = json_integer_value(json_object_get(r, "conditions"));
	m->scenes = json_integer_value(json_object_get(r, "scenes"));
	m->loso_n = json_integer_value(json_object_get(lo, "n"));
	m->loso_open = json_integer_value(json_object_get(lo, "open"));
	return TL_OK;
}

/* A sweep the saved model cannot predict (its metric not a column there, no summary.csv): the one line names the
 * model too, since the metric is the model's, not a --metric the user gave. */
static void saved_error(const char *model_json, const char *metric, char *err, size_t err_size)
{
	char why[1024];
	snprintf(why, sizeof why, "%s", err);
	tl_error(err, err_size, TL_ERR_ARG, "--model %s (metric %s): %s", model_json, metric, why);
}

int sty_model_predict(const char *model_json, const char *sweep, char *metric, size_t metric_size, sty_model_pred **out,
		      size_t *n, char *err, size_t err_size)
{
	saved m;
	*out = NULL, *n = 0;
	int rc = model_load(model_json, &m, err, err_size);
	if (rc)
		return rc;
	if (metric)
		snprintf(metric, metric_size, "%s", m.metric);
	if ((rc = predict_rows(sweep, m.metric, m.m_jnd, m.half, out, n, err, err_size)))
		saved_error(model_json, m.metric, err, err_size);
	json_decref(m.root);
	return rc;
}

/* --model MODEL.json --predict SWEEP2: predictions from a saved model, no fit; with --out a copy of the model holding
 * them (the prior of an adaptive design of SWEEP2's clips). */
static int run_saved(const sty_model_desc *d, sty_model_summary *s, char *err, size_t err_size)
{
	if (d->sweep || d->tally)
		return tl_error(err, err_size, TL_ERR_ARG, "--model predicts from a saved model: no --sweep or --tally "
			      "(those fit a new one)");
	if (!d->predict || (!d->out && !d->predict_out))
		return tl_error(err, err_size, TL_ERR_ARG, "--model MODEL.json needs --predict SWEEP2 and --predict-out CSV "
			      "or --out MODEL2.json");
	saved m;
	int rc = model_load(d->model, &m, err, err_size);
	if (rc)
		return rc;
	if (d->metric && strcmp(d->metric, m.metric))
		rc = tl_error(err, err_size, TL_ERR_ARG, "--metric %s: the model %s is fitted on %s", d->metric, d->model,
			      m.metric);
	s->m_jnd = m.m_jnd, s->loso_rmse_log2 = m.rmse;
	s->conditions = (size_t)m.conditions, s->scenes = (size_t)m.scenes;
	s->loso_n = (size_t)m.loso_n, s->loso_open = (size_t)m.loso_open;
	sty_model_pred *q = NULL;
	size_t n = 0;
	json_t *preds = json_array();
	char csv[4200];
	predictions_path(d, csv, sizeof csv);
	if (!rc && (rc = predict_rows(d->predict, m.metric, m.m_jnd, m.half, &q, &n, err, err_size)))
		saved_error(d->model, m.metric, err, err_size);
	if (!rc)
		rc = write_predictions(csv, q, n, preds, err, err_size);
	s->predictions = n;
	if (!rc && d->out) {
		json_object_set_new(m.root, "predicted_sweep", json_string(d->predict));
		json_object_set(m.root, "predictions", preds);
		rc = write_json_atomic(m.root, d->out, err, err_size);
	}
	free(q);
	json_decref(preds);
	json_decref(m.root);
	return rc;
}

int sty_model_run(const sty_model_desc *d, sty_model_summary *s, char *err, size_t err_size)
{
	memset(s, 0, sizeof *s);
	s->loso_rmse_log2 = NAN;
	if (d->model)
		return run_saved(d, s, err, err_size);
	if (!d->sweep || !d->tally)
		return tl_error(err, err_size, TL_ERR_ARG, "need --sweep SWEEP and --tally DIR (or --model MODEL.json)");
	const char *metric = d->metric ? d->metric : "flip_mean";
	model m = {0};
	fit f = {0};
	json_t *root = json_object(), *knots = json_array(), *rows = json_array(), *preds = json_array();
	int rc = load_sweep(d->sweep, metric, &m.clips, &m.nclips, err, err_size);
	if (!rc)
		rc = load_tally(d->tally, &m, err, err_size);
	if (!rc && m.n < 2)
		rc = tl_error(err, err_size, TL_ERR_INPUT, "%s/jod.csv and %s/summary.csv share %zu condition(s) with a "
			      "positive %s (method, T, period, scene, camera): need at least two", d->tally, d->sweep, m.n,
			      metric);
	if (!rc)
		rc = fit_model(m.c, m.n, NULL, &f, err, err_size);
	if (!rc) {
		s->conditions = m.n;
		s->m_jnd = f.m_jnd = as_stored(f.m_jnd);
		for (size_t i = 0; i < m.n; i++) {
			bool seen = false;
			for (size_t j = 0; j < i && !seen; j++)
				seen = !strcmp(m.c[i].clip->scene, m.c[j].clip->scene);
			s->scenes += !seen;
		}
		for (size_t i = 0; i < f.k; i++)
			json_array_append_new(knots, json_pack("[f, f]", exp2(f.kx[i]), f.kd[i]));
		rc = loso(&m, rows, s, err, err_size);
	}
	/* NAN without a leave-one-scene-out error: open intervals */
	double half = as_stored(1.959964 * s->loso_rmse_log2);
	if (!rc && d->predict) {
		char csv[4200];
		sty_model_pred *q = NULL;
		size_t n = 0;
		predictions_path(d, csv, sizeof csv);
		rc = predict_rows(d->predict, metric, f.m_jnd, half, &q, &n, err, err_size);
		if (!rc)
			rc = write_predictions(csv, q, n, preds, err, err_size);
		s->predictions = n;
		free(q);
	}
	if (!rc && d->out) {
		json_object_set_new(root, "format", json_string(STY_MODEL_FORMAT));
		json_object_set_new(root, "metric", json_string(metric));
		json_object_set_new(root, "fit", json_string("isotonic regression of -JOD on log2 metric, weighted by "
							     "participants; knots interpolated linearly in log2 metric"));
		json_object_set_new(root, "sweep", json_string(d->sweep));
		json_object_set_new(root, "tally", json_string(d->tally));
		json_object_set_new(root, "conditions", json_integer((json_int_t)s->conditions));
		json_object_set_new(root, "scenes", json_integer((json_int_t)s->scenes));
		json_object_set_new(root, "metric_at_1jnd", num_json(f.m_jnd));
		json_object_set_new(root, "knots", knots), knots = NULL;
		json_t *lo = json_pack("{s:o, s:I, s:I, s:o}", "rmse_log2_t_jnd", num_json(s->loso_rmse_log2), "n",
				       (json_int_t)s->loso_n, "open", (json_int_t)s->loso_open, "rows", rows);
		rows = NULL;
		json_object_set_new(root, "leave_one_scene_out", lo);
		json_object_set_new(root, "interval_half_width_log2", num_json(half));
		if (d->predict) {
			json_object_set_new(root, "predicted_sweep", json_string(d->predict));
			json_object_set_new(root, "predictions", preds), preds = NULL;
		}
		rc = write_json_atomic(root, d->out, err, err_size);
	}
	json_decref(root), json_decref(knots), json_decref(rows), json_decref(preds);
	fit_free(&f);
	model_free(&m);
	return rc;
}

int sty_model_prior(const char *model_json, const char *method, long period, const char *scene, const char *camera,
		    double *theta, double *sd, char *err, size_t err_size)
{
	json_t *root = NULL;
	int rc = model_json_read("--prior", model_json, &root, err, err_size);
	if (rc)
		return rc;
	json_t *preds = json_object_get(root, "predictions");
	double half = json_number_value(json_object_get(root, "interval_half_width_log2"));
	if (!json_is_array(preds) || !json_is_number(json_object_get(root, "interval_half_width_log2"))) {
		json_decref(root);
		return tl_error(err, err_size, TL_ERR_ARG, "--prior %s: no predictions with an interval (write the model "
			      "with --predict SWEEP, the sweep of the study's clips)", model_json);
	}
	int found = 0;
	size_t i;
	json_t *p;
	json_array_foreach(preds, i, p)
	{
		json_t *per = json_object_get(p, "period"), *t = json_object_get(p, "t_jnd");
		long pv = json_is_integer(per) ? (long)json_integer_value(per) : 0;
		const char *pm = json_string_value(json_object_get(p, "method"));
		const char *ps = json_string_value(json_object_get(p, "scene"));
		const char *pc = json_string_value(json_object_get(p, "camera"));
		if (!pm || !ps || !pc || strcmp(pm, method) || strcmp(ps, scene) || strcmp(pc, camera) || pv != period)
			continue;
		if (json_is_number(t) && json_number_value(t) > 0) {
			*theta = log2(json_number_value(t));
			*sd = half / 1.959964;
			found = 1;
		}
		break;
	}
	json_decref(root);
	return found;
}
