/* study_report_plots.c — the sweep report's plots and images of one scene x camera group (study_report.h; DESIGN
 * section 9): report/data/<group>.csv with its gnuplot script and the SVG plots against T (one line per method with
 * a threshold, variants without one as horizontal lines, exceedance as a curve), Fig. 4 from a coherence analysis,
 * and per run the thumbnails of its worst frame and the max-RGB difference heatmap (DESIGN section 3). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_report_internal.h"
#include "taslab/imageio.h"
#include "taslab/metrics.h"
#include "taslab/run.h"
#include "taslab/tl_fs.h"

/* ------------------------------------------------------------------ plots */

const sty_rpt_plot sty_rpt_plots[] = {
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
_Static_assert(sizeof sty_rpt_plots / sizeof sty_rpt_plots[0] == STY_RPT_PLOT_COUNT, "STY_RPT_PLOT_COUNT");

/* Rows of one group, by method then T (lines are drawn in data order). */
int sty_rpt_cmp_row(const void *a, const void *b)
{
	const sty_rpt_row *x = a, *y = b;
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
int sty_rpt_group_plots(const char *rdir, const char *stem, sty_rpt_row *g, size_t ng, bool drawn[], char *err,
			size_t err_size)
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
	for (size_t k = 0; k < STY_RPT_PLOT_COUNT; k++)
		fprintf(a.f, ",%s", sty_rpt_plots[k].column);
	fputc('\n', a.f);
	for (size_t m = 0; m < nm; m++) {
		fprintf(a.f, "%s# %s\n", m ? "\n\n" : "", methods[m]);
		for (size_t i = 0; i < ng; i++) {
			if (strcmp(g[i].v->method, methods[m]) || !isfinite(g[i].v->T))
				continue;
			fprintf(a.f, "%g", g[i].v->T);
			for (size_t k = 0; k < STY_RPT_PLOT_COUNT; k++) {
				double v = mtr_sweep_value(g[i].r, sty_rpt_plots[k].column);
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
	size_t entries = nm;
	for (size_t i = 0; i < ng; i++)
		entries += !isfinite(g[i].v->T) && g[i].r->status.run;
	mtr_plot_svg_preamble(f, entries);
	fprintf(f, "set datafile separator ','\nset grid\nset logscale x 2\nset xrange [%g:%g]\n"
		   "set xlabel 'threshold T (code values)'\nset termoption noenhanced\n",
		tmin / 1.25, tmax * 1.25);
	for (size_t k = 0; k < STY_RPT_PLOT_COUNT; k++) {
		const sty_rpt_plot *p = &sty_rpt_plots[k];
		bool exceed = !strcmp(p->column, "exceed_T");
		char parts[8192] = "";
		size_t len = 0;
		for (size_t m = 0; m < nm; m++)
			len += (size_t)snprintf(parts + len, sizeof parts - len,
						"%s'%s/data/%s.csv' index %zu using 1:%zu with linespoints title '%s'",
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
int sty_rpt_coherence_plot(const char *csv, const char *svg, const char *gp, char *err, size_t err_size)
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

/* Thumbnails of the ref and the run at frame f and the max-RGB difference heatmap (DESIGN section 3); stereo runs:
 * of their side-by-side frames (sbs/, left | right). */
int sty_rpt_run_images(const char *run_dir, const char *ref_dir, uint32_t f, const char *ref_png, const char *run_png,
		       const char *heat_png, char *err, size_t err_size)
{
	char pa[TL_PATH_MAX], pb[TL_PATH_MAX];
	uint8_t *a = NULL, *b = NULL;
	uint32_t wa, ha, wb, hb;
	float *map = NULL;
	run_manifest m;
	const bool stereo = !run_manifest_read(run_dir, &m, pa, sizeof pa) && m.views > 1;
	snprintf(pa, sizeof pa, "%s/%s/%06u.png", ref_dir, stereo ? "sbs" : "frames", f);
	snprintf(pb, sizeof pb, "%s/%s/%06u.png", run_dir, stereo ? "sbs" : "frames", f);
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
			rc = mtr_heatmap_write(heat_png, map, wa, ha, STY_RPT_HEAT_MAX, err, err_size);
	}
	free(map);
	free(a);
	free(b);
	return rc;
}
