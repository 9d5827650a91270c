/* study_plan.c — per-participant trial plans (study_plan.h), made by sty_design for a new study and by
 * sty_add_participants (study_status.h, issue 27.7) for participants added to a designed study later. */
#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_adaptive_db.h"
#include "study_plan.h"
#include "taslab/study_status.h"

/* An adaptive trial in a plan (issue 28): the group's representative condition with this bit set. */
#define ADAPTIVE_SLOT ((size_t)1 << (sizeof(size_t) * 8 - 1))

/* One seeded bit per (seed, pair of participants, trial): splitmix64's finaliser. */
static unsigned order_bit(uint64_t seed, uint64_t pair, uint64_t k)
{
	uint64_t z = seed * 0x9e3779b97f4a7c15ull + pair * 0xbf58476d1ce4e5b9ull + k * 0x94d049bb133111ebull + 1;
	z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
	z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
	return (unsigned)((z ^ (z >> 31)) & 1);
}

int sty_plan_participants(sty *s, const int *is_catch, size_t nc, const sty_plan_params *pp, uint32_t first,
			  uint32_t count, uint32_t *per_out, uint32_t *breaks_out, char *err, size_t err_size)
{
	size_t ntest = 0, ncatch = 0, ngold = 0;
	for (size_t i = 0; i < nc; i++)
		is_catch[i] == 2 ? ngold++ : is_catch[i] ? ncatch++ : ntest++;
	sqlite3_stmt *ip = NULL, *it = NULL;
	sqlite3_prepare_v2(s->db, "INSERT INTO participants(id, code, label) VALUES(?,?,?)", -1, &ip, NULL);
	sqlite3_prepare_v2(s->db, "INSERT INTO trials(participant, idx, condition, ref_first, kind, break_before)"
				  " VALUES(?,?,?,?,?,?)", -1, &it, NULL);
	/* Plan per participant: [training] then shuffled (test conditions + catch trials + gold trials). */
	gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
	size_t per = (pp->adaptive ? pp->trials : ntest) + pp->catch_trials + pp->gold_trials;
	size_t *order = calloc(per + pp->training + 1, sizeof *order);
	int *flip = calloc(nc + 1, sizeof *flip);
	size_t *tests = calloc(ntest + 1, sizeof *tests), *catches = calloc(ncatch + 1, sizeof *catches),
	       *golds = calloc(ngold + 1, sizeof *golds);
	int ok = ip && it && rng && order && flip && tests && catches && golds && (ncatch || !pp->catch_trials) &&
		 (ngold || !pp->gold_trials) && (!pp->adaptive || pp->ngroups);
	for (size_t i = 0, a = 0, b = 0, g = 0; ok && i < nc; i++)
		is_catch[i] == 2 ? (golds[g++] = i) : is_catch[i] ? (catches[b++] = i) : (tests[a++] = i);
	uint32_t breaks = 0;
	for (uint32_t pi = first; ok && pi < first + count; pi++) {
		char code[33], label[32];
		if (!sty_random_hex(code)) {
			ok = 0;
			break;
		}
		snprintf(label, sizeof label, "P%03u", pi + 1);
		sqlite3_reset(ip);
		sqlite3_bind_int64(ip, 1, pi + 1);
		sqlite3_bind_text(ip, 2, code, -1, SQLITE_TRANSIENT);
		sqlite3_bind_text(ip, 3, label, -1, SQLITE_TRANSIENT);
		ok = sqlite3_step(ip) == SQLITE_DONE;
		/* Each pair of participants (2k, 2k+1) shares one seeded draw of in-pair orders, the second taking the
		 * complement: orders are random per participant and each pair appears in both orders. */
		gsl_rng_set(rng, (unsigned long)(pp->seed * 1000003ull + (pi / 2) * 2654435761ull + 1));
		for (size_t c = 0; c < nc; c++)
			flip[c] = (int)gsl_rng_uniform_int(rng, 2) ^ (int)(pi % 2);
		gsl_rng_set(rng, (unsigned long)(pp->seed * 1000003ull + pi * 40503ull + 7777));
		size_t n = 0;
		for (size_t k = 0; k < pp->training; k++)
			order[n++] = ntest ? tests[gsl_rng_uniform_int(rng, ntest)] : catches[0];
		size_t start = n;
		size_t goff = pp->adaptive ? gsl_rng_uniform_int(rng, pp->ngroups) : 0; /* full plans draw as before */
		for (size_t k = 0; k < (pp->adaptive ? pp->trials : ntest); k++)
			order[n++] = pp->adaptive ? pp->groups[(k + goff) % pp->ngroups] | ADAPTIVE_SLOT : tests[k];
		size_t off = ncatch ? gsl_rng_uniform_int(rng, ncatch) : 0; /* which catch pairs: rotates per participant */
		for (size_t k = 0; k < pp->catch_trials; k++)
			order[n++] = catches[(k + off) % ncatch];
		/* gold trials rotate over the sets' gold conditions the same way; drawn only when there are some, so a
		 * design without them plans exactly as before */
		size_t goff2 = pp->gold_trials ? gsl_rng_uniform_int(rng, ngold) : 0;
		for (size_t k = 0; k < pp->gold_trials; k++)
			order[n++] = golds[(k + goff2) % ngold];
		gsl_ran_shuffle(rng, order + start, n - start, sizeof *order);
		for (size_t k = 0; ok && k < n; k++) {
			size_t c = order[k] & ~ADAPTIVE_SLOT;
			bool adaptive = order[k] & ADAPTIVE_SLOT;
			const char *kind = k < start ? "training" : is_catch[c] == 2 ? "gold" : is_catch[c] ? "catch" : "test";
			int brk = pp->break_every && k > 0 && k % pp->break_every == 0;
			breaks += brk && pi == first;
			sqlite3_reset(it);
			sqlite3_bind_int64(it, 1, pi + 1);
			sqlite3_bind_int64(it, 2, (sqlite3_int64)k);
			sqlite3_bind_int64(it, 3, (sqlite3_int64)c + 1);
			/* an adaptive trial's order: one seeded bit per trial, complementary for participants 2k and 2k+1 */
			sqlite3_bind_int(it, 4, adaptive ? (int)(order_bit(pp->seed, pi / 2, k) ^ (pi % 2)) : flip[c]);
			sqlite3_bind_text(it, 5, kind, -1, SQLITE_STATIC);
			sqlite3_bind_int(it, 6, brk);
			ok = sqlite3_step(it) == SQLITE_DONE;
			if (ok && adaptive)
				ok = sty_adaptive_plan(s, pi + 1, k, (int64_t)c + 1) == TL_OK;
		}
		*per_out = (uint32_t)n;
	}
	sqlite3_finalize(ip);
	sqlite3_finalize(it);
	gsl_rng_free(rng);
	free(order);
	free(flip);
	free(tests);
	free(catches);
	free(golds);
	*breaks_out = breaks;
	return ok ? TL_OK : sty_db_fail(s, err, err_size, "writing the participants' plans");
}

/* The plan settings of a designed study, read back from its first participant's plan (training trials come first,
 * catch trials are counted, the first break is at break_every), and its seed from the meta table. */
static int plan_settings(sty *s, sty_plan_params *pp, uint32_t *existing, char *err, size_t err_size)
{
	memset(pp, 0, sizeof *pp);
	sqlite3_stmt *st;
	if (sqlite3_prepare_v2(s->db,
			       "SELECT (SELECT value FROM meta WHERE key = 'seed'), (SELECT count(*) FROM participants),"
			       " (SELECT coalesce(max(id), 0) FROM participants),"
			       " (SELECT count(*) FROM trials WHERE participant = 1 AND kind = 'training'),"
			       " (SELECT count(*) FROM trials WHERE participant = 1 AND kind = 'catch' AND retake_of IS NULL),"
			       " (SELECT count(*) FROM trials WHERE participant = 1 AND kind = 'gold' AND retake_of IS NULL),"
			       " (SELECT coalesce(min(idx), 0) FROM trials WHERE participant = 1 AND break_before),"
			       " (SELECT value FROM meta WHERE key = 'design')", -1, &st, NULL))
		return sty_db_fail(s, err, err_size, "reading the design");
	int rc = TL_OK;
	if (sqlite3_step(st) != SQLITE_ROW) {
		rc = sty_db_fail(s, err, err_size, "reading the design");
	} else if (sqlite3_column_type(st, 0) == SQLITE_NULL || !sty_stimuli(s)[0] || sqlite3_column_int(st, 1) == 0) {
		rc = tl_error(err, err_size, TL_ERR_ARG, "%s has no design to add participants to (an imported study, or "
			      "no participants): make one with 'taslab study design'", sty_path(s));
	} else if (sqlite3_column_type(st, 7) == SQLITE_TEXT && !strcmp((const char *)sqlite3_column_text(st, 7), "adaptive")) {
		rc = tl_error(err, err_size, TL_ERR_ARG, "%s is an adaptive design: adding participants to one is not supported "
			      "yet (design it again with the participants you need)", sty_path(s));
	} else if (sqlite3_column_int64(st, 1) != sqlite3_column_int64(st, 2)) {
		rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: participant ids are not 1..N (edited by hand?)", sty_path(s));
	} else {
		pp->seed = strtoull((const char *)sqlite3_column_text(st, 0), NULL, 10);
		*existing = (uint32_t)sqlite3_column_int(st, 1);
		pp->training = (uint32_t)sqlite3_column_int(st, 3);
		pp->catch_trials = (uint32_t)sqlite3_column_int(st, 4);
		pp->gold_trials = (uint32_t)sqlite3_column_int(st, 5);
		pp->break_every = (uint32_t)sqlite3_column_int(st, 6);
	}
	sqlite3_finalize(st);
	return rc;
}

int sty_add_participants(sty *s, uint32_t count, uint32_t *first, char *err, size_t err_size)
{
	*first = 0;
	if (count < 1 || count > 10000)
		return tl_error(err, err_size, TL_ERR_ARG, "--participants must be 1..10000");
	if (sqlite3_exec(s->db, "BEGIN IMMEDIATE", NULL, NULL, NULL) != SQLITE_OK)
		return sty_db_fail(s, err, err_size, "adding participants");
	sty_plan_params pp;
	uint32_t existing = 0, per = 0, breaks = 0;
	int *is_catch = NULL;
	size_t nc = 0;
	sqlite3_stmt *st = NULL;
	int rc = plan_settings(s, &pp, &existing, err, err_size);
	if (!rc && existing + (uint64_t)count > 100000)
		rc = tl_error(err, err_size, TL_ERR_ARG, "a study holds at most 100000 participants");
	if (!rc && sqlite3_prepare_v2(s->db, "SELECT id, is_catch FROM conditions ORDER BY id", -1, &st, NULL))
		rc = sty_db_fail(s, err, err_size, "reading the design");
	while (!rc && sqlite3_step(st) == SQLITE_ROW) {
		int *n = realloc(is_catch, (nc + 1) * sizeof *n);
		if (!n) {
			rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
			break;
		}
		is_catch = n;
		if (sqlite3_column_int64(st, 0) != (sqlite3_int64)nc + 1)
			rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: condition ids are not 1..N (edited by hand?)", sty_path(s));
		is_catch[nc++] = sqlite3_column_int(st, 1);
	}
	sqlite3_finalize(st);
	if (!rc)
		rc = sty_plan_participants(s, is_catch, nc, &pp, existing, count, &per, &breaks, err, err_size);
	free(is_catch);
	if (!rc && sqlite3_exec(s->db, "COMMIT", NULL, NULL, NULL) != SQLITE_OK)
		rc = sty_db_fail(s, err, err_size, "adding participants");
	if (rc)
		sqlite3_exec(s->db, "ROLLBACK", NULL, NULL, NULL);
	else
		*first = existing + 1;
	return rc;
}
