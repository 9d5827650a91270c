/* scene.c — scene files (JSON, schema in scenes/README.md) and evaluation as a pure function of
 * time (DESIGN section 2). Parsing is strict: unknown keys, wrong types and out-of-range values are
 * errors that name the file and the JSON path, so a typo never silently changes an experiment. */
#include "taslab/scene.h"

#include <ctype.h>
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gltf.h"
#include "procgen.h"

#define PATH_MAX_LEN 256

typedef struct jp {
	const char *file;
	char *err;
	size_t err_size;
} jp;

#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static int jfail(jp *c, const char *path, const char *fmt, ...)
{
	char msg[512];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(msg, sizeof msg, fmt, ap);
	va_end(ap);
	snprintf(c->err, c->err_size, "%s: %s: %s", c->file, path, msg);
	return SCENE_ERR_SCHEMA;
}

static void subpath(char *out, const char *path, const char *key)
{
	snprintf(out, PATH_MAX_LEN, "%s.%s", path, key);
}

static void subidx(char *out, const char *path, size_t i)
{
	snprintf(out, PATH_MAX_LEN, "%s[%zu]", path, i);
}

/* Rejects keys not in `allowed` (NULL-terminated). */
static int jkeys(jp *c, json_t *obj, const char *path, const char *const *allowed)
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

static int jnum(jp *c, json_t *obj, const char *key, const char *path, float def, float lo, float hi, float *out)
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

static int jarr_floats(jp *c, json_t *v, const char *p, int n, float *out)
{
	if (!json_is_array(v) || (int)json_array_size(v) != n)
		return jfail(c, p, "expected an array of %d numbers", n);
	for (int i = 0; i < n; i++) {
		json_t *e = json_array_get(v, (size_t)i);
		if (!json_is_number(e) || !isfinite(json_number_value(e)))
			return jfail(c, p, "element %d is not a finite number", i);
		out[i] = (float)json_number_value(e);
	}
	return 0;
}

static int jvec(jp *c, json_t *obj, const char *key, const char *path, int n, const float *def, float *out)
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

static int jv3(jp *c, json_t *obj, const char *key, const char *path, tlm_vec3 def, int required, tlm_vec3 *out)
{
	float d[3] = {def.x, def.y, def.z}, o[3];
	int rc = jvec(c, obj, key, path, 3, required ? NULL : d, o);
	if (!rc)
		*out = tlm_v3(o[0], o[1], o[2]);
	return rc;
}

static int jstr(jp *c, json_t *obj, const char *key, const char *path, const char *def, const char **out)
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

static int jbool(jp *c, json_t *obj, const char *key, const char *path, bool def, bool *out)
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

static int jname(jp *c, const char *s, const char *p, char out[SCENE_NAME_MAX])
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

/* ------------------------------------------------------------------ transforms and motion */

static int parse_rotation(jp *c, json_t *obj, const char *path, tlm_quat *out)
{
	json_t *q = json_object_get(obj, "rotation");
	json_t *e = json_object_get(obj, "rotation_deg");
	char p[PATH_MAX_LEN];
	if (q && e) {
		subpath(p, path, "rotation");
		return jfail(c, p, "give either rotation (quaternion) or rotation_deg (Euler), not both");
	}
	float v[4];
	if (q) {
		subpath(p, path, "rotation");
		if (jarr_floats(c, q, p, 4, v))
			return SCENE_ERR_SCHEMA;
		*out = tlm_quat_normalize((tlm_quat){v[0], v[1], v[2], v[3]});
	} else if (e) {
		subpath(p, path, "rotation_deg");
		if (jarr_floats(c, e, p, 3, v))
			return SCENE_ERR_SCHEMA;
		*out = tlm_quat_euler_deg(v[0], v[1], v[2]);
	} else {
		*out = tlm_quat_identity();
	}
	return 0;
}

static int parse_trs(jp *c, json_t *obj, const char *path, tlm_trs *trs)
{
	*trs = tlm_trs_identity();
	if (jv3(c, obj, "translation", path, tlm_v3(0, 0, 0), 0, &trs->t) || parse_rotation(c, obj, path, &trs->r))
		return SCENE_ERR_SCHEMA;
	json_t *s = json_object_get(obj, "scale");
	if (json_is_number(s)) {
		float k = (float)json_number_value(s);
		trs->s = tlm_v3(k, k, k);
	} else if (jv3(c, obj, "scale", path, tlm_v3(1, 1, 1), 0, &trs->s)) {
		return SCENE_ERR_SCHEMA;
	}
	return 0;
}

static int parse_track(jp *c, json_t *m, const char *path, const char *key, anim_path ap, anim_interp interp,
		       json_t *times, anim_track *tr)
{
	json_t *vals = json_object_get(m, key);
	char p[PATH_MAX_LEN];
	subpath(p, path, key);
	size_t n = json_array_size(times);
	int comps = anim_path_components(ap);
	int euler = !strcmp(key, "rotation_deg");
	int in_comps = euler ? 3 : comps;
	size_t per_key = interp == ANIM_INTERP_CUBICSPLINE ? 3 : 1;
	if (!json_is_array(vals) || json_array_size(vals) != n * per_key)
		return jfail(c, p, "expected %zu values (%s%zu keys)", n * per_key,
			     per_key == 3 ? "in-tangent, value, out-tangent for each of " : "one for each of ", n);
	tr->path = ap;
	tr->interp = interp;
	tr->key_count = n;
	tr->times = calloc(n, sizeof *tr->times);
	tr->values = calloc(n * per_key * (size_t)comps, sizeof *tr->values);
	if (!tr->times || !tr->values)
		return SCENE_ERR_NOMEM;
	for (size_t i = 0; i < n; i++)
		tr->times[i] = (float)json_number_value(json_array_get(times, i));
	for (size_t i = 0; i < n * per_key; i++) {
		char pi[PATH_MAX_LEN];
		float v[4];
		subidx(pi, p, i);
		if (jarr_floats(c, json_array_get(vals, i), pi, in_comps, v))
			return SCENE_ERR_SCHEMA;
		if (euler) {
			tlm_quat q = tlm_quat_euler_deg(v[0], v[1], v[2]);
			v[0] = q.x, v[1] = q.y, v[2] = q.z, v[3] = q.w;
		}
		memcpy(&tr->values[i * (size_t)comps], v, (size_t)comps * sizeof *v);
	}
	char why[200];
	if (anim_track_validate(tr, why, sizeof why))
		return jfail(c, p, "%s", why);
	return 0;
}

static int parse_motion(jp *c, json_t *m, const char *path, anim_motion *out)
{
	const char *type;
	memset(out, 0, sizeof *out);
	if (!json_is_object(m))
		return jfail(c, path, "expected an object with a \"type\"");
	if (jstr(c, m, "type", path, NULL, &type))
		return SCENE_ERR_SCHEMA;
	float big = 1e6f;
	if (jnum(c, m, "start_s", path, 0, 0, big, &out->start_s))
		return SCENE_ERR_SCHEMA;
	if (!strcmp(type, "spin")) {
		static const char *const k[] = {"type", "axis", "rate_deg_s", "phase_deg", "start_s", NULL};
		out->kind = ANIM_MOTION_SPIN;
		if (jkeys(c, m, path, k) || jv3(c, m, "axis", path, tlm_v3(0, 1, 0), 0, &out->axis) ||
		    jnum(c, m, "rate_deg_s", path, 90, -big, big, &out->rate_deg_s) ||
		    jnum(c, m, "phase_deg", path, 0, -big, big, &out->phase_deg))
			return SCENE_ERR_SCHEMA;
	} else if (!strcmp(type, "orbit")) {
		static const char *const k[] = {"type", "axis", "center", "radius", "rate_deg_s", "phase_deg", "start_s", NULL};
		out->kind = ANIM_MOTION_ORBIT;
		if (jkeys(c, m, path, k) || jv3(c, m, "axis", path, tlm_v3(0, 1, 0), 0, &out->axis) ||
		    jv3(c, m, "center", path, tlm_v3(0, 0, 0), 0, &out->center) ||
		    jnum(c, m, "radius", path, 1, 0, big, &out->radius) ||
		    jnum(c, m, "rate_deg_s", path, 30, -big, big, &out->rate_deg_s) ||
		    jnum(c, m, "phase_deg", path, 0, -big, big, &out->phase_deg))
			return SCENE_ERR_SCHEMA;
	} else if (!strcmp(type, "bob")) {
		static const char *const k[] = {"type", "amplitude", "frequency_hz", "phase_deg", "start_s", NULL};
		out->kind = ANIM_MOTION_BOB;
		if (jkeys(c, m, path, k) || jv3(c, m, "amplitude", path, tlm_v3(0, 0.5f, 0), 0, &out->amplitude) ||
		    jnum(c, m, "frequency_hz", path, 0.5f, 0, 1000, &out->frequency_hz) ||
		    jnum(c, m, "phase_deg", path, 0, -big, big, &out->phase_deg))
			return SCENE_ERR_SCHEMA;
	} else if (!strcmp(type, "fall")) {
		static const char *const k[] = {"type", "velocity", "gravity", "floor_y", "restitution", "start_s", NULL};
		out->kind = ANIM_MOTION_FALL;
		if (jkeys(c, m, path, k) || jv3(c, m, "velocity", path, tlm_v3(0, 0, 0), 0, &out->velocity) ||
		    jnum(c, m, "gravity", path, 9.81f, 0.01f, 1000, &out->gravity) ||
		    jnum(c, m, "floor_y", path, 0, -big, big, &out->floor_y) ||
		    jnum(c, m, "restitution", path, 0.5f, 0, 0.99f, &out->restitution))
			return SCENE_ERR_SCHEMA;
	} else if (!strcmp(type, "keyframes")) {
		static const char *const k[] = {"type", "interpolation", "times", "translation", "rotation",
						"rotation_deg", "scale", "start_s", NULL};
		const char *is;
		out->kind = ANIM_MOTION_TRACKS;
		if (jkeys(c, m, path, k) || jstr(c, m, "interpolation", path, "LINEAR", &is))
			return SCENE_ERR_SCHEMA;
		anim_interp interp = anim_interp_from_string(is);
		char p[PATH_MAX_LEN];
		if (!interp) {
			subpath(p, path, "interpolation");
			return jfail(c, p, "unknown interpolation '%s' (use STEP, LINEAR or CUBICSPLINE)", is);
		}
		json_t *times = json_object_get(m, "times");
		subpath(p, path, "times");
		if (!json_is_array(times) || json_array_size(times) == 0)
			return jfail(c, p, "expected a non-empty array of key times in seconds");
		for (size_t i = 0; i < json_array_size(times); i++)
			if (!json_is_number(json_array_get(times, i)))
				return jfail(c, p, "element %zu is not a number", i);
		if (json_object_get(m, "rotation") && json_object_get(m, "rotation_deg"))
			return jfail(c, path, "give either rotation or rotation_deg keys, not both");
		static const struct {
			const char *key;
			anim_path path;
		} chans[] = {{"translation", ANIM_PATH_TRANSLATION},
			     {"rotation", ANIM_PATH_ROTATION},
			     {"rotation_deg", ANIM_PATH_ROTATION},
			     {"scale", ANIM_PATH_SCALE}};
		out->tracks = calloc(4, sizeof *out->tracks);
		if (!out->tracks)
			return SCENE_ERR_NOMEM;
		for (size_t i = 0; i < 4; i++) {
			if (!json_object_get(m, chans[i].key))
				continue;
			int rc = parse_track(c, m, path, chans[i].key, chans[i].path, interp, times,
					     &out->tracks[out->track_count++]);
			if (rc)
				return rc;
		}
		if (out->track_count == 0)
			return jfail(c, path, "keyframes need at least one of translation, rotation, rotation_deg, scale");
	} else {
		char p[PATH_MAX_LEN];
		subpath(p, path, "type");
		return jfail(c, p, "unknown motion type '%s' (use spin, orbit, bob, fall or keyframes)", type);
	}
	return 0;
}

static int parse_motions(jp *c, json_t *obj, const char *path, size_t *count, anim_motion **out)
{
	json_t *a = json_object_get(obj, "animation");
	char p[PATH_MAX_LEN];
	subpath(p, path, "animation");
	*count = 0;
	*out = NULL;
	if (!a)
		return 0;
	if (!json_is_array(a))
		return jfail(c, p, "expected an array of motions");
	*out = calloc(json_array_size(a) + 1, sizeof **out);
	if (!*out)
		return SCENE_ERR_NOMEM;
	for (size_t i = 0; i < json_array_size(a); i++) {
		char pi[PATH_MAX_LEN];
		subidx(pi, p, i);
		int rc = parse_motion(c, json_array_get(a, i), pi, &(*out)[i]);
		*count = i + 1; /* so a partially parsed motion is still freed */
		if (rc)
			return rc;
	}
	return 0;
}

/* ------------------------------------------------------------------ named tables */

static int find_named(const char *names, size_t stride, size_t n, const char *name)
{
	for (size_t i = 0; i < n; i++)
		if (!strcmp(names + i * stride, name))
			return (int)i;
	return -1;
}

#define FIND(arr, n, key) find_named((arr)[0].name, sizeof((arr)[0]), (n), (key))

static int ref_texture(jp *c, scene *s, json_t *obj, const char *key, const char *path, int *out)
{
	const char *name;
	*out = SCENE_TEX_NONE;
	if (!json_object_get(obj, key))
		return 0;
	if (jstr(c, obj, key, path, NULL, &name))
		return SCENE_ERR_SCHEMA;
	*out = s->texture_count ? FIND(s->textures, s->texture_count, name) : -1;
	if (*out < 0) {
		char p[PATH_MAX_LEN];
		subpath(p, path, key);
		return jfail(c, p, "no texture named '%s' in $.textures", name);
	}
	return 0;
}

static int parse_textures(jp *c, scene *s, json_t *root)
{
	json_t *t = json_object_get(root, "textures");
	if (!t)
		return 0;
	if (!json_is_object(t))
		return jfail(c, "$.textures", "expected an object mapping names to texture descriptions");
	s->textures = calloc(json_object_size(t) + 1, sizeof *s->textures);
	if (!s->textures)
		return SCENE_ERR_NOMEM;
	const char *name;
	json_t *d;
	json_object_foreach(t, name, d) {
		static const char *const k[] = {"pattern", "output", "scale", "a", "b", "strength", "seed", NULL};
		char p[PATH_MAX_LEN];
		subpath(p, "$.textures", name);
		scene_texture *tex = &s->textures[s->texture_count];
		if (jname(c, name, p, tex->name) || jkeys(c, d, p, k))
			return SCENE_ERR_SCHEMA;
		procgen_texture_desc desc = {0};
		const char *pat, *outp;
		float seed;
		static const float one[4] = {1, 1, 1, 1}, zero[4] = {0, 0, 0, 1};
		if (jstr(c, d, "pattern", p, NULL, &pat) || jstr(c, d, "output", p, "color", &outp) ||
		    jnum(c, d, "scale", p, 4, 0.001f, 4096, &desc.scale) || jvec(c, d, "a", p, 4, zero, desc.a) ||
		    jvec(c, d, "b", p, 4, one, desc.b) || jnum(c, d, "strength", p, 4, 0, 1000, &desc.strength) ||
		    jnum(c, d, "seed", p, 1, 0, 4294967295.0f, &seed))
			return SCENE_ERR_SCHEMA;
		desc.seed = (uint32_t)seed;
		desc.pattern = procgen_pattern_from_string(pat);
		desc.output = procgen_output_from_string(outp);
		char pp[PATH_MAX_LEN];
		if (!desc.pattern) {
			subpath(pp, p, "pattern");
			return jfail(c, pp, "unknown pattern '%s' (use flat, checker, bricks, noise or stripes)", pat);
		}
		if (!desc.output) {
			subpath(pp, p, "output");
			return jfail(c, pp, "unknown output '%s' (use color, normal, metal_rough or occlusion)", outp);
		}
		tex->srgb = desc.output == PROCGEN_OUTPUT_COLOR;
		tex->rgba = malloc((size_t)s->texture_size * s->texture_size * 4);
		if (!tex->rgba)
			return SCENE_ERR_NOMEM;
		s->texture_count++;
		if (procgen_texture(&desc, s->texture_size, tex->rgba))
			return SCENE_ERR_NOMEM;
	}
	return 0;
}

static int parse_materials(jp *c, scene *s, json_t *root)
{
	json_t *t = json_object_get(root, "materials");
	if (!t)
		return 0;
	if (!json_is_object(t))
		return jfail(c, "$.materials", "expected an object mapping names to materials");
	s->materials = calloc(json_object_size(t) + 1, sizeof *s->materials);
	if (!s->materials)
		return SCENE_ERR_NOMEM;
	const char *name;
	json_t *d;
	json_object_foreach(t, name, d) {
		static const char *const k[] = {"base_color", "metallic", "roughness", "emissive", "normal_scale",
						"occlusion_strength", "alpha_mode", "alpha_cutoff", "double_sided",
						"base_color_texture", "metal_rough_texture", "normal_texture",
						"emissive_texture", "occlusion_texture", NULL};
		char p[PATH_MAX_LEN];
		subpath(p, "$.materials", name);
		scene_material *m = &s->materials[s->material_count];
		static const float white[4] = {1, 1, 1, 1}, black[3] = {0, 0, 0};
		const char *am;
		if (jname(c, name, p, m->name) || jkeys(c, d, p, k) || jvec(c, d, "base_color", p, 4, white, m->base_color) ||
		    jnum(c, d, "metallic", p, 0, 0, 1, &m->metallic) || jnum(c, d, "roughness", p, 0.5f, 0, 1, &m->roughness) ||
		    jvec(c, d, "emissive", p, 3, black, m->emissive) ||
		    jnum(c, d, "normal_scale", p, 1, -100, 100, &m->normal_scale) ||
		    jnum(c, d, "occlusion_strength", p, 1, 0, 1, &m->occlusion_strength) ||
		    jstr(c, d, "alpha_mode", p, "OPAQUE", &am) || jnum(c, d, "alpha_cutoff", p, 0.5f, 0, 1, &m->alpha_cutoff) ||
		    jbool(c, d, "double_sided", p, false, &m->double_sided) ||
		    ref_texture(c, s, d, "base_color_texture", p, &m->base_color_tex) ||
		    ref_texture(c, s, d, "metal_rough_texture", p, &m->metal_rough_tex) ||
		    ref_texture(c, s, d, "normal_texture", p, &m->normal_tex) ||
		    ref_texture(c, s, d, "emissive_texture", p, &m->emissive_tex) ||
		    ref_texture(c, s, d, "occlusion_texture", p, &m->occlusion_tex))
			return SCENE_ERR_SCHEMA;
		if (!strcmp(am, "OPAQUE"))
			m->alpha_mode = SCENE_ALPHA_OPAQUE;
		else if (!strcmp(am, "MASK"))
			m->alpha_mode = SCENE_ALPHA_MASK;
		else if (!strcmp(am, "BLEND"))
			m->alpha_mode = SCENE_ALPHA_BLEND;
		else {
			char pp[PATH_MAX_LEN];
			subpath(pp, p, "alpha_mode");
			return jfail(c, pp, "unknown alpha mode '%s' (use OPAQUE, MASK or BLEND)", am);
		}
		s->material_count++;
	}
	return 0;
}

static int parse_meshes(jp *c, scene *s, json_t *root)
{
	json_t *t = json_object_get(root, "meshes");
	if (!t)
		return 0;
	if (!json_is_object(t))
		return jfail(c, "$.meshes", "expected an object mapping names to meshes");
	s->meshes = calloc(json_object_size(t) + 1, sizeof *s->meshes);
	if (!s->meshes)
		return SCENE_ERR_NOMEM;
	const char *name;
	json_t *d;
	json_object_foreach(t, name, d) {
		static const char *const k[] = {"type", "size", "radius", "height", "tube_radius",
						"segments", "rings", "uv_scale", NULL};
		char p[PATH_MAX_LEN];
		subpath(p, "$.meshes", name);
		scene_mesh *m = &s->meshes[s->mesh_count];
		procgen_mesh_desc md = {0};
		float seg, rings;
		if (jname(c, name, p, m->name) || jkeys(c, d, p, k) || jstr(c, d, "type", p, NULL, &md.kind) ||
		    jv3(c, d, "size", p, tlm_v3(1, 1, 1), 0, &md.size) || jnum(c, d, "radius", p, 0.5f, 0, 1e5f, &md.radius) ||
		    jnum(c, d, "height", p, 1, 0, 1e5f, &md.height) ||
		    jnum(c, d, "tube_radius", p, 0.15f, 0, 1e5f, &md.tube_radius) ||
		    jnum(c, d, "segments", p, 0, 0, 1024, &seg) || jnum(c, d, "rings", p, 0, 0, 1024, &rings) ||
		    jnum(c, d, "uv_scale", p, 1, 0.0001f, 1e4f, &md.uv_scale))
			return SCENE_ERR_SCHEMA;
		md.segments = (int)seg;
		md.rings = (int)rings;
		char why[200];
		int rc = procgen_mesh(&md, m, why, sizeof why);
		if (rc == -2)
			return SCENE_ERR_NOMEM;
		if (rc)
			return jfail(c, p, "%s", why);
		s->mesh_count++;
	}
	return 0;
}

static int parse_objects(jp *c, scene *s, json_t *root)
{
	json_t *a = json_object_get(root, "objects");
	if (!a && json_object_get(root, "assets"))
		return 0;
	if (!json_is_array(a) || json_array_size(a) == 0)
		return jfail(c, "$.objects", "expected a non-empty array of objects (or glTF \"assets\")");
	s->objects = calloc(json_array_size(a) + 1, sizeof *s->objects);
	if (!s->objects)
		return SCENE_ERR_NOMEM;
	for (size_t i = 0; i < json_array_size(a); i++) {
		static const char *const k[] = {"name", "mesh", "material", "parent", "casts_shadow", "translation",
						"rotation", "rotation_deg", "scale", "animation", NULL};
		json_t *d = json_array_get(a, i);
		char p[PATH_MAX_LEN], pp[PATH_MAX_LEN];
		subidx(p, "$.objects", i);
		scene_object *o = &s->objects[i];
		const char *name, *mesh, *mat, *parent;
		if (jkeys(c, d, p, k) || jstr(c, d, "name", p, NULL, &name) || jname(c, name, p, o->name) ||
		    jstr(c, d, "mesh", p, NULL, &mesh) || jstr(c, d, "material", p, NULL, &mat) ||
		    jstr(c, d, "parent", p, "", &parent) || jbool(c, d, "casts_shadow", p, true, &o->casts_shadow) ||
		    parse_trs(c, d, p, &o->base))
			return SCENE_ERR_SCHEMA;
		s->object_count = i + 1;
		if (parse_motions(c, d, p, &o->motion_count, &o->motions))
			return SCENE_ERR_SCHEMA;
		if (i > 0 && FIND(s->objects, i, o->name) >= 0)
			return jfail(c, p, "duplicate object name '%s'", o->name);
		o->mesh = s->mesh_count ? FIND(s->meshes, s->mesh_count, mesh) : -1;
		o->material = s->material_count ? FIND(s->materials, s->material_count, mat) : -1;
		if (o->mesh < 0) {
			subpath(pp, p, "mesh");
			return jfail(c, pp, "no mesh named '%s' in $.meshes", mesh);
		}
		if (o->material < 0) {
			subpath(pp, p, "material");
			return jfail(c, pp, "no material named '%s' in $.materials", mat);
		}
		o->parent = -1;
		if (parent[0]) {
			o->parent = i ? FIND(s->objects, i, parent) : -1;
			if (o->parent < 0) {
				subpath(pp, p, "parent");
				return jfail(c, pp, "no earlier object named '%s' (parents must come before children)", parent);
			}
		}
	}
	return 0;
}

static int grow_objects(scene *s, size_t extra)
{
	scene_object *n = realloc(s->objects, (s->object_count + extra + 1) * sizeof *n);
	if (!n)
		return SCENE_ERR_NOMEM;
	memset(n + s->object_count, 0, (extra + 1) * sizeof *n);
	s->objects = n;
	return 0;
}

/* "assets": glTF files placed in the scene; each gets a root object carrying the placement and motions,
 * under which the asset's node hierarchy hangs. Paths are relative to the scene file. */
static int parse_assets(jp *c, scene *s, json_t *root)
{
	json_t *a = json_object_get(root, "assets");
	if (!a)
		return 0;
	if (!json_is_array(a))
		return jfail(c, "$.assets", "expected an array of glTF assets");
	for (size_t i = 0; i < json_array_size(a); i++) {
		static const char *const k[] = {"name", "gltf", "parent", "translation", "rotation", "rotation_deg",
						"scale", "animation", NULL};
		json_t *d = json_array_get(a, i);
		char p[PATH_MAX_LEN], pp[PATH_MAX_LEN], file[4096];
		subidx(p, "$.assets", i);
		const char *name, *gl, *parent;
		if (jkeys(c, d, p, k) || jstr(c, d, "name", p, NULL, &name) || jstr(c, d, "gltf", p, NULL, &gl) ||
		    jstr(c, d, "parent", p, "", &parent))
			return SCENE_ERR_SCHEMA;
		int rc = grow_objects(s, 1);
		if (rc)
			return rc;
		scene_object *o = &s->objects[s->object_count];
		o->mesh = o->material = o->parent = -1;
		if (jname(c, name, p, o->name) || parse_trs(c, d, p, &o->base))
			return SCENE_ERR_SCHEMA;
		s->object_count++;
		if (parse_motions(c, d, p, &o->motion_count, &o->motions))
			return SCENE_ERR_SCHEMA;
		if (FIND(s->objects, s->object_count - 1, o->name) >= 0)
			return jfail(c, p, "duplicate object name '%s'", o->name);
		if (parent[0] && (o->parent = FIND(s->objects, s->object_count - 1, parent)) < 0) {
			subpath(pp, p, "parent");
			return jfail(c, pp, "no object named '%s'", parent);
		}
		const char *slash = strrchr(c->file, '/');
		if (gl[0] == '/' || !slash)
			snprintf(file, sizeof file, "%s", gl);
		else
			snprintf(file, sizeof file, "%.*s/%s", (int)(slash - c->file), c->file, gl);
		char gerr[1024];
		rc = gltf_append(s, file, (int)s->object_count - 1, NULL, gerr, sizeof gerr);
		if (rc) {
			subpath(pp, p, "gltf");
			jfail(c, pp, "%s", gerr);
			return rc == SCENE_ERR_NOMEM ? rc : SCENE_ERR_SCHEMA;
		}
	}
	return 0;
}

/* "intensity_keys": {"times": [...strictly increasing], "values": [...>= 0]} */
static int parse_intensity_keys(jp *c, json_t *light, const char *p, scene_light *l)
{
	char pk[PATH_MAX_LEN], pp[PATH_MAX_LEN];
	json_t *k = json_object_get(light, "intensity_keys");
	if (!k)
		return 0;
	subpath(pk, p, "intensity_keys");
	static const char *const allowed[] = {"times", "values", NULL};
	if (!json_is_object(k))
		return jfail(c, pk, "expected an object with \"times\" and \"values\"");
	if (jkeys(c, k, pk, allowed))
		return SCENE_ERR_SCHEMA;
	json_t *t = json_object_get(k, "times"), *v = json_object_get(k, "values");
	size_t n = json_array_size(t);
	if (!json_is_array(t) || !json_is_array(v) || n == 0 || json_array_size(v) != n)
		return jfail(c, pk, "needs \"times\" and \"values\": arrays of equal, non-zero length");
	l->intensity_times = calloc(n, sizeof(float));
	l->intensity_values = calloc(n, sizeof(float));
	if (!l->intensity_times || !l->intensity_values)
		return SCENE_ERR_NOMEM;
	l->intensity_key_count = n;
	for (size_t i = 0; i < n; i++) {
		json_t *ti = json_array_get(t, i), *vi = json_array_get(v, i);
		subidx(pp, pk, i);
		if (!json_is_number(ti) || !json_is_number(vi))
			return jfail(c, pp, "times and values must be numbers");
		l->intensity_times[i] = (float)json_number_value(ti);
		l->intensity_values[i] = (float)json_number_value(vi);
		if (l->intensity_values[i] < 0 || (i && l->intensity_times[i] <= l->intensity_times[i - 1]))
			return jfail(c, pp, "values must be >= 0 and times strictly increasing");
	}
	return 0;
}

static float light_intensity(const scene_light *l, float t)
{
	size_t n = l->intensity_key_count;
	if (!n)
		return l->intensity;
	if (t <= l->intensity_times[0])
		return l->intensity_values[0];
	for (size_t i = 1; i < n; i++)
		if (t < l->intensity_times[i]) {
			float u = (t - l->intensity_times[i - 1]) / (l->intensity_times[i] - l->intensity_times[i - 1]);
			return l->intensity_values[i - 1] + u * (l->intensity_values[i] - l->intensity_values[i - 1]);
		}
	return l->intensity_values[n - 1];
}

static int parse_lights(jp *c, scene *s, json_t *root)
{
	json_t *a = json_object_get(root, "lights");
	if (!a)
		return 0;
	if (!json_is_array(a))
		return jfail(c, "$.lights", "expected an array of lights");
	if (json_array_size(a) > SCENE_MAX_LIGHTS)
		return jfail(c, "$.lights", "at most %d lights are supported", SCENE_MAX_LIGHTS);
	s->lights = calloc(json_array_size(a) + 1, sizeof *s->lights);
	if (!s->lights)
		return SCENE_ERR_NOMEM;
	for (size_t i = 0; i < json_array_size(a); i++) {
		static const char *const k[] = {"name", "type", "color", "intensity", "range", "inner_cone_deg",
						"outer_cone_deg", "casts_shadow", "shadow_extent", "shadow_center",
						"position", "direction", "animation", "intensity_keys", NULL};
		json_t *d = json_array_get(a, i);
		char p[PATH_MAX_LEN], pp[PATH_MAX_LEN];
		subidx(p, "$.lights", i);
		scene_light *l = &s->lights[i];
		const char *name, *type;
		static const float white[3] = {1, 1, 1};
		tlm_vec3 dir;
		if (jkeys(c, d, p, k) || jstr(c, d, "name", p, NULL, &name) || jname(c, name, p, l->name) ||
		    jstr(c, d, "type", p, NULL, &type) || jvec(c, d, "color", p, 3, white, l->color) ||
		    jnum(c, d, "intensity", p, 1, 0, 1e9f, &l->intensity) || jnum(c, d, "range", p, 0, 0, 1e9f, &l->range) ||
		    jnum(c, d, "inner_cone_deg", p, 0, 0, 90, &l->inner_cone_deg) ||
		    jnum(c, d, "outer_cone_deg", p, 45, 0.1f, 90, &l->outer_cone_deg) ||
		    jbool(c, d, "casts_shadow", p, true, &l->casts_shadow) ||
		    jnum(c, d, "shadow_extent", p, 20, 0.01f, 1e6f, &l->shadow_extent) ||
		    jv3(c, d, "shadow_center", p, tlm_v3(0, 0, 0), 0, &l->shadow_center) ||
		    jv3(c, d, "position", p, tlm_v3(0, 0, 0), 0, &l->base.t) ||
		    jv3(c, d, "direction", p, tlm_v3(0, -1, 0), 0, &dir))
			return SCENE_ERR_SCHEMA;
		s->light_count = i + 1;
		l->base.s = tlm_v3(1, 1, 1);
		if (parse_motions(c, d, p, &l->motion_count, &l->motions) || parse_intensity_keys(c, d, p, l))
			return SCENE_ERR_SCHEMA;
		static const char *kinds[] = {NULL, "directional", "point", "spot"};
		for (int kk = 1; kk < SCENE_LIGHT_COUNT; kk++)
			if (!strcmp(type, kinds[kk]))
				l->kind = (scene_light_kind)kk;
		if (!l->kind) {
			subpath(pp, p, "type");
			return jfail(c, pp, "unknown light type '%s' (use directional, point or spot)", type);
		}
		if (l->inner_cone_deg >= l->outer_cone_deg && l->kind == SCENE_LIGHT_SPOT) {
			subpath(pp, p, "inner_cone_deg");
			return jfail(c, pp, "must be smaller than outer_cone_deg");
		}
		if (tlm_v3_length(dir) < 1e-6f) {
			subpath(pp, p, "direction");
			return jfail(c, pp, "must not be the zero vector");
		}
		/* Orientation that turns the light's local -Z onto `dir`. */
		dir = tlm_v3_normalize_or(dir, tlm_v3(0, -1, 0));
		tlm_vec3 from = tlm_v3(0, 0, -1);
		float cd = tlm_v3_dot(from, dir);
		if (cd < -0.99999f)
			l->base.r = tlm_quat_axis_angle(tlm_v3(0, 1, 0), TLM_PI);
		else
			l->base.r = tlm_quat_normalize((tlm_quat){tlm_v3_cross(from, dir).x, tlm_v3_cross(from, dir).y,
								  tlm_v3_cross(from, dir).z, 1.0f + cd});
	}
	return 0;
}

static int parse_cameras(jp *c, scene *s, json_t *root)
{
	json_t *a = json_object_get(root, "cameras");
	if (!json_is_array(a) || json_array_size(a) == 0)
		return jfail(c, "$.cameras", "expected a non-empty array of camera paths");
	s->cameras = calloc(json_array_size(a), sizeof *s->cameras);
	if (!s->cameras)
		return SCENE_ERR_NOMEM;
	for (size_t i = 0; i < json_array_size(a); i++) {
		static const char *const k[] = {"name", "motion", "fov_deg", "znear", "zfar", "keys", NULL};
		json_t *d = json_array_get(a, i);
		char p[PATH_MAX_LEN], pp[PATH_MAX_LEN];
		subidx(p, "$.cameras", i);
		scene_camera *cam = &s->cameras[i];
		const char *name, *motion;
		if (jkeys(c, d, p, k) || jstr(c, d, "name", p, NULL, &name) || jname(c, name, p, cam->name) ||
		    jstr(c, d, "motion", p, NULL, &motion) || jnum(c, d, "fov_deg", p, 60, 1, 179, &cam->fov_deg) ||
		    jnum(c, d, "znear", p, 0.05f, 1e-4f, 1e4f, &cam->znear) ||
		    jnum(c, d, "zfar", p, 200, 1e-3f, 1e7f, &cam->zfar))
			return SCENE_ERR_SCHEMA;
		s->camera_count = i + 1;
		if (i > 0 && FIND(s->cameras, i, cam->name) >= 0)
			return jfail(c, p, "duplicate camera path name '%s'", cam->name);
		if (!strcmp(motion, "stationary"))
			cam->motion = SCENE_CAMERA_STATIONARY;
		else if (!strcmp(motion, "moving"))
			cam->motion = SCENE_CAMERA_MOVING;
		else {
			subpath(pp, p, "motion");
			return jfail(c, pp, "unknown motion class '%s' (use stationary or moving)", motion);
		}
		if (!(cam->zfar > cam->znear)) {
			subpath(pp, p, "zfar");
			return jfail(c, pp, "must be greater than znear");
		}
		json_t *keys = json_object_get(d, "keys");
		subpath(pp, p, "keys");
		if (!json_is_array(keys) || json_array_size(keys) == 0)
			return jfail(c, pp, "expected a non-empty array of {t, position, target}");
		cam->keys = calloc(json_array_size(keys), sizeof *cam->keys);
		if (!cam->keys)
			return SCENE_ERR_NOMEM;
		for (size_t j = 0; j < json_array_size(keys); j++) {
			static const char *const kk[] = {"t", "position", "target", NULL};
			json_t *kd = json_array_get(keys, j);
			char pk[PATH_MAX_LEN];
			subidx(pk, pp, j);
			scene_camera_key *key = &cam->keys[j];
			if (jkeys(c, kd, pk, kk) || jnum(c, kd, "t", pk, 0, -1e6f, 1e6f, &key->t) ||
			    jv3(c, kd, "position", pk, tlm_v3(0, 0, 0), 1, &key->position) ||
			    jv3(c, kd, "target", pk, tlm_v3(0, 0, 0), 1, &key->target))
				return SCENE_ERR_SCHEMA;
			if (j > 0 && !(key->t > cam->keys[j - 1].t))
				return jfail(c, pk, "key times must be strictly increasing");
			if (tlm_v3_length(tlm_v3_sub(key->target, key->position)) < 1e-6f)
				return jfail(c, pk, "target must differ from position");
			cam->key_count = j + 1;
		}
		if (cam->motion == SCENE_CAMERA_STATIONARY && cam->key_count != 1)
			return jfail(c, pp, "a stationary camera path has exactly one key");
		if (cam->motion == SCENE_CAMERA_MOVING && cam->key_count < 2)
			return jfail(c, pp, "a moving camera path needs at least two keys");
	}
	return 0;
}

static int parse_root(jp *c, scene *s, json_t *root)
{
	static const char *const k[] = {"taslab_scene", "name", "duration_s", "fps", "exposure", "ambient", "sky",
					"texture_size", "shadow_map_size", "textures", "materials", "meshes",
					"objects", "assets", "lights", "cameras", NULL};
	if (!json_is_object(root))
		return jfail(c, "$", "expected a JSON object");
	if (jkeys(c, root, "$", k))
		return SCENE_ERR_SCHEMA;
	json_t *ver = json_object_get(root, "taslab_scene");
	if (!json_is_integer(ver) || json_integer_value(ver) != 1)
		return jfail(c, "$.taslab_scene", "expected 1 (scene format version); is this a taslab scene file?");
	const char *name;
	float ts, ss;
	static const float amb[3] = {0.03f, 0.03f, 0.035f}, sky[3] = {0.05f, 0.06f, 0.08f};
	if (jstr(c, root, "name", "$", NULL, &name) || jname(c, name, "$.name", s->name) ||
	    jnum(c, root, "duration_s", "$", 5, 0.001f, 36000, &s->duration_s) ||
	    jnum(c, root, "fps", "$", 60, 1, 1000, &s->fps) || jnum(c, root, "exposure", "$", 1, 0, 1e6f, &s->exposure) ||
	    jvec(c, root, "ambient", "$", 3, amb, s->ambient) || jvec(c, root, "sky", "$", 3, sky, s->sky) ||
	    jnum(c, root, "texture_size", "$", 512, 4, 4096, &ts) ||
	    jnum(c, root, "shadow_map_size", "$", 1024, 16, 8192, &ss))
		return SCENE_ERR_SCHEMA;
	s->texture_size = (uint32_t)ts;
	s->shadow_map_size = (uint32_t)ss;
	if ((s->texture_size & (s->texture_size - 1)) || (float)s->texture_size != ts)
		return jfail(c, "$.texture_size", "must be a power of two");
	int rc;
	if ((rc = parse_textures(c, s, root)) || (rc = parse_materials(c, s, root)) || (rc = parse_meshes(c, s, root)) ||
	    (rc = parse_objects(c, s, root)) || (rc = parse_assets(c, s, root)) || (rc = parse_lights(c, s, root)) ||
	    (rc = parse_cameras(c, s, root)))
		return rc;
	size_t drawable = 0;
	for (size_t i = 0; i < s->object_count; i++)
		drawable += s->objects[i].mesh >= 0;
	if (!drawable)
		return jfail(c, "$.objects", "the scene has no object with a mesh: nothing to render");
	if (scene_shadow_layer_count(s) > SCENE_MAX_SHADOW_LAYERS)
		return jfail(c, "$.lights", "shadowed lights need %u shadow-map layers, at most %d are supported "
				 "(a point light takes 6)", scene_shadow_layer_count(s), SCENE_MAX_SHADOW_LAYERS);
	return 0;
}

int scene_load_from_memory(const char *json, size_t len, const char *origin, scene **out, char *err, size_t err_size)
{
	jp c = {origin, err, err_size};
	json_error_t je;
	*out = NULL;
	json_t *root = json_loadb(json, len, JSON_REJECT_DUPLICATES, &je);
	if (!root) {
		snprintf(err, err_size, "%s:%d:%d: not valid JSON: %s", origin, je.line, je.column, je.text);
		return SCENE_ERR_PARSE;
	}
	scene *s = calloc(1, sizeof *s);
	int rc = s ? 0 : SCENE_ERR_NOMEM;
	if (!rc)
		s->path = strdup(origin);
	if (!rc && !s->path)
		rc = SCENE_ERR_NOMEM;
	if (!rc)
		rc = parse_root(&c, s, root);
	json_decref(root);
	if (rc == SCENE_ERR_NOMEM)
		snprintf(err, err_size, "%s: out of memory while loading the scene", origin);
	if (rc) {
		scene_destroy(&s);
		return rc;
	}
	*out = s;
	return 0;
}

/* Grows a scene array by `extra` zeroed entries (keeps one spare). */
#define GROW(arr, count, extra)                                                                                    \
	do {                                                                                                       \
		void *p_ = realloc((arr), ((count) + (extra) + 1) * sizeof *(arr));                                \
		if (!p_)                                                                                           \
			goto nomem;                                                                                \
		(arr) = p_;                                                                                        \
		memset((arr) + (count), 0, ((extra) + 1) * sizeof *(arr));                                         \
	} while (0)

/* A scene around a bare glTF file (`taslab render --scene model.gltf`): the asset on a floor, a sun, a key
 * spot and a fill light scaled to the asset's bounds at t = 0, and two camera paths framing the bounds:
 * `orbit` (moving, a 90 degree arc over 5 s) and `front` (stationary), plus the asset's own cameras. */
static int scene_from_gltf(const char *path, scene **out, char *err, size_t err_size)
{
	scene *s = calloc(1, sizeof *s);
	tlm_mat4 *world = NULL;
	if (!s || !(s->path = strdup(path)))
		goto nomem;
	const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
	size_t n = 0;
	for (const char *q = base; *q && *q != '.' && n < SCENE_NAME_MAX - 1; q++)
		s->name[n++] = (isalnum((unsigned char)*q) || *q == '-' || *q == '_') ? *q : '_';
	if (!n)
		s->name[n++] = 'g';
	s->duration_s = 5.0f;
	s->fps = 60.0f;
	s->exposure = 1.0f;
	s->ambient[0] = s->ambient[1] = s->ambient[2] = 0.03f;
	s->sky[0] = 0.05f, s->sky[1] = 0.06f, s->sky[2] = 0.08f;
	s->texture_size = 1024;
	s->shadow_map_size = 1024;
	int rc = gltf_append(s, path, -1, NULL, err, err_size);
	if (rc)
		goto fail;
	world = calloc(s->object_count + 1, sizeof *world);
	if (!world)
		goto nomem;
	scene_eval(s, 0.0f, world, NULL);
	tlm_vec3 lo = tlm_v3(1e30f, 1e30f, 1e30f), hi = tlm_v3(-1e30f, -1e30f, -1e30f);
	for (size_t i = 0; i < s->object_count; i++) {
		if (s->objects[i].mesh < 0)
			continue;
		const scene_mesh *m = &s->meshes[s->objects[i].mesh];
		for (int k = 0; k < 8; k++) {
			tlm_vec3 p = tlm_v3(k & 1 ? m->bounds_max.x : m->bounds_min.x, k & 2 ? m->bounds_max.y : m->bounds_min.y,
					    k & 4 ? m->bounds_max.z : m->bounds_min.z);
			p = tlm_mat4_mul_point(world[i], p);
			lo = tlm_v3(fminf(lo.x, p.x), fminf(lo.y, p.y), fminf(lo.z, p.z));
			hi = tlm_v3(fmaxf(hi.x, p.x), fmaxf(hi.y, p.y), fmaxf(hi.z, p.z));
		}
	}
	if (lo.x > hi.x) {
		snprintf(err, err_size, "%s: the glTF has no triangle meshes to render", path);
		rc = SCENE_ERR_SCHEMA;
		goto fail;
	}
	tlm_vec3 c = tlm_v3_scale(tlm_v3_add(lo, hi), 0.5f);
	float r = fmaxf(0.5f * tlm_v3_length(tlm_v3_sub(hi, lo)), 1e-3f);
	/* floor */
	GROW(s->meshes, s->mesh_count, 1);
	GROW(s->materials, s->material_count, 1);
	GROW(s->objects, s->object_count, 1);
	procgen_mesh_desc fd = {.kind = "plane", .size = {6 * r, 0, 6 * r}, .segments = 8, .uv_scale = 1};
	char why[200];
	if (procgen_mesh(&fd, &s->meshes[s->mesh_count], why, sizeof why))
		goto nomem;
	snprintf(s->meshes[s->mesh_count].name, SCENE_NAME_MAX, "taslab_floor");
	scene_material *fm = &s->materials[s->material_count];
	snprintf(fm->name, SCENE_NAME_MAX, "taslab_floor");
	fm->base_color[0] = fm->base_color[1] = fm->base_color[2] = 0.35f, fm->base_color[3] = 1;
	fm->roughness = 0.8f;
	fm->normal_scale = fm->occlusion_strength = 1;
	fm->base_color_tex = fm->metal_rough_tex = fm->normal_tex = fm->emissive_tex = fm->occlusion_tex = SCENE_TEX_NONE;
	scene_object *fo = &s->objects[s->object_count];
	snprintf(fo->name, SCENE_NAME_MAX, "taslab_floor");
	fo->mesh = (int)s->mesh_count++;
	fo->material = (int)s->material_count++;
	fo->parent = -1;
	fo->casts_shadow = false;
	fo->base = tlm_trs_identity();
	fo->base.t = tlm_v3(c.x, lo.y - 1e-3f * r, c.z);
	s->object_count++;
	/* lights: intensities scale with distance^2 so the asset is lit alike at any size */
	GROW(s->lights, s->light_count, 3);
	scene_light *L = s->lights;
	float d = 3.0f * r;
	L[0] = (scene_light){.name = "sun", .kind = SCENE_LIGHT_DIRECTIONAL, .color = {1, 0.96f, 0.9f}, .intensity = 2.0f,
			     .casts_shadow = true, .shadow_extent = 2.0f * r, .shadow_center = c};
	L[1] = (scene_light){.name = "key", .kind = SCENE_LIGHT_SPOT, .color = {1, 0.9f, 0.8f}, .intensity = 2.5f * d * d,
			     .inner_cone_deg = 20, .outer_cone_deg = 32, .casts_shadow = true};
	L[2] = (scene_light){.name = "fill", .kind = SCENE_LIGHT_POINT, .color = {0.6f, 0.7f, 1.0f}, .intensity = 0.8f * d * d};
	tlm_vec3 sun_dir = tlm_v3_normalize_or(tlm_v3(-0.4f, -1.0f, -0.3f), tlm_v3(0, -1, 0));
	tlm_vec3 key_pos = tlm_v3_add(c, tlm_v3(0.6f * d, 0.8f * d, 0.6f * d));
	tlm_vec3 dirs[2] = {sun_dir, tlm_v3_normalize_or(tlm_v3_sub(c, key_pos), tlm_v3(0, -1, 0))};
	for (int i = 0; i < 3; i++) {
		L[i].base = tlm_trs_identity();
		if (i < 2) { /* orientation turning -Z onto the direction */
			tlm_vec3 from = tlm_v3(0, 0, -1), ax = tlm_v3_cross(from, dirs[i]);
			L[i].base.r = tlm_quat_normalize((tlm_quat){ax.x, ax.y, ax.z, 1.0f + tlm_v3_dot(from, dirs[i])});
		}
	}
	L[1].base.t = key_pos;
	L[2].base.t = tlm_v3_add(c, tlm_v3(-0.8f * d, 0.4f * d, 0.5f * d));
	s->light_count = 3;
	/* cameras: glTF cameras (if any) were appended by gltf_append; put ours first */
	size_t own = s->camera_count;
	GROW(s->cameras, s->camera_count, 2);
	memmove(s->cameras + 2, s->cameras, own * sizeof *s->cameras);
	memset(s->cameras, 0, 2 * sizeof *s->cameras);
	float dist = r / tanf(0.5f * 50.0f * TLM_PI / 180.0f) * 1.1f;
	for (int k = 0; k < 2; k++) {
		scene_camera *cam = &s->cameras[k];
		snprintf(cam->name, SCENE_NAME_MAX, k ? "front" : "orbit");
		cam->motion = k ? SCENE_CAMERA_STATIONARY : SCENE_CAMERA_MOVING;
		cam->fov_deg = 50.0f;
		cam->znear = fmaxf(1e-3f, 0.01f * dist);
		cam->zfar = 20.0f * dist;
		cam->key_count = k ? 1 : 5;
		cam->keys = calloc(cam->key_count, sizeof *cam->keys);
		if (!cam->keys)
			goto nomem;
		for (size_t j = 0; j < cam->key_count; j++) {
			float a = (k ? 20.0f : -45.0f + 22.5f * (float)j) * TLM_PI / 180.0f;
			cam->keys[j].t = 1.25f * (float)j;
			cam->keys[j].position = tlm_v3_add(c, tlm_v3(dist * sinf(a), 0.35f * dist, dist * cosf(a)));
			cam->keys[j].target = c;
		}
	}
	s->camera_count += 2;
	free(world);
	*out = s;
	return 0;
nomem:
	snprintf(err, err_size, "%s: out of memory", path);
	rc = SCENE_ERR_NOMEM;
fail:
	free(world);
	scene_destroy(&s);
	return rc;
}

int scene_load(const char *path, scene **out, char *err, size_t err_size)
{
	*out = NULL;
	size_t plen = strlen(path);
	if ((plen > 5 && !strcmp(path + plen - 5, ".gltf")) || (plen > 4 && !strcmp(path + plen - 4, ".glb")))
		return scene_from_gltf(path, out, err, err_size);
	FILE *f = fopen(path, "rb");
	if (!f) {
		snprintf(err, err_size, "%s: cannot open scene file: %s (built-in scenes are in scenes/; see 'taslab render --help')",
			 path, strerror(errno));
		return SCENE_ERR_IO;
	}
	char *buf = NULL;
	size_t len = 0, cap = 0;
	for (;;) {
		if (len == cap) {
			cap = cap ? cap * 2 : 65536;
			if (cap > (64u << 20)) {
				free(buf);
				fclose(f);
				snprintf(err, err_size, "%s: scene file larger than 64 MiB", path);
				return SCENE_ERR_IO;
			}
			char *nb = realloc(buf, cap);
			if (!nb) {
				free(buf);
				fclose(f);
				snprintf(err, err_size, "%s: out of memory", path);
				return SCENE_ERR_NOMEM;
			}
			buf = nb;
		}
		size_t n = fread(buf + len, 1, cap - len, f);
		len += n;
		if (n == 0)
			break;
	}
	int bad = ferror(f);
	fclose(f);
	if (bad) {
		free(buf);
		snprintf(err, err_size, "%s: read error", path);
		return SCENE_ERR_IO;
	}
	int rc = scene_load_from_memory(buf, len, path, out, err, err_size);
	free(buf);
	return rc;
}

void scene_destroy(scene **ps)
{
	if (!ps || !*ps)
		return;
	scene *s = *ps;
	for (size_t i = 0; i < s->mesh_count; i++) {
		free(s->meshes[i].vertices);
		free(s->meshes[i].indices);
	}
	for (size_t i = 0; i < s->texture_count; i++)
		free(s->textures[i].rgba);
	for (size_t i = 0; i < s->object_count; i++) {
		for (size_t j = 0; j < s->objects[i].motion_count; j++)
			anim_motion_finish(&s->objects[i].motions[j]);
		free(s->objects[i].motions);
	}
	for (size_t i = 0; i < s->light_count; i++) {
		for (size_t j = 0; j < s->lights[i].motion_count; j++)
			anim_motion_finish(&s->lights[i].motions[j]);
		free(s->lights[i].motions);
		free(s->lights[i].intensity_times);
		free(s->lights[i].intensity_values);
	}
	for (size_t i = 0; i < s->camera_count; i++)
		free(s->cameras[i].keys);
	free(s->meshes);
	free(s->textures);
	free(s->materials);
	free(s->objects);
	free(s->lights);
	free(s->cameras);
	free(s->path);
	free(s);
	*ps = NULL;
}

/* ------------------------------------------------------------------ evaluation */

static tlm_trs eval_trs(tlm_trs base, const anim_motion *m, size_t n, float t)
{
	tlm_trs trs = base;
	for (size_t i = 0; i < n; i++)
		anim_motion_apply(&m[i], t, &trs);
	return trs;
}

void scene_eval(const scene *s, float t, tlm_mat4 *world, scene_light_state *lights)
{
	if (world)
		for (size_t i = 0; i < s->object_count; i++) {
			const scene_object *o = &s->objects[i];
			tlm_mat4 local = tlm_trs_matrix(eval_trs(o->base, o->motions, o->motion_count, t));
			/* Parents precede children (enforced at load), so world[parent] is ready. */
			world[i] = o->parent >= 0 ? tlm_mat4_mul(world[o->parent], local) : local;
		}
	if (lights)
		for (size_t i = 0; i < s->light_count; i++) {
			const scene_light *l = &s->lights[i];
			tlm_trs trs = eval_trs(l->base, l->motions, l->motion_count, t);
			lights[i].position = trs.t;
			lights[i].direction = tlm_v3_normalize_or(tlm_quat_rotate(trs.r, tlm_v3(0, 0, -1)), tlm_v3(0, -1, 0));
			lights[i].intensity = light_intensity(l, t);
		}
}

int scene_find_camera(const scene *s, const char *name)
{
	return s->camera_count ? FIND(s->cameras, s->camera_count, name) : -1;
}

/* Cubic Hermite between keys i and i+1 with Catmull-Rom (central difference) tangents. */
static tlm_vec3 hermite_path(const scene_camera_key *k, size_t n, size_t i, float t, int target)
{
#define KP(j) (target ? k[(j)].target : k[(j)].position)
	size_t im = i > 0 ? i - 1 : i, ip = i + 2 < n ? i + 2 : i + 1;
	float t0 = k[i].t, t1 = k[i + 1].t, dt = t1 - t0;
	tlm_vec3 m0 = tlm_v3_scale(tlm_v3_sub(KP(i + 1), KP(im)), 1.0f / (k[i + 1].t - k[im].t));
	tlm_vec3 m1 = tlm_v3_scale(tlm_v3_sub(KP(ip), KP(i)), 1.0f / (k[ip].t - k[i].t));
	float u = (t - t0) / dt, u2 = u * u, u3 = u2 * u;
	tlm_vec3 r = tlm_v3_scale(KP(i), 2 * u3 - 3 * u2 + 1);
	r = tlm_v3_add(r, tlm_v3_scale(m0, (u3 - 2 * u2 + u) * dt));
	r = tlm_v3_add(r, tlm_v3_scale(KP(i + 1), -2 * u3 + 3 * u2));
	r = tlm_v3_add(r, tlm_v3_scale(m1, (u3 - u2) * dt));
	return r;
#undef KP
}

scene_camera_state scene_camera_eval(const scene *s, int camera, float t)
{
	const scene_camera *c = &s->cameras[camera];
	scene_camera_state st = {c->keys[0].position, c->keys[0].target, c->fov_deg, c->znear, c->zfar};
	size_t n = c->key_count;
	if (n == 1 || t <= c->keys[0].t)
		return st;
	if (t >= c->keys[n - 1].t) {
		st.eye = c->keys[n - 1].position;
		st.target = c->keys[n - 1].target;
		return st;
	}
	size_t i = 0;
	while (i + 2 < n && t >= c->keys[i + 1].t)
		i++;
	st.eye = hermite_path(c->keys, n, i, t, 0);
	st.target = hermite_path(c->keys, n, i, t, 1);
	return st;
}

const char *scene_camera_motion_name(scene_camera_motion m)
{
	return m == SCENE_CAMERA_STATIONARY ? "stationary" : m == SCENE_CAMERA_MOVING ? "moving" : "invalid";
}

const char *scene_light_kind_name(scene_light_kind k)
{
	static const char *n[] = {"invalid", "directional", "point", "spot"};
	return k > 0 && k < SCENE_LIGHT_COUNT ? n[k] : "invalid";
}

uint32_t scene_shadow_layer_count(const scene *s)
{
	uint32_t n = 0;
	for (size_t i = 0; i < s->light_count; i++)
		if (s->lights[i].casts_shadow)
			n += s->lights[i].kind == SCENE_LIGHT_POINT ? 6u : 1u;
	return n;
}
