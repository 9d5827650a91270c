#define _XOPEN_SOURCE 700 /* realpath */
/* sweep_resolve.c — the sweep key table (output/sweep_keys.h) as `taslab sweep` options and their overlay onto a
 * request, and a sweep request (file and/or options) resolved against the scene files and the method registry into
 * the spec written to SWEEP/sweep.json (sweep_cli.h, output/sweep.h; DESIGN sections 4 and 9, issue 30.2). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sweep_cli.h"
#include "taslab/colour.h"
#include "taslab/method.h"
#include "taslab/metrics.h"
#include "taslab/metrics_flip.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/sweep_keys.h"
#include "taslab/tl_hash.h"

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

/* "--ocio-config" for the key "ocio_config". */
static void key_flag(const sweep_key *k, char *out, size_t n)
{
	snprintf(out, n, "--%s", k->name);
	for (char *p = out; *p; p++)
		if (*p == '_')
			*p = '-';
}

static bool key_given(const sweep_key *k, const sweep_cli_value *v)
{
	switch (k->type) {
	case SWEEP_KEY_SIZE: return v->size[0] > 0;
	case SWEEP_KEY_NUMBER: return v->number > 0;
	case SWEEP_KEY_WHOLE: return v->whole > 0;
	case SWEEP_KEY_BOOL: return v->flag;
	default: return v->text != NULL;
	}
}

const cli_opt *cli_sweep_key_options(void)
{
	/* as cli_method_options: the table is built from the key table on first use and stays */
	static cli_opt table[SWEEP_CLI_KEYS_MAX + 1];
	static char names[SWEEP_CLI_KEYS_MAX][40];
	if (table[0].name)
		return table;
	size_t n;
	const sweep_key *keys = sweep_keys(&n);
	for (size_t i = 0; i < n && i < SWEEP_CLI_KEYS_MAX; i++) {
		static const cli_opt_type types[SWEEP_KEY_TYPE_COUNT] = {
			[SWEEP_KEY_NAMES] = CLI_STRING, [SWEEP_KEY_NUMBERS] = CLI_STRING, [SWEEP_KEY_WHOLES] = CLI_STRING,
			[SWEEP_KEY_STRING] = CLI_STRING, [SWEEP_KEY_FRAMES] = CLI_STRING,  [SWEEP_KEY_SIZE] = CLI_SIZE,
			[SWEEP_KEY_NUMBER] = CLI_DOUBLE, [SWEEP_KEY_WHOLE] = CLI_UINT,      [SWEEP_KEY_BOOL] = CLI_FLAG,
		};
		char flag[48];
		key_flag(&keys[i], flag, sizeof flag);
		snprintf(names[i], sizeof names[i], "%s", flag + 2);
		table[i] = (cli_opt){.name = names[i], .arg = keys[i].type == SWEEP_KEY_BOOL ? NULL : keys[i].arg,
				     .help = keys[i].help, .type = types[keys[i].type],
				     .offset = offsetof(sweep_opts, keys) + i * sizeof(sweep_cli_value), .lo = keys[i].lo,
				     .hi = keys[i].hi};
	}
	return table;
}

bool cli_sweep_opt_given(const sweep_opts *o, const char *name)
{
	size_t n;
	const sweep_key *keys = sweep_keys(&n), *k = sweep_key_find(name);
	return k && key_given(k, &o->keys[k - keys]);
}

bool cli_sweep_opts_change_spec(const sweep_opts *o)
{
	size_t n;
	const sweep_key *keys = sweep_keys(&n);
	for (size_t i = 0; i < n; i++)
		if (!(keys[i].flags & SWEEP_KEY_RESUME_OK) && key_given(&keys[i], &o->keys[i]))
			return true;
	return false;
}

void cli_sweep_keys_help(FILE *out)
{
	size_t n;
	const sweep_key *keys = sweep_keys(&n);
	fprintf(out, "\nsweep settings (each also a sweep file key: NAME with '_' for '-'; lists comma-separated here):\n");
	for (size_t i = 0; i < n; i++) {
		char flag[48], left[80];
		key_flag(&keys[i], flag, sizeof flag);
		snprintf(left, sizeof left, "%s%s%s", flag, keys[i].arg ? " " : "", keys[i].arg ? keys[i].arg : "");
		cli_print_option(out, 0, left, keys[i].help);
	}
}

int cli_sweep_request_from_opts(const sweep_opts *o, sweep_request *r, char *err, size_t err_size)
{
	size_t nkeys;
	const sweep_key *keys = sweep_keys(&nkeys);
	int rc = TL_OK;
	for (size_t i = 0; !rc && i < nkeys; i++) {
		const sweep_key *k = &keys[i];
		const sweep_cli_value *v = &o->keys[i];
		char flag[48], *f = (char *)r + k->offset;
		size_t *count = (size_t *)((char *)r + k->count_offset);
		if (!key_given(k, v))
			continue;
		key_flag(k, flag, sizeof flag);
		switch (k->type) {
		case SWEEP_KEY_NAMES: {
			bool *all = k->all ? (bool *)((char *)r + k->all_offset) : NULL;
			*count = 0;
			if (all && (*all = !strcmp(v->text, k->all)))
				break;
			rc = split_into(v->text, flag, f, k->size, k->max, count, err, err_size);
			break;
		}
		case SWEEP_KEY_NUMBERS: {
			/* through float, as --threshold (a variant's T is a float: tfr@8.1 names the T it renders) */
			float x[SWEEP_MAX_VALUES];
			rc = cli_parse_float_list(v->text, flag, k->lo, k->hi, x, k->max < SWEEP_MAX_VALUES ? k->max : SWEEP_MAX_VALUES,
						  count, err, err_size);
			for (size_t j = 0; !rc && j < *count; j++)
				((double *)f)[j] = x[j];
			break;
		}
		case SWEEP_KEY_WHOLES: {
			char buf[512];
			const char *items[SWEEP_MAX_VALUES];
			rc = cli_split_list(v->text, flag, buf, sizeof buf, items, k->max < SWEEP_MAX_VALUES ? k->max : SWEEP_MAX_VALUES,
					    count, err, err_size);
			for (size_t j = 0; !rc && j < *count; j++) {
				uint64_t u;
				rc = cli_parse_uint(items[j], flag, (uint64_t)k->lo, (uint64_t)k->hi, &u, err, err_size);
				((uint32_t *)f)[j] = (uint32_t)u;
			}
			break;
		}
		case SWEEP_KEY_STRING:
		case SWEEP_KEY_FRAMES: /* --frames is checked against each scene's clip by the resolver */
			if (strlen(v->text) >= k->size)
				return tl_error(err, err_size, TL_ERR_ARG, "%s is too long", flag);
			snprintf(f, k->size, "%s", v->text);
			break;
		case SWEEP_KEY_SIZE: memcpy(f, v->size, sizeof v->size); break;
		case SWEEP_KEY_NUMBER: *(double *)f = v->number; break;
		case SWEEP_KEY_WHOLE: *(uint32_t *)f = v->whole; break;
		case SWEEP_KEY_BOOL: *(bool *)f = true; break;
		default: return tl_error(err, err_size, TL_ERR_INTERNAL, "sweep key %s: bad table line", k->name);
		}
		r->set |= sweep_key_bit(k);
	}
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
		if (m->options[k].variant == '-' && m->options[k].type == METHOD_OPT_BOOL && nflags < 8)
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
	/* the settings a sweep keeps as given (device, validation, truth, the display transform's config, display and
	 * view, ...: the SWEEP_KEY_SPEC keys); size, baseline, metrics and ppd get their defaults below */
	sweep_spec_copy_keys(s, r);
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
	if (r->ipd > 0 && !r->stereo)
		return tl_error(err, err_size, TL_ERR_ARG, "ipd needs stereo (--ipd goes with --stereo)");
	s->ipd = s->stereo ? (r->ipd > 0 ? r->ipd : RENDER_STEREO_IPD_DEFAULT) : 0.0;
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
	/* the sweep's identity holds the build */
	snprintf(s->build_digest, sizeof s->build_digest, "%s", tl_build_digest());
	return TL_OK;
}
