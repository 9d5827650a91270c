/* metric.h — the metric plug-in interface (private to metrics/; ARCHITECTURE.md "libvmaf, one plug-in per file").
 *
 * A metric is one file, metric_<name>.c, that exports one `const mtr_metric mtr_metric_<name>` with its options
 * table and callbacks; registry.c is the only list of them. The comparer (compare.c) runs the selected metrics on
 * every frame pair. The per-pixel statistics that several metrics share (max-RGB map, squared error, flicker) are
 * computed in ONE pass over the images (pixel.c) for all metrics that ask for them through `pixel_pass`, so adding
 * a metric never adds a pass over memory that another metric already makes.
 *
 * Adding a metric: write metric_<name>.c (columns, options, create/compute/pool/destroy), add its fields to
 * mtr_frame_stats (metrics.h) and one line to registry.c. Column order in frames.csv / summary.json is the registry
 * order, then each metric's columns in their table order (DESIGN section 6 fixes it; new metrics go last).
 */
#ifndef TASLAB_METRICS_METRIC_H
#define TASLAB_METRICS_METRIC_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "taslab/metrics.h"

/* Hot loops get an AVX2 clone next to the baseline-ISA one, picked at load time (ifunc), on x86-64 Linux with gcc;
 * not under ThreadSanitizer (its runtime is not ready when ifunc resolvers run). No FMA in either (ISO C mode does
 * not contract), so both clones give the same results. Same rule as FLIP_TARGET_CLONES in flip.c. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) &&                           \
	!defined(MTR_NO_CLONES) && !defined(__SANITIZE_THREAD__)
#define MTR_TARGET_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define MTR_TARGET_CLONES
#endif

/* Sum of n floats in 8 independent float partial sums (gcc vectorises them without reassociating, so the result does
 * not depend on the ISA), the tail and the lanes added in double. Used for row sums by the pixel pass and SSIM. */
static inline double mtr_lane_sum(const float *restrict v, size_t n)
{
	float acc[8] = {0};
	size_t x = 0;
	for (; x + 8 <= n; x += 8)
		for (int u = 0; u < 8; u++)
			acc[u] += v[x + (size_t)u];
	double s = 0;
	for (; x < n; x++)
		s += v[x];
	for (int u = 0; u < 8; u++)
		s += acc[u];
	return s;
}

/* ---- the shared pixel pass (pixel.c) ---- */
enum {
	MTR_PASS_MAXRGB = 1u,  /* d = max-RGB difference: map, sum, max and where, exceed_T counts, histogram */
	MTR_PASS_SQ = 2u,      /* sum of squared channel differences (MSE) */
	MTR_PASS_FLICKER = 4u, /* sum of max_c |(a - a_prev) - (b - b_prev)| (needs the previous frames) */
};

typedef struct mtr_pixel_result {
	double sum_d, sum_sq, sum_flicker;
	uint64_t hist[256];                  /* counts of floor(d), clamped to 0..255 */
	uint64_t exceed[MTR_THRESHOLD_COUNT]; /* d > mtr_thresholds[k] */
	float max;                           /* max d, first in row order at (max_x, max_y) */
	uint32_t max_x, max_y;
	bool integral; /* every d is a whole number (8-bit inputs): hist is the exact distribution of d */
} mtr_pixel_result;

/* One pass over a, b (and a_prev, b_prev with MTR_PASS_FLICKER) on `threads` row bands. `map` (optional,
 * width*height) receives d. Returns TL_OK or TL_ERR_NOMEM. */
int mtr_pixel_pass(const mtr_image *a, const mtr_image *b, const mtr_image *a_prev, const mtr_image *b_prev,
		   unsigned what, float *map, int threads, mtr_pixel_result *out);

/* Exact type-7 percentile (0..100) of n values whose distribution is the 256-bin histogram of whole numbers. */
double mtr_hist_percentile(const uint64_t hist[256], uint64_t n, double pct);

/* ---- threads (metrics.c) ---- */
#define MTR_MAX_THREADS 64
/* The number of bands to use: `requested` (<= 0: all online cores), at most MTR_MAX_THREADS and `rows`. */
int mtr_thread_count(int requested, uint32_t rows);
/* Runs fn(ctx, band, y0, y1) for `threads` contiguous row bands of [0, rows), in parallel (band 0 on the caller). */
typedef void (*mtr_band_fn)(void *ctx, int band, uint32_t y0, uint32_t y1);
void mtr_parallel_rows(uint32_t rows, int threads, mtr_band_fn fn, void *ctx);

/* ---- plug-ins ---- */

/* What a metric sees of one frame pair. */
typedef struct mtr_pair {
	const mtr_image *a, *b;           /* reference and test */
	const mtr_image *a_prev, *b_prev; /* the previous pair, or both NULL (first frame) */
	const mtr_pixel_result *px;       /* the shared pass (the metric's `pixel_pass` bits were computed) */
	const float *map;                 /* d per pixel, or NULL when the caller did not ask for the map */
	float *flip_map;                  /* optional output: per-pixel FLIP error (heatmaps) */
	int threads;
} mtr_pair;

/* A numeric option of a metric (libvmaf's VmafOption): a double at `offset` in the metric's state. */
typedef struct mtr_metric_option {
	const char *name; /* as given on the command line: --NAME */
	const char *help;
	size_t offset;
	double def, lo, hi; /* default and accepted range (inclusive) */
} mtr_metric_option;

/* A result column: a double at `offset` in mtr_frame_stats. */
enum { MTR_COL_FRAMES = 1u, MTR_COL_SUMMARY = 2u, MTR_COL_BOTH = 3u };
typedef struct mtr_column {
	const char *name; /* DESIGN section 6's name */
	size_t offset;
	unsigned where;   /* MTR_COL_*: frames.csv, summary.json or both */
} mtr_column;

typedef struct mtr_metric {
	const char *name; /* --metrics token */
	const char *help;
	unsigned pixel_pass;             /* MTR_PASS_* bits it reads from mtr_pair.px */
	const mtr_column *columns;       /* {0}-terminated */
	const mtr_metric_option *options; /* {0}-terminated, or NULL */
	size_t state_size;               /* zero-initialised, options set to their values before create */
	/* Optional: set-up after the options are known. */
	int (*create)(void *state, char *err, size_t err_size);
	/* Fills the metric's fields of *out for one pair (the others are left alone). */
	int (*compute)(void *state, const mtr_pair *p, mtr_frame_stats *out, char *err, size_t err_size);
	/* Pools n frames' fields into *pooled. `state` is NULL for the stateless mtr_pool(). */
	void (*pool)(void *state, const mtr_frame_stats *frames, size_t n, mtr_frame_stats *pooled);
	/* Optional, for state that pools over pixels: adds what `from` (the same metric with the same options) has
	 * gathered over its frames to `into`, as if `into` had compared them too (a stereo diff pools both eyes). */
	void (*merge)(void *into, const void *from);
	/* Optional: frees what create/compute allocated (not the state itself). */
	void (*destroy)(void *state);
} mtr_metric;

/* The registry (registry.c): every metric, in column order, NULL-terminated. */
extern const mtr_metric *const mtr_metric_registry[];

/* Sets every field of the metric's columns in *s to NAN (a metric not selected or without a value). */
void mtr_metric_clear(const mtr_metric *m, mtr_frame_stats *s);

#endif
