/* study_report.h — the sweep report (DESIGN section 9): SWEEP/report/index.html, a self-contained page that opens
 * from disk, offline. It joins the sweep's metrics (metrics_sweep.h) with a study's tallies (study.h) per condition.
 *
 * Contents, per scene and camera path: plots against T with one line per method (reuse, reduction of shaded samples,
 * speedup vs ref, exceed_T, max-RGB p99, flicker, FLIP; methods without a threshold as horizontal lines, and exceed
 * as the curve of the fraction of pixels above T); Table 1; the coherence curves (Fig. 4) when
 * SWEEP/analysis/<scene>/<camera>/coherence.csv exists (`taslab analyze coherence --out` there); thumbnails and
 * max-RGB difference heatmaps of each run's worst frame (largest p99); each variant's clip beside the reference's,
 * played in sync. With a study: Q, p_ref and JND with 95% intervals per condition (method, T, period, scene, camera)
 * beside the metrics, and a plot of JND against a chosen metric; the study's thresholds (t_jnd at 1 JND), and with a
 * model (`study model --out`) the predicted threshold beside each and for every series nobody rated
 * (report/data/thresholds.csv).
 *
 * Files: report/index.html, report/plots/ (SVG, gnuplot), report/img/ (PNG), report/data/ (CSV: what the plots show),
 * report/study/ (the tally, with a study). Clips are referenced in place (../clips/...). Every file is written
 * atomically; index.html last.
 *
 * Errors: negative tl_err, one line in `err`.
 */
#ifndef TASLAB_STUDY_REPORT_H
#define TASLAB_STUDY_REPORT_H

#include <stddef.h>

#include "taslab/metrics_sweep.h"
#include "taslab/sweep.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sty_report_desc {
	const char *dir;             /* the sweep folder */
	const sweep_spec *spec;
	const mtr_sweep_row *rows;   /* mtr_sweep_collect, plan order */
	size_t count;
	const char *study;           /* a study database (study.h) or NULL */
	const char *jnd_metric;      /* summary.csv column the JND is plotted against (NULL: flip_mean) */
	const char *model;           /* a saved metric-to-JND model (study_model.h, `study model --out`) or NULL: its
				      * predicted thresholds for the sweep's series beside the measured ones */
	/* A stereo sweep's report beside a mono sweep (issue 25): its folder, spec and rows (mtr_sweep_collect), or NULL:
	 * SWEEP/stereo_vs_mono.csv and a "Stereo" section with each run's speedup and shaded samples in both. */
	const char *mono_dir;
	const sweep_spec *mono_spec;
	const mtr_sweep_row *mono_rows;
	size_t mono_count;
} sty_report_desc;

/* Writes the report; `index` (may be NULL) receives the path of index.html. Plots need gnuplot: without it the page
 * says so where the plots would be (TL_OK). */
int sty_report_write(const sty_report_desc *d, char *index, size_t index_size, char *err, size_t err_size);

/* Whether `column` is a summary.csv column the JND can be plotted against (mtr_sweep_value knows it). */
int sty_report_metric_known(const char *column);

#ifdef __cplusplus
}
#endif
#endif
