/* study_adaptive_db.c — the adaptive design in the study database (issue 28; study.h sty_design with adaptive): a
 * participant's plan holds N test trials per participant, each aimed at a method x period x scene x camera path (a
 * group) but without its T; the trial's T is chosen when the trial is first shown (sty_next_trial), by QUEST+ on the
 * answers of every participant in that group so far (sty_adapt, study_adaptive.c), and stored in the same transaction
 * as the clip names. The state is the database: after a crash or SIGKILL the trial shown comes back as it was, and a
 * trial not yet shown is chosen from the same answers again. The posterior is a product over answers, so the choice
 * depends on the set of answers in the group, not on their order: the same seed and answers replay the same trials.
 *
 * Table adaptive_trials(participant, idx, grp, resolved): grp is a condition of the group (the plan's placeholder in
 * trials.condition until resolved); the group's levels are its test conditions with the same method, period, scene
 * and camera. */
#include <math.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_adaptive_db.h"
#include "taslab/study_threshold.h"

int sty_adaptive_schema(sty *s, char *err, size_t err_size)
{
	if (sqlite3_exec(s->db, "CREATE TABLE IF NOT EXISTS adaptive_trials(participant INTEGER NOT NULL, idx INTEGER NOT NULL,"
				" grp INTEGER NOT NULL REFERENCES conditions(id), resolved INTEGER NOT NULL DEFAULT 0,"
				" PRIMARY KEY(participant, idx), FOREIGN KEY(participant, idx) REFERENCES trials(participant, idx))",
			 NULL, NULL, NULL) != SQLITE_OK)
		return sty_db_fail(s, err, err_size, "adaptive design");
	if (sqlite3_exec(s->db, "CREATE TABLE IF NOT EXISTS adaptive_prior(grp INTEGER PRIMARY KEY REFERENCES conditions(id),"
				" theta REAL NOT NULL, sd REAL NOT NULL)", NULL, NULL, NULL) != SQLITE_OK)
		return sty_db_fail(s, err, err_size, "adaptive design");
	return TL_OK;
}

int sty_adaptive_set_prior(sty *s, int64_t grp, double theta, double sd)
{
	sqlite3_stmt *st;
	if (!(st = sty_stmt(s, "INSERT INTO adaptive_prior(grp, theta, sd) VALUES(?, ?, ?)")))
		return TL_ERR_DB;
	sqlite3_bind_int64(st, 1, grp);
	sqlite3_bind_double(st, 2, theta);
	sqlite3_bind_double(st, 3, sd);
	int r = sqlite3_step(st);
	sty_stmt_done(s, st);
	return r == SQLITE_DONE ? TL_OK : TL_ERR_DB;
}

/* The group's prior into `a` when the design stored one (studies designed before issue 28's --prior have no table). */
static int apply_prior(sty *s, int64_t grp, sty_adapt *a, char *err, size_t err_size)
{
	sqlite3_stmt *st;
	if (!(st = sty_stmt(s, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'adaptive_prior'")))
		return sty_db_fail(s, err, err_size, "adaptive design");
	int has = sqlite3_step(st) == SQLITE_ROW;
	sty_stmt_done(s, st);
	if (!has)
		return TL_OK;
	if (!(st = sty_stmt(s,
			    "SELECT p.theta, p.sd FROM adaptive_prior p JOIN conditions c ON c.id = p.grp JOIN conditions g ON"
			    " g.id = ?1 WHERE c.method = g.method AND c.period IS g.period AND c.scene = g.scene AND"
			    " c.camera = g.camera")))
		return sty_db_fail(s, err, err_size, "adaptive design");
	sqlite3_bind_int64(st, 1, grp);
	int r = sqlite3_step(st);
	if (r == SQLITE_ROW) /* an SD below 0.1 octave would pin theta to one grid step: 0.1 at least */
		sty_adapt_prior(a, sqlite3_column_double(st, 0), fmax(sqlite3_column_double(st, 1), 0.1));
	sty_stmt_done(s, st);
	return r == SQLITE_ROW || r == SQLITE_DONE ? TL_OK : sty_db_fail(s, err, err_size, "adaptive design");
}

int sty_adaptive_plan(sty *s, int64_t pid, int64_t idx, int64_t grp)
{
	sqlite3_stmt *st;
	if (!(st = sty_stmt(s, "INSERT INTO adaptive_trials(participant, idx, grp) VALUES(?, ?, ?)")))
		return TL_ERR_DB;
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, idx);
	sqlite3_bind_int64(st, 3, grp);
	int r = sqlite3_step(st);
	sty_stmt_done(s, st);
	return r == SQLITE_DONE ? TL_OK : TL_ERR_DB;
}

/* The group's levels: condition ids and T (NAN: the method has none), ordered by T. */
#define MAX_GROUP_LEVELS 64
static int group_levels(sty *s, int64_t grp, int64_t *ids, double *T, size_t *n, char *err, size_t err_size)
{
	sqlite3_stmt *st;
	*n = 0;
	if (!(st = sty_stmt(s,
			    "SELECT c.id, c.T FROM conditions c JOIN conditions g ON g.id = ?1 WHERE c.is_catch = 0 AND"
			    " c.method = g.method AND c.period IS g.period AND c.scene = g.scene AND c.camera = g.camera"
			    " ORDER BY c.T, c.id")))
		return sty_db_fail(s, err, err_size, "adaptive design");
	sqlite3_bind_int64(st, 1, grp);
	while (sqlite3_step(st) == SQLITE_ROW && *n < MAX_GROUP_LEVELS) {
		ids[*n] = sqlite3_column_int64(st, 0);
		T[*n] = sqlite3_column_type(st, 1) == SQLITE_NULL ? NAN : sqlite3_column_double(st, 1);
		(*n)++;
	}
	sty_stmt_done(s, st);
	return *n ? TL_OK : tl_error(err, err_size, TL_ERR_INTERNAL, "%s: adaptive group %lld has no condition", s->path,
				       (long long)grp);
}

int sty_adaptive_choice(sty *s, int64_t grp, int64_t *condition, char *err, size_t err_size)
{
	int64_t ids[MAX_GROUP_LEVELS];
	double T[MAX_GROUP_LEVELS];
	size_t n;
	int rc = group_levels(s, grp, ids, T, &n, err, err_size);
	if (rc)
		return rc;
	if (n == 1 || isnan(T[0])) { /* one level, or a method without T: nothing to choose */
		*condition = ids[0];
		return TL_OK;
	}
	sty_adapt *a = sty_adapt_new(T, n);
	if (!a)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	if ((rc = apply_prior(s, grp, a, err, err_size))) {
		sty_adapt_free(&a);
		return rc;
	}
	sqlite3_stmt *st;
	if (!(st = sty_stmt(s,
			    "SELECT t.condition, t.ref_first, a.answer FROM answers a JOIN trials t ON t.participant ="
			    " a.participant AND t.idx = a.idx JOIN conditions c ON c.id = t.condition JOIN conditions g ON"
			    " g.id = ?1 WHERE t.kind = 'test' AND a.broken IS NULL AND c.is_catch = 0 AND c.method = g.method AND"
			    " c.period IS g.period AND c.scene = g.scene AND c.camera = g.camera"))) {
		sty_adapt_free(&a);
		return sty_db_fail(s, err, err_size, "adaptive design");
	}
	sqlite3_bind_int64(st, 1, grp);
	int r;
	while ((r = sqlite3_step(st)) == SQLITE_ROW) {
		int64_t c = sqlite3_column_int64(st, 0);
		int answer = sqlite3_column_int(st, 2), rating = sqlite3_column_int(st, 1) ? -answer : answer;
		for (size_t l = 0; l < n; l++)
			if (ids[l] == c)
				sty_adapt_update(a, l, rating > 0 ? 1 : rating == 0 ? 0.5 : 0);
	}
	sty_stmt_done(s, st);
	if (r != SQLITE_DONE)
		rc = sty_db_fail(s, err, err_size, "adaptive design");
	else
		*condition = ids[sty_adapt_choose(a, NULL)];
	sty_adapt_free(&a);
	return rc;
}

int sty_adaptive_resolve(sty *s, int64_t pid, char *err, size_t err_size)
{
	sqlite3_stmt *st;
	int rc = TL_OK;
	/* a study without the table is not adaptive */
	if (!(st = sty_stmt(s, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'adaptive_trials'")))
		return sty_db_fail(s, err, err_size, "adaptive design");
	int adaptive = sqlite3_step(st) == SQLITE_ROW;
	sty_stmt_done(s, st);
	if (!adaptive)
		return TL_OK;
	if (!(st = sty_stmt(s,
			    "SELECT a.idx, a.grp FROM adaptive_trials a WHERE a.participant = ?1 AND a.resolved = 0 AND"
			    " a.idx = (SELECT min(idx) FROM trials u WHERE participant = ?1 AND"
			    " NOT EXISTS (SELECT 1 FROM answers b WHERE b.participant = ?1 AND b.idx = u.idx))")))
		return sty_db_fail(s, err, err_size, "adaptive design");
	sqlite3_bind_int64(st, 1, pid);
	int r = sqlite3_step(st);
	int64_t idx = r == SQLITE_ROW ? sqlite3_column_int64(st, 0) : -1, grp = r == SQLITE_ROW ? sqlite3_column_int64(st, 1) : 0;
	sty_stmt_done(s, st);
	if (r == SQLITE_DONE)
		return TL_OK; /* the current trial is chosen already, or not an adaptive one */
	if (r != SQLITE_ROW)
		return sty_db_fail(s, err, err_size, "adaptive design");
	int64_t cond;
	if ((rc = sty_adaptive_choice(s, grp, &cond, err, err_size)))
		return rc;
	if (!(st = sty_stmt(s, "UPDATE trials SET condition = ?3 WHERE participant = ?1 AND idx = ?2;")))
		return sty_db_fail(s, err, err_size, "adaptive design");
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, idx);
	sqlite3_bind_int64(st, 3, cond);
	r = sqlite3_step(st);
	sty_stmt_done(s, st);
	if (r != SQLITE_DONE ||
	    !(st = sty_stmt(s, "UPDATE adaptive_trials SET resolved = 1 WHERE participant = ?1 AND idx = ?2")))
		return sty_db_fail(s, err, err_size, "adaptive design");
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, idx);
	r = sqlite3_step(st);
	sty_stmt_done(s, st);
	return r == SQLITE_DONE ? TL_OK : sty_db_fail(s, err, err_size, "adaptive design");
}
