/* study_report_budget.c — the sweep report's matched-budget comparison of one scene x camera group (BASELINES.md
 * section 0 "Comparison"; issue 26): the plot of shaded fraction against exceed_8, one curve per method over its
 * settings (report/data/<group>--budget.csv and .gp, plots/<group>--budget.svg), and the table of each TAS variant
 * beside each other method at its nearest clip-mean shaded samples (pairs from mtr_sweep_matched); and the survey's
 * models of reuse fitted to the group's methods with a period ([S] sec. 4.1, eqs. 5-7; metrics/reuse_model.c). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "study_report_internal.h"
#include "taslab/metrics.h"
#include "taslab/tl_fs.h"

/* A row is on the plot: a run that is there, not the reference, with both coordinates. */
static bool on_plot(const sty_rpt_row *x)
{
	return x->r->status.run && !x->r->summary.facts.reference && !x->r->run.is_ref &&
	       isfinite(mtr_sweep_value(x->r, "shaded_fraction")) && isfinite(mtr_sweep_value(x->r, "exceed_8"));
}

int sty_rpt_budget_plot(const char *rdir, const char *stem, const sty_rpt_group *g, bool *drawn, char *err,
			size_t err_size)
{
	*drawn = false;
	char path[TL_PATH_MAX], gp[TL_PATH_MAX];
	tl_atomic a;
	snprintf(path, sizeof path, "%s/data/%s--budget.csv", rdir, stem);
	int rc = tl_atomic_open(&a, path, err, err_size);
	if (rc)
		return rc;
	/* blocks (gnuplot `index`): one per method, its settings by shaded fraction so the curve runs left to right */
	const char *methods[SWEEP_MAX_VARIANTS];
	size_t nm = 0;
	fprintf(a.f, "# shaded_fraction,exceed_8,variant\n");
	for (size_t i = 0; i < g->n; i++) {
		const char *m = g->rows[i].v->method;
		if (!on_plot(&g->rows[i]) || (nm && !strcmp(methods[nm - 1], m))) /* rows are sorted by method */
			continue;
		size_t idx[SWEEP_MAX_VARIANTS], k = 0;
		for (size_t j = i; j < g->n && !strcmp(g->rows[j].v->method, m); j++)
			if (on_plot(&g->rows[j])) {
				size_t at = k++;
				double x = mtr_sweep_value(g->rows[j].r, "shaded_fraction");
				for (; at && mtr_sweep_value(g->rows[idx[at - 1]].r, "shaded_fraction") > x; at--)
					idx[at] = idx[at - 1];
				idx[at] = j;
			}
		fprintf(a.f, "%s# %s\n", nm ? "\n\n" : "", m);
		for (size_t q = 0; q < k; q++)
			fprintf(a.f, "%.9g,%.9g,%s\n", mtr_sweep_value(g->rows[idx[q]].r, "shaded_fraction"),
				mtr_sweep_value(g->rows[idx[q]].r, "exceed_8"), g->rows[idx[q]].v->variant);
		methods[nm++] = m;
	}
	if ((rc = tl_atomic_commit(&a, err, err_size)))
		return rc;
	if (!nm)
		return TL_OK;
	mtr_plot plot;
	snprintf(gp, sizeof gp, "%s/data/%s--budget.gp", rdir, stem);
	FILE *f = mtr_plot_begin(&plot, gp, err, err_size);
	if (!f)
		return TL_ERR_OUTPUT;
	mtr_plot_svg_preamble(f, nm);
	fprintf(f, "set datafile separator ','\nset grid\nset termoption noenhanced\nset xrange [0:1.05]\n"
		   "set output '%s/plots/%s--budget.svg'\nset title 'matched budget: exceed_8 against shaded fraction'\n"
		   "set xlabel 'shaded fraction (shaded / visible samples)'\nset ylabel 'fraction of pixels with d > 8'\nplot ",
		rdir, stem);
	for (size_t m = 0; m < nm; m++)
		fprintf(f, "%s'%s' index %zu using 1:2 with linespoints title '%s'", m ? ", " : "", path, m,
			methods[m]);
	fputc('\n', f);
	rc = mtr_plot_end(&plot, err, err_size);
	*drawn = rc == TL_OK;
	return rc;
}

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

static void budget_row(FILE *f, const sweep_spec *s, const mtr_sweep_row *r, bool tas)
{
	static const struct {
		const char *column, *fmt;
	} cols[] = {{"shaded_fraction", "%.3f"}, {"shaded_per_frame", "%.0f"}, {"exceed_8", "%.5f"},
		    {"flip_mean", "%.4f"},       {"flicker_mean", "%.3f"},     {"gpu_ms_median", "%.2f"}};
	fprintf(f, "<tr%s><td class=\"l\">", tas ? " class=\"tas\"" : "");
	esc(f, s->variants[r->run.variant].variant);
	fprintf(f, "%s</td>", tas ? " (TAS)" : "");
	for (size_t c = 0; c < sizeof cols / sizeof cols[0]; c++) {
		double v = mtr_sweep_value(r, cols[c].column);
		fputs("<td>", f);
		if (isfinite(v))
			fprintf(f, cols[c].fmt, v);
		else
			fputs("–", f);
		fputs("</td>", f);
	}
	fputs("</tr>\n", f);
}

void sty_rpt_budget_html(FILE *f, const sty_report_desc *d, const sty_rpt_group *g, const char *stem,
			 const mtr_match_pair *p, size_t np)
{
	fprintf(f, "<h3>Matched budget</h3>\n");
	if (g->budget) {
		fprintf(f, "<div class=\"plots\"><figure><img src=\"plots/");
		esc(f, stem);
		fprintf(f, "--budget.svg\" alt=\"exceed_8 against shaded fraction\"><figcaption>exceed_8 against shaded "
			   "fraction, one curve per method over its settings (a cache of a partial payload counts the payloads "
			   "it evaluates, and shades every sample besides: compare its GPU ms)</figcaption></figure></div>\n");
	}
	size_t shown = 0;
	for (size_t k = 0; k < np; k++) {
		const mtr_sweep_row *t = &d->rows[p[k].tas];
		if (t->run.scene != g->scene || t->run.camera != g->cam)
			continue;
		if (!shown++)
			fprintf(f, "<div class=\"scroll\"><table class=\"budget\"><tr><th class=\"l\">variant</th>"
				   "<th>shaded fraction</th><th>shaded / frame</th><th>exceed_8</th><th>FLIP</th>"
				   "<th>flicker</th><th>GPU ms</th></tr>\n");
		if (k == 0 || p[k - 1].tas != p[k].tas)
			budget_row(f, d->spec, t, true);
		budget_row(f, d->spec, &d->rows[p[k].other], false);
	}
	if (shown)
		fprintf(f, "</table></div>\n<p class=\"note\">Each TAS variant (bold), then each other method at its "
			   "setting with the nearest clip-mean shaded samples per frame. Differences against ref; GPU ms: "
			   "median frame time.</p>\n");
	else
		fprintf(f, "<p class=\"note\">No TAS variant with another method to match here.</p>\n");
}

void sty_rpt_reuse_html(FILE *f, const sty_report_desc *d, const sty_rpt_group *g)
{
	(void)d;
	if (!g->nreuse)
		return;
	fprintf(f, "<h3>Models of reuse <span class=\"note\">([S] sec. 4.1, eqs. 5–7)</span></h3>\n");
	size_t single = 0;
	for (size_t k = 0; k < g->nreuse; k++) {
		const mtr_reuse_group *m = &g->reuse[k];
		if (!m->e5.ok) { /* one period (the demo's): nothing to fit against Δn; named below */
			single++;
			continue;
		}
		fprintf(f, "<p class=\"note\"><b>");
		esc(f, m->name);
		fprintf(f, "</b>: eq. 5 ε(Δn) = α (1 − e<sup>−λ(Δn−1)</sup>) with α = %.3g, λ = %.3g (RMSE %.2g)",
			m->e5.alpha, m->e5.lambda, m->e5.rmse);
		fprintf(f, "; eq. 7 hit rate μ (1 − 1/Δn) with μ = %.3f; eq. 6 over %zu frames: ", m->mu, m->e6.frames);
		if (!m->e6.ok)
			fprintf(f, "not determined");
		else if (m->e6.three_terms)
			fprintf(f, "A<sub>hit</sub> = %.0f ns, A<sub>miss</sub> = %.0f ns per sample, c = %.1f ms (R² %.2f)",
				m->e6.a_hit * 1e6, m->e6.a_miss * 1e6, m->e6.c, m->e6.r2);
		else
			fprintf(f, "A<sub>miss</sub> − A<sub>hit</sub> = %.0f ns per sample, c′ = %.1f ms (R² %.2f; hits + "
				   "misses constant, so A<sub>hit</sub> and c are one term)",
				m->e6.miss_minus_hit * 1e6, m->e6.c, m->e6.r2);
		fprintf(f, "</p>\n<div class=\"scroll\"><table class=\"budget\"><tr><th>Δn</th><th>max-RGB mean</th>"
			   "<th>eq. 5</th><th>hit rate</th><th>eq. 7</th><th>GPU ms</th><th>eqs. 6+7</th></tr>\n");
		for (size_t i = 0; i < m->np; i++) {
			const mtr_reuse_point *p = &m->pts[i];
			fprintf(f, "<tr><td>%g</td>", p->dn);
			sty_rpt_cell(f, p->eps, "%.3f");
			sty_rpt_cell(f, mtr_reuse_eps(m, p->dn), "%.3f");
			sty_rpt_cell(f, p->hit_rate, "%.3f");
			sty_rpt_cell(f, mtr_reuse_hit_rate(m, p->dn), "%.3f");
			sty_rpt_cell(f, p->ms, "%.1f");
			sty_rpt_cell(f, mtr_reuse_ms(m, p->dn, p->visible), "%.1f");
			fprintf(f, "</tr>\n");
		}
		fprintf(f, "</table></div>\n");
	}
	if (single) {
		fprintf(f, "<p class=\"note\">Swept at fewer than two periods &gt; 1, so not fitted here:");
		for (size_t k = 0, n = 0; k < g->nreuse; k++)
			if (!g->reuse[k].e5.ok) {
				fprintf(f, "%s ", n++ ? "," : "");
				esc(f, g->reuse[k].name);
			}
		fprintf(f, " (sweep them at --periods 2,4,8 for these models).</p>\n");
	}
	if (single < g->nreuse)
		fprintf(f, "<p class=\"note\">Fitted to this sweep's runs of each method at its periods (Δn = N), error = "
			   "mean max-RGB against ref, frames after each run's first; all groups in data/reuse_model.csv. "
			   "<code>taslab analyze reuse-model</code> fits another metric.</p>\n");
}
