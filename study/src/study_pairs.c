/* study_pairs.c — study stimuli from a sweep's runs (issue 27.13; study.h sty_pairs_from_sweep): one pairs.json set
 * per scene x camera path of the sweep, whose clips are the sweep's own clips (hard links, or copies across file
 * systems), so the clips rated are the clips the sweep measured and nothing is rendered twice. The set records
 * where its clips came from (pairs.h "source", "sweep_run") and the runs' input digests, which the sweep report
 * checks before it joins the study to the sweep (study_report_check.c). */
#define _DEFAULT_SOURCE /* realpath */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "study_internal.h"
#include "taslab/pairs.h"
#include "taslab/run.h"
#include "taslab/sweep.h"

/* dst as a hard link to src, or a copy of it (another file system); never over an existing file. */
static int link_or_copy(const char *src, const char *dst, char *err, size_t err_size)
{
	if (!link(src, dst))
		return TL_OK;
	if (errno != EXDEV && errno != EPERM && errno != EMLINK)
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot link %s: %s", dst, src, strerror(errno));
	char *data = NULL;
	size_t size = 0;
	int rc = tl_read_file(src, (size_t)1 << 34, &data, &size, err, err_size);
	if (!rc)
		rc = tl_write_file(dst, data, size, err, err_size);
	free(data);
	return rc;
}

#define NO_VARIANT (-1) /* variant_of: the sweep has no such variant */

/* Index of the spec's variant whose token or id is `token`, or NO_VARIANT. */
static int variant_of(const sweep_spec *sp, const char *token)
{
	for (size_t v = 0; v < sp->variant_count; v++)
		if (!strcmp(sp->variants[v].variant, token) || !strcmp(sp->variants[v].id, token))
			return (int)v;
	return NO_VARIANT;
}

/* The sweep's reference variant: the one of its reference runs (the plan says which; the study names no method). */
static int ref_variant(const sweep_spec *sp)
{
	sweep_run r;
	for (size_t i = 0, n = sweep_run_count(sp); i < n; i++)
		if (!sweep_run_at(sp, i, &r) && r.is_ref)
			return (int)r.variant;
	return NO_VARIANT;
}

/* The plan's run of scene sc, camera c and variant v. */
static int run_of(const sweep_spec *sp, size_t sc, size_t c, size_t v, sweep_run *out)
{
	size_t n = sweep_run_count(sp);
	for (size_t i = 0; i < n; i++)
		if (!sweep_run_at(sp, i, out) && out->scene == sc && out->camera == c && out->variant == v)
			return TL_OK;
	return TL_ERR_ARG;
}

/* A run of the sweep, complete with its clip (checked as the sweep checks it), and its manifest. */
static int complete_run(const sweep_spec *sp, const char *sweep, const sweep_run *r, run_manifest *m, char *clip,
			size_t clip_size, char *rel, size_t rel_size, char *err, size_t err_size)
{
	char run[TL_PATH_MAX], why[1024] = "";
	sweep_status st;
	sweep_run_path(sp, sweep, r, SWEEP_PATH_RUN, run, sizeof run);
	sweep_run_path(sp, sweep, r, SWEEP_PATH_CLIP, clip, clip_size);
	sweep_run_status_checked(sp, sweep, r, &st, why, sizeof why);
	if (!st.run || !st.clip)
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: %s (finish the sweep first: taslab sweep %s/sweep.json)", run,
				st.damaged ? why : !st.run ? "the run is not complete" : "the run has no clip", sweep);
	sweep_run_path(sp, "", r, SWEEP_PATH_RUN, rel, rel_size);
	memmove(rel, rel + 1, strlen(rel)); /* "/runs/..." -> "runs/..." */
	return run_manifest_read(run, m, err, err_size);
}

/* One set: OUT/<scene>--<camera>/ with clips/ (the sweep's clips) and pairs.json, written last. */
static int write_set(const sweep_spec *sp, const char *sweep, size_t sc, size_t c, const int *vars, size_t nv,
		     const char *out, char *err, size_t err_size)
{
	const sweep_scene *scn = &sp->scenes[sc];
	char dir[TL_PATH_MAX], path[TL_PATH_MAX + 300], clip[TL_PATH_MAX], rel[512];
	snprintf(dir, sizeof dir, "%s/%s--%s", out, scn->name, scn->cameras[c].name);
	snprintf(path, sizeof path, "%s/clips", dir);
	int rc = tl_mkdirs(path, err, err_size);
	if (rc)
		return rc;
	pairs_condition *conds = calloc(nv ? nv : 1, sizeof *conds);
	run_manifest *m = malloc(sizeof *m);
	if (!conds || !m) {
		free(conds);
		free(m);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	pairs_set set = {.fps = scn->fps, .first_frame = scn->first, .last_frame = scn->end - 1, .width = sp->width,
			 .height = sp->height, .conditions = conds, .views = sp->stereo ? 2 : 1, .ipd = sp->ipd};
	snprintf(set.scene, sizeof set.scene, "%s", scn->name);
	snprintf(set.scene_path, sizeof set.scene_path, "%s", scn->path);
	snprintf(set.camera, sizeof set.camera, "%s", scn->cameras[c].name);
	snprintf(set.camera_motion, sizeof set.camera_motion, "%s", scn->cameras[c].motion);
	snprintf(set.display_transform, sizeof set.display_transform, "%s", sp->display_transform);
	snprintf(set.sweep, sizeof set.sweep, "%s", sweep);
	snprintf(set.ref_clip, sizeof set.ref_clip, "clips/ref.webm");
	sweep_run r;
	int ref = ref_variant(sp);
	if (ref < 0 || run_of(sp, sc, c, (size_t)ref, &r)) {
		rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: the sweep has no ref run of %s/%s", sweep, scn->name,
			      scn->cameras[c].name);
		goto done;
	}
	if ((rc = complete_run(sp, sweep, &r, m, clip, sizeof clip, set.sweep_ref_run, sizeof set.sweep_ref_run, err,
			       err_size)))
		goto done;
	snprintf(set.ref_method, sizeof set.ref_method, "%s", m->method);
	snprintf(set.scene_digest, sizeof set.scene_digest, "%s", m->scene_digest);
	snprintf(set.colour_digest, sizeof set.colour_digest, "%s", m->colour_digest);
	snprintf(path, sizeof path, "%s/%s", dir, set.ref_clip);
	if ((rc = link_or_copy(clip, path, err, err_size)))
		goto done;
	for (size_t k = 0; k < nv; k++) {
		const sweep_variant *v = &sp->variants[vars[k]];
		pairs_condition *pc = &conds[set.count];
		if ((rc = run_of(sp, sc, c, (size_t)vars[k], &r)) ||
		    (rc = complete_run(sp, sweep, &r, m, clip, sizeof clip, rel, sizeof rel, err, err_size)))
			goto done;
		if (!m->facts.known) {
			rc = tl_error(err, err_size, TL_ERR_INPUT, "%s/%s: its manifest has no method_facts (rendered before "
								 "issue 30.1): render the sweep again",
				      sweep, rel);
			goto done;
		}
		snprintf(pc->id, sizeof pc->id, "%s", v->id);
		snprintf(pc->method, sizeof pc->method, "%s", v->method);
		snprintf(pc->variant, sizeof pc->variant, "%s", v->variant);
		pc->T = v->T;
		pc->period = v->period;
		pc->facts = m->facts;
		snprintf(pc->sweep_run, sizeof pc->sweep_run, "%s", rel);
		snprintf(pc->clip, sizeof pc->clip, "clips/%s.webm", v->id);
		snprintf(path, sizeof path, "%s/%s", dir, pc->clip);
		if ((rc = link_or_copy(clip, path, err, err_size)))
			goto done;
		set.count++;
	}
	snprintf(path, sizeof path, "%s/pairs.json", dir);
	rc = pairs_write(path, &set, err, err_size);
done:
	free(conds);
	free(m);
	return rc;
}

int sty_pairs_from_sweep(const sty_pairs_desc *d, size_t *sets, char *err, size_t err_size)
{
	char path[TL_PATH_MAX + 32], sweep[TL_PATH_MAX];
	*sets = 0;
	if (!realpath(d->sweep, sweep))
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: %s (give a sweep folder, the one holding sweep.json)", d->sweep,
				strerror(errno));
	snprintf(path, sizeof path, "%s/sweep.json", sweep);
	if (!tl_is_file(path))
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: not a sweep folder (no sweep.json)", d->sweep);
	/* Outputs are new: a folder that exists must be empty, so no earlier set is mixed in or replaced. */
	if (tl_is_dir(d->out)) {
		int fd = open(d->out, O_RDONLY | O_DIRECTORY);
		bool empty = true;
		if (fd >= 0) {
			DIR *dd = fdopendir(fd);
			for (struct dirent *e; dd && (e = readdir(dd));)
				empty &= !strcmp(e->d_name, ".") || !strcmp(e->d_name, "..");
			if (dd)
				closedir(dd);
			else
				close(fd);
		}
		if (!empty)
			return tl_error(err, err_size, TL_ERR_INPUT, "%s is not empty: give a new folder for the stimuli", d->out);
	} else if (tl_is_file(d->out))
		return tl_error(err, err_size, TL_ERR_INPUT, "%s is a file: give a new folder for the stimuli", d->out);
	sweep_spec *sp = malloc(sizeof *sp);
	int *vars = malloc(SWEEP_MAX_VARIANTS * sizeof *vars);
	size_t nv = 0;
	int rc = !sp || !vars ? tl_error(err, err_size, TL_ERR_NOMEM, "out of memory") : sweep_spec_read(path, sp, err, err_size);
	int refv = rc ? NO_VARIANT : ref_variant(sp);
	if (!rc && refv < 0)
		rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: the sweep has no reference runs", d->sweep);
	/* The variants: those asked for (tokens or ids of the sweep), else every one but the reference. */
	for (size_t k = 0; !rc && k < d->variant_count; k++) {
		int v = variant_of(sp, d->variants[k]);
		char list[2048] = "";
		if (v < 0 || v == refv) {
			for (size_t q = 0; q < sp->variant_count; q++)
				if ((int)q != refv && strlen(list) + strlen(sp->variants[q].variant) + 3 < sizeof list)
					strcat(strcat(list, list[0] ? ", " : ""), sp->variants[q].variant);
			rc = tl_error(err, err_size, TL_ERR_ARG, "--variants: '%s' is not a variant of %s%s (it has %s)",
				      d->variants[k], d->sweep, v >= 0 ? " other than its reference" : "", list);
			break;
		}
		for (size_t q = 0; q < nv; q++)
			if (vars[q] == v)
				rc = tl_error(err, err_size, TL_ERR_ARG, "--variants: '%s' is listed twice", d->variants[k]);
		vars[nv++] = v;
	}
	for (size_t v = 0; !rc && !d->variant_count && v < sp->variant_count; v++)
		if ((int)v != refv)
			vars[nv++] = (int)v;
	if (!rc && !nv)
		rc = tl_error(err, err_size, TL_ERR_ARG, "%s holds only reference runs: no pairs to make", d->sweep);
	/* Every run is checked (complete, with its clip and method facts) before anything is written. */
	run_manifest *m = rc ? NULL : malloc(sizeof *m);
	if (!rc && !m)
		rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	for (size_t sc = 0; !rc && sc < sp->scene_count; sc++)
		for (size_t c = 0; !rc && c < sp->scenes[sc].camera_count; c++)
			for (size_t k = 0; !rc && k <= nv; k++) {
				sweep_run r;
				char clip[TL_PATH_MAX], rel[512];
				int v = k < nv ? vars[k] : refv;
				if (v < 0 || run_of(sp, sc, c, (size_t)v, &r))
					rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: no run of %s in %s/%s", d->sweep,
						      v < 0 ? "the reference" : sp->variants[v].variant, sp->scenes[sc].name,
						      sp->scenes[sc].cameras[c].name);
				else
					rc = complete_run(sp, sweep, &r, m, clip, sizeof clip, rel, sizeof rel, err, err_size);
				if (!rc && k < nv && !m->facts.known)
					rc = tl_error(err, err_size, TL_ERR_INPUT, "%s/%s: its manifest has no method_facts "
										 "(rendered before issue 30.1): render it again",
						      sweep, rel);
			}
	free(m);
	for (size_t sc = 0; !rc && sc < sp->scene_count; sc++)
		for (size_t c = 0; !rc && c < sp->scenes[sc].camera_count; c++)
			if (!(rc = write_set(sp, sweep, sc, c, vars, nv, d->out, err, err_size)))
				(*sets)++;
	free(sp);
	free(vars);
	return rc;
}
