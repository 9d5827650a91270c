/* metrics_tfr.h — outputs of the TFR analysis (taslab/analysis.h, produced by the renderer's analyze.h; DESIGN sections 4 and 6, paper Figs. 4,
 * 7, 8, 9): CSV and JSON for every figure, gnuplot plots and gradient heatmaps for people.
 *
 * Every file is written under a temporary name and renamed when complete; the JSON summary is written
 * last, so its presence means the folder is complete. The writers return TL_OK, TL_ERR_OUTPUT when a folder or file
 * under DIR cannot be written (a full disk: "write ...: No space left on device", exit 2 without "fix your command
 * line"; issue 30.5), or TL_ERR_NOMEM; mtr_tfr_write_gradients TL_ERR_INTERNAL without kept gradients. */
#ifndef TASLAB_METRICS_TFR_H
#define TASLAB_METRICS_TFR_H

#include <stdbool.h>
#include <stddef.h>

#include "taslab/analysis.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mtr_tfr_meta {
	const char *scene, *camera, *device;
	const float *thresholds;
	size_t threshold_count;
	double seconds_per_frame; /* analysis wall time per analysis frame (reported in the JSON) */
} mtr_tfr_meta;

/* Temporal coherence (Fig. 4) and visibility coherence (sec. 4.1) of `n` analysed frames:
 * DIR/coherence.csv         T,k,unchanged_samples,visible_samples,fraction_unchanged   (pooled, k = 1..120)
 * DIR/coherence_frames.csv  frame,T,k,fraction_unchanged
 * DIR/visibility.csv        frame,visible_samples,visible_at_previous,visibility_coherence
 * DIR/coherence.json        summary (fraction unchanged for 120 frames per T, mean visibility coherence)
 * DIR/coherence.png         fraction unchanged against k, one line per T (when `plots`; gnuplot) */
int mtr_tfr_write_coherence(const analyze_result *frames, size_t n, const mtr_tfr_meta *meta, const char *dir,
			    bool plots, char *err, size_t err_size);

/* Predictor evaluation (Figs. 7, 9):
 * DIR/predictors.csv        T,predictor,filtered,late,early,on_time,unchanged,samples,late_fraction,
 *                           early_fraction,on_time_fraction,unchanged_fraction   (pooled over frames)
 * DIR/predictors_frames.csv frame, then the same columns (counts only)
 * DIR/predictors.json       the pooled table
 * DIR/predictors.png        stacked late/early/on-time/unchanged fractions per predictor and T (`plots`) */
int mtr_tfr_write_predictors(const analyze_result *frames, size_t n, const mtr_tfr_meta *meta, const char *dir,
			     bool plots, char *err, size_t err_size);

/* Gradient images like Fig. 8 for one analysed frame (kept with analyze_desc.keep_gradients):
 * DIR/gradients/NNNNNN_T<T>_<predictor>.png for the three predictors, unfiltered and filtered, as
 * heatmaps in code values per frame from 0 to T/4 (a 4-frame deadline saturates the colour scale). */
int mtr_tfr_write_gradients(const analyze_result *r, const mtr_tfr_meta *meta, const char *dir, char *err,
			    size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
