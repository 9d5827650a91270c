/* study_design.c — a study's design (study.h sty_design): the DESIGN section 4 rule for a condition, conditions
 * from the pairs.json sets of a stimulus folder, catch trials, and the randomised per-participant plans. */
#define _DEFAULT_SOURCE /* realpath */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "study_adaptive_db.h"
#include "taslab/study_model.h"
#include "study_internal.h"
#include "study_plan.h"
#include "taslab/pairs.h"
#include "taslab/tl_fs.h"

int sty_describe_method(sty *s, const char *method, const run_method_facts *facts, char *err, size_t err_size)
{
	size_t i = 0;
	while (i < s->method_count && strcmp(s->methods[i].name, method))
		i++;
	if (strlen(method) >= sizeof s->methods[0].name || i == STY_MAX_METHODS)
		return tl_error(err, err_size, TL_ERR_ARG, "method '%s': name too long, or more than %d methods", method,
				STY_MAX_METHODS);
	snprintf(s->methods[i].name, sizeof s->methods[i].name, "%s", method);
	s->methods[i].facts = *facts;
	s->methods[i].facts.known = true;
	if (i == s->method_count)
		s->method_count++;
	return TL_OK;
}

const run_method_facts *sty_method_facts(const sty *s, const char *method)
{
	for (size_t i = 0; i < s->method_count; i++)
		if (!strcmp(s->methods[i].name, method))
			return &s->methods[i].facts;
	return NULL;
}

const char *sty_reference_method(const sty *s)
{
	for (size_t i = 0; i < s->method_count; i++)
		if (s->methods[i].facts.reference)
			return s->methods[i].name;
	return NULL;
}

bool sty_period_valid(long period) { return period == 1 || period == 2 || period == 4 || period == 8; }

int sty_condition_rule(const run_method_facts *f, const char *method, double T, long period, char *why,
		       size_t why_size)
{
	bool has_T = f && f->takes_threshold, has_N = f && f->takes_period;
	if (!f || !f->known) /* issue 30.1: no list of names here; the registry or pairs.json describes each method */
		snprintf(why, why_size, "method '%s' is not one of the methods taslab knows (its method registry, or "
			 "pairs.json's method_facts)", method);
	else if (has_T && isnan(T))
		snprintf(why, why_size, "method %s needs a threshold T", method);
	else if (!has_T && !isnan(T))
		snprintf(why, why_size, "method %s has no threshold T (leave T empty)", method);
	else if (has_N && !period)
		snprintf(why, why_size, "method %s needs a period (1, 2, 4 or 8)", method);
	else if (!has_N && period)
		snprintf(why, why_size, "method %s has no period (leave period empty)", method);
	else if (has_N && !sty_period_valid(period))
		snprintf(why, why_size, "period %ld of method %s is not 1, 2, 4 or 8", period, method);
	else
		return TL_OK;
	return TL_ERR_INPUT;
}

/* ------------------------------------------------------------------ design */

typedef struct cond {
	char scene[64], camera[64], motion[16], method[32];
	double T;        /* NAN: none */
	uint32_t period; /* 0: none */
	char ref_clip[512], test_clip[512];
	int is_catch;    /* role: 0 test, 1 catch (reference against itself), 2 gold (a copy of a test condition) */
	char id[64];     /* the pairs.json condition id ("tfr-T64") */
	char ref_method[32]; /* the reference's method name (pairs.json reference.method), for added catch trials */
	double clip_ms;      /* a clip's duration from pairs.json frames and fps (the server's playback check) */
} cond;

/* Reads one pairs.json (from `taslab pair`, output/pairs.h) into conditions; `rel` is its folder relative to
 * the stimuli. Every clip it names must exist, so a session never fails midway on a missing file. */
static int read_pairs(const sty *s, const char *file, const char *rel, cond **cs, size_t *n, uint32_t *views, char *err,
		      size_t err_size)
{
	pairs_set set;
	int rc = pairs_read(file, &set, err, err_size);
	if (rc)
		return rc;
	/* One kind of display per study (STEREO.md "studies add display=stereo"): the page shows every clip one way. */
	if (*views && set.views != *views) {
		pairs_free(&set);
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: a %s set in a study of %s sets: make stereo and mono sets two "
				"studies (a participant's page shows one kind of clip)", file, *views > 1 ? "mono" : "stereo",
				*views > 1 ? "stereo" : "mono");
	}
	*views = set.views;
	if (strcmp(set.camera_motion, "stationary") && strcmp(set.camera_motion, "moving")) {
		pairs_free(&set);
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: camera_motion must be stationary or moving", file);
	}
	char dir[TL_PATH_MAX], clip[TL_PATH_MAX];
	snprintf(dir, sizeof dir, "%s", file);
	char *slash = strrchr(dir, '/');
	if (slash)
		*slash = 0;
	else
		snprintf(dir, sizeof dir, ".");
	for (size_t i = 0; i <= set.count; i++) {
		snprintf(clip, sizeof clip, "%s/%s", dir, i < set.count ? set.conditions[i].clip : set.ref_clip);
		if (!tl_is_file(clip)) {
			pairs_free(&set);
			return tl_error(err, err_size, TL_ERR_INPUT, "%s: clip %s does not exist (render the set again with 'taslab pair')",
					file, clip);
		}
	}
	/* The same rule as import: T and period exactly as the method has them (DESIGN section 4). */
	for (size_t i = 0; i < set.count; i++) {
		const pairs_condition *c = &set.conditions[i];
		char why[160];
		const run_method_facts *f = c->facts.known ? &c->facts : sty_method_facts(s, c->method);
		if (sty_condition_rule(f, c->method, c->T, (long)c->period, why, sizeof why)) {
			rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: condition '%s': %s", file, c->id, why);
			pairs_free(&set);
			return rc;
		}
	}
	for (size_t i = 0; i < set.count; i++) {
		const pairs_condition *c = &set.conditions[i];
		cond *nc = realloc(*cs, (*n + 1) * sizeof *nc);
		if (!nc) {
			pairs_free(&set);
			return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		}
		*cs = nc;
		cond *x = &nc[(*n)++];
		memset(x, 0, sizeof *x);
		snprintf(x->scene, sizeof x->scene, "%s", set.scene);
		snprintf(x->camera, sizeof x->camera, "%s", set.camera);
		snprintf(x->motion, sizeof x->motion, "%s", set.camera_motion);
		snprintf(x->method, sizeof x->method, "%s", c->method);
		x->T = c->T;
		x->period = c->period;
		snprintf(x->id, sizeof x->id, "%s", c->id);
		x->clip_ms = set.fps > 0 ? (double)(set.last_frame - set.first_frame + 1) * 1000.0 / set.fps : NAN;
		snprintf(x->ref_clip, sizeof x->ref_clip, "%s%s%s", rel, rel[0] ? "/" : "", set.ref_clip);
		snprintf(x->test_clip, sizeof x->test_clip, "%s%s%s", rel, rel[0] ? "/" : "", c->clip);
		/* reference against itself; the facts from the file, else the caller's (checked above) */
		x->is_catch = (c->facts.known ? &c->facts : sty_method_facts(s, c->method))->reference;
		const char *ref = set.ref_method[0] ? set.ref_method : sty_reference_method(s);
		snprintf(x->ref_method, sizeof x->ref_method, "%s", ref ? ref : "");
	}
	pairs_free(&set);
	return TL_OK;
}

/* Gold trials (P.910-crowd's gold questions, README "Telemetry and screening"): per set (one reference clip) a copy of
 * one test condition with role 2 — the one whose pairs.json id is `variant`, else the one with the largest T, else the
 * largest period: the strongest degradation the set has, whose known answer is "reference much better". */
static int add_gold(cond **cs, size_t *nc, const char *variant, char *err, size_t err_size)
{
	size_t n0 = *nc, added = 0;
	for (size_t i = 0; i < n0; i++) {
		size_t first = i, best = SIZE_MAX;
		for (size_t j = 0; j < i && first == i; j++)
			first = strcmp((*cs)[j].ref_clip, (*cs)[i].ref_clip) ? i : j;
		if (first != i)
			continue; /* this set was looked at already */
		for (size_t j = i; j < n0; j++) {
			const cond *c = &(*cs)[j], *b = best == SIZE_MAX ? NULL : &(*cs)[best];
			if (c->is_catch || strcmp(c->ref_clip, (*cs)[i].ref_clip))
				continue;
			if (variant ? !strcmp(c->id, variant)
				    : (isfinite(c->T) && (!b || !isfinite(b->T) || c->T > b->T)) ||
					      (!isfinite(c->T) && c->period && (!b || (!isfinite(b->T) && c->period > b->period))))
				best = j;
		}
		if (best == SIZE_MAX) {
			if (variant)
				return tl_error(err, err_size, TL_ERR_INPUT, "--gold-variant %s: the set of %s / %s has no condition "
						"with that id (pairs.json conditions[].id)", variant, (*cs)[i].scene, (*cs)[i].camera);
			continue;
		}
		cond *ncs = realloc(*cs, (*nc + 1) * sizeof *ncs);
		if (!ncs)
			return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		*cs = ncs;
		ncs[*nc] = ncs[best];
		ncs[(*nc)++].is_catch = 2;
		added++;
	}
	if (!added)
		return tl_error(err, err_size, TL_ERR_INPUT, "--gold: no set has a variant with a T or a period to be the gold "
				"condition; name one with --gold-variant ID (a pairs.json condition id)");
	return TL_OK;
}

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

int sty_design(sty *s, const sty_design_desc *d, sty_design_summary *out, char *err, size_t err_size)
{
	cond *cs = NULL;
	size_t nc = 0;
	int rc = TL_ERR_ARG;
	char **sets = NULL;
	size_t nsets = 0;
	uint32_t views = 0; /* of the sets: 1 mono, 2 stereo (one kind per study) */
	memset(out, 0, sizeof *out);
	if (!d->stimuli || d->participants < 1 || d->participants > 100000) {
		snprintf(err, err_size, "need --stimuli DIR and 1..100000 --participants");
		return TL_ERR_ARG;
	}
	if (d->seed > STY_SEED_MAX)
		return tl_error(err, err_size, TL_ERR_ARG, "--seed %llu: at most %u (GSL's mt19937 keeps 32 bits of a seed)",
				(unsigned long long)d->seed, STY_SEED_MAX);
	if (d->adaptive != (d->trials > 0))
		return tl_error(err, err_size, TL_ERR_ARG, d->adaptive ? "--adaptive needs --trials N (test trials per participant)"
									: "--trials N goes with --adaptive (a full design rates every condition)");
	if (d->gold_variant && !d->gold_trials)
		return tl_error(err, err_size, TL_ERR_ARG, "--gold-variant goes with --gold K (gold trials per participant)");
	if (d->prior) { /* the model is read before anything is written: one line for a file that cannot be a prior */
		double th, sd;
		if (!d->adaptive)
			return tl_error(err, err_size, TL_ERR_ARG, "--prior goes with --adaptive (a full design has no prior)");
		int r = sty_model_prior(d->prior, "", 0, "", "", &th, &sd, err, err_size);
		if (r < 0)
			return r;
	}
	sqlite3_stmt *cnt;
	sqlite3_prepare_v2(s->db, "SELECT (SELECT count(*) FROM conditions) + (SELECT count(*) FROM participants)", -1, &cnt, NULL);
	int used = sqlite3_step(cnt) == SQLITE_ROW && sqlite3_column_int(cnt, 0) > 0;
	sqlite3_finalize(cnt);
	if (used) {
		snprintf(err, err_size, "%s already holds a study design; use a new --db file", s->path);
		return TL_ERR_ARG;
	}
	char root[4096];
	if (!realpath(d->stimuli, root)) {
		snprintf(err, err_size, "%s: %s (give the folder that holds the pairs.json sets)", d->stimuli, strerror(errno));
		return TL_ERR_ARG;
	}
	/* Sets: ROOT/pairs.json and ROOT/<name>/pairs.json, in name order. */
	char p[8192];
	struct stat sb;
	snprintf(p, sizeof p, "%s/pairs.json", root);
	if (stat(p, &sb) == 0 && (sets = malloc(sizeof *sets)))
		sets[nsets++] = strdup("");
	DIR *dir = opendir(root);
	struct dirent *e;
	while (dir && (e = readdir(dir))) {
		if (e->d_name[0] == '.')
			continue;
		snprintf(p, sizeof p, "%s/%s/pairs.json", root, e->d_name);
		if (stat(p, &sb) == 0) {
			char **ns = realloc(sets, (nsets + 1) * sizeof *ns);
			if (!ns)
				break;
			sets = ns;
			sets[nsets++] = strdup(e->d_name);
		}
	}
	if (dir)
		closedir(dir);
	if (nsets == 0) {
		snprintf(err, err_size, "%s: no pairs.json here or one folder below (make sets with 'taslab pair')", root);
		goto done;
	}
	qsort(sets, nsets, sizeof *sets, cmp_str);
	for (size_t i = 0; i < nsets; i++) {
		snprintf(p, sizeof p, "%s%s%s/pairs.json", root, sets[i][0] ? "/" : "", sets[i]);
		if ((rc = read_pairs(s, p, sets[i], &cs, &nc, &views, err, err_size)))
			goto done;
		rc = TL_ERR_ARG;
	}
	size_t ntest = 0, ncatch = 0;
	for (size_t i = 0; i < nc; i++)
		cs[i].is_catch ? ncatch++ : ntest++;
	if (d->adaptive && ntest == 0) {
		snprintf(err, err_size, "%s: --adaptive needs test conditions; the sets hold only reference-vs-reference pairs", root);
		goto done;
	}
	if (ntest == 0 && d->catch_trials == 0) {
		snprintf(err, err_size, "%s: the sets hold only reference-vs-reference pairs; add variants with 'taslab pair --variants'", root);
		goto done;
	}
	/* Catch trials use reference-vs-reference pairs; every set can provide one from its reference clip. */
	if (d->catch_trials)
		for (size_t i = 0, n0 = nc; i < n0; i++) {
			int have = 0;
			for (size_t j = 0; j < nc; j++)
				have |= cs[j].is_catch && !strcmp(cs[j].ref_clip, cs[i].ref_clip);
			if (!have) {
				cond *ncs = realloc(cs, (nc + 1) * sizeof *ncs);
				if (!ncs)
					goto done;
				cs = ncs;
				cs[nc] = cs[i];
				if (!cs[i].ref_method[0]) {
					snprintf(err, err_size, "a pairs.json names no reference method (made by an older taslab); "
						 "make the set again with 'taslab pair'");
					goto done;
				}
				snprintf(cs[nc].method, sizeof cs[nc].method, "%s", cs[i].ref_method);
				cs[nc].T = NAN;
				cs[nc].period = 0;
				snprintf(cs[nc].test_clip, sizeof cs[nc].test_clip, "%s", cs[i].ref_clip);
				cs[nc].is_catch = 1;
				nc++;
				ncatch++;
			}
		}
	if (d->catch_trials && ncatch == 0) {
		snprintf(err, err_size, "no reference clips for catch trials");
		goto done;
	}
	if (d->gold_trials && (rc = add_gold(&cs, &nc, d->gold_variant, err, err_size)))
		goto done;
	rc = TL_ERR_ARG;
	char *msg = NULL;
	if (sqlite3_exec(s->db, "BEGIN IMMEDIATE", NULL, NULL, &msg) != SQLITE_OK) {
		sqlite3_free(msg);
		rc = sty_db_fail(s, err, err_size, "begin");
		goto done;
	}
	sqlite3_stmt *ic;
	sqlite3_prepare_v2(s->db, "INSERT INTO conditions(id, scene, camera, camera_motion, method, T, ref_clip, test_clip, is_catch,"
				  " period, clip_ms) VALUES(?,?,?,?,?,?,?,?,?,?,?)", -1, &ic, NULL);
	int ok = 1;
	for (size_t i = 0; i < nc && ok; i++) {
		sqlite3_reset(ic);
		sqlite3_bind_int64(ic, 1, (sqlite3_int64)i + 1);
		sqlite3_bind_text(ic, 2, cs[i].scene, -1, SQLITE_STATIC);
		sqlite3_bind_text(ic, 3, cs[i].camera, -1, SQLITE_STATIC);
		sqlite3_bind_text(ic, 4, cs[i].motion, -1, SQLITE_STATIC);
		sqlite3_bind_text(ic, 5, cs[i].method, -1, SQLITE_STATIC);
		if (isnan(cs[i].T))
			sqlite3_bind_null(ic, 6);
		else
			sqlite3_bind_double(ic, 6, cs[i].T);
		sqlite3_bind_text(ic, 7, cs[i].ref_clip, -1, SQLITE_STATIC);
		sqlite3_bind_text(ic, 8, cs[i].test_clip, -1, SQLITE_STATIC);
		sqlite3_bind_int(ic, 9, cs[i].is_catch);
		if (cs[i].period)
			sqlite3_bind_int64(ic, 10, cs[i].period);
		else
			sqlite3_bind_null(ic, 10);
		if (isfinite(cs[i].clip_ms) && cs[i].clip_ms > 0)
			sqlite3_bind_double(ic, 11, cs[i].clip_ms);
		else
			sqlite3_bind_null(ic, 11);
		ok = sqlite3_step(ic) == SQLITE_DONE;
	}
	sqlite3_finalize(ic);
	/* The participants' plans (study_plan.c; sty_add_participants makes later participants' the same way). */
	int *is_catch = calloc(nc + 1, sizeof *is_catch);
	for (size_t i = 0; is_catch && i < nc; i++)
		is_catch[i] = cs[i].is_catch;
	/* Adaptive (issue 28): the test trials are aimed at groups (method x period x scene x camera), each represented by
	 * its first test condition; the T is chosen when the trial is shown (study_adaptive_db.c). */
	size_t *groups = calloc(nc + 1, sizeof *groups), ngroups = 0;
	if (!groups || (d->adaptive && sty_adaptive_schema(s, err, err_size)))
		ok = 0;
	for (size_t k = 0; ok && k < nc; k++) {
		int seen = cs[k].is_catch;
		for (size_t g = 0; g < ngroups && !seen; g++) {
			const cond *a = &cs[k], *b = &cs[groups[g]];
			seen = !strcmp(a->method, b->method) && a->period == b->period && !strcmp(a->scene, b->scene) &&
			       !strcmp(a->camera, b->camera);
		}
		if (!seen)
			groups[ngroups++] = k;
	}
	/* A model's predictions as the groups' priors (issue 28 "--prior"), stored with the design. */
	out->groups = d->adaptive ? (uint32_t)ngroups : 0;
	for (size_t g = 0; ok && d->prior && g < ngroups; g++) {
		const cond *c = &cs[groups[g]];
		double th, sd;
		if (sty_model_prior(d->prior, c->method, c->period, c->scene, c->camera, &th, &sd, err, err_size) == 1) {
			ok = !sty_adaptive_set_prior(s, (int64_t)groups[g] + 1, th, sd); /* condition ids are 1 + index */
			out->priors++;
		}
	}
	sty_plan_params pp = {.seed = d->seed, .training = d->training, .catch_trials = d->catch_trials,
			      .gold_trials = d->gold_trials, .break_every = d->break_every, .adaptive = d->adaptive, .trials = d->trials,
			      .groups = groups, .ngroups = ngroups};
	uint32_t breaks = 0;
	ok = ok && is_catch && !sty_plan_participants(s, is_catch, nc, &pp, 0, d->participants, &out->trials_per_participant,
						      &breaks, err, err_size);
	free(is_catch);
	free(groups);
	char seedbuf[32];
	snprintf(seedbuf, sizeof seedbuf, "%llu", (unsigned long long)d->seed);
	ok = ok && !sty_meta_set(s, "stimuli", root) && !sty_meta_set(s, "seed", seedbuf) &&
	     !sty_meta_set(s, "design", d->adaptive ? "adaptive" : "full") &&
	     !sty_meta_set(s, "display", views > 1 ? "stereo" : "");
	if (!ok || sqlite3_exec(s->db, "COMMIT", NULL, NULL, NULL) != SQLITE_OK) {
		rc = sty_db_fail(s, err, err_size, "writing the design");
		sqlite3_exec(s->db, "ROLLBACK", NULL, NULL, NULL);
		goto done;
	}
	snprintf(s->stimuli, sizeof s->stimuli, "%s", root);
	snprintf(s->display, sizeof s->display, "%s", views > 1 ? "stereo" : "");
	/* Session length: clip durations from the first set's pairs.json frames and fps. */
	double clip_s = 5.0;
	snprintf(p, sizeof p, "%s%s%s/pairs.json", root, sets[0][0] ? "/" : "", sets[0]);
	pairs_set first;
	char why[256];
	if (!pairs_read(p, &first, why, sizeof why)) {
		clip_s = (double)(first.last_frame - first.first_frame + 1) / first.fps;
		pairs_free(&first);
	}
	double ans = d->answer_s > 0 ? d->answer_s : 4.0, gap = d->gap_s > 0 ? d->gap_s : 0.5;
	out->conditions = (uint32_t)nc;
	out->sets = (uint32_t)nsets;
	out->participants = d->participants;
	out->breaks = breaks;
	out->session_minutes = (out->trials_per_participant * (2 * clip_s + gap + ans) + 30.0 * breaks) / 60.0;
	rc = TL_OK;
done:
	for (size_t i = 0; i < nsets; i++)
		free(sets[i]);
	free(sets);
	free(cs);
	return rc;
}

int sty_participant_codes(sty *s, char ***codes, size_t *n, char *err, size_t err_size)
{
	sqlite3_stmt *st;
	*codes = NULL;
	*n = 0;
	if (sqlite3_prepare_v2(s->db, "SELECT code FROM participants ORDER BY id", -1, &st, NULL))
		return sty_db_fail(s, err, err_size, "participants");
	while (sqlite3_step(st) == SQLITE_ROW) {
		char **nc = realloc(*codes, (*n + 1) * sizeof *nc);
		if (!nc)
			break;
		*codes = nc;
		(*codes)[(*n)++] = strdup((const char *)sqlite3_column_text(st, 0));
	}
	sqlite3_finalize(st);
	return TL_OK;
}
