/* study_report.c — SWEEP/report/index.html: the sweep's metrics per scene and camera path, with plots against T,
 * Table 1, images, synchronised clip pairs, and a study's tallies per condition (study_report.h; DESIGN section 9).
 *
 * The page is self-contained (inline CSS and script, no network) and refers only to files under the sweep folder by
 * relative paths, so it opens from disk (file://) offline. Plots are SVG drawn by gnuplot (metrics.h mtr_plot_*). */
#include "taslab/study_report.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "taslab/imageio.h"
#include "taslab/metrics.h"
#include "taslab/study.h"
#include "taslab/tl_clock.h"
#include "taslab/tl_fs.h"

/* ------------------------------------------------------------------ small helpers */

static void esc(FILE *f, const char *s)
{
	for (; *s; s++)
		switch (*s) {
		case '<': fputs("&lt;", f); break;
		case '>': fputs("&gt;", f); break;
		case '&': fputs("&amp;", f); break;
		case '"': fputs("&quot;", f); break;
		case '\'': fputs("&#39;", f); break;
		default: fputc(*s, f);
		}
}

/* A value for a table cell: "–" when not available. */
static void cellf(FILE *f, double v, const char *fmt)
{
	fputs("<td>", f);
	if (isfinite(v))
		fprintf(f, fmt, v);
	else
		fputs("–", f);
	fputs("</td>", f);
}

/* Table cells: a summary column and its format, NULL-terminated. */
typedef struct cell_def {
	const char *column, *fmt;
} cell_def;

static const cell_def TABLE1_CELLS[] = {{"shaded_per_frame", "%.0f"}, {"reduction_percent", "%.2f %%"},
					 {"reuse_percent", "%.2f %%"}, {"speedup_vs_ref", "%.2f×"}, {NULL, NULL}};
static const cell_def RUN_CELLS[] = {{"reuse_percent", "%.1f %%"}, {"reduction_percent", "%.1f %%"},
				      {"speedup_vs_ref", "%.2f×"},  {"exceed_T", "%.5f"},
				      {"exceed_8", "%.5f"},         {"maxrgb_p99", "%.2f"},
				      {"flicker_mean", "%.3f"},     {"flip_mean", "%.4f"},
				      {"psnr", "%.1f dB"},          {"late_percent", "%.3f %%"},
				      {NULL, NULL}};

static void cells(FILE *f, const mtr_sweep_row *r, const cell_def *c)
{
	for (; c->column; c++)
		cellf(f, mtr_sweep_value(r, c->column), c->fmt);
}

/* File-name stem of a scene/camera group. */
static void group_stem(const sweep_spec *s, size_t scene, size_t cam, char *out, size_t n)
{
	snprintf(out, n, "%s--%s", s->scenes[scene].name, s->scenes[scene].cameras[cam].name);
}

/* One study condition (a row of the tally's conditions.csv). */
typedef struct cond {
	char method[32], scene[64], camera[64];
	double T;
	unsigned period;   /* 0: none, or the tally has no period column */
	bool has_period;
	double n, Q, Q_lo, Q_hi, p, p_lo, p_hi, jnd, jnd_lo, jnd_hi;
} cond;

typedef struct study_tab {
	cond *c;
	size_t n;
} study_tab;

/* JND from p clamped half an observation from 0 and 1 (metrics.h, the study's convention). */
static double jnd_of(double p, double n)
{
	if (!isfinite(p) || !(n > 0))
		return NAN;
	double lo = 1 / (2 * n), hi = 1 - lo;
	return mtr_jnd_from_p(p < lo ? lo : p > hi ? hi : p);
}

/* Splits a CSV line in place (the tally writes plain cells for these columns; quoted cells are unquoted). */
static size_t split_csv(char *line, char **cells, size_t max)
{
	size_t n = 0;
	char *p = line;
	while (n < max) {
		if (*p == '"') {
			char *o = ++p, *w = p;
			while (*p && !(*p == '"' && p[1] != '"'))
				*w++ = (*p == '"' ? (p++, '"') : *p), p++;
			*w = 0;
			cells[n++] = o;
			if (*p == '"')
				p++;
			if (*p != ',')
				break;
			p++;
			continue;
		}
		cells[n++] = p;
		char *c = strchr(p, ',');
		if (!c)
			break;
		*c = 0;
		p = c + 1;
	}
	return n;
}

static int load_study(const char *db, const char *out, study_tab *t, char *err, size_t err_size)
{
	sty *s = NULL;
	memset(t, 0, sizeof *t);
	int rc = sty_open(db, &s, err, err_size);
	if (rc)
		return rc;
	sty_tally_desc td = {.out = out, .bootstrap = 200, .seed = 1, .no_plot = true};
	rc = sty_tally(s, &td, err, err_size);
	sty_close(&s);
	if (rc)
		return rc;
	char path[TL_PATH_MAX], *text = NULL;
	size_t len;
	snprintf(path, sizeof path, "%s/conditions.csv", out);
	if ((rc = tl_read_file(path, 64u << 20, &text, &len, err, err_size)))
		return rc;
	size_t lines = 0;
	for (size_t i = 0; i < len; i++)
		lines += text[i] == '\n';
	t->c = calloc(lines + 1, sizeof *t->c);
	if (!t->c) {
		free(text);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	/* columns by name: the tally may gain columns (period) without breaking this */
	enum { C_METHOD, C_T, C_PERIOD, C_SCENE, C_CAMERA, C_N, C_Q, C_QLO, C_QHI, C_P, C_PLO, C_PHI, C_JND, C_COUNT };
	static const char *const names[C_COUNT] = {"method", "T", "period", "scene", "camera", "n", "Q",
						   "Q_lo", "Q_hi", "p_ref", "p_ref_lo", "p_ref_hi", "jnd"};
	int col[C_COUNT];
	for (int k = 0; k < C_COUNT; k++)
		col[k] = -1;
	char *save = NULL;
	bool header = true;
	for (char *l = strtok_r(text, "\r\n", &save); l; l = strtok_r(NULL, "\r\n", &save)) {
		char *cells[64];
		size_t nc = split_csv(l, cells, 64);
		if (header) {
			for (size_t i = 0; i < nc; i++)
				for (int k = 0; k < C_COUNT; k++)
					if (!strcmp(cells[i], names[k]))
						col[k] = (int)i;
			header = false;
			if (col[C_METHOD] < 0 || col[C_SCENE] < 0 || col[C_CAMERA] < 0 || col[C_P] < 0) {
				free(text);
				return tl_error(err, err_size, TL_ERR_INPUT, "%s: no method/scene/camera/p_ref columns", path);
			}
			continue;
		}
		cond *c = &t->c[t->n];
#define CELL(k) (col[k] >= 0 && (size_t)col[k] < nc ? cells[col[k]] : "")
#define NUM(k) (*CELL(k) ? strtod(CELL(k), NULL) : NAN)
		snprintf(c->method, sizeof c->method, "%s", CELL(C_METHOD));
		snprintf(c->scene, sizeof c->scene, "%s", CELL(C_SCENE));
		snprintf(c->camera, sizeof c->camera, "%s", CELL(C_CAMERA));
		c->T = NUM(C_T);
		c->has_period = col[C_PERIOD] >= 0;
		c->period = c->has_period && *CELL(C_PERIOD) ? (unsigned)strtoul(CELL(C_PERIOD), NULL, 10) : 0;
		c->n = NUM(C_N), c->Q = NUM(C_Q), c->Q_lo = NUM(C_QLO), c->Q_hi = NUM(C_QHI);
		c->p = NUM(C_P), c->p_lo = NUM(C_PLO), c->p_hi = NUM(C_PHI);
		/* the tally's JND; its interval maps the Wilson interval of p_ref (Phi^-1 is monotone) */
		c->jnd = col[C_JND] >= 0 ? NUM(C_JND) : jnd_of(c->p, c->n);
		c->jnd_lo = jnd_of(c->p_lo, c->n), c->jnd_hi = jnd_of(c->p_hi, c->n);
#undef NUM
#undef CELL
		t->n++;
	}
	free(text);
	return TL_OK;
}

/* The study condition of a run: same method, T, period (when the tally has it), scene and camera. Without a period
 * column, a method swept at several periods cannot be matched (NULL). */
static const cond *find_cond(const study_tab *t, const sweep_spec *s, const mtr_sweep_row *r)
{
	const sweep_variant *v = &s->variants[r->run.variant];
	const sweep_scene *sc = &s->scenes[r->run.scene];
	const cond *hit = NULL;
	int hits = 0;
	for (size_t i = 0; i < t->n; i++) {
		const cond *c = &t->c[i];
		if (strcmp(c->method, v->method) || strcmp(c->scene, sc->name) || strcmp(c->camera, sc->cameras[r->run.camera].name))
			continue;
		if (isfinite(v->T) != isfinite(c->T) || (isfinite(v->T) && fabs(v->T - c->T) > 1e-9))
			continue;
		if (c->has_period && c->period != v->period)
			continue;
		hit = c, hits++;
	}
	return hits == 1 ? hit : NULL;
}

/* ------------------------------------------------------------------ images */

/* Integer box downscale so the width is at most `max_w`. */
static uint8_t *downscale(const uint8_t *rgb, uint32_t w, uint32_t h, uint32_t max_w, uint32_t *ow, uint32_t *oh)
{
	uint32_t k = (w + max_w - 1) / max_w;
	if (k < 1)
		k = 1;
	*ow = w / k ? w / k : 1, *oh = h / k ? h / k : 1;
	uint8_t *out = malloc((size_t)*ow * *oh * 3);
	if (!out)
		return NULL;
	for (uint32_t y = 0; y < *oh; y++)
		for (uint32_t x = 0; x < *ow; x++)
			for (int c = 0; c < 3; c++) {
				unsigned sum = 0, cnt = 0;
				for (uint32_t dy = 0; dy < k && y * k + dy < h; dy++)
					for (uint32_t dx = 0; dx < k && x * k + dx < w; dx++, cnt++)
						sum += rgb[((size_t)(y * k + dy) * w + x * k + dx) * 3 + (size_t)c];
				out[((size_t)y * *ow + x) * 3 + (size_t)c] = (uint8_t)((sum + cnt / 2) / (cnt ? cnt : 1));
			}
	return out;
}

#define THUMB_W 320
#define HEAT_MAX 32.0 /* heatmap colour scale: 0..32 code values (T = 8..16 differences stay visible) */

static int write_thumb(const char *path, const uint8_t *rgb, uint32_t w, uint32_t h, char *err, size_t err_size)
{
	uint32_t tw, th;
	uint8_t *t = downscale(rgb, w, h, THUMB_W, &tw, &th);
	if (!t)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	int rc = imageio_write_png_rgb8_packed(path, tw, th, t, err, err_size);
	free(t);
	return rc;
}

/* Thumbnails of the ref and the run at frame f and the max-RGB difference heatmap (DESIGN section 3). */
static int run_images(const char *run_dir, const char *ref_dir, uint32_t f, const char *ref_png, const char *run_png,
		      const char *heat_png, char *err, size_t err_size)
{
	char pa[TL_PATH_MAX], pb[TL_PATH_MAX];
	uint8_t *a = NULL, *b = NULL;
	uint32_t wa, ha, wb, hb;
	float *map = NULL;
	snprintf(pa, sizeof pa, "%s/frames/%06u.png", ref_dir, f);
	snprintf(pb, sizeof pb, "%s/frames/%06u.png", run_dir, f);
	int rc = imageio_read_rgb8(pa, &wa, &ha, &a, err, err_size);
	if (!rc)
		rc = imageio_read_rgb8(pb, &wb, &hb, &b, err, err_size);
	if (!rc && (wa != wb || ha != hb))
		rc = tl_error(err, err_size, TL_ERR_INPUT, "%s and %s differ in size", pa, pb);
	if (!rc && ref_png)
		rc = write_thumb(ref_png, a, wa, ha, err, err_size);
	if (!rc)
		rc = write_thumb(run_png, b, wb, hb, err, err_size);
	if (!rc && heat_png) {
		size_t n = (size_t)wa * ha;
		if (!(map = malloc(n * sizeof *map)))
			rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		for (size_t i = 0; !rc && i < n; i++) {
			int d = 0;
			for (int c = 0; c < 3; c++) {
				int x = abs((int)a[i * 3 + (size_t)c] - (int)b[i * 3 + (size_t)c]);
				d = x > d ? x : d;
			}
			map[i] = (float)d;
		}
		if (!rc)
			rc = mtr_heatmap_write(heat_png, map, wa, ha, HEAT_MAX, err, err_size);
	}
	free(map);
	free(a);
	free(b);
	return rc;
}

/* ------------------------------------------------------------------ plots */

typedef struct plot_def {
	const char *column, *name, *title, *ylabel;
	bool logy;
} plot_def;

static const plot_def PLOTS[] = {
	{"reuse_percent", "reuse", "shading reuse", "reuse (%)", false},
	{"reduction_percent", "reduction", "shaded samples: reduction against the baseline", "reduction (%)", false},
	{"speedup_vs_ref", "speedup", "speedup against ref (median GPU frame time)", "speedup (x)", false},
	{"exceed_T", "exceed", "pixels with max-RGB difference d > T", "fraction of pixels", false},
	{"maxrgb_p99", "p99", "max-RGB difference, 99th percentile", "code values", false},
	{"flicker_mean", "flicker", "flicker: difference of frame-to-frame changes", "code values (mean)", false},
	{"flip_mean", "flip", "LDR-FLIP error (mean)", "FLIP", false},
	/* only with `sweep --truth` (drawn when some run has the value) */
	{"late_percent", "late", "late samples: reused more than T from their true shading (--truth)",
	 "% of reused samples", false},
};
#define PLOT_COUNT (sizeof PLOTS / sizeof PLOTS[0])

/* Rows of one group, by method then T (lines are drawn in data order). */
typedef struct grow {
	const mtr_sweep_row *r;
	const sweep_variant *v;
} grow;

static int cmp_grow(const void *a, const void *b)
{
	const grow *x = a, *y = b;
	int c = strcmp(x->v->method, y->v->method);
	if (c)
		return c;
	double tx = isfinite(x->v->T) ? x->v->T : -1, ty = isfinite(y->v->T) ? y->v->T : -1;
	if (tx != ty)
		return tx < ty ? -1 : 1;
	return (int)x->v->period - (int)y->v->period;
}

/* Writes report/data/<group>.csv (blocks per threshold method, two blank lines apart, for gnuplot's `index`) and the
 * group's gnuplot script; `drawn[k]` says whether plot k has anything to draw. */
static int group_plots(const char *rdir, const char *stem, grow *g, size_t ng, bool drawn[],
		       char *err, size_t err_size)
{
	char path[TL_PATH_MAX], gp[TL_PATH_MAX];
	tl_atomic a;
	snprintf(path, sizeof path, "%s/data/%s.csv", rdir, stem);
	int rc = tl_atomic_open(&a, path, err, err_size);
	if (rc)
		return rc;
	/* blocks: one per method with a threshold: T, then every plot column */
	const char *methods[SWEEP_MAX_VARIANTS];
	size_t nm = 0;
	for (size_t i = 0; i < ng; i++)
		if (isfinite(g[i].v->T) && (!nm || strcmp(methods[nm - 1], g[i].v->method)))
			methods[nm++] = g[i].v->method;
	fprintf(a.f, "# T");
	for (size_t k = 0; k < PLOT_COUNT; k++)
		fprintf(a.f, ",%s", PLOTS[k].column);
	fputc('\n', a.f);
	for (size_t m = 0; m < nm; m++) {
		fprintf(a.f, "%s# %s\n", m ? "\n\n" : "", methods[m]);
		for (size_t i = 0; i < ng; i++) {
			if (strcmp(g[i].v->method, methods[m]) || !isfinite(g[i].v->T))
				continue;
			fprintf(a.f, "%g", g[i].v->T);
			for (size_t k = 0; k < PLOT_COUNT; k++) {
				double v = mtr_sweep_value(g[i].r, PLOTS[k].column);
				fputc(',', a.f);
				if (isfinite(v))
					fprintf(a.f, "%.9g", v), drawn[k] = true;
			}
			fputc('\n', a.f);
		}
	}
	if ((rc = tl_atomic_commit(&a, err, err_size)))
		return rc;
	/* variants without a threshold: horizontal lines; exceed: their curve over T = 2..64 */
	mtr_plot plot;
	snprintf(gp, sizeof gp, "%s/data/%s.gp", rdir, stem);
	FILE *f = mtr_plot_begin(&plot, gp, err, err_size);
	if (!f)
		return TL_ERR_OUTPUT;
	double tmin = 2, tmax = 64;
	for (size_t i = 0; i < ng; i++)
		if (isfinite(g[i].v->T)) {
			tmin = fmin(tmin, g[i].v->T);
			tmax = fmax(tmax, g[i].v->T);
		}
	fprintf(f, "set terminal svg size 460,300 dynamic font 'sans,10' background rgb 'white'\nset datafile separator ','\n"
		   "set grid\nset key outside bottom center horizontal noenhanced\nset logscale x 2\nset xrange [%g:%g]\n"
		   "set xlabel 'threshold T (code values)'\nset termoption noenhanced\n",
		tmin / 1.25, tmax * 1.25);
	for (size_t k = 0; k < PLOT_COUNT; k++) {
		const plot_def *p = &PLOTS[k];
		bool exceed = !strcmp(p->column, "exceed_T");
		char parts[8192] = "";
		size_t len = 0;
		for (size_t m = 0; m < nm; m++)
			len += (size_t)snprintf(parts + len, sizeof parts - len,
						"%s'%s/data/%s.csv' index %zu using 1:%zu with linespoints lw 2 pt 7 title '%s'",
						len ? ", " : "", rdir, stem, m, k + 2, methods[m]);
		for (size_t i = 0; i < ng; i++) {
			const sweep_variant *v = g[i].v;
			if (isfinite(v->T) || !g[i].r->status.run)
				continue;
			if (exceed) { /* fraction above x for x = 2..64, as an inline data block */
				bool any = false;
				for (int t = 0; t < MTR_THRESHOLD_COUNT; t++) {
					char col[32];
					snprintf(col, sizeof col, "exceed_%g", mtr_thresholds[t]);
					any |= isfinite(mtr_sweep_value(g[i].r, col));
				}
				if (!any || g[i].r->summary.facts.reference) /* the reference, from its manifest (issue 30.1) */
					continue;
				len += (size_t)snprintf(parts + len, sizeof parts - len,
							"%s'-' using 1:2 with linespoints dt 2 lw 2 pt 6 title '%s'",
							len ? ", " : "", v->variant);
				drawn[k] = true;
				continue;
			}
			double y = mtr_sweep_value(g[i].r, p->column);
			if (!isfinite(y) || (g[i].r->summary.facts.reference && strcmp(p->column, "speedup_vs_ref")))
				continue;
			len += (size_t)snprintf(parts + len, sizeof parts - len, "%s%.9g with lines dt 2 lw 2 title '%s'",
						len ? ", " : "", y, v->variant);
			drawn[k] = true;
		}
		if (!drawn[k] || !len)
			continue;
		fprintf(f, "set output '%s/plots/%s--%s.svg'\nset title '%s'\nset ylabel '%s'\nplot %s\n", rdir, stem, p->name,
			p->title, p->ylabel, parts);
		if (exceed) /* the inline blocks, in the order of the '-' entries */
			for (size_t i = 0; i < ng; i++) {
				const sweep_variant *v = g[i].v;
				if (isfinite(v->T) || !g[i].r->status.run || g[i].r->summary.facts.reference)
					continue;
				bool any = false;
				for (int t = 0; t < MTR_THRESHOLD_COUNT; t++) {
					char col[32];
					snprintf(col, sizeof col, "exceed_%g", mtr_thresholds[t]);
					double y = mtr_sweep_value(g[i].r, col);
					if (isfinite(y))
						fprintf(f, "%g,%.9g\n", mtr_thresholds[t], y), any = true;
				}
				if (any)
					fprintf(f, "e\n");
			}
	}
	return mtr_plot_end(&plot, err, err_size);
}

/* Fig. 4 from an analysis folder: fraction unchanged against k, one line per T (coherence.csv:
 * T,k,unchanged_samples,visible_samples,fraction_unchanged). */
static int coherence_plot(const char *csv, const char *svg, const char *gp, char *err, size_t err_size)
{
	mtr_plot plot;
	FILE *f = mtr_plot_begin(&plot, gp, err, err_size);
	if (!f)
		return TL_ERR_OUTPUT;
	fprintf(f, "set terminal svg size 460,300 dynamic font 'sans,10' background rgb 'white'\nset datafile separator ','\n"
		   "set grid\nset key outside right noenhanced\nset output '%s'\nset title 'temporal coherence (Fig. 4)'\n"
		   "set xlabel 'k (frames)'\nset ylabel 'fraction unchanged for >= k frames'\nset yrange [0:1]\n"
		   "plot for [T in '2 4 8 16 32 64'] '%s' using ($1 == T+0 ? $2 : 1/0):5 every ::1 with lines lw 2 title 'T = '.T\n",
		svg, csv);
	return mtr_plot_end(&plot, err, err_size);
}

/* ------------------------------------------------------------------ the page */

static const char *CSS =
	"body{font:14px/1.45 system-ui,sans-serif;margin:0;color:#1b1f24;background:#f6f7f9}"
	"header{background:#1b2a3a;color:#fff;padding:18px 28px}header h1{margin:0 0 6px;font-size:22px}"
	"header p{margin:2px 0;opacity:.85}main{padding:10px 28px 40px}nav a{margin-right:12px}"
	"section{background:#fff;border:1px solid #dde1e6;border-radius:8px;padding:14px 18px;margin:18px 0}"
	"h2{margin:4px 0 10px;font-size:18px}h3{font-size:15px;margin:14px 0 6px}"
	".plots{display:grid;grid-template-columns:repeat(auto-fill,minmax(330px,1fr));gap:10px}"
	".plots figure{margin:0;border:1px solid #eceef1;border-radius:6px;padding:4px;background:#fff}"
	".plots img{width:100%;height:auto;display:block}figcaption{font-size:12px;color:#555;text-align:center}"
	"table{border-collapse:collapse;font-size:13px;margin:6px 0}th,td{border-bottom:1px solid #e3e6ea;padding:3px 8px;"
	"text-align:right;vertical-align:middle}th{background:#f0f2f5;position:sticky;top:0}td.l,th.l{text-align:left}"
	"td{white-space:nowrap}td img{max-width:104px;height:auto;display:block;image-rendering:pixelated}"
	".missing{color:#b3261e;font-weight:600}.note{color:#666;font-size:12px}"
	".player{display:flex;flex-wrap:wrap;gap:12px;align-items:flex-start;margin-top:8px}"
	".player figure{flex:1 1 320px;max-width:640px;margin:0}.player video{width:100%;background:#000;"
	"image-rendering:pixelated}"
	".player .ctl{width:100%;display:flex;gap:10px;align-items:center}.scroll{overflow-x:auto}";

static const char *SCRIPT =
	"// Clip pairs (ref | variant): both start together from the same frame; while they play, a drift of more than one\n"
	"// frame (a decoder falling behind on a busy machine) pauses both, seeks both to the reference's time and starts\n"
	"// them together again, so the two never show frames further apart than that.\n"
	"(function(){\n"
	"const players=[];\n"
	"function seeked(v,t){ return new Promise(function(r){ if(Math.abs(v.currentTime-t)<1e-4&&!v.seeking) return r();\n"
	"  v.addEventListener('seeked',function(){ r(); },{once:true}); v.currentTime=t; }); }\n"
	"function ready(v){ return v.readyState>=3?Promise.resolve():new Promise(function(r){ v.addEventListener('canplay',function(){ r(); },{once:true}); }); }\n"
	"document.querySelectorAll('.player').forEach(function(p){\n"
	"  const ref=p.querySelector('video.ref'), test=p.querySelector('video.test'), sel=p.querySelector('select');\n"
	"  const btn=p.querySelector('button'), info=p.querySelector('.sync'), fps=+p.dataset.fps||60;\n"
	"  const st={ref:ref,test:test,playing:false,resyncing:false,resyncs:0};\n"
	"  function show(){ info.textContent='frame '+Math.floor(ref.currentTime*fps+1e-6)+', variant offset '+\n"
	"    (1000*(test.currentTime-ref.currentTime)).toFixed(1)+' ms, resyncs '+st.resyncs; }\n"
	"  let token=0; // the latest start wins: an older one stops after its seeks\n"
	"  async function start(t){ const my=++token; st.resyncing=true; ref.pause(); test.pause();\n"
	"    await Promise.all([seeked(ref,t),seeked(test,t)]); await Promise.all([ready(ref),ready(test)]);\n"
	"    if(my!==token) return; st.resyncing=false; if(!st.playing){ show(); return; }\n"
	"    await Promise.all([ref.play(),test.play()]).catch(function(){}); if(my===token) requestAnimationFrame(watch); }\n"
	"  function watch(){ if(!st.playing||st.resyncing) return; show();\n"
	"    if(ref.ended||test.ended||ref.currentTime>=ref.duration-0.5/fps){ start(0); return; } // loop, together\n"
	"    if(Math.abs(test.currentTime-ref.currentTime)>1/fps||ref.paused!==test.paused){ st.resyncs++; start(ref.currentTime); return; }\n"
	"    requestAnimationFrame(watch); }\n"
	"  btn.addEventListener('click',function(){ st.playing=!st.playing; btn.textContent=st.playing?'pause':'play both';\n"
	"    if(st.playing) start(ref.ended?0:ref.currentTime); else start(ref.currentTime); });\n"
	"  sel.addEventListener('change',function(){ test.src=sel.value; start(ref.currentTime); });\n"
	"  players.push(st);\n"
	"});\n"
	"window.taslabReport={players:players};\n"
	"})();\n";

typedef struct group_info {
	size_t scene, cam;
	grow rows[SWEEP_MAX_VARIANTS];
	size_t n;
	const mtr_sweep_row *ref;
	bool drawn[PLOT_COUNT];
	bool plots_ok;
	bool coherence;
} group_info;

static void page_table1(FILE *f, const sweep_spec *s, group_info *gi, size_t ng)
{
	fprintf(f, "<section id=\"table1\"><h2>Table 1: shaded samples and their reduction</h2>\n<p class=\"note\">Shaded "
		   "samples are the methods' own counts (DESIGN section 5), per frame; the reduction is 1 − shaded / "
		   "baseline's shaded (baseline %s) over the same frames; speedup = ref's median GPU frame time / the run's "
		   "(cf. paper Table 1, Fig. 12). Also in <a href=\"../table1.md\">table1.md</a> and "
		   "<a href=\"../summary.csv\">summary.csv</a>.</p>\n<div class=\"scroll\"><table><tr><th class=\"l\">scene</th>"
		   "<th class=\"l\">camera</th><th class=\"l\">variant</th><th>shaded samples / frame</th><th>reduction</th>"
		   "<th>reuse</th><th>speedup vs ref</th></tr>\n",
		s->baseline);
	for (size_t g = 0; g < ng; g++)
		for (size_t i = 0; i < gi[g].n + 1; i++) {
			const mtr_sweep_row *r = i ? gi[g].rows[i - 1].r : gi[g].ref;
			if (!r)
				continue;
			const sweep_scene *sc = &s->scenes[gi[g].scene];
			fprintf(f, "<tr><td class=\"l\">");
			esc(f, sc->name);
			fprintf(f, "</td><td class=\"l\">");
			esc(f, sc->cameras[gi[g].cam].name);
			fprintf(f, " (%s)</td><td class=\"l\">", sc->cameras[gi[g].cam].motion);
			esc(f, s->variants[r->run.variant].variant);
			fprintf(f, "</td>");
			if (!r->status.run) {
				fprintf(f, "<td class=\"missing\" colspan=\"4\">run missing or failed</td></tr>\n");
				continue;
			}
			cells(f, r, TABLE1_CELLS);
			fprintf(f, "</tr>\n");
		}
	fprintf(f, "</table></div></section>\n");
}

/* A thumbnail cell; files are named by group, variant and frame. */
static void img_cell(FILE *f, const char *rel, const char *alt)
{
	fprintf(f, "<td><a href=\"%s\"><img src=\"%s\" alt=\"", rel, rel);
	esc(f, alt);
	fprintf(f, "\" loading=\"lazy\"></a></td>");
}

int sty_report_metric_known(const char *column)
{
	static const char *const extra[] = {"exceed_T", "reuse_percent", "reduction_percent", "speedup_vs_ref",
					    "gpu_ms_median", "shaded_per_frame", "late_percent", NULL};
	for (int i = 0; extra[i]; i++)
		if (!strcmp(extra[i], column))
			return 1;
	for (int c = 0; mtr_column_name(c); c++)
		if (!strcmp(mtr_column_name(c), column))
			return 1;
	return 0;
}

int sty_report_write(const sty_report_desc *d, char *index, size_t index_size, char *err, size_t err_size)
{
	const sweep_spec *s = d->spec;
	const char *jnd_metric = d->jnd_metric ? d->jnd_metric : "flip_mean";
	char rdir[TL_PATH_MAX], path[TL_PATH_MAX + 64], note[1024];
	snprintf(rdir, sizeof rdir, "%s/report", d->dir);
	const char *subs[] = {"plots", "img", "data"};
	int rc = TL_OK;
	for (int k = 0; k < 3 && !rc; k++) {
		snprintf(path, sizeof path, "%s/%s", rdir, subs[k]);
		rc = tl_mkdirs(path, err, err_size);
	}
	if (rc)
		return rc;
	study_tab study = {0};
	if (d->study) {
		snprintf(path, sizeof path, "%s/study", rdir);
		if ((rc = tl_mkdirs(path, err, err_size)) || (rc = load_study(d->study, path, &study, err, err_size)))
			return rc;
	}
	/* groups: scene x camera, with their rows sorted by method and T */
	size_t ng = 0;
	for (size_t i = 0; i < s->scene_count; i++)
		ng += s->scenes[i].camera_count;
	group_info *gi = calloc(ng ? ng : 1, sizeof *gi);
	if (!gi) {
		free(study.c);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	size_t g = 0;
	for (size_t i = 0; i < s->scene_count; i++)
		for (size_t c = 0; c < s->scenes[i].camera_count; c++, g++) {
			gi[g].scene = i, gi[g].cam = c;
			for (size_t k = 0; k < d->count; k++) {
				const mtr_sweep_row *r = &d->rows[k];
				if (r->run.scene != i || r->run.camera != c)
					continue;
				if (r->run.is_ref)
					gi[g].ref = r;
				else
					gi[g].rows[gi[g].n++] = (grow){r, &s->variants[r->run.variant]};
			}
			qsort(gi[g].rows, gi[g].n, sizeof gi[g].rows[0], cmp_grow);
		}
	/* plots and images per group */
	bool gnuplot_note = false;
	for (g = 0; g < ng && !rc; g++) {
		char stem[256];
		group_stem(s, gi[g].scene, gi[g].cam, stem, sizeof stem);
		grow all[SWEEP_MAX_VARIANTS + 1];
		size_t na = 0;
		if (gi[g].ref)
			all[na++] = (grow){gi[g].ref, &s->variants[gi[g].ref->run.variant]};
		for (size_t i = 0; i < gi[g].n; i++)
			all[na++] = gi[g].rows[i];
		int prc = group_plots(rdir, stem, all, na, gi[g].drawn, note, sizeof note);
		gi[g].plots_ok = prc == TL_OK;
		if (prc == TL_ERR_UNSUPPORTED)
			gnuplot_note = true;
		else if (prc)
			rc = tl_error(err, err_size, prc, "%s", note);
		char csv[TL_PATH_MAX + 128], svg[TL_PATH_MAX + 128], gp[TL_PATH_MAX + 128];
		snprintf(csv, sizeof csv, "%s/analysis/%s/%s/coherence.csv", d->dir, s->scenes[gi[g].scene].name,
			 s->scenes[gi[g].scene].cameras[gi[g].cam].name);
		if (tl_is_file(csv)) {
			snprintf(svg, sizeof svg, "%s/plots/%s--coherence.svg", rdir, stem);
			snprintf(gp, sizeof gp, "%s/data/%s--coherence.gp", rdir, stem);
			gi[g].coherence = coherence_plot(csv, svg, gp, note, sizeof note) == TL_OK;
		}
		if (!gi[g].ref || !gi[g].ref->status.run)
			continue;
		char ref_dir[TL_PATH_MAX];
		sweep_run_path(s, d->dir, &gi[g].ref->run, SWEEP_PATH_RUN, ref_dir, sizeof ref_dir);
		for (size_t i = 0; i < gi[g].n && !rc; i++) {
			const mtr_sweep_row *r = gi[g].rows[i].r;
			if (!r->status.run)
				continue;
			char run_dir[TL_PATH_MAX], a[TL_PATH_MAX + 128], b[TL_PATH_MAX + 128], h[TL_PATH_MAX + 128];
			sweep_run_path(s, d->dir, &r->run, SWEEP_PATH_RUN, run_dir, sizeof run_dir);
			snprintf(a, sizeof a, "%s/img/%s--ref--%06u.png", rdir, stem, r->worst_frame);
			snprintf(b, sizeof b, "%s/img/%s--%s--%06u.png", rdir, stem, gi[g].rows[i].v->id, r->worst_frame);
			snprintf(h, sizeof h, "%s/img/%s--%s--%06u-diff.png", rdir, stem, gi[g].rows[i].v->id, r->worst_frame);
			rc = run_images(run_dir, ref_dir, r->worst_frame, a, b, h, err, err_size);
		}
	}
	/* the study: joined table and JND against the chosen metric */
	bool jnd_plot = false;
	if (!rc && d->study) {
		tl_atomic a;
		snprintf(path, sizeof path, "%s/data/study.csv", rdir);
		if (!(rc = tl_atomic_open(&a, path, err, err_size))) {
			fprintf(a.f, "scene,camera,method,variant,T,period,%s,n,Q,Q_lo,Q_hi,p_ref,p_ref_lo,p_ref_hi,jnd,jnd_lo,jnd_hi\n",
				jnd_metric);
			for (size_t k = 0; k < d->count; k++) {
				const mtr_sweep_row *r = &d->rows[k];
				const cond *c = find_cond(&study, s, r);
				if (!c)
					continue;
				const sweep_variant *v = &s->variants[r->run.variant];
				double x = mtr_sweep_value(r, jnd_metric);
				fprintf(a.f, "%s,%s,%s,%s,", s->scenes[r->run.scene].name,
					s->scenes[r->run.scene].cameras[r->run.camera].name, v->method, v->variant);
				if (isfinite(v->T))
					fprintf(a.f, "%g", v->T);
				fputc(',', a.f);
				if (v->period)
					fprintf(a.f, "%u", v->period);
				double vals[] = {x, c->n, c->Q, c->Q_lo, c->Q_hi, c->p, c->p_lo, c->p_hi, c->jnd, c->jnd_lo, c->jnd_hi};
				for (size_t q = 0; q < sizeof vals / sizeof vals[0]; q++) {
					fputc(',', a.f);
					if (isfinite(vals[q]))
						fprintf(a.f, "%.9g", vals[q]);
				}
				fputc('\n', a.f);
				jnd_plot |= isfinite(x) && isfinite(c->jnd);
			}
			rc = tl_atomic_commit(&a, err, err_size);
		}
		if (!rc && jnd_plot) {
			mtr_plot plot;
			char gp[TL_PATH_MAX + 64];
			snprintf(gp, sizeof gp, "%s/data/study.gp", rdir);
			FILE *f = mtr_plot_begin(&plot, gp, err, err_size);
			if (!f) {
				rc = TL_ERR_OUTPUT;
			} else {
				fprintf(f, "set terminal svg size 640,400 dynamic font 'sans,10' background rgb 'white'\n"
					   "set datafile separator ','\nset grid\nset key outside right noenhanced\n"
					   "set termoption noenhanced\nset output '%s/plots/jnd.svg'\n"
					   "set title 'JND against %s (one point per condition, 95%% intervals)'\n"
					   "set xlabel '%s'\nset ylabel 'JND'\nset arrow from graph 0, first 1 to graph 1, first 1 nohead dt 2\n"
					   "methods = system(\"tail -n +2 '%s/data/study.csv' | cut -d, -f3 | sort -u | tr '\\\\n' ' '\")\n"
					   "plot for [m in methods] '%s/data/study.csv' using (strcol(3) eq m ? $7 : 1/0):15:16:17 every ::1 "
					   "with yerrorbars pt 7 title m\n",
					rdir, jnd_metric, jnd_metric, rdir, rdir);
				jnd_plot = mtr_plot_end(&plot, note, sizeof note) == TL_OK;
			}
		}
	}
	if (rc) {
		free(gi);
		free(study.c);
		return rc;
	}
	/* index.html */
	tl_atomic page;
	snprintf(path, sizeof path, "%s/index.html", rdir);
	if ((rc = tl_atomic_open(&page, path, err, err_size))) {
		free(gi);
		free(study.c);
		return rc;
	}
	FILE *f = page.f;
	char when[32];
	tl_clock_utc(when, sizeof when);
	size_t complete = 0;
	for (size_t k = 0; k < d->count; k++)
		complete += d->rows[k].status.run && d->rows[k].status.clip && d->rows[k].status.metrics;
	fprintf(f, "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
		   "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>taslab sweep report</title>\n"
		   "<style>%s</style></head><body>\n<header><h1>taslab sweep report</h1>\n<p>",
		CSS);
	for (size_t i = 0; i < s->scene_count; i++) {
		fputs(i ? ", " : "scenes: ", f);
		esc(f, s->scenes[i].name);
		fprintf(f, " (frames %u–%u at %g fps, %zu camera path%s)", s->scenes[i].first, s->scenes[i].end - 1,
			s->scenes[i].fps, s->scenes[i].camera_count, s->scenes[i].camera_count > 1 ? "s" : "");
	}
	fprintf(f, "</p>\n<p>variants: ");
	for (size_t v = 0; v < s->variant_count; v++) {
		fputs(v ? ", " : "", f);
		esc(f, s->variants[v].variant);
	}
	fprintf(f, " · %ux%u · display: ", s->width, s->height);
	esc(f, s->display_transform);
	fprintf(f, "</p>\n<p>%zu of %zu runs complete · generated %s · <a style=\"color:#9cf\" href=\"../summary.csv\">"
		   "summary.csv</a> · <a style=\"color:#9cf\" href=\"../table1.md\">table1.md</a> · "
		   "<a style=\"color:#9cf\" href=\"../sweep.json\">sweep.json</a></p></header>\n<main>\n<nav>",
		complete, d->count, when);
	fprintf(f, "<a href=\"#table1\">Table 1</a>");
	if (d->study)
		fprintf(f, "<a href=\"#study\">Study</a>");
	for (g = 0; g < ng; g++) {
		const sweep_scene *sc = &s->scenes[gi[g].scene];
		char stem[256];
		group_stem(s, gi[g].scene, gi[g].cam, stem, sizeof stem);
		fprintf(f, "<a href=\"#");
		esc(f, stem);
		fprintf(f, "\">");
		esc(f, sc->name);
		fputs(" / ", f);
		esc(f, sc->cameras[gi[g].cam].name);
		fprintf(f, "</a>");
	}
	fprintf(f, "</nav>\n");
	if (gnuplot_note)
		fprintf(f, "<p class=\"missing\">gnuplot is not installed: no plots (the numbers are in summary.csv).</p>\n");
	page_table1(f, s, gi, ng);
	if (d->study) {
		fprintf(f, "<section id=\"study\"><h2>Study</h2><p class=\"note\">From ");
		esc(f, d->study);
		fprintf(f, " (tally in <a href=\"study/conditions.csv\">study/conditions.csv</a>): Q = mean reference-relative "
			   "rating (+2: reference much better), p_ref = share preferring the reference (ties halved), JND = "
			   "Φ⁻¹(p_ref)/Φ⁻¹(0.75), 95%% intervals (DESIGN section 7). Joined per condition (method, T, period, "
			   "scene, camera) in <a href=\"data/study.csv\">data/study.csv</a>.</p>\n");
		if (jnd_plot)
			fprintf(f, "<figure class=\"plots\"><img src=\"plots/jnd.svg\" alt=\"JND against %s\"></figure>\n",
				jnd_metric);
		else
			fprintf(f, "<p class=\"note\">No condition of the study matches a run with %s: no JND plot.</p>\n",
				jnd_metric);
		fprintf(f, "</section>\n");
	}
	for (g = 0; g < ng; g++) {
		const sweep_scene *sc = &s->scenes[gi[g].scene];
		const sweep_camera *cam = &sc->cameras[gi[g].cam];
		char stem[256];
		group_stem(s, gi[g].scene, gi[g].cam, stem, sizeof stem);
		fprintf(f, "<section id=\"");
		esc(f, stem);
		fprintf(f, "\"><h2>");
		esc(f, sc->name);
		fputs(" / ", f);
		esc(f, cam->name);
		fprintf(f, " <span class=\"note\">(%s camera, %u frames)</span></h2>\n", cam->motion, sc->end - sc->first);
		fprintf(f, "<h3>Against T</h3><div class=\"plots\">\n");
		bool any = false;
		for (size_t k = 0; k < PLOT_COUNT; k++) {
			if (!gi[g].drawn[k] || !gi[g].plots_ok)
				continue;
			any = true;
			fprintf(f, "<figure><img src=\"plots/");
			esc(f, stem);
			fprintf(f, "--%s.svg\" alt=\"%s\"><figcaption>%s</figcaption></figure>\n", PLOTS[k].name, PLOTS[k].title,
				PLOTS[k].title);
		}
		if (gi[g].coherence) {
			fprintf(f, "<figure><img src=\"plots/");
			esc(f, stem);
			fprintf(f, "--coherence.svg\" alt=\"temporal coherence\"><figcaption>temporal coherence (analysis)"
				   "</figcaption></figure>\n");
		}
		fprintf(f, "</div>\n");
		if (!any)
			fprintf(f, "<p class=\"note\">Nothing to plot yet.</p>\n");
		fprintf(f, "<p class=\"note\">Methods with a threshold are lines over T; variants without one are dashed "
			   "horizontal lines (for exceedance: their fraction of pixels above each T). Heatmaps: max-RGB "
			   "difference to ref at the run's worst frame (largest p99), scale 0–%g code values.</p>\n",
			HEAT_MAX);
		/* the runs */
		fprintf(f, "<h3>Runs</h3><div class=\"scroll\"><table><tr><th class=\"l\">variant</th><th>reuse</th>"
			   "<th>reduction</th><th>speedup</th><th>exceed_T</th><th>exceed_8</th><th>p99</th><th>flicker</th>"
			   "<th>FLIP</th><th>PSNR</th><th>late</th>");
		if (d->study)
			fprintf(f, "<th>Q [95%%]</th><th>p_ref [95%%]</th><th>JND [95%%]</th>");
		fprintf(f, "<th>frame</th><th>ref</th><th>variant</th><th>difference</th></tr>\n");
		for (size_t i = 0; i < gi[g].n; i++) {
			const mtr_sweep_row *r = gi[g].rows[i].r;
			const sweep_variant *v = gi[g].rows[i].v;
			fprintf(f, "<tr><td class=\"l\">");
			esc(f, v->variant);
			fprintf(f, "</td>");
			if (!r->status.run) {
				fprintf(f, "<td class=\"missing\" colspan=\"9\">run missing or failed (see ../logs/)</td></tr>\n");
				continue;
			}
			cells(f, r, RUN_CELLS);
			if (d->study) {
				const cond *c = find_cond(&study, s, r);
				if (c)
					fprintf(f, "<td>%.2f [%.2f, %.2f]</td><td>%.2f [%.2f, %.2f]</td><td>%.2f [%.2f, %.2f]</td>",
						c->Q, c->Q_lo, c->Q_hi, c->p, c->p_lo, c->p_hi, c->jnd, c->jnd_lo, c->jnd_hi);
				else
					fprintf(f, "<td>–</td><td>–</td><td>–</td>");
			}
			fprintf(f, "<td>%u</td>", r->worst_frame);
			if (gi[g].ref && gi[g].ref->status.run) {
				char rel[1024], alt[256];
				snprintf(rel, sizeof rel, "img/%s--ref--%06u.png", stem, r->worst_frame);
				snprintf(alt, sizeof alt, "ref, frame %u", r->worst_frame);
				img_cell(f, rel, alt);
				snprintf(rel, sizeof rel, "img/%s--%s--%06u.png", stem, v->id, r->worst_frame);
				snprintf(alt, sizeof alt, "%s, frame %u", v->variant, r->worst_frame);
				img_cell(f, rel, alt);
				snprintf(rel, sizeof rel, "img/%s--%s--%06u-diff.png", stem, v->id, r->worst_frame);
				snprintf(alt, sizeof alt, "difference of %s to ref, frame %u", v->variant, r->worst_frame);
				img_cell(f, rel, alt);
			} else {
				fprintf(f, "<td colspan=\"3\" class=\"missing\">no ref run</td>");
			}
			fprintf(f, "</tr>\n");
		}
		fprintf(f, "</table></div>\n");
		/* the clip pair */
		char ref_clip[1024] = "", first_clip[1024] = "";
		if (gi[g].ref && gi[g].ref->status.clip)
			snprintf(ref_clip, sizeof ref_clip, "../clips/%s/%s/ref.webm", sc->name, cam->name);
		size_t nclips = 0;
		for (size_t i = 0; i < gi[g].n; i++)
			if (gi[g].rows[i].r->status.clip) {
				if (!nclips++)
					snprintf(first_clip, sizeof first_clip, "../clips/%s/%s/%s.webm", sc->name, cam->name,
						 gi[g].rows[i].v->id);
			}
		if (ref_clip[0] && nclips) {
			fprintf(f, "<h3>Clips</h3><div class=\"player\" data-fps=\"%g\"><div class=\"ctl\"><button type=\"button\">"
				   "play both</button><label>variant <select>", sc->fps);
			for (size_t i = 0; i < gi[g].n; i++) {
				if (!gi[g].rows[i].r->status.clip)
					continue;
				fprintf(f, "<option value=\"../clips/");
				esc(f, sc->name);
				fputc('/', f);
				esc(f, cam->name);
				fprintf(f, "/%s.webm\">", gi[g].rows[i].v->id);
				esc(f, gi[g].rows[i].v->variant);
				fprintf(f, "</option>");
			}
			fprintf(f, "</select></label><span class=\"sync note\"></span></div>\n<figure><figcaption>ref</figcaption>"
				   "<video class=\"ref\" src=\"");
			esc(f, ref_clip);
			fprintf(f, "\" muted playsinline preload=\"metadata\"></video></figure><figure><figcaption>variant"
				   "</figcaption><video class=\"test\" src=\"");
			esc(f, first_clip);
			fprintf(f, "\" muted playsinline preload=\"metadata\"></video></figure></div>\n");
		}
		fprintf(f, "</section>\n");
	}
	fprintf(f, "</main>\n<script>\n%s</script>\n</body></html>\n", SCRIPT);
	rc = tl_atomic_commit(&page, err, err_size);
	if (!rc && index)
		snprintf(index, index_size, "%s", path);
	free(gi);
	free(study.c);
	return rc;
}
