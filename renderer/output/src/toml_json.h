/* toml_json.h (private to renderer/output) — reads a TOML file into the jansson value its JSON twin would give. */
#ifndef TASLAB_TOML_JSON_H
#define TASLAB_TOML_JSON_H

#include <stddef.h>

#include <jansson.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Parses the TOML file at `path` (at most 1 MiB) into *out (a JSON object; the caller owns it). Strings, integers,
 * floats, booleans, arrays and tables map to their JSON kinds; dates and times are refused. TL_ERR_INPUT with one line
 * "path:line:column: what" for a syntax error, TL_ERR_IO-class errors from reading the file. */
int tl_toml_read(const char *path, json_t **out, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
