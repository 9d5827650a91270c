/* analyze.h — temporal forward rendering (TFR) analysis of single frames (DESIGN section 4, paper
 * secs. 4.1 and 5): temporal coherence of shading, visibility coherence, and gradient predictors.
 *
 * For an analysis frame t every visible sample (surface point x) is shaded as it was k frames ago,
 * s_k, for k = 0..120 (object transforms, lights, camera and shadow maps all at t - k), one full-frame
 * shading pass per k on the Vulkan device; per-pixel state (first exceedance k1, next exceedance k2,
 * gradients) stays on the device and only counters and, on request, gradient images are read back.
 *
 *  - coherence (Fig. 4): per T, the number of samples with d(s_j, s_0) <= T for all j <= k, k = 0..120;
 *  - visibility coherence (sec. 4.1): samples at t that were visible at t - 1 (reprojection + object
 *    and depth test);
 *  - predictors (Figs. 7, 9): k1 = first k >= 1 with d(s_k, s_0) > T (none within K = 119: unchanged),
 *    true deadline D = k1; gradients at t - k1: single-frame d(s_k1, s_k1+1), long-range
 *    d(s_k1, s_k2)/(k2 - k1), instantaneous |ds/dt| by a symmetric difference of +-h frames (our
 *    stand-in for the paper's analytic derivatives); each unfiltered and with the spatial max filter
 *    (8x8 max downsample, then 9x9 max kernel: 72x72 pixels). Predicted deadline d = T/g clamped to
 *    [1, 118]: late if d > D, early if d < D - 1, else on time.
 *
 * Times t - k before 0 are evaluated like any other time (animations are functions of time). */
#ifndef TASLAB_ANALYZE_H
#define TASLAB_ANALYZE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "taslab/analysis.h"
#include "taslab/colour.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct analyze_desc {
	const struct scene *scene;
	int camera;
	uint32_t width, height;
	float fps;                   /* 0 = the scene's */
	const float *thresholds;     /* T values (> 0), 1..ANALYZE_MAX_T */
	size_t threshold_count;
	float inst_step;             /* h in frames for the instantaneous derivative (0 = 0.125) */
	bool predictors;             /* evaluate the instantaneous derivatives (needed for predictors only) */
	bool keep_gradients;         /* read back the gradient images (analyze_result.gradients) */
	const struct colour *colour; /* display transform (NULL: the built-in default) */
} analyze_desc;

typedef struct analyze analyze;

int analyze_create(vkdev *dev, const analyze_desc *desc, analyze **out, char *err, size_t err_size);
void analyze_destroy(analyze **a);
/* Analyses frame `frame` (t = frame / fps). `out` is overwritten; free its arrays with analyze_result_free. */
int analyze_frame(analyze *a, uint32_t frame, analyze_result *out, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
