/* sweep.h — sweep files and the layout of a sweep folder (DESIGN section 9).
 *
 * Two forms of one description:
 *  - a sweep *request*: what a user writes (a JSON sweep file, or the options of `taslab sweep`): scene names or
 *    paths, camera path names or "all", variant tokens, or methods x thresholds x periods to expand, frames as
 *    "A:B", the size, ... Names are not checked here (the CLI resolves them against the scene files and the
 *    method registry, which this layer cannot see);
 *  - a resolved sweep *spec*: SWEEP/sweep.json, written by `taslab sweep` before anything is rendered: every scene
 *    with its file, frame range, fps and camera paths (with their motion class), every variant with its id, method
 *    name, T and period, the size, the display transform and the metric settings. Rerunning `taslab sweep` on it
 *    (or on the same request) resumes the sweep; `taslab report`, Slurm tasks and the local job runner read it.
 *
 * Sweep file (request) keys: the table of sweep_keys.h (src/sweep_keys.c) — one line per key, from which this reader,
 * the command line of `taslab sweep`, its help and sweep.json's settings follow; anything else is refused with one
 * line naming the key. Lists (scenes, cameras, variants, methods, thresholds, periods) are JSON/TOML lists, or
 * "all" for cameras and methods; size is "WxH" or [W, H]; frames "A:B" | "A" | ":B" | "A:". Relative paths (out,
 * ocio_config, and scene entries that are paths) are relative to the sweep file's folder.
 *
 * Folder layout (index i of the plan: all `ref` runs first, scene-major, then every other run scene-major,
 * camera, variant — the order Slurm array task ids and `--task I` use):
 *   SWEEP/sweep.json                       the spec
 *   SWEEP/runs/<scene>/<camera>/<id>/      run folder (run.h); complete iff manifest.json exists
 *   SWEEP/clips/<scene>/<camera>/<id>.webm the run's clip (clip.h), written atomically
 *   SWEEP/metrics/<scene>/<camera>/<id>/   `metrics diff` against the ref run of the same scene and path;
 *                                          complete iff summary.json exists (written last)
 *   SWEEP/logs/<scene>/<camera>/<id>.log   what the run's process printed
 *   SWEEP/summary.csv, SWEEP/table1.md, SWEEP/report/index.html
 *
 * Errors: negative tl_err, one line in `err`. The structs are plain data with fixed arrays (about 100 KB:
 * allocate them on the heap).
 */
#ifndef TASLAB_SWEEP_H
#define TASLAB_SWEEP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "taslab/tl_error.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SWEEP_MAX_SCENES 16
#define SWEEP_MAX_CAMERAS 16
#define SWEEP_MAX_VARIANTS 64
#define SWEEP_MAX_VALUES 16   /* thresholds, periods */
#define SWEEP_NAME_MAX 64
#define SWEEP_PATH_MAX 1024

/* ---- request ---- */

/* The fields of the keys of sweep_keys.h (each key's line says which); the resolver fills the defaults. */
typedef struct sweep_request {
	uint32_t set;                                   /* bit i: key i of sweep_keys() was given (sweep_request_has) */
	char scenes[SWEEP_MAX_SCENES][SWEEP_PATH_MAX];  /* names or paths */
	size_t scene_count;
	bool cameras_all;
	char cameras[SWEEP_MAX_CAMERAS * 4][2 * SWEEP_NAME_MAX]; /* NAME or SCENE/NAME */
	size_t camera_count;
	char variants[SWEEP_MAX_VARIANTS][SWEEP_NAME_MAX];
	size_t variant_count;
	bool methods_all;
	char methods[SWEEP_MAX_VARIANTS][SWEEP_NAME_MAX];
	size_t method_count;
	double thresholds[SWEEP_MAX_VALUES];
	size_t threshold_count;
	uint32_t periods[SWEEP_MAX_VALUES];
	size_t period_count;
	char frames[64];
	uint32_t width, height;
	double fps, ppd;
	char out[SWEEP_PATH_MAX], baseline[SWEEP_NAME_MAX], metrics[128];
	char device[256], ocio_config[SWEEP_PATH_MAX], display[128], view[128];
	bool validation, truth;
	uint32_t jobs;
	bool stereo; /* --stereo: every run renders both eyes (STEREO.md) */
	double ipd;  /* --ipd M with --stereo (0: not given) */
} sweep_request;

/* Reads a sweep file (request form). Unknown keys, wrong types, empty lists, lists longer than the limits
 * above and malformed values are TL_ERR_INPUT naming the file and the key. */
int sweep_request_read(const char *path, sweep_request *r, char *err, size_t err_size);

/* ---- resolved spec (SWEEP/sweep.json) ---- */

typedef struct sweep_camera {
	char name[SWEEP_NAME_MAX];
	char motion[16];          /* "stationary" | "moving" (the study's Camera factor) */
} sweep_camera;

typedef struct sweep_scene {
	char name[SWEEP_NAME_MAX];
	char path[SWEEP_PATH_MAX]; /* absolute path of the scene file */
	uint32_t first, end;       /* frames [first, end) */
	double fps;
	sweep_camera cameras[SWEEP_MAX_CAMERAS];
	size_t camera_count;
	char digest[24];           /* scene_digest: the file and its assets, when the sweep was resolved (issue 31.4) */
} sweep_scene;

typedef struct sweep_variant {
	char variant[SWEEP_NAME_MAX]; /* canonical token "tarc-oracle@8" */
	char id[SWEEP_NAME_MAX];      /* folder name "tarc-oracle-T8" */
	char method[32];              /* the variant's method name "tarc-oracle" */
	double T;                     /* NAN without a threshold */
	uint32_t period;              /* 0 without a period */
} sweep_variant;

typedef struct sweep_spec {
	sweep_scene scenes[SWEEP_MAX_SCENES];
	size_t scene_count;
	sweep_variant variants[SWEEP_MAX_VARIANTS]; /* "ref" among them */
	size_t variant_count;
	/* the settings kept as given (the SWEEP_KEY_SPEC keys of sweep_keys.h), defaults filled by the resolver */
	uint32_t width, height;
	char baseline[SWEEP_NAME_MAX];  /* a variant token of the list */
	char metrics[128];              /* metric list for `metrics diff` ("all") */
	double ppd;                     /* FLIP pixels per degree */
	char device[256];               /* --device as given ("" = the default choice) */
	bool validation;
	bool truth;                     /* variants whose method has --truth are rendered with it */
	char ocio_config[SWEEP_PATH_MAX], display[128], view[128]; /* as given ("" = default) */
	char display_transform[256];    /* the resolved transform's name (colour_name) */
	char colour_digest[24];         /* colour_digest: the config and its LUTs, when resolved (issue 31.4) */
	char build_digest[24];          /* tl_build_digest() of the taslab that resolved it ("" in a sweep.json made
					 * before builds were recorded): a resume by another build is refused */
	bool stereo;                    /* every run stereo (--size per eye): part of the sweep's identity */
	double ipd;                     /* stereo: metres (default 0.063); 0 for mono */
} sweep_spec;

int sweep_spec_write(const char *path, const sweep_spec *s, char *err, size_t err_size);
/* TL_ERR_INPUT naming the file and what is wrong (strict: unknown keys, types, ranges, duplicate ids). */
int sweep_spec_read(const char *path, sweep_spec *s, char *err, size_t err_size);
/* Whether `path` holds a JSON object with a "taslab_sweep" key: a resolved sweep.json (valid or not), so a failure of
 * sweep_spec_read is the reason to report, not what the request reader says of it (issue 31.5). */
bool sweep_file_is_spec(const char *path);
/* 0 when a and b describe the same sweep (same runs, same rendering and metric settings); otherwise 1 with the
 * first difference in `what` ("variants: tfr@8 vs tfr@16"). */
int sweep_spec_compare(const sweep_spec *a, const sweep_spec *b, char *what, size_t what_size);
/* TL_OK when this taslab build (tl_build_digest) is the one that resolved the sweep; otherwise TL_ERR_INPUT naming
 * `path` (its sweep.json) and both digests: a resume by another build would mix its runs with the old build's. */
int sweep_build_check(const sweep_spec *s, const char *path, char *err, size_t err_size);

/* ---- the plan ---- */

typedef struct sweep_run {
	size_t index;
	size_t scene, camera, variant;  /* indices into the spec */
	size_t ref_index;               /* plan index of the ref run of the same scene and camera */
	bool is_ref;
} sweep_run;

/* Number of runs: sum over scenes of cameras x variants. */
size_t sweep_run_count(const sweep_spec *s);
/* Run `index` of the plan (see the order above). TL_ERR_ARG when out of range. */
int sweep_run_at(const sweep_spec *s, size_t index, sweep_run *out);

typedef enum sweep_path_kind {
	SWEEP_PATH_RUN = 0,  /* SWEEP/runs/<scene>/<camera>/<id> */
	SWEEP_PATH_CLIP,     /* SWEEP/clips/<scene>/<camera>/<id>.webm */
	SWEEP_PATH_METRICS,  /* SWEEP/metrics/<scene>/<camera>/<id> */
	SWEEP_PATH_LOG,      /* SWEEP/logs/<scene>/<camera>/<id>.log */
} sweep_path_kind;

/* The path of one of a run's outputs under `dir` (the sweep folder). */
void sweep_run_path(const sweep_spec *s, const char *dir, const sweep_run *r, sweep_path_kind kind, char *out,
		    size_t out_size);

/* What exists of a run: the run is complete (manifest.json), its clip, its metrics (summary.json); `damaged` only
 * from sweep_run_status_checked. */
typedef struct sweep_status {
	bool run, clip, metrics;
	bool damaged; /* a manifest, but the run does not match it or the spec (then `run` is false) */
} sweep_status;
/* Cheap (file existence only): for the job runner's polling. */
void sweep_run_status(const sweep_spec *s, const char *dir, const sweep_run *r, sweep_status *st);
/* The same, and a run with a manifest is checked against it (run_check: missing, extra, mixed-size frames) and
 * against the spec (variant, frames, size): one that fails is damaged — not run, its reason in `why` (issue 31.8).
 * Reads every frame's header: once per run and step, not in a polling loop. */
void sweep_run_status_checked(const sweep_spec *s, const char *dir, const sweep_run *r, sweep_status *st, char *why,
			      size_t why_size);
/* Run `index` of the plan has everything: run (checked), clip and metrics. */
bool sweep_run_complete(const sweep_spec *s, const char *dir, size_t index);

#ifdef __cplusplus
}
#endif
#endif
