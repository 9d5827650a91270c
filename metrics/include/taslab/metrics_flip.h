/* metrics_flip.h — LDR-FLIP image difference (the algorithm behind the `flip` metric plug-in, metric_flip.c;
 * DESIGN section 6).
 *
 * Implements LDR-FLIP as described by Andersson, Nilsson, Akenine-Möller, Oskarsson, Åström and Fairchild,
 * "FLIP: A Difference Evaluator for Alternating Images", Proc. ACM Comput. Graph. Interact. Tech. 3(2), 2020
 * (HPG 2020), with the refinements of NVIDIA's public FLIP releases up to v1.6 (separable spatial filters,
 * clamp-to-edge borders). Results match the v1.6 reference tool to ~1e-7 on the mean.
 *
 * Thread-safety: an mtr_flip object is immutable after creation; any number of threads may call
 * mtr_flip_compute() on the same object concurrently.
 *
 * Errors: every function that can fail returns 0 or a negative tl_err (taslab/tl_error.h): TL_ERR_ARG for bad
 * arguments, TL_ERR_NOMEM when memory runs out, with one line in `err` where the function takes one.
 */
#ifndef TASLAB_METRICS_FLIP_H
#define TASLAB_METRICS_FLIP_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The FLIP default viewing condition: 0.7 m from a 0.7 m wide 3840-pixel monitor, 3840 px * pi / 180 per degree. */
#define MTR_FLIP_PPD_DEFAULT 67.02064327658226

/* Precomputed filters for one pixels-per-degree value. */
typedef struct mtr_flip mtr_flip;

/* Creates the filters for `ppd` (pixels per degree of visual angle, in (0, 1000]; the FLIP default is
 * 0.7 m * (3840 px / 0.7 m) * pi / 180 = 67.0206...). Returns 0, or TL_ERR_ARG / TL_ERR_NOMEM with a one-line message
 * in `err` (which may be NULL / err_size 0). */
int mtr_flip_create(double ppd, mtr_flip **out, char *err, size_t err_size);

/* Frees the object and nulls the pointer; accepts NULL and a pointer to NULL. */
void mtr_flip_destroy(mtr_flip **f);

/* FLIP error of `test_rgb` against `ref_rgb`. Inputs are display-referred sRGB values on the 0..255 scale, packed
 * RGB (3 floats per pixel, row-major, no padding); values need not be integral and are clamped to 0..255 (NaN to 0).
 * `map` (optional, width*height floats) receives the per-pixel error in [0,1]; `*mean` (required) receives the mean
 * per-pixel error, accumulated in double.
 * `threads` <= 0 uses all online cores (pthreads, one band of rows each). Any size >= 1x1 works; borders are
 * clamp-to-edge. Returns 0, or TL_ERR_ARG (zero size, NULL input) / TL_ERR_NOMEM with one line in `err`. */
int mtr_flip_compute(const mtr_flip *f, uint32_t width, uint32_t height, const float *ref_rgb, const float *test_rgb,
                     float *map, int threads, double *mean, char *err, size_t err_size);

/* A consumer of the error values as they are computed: called on the worker threads with `n` values of row `y` from
 * column `x0` (a row comes in pieces of at most 512 columns, in column order); `band` (0 .. threads-1) identifies the
 * calling thread's band of rows, so a consumer can keep per-band state without locks. */
typedef void (*mtr_flip_row_fn)(void *ctx, int band, uint32_t y, uint32_t x0, const float *err, size_t n);

/* mtr_flip_compute that also hands every computed piece of a row to `row_fn` (may be NULL) while it is in cache;
 * pooling statistics this way saves a pass over the map. At most `threads` bands (`threads` <= 0: all cores). */
int mtr_flip_compute_rows(const mtr_flip *f, uint32_t width, uint32_t height, const float *ref_rgb,
                          const float *test_rgb, float *map, mtr_flip_row_fn row_fn, void *row_ctx, int threads,
                          double *mean, char *err, size_t err_size);

/* Pooled statistics of a FLIP map as the reference tool prints them. The weighted percentiles are weighted by the
 * error value itself: the values are sorted ascending and the first whose running sum exceeds p * (sum of all
 * values) is returned (0 for an all-zero map). */
typedef struct mtr_flip_pool {
	double mean, weighted_median, q1_weighted, q3_weighted, min, max;
} mtr_flip_pool;

/* Computes the pooled statistics of `n` map values (`map` is not modified; a sorted copy is allocated).
 * Returns 0, TL_ERR_ARG on NULL arguments or n == 0, TL_ERR_NOMEM. */
int mtr_flip_pool_stats(const float *map, size_t n, mtr_flip_pool *out);

#ifdef __cplusplus
}
#endif

#endif /* TASLAB_METRICS_FLIP_H */
