/* sweep.c — sweep files (request and resolved spec), their comparison, the plan and the folder layout (sweep.h). */
#include "taslab/sweep.h"

#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "taslab/run.h"
#include "taslab/sweep_keys.h"
#include "taslab/tl_fs.h"
#include "taslab/tl_hash.h"
#include "taslab/tl_json.h"
#include "taslab/tl_parse.h"
#include "toml_json.h"

/* ------------------------------------------------------------------ helpers */

typedef struct ctx {
	const char *file;
	char *err;
	size_t err_size;
} ctx;

#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static int bad(const ctx *c, const char *key, const char *fmt, ...)
{
	char why[512];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(why, sizeof why, fmt, ap);
	va_end(ap);
	return tl_error(c->err, c->err_size, TL_ERR_INPUT, "%s: \"%s\": %s", c->file, key, why);
}

/* A string value that fits `n` bytes (with its NUL) and holds no control characters. */
static int get_string(const ctx *c, const char *key, json_t *v, char *dst, size_t n)
{
	const char *s = json_string_value(v);
	if (!s)
		return bad(c, key, "must be a string");
	size_t len = strlen(s);
	if (len != json_string_length(v))
		return bad(c, key, "holds a NUL character");
	if (!len)
		return bad(c, key, "must not be empty");
	if (len >= n)
		return bad(c, key, "longer than %zu characters", n - 1);
	for (const unsigned char *p = (const unsigned char *)s; *p; p++)
		if (*p < 0x20 || *p == 0x7f)
			return bad(c, key, "holds a control character");
	memcpy(dst, s, len + 1);
	return TL_OK;
}

/* `s` for a message: control characters as '?', at most 64 characters (keys come from untrusted files). */
static const char *printable(const char *s, char *buf, size_t n)
{
	size_t i = 0;
	for (; s[i] && i + 1 < n && i < 64; i++)
		buf[i] = (unsigned char)s[i] < 0x20 || s[i] == 0x7f ? '?' : s[i];
	buf[i] = 0;
	return buf;
}

/* A name usable as one folder name: no '/', not "." or "..", not starting with '.'. */
static bool safe_name(const char *s)
{
	return *s && *s != '.' && !strchr(s, '/') && !strchr(s, '\\');
}

/* "dir of file" + rel, unless rel is absolute. */
static void relative_to(const char *file, const char *rel, char *out, size_t n)
{
	const char *slash = strrchr(file, '/');
	if (rel[0] == '/' || !slash)
		snprintf(out, n, "%s", rel);
	else
		snprintf(out, n, "%.*s/%s", (int)(slash - file), file, rel);
}

/* A list of strings (or one string when `one_ok`) into fixed rows. */
static int get_string_list(const ctx *c, const char *key, json_t *v, char *rows, size_t row_size, size_t max,
			   size_t *count, bool one_ok)
{
	*count = 0;
	if (one_ok && json_is_string(v)) {
		*count = 1;
		return get_string(c, key, v, rows, row_size);
	}
	if (!json_is_array(v))
		return bad(c, key, "must be a list of strings");
	if (!json_array_size(v))
		return bad(c, key, "must not be empty");
	if (json_array_size(v) > max)
		return bad(c, key, "at most %zu entries", max);
	size_t i;
	json_t *e;
	json_array_foreach(v, i, e) {
		int rc = get_string(c, key, e, rows + i * row_size, row_size);
		if (rc)
			return rc;
	}
	*count = json_array_size(v);
	return TL_OK;
}

static int get_number(const ctx *c, const char *key, json_t *v, double lo, double hi, double *out)
{
	if (!json_is_number(v) || !isfinite(json_number_value(v)) || json_number_value(v) < lo || json_number_value(v) > hi)
		return bad(c, key, "must be a number in [%g, %g]", lo, hi);
	*out = json_number_value(v);
	return TL_OK;
}

static int get_uint(const ctx *c, const char *key, json_t *v, json_int_t lo, json_int_t hi, uint32_t *out)
{
	if (!json_is_integer(v) || json_integer_value(v) < lo || json_integer_value(v) > hi)
		return bad(c, key, "must be a whole number in [%lld, %lld]", (long long)lo, (long long)hi);
	*out = (uint32_t)json_integer_value(v);
	return TL_OK;
}

static int get_bool(const ctx *c, const char *key, json_t *v, bool *out)
{
	if (!json_is_boolean(v))
		return bad(c, key, "must be true or false");
	*out = json_is_true(v);
	return TL_OK;
}

/* "WxH" (the command line's parser, tl_parse.h: nothing wraps) or [W, H]. */
static int get_size(const ctx *c, const char *key, json_t *v, uint32_t *w, uint32_t *h)
{
	char why[256];
	if (json_is_string(v) && !tl_parse_size(json_string_value(v), w, h, why, sizeof why))
		return TL_OK;
	if (json_is_array(v) && json_array_size(v) == 2) {
		int rc = get_uint(c, key, json_array_get(v, 0), 1, TL_SIZE_MAX, w);
		return rc ? rc : get_uint(c, key, json_array_get(v, 1), 1, TL_SIZE_MAX, h);
	}
	return bad(c, key, "must be \"WxH\" or [W, H] with each 1..%u", TL_SIZE_MAX);
}

/* "A:B", "A", ":B" or "A:", checked as `--frames` checks it (tl_parse.h): a range the resolver will accept. */
static int get_frames(const ctx *c, const char *key, json_t *v, char *dst, size_t n)
{
	int rc = get_string(c, key, v, dst, n);
	uint32_t a, b = TL_FRAME_MAX;
	bool given;
	char why[256], pv[80];
	if (!rc && tl_parse_frames(dst, &a, &b, &given, why, sizeof why))
		rc = bad(c, key, "'%s' %s", printable(dst, pv, sizeof pv), why);
	return rc;
}

/* ------------------------------------------------------------------ request */

/* A scene entry that is a path (a '/' or a file extension) rather than a built-in scene's name, as the command line's
 * --scenes tells them apart (cli_resolve_scene). */
static bool looks_like_path(const char *s)
{
	return strchr(s, '/') || strstr(s, ".json") || strstr(s, ".gltf") || strstr(s, ".glb");
}

/* One key's value from a file into the request, as the key's table line says (sweep_keys.h). */
static int read_key(const ctx *c, const sweep_key *k, json_t *v, sweep_request *r)
{
	char *f = (char *)r + k->offset, tmp[SWEEP_PATH_MAX];
	size_t *count = (size_t *)((char *)r + k->count_offset);
	int rc = TL_OK;
	r->set |= sweep_key_bit(k);
	switch (k->type) {
	case SWEEP_KEY_NAMES:
		if (k->all && json_is_string(v) && !strcmp(json_string_value(v), k->all)) {
			*(bool *)((char *)r + k->all_offset) = true;
			break;
		}
		rc = get_string_list(c, k->name, v, f, k->size, k->max, count, false);
		for (size_t i = 0; !rc && (k->flags & SWEEP_KEY_RELATIVE) && i < *count; i++) {
			char *e = f + i * k->size;
			if (looks_like_path(e)) {
				relative_to(c->file, e, tmp, sizeof tmp);
				snprintf(e, k->size, "%s", tmp);
			}
		}
		break;
	case SWEEP_KEY_NUMBERS:
	case SWEEP_KEY_WHOLES: {
		if (!json_is_array(v) || !json_array_size(v) || json_array_size(v) > k->max)
			return bad(c, k->name, "must be a list of 1..%zu numbers", k->max);
		size_t i;
		json_t *e;
		json_array_foreach(v, i, e) {
			if (k->type == SWEEP_KEY_NUMBERS)
				rc = get_number(c, k->name, e, k->lo, k->hi, (double *)f + i);
			else
				rc = get_uint(c, k->name, e, (json_int_t)k->lo, (json_int_t)k->hi, (uint32_t *)f + i);
			if (rc)
				break;
		}
		*count = json_array_size(v);
		break;
	}
	case SWEEP_KEY_STRING:
		if (!(k->flags & SWEEP_KEY_RELATIVE))
			rc = get_string(c, k->name, v, f, k->size);
		else if (!(rc = get_string(c, k->name, v, tmp, sizeof tmp)))
			relative_to(c->file, tmp, f, k->size);
		break;
	case SWEEP_KEY_FRAMES: rc = get_frames(c, k->name, v, f, k->size); break;
	case SWEEP_KEY_SIZE: rc = get_size(c, k->name, v, (uint32_t *)f, (uint32_t *)f + 1); break;
	case SWEEP_KEY_NUMBER: rc = get_number(c, k->name, v, k->lo, k->hi, (double *)f); break;
	case SWEEP_KEY_WHOLE: rc = get_uint(c, k->name, v, (json_int_t)k->lo, (json_int_t)k->hi, (uint32_t *)f); break;
	case SWEEP_KEY_BOOL: rc = get_bool(c, k->name, v, (bool *)f); break;
	default: rc = tl_error(c->err, c->err_size, TL_ERR_INTERNAL, "sweep key %s: bad table line", k->name);
	}
	return rc;
}

int sweep_request_read(const char *path, sweep_request *r, char *err, size_t err_size)
{
	memset(r, 0, sizeof *r);
	json_t *j = NULL;
	size_t plen = strlen(path);
	const bool toml = plen > 5 && !strcasecmp(path + plen - 5, ".toml");
	int rc = toml ? tl_toml_read(path, &j, err, err_size) : tl_json_read(path, &j, err, err_size);
	if (rc)
		return rc;
	ctx c = {path, err, err_size};
	if (!json_is_object(j)) {
		json_decref(j);
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: a sweep file is a JSON object or a TOML document (see 'taslab sweep --help')", path);
	}
	const char *key;
	json_t *v;
	json_object_foreach(j, key, v) {
		const sweep_key *k = sweep_key_find(key);
		if (k) {
			rc = read_key(&c, k, v, r);
		} else if (!strcmp(key, "taslab_sweep")) {
			rc = tl_error(err, err_size, TL_ERR_INPUT,
				      "%s: a resolved sweep.json, not a sweep file (give it as 'taslab sweep %s' to resume)", path,
				      path);
		} else {
			char pk[80], known[512];
			rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: unknown key \"%s\" (known: %s)", path,
				      printable(key, pk, sizeof pk), sweep_key_list(", ", known, sizeof known));
		}
		if (rc)
			break;
	}
	json_decref(j);
	return rc;
}

/* ------------------------------------------------------------------ spec */

static json_t *jnum(double v) { return isfinite(v) ? json_real(v) : json_null(); }

/* A scalar key's value (at `f`) as sweep.json holds it. NULL for a string that is not UTF-8. */
static json_t *key_json(const sweep_key *k, const char *f)
{
	switch (k->type) {
	case SWEEP_KEY_STRING:
	case SWEEP_KEY_FRAMES: return json_string(f);
	case SWEEP_KEY_SIZE: return json_pack("[i,i]", (int)((const uint32_t *)f)[0], (int)((const uint32_t *)f)[1]);
	case SWEEP_KEY_NUMBER: return json_real(*(const double *)f);
	case SWEEP_KEY_WHOLE: return json_integer(*(const uint32_t *)f);
	case SWEEP_KEY_BOOL: return json_boolean(*(const bool *)f);
	default: return NULL;
	}
}

int sweep_spec_write(const char *path, const sweep_spec *s, char *err, size_t err_size)
{
	json_t *scenes = json_array(), *variants = json_array();
	for (size_t i = 0; i < s->scene_count; i++) {
		const sweep_scene *sc = &s->scenes[i];
		json_t *cams = json_array();
		for (size_t k = 0; k < sc->camera_count; k++)
			json_array_append_new(cams, json_pack("{s:s, s:s}", "name", sc->cameras[k].name, "motion",
							      sc->cameras[k].motion));
		json_array_append_new(scenes, json_pack("{s:s, s:s, s:s, s:[i,i], s:f, s:o}", "name", sc->name, "path", sc->path,
							"digest", sc->digest, "frames", (int)sc->first, (int)sc->end, "fps",
							sc->fps, "cameras", cams));
	}
	for (size_t i = 0; i < s->variant_count; i++) {
		const sweep_variant *v = &s->variants[i];
		json_array_append_new(variants, json_pack("{s:s, s:s, s:s, s:o, s:o}", "variant", v->variant, "id", v->id,
							  "method", v->method, "T", jnum(v->T), "period",
							  v->period ? json_integer(v->period) : json_null()));
	}
	json_t *j = json_pack("{s:i, s:o, s:o, s:s, s:s, s:s}", "taslab_sweep", 1, "scenes", scenes, "variants", variants,
			      "display_transform", s->display_transform, "colour_digest", s->colour_digest, "build_digest",
			      s->build_digest);
	/* the settings kept as given: one entry per SWEEP_KEY_SPEC key of the table (sweep_keys.h) */
	size_t nkeys;
	const sweep_key *keys = sweep_keys(&nkeys);
	for (size_t i = 0; j && i < nkeys; i++)
		if ((keys[i].flags & SWEEP_KEY_SPEC) &&
		    json_object_set_new(j, keys[i].name, key_json(&keys[i], (const char *)s + keys[i].spec_offset))) {
			json_decref(j); /* a string that is not UTF-8: written as nothing, as json_pack refuses it */
			j = NULL;
		}
	int rc = tl_json_write(path, j, err, err_size);
	json_decref(j);
	return rc;
}

bool sweep_file_is_spec(const char *path)
{
	json_t *j = NULL;
	char err[256];
	if (tl_json_read(path, &j, err, sizeof err))
		return false;
	bool spec = json_is_object(j) && json_object_get(j, "taslab_sweep");
	json_decref(j);
	return spec;
}

/* Keys of an object must all be in `known` (NULL-terminated). */
static int only_keys(const ctx *c, const char *where, json_t *o, const char *const *known)
{
	if (!json_is_object(o))
		return bad(c, where, "must be an object");
	const char *key;
	json_t *v;
	json_object_foreach(o, key, v) {
		size_t i = 0;
		while (known[i] && strcmp(known[i], key))
			i++;
		char pk[80];
		if (!known[i])
			return bad(c, where, "unknown key \"%s\"", printable(key, pk, sizeof pk));
	}
	return TL_OK;
}

/* A string that may be empty (settings "as given"). */
static int get_string_or_empty(const ctx *c, const char *key, json_t *v, char *dst, size_t n)
{
	if (json_is_string(v) && !json_string_length(v)) {
		dst[0] = 0;
		return TL_OK;
	}
	return get_string(c, key, v, dst, n);
}

static int read_variant(const ctx *c, json_t *o, sweep_variant *v)
{
	static const char *const keys[] = {"variant", "id", "method", "T", "period", NULL};
	int rc = only_keys(c, "variants", o, keys);
	json_t *T = json_object_get(o, "T"), *N = json_object_get(o, "period");
	if (!rc)
		rc = get_string(c, "variants.variant", json_object_get(o, "variant"), v->variant, sizeof v->variant);
	if (!rc)
		rc = get_string(c, "variants.id", json_object_get(o, "id"), v->id, sizeof v->id);
	if (!rc)
		rc = get_string(c, "variants.method", json_object_get(o, "method"), v->method, sizeof v->method);
	if (!rc && !safe_name(v->id))
		rc = bad(c, "variants.id", "'%s' is not a folder name", v->id);
	if (!rc && !json_is_null(T))
		rc = get_number(c, "variants.T", T, 1e-6, 255, &v->T);
	else if (!rc)
		v->T = NAN;
	if (!rc && !json_is_null(N))
		rc = get_uint(c, "variants.period", N, 1, 1024, &v->period);
	return rc;
}

static int read_scene(const ctx *c, json_t *o, sweep_scene *sc)
{
	static const char *const keys[] = {"name", "path", "digest", "frames", "fps", "cameras", NULL};
	int rc = only_keys(c, "scenes", o, keys);
	json_t *fr = json_object_get(o, "frames"), *cams = json_object_get(o, "cameras");
	if (!rc)
		rc = get_string(c, "scenes.name", json_object_get(o, "name"), sc->name, sizeof sc->name);
	if (!rc && !safe_name(sc->name))
		rc = bad(c, "scenes.name", "'%s' is not a folder name", sc->name);
	if (!rc)
		rc = get_string(c, "scenes.path", json_object_get(o, "path"), sc->path, sizeof sc->path);
	/* a sweep.json made before digests were recorded has none: "" (it resumes only as a different sweep) */
	if (!rc && json_object_get(o, "digest"))
		rc = get_string_or_empty(c, "scenes.digest", json_object_get(o, "digest"), sc->digest, sizeof sc->digest);
	if (!rc && (json_array_size(fr) != 2 || get_uint(c, "scenes.frames", json_array_get(fr, 0), 0, TL_FRAME_MAX - 1, &sc->first) ||
		    get_uint(c, "scenes.frames", json_array_get(fr, 1), 1, TL_FRAME_MAX, &sc->end) || sc->end <= sc->first))
		rc = bad(c, "scenes.frames", "must be [first, end] with first < end");
	if (!rc)
		rc = get_number(c, "scenes.fps", json_object_get(o, "fps"), 1, 1000, &sc->fps);
	if (!rc && (!json_is_array(cams) || !json_array_size(cams) || json_array_size(cams) > SWEEP_MAX_CAMERAS))
		rc = bad(c, "scenes.cameras", "must be a list of 1..%d camera paths", SWEEP_MAX_CAMERAS);
	static const char *const cam_keys[] = {"name", "motion", NULL};
	for (size_t k = 0; !rc && k < json_array_size(cams); k++) {
		json_t *e = json_array_get(cams, k);
		sweep_camera *cam = &sc->cameras[k];
		if (!(rc = only_keys(c, "scenes.cameras", e, cam_keys)) &&
		    !(rc = get_string(c, "scenes.cameras.name", json_object_get(e, "name"), cam->name, sizeof cam->name)) &&
		    !(rc = get_string(c, "scenes.cameras.motion", json_object_get(e, "motion"), cam->motion,
				      sizeof cam->motion))) {
			if (!safe_name(cam->name))
				rc = bad(c, "scenes.cameras.name", "'%s' is not a folder name", cam->name);
			else if (strcmp(cam->motion, "stationary") && strcmp(cam->motion, "moving"))
				rc = bad(c, "scenes.cameras.motion", "must be stationary or moving");
			for (size_t q = 0; !rc && q < k; q++)
				if (!strcmp(sc->cameras[q].name, cam->name))
					rc = bad(c, "scenes.cameras", "'%s' is listed twice", cam->name);
		}
		sc->camera_count = k + 1;
	}
	return rc;
}

/* A setting kept as given (a SWEEP_KEY_SPEC key) from sweep.json into `f`, its field in the spec. */
static int read_spec_key(const ctx *c, const sweep_key *k, json_t *v, char *f)
{
	/* a key added after the first sweeps: absent in the older sweep.json files, and a number 0 when not given (as in
	 * the request), so a sweep without it resumes as the same sweep */
	if ((k->flags & SWEEP_KEY_OPTIONAL) &&
	    (!v || ((k->type == SWEEP_KEY_NUMBER || k->type == SWEEP_KEY_WHOLE) && json_is_number(v) &&
		    json_number_value(v) == 0))) {
		memset(f, 0, sweep_key_value_size(k));
		return TL_OK;
	}
	switch (k->type) {
	case SWEEP_KEY_STRING:
	case SWEEP_KEY_FRAMES:
		return k->flags & SWEEP_KEY_EMPTY_OK ? get_string_or_empty(c, k->name, v, f, k->size)
						     : get_string(c, k->name, v, f, k->size);
	case SWEEP_KEY_SIZE: return get_size(c, k->name, v, (uint32_t *)f, (uint32_t *)f + 1);
	case SWEEP_KEY_NUMBER: return get_number(c, k->name, v, k->lo, k->hi, (double *)f);
	case SWEEP_KEY_WHOLE: return get_uint(c, k->name, v, (json_int_t)k->lo, (json_int_t)k->hi, (uint32_t *)f);
	case SWEEP_KEY_BOOL: return get_bool(c, k->name, v, (bool *)f);
	default: return tl_error(c->err, c->err_size, TL_ERR_INTERNAL, "sweep key %s: not one sweep.json holds", k->name);
	}
}

int sweep_spec_read(const char *path, sweep_spec *s, char *err, size_t err_size)
{
	memset(s, 0, sizeof *s);
	json_t *j = NULL;
	int rc = tl_json_read(path, &j, err, err_size);
	if (rc)
		return rc;
	ctx c = {path, err, err_size};
	/* the spec's own keys, then the settings kept as given (the SWEEP_KEY_SPEC keys of sweep_keys.h) */
	const char *keys[40] = {"taslab_sweep", "scenes", "variants", "display_transform", "colour_digest", "build_digest"};
	size_t nkeys, n = 6;
	const sweep_key *table = sweep_keys(&nkeys);
	for (size_t i = 0; i < nkeys && n + 1 < sizeof keys / sizeof keys[0]; i++)
		if (table[i].flags & SWEEP_KEY_SPEC)
			keys[n++] = table[i].name;
	json_t *scenes = json_object_get(j, "scenes"), *variants = json_object_get(j, "variants");
	if (!json_is_object(j) || json_integer_value(json_object_get(j, "taslab_sweep")) != 1)
		rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: not a taslab sweep.json (no \"taslab_sweep\": 1)", path);
	if (!rc)
		rc = only_keys(&c, "sweep.json", j, keys);
	if (!rc && (!json_is_array(scenes) || !json_array_size(scenes) || json_array_size(scenes) > SWEEP_MAX_SCENES))
		rc = bad(&c, "scenes", "must be a list of 1..%d scenes", SWEEP_MAX_SCENES);
	for (size_t i = 0; !rc && i < json_array_size(scenes); i++) {
		rc = read_scene(&c, json_array_get(scenes, i), &s->scenes[i]);
		for (size_t q = 0; !rc && q < i; q++)
			if (!strcmp(s->scenes[q].name, s->scenes[i].name))
				rc = bad(&c, "scenes", "'%s' is listed twice", s->scenes[i].name);
		s->scene_count = i + 1;
	}
	if (!rc && (!json_is_array(variants) || !json_array_size(variants) || json_array_size(variants) > SWEEP_MAX_VARIANTS))
		rc = bad(&c, "variants", "must be a list of 1..%d variants", SWEEP_MAX_VARIANTS);
	bool has_ref = false;
	for (size_t i = 0; !rc && i < json_array_size(variants); i++) {
		rc = read_variant(&c, json_array_get(variants, i), &s->variants[i]);
		for (size_t q = 0; !rc && q < i; q++)
			if (!strcmp(s->variants[q].id, s->variants[i].id) || !strcmp(s->variants[q].variant, s->variants[i].variant))
				rc = bad(&c, "variants", "'%s' is listed twice", s->variants[i].variant);
		has_ref |= !rc && !strcmp(s->variants[i].id, "ref");
		s->variant_count = i + 1;
	}
	if (!rc && !has_ref)
		rc = bad(&c, "variants", "no ref variant (every run is compared with the ref run of its scene and path)");
	for (size_t i = 0; !rc && i < nkeys; i++)
		if (table[i].flags & SWEEP_KEY_SPEC)
			rc = read_spec_key(&c, &table[i], json_object_get(j, table[i].name), (char *)s + table[i].spec_offset);
	bool baseline_found = !rc && !strcmp(s->baseline, "auto");
	for (size_t i = 0; !rc && i < s->variant_count; i++)
		baseline_found |= !strcmp(s->variants[i].variant, s->baseline);
	if (!rc && !baseline_found)
		rc = bad(&c, "baseline", "'%s' is not one of the variants", s->baseline);
	if (!rc)
		rc = get_string(&c, "display_transform", json_object_get(j, "display_transform"), s->display_transform,
				sizeof s->display_transform);
	if (!rc && json_object_get(j, "colour_digest"))
		rc = get_string_or_empty(&c, "colour_digest", json_object_get(j, "colour_digest"), s->colour_digest,
					 sizeof s->colour_digest);
	/* a sweep.json made before builds were recorded has none: "" (it resumes only as a different sweep) */
	if (!rc && json_object_get(j, "build_digest"))
		rc = get_string_or_empty(&c, "build_digest", json_object_get(j, "build_digest"), s->build_digest,
					 sizeof s->build_digest);
	json_decref(j);
	return rc;
}

#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static int differ(char *what, size_t n, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(what, n, fmt, ap);
	va_end(ap);
	return 1;
}

static bool same_num(double a, double b) { return (isnan(a) && isnan(b)) || a == b; }

/* A setting's value in words for sweep_spec_compare's message (strings quoted, so "" shows). */
static const char *key_text(const sweep_key *k, const char *f, char *out, size_t n)
{
	switch (k->type) {
	case SWEEP_KEY_STRING:
	case SWEEP_KEY_FRAMES: snprintf(out, n, "'%s'", f); break;
	case SWEEP_KEY_SIZE: snprintf(out, n, "%ux%u", ((const uint32_t *)f)[0], ((const uint32_t *)f)[1]); break;
	case SWEEP_KEY_NUMBER: snprintf(out, n, "%g", *(const double *)f); break;
	case SWEEP_KEY_WHOLE: snprintf(out, n, "%u", *(const uint32_t *)f); break;
	case SWEEP_KEY_BOOL: snprintf(out, n, "%s", *(const bool *)f ? "on" : "off"); break;
	default: snprintf(out, n, "?");
	}
	return out;
}

/* Whether two values of a setting are the same: numbers exactly, the rest by their bytes up to a string's end. */
static bool key_same(const sweep_key *k, const char *a, const char *b)
{
	switch (k->type) {
	case SWEEP_KEY_STRING:
	case SWEEP_KEY_FRAMES: return !strcmp(a, b);
	case SWEEP_KEY_NUMBER: return *(const double *)a == *(const double *)b;
	case SWEEP_KEY_BOOL: return *(const bool *)a == *(const bool *)b;
	default: return !memcmp(a, b, sweep_key_value_size(k));
	}
}

int sweep_spec_compare(const sweep_spec *a, const sweep_spec *b, char *what, size_t n)
{
	if (a->scene_count != b->scene_count)
		return differ(what, n, "%zu scenes vs %zu", a->scene_count, b->scene_count);
	for (size_t i = 0; i < a->scene_count; i++) {
		const sweep_scene *x = &a->scenes[i], *y = &b->scenes[i];
		if (strcmp(x->name, y->name) || strcmp(x->path, y->path))
			return differ(what, n, "scene %s (%s) vs %s (%s)", x->name, x->path, y->name, y->path);
		if (x->first != y->first || x->end != y->end)
			return differ(what, n, "%s: frames %u:%u vs %u:%u", x->name, x->first, x->end, y->first, y->end);
		if (strcmp(x->digest, y->digest)) /* the scene file or one of its assets changed (issue 31.4) */
			return differ(what, n, "%s: the scene file or its assets changed (content digest %s vs %s)", x->name,
				      x->digest[0] ? x->digest : "none", y->digest[0] ? y->digest : "none");
		if (x->fps != y->fps)
			return differ(what, n, "%s: fps %g vs %g", x->name, x->fps, y->fps);
		if (x->camera_count != y->camera_count)
			return differ(what, n, "%s: %zu camera paths vs %zu", x->name, x->camera_count, y->camera_count);
		for (size_t k = 0; k < x->camera_count; k++)
			if (strcmp(x->cameras[k].name, y->cameras[k].name))
				return differ(what, n, "%s: camera %s vs %s", x->name, x->cameras[k].name, y->cameras[k].name);
	}
	if (a->variant_count != b->variant_count)
		return differ(what, n, "%zu variants vs %zu", a->variant_count, b->variant_count);
	for (size_t i = 0; i < a->variant_count; i++)
		if (strcmp(a->variants[i].variant, b->variants[i].variant) || strcmp(a->variants[i].id, b->variants[i].id) ||
		    !same_num(a->variants[i].T, b->variants[i].T) || a->variants[i].period != b->variants[i].period)
			return differ(what, n, "variant %s vs %s", a->variants[i].variant, b->variants[i].variant);
	/* the settings kept as given: any difference is another sweep ("ppd 40 vs 67.0206", "truth on vs off") */
	size_t nkeys;
	const sweep_key *keys = sweep_keys(&nkeys);
	for (size_t i = 0; i < nkeys; i++) {
		const char *x = (const char *)a + keys[i].spec_offset, *y = (const char *)b + keys[i].spec_offset;
		char tx[SWEEP_PATH_MAX + 8], ty[SWEEP_PATH_MAX + 8];
		if ((keys[i].flags & SWEEP_KEY_SPEC) && !key_same(&keys[i], x, y))
			return differ(what, n, "%s %s vs %s", keys[i].name, key_text(&keys[i], x, tx, sizeof tx),
				      key_text(&keys[i], y, ty, sizeof ty));
	}
	if (strcmp(a->display_transform, b->display_transform))
		return differ(what, n, "display transform %s vs %s", a->display_transform, b->display_transform);
	if (strcmp(a->colour_digest, b->colour_digest))
		return differ(what, n, "the OpenColorIO config or one of its LUTs changed (content digest %s vs %s)",
			      a->colour_digest[0] ? a->colour_digest : "none", b->colour_digest[0] ? b->colour_digest : "none");
	if (strcmp(a->build_digest, b->build_digest))
		return differ(what, n, "another taslab build (build digest %s vs %s)",
			      a->build_digest[0] ? a->build_digest : "none", b->build_digest[0] ? b->build_digest : "none");
	return 0;
}

int sweep_build_check(const sweep_spec *s, const char *path, char *err, size_t err_size)
{
	const char *mine = tl_build_digest();
	if (!mine[0]) /* no digest of this build: it cannot be told apart from any other */
		return tl_error(err, err_size, TL_ERR_INPUT,
				"%s: this taslab's build digest is unknown (/proc/self/exe unreadable), so it cannot resume a sweep",
				path);
	if (!strcmp(s->build_digest, mine))
		return TL_OK;
	if (!s->build_digest[0])
		return tl_error(err, err_size, TL_ERR_INPUT,
				"%s was made before taslab recorded builds: rebuild its report with 'taslab report', or sweep again "
				"with another --out",
				path);
	return tl_error(err, err_size, TL_ERR_INPUT,
			"%s was started by another taslab build (build digest %s, this one's %s): resume it with that build, "
			"or start the sweep again with another --out",
			path, s->build_digest, mine);
}

/* ------------------------------------------------------------------ plan */

size_t sweep_run_count(const sweep_spec *s)
{
	size_t n = 0;
	for (size_t i = 0; i < s->scene_count; i++)
		n += s->scenes[i].camera_count * s->variant_count;
	return n;
}

static size_t ref_variant(const sweep_spec *s)
{
	for (size_t v = 0; v < s->variant_count; v++)
		if (!strcmp(s->variants[v].id, "ref"))
			return v;
	return 0;
}

int sweep_run_at(const sweep_spec *s, size_t index, sweep_run *out)
{
	memset(out, 0, sizeof *out);
	size_t ref = ref_variant(s), cams = 0;
	for (size_t i = 0; i < s->scene_count; i++)
		cams += s->scenes[i].camera_count;
	/* First the ref run of every scene and camera (scene-major): everything else is compared with them. */
	size_t k = 0;
	for (size_t i = 0; i < s->scene_count; i++)
		for (size_t c = 0; c < s->scenes[i].camera_count; c++, k++)
			if (k == index) {
				*out = (sweep_run){.index = index, .scene = i, .camera = c, .variant = ref, .ref_index = k,
						   .is_ref = true};
				return TL_OK;
			}
	/* Then every other variant, scene-major, camera, variant order. */
	size_t j = cams, pair = 0;
	for (size_t i = 0; i < s->scene_count; i++)
		for (size_t c = 0; c < s->scenes[i].camera_count; c++, pair++)
			for (size_t v = 0; v < s->variant_count; v++) {
				if (v == ref)
					continue;
				if (j++ == index) {
					*out = (sweep_run){.index = index, .scene = i, .camera = c, .variant = v,
							   .ref_index = pair, .is_ref = false};
					return TL_OK;
				}
			}
	return TL_ERR_ARG;
}

void sweep_run_path(const sweep_spec *s, const char *dir, const sweep_run *r, sweep_path_kind kind, char *out,
		    size_t out_size)
{
	static const char *const top[] = {"runs", "clips", "metrics", "logs"};
	static const char *const ext[] = {"", ".webm", "", ".log"};
	const sweep_scene *sc = &s->scenes[r->scene];
	snprintf(out, out_size, "%s/%s/%s/%s/%s%s", dir, top[kind], sc->name, sc->cameras[r->camera].name,
		 s->variants[r->variant].id, ext[kind]);
}

void sweep_run_status(const sweep_spec *s, const char *dir, const sweep_run *r, sweep_status *st)
{
	char p[TL_PATH_MAX], q[TL_PATH_MAX];
	sweep_run_path(s, dir, r, SWEEP_PATH_RUN, p, sizeof p);
	snprintf(q, sizeof q, "%s/manifest.json", p);
	st->run = tl_is_file(q);
	sweep_run_path(s, dir, r, SWEEP_PATH_CLIP, p, sizeof p);
	st->clip = tl_is_file(p);
	/* The ref run is the reference of its scene and path: there is nothing to compare it with. */
	sweep_run_path(s, dir, r, SWEEP_PATH_METRICS, p, sizeof p);
	snprintf(q, sizeof q, "%s/summary.json", p);
	st->metrics = r->is_ref ? st->run : tl_is_file(q);
	st->damaged = false;
}

void sweep_run_status_checked(const sweep_spec *s, const char *dir, const sweep_run *r, sweep_status *st, char *why,
			      size_t why_size)
{
	sweep_run_status(s, dir, r, st);
	if (why_size)
		why[0] = 0;
	if (!st->run)
		return;
	char p[TL_PATH_MAX];
	run_manifest m;
	sweep_run_path(s, dir, r, SWEEP_PATH_RUN, p, sizeof p);
	const sweep_scene *sc = &s->scenes[r->scene];
	const sweep_variant *v = &s->variants[r->variant];
	int rc = run_check(p, &m, why, why_size);
	if (!rc && (strcmp(m.variant, v->variant) || strcmp(m.camera, sc->cameras[r->camera].name)))
		rc = tl_error(why, why_size, TL_ERR_INPUT, "%s: the manifest is of %s on '%s', the sweep's run is %s on '%s'", p,
			      m.variant, m.camera, v->variant, sc->cameras[r->camera].name);
	/* made from other inputs than the sweep's: the scene, an asset, the config or a LUT changed in between (31.4) */
	if (!rc && (strcmp(m.scene_digest, sc->digest) || strcmp(m.colour_digest, s->colour_digest)))
		rc = tl_error(why, why_size, TL_ERR_INPUT,
			      "%s: made from other inputs (scene digest %s, colour digest %s; the sweep's: %s, %s)", p,
			      m.scene_digest[0] ? m.scene_digest : "none", m.colour_digest[0] ? m.colour_digest : "none",
			      sc->digest[0] ? sc->digest : "none", s->colour_digest[0] ? s->colour_digest : "none");
	/* rendered by another build than the sweep's: its frames need not be those this build makes */
	if (!rc && strcmp(m.build_digest, s->build_digest))
		rc = tl_error(why, why_size, TL_ERR_INPUT,
			      "%s: rendered by another taslab build (build digest %s; the sweep's: %s)", p,
			      m.build_digest[0] ? m.build_digest : "none", s->build_digest[0] ? s->build_digest : "none");
	if (!rc && (m.first_frame != sc->first || m.last_frame + 1 != sc->end || m.width != s->width || m.height != s->height))
		rc = tl_error(why, why_size, TL_ERR_INPUT, "%s: frames %u..%u at %ux%u, the sweep's are %u..%u at %ux%u", p,
			      m.first_frame, m.last_frame, m.width, m.height, sc->first, sc->end - 1, s->width, s->height);
	if (rc) {
		st->damaged = true;
		st->run = st->clip = st->metrics = false;
	}
}

bool sweep_run_complete(const sweep_spec *s, const char *dir, size_t index)
{
	sweep_run r;
	sweep_status st;
	char why[16];
	if (sweep_run_at(s, index, &r))
		return false;
	sweep_run_status_checked(s, dir, &r, &st, why, sizeof why);
	return st.run && st.clip && st.metrics;
}
