/* tl_json.h — JSON files through jansson, written with the atomic-write helper (tl_fs.h).
 * The JSON type is jansson's `json_t` (include <jansson.h> to build values). */
#ifndef TASLAB_TL_JSON_H
#define TASLAB_TL_JSON_H

#include <stddef.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

struct json_t;

/* Writes `value` to `path` atomically, indented by 2, keys sorted (deterministic files). */
int tl_json_write(const char *path, const struct json_t *value, char *err, size_t err_size);
/* The same text into an open stream (a tl_atomic of a set committed together); 0, or -1 on failure. */
int tl_json_dump(FILE *f, const struct json_t *value);
/* Reads a JSON file (at most 64 MiB, nesting at most 64 deep); *out is a new reference (json_decref it).
 * TL_ERR_INPUT with the line and column of a syntax error. */
int tl_json_read(const char *path, struct json_t **out, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
