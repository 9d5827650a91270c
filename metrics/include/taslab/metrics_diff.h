/* metrics_diff.h — `taslab metrics diff`: compare two frame sequences (run folders or image folders) and
 * write DIR/frames.csv and DIR/summary.json (names as in DESIGN section 6), optional heatmaps and plots.
 * Decoding of frame pair i+1 (its two frames on two threads) overlaps the statistics of pair i. */
#ifndef TASLAB_METRICS_DIFF_H
#define TASLAB_METRICS_DIFF_H

#include <stdbool.h>
#include <stddef.h>

#include "taslab/colour.h"
#include "taslab/metrics.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mtr_format { MTR_FORMAT_PNG = 0, MTR_FORMAT_EXR } mtr_format;

typedef struct mtr_diff_desc {
	const char *ref, *test; /* run folders (their frames/) or folders of images */
	const char *out;        /* output folder */
	mtr_format format;      /* PNG: the display frames as stored; EXR: through `colour` (unquantised) */
	const struct colour *colour;   /* required for EXR */
	bool heatmaps;          /* DIR/heatmaps/NNNNNN.png (max-RGB) and, with flip, DIR/heatmaps/flip/NNNNNN.png */
	double heatmap_max;     /* colour scale maximum (code values); 0: 64 */
	bool plots;             /* DIR/plots/ PNG plots through gnuplot (skipped with a note if gnuplot is missing) */
	int threads;            /* <= 0: all cores */
	const char *metrics;    /* comma-separated metrics to compute (NULL or "all": every one); the columns of the
	                           others stay in frames.csv (empty) and summary.json (null) */
	const mtr_option_value *options; /* metric options by name, e.g. {"ppd", 67.02} (mtr_compare_desc) */
	size_t option_count;
} mtr_diff_desc;

typedef struct mtr_diff_result {
	size_t frames;          /* frame pairs (per eye) */
	uint32_t views;         /* 2: two stereo runs, each eye against the same eye into OUT/L/ and OUT/R/ (every file
	                           of a mono diff), both eyes pooled into OUT/frames.csv and OUT/summary.json; else 1 */
	mtr_frame_stats pooled; /* stereo: over both eyes */
	mtr_frame_stats eye[2]; /* stereo: each eye's pooled values (L, R) */
	double seconds;         /* wall time */
	double compute_seconds; /* time in statistics (excluding decoding) */
} mtr_diff_result;

/* Returns TL_OK or a tl_err code, among them TL_ERR_ARG (EXR without `colour`, a bad metric or option),
 * TL_ERR_INPUT (a run or folder that is missing, incomplete or unlike the other — a stereo run against a mono
 * run or a folder of images among them; for a frame, the image reader's
 * code), TL_ERR_OUTPUT (OUT cannot be written) and TL_ERR_NOMEM. */
int mtr_diff_run(const mtr_diff_desc *d, mtr_diff_result *res, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
