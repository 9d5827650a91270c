/* pairs.h — pairs.json, the stimulus set of one scene and camera path written by `taslab pair` and read
 * by the study module (DESIGN sections 5, 7):
 *
 *   { "taslab_pairs": 1, "scene", "scene_path", "camera", "camera_motion", "fps", "frames": [first, last],
 *     "size": [w, h], "display_transform", "reference": {"run", "clip", "method"},
 *     stereo sets only: "display": "stereo", "ipd" (metres; clips side by side, 2w x h, left | right; size per eye),
 *     "conditions": [ {"id", "method", "variant", "T", "period", "method_facts", "run", "clip", "inspect"}, ... ] }
 *
 * "method_facts" (run.h run_method_facts) says what the study needs to know of a condition's method: whether it is
 * the reference (a catch pair) and whether it takes T and a period (issue 30.1); reference.method names the
 * reference method (the catch trials' condition). Sets made before they were recorded read with facts.known false
 * and ref_method "".
 *
 * A set taken from a sweep's runs (`taslab study pairs --sweep`, issue 27.13) has no run or inspect paths of its own
 * and says where its clips came from: "source": {"sweep": ABSOLUTE FOLDER, "ref_run"}, and per condition
 * "sweep_run" (relative to that folder); "scene_digest" and "colour_digest" (run.h) are the runs' input digests.
 *
 * Paths are relative to the folder holding pairs.json; the reader refuses absolute paths and ".." (source.sweep
 * excepted: it names a folder, never a file the study serves).
 * The file is written last and atomically: its presence means the set is complete. */
#ifndef TASLAB_PAIRS_H
#define TASLAB_PAIRS_H

#include <stddef.h>
#include <stdint.h>

#include "taslab/run.h"
#include "taslab/tl_error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct pairs_condition {
	char id[64];          /* unique within the set, e.g. "tarc-oracle-T8" */
	char method[32];      /* the variant's method name ("tarc-oracle") */
	char variant[64];     /* the variant token ("tarc-oracle@8") */
	double T;             /* NAN when the method has no threshold */
	uint32_t period;      /* 0 when the method has no period */
	run_method_facts facts; /* "method_facts"; known false when the file has none */
	char run[256], clip[256], inspect[256]; /* run and inspect: "" when the set has none (a set from a sweep) */
	char sweep_run[256];  /* "sweep_run": the run folder relative to the sweep (source.sweep) its clip came from */
} pairs_condition;

typedef struct pairs_set {
	char scene[64], camera[64], camera_motion[16];
	char scene_path[1024], display_transform[256];
	double fps;
	uint32_t first_frame, last_frame, width, height; /* stereo: size per eye */
	uint32_t views;       /* 2: "display": "stereo" (side-by-side clips, STEREO.md); 1 (or 0 when written): mono */
	double ipd;           /* stereo: metres */
	char ref_run[256], ref_clip[256];
	char ref_method[32];  /* reference.method: the reference's method name ("" when the file has none) */
	char scene_digest[24], colour_digest[24]; /* the runs' input digests (run.h; `pair` and `study pairs` record
						    * them); "" in a set made before */
	char sweep[1024];     /* source.sweep: the sweep folder the clips were taken from ("" : rendered by `pair`) */
	char sweep_ref_run[256]; /* source.ref_run: the reference's run folder relative to that sweep */
	pairs_condition *conditions; /* malloc'ed by pairs_read; borrowed by pairs_write */
	size_t count;
} pairs_set;

int pairs_write(const char *path, const pairs_set *s, char *err, size_t err_size);
/* TL_ERR_INPUT naming the file and what is wrong. Free with pairs_free. */
int pairs_read(const char *path, pairs_set *s, char *err, size_t err_size);
void pairs_free(pairs_set *s);

#ifdef __cplusplus
}
#endif
#endif
