/* scene_parse.c — scene files (JSON, schema in scenes/README.md) into a scene: transforms and motions,
 * textures, materials, meshes, objects, glTF assets, lights, camera paths (DESIGN section 2). Parsing is
 * strict: unknown keys, wrong types and out-of-range values are errors naming the file and JSON path. */
#include "scene_internal.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gltf.h"
#include "procgen.h"

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
			return TL_ERR_INPUT;
		/* a unit quaternion, normalised here; a zero one has no rotation to normalise to */
		if (!(sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]) >= 1e-6f))
			return jfail(c, p, "[%g, %g, %g, %g] is not a rotation quaternion (x, y, z, w; not all zero)",
				     (double)v[0], (double)v[1], (double)v[2], (double)v[3]);
		*out = tlm_quat_normalize((tlm_quat){v[0], v[1], v[2], v[3]});
	} else if (e) {
		subpath(p, path, "rotation_deg");
		if (jarr_floats(c, e, p, 3, v))
			return TL_ERR_INPUT;
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
		return TL_ERR_INPUT;
	json_t *s = json_object_get(obj, "scale");
	if (json_is_number(s)) {
		float k = (float)json_number_value(s);
		if (!isfinite(k)) {
			char p[PATH_MAX_LEN];
			subpath(p, path, "scale");
			return jfail(c, p, "not a finite number (in float range, |x| < 3.4e38)");
		}
		trs->s = tlm_v3(k, k, k);
	} else if (jv3(c, obj, "scale", path, tlm_v3(1, 1, 1), 0, &trs->s)) {
		return TL_ERR_INPUT;
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
		return TL_ERR_NOMEM;
	for (size_t i = 0; i < n; i++)
		tr->times[i] = (float)json_number_value(json_array_get(times, i));
	for (size_t i = 0; i < n * per_key; i++) {
		char pi[PATH_MAX_LEN];
		float v[4];
		subidx(pi, p, i);
		if (jarr_floats(c, json_array_get(vals, i), pi, in_comps, v))
			return TL_ERR_INPUT;
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

/* Rotation axes of spin and orbit: a zero axis has no direction (evaluation would silently use +Y). */
static int nonzero_axis(jp *c, tlm_vec3 axis, const char *path)
{
	char p[PATH_MAX_LEN];
	subpath(p, path, "axis");
	if (!(tlm_v3_length(axis) >= 1e-6f))
		return jfail(c, p, "must not be the zero vector");
	return 0;
}

static int parse_motion(jp *c, json_t *m, const char *path, anim_motion *out)
{
	const char *type;
	memset(out, 0, sizeof *out);
	if (!json_is_object(m))
		return jfail(c, path, "expected an object with a \"type\"");
	if (jstr(c, m, "type", path, NULL, &type))
		return TL_ERR_INPUT;
	float big = 1e6f;
	if (jnum(c, m, "start_s", path, 0, 0, big, &out->start_s))
		return TL_ERR_INPUT;
	if (!strcmp(type, "spin")) {
		static const char *const k[] = {"type", "axis", "rate_deg_s", "phase_deg", "start_s", NULL};
		out->kind = ANIM_MOTION_SPIN;
		if (jkeys(c, m, path, k) || jv3(c, m, "axis", path, tlm_v3(0, 1, 0), 0, &out->axis) ||
		    jnum(c, m, "rate_deg_s", path, 90, -big, big, &out->rate_deg_s) ||
		    jnum(c, m, "phase_deg", path, 0, -big, big, &out->phase_deg) || nonzero_axis(c, out->axis, path))
			return TL_ERR_INPUT;
	} else if (!strcmp(type, "orbit")) {
		static const char *const k[] = {"type", "axis", "center", "radius", "rate_deg_s", "phase_deg", "start_s", NULL};
		out->kind = ANIM_MOTION_ORBIT;
		if (jkeys(c, m, path, k) || jv3(c, m, "axis", path, tlm_v3(0, 1, 0), 0, &out->axis) ||
		    jv3(c, m, "center", path, tlm_v3(0, 0, 0), 0, &out->center) ||
		    jnum(c, m, "radius", path, 1, 0, big, &out->radius) ||
		    jnum(c, m, "rate_deg_s", path, 30, -big, big, &out->rate_deg_s) ||
		    jnum(c, m, "phase_deg", path, 0, -big, big, &out->phase_deg) || nonzero_axis(c, out->axis, path))
			return TL_ERR_INPUT;
	} else if (!strcmp(type, "bob")) {
		static const char *const k[] = {"type", "amplitude", "frequency_hz", "phase_deg", "start_s", NULL};
		out->kind = ANIM_MOTION_BOB;
		if (jkeys(c, m, path, k) || jv3(c, m, "amplitude", path, tlm_v3(0, 0.5f, 0), 0, &out->amplitude) ||
		    jnum(c, m, "frequency_hz", path, 0.5f, 0, 1000, &out->frequency_hz) ||
		    jnum(c, m, "phase_deg", path, 0, -big, big, &out->phase_deg))
			return TL_ERR_INPUT;
	} else if (!strcmp(type, "fall")) {
		static const char *const k[] = {"type", "velocity", "gravity", "floor_y", "restitution", "start_s", NULL};
		out->kind = ANIM_MOTION_FALL;
		if (jkeys(c, m, path, k) || jv3(c, m, "velocity", path, tlm_v3(0, 0, 0), 0, &out->velocity) ||
		    jnum(c, m, "gravity", path, 9.81f, 0.01f, 1000, &out->gravity) ||
		    jnum(c, m, "floor_y", path, 0, -big, big, &out->floor_y) ||
		    jnum(c, m, "restitution", path, 0.5f, 0, 0.99f, &out->restitution))
			return TL_ERR_INPUT;
	} else if (!strcmp(type, "keyframes")) {
		static const char *const k[] = {"type", "interpolation", "times", "translation", "rotation",
						"rotation_deg", "scale", "start_s", NULL};
		const char *is;
		out->kind = ANIM_MOTION_TRACKS;
		if (jkeys(c, m, path, k) || jstr(c, m, "interpolation", path, "LINEAR", &is))
			return TL_ERR_INPUT;
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
			return TL_ERR_NOMEM;
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
		return TL_ERR_NOMEM;
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

#define FIND SCENE_FIND

static int ref_texture(jp *c, scene *s, json_t *obj, const char *key, const char *path, int *out)
{
	const char *name;
	*out = SCENE_TEX_NONE;
	if (!json_object_get(obj, key))
		return 0;
	if (jstr(c, obj, key, path, NULL, &name))
		return TL_ERR_INPUT;
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
		return TL_ERR_NOMEM;
	const char *name;
	json_t *d;
	json_object_foreach(t, name, d) {
		static const char *const k[] = {"pattern", "output", "scale", "a", "b", "strength", "seed", NULL};
		char p[PATH_MAX_LEN];
		subpath(p, "$.textures", name);
		scene_texture *tex = &s->textures[s->texture_count];
		if (jname(c, name, p, tex->name) || jkeys(c, d, p, k))
			return TL_ERR_INPUT;
		procgen_texture_desc desc = {0};
		const char *pat, *outp;
		float seed;
		static const float one[4] = {1, 1, 1, 1}, zero[4] = {0, 0, 0, 1};
		if (jstr(c, d, "pattern", p, NULL, &pat) || jstr(c, d, "output", p, "color", &outp) ||
		    jnum(c, d, "scale", p, 4, 0.001f, 4096, &desc.scale) || jvec(c, d, "a", p, 4, zero, desc.a) ||
		    jvec(c, d, "b", p, 4, one, desc.b) || jnum(c, d, "strength", p, 4, 0, 1000, &desc.strength) ||
		    jnum(c, d, "seed", p, 1, 0, 4294967295.0f, &seed))
			return TL_ERR_INPUT;
		desc.seed = seed >= 4294967295.0f ? UINT32_MAX : (uint32_t)seed; /* the float rounds up to 2^32 */
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
		size_t same = 0;
		for (size_t i = 0; i < s->texture_count; i++)
			same += s->textures[i].srgb == tex->srgb;
		if (same >= SCENE_MAX_TEXTURES)
			return jfail(c, p, "more than %d %s textures (the renderer's texture array limit)", SCENE_MAX_TEXTURES,
				     tex->srgb ? "colour" : "linear");
		tex->rgba = malloc((size_t)s->texture_size * s->texture_size * 4);
		if (!tex->rgba)
			return TL_ERR_NOMEM;
		s->texture_count++;
		if (procgen_texture(&desc, s->texture_size, tex->rgba))
			return TL_ERR_NOMEM;
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
		return TL_ERR_NOMEM;
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
			return TL_ERR_INPUT;
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
		return TL_ERR_NOMEM;
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
			return TL_ERR_INPUT;
		md.segments = (int)seg;
		md.rings = (int)rings;
		char why[200];
		int rc = procgen_mesh(&md, m, why, sizeof why);
		if (rc == TL_ERR_NOMEM)
			return rc;
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
		return TL_ERR_NOMEM;
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
			return TL_ERR_INPUT;
		s->object_count = i + 1;
		if (parse_motions(c, d, p, &o->motion_count, &o->motions))
			return TL_ERR_INPUT;
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
		return TL_ERR_NOMEM;
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
			return TL_ERR_INPUT;
		int rc = grow_objects(s, 1);
		if (rc)
			return rc;
		scene_object *o = &s->objects[s->object_count];
		o->mesh = o->material = o->parent = -1;
		if (jname(c, name, p, o->name) || parse_trs(c, d, p, &o->base))
			return TL_ERR_INPUT;
		s->object_count++;
		if (parse_motions(c, d, p, &o->motion_count, &o->motions))
			return TL_ERR_INPUT;
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
			return rc == TL_ERR_NOMEM ? rc : TL_ERR_INPUT;
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
		return TL_ERR_INPUT;
	json_t *t = json_object_get(k, "times"), *v = json_object_get(k, "values");
	size_t n = json_array_size(t);
	if (!json_is_array(t) || !json_is_array(v) || n == 0 || json_array_size(v) != n)
		return jfail(c, pk, "needs \"times\" and \"values\": arrays of equal, non-zero length");
	l->intensity_times = calloc(n, sizeof(float));
	l->intensity_values = calloc(n, sizeof(float));
	if (!l->intensity_times || !l->intensity_values)
		return TL_ERR_NOMEM;
	l->intensity_key_count = n;
	for (size_t i = 0; i < n; i++) {
		json_t *ti = json_array_get(t, i), *vi = json_array_get(v, i);
		subidx(pp, pk, i);
		if (!json_is_number(ti) || !json_is_number(vi))
			return jfail(c, pp, "times and values must be numbers");
		l->intensity_times[i] = (float)json_number_value(ti);
		l->intensity_values[i] = (float)json_number_value(vi);
		if (!isfinite(l->intensity_times[i]) || !isfinite(l->intensity_values[i]))
			return jfail(c, pp, "times and values must be finite numbers (in float range, |x| < 3.4e38)");
		if (l->intensity_values[i] < 0 || (i && l->intensity_times[i] <= l->intensity_times[i - 1]))
			return jfail(c, pp, "values must be >= 0 and times strictly increasing");
	}
	return 0;
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
		return TL_ERR_NOMEM;
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
			return TL_ERR_INPUT;
		s->light_count = i + 1;
		l->base.s = tlm_v3(1, 1, 1);
		if (parse_motions(c, d, p, &l->motion_count, &l->motions) || parse_intensity_keys(c, d, p, l))
			return TL_ERR_INPUT;
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
		return TL_ERR_NOMEM;
	for (size_t i = 0; i < json_array_size(a); i++) {
		static const char *const k[] = {"name", "motion", "fov_deg", "znear", "zfar", "keys", NULL};
		json_t *d = json_array_get(a, i);
		char p[PATH_MAX_LEN], pp[PATH_MAX_LEN];
		subidx(p, "$.cameras", i);
		scene_camera *cam = &s->cameras[i];
		const char *name, *motion;
		if (jkeys(c, d, p, k) || jstr(c, d, "name", p, NULL, &name) || jname(c, name, p, cam->name) ||
		    jstr(c, d, "motion", p, NULL, &motion) || jnum(c, d, "fov_deg", p, 60, SCENE_FOV_MIN_DEG, SCENE_FOV_MAX_DEG, &cam->fov_deg) ||
		    jnum(c, d, "znear", p, 0.05f, 1e-4f, 1e4f, &cam->znear) ||
		    jnum(c, d, "zfar", p, 200, 1e-3f, 1e7f, &cam->zfar))
			return TL_ERR_INPUT;
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
			return TL_ERR_NOMEM;
		for (size_t j = 0; j < json_array_size(keys); j++) {
			static const char *const kk[] = {"t", "position", "target", NULL};
			json_t *kd = json_array_get(keys, j);
			char pk[PATH_MAX_LEN];
			subidx(pk, pp, j);
			scene_camera_key *key = &cam->keys[j];
			if (jkeys(c, kd, pk, kk) || jnum(c, kd, "t", pk, 0, -1e6f, 1e6f, &key->t) ||
			    jv3(c, kd, "position", pk, tlm_v3(0, 0, 0), 1, &key->position) ||
			    jv3(c, kd, "target", pk, tlm_v3(0, 0, 0), 1, &key->target))
				return TL_ERR_INPUT;
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
		return TL_ERR_INPUT;
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
		return TL_ERR_INPUT;
	s->texture_size = (uint32_t)ts;
	s->shadow_map_size = (uint32_t)ss;
	if ((s->texture_size & (s->texture_size - 1)) || (float)s->texture_size != ts)
		return jfail(c, "$.texture_size", "must be a power of two");
	if (c->texture_size)
		s->texture_size = c->texture_size;
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
	return scene_parse_memory(json, len, origin, 0, out, err, err_size);
}

int scene_parse_memory(const char *json, size_t len, const char *origin, uint32_t texture_size, scene **out, char *err,
		       size_t err_size)
{
	jp c = {origin, err, err_size, texture_size};
	json_error_t je;
	*out = NULL;
	json_t *root = json_loadb(json, len, JSON_REJECT_DUPLICATES, &je);
	if (!root) {
		snprintf(err, err_size, "%s:%d:%d: not valid JSON: %s", origin, je.line, je.column, je.text);
		scene_err_one_line(err, err_size);
		return TL_ERR_INPUT;
	}
	scene *s = calloc(1, sizeof *s);
	int rc = s ? 0 : TL_ERR_NOMEM;
	if (!rc)
		s->path = strdup(origin);
	if (!rc && !s->path)
		rc = TL_ERR_NOMEM;
	if (!rc)
		rc = parse_root(&c, s, root);
	json_decref(root);
	if (rc == TL_ERR_NOMEM)
		snprintf(err, err_size, "%s: out of memory while loading the scene", origin);
	if (rc) {
		scene_err_one_line(err, err_size);
		scene_destroy(&s);
		return rc;
	}
	*out = s;
	return 0;
}
