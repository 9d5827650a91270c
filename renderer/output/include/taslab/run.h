/* run.h — a run folder (DESIGN section 5): its writer and its reader.
 *
 *   RUN/frames/NNNNNN.exr   scene-linear RGBA half (attributes taslab:scene, :camera, :method, ...)
 *   RUN/frames/NNNNNN.png   display-referred 8-bit RGB
 *   RUN/decisions/NNNNNN.png  `render --decisions`: the reuse decision per pixel (frame_decision, frame.h) as
 *                           colours: none black, reused (96,96,96), new (0,220,255), second frame
 *                           (40,90,255), predicted (255,48,0), scheduled (255,210,0), late (255,0,255:
 *                           reused but more than T from the truth; with --truth)
 *   RUN/rates/NNNNNN.png    `render --rate-images` (VRS methods, vref): the shading rate of each 16x16 tile
 *                           (frame_rate, frame.h), one pixel per tile (ceil(W/16) x ceil(H/16)) as colours:
 *                           1x1 black, 1x2 (0,0,255), 2x1 (0,160,255), 2x2 (0,200,0), 2x4 (255,255,0),
 *                           4x2 (255,150,0), 4x4 (255,0,0)
 *   RUN/stats.csv           one row per frame (frame.h)
 *   stereo (STEREO.md): RUN/frames/L/ and RUN/frames/R/ instead of RUN/frames/ (the same names inside), and
 *   RUN/sbs/NNNNNN.png, the display frames side by side (2W x H, left | right); manifest inputs.stereo, inputs.ipd
 *   RUN/manifest.json       written last and atomically: inputs, method options, device, totals
 *
 * Completeness protocol: run_writer_create removes an old manifest.json first and every frame, stats.csv
 * and the manifest are written through the atomic-write helper (tl_fs.h); manifest.json comes last. A
 * folder with a manifest.json is a complete run; one without is not. A re-used folder is emptied of the
 * previous run's frames, stats and temporary files, so it holds exactly one run.
 *
 * Errors: negative tl_err (tl_error.h) and one line in `err`. Ownership: create/destroy pairs; the
 * writer copies every string of run_info it keeps.
 */
#ifndef TASLAB_RUN_H
#define TASLAB_RUN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "taslab/frame.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One method option as recorded in manifest.json's "method_options" (key → number, bool or string). INTEGER is a
 * number written as a JSON integer ("max-age": 7, not 7.0; issue 24.8): the integer options and derived sizes. */
typedef enum run_value_type { RUN_VALUE_NUMBER = 0, RUN_VALUE_BOOL, RUN_VALUE_STRING, RUN_VALUE_INTEGER } run_value_type;
typedef struct run_option {
	const char *key;
	run_value_type type;
	double number;
	bool boolean;
	const char *string;
} run_option;

#define RUN_MAX_OPTIONS 16

/* What the other modules need to know of a run's method (issue 30.1): the method registry (method.h,
 * method_facts) writes them into manifest.json (inputs.method_facts) and pairs.json (conditions[].method_facts),
 * and metrics/ and study/ read them from there instead of knowing method names:
 *   "method_facts": {"family": "atlas", "baseline": "sa", "reference": false, "takes_threshold": true,
 *                    "takes_period": false}
 * A file made before they were recorded reads as known = false; its readers ask for the run (or set) to be made
 * again. */
typedef struct run_method_facts {
	bool known;           /* the file recorded them */
	char family[32];      /* "reference", "forward", "reprojection", "atlas", ... (method.h) */
	char baseline[32];    /* the method whose run this one's reductions are against when that run is in the same
			       * set ("sa" for the atlas methods, paper Table 1); the reference otherwise */
	bool reference;       /* the reference method, which every other one is compared with */
	bool takes_threshold; /* has a threshold T (variant @T) */
	bool takes_period;    /* has a period N (variant /N) */
} run_method_facts;

typedef struct run_info {
	const char *scene_name, *scene_path, *camera, *camera_motion, *device, *driver;
	const char *method;  /* the variant's method name, e.g. "tarc-oracle" (EXR taslab:method, CSV method) */
	const char *variant; /* the variant token, e.g. "tarc-oracle@8" */
	double threshold;    /* T, NAN when the method has none */
	uint32_t period;     /* N of rrc/sau, 0 when the method has none */
	run_method_facts facts; /* inputs.method_facts */
	const run_option *options; /* the method's options, all of them (defaults included) */
	size_t option_count;
	const run_option *derived; /* what the method derived from them (render_derived): inputs.method_derived */
	size_t derived_count;
	/* Library versions for the manifest's "versions" (NULL: not recorded): OpenColorIO, and the Vulkan API version
	 * of the device ("1.3.230"); the driver is `driver`. */
	const char *ocio_version, *vulkan_api;
	uint32_t first_frame, last_frame; /* inclusive */
	uint32_t width, height;
	float fps;
	bool validation;
	bool write_exr, write_png;
	bool write_decisions; /* RUN/decisions/NNNNNN.png from frame_image.decisions */
	bool write_rates;     /* RUN/rates/NNNNNN.png from frame_image.tile_rates */
	const char *command_line;
	const char *display_transform; /* colour_name() of the view transform used for the PNGs */
	/* Content hashes of the inputs (scene_digest: the scene file and its assets; colour_digest: the config and its
	 * LUTs), recorded so a run made from other inputs than a sweep's is told apart (NULL: not recorded). */
	const char *scene_digest, *colour_digest;
	uint32_t views;       /* 2: a stereo run (run_writer_frame_views); 0 or 1: mono */
	double ipd;           /* stereo: metres between the eyes */
} run_info;

typedef struct run_writer run_writer;

int run_writer_create(const char *dir, const run_info *info, run_writer **out, char *err, size_t err_size);
/* Writes the frame's EXR and PNG and appends its stats.csv row. */
int run_writer_frame(run_writer *w, const frame_image *img, const frame_stats *st, char *err, size_t err_size);
/* A stereo run's frame: the eyes' images (imgs[0] left, imgs[1] right) into frames/L/ and frames/R/, the side-by-side
 * PNG into sbs/, and the stats row. TL_ERR_ARG when the run is not stereo or the eyes differ in size. */
int run_writer_frame_views(run_writer *w, const frame_image *imgs, uint32_t views, const frame_stats *st, char *err,
			   size_t err_size);
/* The folder of view v's frames of a run with `views` views: "frames" (mono), "frames/L", "frames/R". */
const char *run_view_dir(uint32_t views, uint32_t v);
/* The frame_decision a decision-map colour stands for; -1 for any other colour. */
int run_decision_code(const uint8_t rgb[3]);
/* The frame_rate a rate-image colour stands for; -1 for any other colour. */
int run_rate_code(const uint8_t rgb[3]);
/* Closes stats.csv and writes manifest.json (atomically) with totals. */
int run_writer_finish(run_writer *w, double wall_s, char *err, size_t err_size);
/* Frees the writer; an unfinished run leaves no manifest.json. */
void run_writer_destroy(run_writer **w);

/* ---- reading ---- */

typedef struct run_manifest {
	char scene[64], camera[64], camera_motion[16], method[32], variant[64];
	char scene_path[1024], device[256], display_transform[256];
	char scene_digest[24], colour_digest[24]; /* "" when the manifest has none (made before they were recorded) */
	char build_digest[24];     /* versions.build: tl_build_digest() of the taslab that rendered it ("" before) */
	double threshold;          /* NAN when absent */
	uint32_t period;           /* 0 when absent */
	run_method_facts facts;    /* inputs.method_facts; known = false in a manifest made before them */
	uint32_t first_frame, last_frame, width, height;
	double fps;
	bool exr, png;
	uint64_t frames, visible_samples, shaded_samples;
	double gpu_ms_median, wall_s;
	uint32_t views;            /* 2: stereo (inputs.stereo), 1: mono (also a manifest made before stereo runs) */
	double ipd;                /* stereo: inputs.ipd in metres; 0 for mono */
} run_manifest;

/* Reads DIR/manifest.json. TL_ERR_INPUT when the folder is not a complete run (no manifest) or the
 * manifest lacks a field or holds an impossible value (frames, size, fps). */
int run_manifest_read(const char *dir, run_manifest *m, char *err, size_t err_size);

/* Checks that DIR/frames (stereo: DIR/frames/L and DIR/frames/R) holds exactly the manifest's frames in format `ext` ("png" or "exr"): every
 * frame first..last present, no frame outside that range, each of the manifest's size (its header says).
 * TL_ERR_INPUT naming the first problem. */
int run_check_frames(const char *dir, const run_manifest *m, const char *ext, char *err, size_t err_size);
/* Reads the manifest and checks the frames of every format it records (run_check_frames): what each command
 * that reads a run (clip, tonemap, metrics, sweeps) asks before trusting it. TL_ERR_INPUT naming the first problem. */
int run_check(const char *dir, run_manifest *m, char *err, size_t err_size);

/* stats.csv as a table of numbers: values[row * cols + col], NAN for empty cells. */
typedef struct run_stats {
	size_t rows, cols;
	char **names;
	double *values;
} run_stats;

int run_stats_read(const char *dir, run_stats *s, char *err, size_t err_size);
/* Column index of `name`, or -1. */
int run_stats_col(const run_stats *s, const char *name);
/* Value at (row, column name): NAN when the column is absent or the cell empty. */
double run_stats_get(const run_stats *s, size_t row, const char *name);
void run_stats_free(run_stats *s);

#ifdef __cplusplus
}
#endif
#endif
