/* study_report_check.c — before the sweep report joins a study (issue 27.12): are the clips the participants rated
 * the clips of this sweep's runs? Every pairs.json set of the study's stimulus folder is compared with the sweep —
 * frames, size, fps, display transform and the input digests of scene and colour (run.h), and for a set taken from
 * a sweep (`taslab study pairs`) each clip's bytes with the sweep's clip of the same run. A mismatch refuses the
 * study with one line (the ratings are of other clips); what cannot be checked (an imported study, a stimulus folder
 * gone) and the study's conditions no run of the sweep has are said on stderr and on the page. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_internal.h"
#include "study_report_internal.h"
#include "taslab/pairs.h"
#include "taslab/run.h"

/* Same bytes: the same file (a hard link), or equal contents. */
static bool same_bytes(const char *a, const char *b)
{
	if (tl_same_file(a, b))
		return true;
	char *x = NULL, *y = NULL, why[256];
	size_t nx = 0, ny = 0;
	bool same = !tl_read_file(a, (size_t)1 << 32, &x, &nx, why, sizeof why) &&
		    !tl_read_file(b, (size_t)1 << 32, &y, &ny, why, sizeof why) && nx == ny && !memcmp(x, y, nx);
	free(x);
	free(y);
	return same;
}

/* The sweep's scene and camera of a set, or false. */
static bool find_group(const sweep_spec *sp, const pairs_set *set, size_t *sc, size_t *cam)
{
	for (size_t i = 0; i < sp->scene_count; i++)
		for (size_t c = 0; c < sp->scenes[i].camera_count; c++)
			if (!strcmp(sp->scenes[i].name, set->scene) && !strcmp(sp->scenes[i].cameras[c].name, set->camera)) {
				*sc = i, *cam = c;
				return true;
			}
	return false;
}

/* What differs between a set and the sweep ("" when nothing): the first difference, as "size 64x36 (the sweep's
 * 32x18)". `dir` is the set's folder. */
static void set_difference(const sty_report_desc *d, const pairs_set *set, const char *dir, char *why, size_t n)
{
	const sweep_spec *sp = d->spec;
	size_t sc, cam;
	why[0] = 0;
	if (!find_group(sp, set, &sc, &cam))
		return; /* its conditions have no run: listed as missing, not a mismatch */
	const sweep_scene *s = &sp->scenes[sc];
	char scene_digest[24], colour_digest[24];
	snprintf(scene_digest, sizeof scene_digest, "%s", set->scene_digest);
	snprintf(colour_digest, sizeof colour_digest, "%s", set->colour_digest);
	if ((!scene_digest[0] || !colour_digest[0]) && set->ref_run[0]) { /* a set of `taslab pair`: its ref run says */
		char run[TL_PATH_MAX + 300], e[512];
		run_manifest *m = malloc(sizeof *m);
		snprintf(run, sizeof run, "%s/%s", dir, set->ref_run);
		if (m && !run_manifest_read(run, m, e, sizeof e)) {
			if (!scene_digest[0])
				snprintf(scene_digest, sizeof scene_digest, "%s", m->scene_digest);
			if (!colour_digest[0])
				snprintf(colour_digest, sizeof colour_digest, "%s", m->colour_digest);
		}
		free(m);
	}
	if (set->first_frame != s->first || set->last_frame + 1 != s->end)
		snprintf(why, n, "frames %u..%u (the sweep's %u..%u)", set->first_frame, set->last_frame, s->first, s->end - 1);
	else if (set->width && (set->width != sp->width || set->height != sp->height))
		snprintf(why, n, "size %ux%u (the sweep's %ux%u)", set->width, set->height, sp->width, sp->height);
	else if (fabs(set->fps - s->fps) > 1e-6)
		snprintf(why, n, "%g fps (the sweep's %g)", set->fps, s->fps);
	else if (set->display_transform[0] && strcmp(set->display_transform, sp->display_transform))
		snprintf(why, n, "display transform '%s' (the sweep's '%s')", set->display_transform, sp->display_transform);
	else if (colour_digest[0] && sp->colour_digest[0] && strcmp(colour_digest, sp->colour_digest))
		snprintf(why, n, "another colour configuration (colour digest %s, the sweep's %s)", colour_digest,
			 sp->colour_digest);
	else if (scene_digest[0] && s->digest[0] && strcmp(scene_digest, s->digest))
		snprintf(why, n, "another scene %s (scene digest %s, the sweep's %s)", s->name, scene_digest, s->digest);
	if (why[0] || !set->sweep[0])
		return;
	/* A set from a sweep: its clips must be this sweep's clips (the same run, rendered once). */
	for (size_t i = 0; i < set->count; i++) {
		const pairs_condition *c = &set->conditions[i];
		char mine[TL_PATH_MAX + 300], theirs[TL_PATH_MAX + 300];
		size_t v = 0;
		while (v < sp->variant_count && strcmp(sp->variants[v].variant, c->variant))
			v++;
		if (v == sp->variant_count)
			continue; /* a condition the sweep lacks: listed as missing */
		snprintf(mine, sizeof mine, "%s/%s", dir, c->clip);
		snprintf(theirs, sizeof theirs, "%s/clips/%s/%s/%s.webm", d->dir, s->name, s->cameras[cam].name,
			 sp->variants[v].id);
		if (tl_is_file(theirs) && !same_bytes(mine, theirs)) {
			snprintf(why, n, "clip %s is not the sweep's clip of %s (%s)", c->clip, c->variant, theirs);
			return;
		}
	}
}

/* Appends "; text" (or "text") to a note. */
static void note_add(char *note, size_t n, const char *text)
{
	size_t len = strlen(note);
	if (len + 3 < n)
		snprintf(note + len, n - len, "%s%s", len ? "; " : "", text);
}

int sty_rpt_study_check(sty *s, const sty_report_desc *d, const char *db, sty_rpt_study *t, char *err,
			size_t err_size)
{
	if (!s->stimuli[0]) {
		snprintf(t->unchecked, sizeof t->unchecked, "the study has no stimulus folder (imported ratings): its clips "
							    "were not checked against the sweep's runs");
		return TL_OK;
	}
	if (!tl_is_dir(s->stimuli)) {
		snprintf(t->unchecked, sizeof t->unchecked, "the study's stimulus folder %s is gone: its clips were not "
							    "checked against the sweep's runs",
			 s->stimuli);
		return TL_OK;
	}
	/* The sets the design read: ROOT/pairs.json and ROOT/<name>/pairs.json, as the conditions' clips name them. */
	sqlite3_stmt *st;
	if (sqlite3_prepare_v2(s->db, "SELECT DISTINCT ref_clip FROM conditions ORDER BY ref_clip", -1, &st, NULL))
		return sty_db_fail(s, err, err_size, "report");
	char done[64][256];
	size_t nd = 0;
	int rc = TL_OK;
	while (!rc && sqlite3_step(st) == SQLITE_ROW) {
		const char *ref = (const char *)sqlite3_column_text(st, 0);
		char rel[256] = "", dir[TL_PATH_MAX + 300], file[TL_PATH_MAX + 320], why[1024];
		const char *slash = strchr(ref, '/');
		snprintf(dir, sizeof dir, "%s", s->stimuli);
		if (slash) { /* ROOT/<name>/pairs.json when it exists, else ROOT/pairs.json */
			snprintf(rel, sizeof rel, "%.*s", (int)(slash - ref), ref);
			snprintf(file, sizeof file, "%s/%s/pairs.json", s->stimuli, rel);
			if (tl_is_file(file))
				snprintf(dir, sizeof dir, "%s/%s", s->stimuli, rel);
			else
				rel[0] = 0;
		}
		bool seen = false;
		for (size_t k = 0; k < nd; k++)
			seen |= !strcmp(done[k], rel);
		if (seen)
			continue;
		if (nd < 64)
			snprintf(done[nd++], sizeof done[0], "%s", rel);
		snprintf(file, sizeof file, "%s/pairs.json", dir);
		pairs_set set;
		if (pairs_read(file, &set, why, sizeof why)) {
			char note[1200];
			snprintf(note, sizeof note, "%s: not checked (%s)", file, why);
			note_add(t->unchecked, sizeof t->unchecked, note);
			continue;
		}
		set_difference(d, &set, dir, why, sizeof why);
		if (why[0])
			rc = tl_error(err, err_size, TL_ERR_INPUT,
				      "%s: its stimuli %s (%s/%s) are not this sweep's runs: %s; the ratings are of other "
				      "clips (report the study with the sweep its stimuli came from: taslab study pairs --sweep)",
				      db, file, set.scene, set.camera, why);
		pairs_free(&set);
	}
	sqlite3_finalize(st);
	return rc;
}

void sty_rpt_study_missing(const sty_report_desc *d, sty_rpt_study *t)
{
	t->missing[0] = 0;
	t->missing_count = 0;
	for (size_t i = 0; i < t->n; i++) {
		const sty_rpt_cond *c = &t->c[i];
		if (!strcmp(c->scene, "all"))
			continue; /* pooled rows join nothing */
		bool found = false;
		for (size_t k = 0; k < d->count && !found; k++)
			found = sty_rpt_study_find(t, d->spec, &d->rows[k]) == c;
		if (found)
			continue;
		char name[256];
		if (isnan(c->T) && !c->period)
			snprintf(name, sizeof name, "%s %s/%s", c->method, c->scene, c->camera);
		else if (c->period)
			snprintf(name, sizeof name, "%s/%u %s/%s", c->method, c->period, c->scene, c->camera);
		else
			snprintf(name, sizeof name, "%s@%g %s/%s", c->method, c->T, c->scene, c->camera);
		t->missing_count++;
		note_add(t->missing, sizeof t->missing, name);
	}
}
