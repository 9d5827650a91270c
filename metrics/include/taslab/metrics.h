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
 *  - FLIP: LDR-FLIP (Andersson et al. 2020) on the display values at `ppd` pixels per degree (metrics_flip.h);
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

/* Statistics of one frame pair (or pooled over frames). Fields of metrics that were not computed are NAN. */
typedef struct mtr_frame_stats {
	double mean, p50, p95, p99, max;       /* of the max-RGB difference map */
	double exceed[MTR_THRESHOLD_COUNT];
	double mse, psnr, ssim;                /* psnr = INFINITY for identical images */
	double flicker_mean;                   /* NAN when there is no previous frame */
	uint32_t max_x, max_y;                 /* where the max difference is (first in row order) */
	/* LDR-FLIP (metrics_flip.h): mean per-pixel error, and the pooled values NVIDIA's tool prints: weighted
	 * median and quartiles (weights = the error values), min, max. Per frame over its pixels; pooled over all
	 * pixels of all frames (mtr_comparer_pool). The weighted ones come from a value-weighted histogram with a
	 * relative bin width of 2^-12 (error below 2.5e-4 x the value); mean, min and max are exact. */
	double flip_mean, flip_weighted_median, flip_q1_weighted, flip_q3_weighted, flip_min, flip_max;
	uint32_t metrics;                      /* bit i set: registry metric i (mtr_metric_name(i)) was computed */
} mtr_frame_stats;

/* All statistics of one frame pair: every metric of the registry with its default options. `a_prev`/`b_prev`
 * (both or neither may be NULL) enable flicker. `map` (optional, width*height floats) receives the max-RGB
 * difference map. `threads` <= 0: all cores. For a sequence use an mtr_comparer (it keeps its buffers). */
int mtr_frame_compare(const mtr_image *a, const mtr_image *b, const mtr_image *a_prev, const mtr_image *b_prev,
		      float *map, int threads, mtr_frame_stats *out, char *err, size_t err_size);

/* Clip-level pooling over n frames: means of per-frame mean/p50/p95/p99/exceed/ssim/flicker/flip_mean (flicker
 * over the frames that have it), max of max, PSNR from the mean MSE, FLIP min/max; the weighted FLIP percentiles
 * need the pixels and are NAN here (an mtr_comparer pools them). Metrics no frame computed stay NAN. */
void mtr_pool(const mtr_frame_stats *frames, size_t n, mtr_frame_stats *pooled);

/* ---- metric selection (the registry: maxrgb, psnr, ssim, flicker, flip — one file each in metrics/src) ---- */

/* Number of metrics in the registry; the name of metric i (NULL past the end); its index by name (-1: none). */
int mtr_metric_count(void);
const char *mtr_metric_name(int i);
int mtr_metric_find(const char *name);
/* "maxrgb,psnr,ssim,flicker,flip" into buf. */
const char *mtr_metric_list(char *buf, size_t buf_size);
/* Parses a comma-separated metric list ("all" or NULL/empty: every metric) into a bit mask. TL_ERR_ARG with one
 * line naming the unknown metric and the known ones. */
int mtr_metric_parse(const char *list, uint32_t *mask, char *err, size_t err_size);

/* A metric option by name, e.g. {"ppd", 40.0} (see `taslab metrics diff --help`). */
typedef struct mtr_option_value {
	const char *name;
	double value;
} mtr_option_value;

typedef struct mtr_compare_desc {
	const char *metrics;              /* comma-separated list; NULL, "" or "all": every metric */
	const mtr_option_value *options;  /* applied to every selected metric that declares the option */
	size_t option_count;
	int threads;                      /* <= 0: all cores */
} mtr_compare_desc;

/* A comparer runs the selected metrics on a sequence of frame pairs and pools them (mtr_diff_run uses one).
 * Options unknown to every metric, values out of range and unknown metrics are TL_ERR_ARG. */
typedef struct mtr_comparer mtr_comparer;
int mtr_comparer_create(const mtr_compare_desc *desc, mtr_comparer **out, char *err, size_t err_size);
/* Frees it and nulls the pointer; accepts NULL. */
void mtr_comparer_destroy(mtr_comparer **c);
/* One frame pair (as mtr_frame_compare; `flip_map`, optional, receives the per-pixel FLIP error). Frames of one
 * comparer must have one size. */
int mtr_comparer_frame(mtr_comparer *c, const mtr_image *a, const mtr_image *b, const mtr_image *a_prev,
		       const mtr_image *b_prev, float *map, float *flip_map, mtr_frame_stats *out, char *err,
		       size_t err_size);
/* Pools the n frames given (mtr_pool) plus what needs the comparer's per-pixel state (FLIP weighted percentiles
 * over all frames compared so far). */
void mtr_comparer_pool(mtr_comparer *c, const mtr_frame_stats *frames, size_t n, mtr_frame_stats *pooled);
/* Adds what `from` gathered over its frames (max-RGB histogram, FLIP's pixel histogram) to `into`, so that
 * mtr_comparer_pool(into, ...) over both comparers' frames pools all their pixels (a stereo diff: one comparer per
 * eye, then both eyes pooled). Both must select the same metrics with the same options and compare frames of one
 * size; TL_ERR_ARG otherwise. */
int mtr_comparer_merge(mtr_comparer *into, const mtr_comparer *from, char *err, size_t err_size);
/* The selected metrics: bit i for registry metric i. */
uint32_t mtr_comparer_selected(const mtr_comparer *c);
/* Counts of floor(d) (max-RGB difference, bin 255 includes larger) over all frames compared; NULL when maxrgb is
 * not selected. */
const uint64_t *mtr_comparer_histogram(const mtr_comparer *c);

/* Result columns in frames.csv / summary.json order (DESIGN section 6): column i's name (NULL past the end), its
 * value in *s (NAN when its metric was not computed), and where it goes (1: frames.csv, 2: summary.json, 3: both). */
const char *mtr_column_name(int i);
double mtr_column_value(int i, const mtr_frame_stats *s);
unsigned mtr_column_where(int i);

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
/* Writes `map` (width*height, values 0..vmax) as a PNG with a legend bar and tick labels drawn below. Returns
 * TL_OK, TL_ERR_NOMEM, or the PNG writer's code (TL_ERR_OUTPUT when PATH cannot be written). */
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

/* The report's SVG plots whose key lists `entries` lines (a sweep of every method: twenty or more): writes the
 * terminal, a key below the plot in three columns, and line types 1..32: sixteen distinct colours (gnuplot's own eight
 * repeat from the ninth line on), solid with filled points, then the same colours dash-dotted with open points. The canvas grows by one key row per three entries so that the plot area
 * keeps its size (460 px wide, about 190 px high) however many methods the key lists. */
void mtr_plot_svg_preamble(FILE *f, size_t entries);

#ifdef __cplusplus
}
#endif
#endif
