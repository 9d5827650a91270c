/* metrics_runs.h — shading statistics of runs from their stats.csv and manifest.json (DESIGN sections 5, 6):
 * reuse, shader-invocation reduction against a baseline run (paper Table 1), speedup against `ref`
 * (paper Fig. 12), and late / early / on-time / unchanged tallies when a run's stats.csv has those columns
 * (paper Figs. 7, 9). */
#ifndef TASLAB_METRICS_RUNS_H
#define TASLAB_METRICS_RUNS_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mtr_run_summary {
	char path[1024];
	char method[32], scene[64], camera[64];
	double threshold;
	size_t frames;
	double reuse_mean;          /* mean of reuse_fraction over frames (0..1) */
	double invocations;         /* sum of fs_invocations + cs_invocations; NAN when the device had none */
	double invocation_reduction;/* 1 - invocations / baseline invocations; NAN without a baseline */
	double gpu_ms_median;       /* median gpu_ms_total; NAN without timestamps */
	double speedup_vs_ref;      /* ref median / this median; NAN without a ref run */
	double late, early, on_time, unchanged; /* column sums, NAN when absent */
} mtr_run_summary;

/* Summarises `n` runs. `baseline` indexes the run invocation reductions are relative to (-1: the first
 * run whose method is ref, if any). Speedups are relative to the first `ref` run with the same scene,
 * camera and frame size. */
int mtr_runs_summarise(const char *const *runs, size_t n, int baseline, mtr_run_summary *out, char *err, size_t err_size);

/* Writes DIR/runs.csv, DIR/runs.json and DIR/table1.md (invocation reduction in the paper's Table 1 layout:
 * one row per method, one column per T). */
int mtr_runs_write(const mtr_run_summary *s, size_t n, const char *dir, char *err, size_t err_size);

/* Draws DIR/reduction.png, reuse.png and speedup.png against T, one line per method (gnuplot, from
 * DIR/runs.csv written by mtr_runs_write). Returns -1 with a note when gnuplot is missing or nothing to draw. */
int mtr_runs_plot(const mtr_run_summary *s, size_t n, const char *dir, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
