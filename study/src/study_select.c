/* study_select.c — trial selection (study_select.h): the participant behind a code, the trial they are at, the
 * answer to it; and the server's calls built on them (study.h): sty_next_trial with the trial's opaque clip names,
 * sty_clip_file, sty_answer. */
#include <pthread.h>
#include <sqlite3.h>
#include <stdio.h>
#include <string.h>

#include "study_adaptive_db.h"
#include "study_internal.h"
#include "study_select.h"

/* ------------------------------------------------------------------ selection */

int64_t sty_select_participant(sty *s, const char *code)
{
	sqlite3_stmt *st;
	int64_t id = -1;
	if (!(st = sty_stmt(s, "SELECT id FROM participants WHERE code = ?")))
		return -1; /* local sentinel: no id (study_select.h) */
	sqlite3_bind_text(st, 1, code, -1, SQLITE_STATIC);
	if (sqlite3_step(st) == SQLITE_ROW)
		id = sqlite3_column_int64(st, 0);
	sty_stmt_done(s, st);
	return id;
}

int sty_select_current(sty *s, int64_t pid, sty_pick *p, char *err, size_t err_size)
{
	memset(p, 0, sizeof *p);
	sqlite3_stmt *st = NULL;
	int rc = TL_OK;
	if (!(st = sty_stmt(s,
			    "SELECT (SELECT count(*) FROM trials WHERE participant = ?1 AND retake_of IS NULL),"
			    " (SELECT count(*) FROM trials u WHERE participant = ?1 AND NOT EXISTS (SELECT 1 FROM answers a"
			    "  WHERE a.participant = ?1 AND a.idx = u.idx)),"
			    " t.idx, t.ref_first, t.kind, t.break_before, c.ref_clip, c.test_clip"
			    " FROM trials t JOIN conditions c ON c.id = t.condition"
			    " WHERE t.participant = ?1 AND NOT EXISTS (SELECT 1 FROM answers a WHERE a.participant = ?1"
			    "  AND a.idx = t.idx)"
			    " ORDER BY t.idx LIMIT 1")))
		return sty_db_fail(s, err, err_size, "next trial");
	sqlite3_bind_int64(st, 1, pid);
	int r = sqlite3_step(st);
	if (r == SQLITE_ROW) {
		/* progress in planned trials (issue 28): a broken trial's retake (study_telemetry.h) is not one more */
		p->total = (uint32_t)sqlite3_column_int(st, 0);
		int left = sqlite3_column_int(st, 1);
		p->answered = (uint32_t)(left < (int)p->total ? (int)p->total - left : 0);
		p->index = (uint32_t)sqlite3_column_int64(st, 2);
		p->ref_first = sqlite3_column_int(st, 3) != 0;
		snprintf(p->kind, sizeof p->kind, "%s", (const char *)sqlite3_column_text(st, 4));
		p->break_before = sqlite3_column_int(st, 5) != 0;
		snprintf(p->ref_clip, sizeof p->ref_clip, "%s", (const char *)sqlite3_column_text(st, 6));
		snprintf(p->test_clip, sizeof p->test_clip, "%s", (const char *)sqlite3_column_text(st, 7));
	} else if (r == SQLITE_DONE) {
		sty_stmt_done(s, st);
		st = NULL;
		if (!(st = sty_stmt(s, "SELECT count(*) FROM trials WHERE participant = ? AND retake_of IS NULL")))
			return sty_db_fail(s, err, err_size, "next trial");
		sqlite3_bind_int64(st, 1, pid);
		if (sqlite3_step(st) == SQLITE_ROW)
			p->total = p->answered = (uint32_t)sqlite3_column_int(st, 0);
		p->done = true;
	} else {
		rc = sty_db_fail(s, err, err_size, "next trial");
	}
	sty_stmt_done(s, st);
	return rc;
}

int sty_select_answer(sty *s, int64_t pid, uint32_t trial, int64_t answer, int64_t rt_ms, char *err, size_t err_size)
{
	int rc = TL_OK;
	sqlite3_stmt *st = NULL;
	/* Does the trial exist, is it answered, and which trial is current (the lowest-index unanswered one). The
	 * lock serialises this check with the INSERT below against the other server threads. */
	if (!(st = sty_stmt(s,
			    "SELECT (SELECT count(*) FROM trials WHERE participant = ?1 AND idx = ?2),"
			    " (SELECT count(*) FROM answers WHERE participant = ?1 AND idx = ?2),"
			    " (SELECT min(idx) FROM trials u WHERE participant = ?1 AND"
			    "  NOT EXISTS (SELECT 1 FROM answers a WHERE a.participant = ?1 AND a.idx = u.idx))"))) {
		rc = sty_db_fail(s, err, err_size, "answer");
		goto done;
	}
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, trial);
	if (sqlite3_step(st) != SQLITE_ROW) {
		rc = sty_db_fail(s, err, err_size, "answer");
		goto done;
	}
	if (sqlite3_column_int(st, 0) == 0) {
		rc = tl_error(err, err_size, TL_ERR_NOTFOUND, "no trial %u for this participant", trial);
		goto done;
	}
	if (sqlite3_column_int(st, 1) != 0) {
		rc = tl_error(err, err_size, TL_ERR_CONFLICT, "trial %u was answered already", trial);
		goto done;
	}
	if (sqlite3_column_int64(st, 2) != (sqlite3_int64)trial) {
		rc = tl_error(err, err_size, TL_ERR_ARG, "trial %u is not the current trial (%lld): trials are answered in order",
			      trial, (long long)sqlite3_column_int64(st, 2));
		goto done;
	}
	sty_stmt_done(s, st);
	st = NULL;
	/* Inside the caller's transaction (a group commit, study_commit.c): the answer is acknowledged only after
	 * that transaction's COMMIT has returned (with synchronous=FULL: on disk). */
	if (!(st = sty_stmt(s, "INSERT INTO answers(participant, idx, answer, rt_ms, at)"
				      " VALUES(?, ?, ?, ?, strftime('%Y-%m-%dT%H:%M:%fZ','now'))"))) {
		rc = sty_db_fail(s, err, err_size, "storing the answer");
		goto done;
	}
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, trial);
	sqlite3_bind_int64(st, 3, answer);
	if (rt_ms >= 0)
		sqlite3_bind_int64(st, 4, rt_ms);
	else
		sqlite3_bind_null(st, 4);
	int r = sqlite3_step(st);
	if (r == SQLITE_CONSTRAINT)
		rc = tl_error(err, err_size, TL_ERR_CONFLICT, "trial %u was answered already", trial);
	else if (r != SQLITE_DONE)
		rc = sty_db_fail(s, err, err_size, "storing the answer");
done:
	sty_stmt_done(s, st);
	return rc;
}

/* ------------------------------------------------------------------ the server's calls (study.h) */

/* The extension a clip's opaque name keeps, so the browser knows the container: ".webm" / ".mp4", else none. */
static const char *clip_ext(const char *path)
{
	size_t n = strlen(path);
	if (n >= 5 && !strcmp(path + n - 5, ".webm"))
		return ".webm";
	if (n >= 4 && !strcmp(path + n - 4, ".mp4"))
		return ".mp4";
	return "";
}

/* The opaque name of side `slot` of trial (pid, idx), made (random, stored) when missing. Caller holds the lock
 * and an open transaction; *made is set when a name was stored. false when SQLite or the kernel's random bits fail (the caller reports TL_ERR_DB). */
static bool clip_name(sty *s, int64_t pid, int64_t idx, int slot, const char *path, char *out, size_t n, bool *made)
{
	sqlite3_stmt *st;
	if (!(st = sty_stmt(s, "SELECT name FROM clip_names WHERE participant = ? AND idx = ? AND slot = ?")))
		return false;
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, idx);
	sqlite3_bind_int(st, 3, slot);
	int r = sqlite3_step(st);
	if (r == SQLITE_ROW)
		snprintf(out, n, "%s", (const char *)sqlite3_column_text(st, 0));
	sty_stmt_done(s, st);
	if (r == SQLITE_ROW)
		return true;
	if (r != SQLITE_DONE)
		return false;
	char hex[33];
	if (!sty_random_hex(hex))
		return false;
	snprintf(out, n, "%s%s", hex, clip_ext(path));
	if (!(st = sty_stmt(s, "INSERT INTO clip_names(name, participant, idx, slot) VALUES(?, ?, ?, ?)")))
		return false;
	sqlite3_bind_text(st, 1, out, -1, SQLITE_STATIC);
	sqlite3_bind_int64(st, 2, pid);
	sqlite3_bind_int64(st, 3, idx);
	sqlite3_bind_int(st, 4, slot);
	r = sqlite3_step(st);
	sty_stmt_done(s, st);
	*made = true;
	return r == SQLITE_DONE;
}

int sty_next_trial(sty *s, const char *code, sty_trial *t, char *err, size_t err_size)
{
	memset(t, 0, sizeof *t);
	t->stereo = !strcmp(s->display, "stereo");
	sty_batch_lock(s);
	int64_t pid = sty_select_participant(s, code);
	int rc = pid < 0 ? tl_error(err, err_size, TL_ERR_NOTFOUND, "unknown participant") : TL_OK;
	bool named = false;
	sty_pick p;
	/* The clip names made for a trial shown for the first time are committed (with other requests' writes, one
	 * fsync: study_commit.c) before the trial is sent. */
	if (!rc)
		rc = sty_batch_join(s, err, err_size);
	int changes = sqlite3_total_changes(s->db);
	/* an adaptive trial's T is chosen when it is first shown, in this transaction (study_adaptive_db.c) */
	if (!rc)
		rc = sty_adaptive_resolve(s, pid, err, err_size);
	if (!rc)
		rc = sty_select_current(s, pid, &p, err, err_size);
	if (!rc) {
		t->total = p.total;
		t->answered = p.answered;
		t->done = p.done;
	}
	if (!rc && !p.done) {
		t->index = p.index;
		snprintf(t->kind, sizeof t->kind, "%s", p.kind);
		t->break_before = p.break_before;
		if (!clip_name(s, pid, t->index, 0, p.ref_first ? p.ref_clip : p.test_clip, t->clip_a, sizeof t->clip_a, &named) ||
		    !clip_name(s, pid, t->index, 1, p.ref_first ? p.test_clip : p.ref_clip, t->clip_b, sizeof t->clip_b, &named))
			rc = sty_db_fail(s, err, err_size, "naming the clips");
	}
	if (pid >= 0) /* a commit to wait for only when this request stored something (clip names, an adaptive T) */
		rc = sty_batch_leave(s, rc, named || sqlite3_total_changes(s->db) != changes, err, err_size);
	if (rc)
		memset(t, 0, sizeof *t);
	pthread_mutex_unlock(&s->lock);
	return rc;
}

int sty_clip_file(sty *s, const char *name, char *rel, size_t rel_size, char *err, size_t err_size)
{
	rel[0] = 0;
	sqlite3_stmt *st;
	pthread_mutex_lock(&s->lock);
	int rc = TL_OK;
	if (!(st = sty_stmt(s,
			    "SELECT CASE WHEN (k.slot = 0) = (t.ref_first != 0) THEN c.ref_clip ELSE c.test_clip END"
			    " FROM clip_names k JOIN trials t ON t.participant = k.participant AND t.idx = k.idx"
			    " JOIN conditions c ON c.id = t.condition WHERE k.name = ?"))) {
		rc = sty_db_fail(s, err, err_size, "clip");
		goto done;
	}
	sqlite3_bind_text(st, 1, name, -1, SQLITE_STATIC);
	int r = sqlite3_step(st);
	if (r == SQLITE_ROW && sqlite3_column_text(st, 0) && sqlite3_column_text(st, 0)[0])
		snprintf(rel, rel_size, "%s", (const char *)sqlite3_column_text(st, 0));
	else if (r == SQLITE_ROW || r == SQLITE_DONE)
		rc = tl_error(err, err_size, TL_ERR_NOTFOUND, "no such clip");
	else
		rc = sty_db_fail(s, err, err_size, "clip");
	sty_stmt_done(s, st);
done:
	pthread_mutex_unlock(&s->lock);
	return rc;
}

int sty_answer(sty *s, const char *code, uint32_t trial, int64_t answer, int64_t rt_ms, char *err, size_t err_size)
{
	if (answer < -2 || answer > 2)
		return tl_error(err, err_size, TL_ERR_ARG, "answer must be an integer from -2 to 2");
	if (rt_ms < -1 || rt_ms > STY_RT_MS_MAX)
		return tl_error(err, err_size, TL_ERR_ARG, "rt_ms must be a whole number of milliseconds from 0 to %d",
				STY_RT_MS_MAX);
	sty_batch_lock(s);
	int64_t pid = sty_select_participant(s, code);
	int rc = pid < 0 ? tl_error(err, err_size, TL_ERR_NOTFOUND, "unknown participant") : sty_batch_join(s, err, err_size);
	if (pid >= 0) {
		if (!rc)
			rc = sty_select_answer(s, pid, trial, answer, rt_ms, err, err_size);
		rc = sty_batch_leave(s, rc, true, err, err_size); /* acknowledged only once committed */
	}
	pthread_mutex_unlock(&s->lock);
	return rc;
}
