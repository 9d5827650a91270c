/* pairs.c — pairs.json writer and reader (pairs.h). */
#include "taslab/pairs.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/tl_error.h"
#include "taslab/tl_json.h"

#include "method_facts.h"

int pairs_write(const char *path, const pairs_set *s, char *err, size_t err_size)
{
	json_t *conds = json_array();
	for (size_t i = 0; conds && i < s->count; i++) {
		const pairs_condition *c = &s->conditions[i];
		json_array_append_new(conds, json_pack("{s:s, s:s, s:s, s:o, s:o, s:s, s:s, s:s}", "id", c->id, "method",
						       c->method, "variant", c->variant, "T",
						       isfinite(c->T) ? json_real(c->T) : json_null(), "period",
						       c->period ? json_integer(c->period) : json_null(), "run", c->run, "clip",
						       c->clip, "inspect", c->inspect));
		json_t *jc = json_array_get(conds, i);
		if (c->facts.known)
			json_object_set_new(jc, "method_facts", method_facts_json(&c->facts));
		if (!c->run[0]) /* a set from a sweep has no run or inspect folder of its own */
			json_object_del(jc, "run");
		if (!c->inspect[0])
			json_object_del(jc, "inspect");
		if (c->sweep_run[0])
			json_object_set_new(jc, "sweep_run", json_string(c->sweep_run));
	}
	json_t *m = json_pack("{s:i, s:s, s:s, s:s, s:s, s:f, s:[I,I], s:[i,i], s:s, s:{s:s, s:s}, s:o}", "taslab_pairs", 1,
			      "scene", s->scene, "scene_path", s->scene_path, "camera", s->camera, "camera_motion",
			      s->camera_motion, "fps", s->fps, "frames", (json_int_t)s->first_frame, (json_int_t)s->last_frame, "size",
			      (int)s->width, (int)s->height, "display_transform", s->display_transform, "reference", "run",
			      s->ref_run, "clip", s->ref_clip, "conditions", conds);
	if (m && s->views > 1) { /* STEREO.md: studies add display=stereo; mono sets are written as before */
		json_object_set_new(m, "display", json_string("stereo"));
		json_object_set_new(m, "ipd", json_real(s->ipd));
	}
	if (m && s->ref_method[0])
		json_object_set_new(json_object_get(m, "reference"), "method", json_string(s->ref_method));
	if (m && !s->ref_run[0])
		json_object_del(json_object_get(m, "reference"), "run");
	if (m && s->scene_digest[0])
		json_object_set_new(m, "scene_digest", json_string(s->scene_digest));
	if (m && s->colour_digest[0])
		json_object_set_new(m, "colour_digest", json_string(s->colour_digest));
	if (m && s->sweep[0])
		json_object_set_new(m, "source", json_pack("{s:s, s:s}", "sweep", s->sweep, "ref_run", s->sweep_ref_run));
	int rc = tl_json_write(path, m, err, err_size);
	json_decref(m);
	return rc;
}

/* A relative path inside the set's folder: not absolute, no ".." component, not empty. */
static int safe_rel(const char *p)
{
	if (!p || !*p || *p == '/')
		return 0;
	for (const char *c = p; *c;) {
		size_t n = strcspn(c, "/");
		if (n == 2 && c[0] == '.' && c[1] == '.')
			return 0;
		c += n;
		if (*c == '/')
			c++;
	}
	return 1;
}

static int get_str(json_t *o, const char *key, char *dst, size_t n, int path_like)
{
	const char *v = json_string_value(json_object_get(o, key));
	if (!v || strlen(v) >= n || (path_like && !safe_rel(v)))
		return -1; /* local sentinel: missing or bad; pairs_read says which key, as TL_ERR_INPUT */
	snprintf(dst, n, "%s", v);
	return 0;
}

int pairs_read(const char *path, pairs_set *s, char *err, size_t err_size)
{
	memset(s, 0, sizeof *s);
	json_t *j = NULL;
	int rc = tl_json_read(path, &j, err, err_size);
	if (rc)
		return rc;
	json_t *fr = json_object_get(j, "frames"), *sz = json_object_get(j, "size"), *ref = json_object_get(j, "reference");
	json_t *conds = json_object_get(j, "conditions");
	const char *bad = NULL;
	char why[160];
	if (get_str(j, "scene", s->scene, sizeof s->scene, 0) || get_str(j, "camera", s->camera, sizeof s->camera, 0) ||
	    get_str(j, "camera_motion", s->camera_motion, sizeof s->camera_motion, 0))
		bad = "scene, camera and camera_motion must be strings";
	else if (get_str(ref, "clip", s->ref_clip, sizeof s->ref_clip, 1) ||
		 (json_object_get(ref, "run") && get_str(ref, "run", s->ref_run, sizeof s->ref_run, 1)))
		bad = "reference.clip (and reference.run) must be relative paths inside the set";
	else if (json_object_get(ref, "method") && get_str(ref, "method", s->ref_method, sizeof s->ref_method, 0))
		bad = "reference.method must be a method name";
	else if (!json_is_array(conds))
		bad = "conditions must be an array";
	else if (json_array_size(fr) != 2 || (sz && json_array_size(sz) != 2) || !(json_number_value(json_object_get(j, "fps")) > 0))
		bad = "frames and fps are missing";
	if (!bad) {
		get_str(j, "scene_path", s->scene_path, sizeof s->scene_path, 0);
		get_str(j, "display_transform", s->display_transform, sizeof s->display_transform, 0);
		get_str(j, "scene_digest", s->scene_digest, sizeof s->scene_digest, 0);
		get_str(j, "colour_digest", s->colour_digest, sizeof s->colour_digest, 0);
		json_t *src = json_object_get(j, "source");
		if (src && (get_str(src, "sweep", s->sweep, sizeof s->sweep, 0) ||
			    get_str(src, "ref_run", s->sweep_ref_run, sizeof s->sweep_ref_run, 1)))
			bad = "source must hold the sweep folder and the reference's run folder in it";
		s->fps = json_number_value(json_object_get(j, "fps"));
		json_int_t a = json_integer_value(json_array_get(fr, 0)), b = json_integer_value(json_array_get(fr, 1));
		json_int_t w = json_integer_value(json_array_get(sz, 0)), h = json_integer_value(json_array_get(sz, 1));
		if (a < 0 || b < a || b > 0xffffffffLL || (sz && (w < 1 || h < 1 || w > 16384 || h > 16384)))
			bad = "frames or size out of range";
		s->first_frame = (uint32_t)a, s->last_frame = (uint32_t)b, s->width = (uint32_t)w, s->height = (uint32_t)h;
		json_t *disp = json_object_get(j, "display"), *ipd = json_object_get(j, "ipd");
		s->views = 1;
		if (disp && !(json_is_string(disp) && (!strcmp(json_string_value(disp), "stereo") ||
						       !strcmp(json_string_value(disp), "mono"))))
			bad = "display must be \"stereo\" or \"mono\"";
		else if (disp && !strcmp(json_string_value(disp), "stereo")) {
			s->views = 2;
			s->ipd = json_number_value(ipd);
			if (!json_is_number(ipd) || !(s->ipd >= 0.0 && s->ipd <= 1.0))
				bad = "a stereo set needs ipd in metres (0..1)";
		}
	}
	size_t n = bad ? 0 : json_array_size(conds);
	if (n && !(s->conditions = calloc(n, sizeof *s->conditions)))
		bad = "out of memory";
	for (size_t i = 0; !bad && i < n; i++) {
		json_t *c = json_array_get(conds, i), *T = json_object_get(c, "T"), *N = json_object_get(c, "period");
		pairs_condition *x = &s->conditions[i];
		if (get_str(c, "method", x->method, sizeof x->method, 0) ||
		    get_str(c, "clip", x->clip, sizeof x->clip, 1) || (T && !json_is_null(T) && !json_is_number(T)) ||
		    (N && !json_is_null(N) && !json_is_integer(N))) {
			bad = "a condition lacks method or a relative clip path, or has a non-numeric T/period";
			break;
		}
		if (method_facts_read(json_object_get(c, "method_facts"), &x->facts)) {
			bad = "a condition's method_facts is not an object of family, baseline, reference, takes_threshold, "
			      "takes_period";
			break;
		}
		if (get_str(c, "variant", x->variant, sizeof x->variant, 0))
			snprintf(x->variant, sizeof x->variant, "%s", x->method);
		get_str(c, "run", x->run, sizeof x->run, 1);
		get_str(c, "inspect", x->inspect, sizeof x->inspect, 1);
		get_str(c, "sweep_run", x->sweep_run, sizeof x->sweep_run, 1);
		x->T = json_is_number(T) ? json_number_value(T) : NAN;
		json_int_t nv = json_is_integer(N) ? json_integer_value(N) : 0;
		x->period = nv > 0 && nv <= 8 ? (uint32_t)nv : 0;
		if (get_str(c, "id", x->id, sizeof x->id, 0)) /* optional: the method and its values */
			snprintf(x->id, sizeof x->id, isfinite(x->T) ? "%s-T%g" : "%s", x->method, x->T);
		if (nv != 0 && nv != 1 && nv != 2 && nv != 4 && nv != 8) {
			snprintf(why, sizeof why, "condition '%s': period %lld is not 1, 2, 4 or 8", x->id, (long long)nv);
			bad = why;
			break;
		}
		if (isfinite(x->T) && !(x->T >= 0 && x->T <= 255)) {
			bad = "a condition's T is outside 0..255";
			break;
		}
		s->count++;
	}
	json_decref(j);
	if (bad) {
		pairs_free(s);
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: not a valid taslab pairs.json: %s (make sets with 'taslab pair')",
				path, bad);
	}
	return TL_OK;
}

void pairs_free(pairs_set *s)
{
	free(s->conditions);
	memset(s, 0, sizeof *s);
}
