/* metrics_runs.h — shading statistics of runs from their stats.csv and manifest.json (DESIGN sections 5, 6):
 * reuse, reduction of shaded samples against a baseline variant (paper Table 1), speedup against `ref`
 * (paper Fig. 12), and the late samples a run counted with --truth. (The predictors' late / early / on-time /
 * unchanged tallies of Figs. 7 and 9 are per scene, path and T, not per run: `taslab analyze predictors`.) */
#ifndef TASLAB_METRICS_RUNS_H
#define TASLAB_METRICS_RUNS_H

#include <stddef.h>
#include <stdio.h>

#include "taslab/run.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mtr_run_summary {
	char path[1024];
	char method[32], variant[64], scene[64], camera[64], camera_motion[16];
	run_method_facts facts;     /* the manifest's inputs.method_facts: reference, baseline (issue 30.1) */
	double threshold;           /* T, NAN when the method has none */
	unsigned period;            /* N, 0 when the method has none */
	unsigned width, height, first_frame;
	size_t frames;
	double visible_samples;     /* sums over the frames */
	double shaded_samples;      /* the methods' own counters: Table 1 "shader invocations" (DESIGN section 5) */
	double allocated_samples;   /* atlas methods; NAN otherwise */
	double reuse_mean;          /* mean of reuse_fraction over frames (0..1) */
	double reduction;           /* 1 - shaded / baseline's shaded; NAN without a matching baseline run */
	char baseline[64];          /* the baseline run's variant ("" without one) */
	double fs_invocations;      /* sum of the device's fragment-invocation statistic (NAN if none): not shading */
	double gpu_ms_median;       /* median gpu_ms_total (period N > 1: of the N-frame windows' means, the amortised
				     * cost of keyframe schemes); NAN without timestamps */
	double speedup_vs_ref;      /* ref median / this median; NAN without a matching ref run */
	double reused_samples;      /* sum; NAN when absent */
	double late_samples;        /* --truth: sum; NAN when absent */
} mtr_run_summary;

/* Summarises `n` runs. Reductions are against the run of variant `baseline` (NULL: the variant the run's manifest
 * names as its baseline — sa for the atlas methods sa, sau, tasa, as Table 1 of the paper reduces against SA — when
 * that run is there, else the reference run) and speedups against the reference run (the manifest's
 * method_facts.reference: `ref`), both with the same scene, camera path, first frame, frame count and size. Runs
 * without such a partner get NAN. A manifest without inputs.method_facts (made before taslab recorded them) is
 * TL_ERR_INPUT: render the run again. */
int mtr_runs_summarise(const char *const *runs, size_t n, const char *baseline, mtr_run_summary *out, char *err,
		       size_t err_size);

/* Writes DIR/runs.csv (one row per run, columns as mtr_run_summary), DIR/runs.json and DIR/table1.md (the
 * paper's Table 1 layout per scene and camera path: variant, shaded samples per frame, reduction, reuse,
 * speedup). */
int mtr_runs_write(const mtr_run_summary *s, size_t n, const char *dir, char *err, size_t err_size);

/* Prints V with the printf format FMT (one floating conversion) into F for a table a reader reads, without the minus
 * sign of a value that rounds to zero at FMT's precision ("-0.00 %": ref's reuse 1 - shaded / visible is -0.0035 %
 * where a coplanar pixel is shaded twice); the CSV and JSON keep the value itself. */
void mtr_fprint_shown(FILE *f, const char *fmt, double v);

/* Writes only the Table 1 file (as in mtr_runs_write) to `path`, atomically (the sweep's SWEEP/table1.md). */
int mtr_runs_write_table1(const char *path, const mtr_run_summary *s, size_t n, char *err, size_t err_size);

/* Draws DIR/reduction.png, reuse.png and speedup.png against T, one line per method with a threshold (gnuplot,
 * from DIR/runs.csv written by mtr_runs_write). Returns non-zero with a note when gnuplot is missing or nothing
 * to draw. */
int mtr_runs_plot(const mtr_run_summary *s, size_t n, const char *dir, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
