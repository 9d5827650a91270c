/* json.c — JSON files written atomically and read with limits (tl_json.h). */
#include "taslab/tl_json.h"

#include <jansson.h>
#include <stdlib.h>

#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"

#define JSON_MAX_BYTES (64u << 20)
#define JSON_MAX_DEPTH 64

int tl_json_dump(FILE *f, const json_t *value)
{
	return value && json_dumpf(value, f, JSON_INDENT(2) | JSON_SORT_KEYS) == 0 && fputc('\n', f) != EOF ? 0 : -1;
}

int tl_json_write(const char *path, const json_t *value, char *err, size_t err_size)
{
	if (!value)
		return tl_error(err, err_size, TL_ERR_NOMEM, "%s: out of memory building the JSON document", path);
	tl_atomic a;
	int rc = tl_atomic_open(&a, path, err, err_size);
	if (rc)
		return rc;
	if (tl_json_dump(a.f, value)) {
		tl_atomic_abort(&a);
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot write", path);
	}
	return tl_atomic_commit(&a, err, err_size);
}

/* Deepest nesting of [ and { outside strings (jansson's parser recurses once per level). */
static int too_deep(const char *s)
{
	int depth = 0, in_str = 0;
	for (; *s; s++) {
		if (in_str) {
			if (*s == '\\' && s[1])
				s++;
			else if (*s == '"')
				in_str = 0;
		} else if (*s == '"') {
			in_str = 1;
		} else if (*s == '[' || *s == '{') {
			if (++depth > JSON_MAX_DEPTH)
				return 1;
		} else if (*s == ']' || *s == '}') {
			depth--;
		}
	}
	return 0;
}

int tl_json_read(const char *path, json_t **out, char *err, size_t err_size)
{
	*out = NULL;
	char *text = NULL;
	size_t len = 0;
	int rc = tl_read_file(path, JSON_MAX_BYTES, &text, &len, err, err_size);
	if (rc)
		return rc;
	if (too_deep(text)) {
		free(text);
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: JSON nested deeper than %d levels", path, JSON_MAX_DEPTH);
	}
	json_error_t je;
	*out = json_loadb(text, len, JSON_REJECT_DUPLICATES, &je);
	free(text);
	if (!*out) {
		/* jansson quotes the offending input ("near '...'"): control characters there would break the one-line
		 * message (found by fuzz_sweep) */
		for (char *c = je.text; *c; c++)
			if ((unsigned char)*c < 0x20 || *c == 0x7f)
				*c = '?';
		return tl_error(err, err_size, TL_ERR_INPUT, "%s:%d:%d: %s", path, je.line, je.column, je.text);
	}
	return TL_OK;
}
