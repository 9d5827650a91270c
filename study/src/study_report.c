/* study_report.c — SWEEP/report/index.html: the sweep's metrics per scene and camera path, with plots against T,
 * Table 1, images, synchronised clip pairs, and a study's tallies per condition (study_report.h; DESIGN section 9).
 *
 * This file gathers the runs into scene x camera groups and writes the report's files in order: the study's tally
 * (study_report_study.c), each group's plots and images (study_report_plots.c), the study joined with the runs,
 * and the page last (study_report_page.c). Plots are SVG drawn by gnuplot (metrics.h mtr_plot_*). */
#include "taslab/study_report.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_report_internal.h"
#include "taslab/metrics.h"
#include "taslab/tl_fs.h"

void sty_rpt_stem(const sweep_spec *s, size_t scene, size_t cam, char *out, size_t n)
{
	snprintf(out, n, "%s--%s", s->scenes[scene].name, s->scenes[scene].cameras[cam].name);
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

/* The groups, scene x camera in spec order, with their rows sorted by method and T; *out is malloc'ed. */
static int groups_of(const sty_report_desc *d, sty_rpt_group **out, size_t *count, char *err, size_t err_size)
{
	const sweep_spec *s = d->spec;
	size_t ng = 0;
	for (size_t i = 0; i < s->scene_count; i++)
		ng += s->scenes[i].camera_count;
	sty_rpt_group *gi = calloc(ng ? ng : 1, sizeof *gi);
	if (!gi)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
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
					gi[g].rows[gi[g].n++] = (sty_rpt_row){r, &s->variants[r->run.variant]};
			}
			qsort(gi[g].rows, gi[g].n, sizeof gi[g].rows[0], sty_rpt_cmp_row);
		}
	*out = gi;
	*count = ng;
	return TL_OK;
}

/* A group's plots (the ref first, then its rows), its coherence curves when SWEEP/analysis has them, and the
 * thumbnails and heatmap of every run's worst frame. *gnuplot_note is set when gnuplot is missing. */
static int group_files(const sty_report_desc *d, const char *rdir, sty_rpt_group *g, bool *gnuplot_note, char *err,
		       size_t err_size)
{
	const sweep_spec *s = d->spec;
	char stem[256], note[1024];
	int rc = TL_OK;
	sty_rpt_stem(s, g->scene, g->cam, stem, sizeof stem);
	sty_rpt_row all[SWEEP_MAX_VARIANTS + 1];
	size_t na = 0;
	if (g->ref)
		all[na++] = (sty_rpt_row){g->ref, &s->variants[g->ref->run.variant]};
	for (size_t i = 0; i < g->n; i++)
		all[na++] = g->rows[i];
	int prc = sty_rpt_group_plots(rdir, stem, all, na, g->drawn, note, sizeof note);
	g->plots_ok = prc == TL_OK;
	if (prc == TL_ERR_UNSUPPORTED)
		*gnuplot_note = true;
	else if (prc)
		rc = tl_error(err, err_size, prc, "%s", note);
	if (prc == TL_OK && (prc = sty_rpt_budget_plot(rdir, stem, g, &g->budget, note, sizeof note)) &&
	    prc != TL_ERR_UNSUPPORTED)
		rc = tl_error(err, err_size, prc, "%s", note);
	char csv[TL_PATH_MAX + 128], svg[TL_PATH_MAX + 128], gp[TL_PATH_MAX + 128];
	snprintf(csv, sizeof csv, "%s/analysis/%s/%s/coherence.csv", d->dir, s->scenes[g->scene].name,
		 s->scenes[g->scene].cameras[g->cam].name);
	if (tl_is_file(csv)) {
		snprintf(svg, sizeof svg, "%s/plots/%s--coherence.svg", rdir, stem);
		snprintf(gp, sizeof gp, "%s/data/%s--coherence.gp", rdir, stem);
		g->coherence = sty_rpt_coherence_plot(csv, svg, gp, note, sizeof note) == TL_OK;
	}
	if (!g->ref || !g->ref->status.run)
		return rc;
	char ref_dir[TL_PATH_MAX];
	sweep_run_path(s, d->dir, &g->ref->run, SWEEP_PATH_RUN, ref_dir, sizeof ref_dir);
	for (size_t i = 0; i < g->n && !rc; i++) {
		const mtr_sweep_row *r = g->rows[i].r;
		if (!r->status.run)
			continue;
		char run_dir[TL_PATH_MAX], a[TL_PATH_MAX + 128], b[TL_PATH_MAX + 128], h[TL_PATH_MAX + 128];
		sweep_run_path(s, d->dir, &r->run, SWEEP_PATH_RUN, run_dir, sizeof run_dir);
		snprintf(a, sizeof a, "%s/img/%s--ref--%06u.png", rdir, stem, r->worst_frame);
		snprintf(b, sizeof b, "%s/img/%s--%s--%06u.png", rdir, stem, g->rows[i].v->id, r->worst_frame);
		snprintf(h, sizeof h, "%s/img/%s--%s--%06u-diff.png", rdir, stem, g->rows[i].v->id, r->worst_frame);
		rc = sty_rpt_run_images(run_dir, ref_dir, r->worst_frame, a, b, h, err, err_size);
	}
	return rc;
}

int sty_report_write(const sty_report_desc *d, char *index, size_t index_size, char *err, size_t err_size)
{
	char rdir[TL_PATH_MAX], path[TL_PATH_MAX + 64];
	snprintf(rdir, sizeof rdir, "%s/report", d->dir);
	const char *subs[] = {"plots", "img", "data"};
	int rc = TL_OK;
	for (int k = 0; k < 3 && !rc; k++) {
		snprintf(path, sizeof path, "%s/%s", rdir, subs[k]);
		rc = tl_mkdirs(path, err, err_size);
	}
	if (rc)
		return rc;
	sty_rpt_study study = {0}, model = {0};
	if ((rc = sty_rpt_model_load(d, &model, err, err_size))) /* a bad model file: refused before the study is tallied */
		return rc;
	if (d->study) {
		snprintf(path, sizeof path, "%s/study", rdir);
		if ((rc = tl_mkdirs(path, err, err_size)) || (rc = sty_rpt_study_load(d, path, &study, err, err_size))) {
			sty_rpt_study_free(&model);
			return rc;
		}
	}
	study.pred = model.pred, study.npred = model.npred;
	memcpy(study.pred_metric, model.pred_metric, sizeof study.pred_metric);
	sty_rpt_group *gi = NULL;
	size_t ng = 0;
	bool gnuplot_note = false, jnd_plot = false;
	rc = groups_of(d, &gi, &ng, err, err_size);
	for (size_t g = 0; g < ng && !rc; g++)
		rc = group_files(d, rdir, &gi[g], &gnuplot_note, err, err_size);
	/* the survey's models of reuse of the methods with a period, per group (data/reuse_model.csv, .md) */
	mtr_reuse_group *reuse = NULL;
	size_t nreuse = 0;
	if (!rc) {
		char note[512];
		if (mtr_reuse_fit(d->spec, d->dir, "maxrgb_mean", &reuse, &nreuse, note, sizeof note)) {
			fprintf(stderr, "taslab report: note: no models of reuse: %s\n", note);
			nreuse = 0;
		}
		snprintf(path, sizeof path, "%s/data", rdir);
		if (nreuse) {
			rc = mtr_reuse_write(d->spec, d->dir, "maxrgb_mean", reuse, nreuse, path, err, err_size);
		} else { /* none now: an earlier report's files go */
			const char *const names[] = {"reuse_model.csv", "reuse_model.md"};
			for (int k = 0; k < 2; k++) {
				snprintf(path, sizeof path, "%s/data/%s", rdir, names[k]);
				remove(path);
			}
		}
		for (size_t g = 0; g < ng; g++)
			for (size_t k = 0; k < nreuse; k++)
				if (reuse[k].scene == gi[g].scene && reuse[k].camera == gi[g].cam) {
					if (!gi[g].nreuse)
						gi[g].reuse = &reuse[k];
					gi[g].nreuse++;
				}
	}
	/* the study: joined table and JND against the chosen metric */
	if (!rc && d->study)
		rc = sty_rpt_study_files(d, rdir, &study, &jnd_plot, err, err_size);
	if (!rc)
		rc = sty_rpt_thresholds_csv(rdir, &study, err, err_size);
	/* What the join could not do is said here (stderr) and on the page (issue 27.12). */
	if (!rc && study.unchecked[0])
		fprintf(stderr, "taslab report: note: %s\n", study.unchecked);
	if (!rc && study.missing_count)
		fprintf(stderr, "taslab report: note: %zu condition(s) of the study have no run in this sweep and are not "
				"joined: %s\n",
			study.missing_count, study.missing);
	if (!rc)
		rc = sty_rpt_stereo_csv(d, err, err_size);
	snprintf(path, sizeof path, "%s/index.html", rdir);
	if (!rc)
		rc = sty_rpt_page_write(d, path, gi, ng, &study, gnuplot_note, jnd_plot, err, err_size);
	if (!rc && index)
		snprintf(index, index_size, "%s", path);
	free(gi);
	free(reuse);
	sty_rpt_study_free(&study);
	return rc;
}
