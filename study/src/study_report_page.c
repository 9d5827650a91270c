/* study_report_page.c — the sweep report's page, report/index.html (study_report.h; DESIGN section 9): header and
 * navigation, Table 1, the study section, and per scene x camera its plots, its runs (metrics, the study's Q, p_ref
 * and JND, the worst frame's images) and its clip pair played in sync.
 *
 * The page is self-contained (inline CSS and script, no network) and refers only to files under the sweep folder by
 * relative paths, so it opens from disk (file://) offline. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_report_internal.h"
#include "taslab/tl_clock.h"
#include "taslab/tl_fs.h"

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

void sty_rpt_cell(FILE *f, double v, const char *fmt)
{
	fputs("<td>", f);
	if (isfinite(v))
		mtr_fprint_shown(f, fmt, v);
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
		sty_rpt_cell(f, mtr_sweep_value(r, c->column), c->fmt);
}

static const char *CSS =
	"body{font:14px/1.45 system-ui,sans-serif;margin:0;color:#1b1f24;background:#f6f7f9}"
	"header{background:#1b2a3a;color:#fff;padding:18px 28px}header h1{margin:0 0 6px;font-size:22px}"
	"header p{margin:2px 0;opacity:.85}main{padding:10px 28px 40px}nav a{margin-right:12px}"
	"section{background:#fff;border:1px solid #dde1e6;border-radius:8px;padding:14px 18px;margin:18px 0}"
	"h2{margin:4px 0 10px;font-size:18px}h3{font-size:15px;margin:14px 0 6px}"
	"tr.tas td{font-weight:600;background:#f1f5fb}"
	".plots{display:grid;grid-template-columns:repeat(auto-fill,minmax(330px,1fr));gap:10px}"
	".plots figure{margin:0;border:1px solid #eceef1;border-radius:6px;padding:4px;background:#fff}"
	".plots img{width:100%;height:auto;display:block}figcaption{font-size:12px;color:#555;text-align:center}"
	"figure.wide{margin:0;max-width:960px}figure.wide img{width:100%;height:auto;display:block}"
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

static void page_table1(FILE *f, const sweep_spec *s, const sty_rpt_group *gi, size_t ng)
{
	fprintf(f, "<section id=\"table1\"><h2>Table 1: shaded samples and their reduction</h2>\n<p class=\"note\">Shaded "
		   "samples are the methods' own counts (DESIGN section 5), per frame; the reduction is 1 − shaded / "
		   "baseline's shaded (baseline %s) over the same frames; speedup = ref's median GPU frame time / the run's "
		   "(a variant with a period N: the median of its N-frame means, the amortised cost of a keyframe every N "
		   "frames; cf. paper Table 1, Fig. 12). Also in <a href=\"../table1.md\">table1.md</a> and "
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

/* The page's head, its header (scenes, variants, runs complete) and the navigation. */
static void page_head(FILE *f, const sty_report_desc *d, const sty_rpt_group *gi, size_t ng, bool gnuplot_note)
{
	const sweep_spec *s = d->spec;
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
	if (d->study || d->model)
		fprintf(f, "<a href=\"#study\">%s</a>", d->study ? "Study" : "Predicted thresholds");
	for (size_t g = 0; g < ng; g++) {
		const sweep_scene *sc = &s->scenes[gi[g].scene];
		char stem[256];
		sty_rpt_stem(s, gi[g].scene, gi[g].cam, stem, sizeof stem);
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
}

/* "t [lo, hi]" with two decimals, inf where open. */
static void thr_text(char *buf, size_t n, double t, double lo, double hi)
{
	char v[3][32];
	double x[3] = {t, lo, hi};
	for (int k = 0; k < 3; k++)
		snprintf(v[k], sizeof v[k], isinf(x[k]) ? "inf" : "%.2f", x[k]);
	snprintf(buf, n, "%s [%s, %s]", v[0], v[1], v[2]);
}

static void thr_row_start(FILE *f, const char *method, long period, const char *scene, const char *camera)
{
	fprintf(f, "<tr><td>");
	esc(f, method);
	fprintf(f, "</td><td>");
	if (period)
		fprintf(f, "%ld", period);
	fprintf(f, "</td><td>");
	esc(f, scene);
	fprintf(f, "</td><td>");
	esc(f, camera);
	fprintf(f, "</td>");
}

/* Issue 28: the measured thresholds (the tally's thresholds.csv) beside Fig. 3; with --model the model's predicted
 * threshold beside each, then the series of this sweep nobody rated with their prediction alone. */
static void page_thresholds(FILE *f, const sty_report_desc *d, const sty_rpt_study *t)
{
	if (!t->nthr && !d->model)
		return;
	char cell[128];
	fprintf(f, "<h3>Thresholds (T at 1 JND)</h3>\n<table id=\"thresholds\"><tr><th>method</th><th>period</th>"
		   "<th>scene</th><th>camera</th><th>trials</th><th>t_jnd [95%% CI]</th>");
	if (d->model)
		fprintf(f, "<th>predicted t_jnd [95%%]</th>");
	fprintf(f, "</tr>\n");
	for (size_t i = 0; i < t->nthr; i++) {
		const sty_threshold_row *h = &t->thr[i];
		thr_row_start(f, h->method, h->period, h->scene, h->camera);
		thr_text(cell, sizeof cell, h->f.t_jnd, h->f.t_jnd_lo, h->f.t_jnd_hi);
		fprintf(f, "<td>%zu</td><td>%s</td>", h->f.n, cell);
		const sty_model_pred *p = sty_rpt_pred_of(t, h);
		if (p)
			thr_text(cell, sizeof cell, p->t_jnd, p->t_jnd_lo, p->t_jnd_hi);
		if (d->model)
			fprintf(f, "<td>%s</td>", p ? cell : "–");
		fprintf(f, "</tr>\n");
	}
	for (size_t i = 0; i < t->npred; i++) {
		const sty_model_pred *p = &t->pred[i];
		if (sty_rpt_pred_rated(t, p))
			continue;
		thr_row_start(f, p->method, p->period, p->scene, p->camera);
		thr_text(cell, sizeof cell, p->t_jnd, p->t_jnd_lo, p->t_jnd_hi);
		fprintf(f, "<td>0</td><td>not rated</td><td>%s</td></tr>\n", cell);
	}
	fprintf(f, "</table>\n<p class=\"note\">t_jnd: the T at which the fitted p_ref of the median observer reaches "
		   "75%% (README \"Thresholds\"); inf: not reached up to the largest rated T.");
	if (t->nthr)
		fprintf(f, " Measured: <a href=\"study/thresholds.csv\">study/thresholds.csv</a>.");
	if (d->model) {
		fprintf(f, " Predicted by the model ");
		esc(f, d->model);
		fprintf(f, " from this sweep's ");
		esc(f, t->pred_metric);
		fprintf(f, " (README \"Metric → JND model\"): where the metric of each series of T reaches its value at 1 JND; "
			   "95%% interval from the model's leave-one-scene-out error; – for pooled rows and series this "
			   "sweep lacks.");
	}
	fprintf(f, " Data: <a href=\"data/thresholds.csv\">data/thresholds.csv</a>.</p>\n");
}

/* The study section: where the tally is, what Q, p_ref and JND are, what the join could not do, Fig. 3 and the JND
 * plot. */
static void page_study(FILE *f, const sty_report_desc *d, const sty_rpt_study *t, bool jnd_plot)
{
	const char *jnd_metric = d->jnd_metric ? d->jnd_metric : "flip_mean";
	fprintf(f, "<section id=\"study\"><h2>Study</h2><p class=\"note\">From ");
	esc(f, d->study);
	fprintf(f, " (tally in <a href=\"study/conditions.csv\">study/conditions.csv</a>, all tables in "
		   "<a href=\"study/tables.md\">study/tables.md</a>): Q = mean reference-relative "
		   "rating (+2: reference much better), p_ref = share preferring the reference (ties halved), JND = "
		   "Φ⁻¹(p_ref)/Φ⁻¹(0.75), 95%% intervals (DESIGN section 7). Joined per condition (method, T, period, "
		   "scene, camera) in <a href=\"data/study.csv\">data/study.csv</a>.</p>\n");
	if (t->unchecked[0]) {
		fprintf(f, "<p class=\"missing\">Not checked: ");
		esc(f, t->unchecked);
		fprintf(f, ".</p>\n");
	} else
		fprintf(f, "<p class=\"note\">The study's stimuli were checked against this sweep's runs (frames, size, "
			   "fps, display transform, scene and colour digests; clips taken from a sweep byte for byte).</p>\n");
	if (t->missing_count) {
		fprintf(f, "<p class=\"missing\">%zu condition(s) of the study have no run in this sweep and are not joined: ",
			t->missing_count);
		esc(f, t->missing);
		fprintf(f, ".</p>\n");
	}
	fprintf(f, "<h3>Fig. 3: quality against T</h3>\n");
	if (t->fig3)
		fprintf(f, "<figure class=\"wide\"><img src=\"plots/fig3.svg\" alt=\"Fig. 3: Q and p_ref against T\">"
			   "<figcaption>As the paper's Fig. 3 (sec. 3): Q with its 95%% t interval (cut to −2..2) and p_ref "
			   "with its 95%% Wilson interval, per method, pooled over scenes and camera paths; dashed: 1 JND "
			   "(p_ref = 75%%). Data: <a href=\"data/fig3.csv\">data/fig3.csv</a>.</figcaption></figure>\n");
	else
		fprintf(f, "<p class=\"note\">%s</p>\n", t->fig3_points ? "Fig. 3 was not drawn (gnuplot failed or is missing); "
									  "its data are in data/fig3.csv."
									: "No rated condition has a threshold T: no Fig. 3.");
	page_thresholds(f, d, t);
	if (jnd_plot)
		fprintf(f, "<h3>JND against %s</h3><figure class=\"wide\" style=\"max-width:720px\"><img src=\"plots/jnd.svg\" "
			   "alt=\"JND against %s\"></figure>\n",
			jnd_metric, jnd_metric);
	else
		fprintf(f, "<p class=\"note\">No condition of the study matches a run with %s: no JND plot.</p>\n", jnd_metric);
	fprintf(f, "</section>\n");
}

/* A group's plots against T and its coherence curves. */
static void page_group_plots(FILE *f, const sty_rpt_group *g, const char *stem)
{
	fprintf(f, "<h3>Against T</h3><div class=\"plots\">\n");
	bool any = false;
	for (size_t k = 0; k < STY_RPT_PLOT_COUNT; k++) {
		if (!g->drawn[k] || !g->plots_ok)
			continue;
		any = true;
		fprintf(f, "<figure><img src=\"plots/");
		esc(f, stem);
		fprintf(f, "--%s.svg\" alt=\"%s\"><figcaption>%s</figcaption></figure>\n", sty_rpt_plots[k].name,
			sty_rpt_plots[k].title, sty_rpt_plots[k].title);
	}
	if (g->coherence) {
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
		STY_RPT_HEAT_MAX);
}

/* A group's runs: metrics, the study's Q, p_ref and JND, the worst frame's images. */
static void page_group_runs(FILE *f, const sty_report_desc *d, const sty_rpt_group *g, const char *stem,
			    const sty_rpt_study *study)
{
	fprintf(f, "<h3>Runs</h3><div class=\"scroll\"><table><tr><th class=\"l\">variant</th><th>reuse</th>"
		   "<th>reduction</th><th>speedup</th><th>exceed_T</th><th>exceed_8</th><th>p99</th><th>flicker</th>"
		   "<th>FLIP</th><th>PSNR</th><th>late</th>");
	if (d->study)
		fprintf(f, "<th>Q [95%%]</th><th>p_ref [95%%]</th><th>JND [95%%]</th>");
	fprintf(f, "<th>frame</th><th>ref</th><th>variant</th><th>difference</th></tr>\n");
	for (size_t i = 0; i < g->n; i++) {
		const mtr_sweep_row *r = g->rows[i].r;
		const sweep_variant *v = g->rows[i].v;
		fprintf(f, "<tr><td class=\"l\">");
		esc(f, v->variant);
		fprintf(f, "</td>");
		if (!r->status.run) {
			fprintf(f, "<td class=\"missing\" colspan=\"9\">run missing or failed (see ../logs/)</td></tr>\n");
			continue;
		}
		cells(f, r, RUN_CELLS);
		if (d->study) {
			const sty_rpt_cond *c = sty_rpt_study_find(study, d->spec, r);
			if (c)
				fprintf(f, "<td>%.2f [%.2f, %.2f]</td><td>%.2f [%.2f, %.2f]</td><td>%.2f [%.2f, %.2f]</td>", c->Q,
					c->Q_lo, c->Q_hi, c->p, c->p_lo, c->p_hi, c->jnd, c->jnd_lo, c->jnd_hi);
			else
				fprintf(f, "<td>–</td><td>–</td><td>–</td>");
		}
		fprintf(f, "<td>%u</td>", r->worst_frame);
		if (g->ref && g->ref->status.run) {
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
}

/* A group's clip pair: the reference beside a chosen variant, played in sync (SCRIPT). */
static void page_group_clips(FILE *f, const sty_rpt_group *g, const sweep_scene *sc, const sweep_camera *cam)
{
	char ref_clip[1024] = "", first_clip[1024] = "";
	if (g->ref && g->ref->status.clip)
		snprintf(ref_clip, sizeof ref_clip, "../clips/%s/%s/ref.webm", sc->name, cam->name);
	size_t nclips = 0;
	for (size_t i = 0; i < g->n; i++)
		if (g->rows[i].r->status.clip) {
			if (!nclips++)
				snprintf(first_clip, sizeof first_clip, "../clips/%s/%s/%s.webm", sc->name, cam->name, g->rows[i].v->id);
		}
	if (!ref_clip[0] || !nclips)
		return;
	fprintf(f, "<h3>Clips</h3><div class=\"player\" data-fps=\"%g\"><div class=\"ctl\"><button type=\"button\">"
		   "play both</button><label>variant <select>", sc->fps);
	for (size_t i = 0; i < g->n; i++) {
		if (!g->rows[i].r->status.clip)
			continue;
		fprintf(f, "<option value=\"../clips/");
		esc(f, sc->name);
		fputc('/', f);
		esc(f, cam->name);
		fprintf(f, "/%s.webm\">", g->rows[i].v->id);
		esc(f, g->rows[i].v->variant);
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

/* One scene x camera section. */
static void page_group(FILE *f, const sty_report_desc *d, const sty_rpt_group *g, const sty_rpt_study *study,
		       const mtr_match_pair *pairs, size_t np)
{
	const sweep_scene *sc = &d->spec->scenes[g->scene];
	const sweep_camera *cam = &sc->cameras[g->cam];
	char stem[256];
	sty_rpt_stem(d->spec, g->scene, g->cam, stem, sizeof stem);
	fprintf(f, "<section id=\"");
	esc(f, stem);
	fprintf(f, "\"><h2>");
	esc(f, sc->name);
	fputs(" / ", f);
	esc(f, cam->name);
	fprintf(f, " <span class=\"note\">(%s camera, %u frames)</span></h2>\n", cam->motion, sc->end - sc->first);
	page_group_plots(f, g, stem);
	sty_rpt_budget_html(f, d, g, stem, pairs, np);
	sty_rpt_reuse_html(f, d, g);
	page_group_runs(f, d, g, stem, study);
	page_group_clips(f, g, sc, cam);
	fprintf(f, "</section>\n");
}

int sty_rpt_page_write(const sty_report_desc *d, const char *path, const sty_rpt_group *gi, size_t ng,
		       const sty_rpt_study *study, bool gnuplot_note, bool jnd_plot, char *err, size_t err_size)
{
	mtr_match_pair *pairs;
	size_t np;
	int rc = mtr_sweep_matched(d->spec, d->rows, d->count, &pairs, &np, err, err_size);
	if (rc)
		return rc;
	tl_atomic page;
	if ((rc = tl_atomic_open(&page, path, err, err_size))) {
		free(pairs);
		return rc;
	}
	FILE *f = page.f;
	page_head(f, d, gi, ng, gnuplot_note);
	page_table1(f, d->spec, gi, ng);
	sty_rpt_page_stereo(f, d);
	if (d->study)
		page_study(f, d, study, jnd_plot);
	else if (d->model) { /* a sweep nobody rated: the predictions alone */
		fprintf(f, "<section id=\"study\"><h2>Predicted thresholds</h2>\n");
		page_thresholds(f, d, study);
		fprintf(f, "</section>\n");
	}
	for (size_t g = 0; g < ng; g++)
		page_group(f, d, &gi[g], study, pairs, np);
	free(pairs);
	fprintf(f, "</main>\n<script>\n%s</script>\n</body></html>\n", SCRIPT);
	return tl_atomic_commit(&page, err, err_size);
}
