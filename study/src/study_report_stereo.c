/* study_report_stereo.c — a stereo sweep's speedups beside a mono sweep's (issue 25; paper sec. 7.3, Fig. 12a: TASA's
 * speedup over Forward+ is 2-5x in stereo against 1.1-3x in mono, because ref shades both eyes and the atlas shades
 * the blocks both eyes see once). `taslab report STEREO_SWEEP --mono MONO_SWEEP` matches each stereo run with the
 * mono run of the same scene, camera path, variant, frames and size (per eye) and writes SWEEP/stereo_vs_mono.csv
 * and a section of the page: speedup vs ref in mono and in stereo and their ratio, shaded samples per frame in mono
 * and in stereo (both eyes) and their ratio. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "study_report_internal.h"
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
	return tl_atomic_commit(&a, err, err_size);
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
		   "<a href=\"../stereo_vs_mono.csv\">stereo_vs_mono.csv</a>.</p>\n<div class=\"scroll\"><table><tr>"
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
