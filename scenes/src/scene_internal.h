/* scene_internal.h (private) — what the parts of the scene library share: the strict JSON helpers
 * (scene_json.c) that name the file and JSON path in every message, and entry points between the
 * loaders (scene_parse.c: scene files; scene_gltf.c: bare glTF files; gltf.cpp: glTF assets). */
#ifndef TASLAB_SCENE_INTERNAL_H
#define TASLAB_SCENE_INTERNAL_H

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

#include "taslab/scene.h"

#define PATH_MAX_LEN 256

/* Parsing context: the file name for messages and the caller's error buffer. */
typedef struct jp {
	const char *file;
	char *err;
	size_t err_size;
	uint32_t texture_size; /* scene_load_desc.texture_size: replaces the file's texture_size unless 0 */
} jp;

/* Formats "FILE: PATH: message" into the error buffer; returns TL_ERR_INPUT. */
#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
int jfail(jp *c, const char *path, const char *fmt, ...);
/* JSON paths for messages: "$.a.b", "$.a[3]" (out: PATH_MAX_LEN bytes). */
void subpath(char *out, const char *path, const char *key);
void subidx(char *out, const char *path, size_t i);
/* Rejects keys of `obj` not in `allowed` (NULL-terminated). */
int jkeys(jp *c, json_t *obj, const char *path, const char *const *allowed);
/* Optional number `key` in [lo, hi] (absent: def). */
int jnum(jp *c, json_t *obj, const char *key, const char *path, float def, float lo, float hi, float *out);
int jarr_floats(jp *c, json_t *v, const char *p, int n, float *out);
int jvec(jp *c, json_t *obj, const char *key, const char *path, int n, const float *def, float *out);
int jv3(jp *c, json_t *obj, const char *key, const char *path, tlm_vec3 def, int required, tlm_vec3 *out);
int jstr(jp *c, json_t *obj, const char *key, const char *path, const char *def, const char **out);
int jbool(jp *c, json_t *obj, const char *key, const char *path, bool def, bool *out);
/* A scene name: 1..SCENE_NAME_MAX-1 characters of [A-Za-z0-9_.-]. */
int jname(jp *c, const char *s, const char *p, char out[SCENE_NAME_MAX]);

/* Replaces control characters (a newline in a file name or in a library's message) by spaces, so that every
 * message stays one line. */
void scene_err_one_line(char *err, size_t err_size);

/* Index of the entry called `name` in an array of structs starting with a name (stride bytes apart), or -1. */
int scene_find_named(const char *names, size_t stride, size_t n, const char *name);
#define SCENE_FIND(arr, n, key) scene_find_named((arr)[0].name, sizeof((arr)[0]), (n), (key))

/* A scene around a bare .gltf/.glb file (scene_gltf.c), with textures of texture_size (0: the default). */
int scene_from_gltf(const char *path, uint32_t texture_size, scene **out, char *err, size_t err_size);
/* scene_load_from_memory with a texture size override (0: none). */
int scene_parse_memory(const char *json, size_t len, const char *origin, uint32_t texture_size, scene **out, char *err,
		       size_t err_size);

#endif
