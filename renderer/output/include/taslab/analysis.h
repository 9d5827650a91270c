/* analysis.h — results of the TFR analysis of one frame (produced by the renderer's analyze.h, written
 * to files by the metrics module's metrics_tfr.h; DESIGN section 4, paper secs. 4.1 and 5, Figs. 4, 7-9).
 * Plain data: no Vulkan. */
#ifndef TASLAB_ANALYSIS_H
#define TASLAB_ANALYSIS_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define ANALYZE_MAX_T 8
#define ANALYZE_K 119      /* largest deadline searched (paper sec. 5: deadlines 1..118 predicted) */
#define ANALYZE_HISTORY 120 /* s_1..s_120 are evaluated (coherence up to k = 120) */

enum { ANALYZE_SINGLE, ANALYZE_LONG, ANALYZE_INST, ANALYZE_SINGLE_F, ANALYZE_LONG_F, ANALYZE_INST_F, ANALYZE_PREDICTORS };
enum { ANALYZE_LATE, ANALYZE_EARLY, ANALYZE_ON_TIME, ANALYZE_UNCHANGED, ANALYZE_CLASSES };

/* Names: "single", "long", "inst", "single_filtered", ... and "late", "early", "on_time", "unchanged". */
const char *analyze_predictor_name(int p);
const char *analyze_class_name(int c);

typedef struct analyze_result {
	uint32_t frame;
	uint32_t width, height;
	size_t threshold_count;
	uint64_t visible;            /* visible samples at t */
	uint64_t visible_prev;       /* of those, visible at t - 1 */
	/* unchanged[i][k]: samples with d(s_j, s_0) <= T_i for all 1 <= j <= k (k = 0: all visible). */
	uint64_t unchanged[ANALYZE_MAX_T][ANALYZE_HISTORY + 1];
	uint64_t classes[ANALYZE_MAX_T][ANALYZE_PREDICTORS][ANALYZE_CLASSES];
	/* keep_gradients: width*height*threshold_count*4 floats, per T a plane of (single, long, inst, D)
	 * with g in code values per frame and D = true deadline (0: unchanged or background);
	 * filtered: (width/8 rounded up)*(height/8 rounded up)*threshold_count*4 (single, long, inst, 0). */
	float *gradients, *gradients_filtered;
	uint32_t filtered_width, filtered_height;
} analyze_result;

/* Frees the gradient arrays (the struct itself is the caller's). */
void analyze_result_free(analyze_result *r);

#ifdef __cplusplus
}
#endif
#endif
