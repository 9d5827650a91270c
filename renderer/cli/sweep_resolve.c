#define _XOPEN_SOURCE 700 /* realpath */
/* sweep_resolve.c — a sweep request (file and/or options) resolved against the scene files and the method registry
 * into the spec written to SWEEP/sweep.json (sweep_cli.h, output/sweep.h; DESIGN sections 4 and 9). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sweep_cli.h"
#include "taslab/colour.h"
#include "taslab/method.h"
#include "taslab/metrics.h"
#include "taslab/metrics_flip.h"
#include "taslab/scene.h"

/* ------------------------------------------------------------------ options onto the request */

static int split_into(const char *list, const char *what, char *rows, size_t row_size, size_t max, size_t *n,
		      char *err, size_t err_size)
{
	char buf[8192];
	const char *items[256];
	int rc = cli_split_list(list, what, buf, sizeof buf, items, max < 256 ? max : 256, n, err, err_size);
	for (size_t i = 0; !rc && i < *n; i++) {
		if (strlen(items[i]) >= row_size)
			return tl_error(err, err_size, TL_ERR_ARG, "%s: '%s' is too long", what, items[i]);
		snprintf(rows + i * row_size, row_size, "%s", items[i]);
	}
	return rc;
}

int cli_sweep_request_from_opts(const sweep_opts *o, sweep_request *r, char *err, size_t err_size)
{
	int rc = TL_OK;
	if (o->scenes) {
		rc = split_into(o->scenes, "--scenes", &r->scenes[0][0], sizeof r->scenes[0], SWEEP_MAX_SCENES,
				&r->scene_count, err, err_size);
		r->set |= SWEEP_SET_SCENES;
	}
	if (!rc && o->cameras) {
		r->cameras_all = !strcmp(o->cameras, "all");
		r->camera_count = 0;
		if (!r->cameras_all)
			rc = split_into(o->cameras, "--cameras", &r->cameras[0][0], sizeof r->cameras[0],
					sizeof r->cameras / sizeof r->cameras[0], &r->camera_count, err, err_size);
		r->set |= SWEEP_SET_CAMERAS;
	}
	if (!rc && o->variants) {
		rc = split_into(o->variants, "--variants", &r->variants[0][0], sizeof r->variants[0], SWEEP_MAX_VARIANTS,
				&r->variant_count, err, err_size);
		r->set |= SWEEP_SET_VARIANTS;
	}
	if (!rc && o->methods) {
		r->methods_all = !strcmp(o->methods, "all");
		r->method_count = 0;
		if (!r->methods_all)
			rc = split_into(o->methods, "--methods", &r->methods[0][0], sizeof r->methods[0], SWEEP_MAX_VARIANTS,
					&r->method_count, err, err_size);
		r->set |= SWEEP_SET_METHODS;
	}
	if (!rc && o->thresholds) {
		float T[SWEEP_MAX_VALUES];
		rc = cli_parse_float_list(o->thresholds, "--thresholds: T", 1e-6, 255, T, SWEEP_MAX_VALUES, &r->threshold_count,
					  err, err_size);
		for (size_t i = 0; !rc && i < r->threshold_count; i++)
			r->thresholds[i] = T[i];
		r->set |= SWEEP_SET_THRESHOLDS;
	}
	if (!rc && o->periods) {
		char buf[512];
		const char *items[SWEEP_MAX_VALUES];
		rc = cli_split_list(o->periods, "--periods", buf, sizeof buf, items, SWEEP_MAX_VALUES, &r->period_count, err,
				    err_size);
		for (size_t i = 0; !rc && i < r->period_count; i++) {
			uint64_t v;
			rc = cli_parse_uint(items[i], "--periods: N", 1, 1024, &v, err, err_size);
			r->periods[i] = (uint32_t)v;
		}
		r->set |= SWEEP_SET_PERIODS;
	}
#define COPY(field, flag, bit)                                                                                     \
	if (!rc && o->field) {                                                                                     \
		if (strlen(o->field) >= sizeof r->field)                                                           \
			return tl_error(err, err_size, TL_ERR_ARG, "--%s is too long", flag);                      \
		snprintf(r->field, sizeof r->field, "%s", o->field);                                               \
		r->set |= bit;                                                                                     \
	}
	COPY(frames, "frames", SWEEP_SET_FRAMES)
	COPY(out, "out", SWEEP_SET_OUT)
	COPY(baseline, "baseline", SWEEP_SET_BASELINE)
	COPY(metrics, "metrics", SWEEP_SET_METRICS)
	COPY(device, "device", SWEEP_SET_DEVICE)
	COPY(ocio_config, "ocio-config", SWEEP_SET_OCIO)
	COPY(display, "display", SWEEP_SET_DISPLAY)
	COPY(view, "view", SWEEP_SET_VIEW)
#undef COPY
	if (o->size[0])
		r->width = o->size[0], r->height = o->size[1], r->set |= SWEEP_SET_SIZE;
	if (o->fps > 0)
		r->fps = o->fps, r->set |= SWEEP_SET_FPS;
	if (o->ppd > 0)
		r->ppd = o->ppd, r->set |= SWEEP_SET_PPD;
	if (o->validation)
		r->validation = true, r->set |= SWEEP_SET_VALIDATION;
	if (o->truth)
		r->truth = true, r->set |= SWEEP_SET_TRUTH;
	if (o->jobs)
		r->jobs = o->jobs, r->set |= SWEEP_SET_JOBS;
	return rc;
}

/* ------------------------------------------------------------------ resolution */

static int camera_list(const scene *scn, char *out, size_t n)
{
	out[0] = 0;
	for (size_t i = 0; i < scn->camera_count; i++) {
		strncat(out, i ? ", " : "", n - strlen(out) - 1);
		strncat(out, scn->cameras[i].name, n - strlen(out) - 1);
	}
	return 0;
}

static int add_camera(sweep_scene *sc, const scene *scn, int cam)
{
	for (size_t k = 0; k < sc->camera_count; k++)
		if (!strcmp(sc->cameras[k].name, scn->cameras[cam].name))
			return TL_OK; /* listed twice: once is enough */
	if (sc->camera_count == SWEEP_MAX_CAMERAS)
		return TL_ERR_ARG;
	sweep_camera *c = &sc->cameras[sc->camera_count++];
	snprintf(c->name, sizeof c->name, "%s", scn->cameras[cam].name);
	snprintf(c->motion, sizeof c->motion, "%s", scene_camera_motion_name(scn->cameras[cam].motion));
	return TL_OK;
}

/* A name that can be a folder of SWEEP/runs/. */
static bool folder_name(const char *s) { return *s && *s != '.' && !strchr(s, '/') && !strchr(s, '\\'); }

static int resolve_scene(const sweep_request *r, size_t i, sweep_spec *s, char *err, size_t err_size)
{
	char path[4096], why[1024], names[1024];
	scene *scn = NULL;
	int rc = cli_resolve_scene(r->scenes[i], path, sizeof path, err, err_size);
	if (rc)
		return rc;
	if ((rc = scene_load(path, &scn, why, sizeof why)))
		return tl_error(err, err_size, rc, "scenes: %s", why);
	sweep_scene *sc = &s->scenes[i];
	memset(sc, 0, sizeof *sc);
	char *abs = realpath(path, NULL);
	snprintf(sc->path, sizeof sc->path, "%s", abs ? abs : path);
	free(abs);
	if (strlen(scn->name) >= sizeof sc->name || !folder_name(scn->name)) {
		rc = tl_error(err, err_size, TL_ERR_INPUT, "scenes: scene '%s' of %s cannot name a folder", scn->name, path);
		goto done;
	}
	snprintf(sc->name, sizeof sc->name, "%s", scn->name);
	scene_digest(scn, sc->digest); /* the sweep's identity holds the scene's content, not only its path (31.4) */
	for (size_t q = 0; q < i; q++)
		if (!strcmp(s->scenes[q].name, sc->name)) {
			rc = tl_error(err, err_size, TL_ERR_ARG, "scenes: scene '%s' is listed twice", sc->name);
			goto done;
		}
	/* frames and fps as `taslab render` takes them: the default is the whole clip */
	sc->fps = r->fps > 0 ? r->fps : scn->fps;
	sc->first = 0;
	sc->end = (uint32_t)lround((double)scn->duration_s * sc->fps);
	if (sc->end < 1)
		sc->end = 1;
	bool given;
	if (r->frames[0] && (rc = cli_parse_frames(r->frames, &sc->first, &sc->end, &given, err, err_size)))
		goto done;
	camera_list(scn, names, sizeof names);
	for (size_t k = 0; k < r->camera_count; k++) {
		const char *name = r->cameras[k], *slash = strchr(name, '/');
		if (slash) {
			if ((size_t)(slash - name) != strlen(sc->name) || strncmp(name, sc->name, strlen(sc->name)))
				continue;
			name = slash + 1;
		}
		int cam = scene_find_camera(scn, name);
		if (cam < 0) {
			rc = tl_error(err, err_size, TL_ERR_ARG, "cameras: scene '%s' has no camera path '%s' (available: %s%s)",
				      sc->name, name, names, slash ? "" : "; name a path of one scene as SCENE/CAMERA");
			goto done;
		}
		if (add_camera(sc, scn, cam)) {
			rc = tl_error(err, err_size, TL_ERR_ARG, "cameras: at most %d camera paths per scene", SWEEP_MAX_CAMERAS);
			goto done;
		}
	}
	if (r->cameras_all || !r->camera_count)
		for (size_t c = 0; c < scn->camera_count && !rc; c++)
			if (add_camera(sc, scn, (int)c))
				rc = tl_error(err, err_size, TL_ERR_ARG, "scene '%s' has more than %d camera paths", sc->name,
					      SWEEP_MAX_CAMERAS);
	for (size_t k = 0; !rc && k < sc->camera_count; k++)
		if (!folder_name(sc->cameras[k].name))
			rc = tl_error(err, err_size, TL_ERR_INPUT, "scene '%s': camera path '%s' cannot name a folder", sc->name,
				      sc->cameras[k].name);
done:
	scene_destroy(&scn);
	return rc;
}

/* Adds a variant token; `explicit` duplicates are errors, expanded ones are skipped. */
static int add_variant(sweep_spec *s, const char *token, bool is_explicit, const char *what, char *err, size_t err_size)
{
	method_config mc;
	char why[512];
	int rc = method_config_parse_variant(&mc, token, why, sizeof why);
	if (rc)
		return tl_error(err, err_size, TL_ERR_ARG, "%s: %s", what, why);
	sweep_variant v = {0};
	method_config_variant(&mc, v.variant, sizeof v.variant);
	method_config_id(&mc, v.id, sizeof v.id);
	method_config_name(&mc, v.method, sizeof v.method);
	v.T = method_config_threshold(&mc);
	v.period = method_config_period(&mc);
	for (size_t i = 0; i < s->variant_count; i++)
		if (!strcmp(s->variants[i].id, v.id))
			return is_explicit ? tl_error(err, err_size, TL_ERR_ARG, "%s: '%s' is listed twice", what, token) : TL_OK;
	if (s->variant_count == SWEEP_MAX_VARIANTS)
		return tl_error(err, err_size, TL_ERR_ARG, "%s: at most %d variants", what, SWEEP_MAX_VARIANTS);
	s->variants[s->variant_count++] = v;
	return TL_OK;
}

/* methods x thresholds x periods: every method's variant sigils from its option table (DESIGN section 4), so methods
 * that land later join without changes here. Flag options ('-': oracle) add a flagged variant next to the plain one. */
static int expand_method(const sweep_request *r, const method_info *m, sweep_spec *s, char *err, size_t err_size)
{
	if (!m->available)
		return tl_error(err, err_size, TL_ERR_UNSUPPORTED, "methods: %s is planned, not available yet", m->name);
	bool has_T = false, has_N = false;
	const char *flags[8];
	size_t nflags = 0;
	for (size_t k = 0; k < m->option_count; k++) {
		has_T |= m->options[k].variant == '@';
		has_N |= m->options[k].variant == '/';
		if (m->options[k].variant == '-' && nflags < 8)
			flags[nflags++] = m->options[k].name;
	}
	if (has_T && !r->threshold_count)
		return tl_error(err, err_size, TL_ERR_ARG, "methods: %s has a threshold: give --thresholds (e.g. 4,8,16)", m->name);
	if (has_N && !r->period_count)
		return tl_error(err, err_size, TL_ERR_ARG, "methods: %s has a period: give --periods (e.g. 2,4,8)", m->name);
	for (size_t f = 0; f <= nflags; f++) {
		char base[SWEEP_NAME_MAX];
		snprintf(base, sizeof base, f ? "%s-%s" : "%s", m->name, f ? flags[f - 1] : "");
		size_t nT = has_T ? r->threshold_count : 1, nN = has_N ? r->period_count : 1;
		for (size_t t = 0; t < nT; t++)
			for (size_t p = 0; p < nN; p++) {
				char tok[SWEEP_NAME_MAX * 2], tpart[32] = "", ppart[32] = "";
				if (has_T)
					snprintf(tpart, sizeof tpart, "@%g", r->thresholds[t]);
				if (has_N)
					snprintf(ppart, sizeof ppart, "/%u", r->periods[p]);
				snprintf(tok, sizeof tok, "%s%s%s", base, tpart, ppart);
				int rc = add_variant(s, tok, false, "methods", err, err_size);
				if (rc)
					return rc;
			}
	}
	return TL_OK;
}

int cli_sweep_resolve(const sweep_request *r, sweep_spec *s, char *err, size_t err_size)
{
	memset(s, 0, sizeof *s);
	int rc;
	if (!r->scene_count)
		return tl_error(err, err_size, TL_ERR_ARG, "--scenes is required (e.g. --scenes calm,moderate; see 'taslab scenes')");
	if (!r->variant_count && !r->methods_all && !r->method_count)
		return tl_error(err, err_size, TL_ERR_ARG,
				"--variants (e.g. ref,tfr@8,rrc/4) or --methods with --thresholds/--periods is required");
	/* variants first: cheap, and a typo should not wait for scene loading */
	for (size_t i = 0; i < r->variant_count; i++)
		if ((rc = add_variant(s, r->variants[i], true, "variants", err, err_size)))
			return rc;
	if (r->methods_all || r->method_count) {
		if ((rc = add_variant(s, "ref", false, "methods", err, err_size)))
			return rc;
		size_t count;
		const method_info *const *all = method_list(&count);
		if (r->methods_all) {
			for (size_t i = 0; i < count; i++)
				if (all[i]->available && strcmp(all[i]->name, "ref") &&
				    (rc = expand_method(r, all[i], s, err, err_size)))
					return rc;
		}
		for (size_t i = 0; i < r->method_count; i++) {
			const method_info *m = method_find(r->methods[i]);
			if (!m)
				return tl_error(err, err_size, TL_ERR_ARG, "methods: unknown method '%s' (see 'taslab render --help')",
						r->methods[i]);
			if (strcmp(m->name, "ref") && (rc = expand_method(r, m, s, err, err_size)))
				return rc;
		}
	}
	bool has_ref = false;
	for (size_t i = 0; i < s->variant_count; i++)
		has_ref |= !strcmp(s->variants[i].id, "ref");
	if (!has_ref)
		return tl_error(err, err_size, TL_ERR_ARG,
				"--variants has no ref: every run is compared with the ref run of its scene and camera path "
				"(add ref to the list)");
	/* baseline: "auto" (sa for the atlas methods when sa is swept, else ref; metrics_runs.h) or a variant of the
	 * list, as its canonical token */
	const char *baseline = r->baseline[0] ? r->baseline : "auto";
	if (!strcmp(baseline, "auto")) {
		snprintf(s->baseline, sizeof s->baseline, "auto");
	} else {
		method_config bc;
		char why[512], token[SWEEP_NAME_MAX];
		if (method_config_parse_variant(&bc, baseline, why, sizeof why))
			return tl_error(err, err_size, TL_ERR_ARG, "baseline: %s", why);
		method_config_variant(&bc, token, sizeof token);
		bool found = false;
		for (size_t i = 0; i < s->variant_count; i++)
			found |= !strcmp(s->variants[i].variant, token);
		if (!found)
			return tl_error(err, err_size, TL_ERR_ARG, "baseline: %s is not one of the variants", token);
		snprintf(s->baseline, sizeof s->baseline, "%s", token);
	}
	/* metrics and display transform */
	uint32_t mask;
	snprintf(s->metrics, sizeof s->metrics, "%s", r->metrics[0] ? r->metrics : "all");
	if (mtr_metric_parse(s->metrics, &mask, err, err_size))
		return TL_ERR_ARG;
	s->ppd = r->ppd > 0 ? r->ppd : MTR_FLIP_PPD_DEFAULT;
	snprintf(s->device, sizeof s->device, "%s", r->device);
	s->validation = r->validation;
	s->truth = r->truth;
	snprintf(s->ocio_config, sizeof s->ocio_config, "%s", r->ocio_config);
	snprintf(s->display, sizeof s->display, "%s", r->display);
	snprintf(s->view, sizeof s->view, "%s", r->view);
	s->width = r->width ? r->width : 960;
	s->height = r->height ? r->height : 540;
	for (size_t i = 0; i < r->camera_count; i++)
		if (!r->cameras[i][0] || r->cameras[i][strlen(r->cameras[i]) - 1] == '/')
			return tl_error(err, err_size, TL_ERR_ARG, "cameras: '%s' names no camera path", r->cameras[i]);
	/* SCENE/CAMERA entries must name a scene of the sweep (checked after loading: names come from the files) */
	s->scene_count = r->scene_count;
	for (size_t i = 0; i < r->scene_count; i++)
		if ((rc = resolve_scene(r, i, s, err, err_size)))
			return rc;
	for (size_t k = 0; k < r->camera_count; k++) {
		const char *slash = strchr(r->cameras[k], '/');
		bool ok = !slash;
		for (size_t i = 0; slash && i < s->scene_count; i++)
			ok |= strlen(s->scenes[i].name) == (size_t)(slash - r->cameras[k]) &&
			      !strncmp(s->scenes[i].name, r->cameras[k], (size_t)(slash - r->cameras[k]));
		if (!ok)
			return tl_error(err, err_size, TL_ERR_ARG, "cameras: '%s' names a scene that is not in --scenes",
					r->cameras[k]);
	}
	for (size_t i = 0; i < s->scene_count; i++)
		if (!s->scenes[i].camera_count)
			return tl_error(err, err_size, TL_ERR_ARG,
					"cameras: none chosen for scene '%s' (the SCENE/CAMERA entries name other scenes)",
					s->scenes[i].name);
	colour *col = NULL;
	colour_desc cd = {.config_path = s->ocio_config[0] ? s->ocio_config : NULL, .display = s->display[0] ? s->display : NULL,
			  .view = s->view[0] ? s->view : NULL};
	if ((rc = colour_create(&cd, &col, err, err_size)))
		return rc;
	snprintf(s->display_transform, sizeof s->display_transform, "%s", colour_name(col));
	colour_digest(col, s->colour_digest);
	colour_destroy(&col);
	return TL_OK;
}
