/* scene_json.c — strict JSON helpers for scene files (scene_internal.h): every message names the file
 * and the JSON path, so a typo never silently changes an experiment. */
#include "scene_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>



#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
int jfail(jp *c, const char *path, const char *fmt, ...)
{
	char msg[512];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(msg, sizeof msg, fmt, ap);
	va_end(ap);
	snprintf(c->err, c->err_size, "%s: %s: %s", c->file, path, msg);
	return TL_ERR_INPUT;
}

void subpath(char *out, const char *path, const char *key)
{
	snprintf(out, PATH_MAX_LEN, "%s.%s", path, key);
}

void subidx(char *out, const char *path, size_t i)
{
	snprintf(out, PATH_MAX_LEN, "%s[%zu]", path, i);
}

/* Rejects keys not in `allowed` (NULL-terminated). */
int jkeys(jp *c, json_t *obj, const char *path, const char *const *allowed)
{
	const char *key;
	json_t *val;
	if (!json_is_object(obj))
		return jfail(c, path, "expected an object");
	json_object_foreach(obj, key, val) {
		int ok = 0;
		for (const char *const *a = allowed; *a; a++)
			if (!strcmp(*a, key))
				ok = 1;
		if (!ok) {
			char list[400] = "";
			for (const char *const *a = allowed; *a; a++) {
				strncat(list, *a, sizeof list - strlen(list) - 1);
				if (a[1])
					strncat(list, ", ", sizeof list - strlen(list) - 1);
			}
			char p[PATH_MAX_LEN];
			subpath(p, path, key);
			return jfail(c, p, "unknown key (allowed here: %s)", list);
		}
	}
	return 0;
}

int jnum(jp *c, json_t *obj, const char *key, const char *path, float def, float lo, float hi, float *out)
{
	json_t *v = json_object_get(obj, key);
	char p[PATH_MAX_LEN];
	subpath(p, path, key);
	if (!v) {
		*out = def;
		return 0;
	}
	if (!json_is_number(v))
		return jfail(c, p, "expected a number");
	double d = json_number_value(v);
	if (!isfinite(d) || d < lo || d > hi)
		return jfail(c, p, "value %g out of range [%g, %g]", d, (double)lo, (double)hi);
	*out = (float)d;
	return 0;
}

int jarr_floats(jp *c, json_t *v, const char *p, int n, float *out)
{
	if (!json_is_array(v) || (int)json_array_size(v) != n)
		return jfail(c, p, "expected an array of %d numbers", n);
	for (int i = 0; i < n; i++) {
		json_t *e = json_array_get(v, (size_t)i);
		/* finite as a float too: 1e39 is a valid JSON number but infinity after the conversion */
		if (!json_is_number(e) || !isfinite((float)json_number_value(e)))
			return jfail(c, p, "element %d is not a finite number (in float range, |x| < 3.4e38)", i);
		out[i] = (float)json_number_value(e);
	}
	return 0;
}

int jvec(jp *c, json_t *obj, const char *key, const char *path, int n, const float *def, float *out)
{
	json_t *v = json_object_get(obj, key);
	char p[PATH_MAX_LEN];
	subpath(p, path, key);
	if (!v) {
		if (!def)
			return jfail(c, p, "required");
		memcpy(out, def, (size_t)n * sizeof *out);
		return 0;
	}
	return jarr_floats(c, v, p, n, out);
}

int jv3(jp *c, json_t *obj, const char *key, const char *path, tlm_vec3 def, int required, tlm_vec3 *out)
{
	float d[3] = {def.x, def.y, def.z}, o[3];
	int rc = jvec(c, obj, key, path, 3, required ? NULL : d, o);
	if (!rc)
		*out = tlm_v3(o[0], o[1], o[2]);
	return rc;
}

int jstr(jp *c, json_t *obj, const char *key, const char *path, const char *def, const char **out)
{
	*out = def ? def : ""; /* defined on every path (errors too), which the optimiser cannot see through jfail */
	json_t *v = json_object_get(obj, key);
	char p[PATH_MAX_LEN];
	subpath(p, path, key);
	if (!v) {
		if (!def)
			return jfail(c, p, "required");
		*out = def;
		return 0;
	}
	if (!json_is_string(v))
		return jfail(c, p, "expected a string");
	*out = json_string_value(v);
	return 0;
}

int jbool(jp *c, json_t *obj, const char *key, const char *path, bool def, bool *out)
{
	*out = def;
	json_t *v = json_object_get(obj, key);
	char p[PATH_MAX_LEN];
	subpath(p, path, key);
	if (!v) {
		*out = def;
		return 0;
	}
	if (!json_is_boolean(v))
		return jfail(c, p, "expected true or false");
	*out = json_is_true(v);
	return 0;
}

void scene_err_one_line(char *err, size_t err_size)
{
	for (size_t i = 0; i < err_size && err[i]; i++)
		if ((unsigned char)err[i] < 0x20 || err[i] == 0x7f)
			err[i] = ' ';
}

int jname(jp *c, const char *s, const char *p, char out[SCENE_NAME_MAX])
{
	size_t n = strlen(s);
	if (n == 0 || n >= SCENE_NAME_MAX)
		return jfail(c, p, "names must be 1 to %d characters", SCENE_NAME_MAX - 1);
	for (size_t i = 0; i < n; i++) {
		char ch = s[i];
		if (!((ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') || ch == '_' ||
		      ch == '-' || ch == '.'))
			return jfail(c, p, "name '%s' may only contain letters, digits, '_', '-' and '.'", s);
	}
	memcpy(out, s, n + 1);
	return 0;
}
