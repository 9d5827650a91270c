/* tl_error.h — the one error enum of taslab, its strerror, and the message convention.
 *
 * Every library function that can fail returns 0 (TL_OK) or one of the negative codes below and writes
 * one line into a caller-supplied `err` buffer: what is wrong and, where it helps, what to do next
 * (CONVENTIONS.md: errors are values, libraries never exit). The code says which class of failure it
 * was, so a command can choose its exit status (tl_exit_status) and a caller can react (a sweep keeps
 * going after TL_ERR_VULKAN in one run, a CLI prints usage hints after TL_ERR_ARG).
 */
#ifndef TASLAB_TL_ERROR_H
#define TASLAB_TL_ERROR_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum tl_err {
	TL_OK = 0,
	TL_ERR_ARG = -1,         /* a bad argument or option value: fix the command line or description */
	TL_ERR_INPUT = -2,       /* an input (scene, image, run folder, CSV, database) is missing or malformed */
	TL_ERR_OUTPUT = -3,      /* an output could not be created or written (permissions, full disk, ...) */
	TL_ERR_NOMEM = -4,       /* out of memory */
	TL_ERR_VULKAN = -5,      /* a Vulkan call failed */
	TL_ERR_VALIDATION = -6,  /* the Khronos validation layer reported a message */
	TL_ERR_UNSUPPORTED = -7, /* valid, but not supported (yet): a planned method, a LUT view transform, ... */
	TL_ERR_DB = -8,          /* the study database (SQLite) failed */
	TL_ERR_CONFLICT = -9,    /* the request conflicts with existing state (answer already stored, ...) */
	TL_ERR_NOTFOUND = -10,   /* a named thing (trial, participant, condition) does not exist */
	TL_ERR_INTERRUPTED = -11, /* stopped on request (a signal) */
	TL_ERR_INTERNAL = -12,   /* a bug: an invariant did not hold */
	TL_ERR_INCOMPLETE = -13, /* the work went on, but some parts of it failed (a sweep's failed runs) */
} tl_err;

#define TL_ERR_MIN TL_ERR_INCOMPLETE

/* A short, static description of a code ("bad argument", "input error", ...); never NULL. */
const char *tl_strerror(int code);

/* The process exit status for a code, as every taslab command uses it: 0 for TL_OK, 2 for errors of
 * the command line and its inputs (TL_ERR_ARG, TL_ERR_INPUT, TL_ERR_UNSUPPORTED), 1 for the rest. */
int tl_exit_status(int code);

/* Formats one line into `err` (when err_size > 0) and returns `code`, so a failure is one statement:
 *     return tl_error(err, err_size, TL_ERR_INPUT, "%s: not a run folder (no manifest.json)", dir); */
#if defined(__GNUC__)
__attribute__((format(printf, 4, 5)))
#endif
int tl_error(char *err, size_t err_size, int code, const char *fmt, ...);

#ifdef __cplusplus
}
#endif
#endif
