/* study_tally_write.c — the tally's files from its result (study_result.h sty_tally_write; study.h sty_tally): one
 * writer per file — observers.csv, conditions.csv, anova.csv, posthoc.csv, jod.csv, tables.md, fig3.csv,
 * conditions.json, anova.json, thresholds.csv (study_threshold_rows.c) — and the Fig. 3 plot (gnuplot). Every CSV
 * has T and period right after method (DESIGN section 4; empty where the variant has none; thresholds.csv has period
 * only, its rows span T), and text cells are written with sty_csv_cell (no spreadsheet
 * formulas). The files appear together or not at all (tl_atomic_commit_set). */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "study_internal.h"
#include "study_threshold_rows.h"
#include "taslab/metrics.h"
#include "taslab/study_result.h"
#include "taslab/tl_fs.h"
#include "taslab/tl_json.h"

/* Every file a tally writes into its folder (fig3.png is gnuplot's, drawn from fig3.gp and fig3.csv). */
static const char *const TALLY_FILES[] = {"observers.csv", "conditions.csv", "anova.csv", "posthoc.csv", "jod.csv",
					  "tables.md", "fig3.csv", "conditions.json", "anova.json", "thresholds.csv", "fig3.gp",
					  "fig3.png"};
#define TALLY_SET 10 /* the first ten are written as one set (tl_atomic_commit_set) */
enum { F_OBSERVERS, F_CONDITIONS, F_ANOVA, F_POSTHOC, F_JOD, F_TABLES, F_FIG3, F_CONDITIONS_JSON, F_ANOVA_JSON,
       F_THRESHOLDS };

/* Numbers follow the study's one convention (study_internal.h sty_num_cell, issue 27.10): undefined is an empty
 * cell (CSV), null (JSON) or "–" (Markdown); infinite is inf / -inf (JSON: the strings). */
static void csv_num(FILE *f, double v, const char *fmt)
{
	char b[64];
	fputs(sty_num_cell(v, fmt, b, sizeof b), f);
}

static const char *md_num(double v, const char *fmt, char *b, size_t n)
{
	sty_num_cell(v, fmt, b, n);
	if (!b[0])
		snprintf(b, n, "–");
	return b;
}

static json_t *num_json(double v)
{
	return isnan(v) ? json_null() : isinf(v) ? json_string(v > 0 ? "inf" : "-inf") : json_real(v);
}

/* A variant's cells: cm, the method as a CSV cell; Ts and Ps, T and period ("" for none); TP, "T,period". */
typedef struct variant_cells {
	char cm[80], Ts[32], Ps[16], TP[64];
} variant_cells;

static void cells_of(const sty_variant *v, variant_cells *c)
{
	sty_csv_cell(v->method, c->cm, sizeof c->cm);
	if (isnan(v->T))
		c->Ts[0] = 0;
	else
		snprintf(c->Ts, sizeof c->Ts, "%g", v->T);
	if (!v->period)
		c->Ps[0] = 0;
	else
		snprintf(c->Ps, sizeof c->Ps, "%u", v->period);
	snprintf(c->TP, sizeof c->TP, "%s,%s", c->Ts, c->Ps);
}

static json_t *T_json(const sty_variant *v) { return isnan(v->T) ? json_null() : json_real(v->T); }
static json_t *period_json(const sty_variant *v) { return v->period ? json_integer(v->period) : json_null(); }

/* ------------------------------------------------------------------ one writer per file */

static void write_observers(FILE *f, const sty_result *r)
{
	fprintf(f, "participant,catch_n,catch_mean_abs_answer,catch_much_better,flagged,broken,rating_variance,p910,gold_n,"
		   "gold_wrong\n");
	for (size_t i = 0; i < r->observer_count; i++) {
		const sty_observer *o = &r->observers[i];
		char label[160];
		fprintf(f, "%s,%d,", sty_csv_cell(o->label, label, sizeof label), o->catch_n);
		if (o->catch_n)
			fprintf(f, "%.4f", o->catch_mean_abs);
		fprintf(f, ",%d,%d,%d,", o->catch_much_better, o->flagged, o->broken);
		csv_num(f, o->rating_variance, "%.4f");
		/* the P.910-crowd flags, ';'-joined (study_result.h): catch (a catch answer outside -1..1), gold (a gold
		 * answer more than one step from "reference much better"), variance (straightlining) */
		static const struct { unsigned bit; const char *name; } flags[] = {
			{STY_P910_CATCH, "catch"}, {STY_P910_GOLD, "gold"}, {STY_P910_VARIANCE, "variance"}};
		fputc(',', f);
		for (size_t k = 0, any = 0; k < sizeof flags / sizeof *flags; k++)
			if (o->p910 & flags[k].bit)
				fprintf(f, "%s%s", any++ ? ";" : "", flags[k].name);
		fprintf(f, ",%d,%d\n", o->gold_n, o->gold_wrong);
	}
}

static void write_conditions(FILE *f, const sty_result *r)
{
	fprintf(f, "method,T,period,scene,camera,n,Q,Q_lo,Q_hi,p_ref,p_ref_lo,p_ref_hi,jnd\n");
	for (size_t i = 0; i < r->row_count; i++) {
		const sty_row *w = &r->rows[i];
		variant_cells vc;
		char csc[160], cca[160];
		cells_of(&r->variants[w->variant], &vc);
		fprintf(f, "%s,%s,%s,%s,%zu,", vc.cm, vc.TP, sty_csv_cell(w->scene, csc, sizeof csc),
			sty_csv_cell(w->camera, cca, sizeof cca), w->n);
		csv_num(f, w->Q, "%.6f"), fputc(',', f);
		csv_num(f, w->Q_lo, "%.6f"), fputc(',', f);
		csv_num(f, w->Q_hi, "%.6f"), fputc(',', f);
		csv_num(f, w->j.p, "%.6f"), fputc(',', f);
		csv_num(f, w->j.p_lo, "%.6f"), fputc(',', f);
		csv_num(f, w->j.p_hi, "%.6f"), fputc(',', f);
		csv_num(f, w->j.jnd, "%.6f"), fputc('\n', f);
	}
}

static void write_jod(FILE *f, const sty_result *r)
{
	fprintf(f, "method,T,period,scene,camera,jod,jod_lo,jod_hi,participants\n");
	for (size_t i = 0; i < r->row_count; i++) {
		const sty_row *w = &r->rows[i];
		variant_cells vc;
		char csc[160], cca[160];
		cells_of(&r->variants[w->variant], &vc);
		fprintf(f, "%s,%s,%s,%s,", vc.cm, vc.TP, sty_csv_cell(w->scene, csc, sizeof csc),
			sty_csv_cell(w->camera, cca, sizeof cca));
		csv_num(f, w->jod, "%.6f"), fputc(',', f);
		csv_num(f, w->jod_lo, "%.6f"), fputc(',', f);
		csv_num(f, w->jod_hi, "%.6f");
		fprintf(f, ",%zu\n", w->participants);
	}
}

/* Fig. 3's points: the pooled row of every variant with a threshold. */
static void write_fig3(FILE *f, const sty_result *r)
{
	fprintf(f, "method,T,period,Q,Q_lo,Q_hi,p_ref_percent,p_ref_lo_percent,p_ref_hi_percent\n");
	for (size_t i = 0; i < r->row_count; i++) {
		const sty_row *w = &r->rows[i];
		if (!w->pooled || isnan(r->variants[w->variant].T))
			continue;
		variant_cells vc;
		cells_of(&r->variants[w->variant], &vc);
		fprintf(f, "%s,%s,", vc.cm, vc.TP);
		csv_num(f, w->Q, "%.6f"), fputc(',', f);
		csv_num(f, w->Q_lo, "%.6f"), fputc(',', f);
		csv_num(f, w->Q_hi, "%.6f"), fputc(',', f);
		csv_num(f, 100 * w->j.p, "%.4f"), fputc(',', f);
		csv_num(f, 100 * w->j.p_lo, "%.4f"), fputc(',', f);
		csv_num(f, 100 * w->j.p_hi, "%.4f"), fputc('\n', f);
	}
}

/* A text cell of tables.md: '|' escaped, line breaks as spaces. */
static const char *md_text(const char *t, char *b, size_t n)
{
	size_t k = 0;
	for (; *t && k + 3 < n; t++) {
		if (*t == '|')
			b[k++] = '\\';
		b[k++] = *t == '\n' || *t == '\r' ? ' ' : *t;
	}
	b[k] = 0;
	return b;
}

/* A variant in a sentence: its method, then " T=8" and " period 4" where it has them. */
static void variant_name(const sty_variant *v, char *b, size_t n)
{
	int k = snprintf(b, n, "%s", v->method);
	if (!isnan(v->T) && k > 0 && (size_t)k < n)
		k += snprintf(b + k, n - (size_t)k, " T=%g", v->T);
	if (v->period && k > 0 && (size_t)k < n)
		snprintf(b + k, n - (size_t)k, " period %u", v->period);
}

/* tables.md (issue 27.11): every table of the tally — conditions, ANOVA with the reason where there is none, post
 * hoc tests, observer screening and JOD — in the same units and conventions as the CSV files. */
/* The model's predictions (tally --model), or none. */
typedef struct preds {
	const char *model;
	sty_model_pred *p;
	size_t n;
} preds;

static void write_tables(FILE *f, const sty_result *r, const preds *pr)
{
	char a[64], b[64], c[64], d[64], e[64], g[64], h[64], sc[160], ca[160];
	fprintf(f, "# Study results\n\n## Conditions\n\n| method | T | period | scene | camera | n | Q [95%% CI] | p_ref [95%% CI] | JND |\n"
		   "|---|---|---|---|---|---|---|---|---|\n");
	for (size_t i = 0; i < r->row_count; i++) {
		const sty_row *w = &r->rows[i];
		const sty_variant *v = &r->variants[w->variant];
		variant_cells vc;
		cells_of(v, &vc);
		fprintf(f, "| %s | %s | %s | %s | %s | %zu | %s [%s, %s] | %s%% [%s, %s] | %s |\n", v->method, vc.Ts, vc.Ps,
			md_text(w->scene, sc, sizeof sc), md_text(w->camera, ca, sizeof ca), w->n, md_num(w->Q, "%.2f", a, sizeof a),
			md_num(w->Q_lo, "%.2f", b, sizeof b), md_num(w->Q_hi, "%.2f", c, sizeof c),
			md_num(100 * w->j.p, "%.1f", d, sizeof d), md_num(100 * w->j.p_lo, "%.1f", e, sizeof e),
			md_num(100 * w->j.p_hi, "%.1f", g, sizeof g), md_num(w->j.jnd, "%.2f", h, sizeof h));
	}
	fprintf(f, "\nQ: mean reference-relative rating (+2 = reference much better) with a 95%% t interval over "
		   "participants, cut to the scale -2..2; p_ref: share of answers preferring the reference (ties count half), "
		   "Wilson interval; JND = Phi^-1(p_ref)/Phi^-1(0.75). \"–\": undefined (fewer than two participants).\n");

	fprintf(f, "\n## Repeated-measures ANOVA (camera motion x scene, per variant)\n\n");
	if (r->anova_count)
		fprintf(f, "| method | T | period | effect | df1 | df2 | F | p | epsilon (GG) | p (GG) | participants |\n"
			   "|---|---|---|---|---|---|---|---|---|---|---|\n");
	else
		fprintf(f, "None: no variant could be analysed (why, per variant, below).\n");
	for (size_t i = 0; i < r->anova_count; i++) {
		const sty_anova_row *x = &r->anova[i];
		variant_cells vc;
		cells_of(&r->variants[x->variant], &vc);
		fprintf(f, "| %s | %s | %s | %s | %g | %g | %s | %s | %s | %s | %zu |\n", r->variants[x->variant].method, vc.Ts,
			vc.Ps, x->effect, x->e.df1, x->e.df2, md_num(x->e.F, "%.3f", a, sizeof a), md_num(x->e.p, "%.4g", b, sizeof b),
			md_num(x->e.epsilon_gg, "%.4f", c, sizeof c), md_num(x->e.p_gg, "%.4g", d, sizeof d), x->participants);
	}
	int notes = 0;
	for (size_t v = 0; v < r->variant_count; v++)
		if (r->variants[v].anova_note[0]) {
			char name[96];
			int rows = 0;
			for (size_t i = 0; i < r->anova_count; i++)
				rows += r->anova[i].variant == v;
			variant_name(&r->variants[v], name, sizeof name);
			fprintf(f, "%s- %s: %s%s.\n", notes++ ? "" : "\n", name, rows ? "" : "no ANOVA: ",
				r->variants[v].anova_note);
		}
	fprintf(f, "\nDependent variable: each participant's mean rating per cell; participants with every cell only. "
		   "GG: Greenhouse-Geisser.\n");

	fprintf(f, "\n## Post hoc paired t tests (Bonferroni)\n\n");
	if (!r->posthoc_count)
		fprintf(f, "None: no variant has an ANOVA with a factor of two or more levels.\n");
	else {
		fprintf(f, "| method | T | period | factor | level 1 | level 2 | t | df | p | p (Bonferroni) |\n"
			   "|---|---|---|---|---|---|---|---|---|---|\n");
		for (size_t i = 0; i < r->posthoc_count; i++) {
			const sty_posthoc_row *h = &r->posthoc[i];
			variant_cells vc;
			cells_of(&r->variants[h->variant], &vc);
			fprintf(f, "| %s | %s | %s | %s | %s | %s | %s | %g | %s | %s |\n", r->variants[h->variant].method,
				vc.Ts, vc.Ps, h->factor, md_text(h->level_1, sc, sizeof sc), md_text(h->level_2, ca, sizeof ca),
				md_num(h->t, "%.3f", a, sizeof a), h->df, md_num(h->p, "%.4g", b, sizeof b),
				md_num(h->p_bonferroni, "%.4g", c, sizeof c));
		}
	}

	fprintf(f, "\n## Observers (catch-trial screening)\n\n| participant | catch trials | mean abs answer | much better | "
		   "flagged |\n|---|---|---|---|---|\n");
	size_t flagged = 0;
	for (size_t i = 0; i < r->observer_count; i++) {
		const sty_observer *o = &r->observers[i];
		flagged += o->flagged;
		fprintf(f, "| %s | %d | %s | %d | %s |\n", md_text(o->label, sc, sizeof sc), o->catch_n,
			md_num(o->catch_mean_abs, "%.2f", a, sizeof a), o->catch_much_better, o->flagged ? "yes" : "no");
	}
	fprintf(f, "\nFlagged: more than half of the catch answers (reference against itself) \"much better\". %zu of %zu "
		   "flagged; %zu left out of the statistics%s.\n",
		flagged, r->observer_count, r->left_out, flagged && !r->left_out ? " (--keep-flagged)" : "");
	size_t catches = 0, gold = 0, gold_n = 0, variance = 0, broken = 0;
	for (size_t i = 0; i < r->observer_count; i++) {
		catches += (r->observers[i].p910 & STY_P910_CATCH) != 0;
		gold += (r->observers[i].p910 & STY_P910_GOLD) != 0;
		gold_n += (size_t)r->observers[i].gold_n;
		variance += (r->observers[i].p910 & STY_P910_VARIANCE) != 0;
		broken += (size_t)r->observers[i].broken;
	}
	fprintf(f, "P.910-crowd screening (observers.csv p910): %zu answered a catch trial \"much better\" (catch), %zu "
		   "failed a gold trial (gold: %zu gold answers in all; one more than a step from \"reference much better\" "
		   "fails), %zu answered without variance (< 0.1); left out only with --p910. Answers of broken playbacks, not "
		   "counted: %zu.\n", catches, gold, gold_n, variance, broken);

	fprintf(f, "\n## JOD (Thurstone Case V, reference at 0)\n\n| method | T | period | scene | camera | JOD [95%% CI] | "
		   "participants |\n|---|---|---|---|---|---|---|\n");
	for (size_t i = 0; i < r->row_count; i++) {
		const sty_row *w = &r->rows[i];
		const sty_variant *v = &r->variants[w->variant];
		variant_cells vc;
		cells_of(v, &vc);
		fprintf(f, "| %s | %s | %s | %s | %s | %s [%s, %s] | %zu |\n", v->method, vc.Ts, vc.Ps,
			md_text(w->scene, sc, sizeof sc), md_text(w->camera, ca, sizeof ca), md_num(w->jod, "%.2f", a, sizeof a),
			md_num(w->jod_lo, "%.2f", b, sizeof b), md_num(w->jod_hi, "%.2f", c, sizeof c), w->participants);
	}
	fprintf(f, "\nJOD = -Phi^-1(p_ref)/Phi^-1(0.75) (1 JOD: 75%% prefer the reference); 95%% percentile bootstrap over "
		   "participants.\n");

	/* issue 28: the measured thresholds (thresholds.csv) beside the JOD */
	fprintf(f, "\n## Thresholds (T at 1 JND)\n\n| method | period | scene | camera | trials | t_jnd [95%% CI] | levels | "
		   "participants |%s\n|---|---|---|---|---|---|---|---|%s\n", pr->model ? " predicted t_jnd [95%] |" : "",
		pr->model ? "---|" : "");
	for (size_t i = 0; i < r->threshold_count; i++) {
		const sty_threshold_row *t = &r->thresholds[i];
		char P[16] = "";
		if (t->period)
			snprintf(P, sizeof P, "%u", t->period);
		fprintf(f, "| %s | %s | %s | %s | %zu | %s [%s, %s] | %zu | %zu |", t->method, P,
			md_text(t->scene, sc, sizeof sc), md_text(t->camera, ca, sizeof ca), t->f.n,
			md_num(t->f.t_jnd, "%.2f", a, sizeof a), md_num(t->f.t_jnd_lo, "%.2f", b, sizeof b),
			md_num(t->f.t_jnd_hi, "%.2f", c, sizeof c), t->f.levels, t->f.participants);
		if (pr->model) { /* beside the measured one, as `report --model` shows it (pooled rows: none) */
			const sty_model_pred *q = t->pooled ? NULL : sty_model_pred_find(pr->p, pr->n, t->method, t->period,
											  t->scene, t->camera);
			if (q)
				fprintf(f, " %s [%s, %s] |", md_num(q->t_jnd, "%.2f", a, sizeof a),
					md_num(q->t_jnd_lo, "%.2f", b, sizeof b), md_num(q->t_jnd_hi, "%.2f", c, sizeof c));
			else
				fprintf(f, " – |");
		}
		fputc('\n', f);
	}
	if (!r->threshold_count)
		fprintf(f, "\nNo method was rated at two or more levels of T: no threshold.\n");
	else
		fprintf(f, "\nt_jnd: the T at which the fitted p_ref of the median observer reaches 0.75 (psychometric function in "
			   "log2 T with lapse and observer variability, README \"Thresholds\"); inf: not reached up to the largest "
			   "rated T; 95%% profile-likelihood interval.\n");
	if (r->threshold_count && pr->model)
		fprintf(f, "Predicted t_jnd: the model %s (README \"Metric → JND model\") for this series of the sweep's clips; "
			   "its 95%% interval from the model's leave-one-scene-out error; – for pooled rows and series it "
			   "does not predict.\n", pr->model);
}

/* anova.csv: per variant its effects, or one row without an effect whose note says why there is none (issue 27.10);
 * a row whose F is undefined says why in its note. */
static void write_anova(FILE *f, const sty_result *r)
{
	fprintf(f, "method,T,period,effect,df1,df2,F,p,p_gg,epsilon_gg,note\n");
	for (size_t v = 0; v < r->variant_count; v++) {
		variant_cells vc;
		char note[400];
		cells_of(&r->variants[v], &vc);
		int rows = 0;
		for (size_t i = 0; i < r->anova_count; i++) {
			const sty_anova_row *a = &r->anova[i];
			if (a->variant != v)
				continue;
			rows++;
			fprintf(f, "%s,%s,%s,%g,%g,", vc.cm, vc.TP, a->effect, a->e.df1, a->e.df2);
			csv_num(f, a->e.F, "%.6f"), fputc(',', f);
			csv_num(f, a->e.p, "%.6g"), fputc(',', f);
			csv_num(f, a->e.p_gg, "%.6g"), fputc(',', f);
			csv_num(f, a->e.epsilon_gg, "%.6f");
			fprintf(f, ",%s\n", a->note ? sty_csv_cell(a->note, note, sizeof note) : "");
		}
		if (!rows && r->variants[v].anova_note[0])
			fprintf(f, "%s,%s,,,,,,,,%s\n", vc.cm, vc.TP,
				sty_csv_cell(r->variants[v].anova_note, note, sizeof note));
	}
}

static void write_posthoc(FILE *f, const sty_result *r)
{
	fprintf(f, "method,T,period,factor,level_1,level_2,t,df,p,p_bonferroni\n");
	for (size_t i = 0; i < r->posthoc_count; i++) {
		const sty_posthoc_row *h = &r->posthoc[i];
		variant_cells vc;
		char l1c[160], l2c[160];
		cells_of(&r->variants[h->variant], &vc);
		fprintf(f, "%s,%s,%s,%s,%s,", vc.cm, vc.TP, h->factor, sty_csv_cell(h->level_1, l1c, sizeof l1c),
			sty_csv_cell(h->level_2, l2c, sizeof l2c));
		csv_num(f, h->t, "%.6f"), fputc(',', f);
		csv_num(f, h->df, "%g"), fputc(',', f);
		csv_num(f, h->p, "%.6g"), fputc(',', f);
		csv_num(f, h->p_bonferroni, "%.6g"), fputc('\n', f);
	}
}

static json_t *conditions_json(const sty_result *r)
{
	json_t *jc = json_array();
	for (size_t i = 0; jc && i < r->row_count; i++) {
		const sty_row *w = &r->rows[i];
		const sty_variant *v = &r->variants[w->variant];
		json_array_append_new(jc, json_pack("{s:s, s:o, s:o, s:s, s:s, s:I, s:f, s:o, s:o, s:f, s:f, s:f, s:f}",
						    "method", v->method, "T", T_json(v), "period", period_json(v), "scene",
						    w->scene, "camera", w->camera, "n", (json_int_t)w->n, "Q", w->Q, "Q_lo",
						    num_json(w->Q_lo), "Q_hi", num_json(w->Q_hi), "p_ref", w->j.p, "p_ref_lo",
						    w->j.p_lo, "p_ref_hi", w->j.p_hi, "jnd", w->j.jnd));
	}
	return jc;
}

/* anova.json: the rows of anova.csv (undefined numbers null, never a row left out), each with its note (null). */
static json_t *anova_json(const sty_result *r)
{
	json_t *ja = json_array();
	for (size_t v = 0; ja && v < r->variant_count; v++) {
		const sty_variant *vv = &r->variants[v];
		int rows = 0;
		for (size_t i = 0; i < r->anova_count; i++) {
			const sty_anova_row *a = &r->anova[i];
			if (a->variant != v)
				continue;
			rows++;
			json_array_append_new(ja, json_pack("{s:s, s:o, s:o, s:s, s:f, s:f, s:o, s:o, s:o, s:o, s:I, s:o}",
							    "method", vv->method, "T", T_json(vv), "period", period_json(vv),
							    "effect", a->effect, "df1", a->e.df1, "df2", a->e.df2, "F",
							    num_json(a->e.F), "p", num_json(a->e.p), "p_gg", num_json(a->e.p_gg),
							    "epsilon_gg", num_json(a->e.epsilon_gg), "participants",
							    (json_int_t)a->participants, "note",
							    a->note ? json_string(a->note) : json_null()));
		}
		if (!rows && vv->anova_note[0])
			json_array_append_new(ja, json_pack("{s:s, s:o, s:o, s:n, s:s}", "method", vv->method, "T", T_json(vv),
							    "period", period_json(vv), "effect", "note", vv->anova_note));
	}
	return ja;
}

/* Fig. 3 style plot: pooled Q with its CI and p_ref against T per method, the 1-JND line (p = 75%). A plot of an
 * earlier tally must not stand beside these tables when this one is not drawn, so fig3.png goes first. */
static void write_plot(const sty_result *r, const sty_tally_desc *d)
{
	char path[4200], methods[1024] = "";
	snprintf(path, sizeof path, "%s/fig3.png", d->out);
	unlink(path);
	if (d->no_plot)
		return;
	for (size_t i = 0; i < r->row_count; i++) { /* the methods with a point, in variant order */
		const sty_variant *v = &r->variants[r->rows[i].variant];
		if (r->rows[i].pooled && !isnan(v->T) && !strstr(methods, v->method) &&
		    strlen(methods) + strlen(v->method) + 2 < sizeof methods)
			strcat(strcat(methods, methods[0] ? " " : ""), v->method);
	}
	snprintf(path, sizeof path, "%s/fig3.gp", d->out);
	mtr_plot plot;
	char note[512];
	FILE *g = mtr_plot_begin(&plot, path, note, sizeof note);
	if (!g)
		return;
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
		d->out, methods, d->out);
	if (mtr_plot_end(&plot, note, sizeof note))
		fprintf(stderr, "taslab study: note: %s; fig3.png not drawn\n", note);
}

/* ------------------------------------------------------------------ the set of files */

/* Outputs over inputs: no file of the tally may be the study database or its journal (a --db kept in the --out
 * folder under one of these names), checked before anything is written. Then the folder is made (*made_dir: by
 * this tally, so removed again when it fails). */
static int prepare(sty *s, const sty_tally_desc *d, bool *made_dir, char *err, size_t err_size)
{
	char path[4200];
	int rc;
	for (size_t k = 0; k < sizeof TALLY_FILES / sizeof *TALLY_FILES; k++) {
		snprintf(path, sizeof path, "%s/%s", d->out, TALLY_FILES[k]);
		if ((rc = sty_check_output(s, path, err, err_size)))
			return rc;
	}
	*made_dir = !tl_is_dir(d->out);
	if ((rc = tl_mkdirs(d->out, err, err_size)))
		return rc;
	tl_fs_clean_temps(d->out);
	return TL_OK;
}

/* The files appear together or not at all: every one is written to its temporary file, and they are renamed into
 * place only when all are complete (a full disk: the folder keeps what it had; a folder made for this tally is
 * removed again). */
static int write_files(const sty_result *r, const sty_tally_desc *d, const preds *pr, bool made_dir, char *err,
		       size_t err_size)
{
	char path[4200];
	tl_atomic outs[TALLY_SET] = {0};
	int rc = TL_OK;
	for (int k = 0; k < TALLY_SET && !rc; k++) {
		snprintf(path, sizeof path, "%s/%s", d->out, TALLY_FILES[k]);
		rc = tl_atomic_open(&outs[k], path, err, err_size);
	}
	if (!rc) {
		write_observers(outs[F_OBSERVERS].f, r);
		write_conditions(outs[F_CONDITIONS].f, r);
		write_anova(outs[F_ANOVA].f, r);
		write_posthoc(outs[F_POSTHOC].f, r);
		write_jod(outs[F_JOD].f, r);
		write_tables(outs[F_TABLES].f, r, pr);
		write_fig3(outs[F_FIG3].f, r);
		if (pr->model)
			sty_write_thresholds_predicted(outs[F_THRESHOLDS].f, r, pr->p, pr->n);
		else
			sty_write_thresholds(outs[F_THRESHOLDS].f, r);
		json_t *jc = conditions_json(r), *ja = anova_json(r);
		if (tl_json_dump(outs[F_CONDITIONS_JSON].f, jc) || tl_json_dump(outs[F_ANOVA_JSON].f, ja))
			rc = tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write the JSON tables", d->out);
		json_decref(jc);
		json_decref(ja);
	}
	if (!rc)
		rc = tl_atomic_commit_set(outs, TALLY_SET, err, err_size);
	if (rc) {
		tl_atomic_abort_set(outs, TALLY_SET);
		if (made_dir)
			rmdir(d->out); /* only when empty: a folder made for this tally holds nothing now */
		return rc;
	}
	write_plot(r, d);
	return TL_OK;
}

int sty_tally_write(sty *s, const sty_result *r, const sty_tally_desc *d, char *err, size_t err_size)
{
	bool made_dir = false;
	int rc = prepare(s, d, &made_dir, err, err_size);
	preds none = {0};
	return rc ? rc : write_files(r, d, &none, made_dir, err, err_size);
}

int sty_tally(sty *s, const sty_tally_desc *d, char *err, size_t err_size)
{
	bool made_dir = false;
	sty_result *r = NULL;
	preds pr = {.model = d->model};
	/* A model (issue 28, `tally --model`): its predictions for the sweep's series, by the code of `report --model`;
	 * a file that is not a model is refused before anything is written. */
	if (d->model && !d->sweep)
		return tl_error(err, err_size, TL_ERR_ARG, "--model needs --sweep SWEEP (the sweep whose clips were rated: the "
				"model predicts from its summary.csv)");
	if (d->sweep && !d->model)
		return tl_error(err, err_size, TL_ERR_ARG, "--sweep goes with --model MODEL.json");
	int rc = d->model ? sty_model_predict(d->model, d->sweep, NULL, 0, &pr.p, &pr.n, err, err_size) : TL_OK;
	/* The outputs are checked and the folder made before the statistics, as they always were: a bad --out is
	 * reported before an empty study. */
	if (!rc)
		rc = prepare(s, d, &made_dir, err, err_size);
	if (rc) {
		free(pr.p);
		return rc;
	}
	if ((rc = sty_tally_compute(s, d, &r, err, err_size))) {
		if (made_dir)
			rmdir(d->out);
		free(pr.p);
		return rc;
	}
	rc = write_files(r, d, &pr, made_dir, err, err_size);
	if (!rc)
		sty_tally_notes(r, stderr);
	sty_result_free(&r);
	free(pr.p);
	return rc;
}

void sty_tally_notes(const sty_result *r, FILE *f)
{
	size_t noted = 0, same = 0;
	for (size_t v = 0; v < r->variant_count; v++) {
		noted += r->variants[v].anova_note[0] != 0;
		same += !strcmp(r->variants[v].anova_note, r->variants[0].anova_note);
	}
	if (!noted)
		return;
	if (noted == r->variant_count && same == noted && !r->anova_count) { /* the usual case: one scene and path */
		fprintf(f, "taslab study: no ANOVA for any variant: %s\n", r->variants[0].anova_note);
		return;
	}
	for (size_t v = 0; v < r->variant_count; v++) {
		const sty_variant *x = &r->variants[v];
		char name[96];
		int rows = 0;
		if (!x->anova_note[0])
			continue;
		for (size_t i = 0; i < r->anova_count; i++)
			rows += r->anova[i].variant == v;
		variant_name(x, name, sizeof name);
		fprintf(f, "taslab study: %s: %s%s\n", name, rows ? "ANOVA incomplete: " : "no ANOVA: ", x->anova_note);
	}
}
