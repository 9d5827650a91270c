/* sweep_keys.h — the one table of sweep settings (issue 30.2): every key of a sweep file is one line of
 * src/sweep_keys.c (name, type, range, help, its field in sweep_request and, for the settings a resolved sweep keeps as
 * given, its field in sweep_spec). Everything else follows from that line, as the method options follow from theirs
 * (method.h):
 *  - the sweep file reader (JSON and TOML) and its list of known keys (sweep_request_read, sweep.h);
 *  - the command-line options of `taslab sweep`, their help and the overlay onto a file's request (cli/cmd_sweep.c,
 *    cli/sweep_resolve.c; the key "ocio_config" is the option --ocio-config);
 *  - for SWEEP_KEY_SPEC keys: the copy into the resolved spec, SWEEP/sweep.json's write and read, and the comparison
 *    that decides whether a folder holds the same sweep (sweep_spec_write/read/compare).
 * Adding a setting (--stereo, --ipd, a metric option) is one table line plus its fields in sweep_request (and
 * sweep_spec) and its use. Defaults that depend on other knowledge (the scene's fps, FLIP's ppd) are the resolver's;
 * the help text states them.
 *
 * No allocation, no state: the table is constant data.
 */
#ifndef TASLAB_SWEEP_KEYS_H
#define TASLAB_SWEEP_KEYS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "taslab/sweep.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum sweep_key_type {
	SWEEP_KEY_NONE = 0,
	SWEEP_KEY_NAMES,   /* strings: `max` rows of `size` bytes, count at count_offset; comma-separated on the command line */
	SWEEP_KEY_NUMBERS, /* doubles in [lo, hi], at most `max`; comma-separated on the command line */
	SWEEP_KEY_WHOLES,  /* uint32_t in [lo, hi], at most `max`; comma-separated on the command line */
	SWEEP_KEY_STRING,  /* char[size], not empty */
	SWEEP_KEY_FRAMES,  /* char[size] holding "A:B", "A", ":B" or "A:" (tl_parse_frames) */
	SWEEP_KEY_SIZE,    /* uint32_t[2] (width, height): "WxH", in a file also [W, H] */
	SWEEP_KEY_NUMBER,  /* double in [lo, hi], lo > 0 (0 is "not given") */
	SWEEP_KEY_WHOLE,   /* uint32_t in [lo, hi], lo > 0 (0 is "not given") */
	SWEEP_KEY_BOOL,    /* bool; on the command line a flag (true when given) */
	SWEEP_KEY_TYPE_COUNT
} sweep_key_type;

enum {
	SWEEP_KEY_SPEC = 1u << 0,      /* kept as given in sweep_spec at spec_offset: written to and read from sweep.json */
	SWEEP_KEY_EMPTY_OK = 1u << 1,  /* SPEC strings: "" in sweep.json means "not given" (the default choice) */
	SWEEP_KEY_OPTIONAL = 1u << 2,  /* SPEC: a sweep.json without it (made before the key existed) reads as zero, and
					* so does a NUMBER or WHOLE 0 ("not given", unless the resolver fills a default):
					* a key added later is SPEC | OPTIONAL, so the sweeps made before it still resume */
	SWEEP_KEY_RELATIVE = 1u << 3,  /* in a file, a path relative to the file's folder (NAMES: the entries that look
					* like a path: a '/' or a .json/.gltf/.glb name) */
	SWEEP_KEY_RESUME_OK = 1u << 4, /* may be given on the command line when resuming a resolved sweep.json (it does
					* not change the sweep: --jobs) */
};

typedef struct sweep_key {
	const char *name;    /* the file key ("ocio_config"); the command line's option is --ocio-config */
	const char *arg;     /* placeholder in help texts ("LIST"); NULL for BOOL */
	const char *help;
	sweep_key_type type;
	size_t offset;       /* of the value in sweep_request */
	size_t size;         /* STRING, FRAMES: the field's size; lists: one entry's */
	size_t max;          /* lists: most entries */
	size_t count_offset; /* lists: the size_t count in sweep_request */
	const char *all;     /* NAMES: the word that stands for every entry ("all"): sets the bool at all_offset */
	size_t all_offset;
	double lo, hi;       /* numbers: the range */
	unsigned flags;      /* SWEEP_KEY_SPEC, ... */
	size_t spec_offset;  /* SWEEP_KEY_SPEC: the field in sweep_spec (same type and size as in the request) */
} sweep_key;

/* The table, in the order of the help and of the "known keys" message; at most 32 keys (sweep_request.set). */
const sweep_key *sweep_keys(size_t *count);
/* The key called `name` (a file key: "ocio_config"), or NULL. */
const sweep_key *sweep_key_find(const char *name);
/* The bit of `k` in sweep_request.set. */
uint32_t sweep_key_bit(const sweep_key *k);
/* Bytes of a scalar key's value (STRING, FRAMES, SIZE, NUMBER, WHOLE, BOOL); 0 for lists. */
size_t sweep_key_value_size(const sweep_key *k);
/* Whether the request sets key `name` (from the file or the command line). */
bool sweep_request_has(const sweep_request *r, const char *name);
/* Copies the SWEEP_KEY_SPEC keys from the request into the spec as given (the resolver then fills its defaults). */
void sweep_spec_copy_keys(sweep_spec *s, const sweep_request *r);
/* "scenes, cameras, ..." (every key, `sep` between them) into out. */
const char *sweep_key_list(const char *sep, char *out, size_t out_size);

#ifdef __cplusplus
}
#endif
#endif
