/* metrics.h — image, temporal and study statistics for scoring threshold sweeps (DESIGN sections 3, 6, 7).
 *
 * Images are display-referred RGB as floats on the 0..255 scale (8-bit PNG values, or EXR values through the
 * OpenColorIO view transform, unquantised), packed, 3 floats per pixel. Nothing here allocates behind the
 * caller's back except where stated; functions return 0 or a negative MTR_ERR_* with a message in `err`.
 *
 * Definitions (paper sec. 3; DESIGN section 3):
 *  - max-RGB difference d(p) = max(|a.r-b.r|, |a.g-b.g|, |a.b-b.b|); a sample has changed iff d > T;
 *  - exceed_T = fraction of pixels with d > T, for T in mtr_thresholds;
 *  - percentiles: linear interpolation between order statistics (type 7, numpy's default);
 *  - PSNR = 10 log10(255^2 / MSE), MSE over all pixels and the three channels; identical images: +inf
 *    (written as an empty CSV cell / JSON null);
 *  - SSIM (Wang et al. 2004): 11x11 Gaussian window, sigma 1.5, K1 = 0.01, K2 = 0.03, L = 255, population
 *    (co)variances, computed per RGB channel over the windows that fit inside the image and averaged over
 *    pixels and channels (equals scikit-image's structural_similarity(..., gaussian_weights=True,
 *    use_sample_covariance=False, data_range=255, channel_axis=2));
 *  - flicker (temporal difference): for frame t > 0, the max-RGB difference of the two sequences'
 *    frame-to-frame changes, f(p) = max_c |(a_t - a_t-1) - (b_t - b_t-1)|; flicker_mean = mean over pixels.
 *    Popping or flicker that one frame pair does not show (a sample reshaded late, then corrected) shows here.
 */
#ifndef TASLAB_METRICS_H
#define TASLAB_METRICS_H

#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MTR_THRESHOLD_COUNT 6
extern const double mtr_thresholds[MTR_THRESHOLD_COUNT]; /* 2, 4, 8, 16, 32, 64 */


typedef struct mtr_image {
	uint32_t width, height;
	const float *rgb; /* width * height * 3, 0..255 */
} mtr_image;

typedef struct mtr_frame_stats {
	double mean, p50, p95, p99, max;       /* of the max-RGB difference map */
	double exceed[MTR_THRESHOLD_COUNT];
	double mse, psnr, ssim;                /* psnr = INFINITY for identical images */
	double flicker_mean;                   /* NAN when there is no previous frame */
	uint32_t max_x, max_y;                 /* where the max difference is (first in row order) */
} mtr_frame_stats;

/* All statistics of one frame pair. `a_prev`/`b_prev` (both or neither may be NULL) enable flicker.
 * `map` (optional, width*height floats) receives the max-RGB difference map. `threads` <= 0: all cores. */
int mtr_frame_compare(const mtr_image *a, const mtr_image *b, const mtr_image *a_prev, const mtr_image *b_prev,
		      float *map, int threads, mtr_frame_stats *out, char *err, size_t err_size);

/* Clip-level pooling over n frames: means of per-frame mean/p50/p95/p99/exceed/ssim/flicker (flicker over
 * the frames that have it), max of max, PSNR from the mean MSE. */
void mtr_pool(const mtr_frame_stats *frames, size_t n, mtr_frame_stats *pooled);

/* Percentile (0..100) of n values by linear interpolation (type 7); reorders `values`. */
double mtr_percentile(float *values, size_t n, double pct);

double mtr_psnr(const mtr_image *a, const mtr_image *b);
double mtr_ssim(const mtr_image *a, const mtr_image *b, int threads);

/* ---- JND maths (paper sec. 3, Fig. 3; DESIGN section 7) ----
 * JND = Phi^-1(p) / Phi^-1(0.75): p = 0.75 is 1 JND, p = 0.5 is 0.
 * p_ref = (n_ref + n_tie/2) / n with a Wilson score interval at `confidence`. So that p = 0 or 1 give finite
 * JNDs, the JND (and its interval) uses p clamped to [1/(2n), 1 - 1/(2n)] — half an observation from the
 * boundary, the smallest change a study of n answers can resolve; `clamped` says when that happened. */
typedef struct mtr_jnd {
	double p, p_lo, p_hi;
	double jnd, jnd_lo, jnd_hi;
	int clamped;
} mtr_jnd;

double mtr_jnd_from_p(double p);
int mtr_jnd_from_counts(double n_ref, double n_tie, double n, double confidence, mtr_jnd *out);

/* ---- heatmaps ----
 * Colour map: a ramp in Oklab with lightness rising linearly from 0.27 to 0.93 and hue turning from blue
 * through teal and green to yellow (equal perceived steps, readable in greyscale), 8-bit sRGB. */
void mtr_colormap(double u, uint8_t rgb[3]);
/* Writes `map` (width*height, values 0..vmax) as a PNG with a legend bar and tick labels drawn below. */
int mtr_heatmap_write(const char *path, const float *map, uint32_t width, uint32_t height, double vmax, char *err,
		      size_t err_size);

/* ---- plots for people (gnuplot) ----
 * A script is written to `script_path` through the atomic-write helper and gnuplot then draws the PNGs it
 * names: mtr_plot_begin returns the stream to write the script into (NULL with a message on failure);
 * mtr_plot_end commits it and runs gnuplot (TL_ERR_UNSUPPORTED with a note when gnuplot is missing or
 * fails: plots are optional, the CSV/JSON beside them are the results). */
typedef struct mtr_plot {
	tl_atomic file;
} mtr_plot;

FILE *mtr_plot_begin(mtr_plot *p, const char *script_path, char *err, size_t err_size);
int mtr_plot_end(mtr_plot *p, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
