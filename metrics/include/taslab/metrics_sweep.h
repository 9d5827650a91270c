/* metrics_sweep.h — the metrics side of a sweep (DESIGN section 9): each run's comparison with the ref run of its
 * scene and camera path (`metrics diff`, DESIGN section 6), and the sweep's tables: SWEEP/summary.csv (one row per
 * run) and SWEEP/table1.md (paper Table 1 layout, from metrics_runs.h).
 *
 * summary.csv columns (DESIGN section 9; a cell is empty where a value does not apply or is not available):
 *   scene,camera,camera_motion,method,variant,T,period,frames,width,height,status,
 *   reuse_percent,shaded_samples,shaded_per_frame,reduction_percent,baseline,gpu_ms_median,speedup_vs_ref,
 *   <every column of the `metrics diff` summary.json: maxrgb_mean,...,exceed_2..exceed_64,psnr,ssim,flicker_mean,
 *   flip_mean,...>,late_samples,late_percent,run
 * status: complete (run, clip and metrics), partial (the run is complete but its clip or metrics are missing),
 * missing (the run is not complete). The ref rows carry no difference metrics (a run compared with itself).
 *
 * The sweep folder layout and the plan are output/sweep.h's. Errors: negative tl_err, one line in `err`.
 */
#ifndef TASLAB_METRICS_SWEEP_H
#define TASLAB_METRICS_SWEEP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "taslab/metrics_matched.h"
#include "taslab/metrics_runs.h"
#include "taslab/sweep.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MTR_SWEEP_MAX_COLUMNS 64

typedef struct mtr_sweep_row {
	sweep_run run;              /* the plan entry */
	sweep_status status;
	mtr_run_summary summary;    /* from stats.csv and manifest.json; valid when status.run */
	/* The pooled metrics of summary.json, by column (mtr_column_name(i)); NAN where absent or not computed. */
	double metric[MTR_SWEEP_MAX_COLUMNS];
	uint32_t worst_frame;       /* frame with the largest maxrgb_p99 (frames.csv); the middle frame without one */
} mtr_sweep_row;

/* Compares run `r` with the ref run of its scene and camera path (both must be complete) into its metrics folder
 * (sweep_run_path SWEEP_PATH_METRICS): frames.csv, distribution.csv, summary.json (last). `threads` <= 0: all
 * cores. Nothing to do for a ref run. */
int mtr_sweep_metrics(const sweep_spec *s, const char *dir, const sweep_run *r, int threads, char *err,
		      size_t err_size);

/* One row per run of the plan, in plan order: status, run summary (reductions against s->baseline and speedups
 * against ref, matched per scene/path/frames/size by mtr_runs_summarise) and pooled metrics. *rows is malloc'ed
 * (free it); *n = sweep_run_count(s). Unreadable outputs of a complete run are TL_ERR_INPUT. */
int mtr_sweep_collect(const sweep_spec *s, const char *dir, mtr_sweep_row **rows, size_t *n, char *err,
		      size_t err_size);

/* A row's value by summary.csv column name (numeric columns: T, period, frames, reuse_percent, reduction_percent,
 * speedup_vs_ref, gpu_ms_median, shaded_per_frame, late_percent, and every metric column such as maxrgb_p99,
 * exceed_8, flip_mean); NAN when absent or not numeric. `exceed_T` is the exceedance at the variant's own T
 * (NAN when T is not one of 2, 4, ..., 64 or the method has no T). `shaded_fraction` is the clip's shaded / visible
 * samples (0..1). */
double mtr_sweep_value(const mtr_sweep_row *row, const char *column);

/* The matched-budget pairs (metrics_matched.h) of the runs that are there, per scene and camera path, by clip-mean
 * shaded samples per frame; the pairs index `rows`. *pairs is malloc'ed (free it; NULL when *np is 0). */
int mtr_sweep_matched(const sweep_spec *s, const mtr_sweep_row *rows, size_t n, mtr_match_pair **pairs, size_t *np,
		      char *err, size_t err_size);

/* Writes DIR/summary.csv and DIR/table1.md (atomically); table1.md ends with the matched-budget comparison. */
int mtr_sweep_write(const sweep_spec *s, const char *dir, const mtr_sweep_row *rows, size_t n, char *err,
		    size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
