/* reuse_model.c — the survey's error, cost and hit-rate models of reuse ([S] sec. 4.1, eqs. 5-7) fitted to a sweep
 * (taslab/reuse_model.h; BASELINES.md A5). */
#include "taslab/reuse_model.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/run.h"
#include "taslab/tl_fs.h"
#include "taslab/tl_json.h"

/* ------------------------------------------------------------------ eq. 5 */

/* The sum of squared residuals of eq. 5 at λ, with α at its least-squares value for that λ. */
static double eq5_sse(const double *dn, const double *eps, size_t n, double lambda, double *alpha)
{
	double yg = 0, gg = 0, yy = 0;
	for (size_t i = 0; i < n; i++) {
		if (!(dn[i] >= 1) || !isfinite(eps[i]))
			continue;
		double g = 1.0 - exp(-lambda * (dn[i] - 1.0));
		yg += eps[i] * g, gg += g * g, yy += eps[i] * eps[i];
	}
	*alpha = gg > 0 ? yg / gg : NAN;
	return gg > 0 ? yy - yg * yg / gg : yy; /* Σ (y - α g)² at the optimal α */
}

void mtr_fit_eq5(const double *dn, const double *eps, size_t n, mtr_eq5 *out)
{
	*out = (mtr_eq5){.alpha = NAN, .lambda = NAN, .rmse = NAN};
	size_t points = 0, distinct = 0;
	for (size_t i = 0; i < n; i++) {
		if (!(dn[i] >= 1) || !isfinite(eps[i]))
			continue;
		points++;
		bool seen = false;
		for (size_t k = 0; k < i; k++)
			seen |= dn[k] == dn[i] && dn[k] >= 1 && isfinite(eps[k]);
		distinct += dn[i] > 1 && !seen;
	}
	if (distinct < 2)
		return;
	/* λ on a log grid of 0.025 decades over [1e-4, 1e3], then golden-section search around the best node */
	enum { STEPS = 280 };
	const double lo = -4.0, step = 7.0 / STEPS;
	double best = INFINITY, best_x = lo, a;
	for (int k = 0; k <= STEPS; k++) {
		double x = lo + step * k, e = eq5_sse(dn, eps, n, pow(10.0, x), &a);
		if (e < best)
			best = e, best_x = x;
	}
	double l = fmax(lo, best_x - step), r = fmin(lo + STEPS * step, best_x + step);
	const double phi = 0.6180339887498949;
	for (int it = 0; it < 80; it++) {
		double x1 = r - phi * (r - l), x2 = l + phi * (r - l);
		if (eq5_sse(dn, eps, n, pow(10.0, x1), &a) <= eq5_sse(dn, eps, n, pow(10.0, x2), &a))
			r = x2;
		else
			l = x1;
	}
	double x = 0.5 * (l + r), sse = eq5_sse(dn, eps, n, pow(10.0, x), &a);
	if (sse > best) /* the grid node was better (a flat or multimodal SSE) */
		x = best_x, sse = eq5_sse(dn, eps, n, pow(10.0, x), &a);
	out->lambda = pow(10.0, x);
	out->alpha = a;
	out->rmse = sqrt(fmax(sse, 0.0) / (double)points);
	out->ok = isfinite(a);
}

/* ------------------------------------------------------------------ eq. 6 */

void mtr_fit_eq6(const double *hits, const double *misses, const double *dt, size_t n, mtr_eq6 *out)
{
	*out = (mtr_eq6){.a_hit = NAN, .a_miss = NAN, .miss_minus_hit = NAN, .c = NAN, .r2 = NAN, .frames = n};
	if (n < 4)
		return;
	/* centred sums: the slopes from the 2x2 normal equations, the constant from the means (numerically stable) */
	double mh = 0, mm = 0, mt = 0;
	for (size_t i = 0; i < n; i++)
		mh += hits[i], mm += misses[i], mt += dt[i];
	mh /= (double)n, mm /= (double)n, mt /= (double)n;
	double shh = 0, smm = 0, shm = 0, sht = 0, smt = 0, stt = 0, svv = 0;
	for (size_t i = 0; i < n; i++) {
		double h = hits[i] - mh, m = misses[i] - mm, t = dt[i] - mt, v = h + m;
		shh += h * h, smm += m * m, shm += h * m, sht += h * t, smt += m * t, stt += t * t, svv += v * v;
	}
	if (!(smm > 0))
		return;
	double det = shh * smm - shm * shm, mean_v = mh + mm;
	double cv_v = mean_v > 0 ? sqrt(svv / (double)n) / mean_v : 0;
	double sse;
	if (cv_v >= 0.02 && !(det > 1e-6 * shh * smm))
		return; /* H and M collinear while V varies (one period: H ≈ k M): neither form is determined */
	if (cv_v >= 0.02) {
		out->three_terms = true;
		out->a_hit = (sht * smm - smt * shm) / det;
		out->a_miss = (smt * shh - sht * shm) / det;
		out->miss_minus_hit = out->a_miss - out->a_hit;
		out->c = mt - out->a_hit * mh - out->a_miss * mm;
		sse = stt - out->a_hit * sht - out->a_miss * smt;
	} else { /* H + M ≈ V constant: Δt = c' + M (A_miss − A_hit) */
		out->miss_minus_hit = smt / smm;
		out->c = mt - out->miss_minus_hit * mm;
		sse = stt - out->miss_minus_hit * smt;
	}
	out->r2 = stt > 0 ? 1.0 - fmax(sse, 0.0) / stt : NAN;
	out->ok = true;
}

double mtr_fit_hit_rate(const double *dn, const double *rate, size_t n)
{
	double hg = 0, gg = 0;
	for (size_t i = 0; i < n; i++)
		if (dn[i] > 1 && isfinite(rate[i])) {
			double g = 1.0 - 1.0 / dn[i];
			hg += rate[i] * g, gg += g * g;
		}
	return gg > 0 ? hg / gg : NAN;
}

/* ------------------------------------------------------------------ a sweep */

typedef struct series {
	double *h, *m, *t;
	size_t n, cap;
} series;

static int push(series *s, double h, double m, double t) /* TL_ERR_NOMEM when it cannot grow */
{
	if (s->n == s->cap) {
		size_t cap = s->cap ? 2 * s->cap : 256;
		double *h2 = realloc(s->h, cap * sizeof *h2);
		if (h2)
			s->h = h2;
		double *m2 = realloc(s->m, cap * sizeof *m2);
		if (m2)
			s->m = m2;
		double *t2 = realloc(s->t, cap * sizeof *t2);
		if (t2)
			s->t = t2;
		if (!h2 || !m2 || !t2)
			return TL_ERR_NOMEM;
		s->cap = cap;
	}
	s->h[s->n] = h, s->m[s->n] = m, s->t[s->n] = t;
	s->n++;
	return TL_OK;
}

/* The variant token without its "/N" period (rrc-random/4 -> rrc-random): the group's name. */
static void group_name(const char *variant, char *out, size_t n)
{
	const char *slash = strchr(variant, '/');
	size_t len = slash ? (size_t)(slash - variant) : strlen(variant);
	const char *rest = slash ? slash + 1 + strspn(slash + 1, "0123456789") : "";
	snprintf(out, n, "%.*s%s", (int)len, variant, rest);
}

/* One run: its error from summary.json, its frames (after the first) into the group's series. 1: not complete. */
static int read_run(const sweep_spec *s, const char *dir, const sweep_run *r, const char *key, mtr_reuse_point *p,
		    series *f, char *err, size_t err_size)
{
	sweep_status st;
	char why[256], path[TL_PATH_MAX + 16];
	sweep_run_status_checked(s, dir, r, &st, why, sizeof why);
	if (!st.run || !st.metrics)
		return 1;
	sweep_run_path(s, dir, r, SWEEP_PATH_METRICS, path, sizeof path);
	strncat(path, "/summary.json", sizeof path - strlen(path) - 1);
	json_t *j = NULL;
	int rc = tl_json_read(path, &j, err, err_size);
	if (rc)
		return rc;
	json_t *v = json_object_get(j, key);
	if (!json_is_number(v) && !json_is_null(v)) {
		json_decref(j);
		return tl_error(err, err_size, TL_ERR_INPUT,
				"--error %s: not a number in %s (try maxrgb_mean, flip_mean or exceed_8)", key, path);
	}
	p->eps = json_is_number(v) ? json_number_value(v) : NAN; /* null: not computed for this run (left out of eq. 5) */
	json_decref(j);
	run_stats rs;
	sweep_run_path(s, dir, r, SWEEP_PATH_RUN, path, sizeof path);
	if ((rc = run_stats_read(path, &rs, err, err_size)))
		return rc;
	double sh = 0, sv = 0, sms = 0;
	size_t k = 0;
	for (size_t row = 1; row < rs.rows; row++) { /* frame 0 of the run: a full shading and first-frame costs */
		double h = run_stats_get(&rs, row, "reused_samples"), m = run_stats_get(&rs, row, "shaded_samples");
		double t = run_stats_get(&rs, row, "gpu_ms_total");
		if (!isfinite(h) || !isfinite(m) || !isfinite(t))
			continue;
		if (push(f, h, m, t)) {
			run_stats_free(&rs);
			return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		}
		sh += h, sv += h + m, sms += t, k++;
	}
	run_stats_free(&rs);
	p->dn = s->variants[r->variant].period;
	p->variant = r->variant;
	p->hit_rate = sv > 0 ? sh / sv : NAN;
	p->ms = k ? sms / (double)k : NAN;
	p->visible = k ? sv / (double)k : NAN;
	return TL_OK;
}

/* The runs of method `name` on (scene, camera) into g, fitted. */
static int fit_group(const sweep_spec *s, const char *dir, const char *key, size_t sc, size_t cam, size_t v0,
		     bool *done, series *f, mtr_reuse_group *g, char *err, size_t err_size)
{
	memset(g, 0, sizeof *g);
	g->scene = sc, g->camera = cam;
	group_name(s->variants[v0].variant, g->name, sizeof g->name);
	f->n = 0;
	for (size_t v = v0; v < s->variant_count; v++) {
		char other[SWEEP_NAME_MAX];
		group_name(s->variants[v].variant, other, sizeof other);
		if (!s->variants[v].period || strcmp(g->name, other))
			continue;
		done[v] = true;
		/* the run's folders and status need its scene, camera and variant only (a variant with a period is no ref) */
		const sweep_run r = {.scene = sc, .camera = cam, .variant = v};
		int got = read_run(s, dir, &r, key, &g->pts[g->np], f, err, err_size);
		if (got < 0)
			return got;
		g->np += got == 0;
	}
	double dn[SWEEP_MAX_VARIANTS], eps[SWEEP_MAX_VARIANTS], hr[SWEEP_MAX_VARIANTS];
	for (size_t i = 0; i < g->np; i++)
		dn[i] = g->pts[i].dn, eps[i] = g->pts[i].eps, hr[i] = g->pts[i].hit_rate;
	mtr_fit_eq5(dn, eps, g->np, &g->e5);
	mtr_fit_eq6(f->h, f->m, f->t, f->n, &g->e6);
	g->mu = mtr_fit_hit_rate(dn, hr, g->np);
	return TL_OK;
}

int mtr_reuse_fit(const sweep_spec *s, const char *dir, const char *error_key, mtr_reuse_group **groups, size_t *n,
		  char *err, size_t err_size)
{
	*groups = NULL, *n = 0;
	series f = {0};
	mtr_reuse_group *out = NULL, g;
	size_t cap = 0;
	int rc = TL_OK;
	bool done[SWEEP_MAX_VARIANTS];
	for (size_t sc = 0; !rc && sc < s->scene_count; sc++)
		for (size_t cam = 0; !rc && cam < s->scenes[sc].camera_count; cam++) {
			memset(done, 0, sizeof done);
			for (size_t v0 = 0; !rc && v0 < s->variant_count; v0++) {
				if (!s->variants[v0].period || done[v0])
					continue;
				if ((rc = fit_group(s, dir, error_key, sc, cam, v0, done, &f, &g, err, err_size)) || !g.np)
					continue;
				if (*n == cap) {
					cap = cap ? 2 * cap : 8;
					mtr_reuse_group *o2 = realloc(out, cap * sizeof *o2);
					if (!o2) {
						rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
						break;
					}
					out = o2;
				}
				out[(*n)++] = g;
			}
		}
	free(f.h), free(f.m), free(f.t);
	if (rc) {
		free(out);
		*n = 0;
		return rc;
	}
	*groups = out;
	return TL_OK;
}

double mtr_reuse_eps(const mtr_reuse_group *g, double dn)
{
	return g->e5.ok ? g->e5.alpha * (1.0 - exp(-g->e5.lambda * (dn - 1.0))) : NAN;
}

double mtr_reuse_hit_rate(const mtr_reuse_group *g, double dn)
{
	return g->mu * (1.0 - 1.0 / dn);
}

double mtr_reuse_ms(const mtr_reuse_group *g, double dn, double visible)
{
	const mtr_eq6 *c = &g->e6;
	double h = mtr_reuse_hit_rate(g, dn), misses = visible * (1.0 - h);
	if (!c->ok || !isfinite(h))
		return NAN;
	if (c->three_terms)
		return c->c + visible * h * c->a_hit + misses * c->a_miss;
	return c->c + misses * c->miss_minus_hit;
}

static void cell(FILE *f, double v, const char *fmt)
{
	if (isfinite(v))
		fprintf(f, fmt, v);
}

int mtr_reuse_write(const sweep_spec *s, const char *dir, const char *error_key, const mtr_reuse_group *gs, size_t n,
		    const char *out_dir, char *err, size_t err_size)
{
	char csv_path[TL_PATH_MAX + 32], md_path[TL_PATH_MAX + 32];
	snprintf(csv_path, sizeof csv_path, "%s/reuse_model.csv", out_dir);
	snprintf(md_path, sizeof md_path, "%s/reuse_model.md", out_dir);
	tl_atomic csv = {0}, md = {0};
	int rc = tl_atomic_open(&csv, csv_path, err, err_size);
	if (!rc)
		rc = tl_atomic_open(&md, md_path, err, err_size);
	if (rc) {
		tl_atomic_abort(&csv);
		return rc;
	}
	fprintf(csv.f, "scene,camera,method,period,error_key,error,error_model,hit_rate,hit_rate_model,ms,ms_model,alpha,"
		       "lambda,error_rmse,mu,a_hit_ns,a_miss_ns,miss_minus_hit_ns,c_ms,r2,frames_fitted\n");
	fprintf(md.f, "# Reuse models of %s ([S] sec. 4.1, eqs. 5-7)\n\nError: the clip mean of `%s` against ref; cost: "
		      "GPU ms per frame over each run's frames after the first; hits = reused samples, misses = shaded "
		      "samples.\n",
		dir, error_key);
	for (size_t k = 0; k < n; k++) {
		const mtr_reuse_group *g = &gs[k];
		const mtr_eq5 *e5 = &g->e5;
		const mtr_eq6 *e6 = &g->e6;
		const char *scn = s->scenes[g->scene].name, *cn = s->scenes[g->scene].cameras[g->camera].name;
		fprintf(md.f, "\n## %s / %s / %s\n\n", scn, cn, g->name);
		if (e5->ok)
			fprintf(md.f, "eq. 5: α = %.4g, λ = %.4g (RMSE %.3g)%s; ", e5->alpha, e5->lambda, e5->rmse,
				e5->rmse <= 1e-9 * fabs(e5->alpha) ? ", exact (two periods)" : "");
		else
			fprintf(md.f, "eq. 5: not determined (needs two periods > 1); ");
		fprintf(md.f, "eq. 7: μ = ");
		cell(md.f, g->mu, "%.4f");
		fprintf(md.f, "; eq. 6 over %zu frames: ", e6->frames);
		if (!e6->ok)
			fprintf(md.f, "not determined (fewer than 4 frames, misses that do not vary, or hits and misses in "
				      "proportion: one period)\n");
		else if (e6->three_terms)
			fprintf(md.f, "A_hit = %.0f ns, A_miss = %.0f ns per sample, c = %.1f ms (R² %.3f)\n", e6->a_hit * 1e6,
				e6->a_miss * 1e6, e6->c, e6->r2);
		else
			fprintf(md.f, "A_miss − A_hit = %.0f ns per sample, c + A_hit·V = %.1f ms (R² %.3f; hits + misses "
				      "hardly vary, so A_hit and c are not separable)\n",
				e6->miss_minus_hit * 1e6, e6->c, e6->r2);
		fprintf(md.f, "\n| Δn | %s | eq. 5 | hit rate | eq. 7 | ms | eqs. 6+7 |\n", error_key);
		fprintf(md.f, "|---:|---:|---:|---:|---:|---:|---:|\n");
		for (size_t i = 0; i < g->np; i++) {
			const mtr_reuse_point *p = &g->pts[i];
			double em = mtr_reuse_eps(g, p->dn), hm = mtr_reuse_hit_rate(g, p->dn);
			double mm = mtr_reuse_ms(g, p->dn, p->visible);
			fprintf(csv.f, "%s,%s,%s,%g,%s,", scn, cn, g->name, p->dn, error_key);
			cell(csv.f, p->eps, "%.6g");
			fputc(',', csv.f);
			cell(csv.f, em, "%.6g");
			fputc(',', csv.f);
			cell(csv.f, p->hit_rate, "%.6f");
			fputc(',', csv.f);
			cell(csv.f, hm, "%.6f");
			fputc(',', csv.f);
			cell(csv.f, p->ms, "%.4f");
			fputc(',', csv.f);
			cell(csv.f, mm, "%.4f");
			const double vals[] = {e5->alpha, e5->lambda, e5->rmse, g->mu, e6->a_hit * 1e6, e6->a_miss * 1e6,
					       e6->miss_minus_hit * 1e6, e6->c, e6->r2};
			for (size_t q = 0; q < sizeof vals / sizeof vals[0]; q++) {
				fputc(',', csv.f);
				cell(csv.f, vals[q], "%.6g");
			}
			fprintf(csv.f, ",%zu\n", e6->frames);
			const double row[] = {p->eps, em, p->hit_rate, hm, p->ms, mm};
			const char *const fmt[] = {"%.4g", "%.4g", "%.3f", "%.3f", "%.1f", "%.1f"};
			fprintf(md.f, "| %g |", p->dn);
			for (size_t q = 0; q < 6; q++) {
				fputc(' ', md.f);
				cell(md.f, row[q], fmt[q]);
				fputs(isfinite(row[q]) ? " |" : "– |", md.f);
			}
			fputc('\n', md.f);
		}
	}
	tl_atomic both[2] = {csv, md};
	return tl_atomic_commit_set(both, 2, err, err_size);
}

int mtr_reuse_model(const sweep_spec *s, const char *dir, const char *error_key, const char *out_dir, size_t *groups,
		    char *err, size_t err_size)
{
	mtr_reuse_group *g = NULL;
	int rc = mtr_reuse_fit(s, dir, error_key, &g, groups, err, err_size);
	if (!rc && !*groups)
		rc = tl_error(err, err_size, TL_ERR_INPUT,
			      "%s: no complete run of a method with a period (rrc/N, rrc-random/N, rrc-interleaved/N, sau/N, "
			      "stu/N, warp/N) with its metrics: sweep one first",
			      dir);
	if (!rc)
		rc = mtr_reuse_write(s, dir, error_key, g, *groups, out_dir, err, err_size);
	free(g);
	return rc;
}
