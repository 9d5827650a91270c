/* study_report_stereo.c — a stereo sweep's speedups beside a mono sweep's (issue 25; paper sec. 7.3, Fig. 12a: TASA's
 * speedup over Forward+ is 2-5x in stereo against 1.1-3x in mono, because ref shades both eyes and the atlas shades
 * the blocks both eyes see once). `taslab report STEREO_SWEEP --mono MONO_SWEEP` matches each stereo run with the
 * mono run of the same scene, camera path, variant, frames and size (per eye) and writes SWEEP/stereo_vs_mono.csv
 * and a section of the page: speedup vs ref in mono and in stereo and their ratio, shaded samples per frame in mono
 * and in stereo (both eyes) and their ratio; and the plot of the speedups, mono beside stereo per run
 * (report/data/stereo--speedup.csv and .gp, report/plots/stereo--speedup.svg; gnuplot, as the report's other plots). */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "study_report_internal.h"
#include "taslab/metrics.h"
#include "taslab/tl_fs.h"

/* The mono row of stereo row r (same scene name, camera name, variant token, frames, size), or NULL. */
static const mtr_sweep_row *mono_of(const sty_report_desc *d, const mtr_sweep_row *r)
{
	const sweep_spec *s = d->spec, *m = d->mono_spec;
	const sweep_scene *sc = &s->scenes[r->run.scene];
	for (size_t i = 0; i < d->mono_count; i++) {
		const mtr_sweep_row *x = &d->mono_rows[i];
		const sweep_scene *mc = &m->scenes[x->run.scene];
		if (!strcmp(mc->name, sc->name) && !strcmp(mc->cameras[x->run.camera].name, sc->cameras[r->run.camera].name) &&
		    !strcmp(m->variants[x->run.variant].variant, s->variants[r->run.variant].variant) &&
		    mc->first == sc->first && mc->end == sc->end && m->width == s->width && m->height == s->height)
			return x;
	}
	return NULL;
}

static double ratio(double a, double b) { return isfinite(a) && isfinite(b) && b > 0 ? a / b : NAN; }

static void num(FILE *f, double v, const char *fmt, const char *none)
{
	if (isfinite(v))
		fprintf(f, fmt, v);
	else
		fputs(none, f);
}

/* The speedup plot: one cluster per stereo run with a complete mono run (scene / path variant), bars mono and stereo,
 * the dashed line at 1 (ref). Optional like every plot of the report: no gnuplot, no plot (the table stays). */
static void speedup_plot(const sty_report_desc *d)
{
	char data[TL_PATH_MAX + 64], gp[TL_PATH_MAX + 64], svg[TL_PATH_MAX + 64], err[512];
	snprintf(data, sizeof data, "%s/report/data/stereo--speedup.csv", d->dir);
	snprintf(gp, sizeof gp, "%s/report/data/stereo--speedup.gp", d->dir);
	snprintf(svg, sizeof svg, "%s/report/plots/stereo--speedup.svg", d->dir);
	remove(svg); /* a plot from an earlier report is not this one's */
	tl_atomic a;
	if (tl_atomic_open(&a, data, err, sizeof err))
		return;
	size_t n = 0;
	double top = 1.0;
	fprintf(a.f, "# run,speedup_mono,speedup_stereo\n");
	for (size_t i = 0; i < d->count; i++) {
		const mtr_sweep_row *r = &d->rows[i], *m = mono_of(d, r);
		if (!r->status.run || !m || !m->status.run)
			continue;
		double sm = mtr_sweep_value(m, "speedup_vs_ref"), ss = mtr_sweep_value(r, "speedup_vs_ref");
		if (!isfinite(sm) || !isfinite(ss))
			continue;
		const sweep_scene *sc = &d->spec->scenes[r->run.scene];
		/* labels: gnuplot strings in double quotes (names are [A-Za-z0-9_@/.-], sweep_keys) */
		fprintf(a.f, "\"%s/%s %s\",%.4f,%.4f\n", sc->name, sc->cameras[r->run.camera].name,
			d->spec->variants[r->run.variant].variant, sm, ss);
		top = fmax(top, fmax(sm, ss));
		n++;
	}
	if (tl_atomic_commit(&a, err, sizeof err) || !n)
		return;
	mtr_plot plot;
	FILE *f = mtr_plot_begin(&plot, gp, err, sizeof err);
	if (!f)
		return;
	fprintf(f, "set terminal svg size %zu,320 dynamic font 'sans,10' background rgb 'white'\nset datafile separator ','\n"
		   "set output '%s'\nset title 'speedup vs ref: mono beside stereo (ref stereo for stereo)'\n"
		   "set grid ytics\nset key outside right noenhanced\nset termoption noenhanced\nset style data histogram\n"
		   "set style histogram cluster gap 1\nset style fill solid 0.85 border -1\nset boxwidth 0.9\n"
		   "set xtics rotate by -30 scale 0\nset yrange [0:%.3f]\nset ylabel 'speedup (ref ms / run ms)'\n"
		   "set arrow from graph 0, first 1 to graph 1, first 1 nohead dt 2 lc rgb '#555555'\n"
		   "plot '%s' using 2:xtic(1) title 'mono' lc rgb '#4477aa', '' using 3 title 'stereo' lc rgb '#ee6677'\n",
		n * 60 + 260 > 1200 ? (size_t)1200 : n * 60 + 260, svg, top * 1.15, data);
	mtr_plot_end(&plot, err, sizeof err);
}

int sty_rpt_stereo_csv(const sty_report_desc *d, char *err, size_t err_size)
{
	if (!d->mono_spec)
		return TL_OK;
	char path[TL_PATH_MAX + 32];
	snprintf(path, sizeof path, "%s/stereo_vs_mono.csv", d->dir);
	tl_atomic a;
	int rc = tl_atomic_open(&a, path, err, err_size);
	if (rc)
		return rc;
	fprintf(a.f, "scene,camera,camera_motion,variant,speedup_mono,speedup_stereo,speedup_ratio,shaded_per_frame_mono,"
		     "shaded_per_frame_stereo,shaded_ratio,gpu_ms_median_mono,gpu_ms_median_stereo\n");
	for (size_t i = 0; i < d->count; i++) {
		const mtr_sweep_row *r = &d->rows[i], *m = mono_of(d, r);
		const sweep_scene *sc = &d->spec->scenes[r->run.scene];
		double sm = m && m->status.run ? mtr_sweep_value(m, "speedup_vs_ref") : NAN;
		double ss = r->status.run ? mtr_sweep_value(r, "speedup_vs_ref") : NAN;
		double pm = m && m->status.run ? mtr_sweep_value(m, "shaded_per_frame") : NAN;
		double ps = r->status.run ? mtr_sweep_value(r, "shaded_per_frame") : NAN;
		double gm = m && m->status.run ? mtr_sweep_value(m, "gpu_ms_median") : NAN;
		double gs = r->status.run ? mtr_sweep_value(r, "gpu_ms_median") : NAN;
		fprintf(a.f, "%s,%s,%s,%s,", sc->name, sc->cameras[r->run.camera].name, sc->cameras[r->run.camera].motion,
			d->spec->variants[r->run.variant].variant);
		num(a.f, sm, "%.4f", ""), fputc(',', a.f), num(a.f, ss, "%.4f", ""), fputc(',', a.f);
		num(a.f, ratio(ss, sm), "%.4f", ""), fputc(',', a.f), num(a.f, pm, "%.1f", ""), fputc(',', a.f);
		num(a.f, ps, "%.1f", ""), fputc(',', a.f), num(a.f, ratio(ps, pm), "%.4f", ""), fputc(',', a.f);
		num(a.f, gm, "%.4f", ""), fputc(',', a.f), num(a.f, gs, "%.4f", ""), fputc('\n', a.f);
	}
	if ((rc = tl_atomic_commit(&a, err, err_size)))
		return rc;
	speedup_plot(d);
	return TL_OK;
}

void sty_rpt_page_stereo(FILE *f, const sty_report_desc *d)
{
	const sweep_spec *s = d->spec;
	if (!s->stereo)
		return;
	fprintf(f, "<section id=\"stereo\"><h2>Stereo (both eyes, %ux%u per eye, ipd %g m)</h2>\n", s->width, s->height,
		s->ipd);
	if (!d->mono_spec) {
		fprintf(f, "<p class=\"note\">Shaded samples and frame times are totals over both eyes. To see the stereo "
			   "speedups beside mono, give a mono sweep of the same scenes, paths, variants, frames and size: "
			   "<code>taslab report SWEEP --mono MONO_SWEEP</code>.</p></section>\n");
		return;
	}
	fprintf(f, "<p class=\"note\">Each run beside the mono run of the same scene, path, variant, frames and size (mono "
		   "sweep <code>");
	for (const char *c = d->mono_dir; *c; c++)
		fputs(*c == '<' ? "&lt;" : *c == '>' ? "&gt;" : *c == '&' ? "&amp;" : (char[2]){*c, 0}, f);
	fprintf(f, "</code>). Speedup = ref's median GPU frame time / the run's, ref of the same sweep (stereo: ref "
		   "stereo). Paper (sec. 7.3, Fig. 12a): TASA 2–5× over Forward+ in stereo, 1.1–3× in mono. Also in "
		   "<a href=\"../stereo_vs_mono.csv\">stereo_vs_mono.csv</a>.</p>\n");
	char svg[TL_PATH_MAX + 64];
	snprintf(svg, sizeof svg, "%s/report/plots/stereo--speedup.svg", d->dir);
	if (access(svg, R_OK) == 0)
		fprintf(f, "<div class=\"plots\"><figure><img src=\"plots/stereo--speedup.svg\" alt=\"speedup vs ref, mono "
			   "beside stereo\"><figcaption>speedup vs ref per run, mono beside stereo (data: <a "
			   "href=\"data/stereo--speedup.csv\">stereo--speedup.csv</a>); the dashed line is ref"
			   "</figcaption></figure></div>\n");
	fprintf(f, "<div class=\"scroll\"><table><tr>"
		   "<th class=\"l\">scene</th><th class=\"l\">camera</th><th class=\"l\">variant</th><th>speedup mono</th>"
		   "<th>speedup stereo</th><th>stereo / mono</th><th>shaded / frame mono</th><th>shaded / frame stereo</th>"
		   "<th>stereo / mono</th></tr>\n");
	for (size_t i = 0; i < d->count; i++) {
		const mtr_sweep_row *r = &d->rows[i], *m = mono_of(d, r);
		const sweep_scene *sc = &s->scenes[r->run.scene];
		fprintf(f, "<tr><td class=\"l\">%s</td><td class=\"l\">%s (%s)</td><td class=\"l\">%s</td>", sc->name,
			sc->cameras[r->run.camera].name, sc->cameras[r->run.camera].motion, s->variants[r->run.variant].variant);
		if (!r->status.run || !m || !m->status.run) {
			fprintf(f, "<td class=\"missing\" colspan=\"6\">%s</td></tr>\n",
				!r->status.run ? "stereo run missing or failed" : "no complete mono run to match");
			continue;
		}
		double sm = mtr_sweep_value(m, "speedup_vs_ref"), ss = mtr_sweep_value(r, "speedup_vs_ref");
		double pm = mtr_sweep_value(m, "shaded_per_frame"), ps = mtr_sweep_value(r, "shaded_per_frame");
		fputs("<td>", f), num(f, sm, "%.2f×", "–"), fputs("</td><td>", f), num(f, ss, "%.2f×", "–");
		fputs("</td><td>", f), num(f, ratio(ss, sm), "%.2f", "–"), fputs("</td><td>", f), num(f, pm, "%.0f", "–");
		fputs("</td><td>", f), num(f, ps, "%.0f", "–"), fputs("</td><td>", f), num(f, ratio(ps, pm), "%.2f", "–");
		fputs("</td></tr>\n", f);
	}
	fprintf(f, "</table></div></section>\n");
}
