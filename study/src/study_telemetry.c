/* study_telemetry.c — remote participants' playback telemetry, the server's verdict on it and the retake of a broken
 * trial (study_telemetry.h; issue 28 "Remote participants"). The limits are the header's; README "Telemetry" states
 * them for users. */
#include <math.h>
#include <sqlite3.h>
#include <stdio.h>
#include <string.h>

#include "study_telemetry.h"

static void add_reason(char *why, size_t size, const char *r)
{
	size_t n = strlen(why);
	snprintf(why + n, size > n ? size - n : 0, "%s%s", n ? ";" : "", r);
}

const char *sty_playback_verdict(const sty_telemetry *t, double clip_ms, char *why, size_t why_size)
{
	if (why_size)
		why[0] = 0;
	/* dropped frames: more than 1 % of the frames played and more than two (frames 0: the browser did not say) */
	double allowed = fmax((double)STY_DROPPED_MIN, STY_DROPPED_SHARE * (double)t->frames);
	if (t->frames > 0 && (double)t->dropped > allowed)
		add_reason(why, why_size, "dropped");
	if (t->hidden_play > 0)
		add_reason(why, why_size, "hidden");
	if (isfinite(clip_ms) && clip_ms > 0) {
		double limit = STY_LONG_FACTOR * clip_ms + STY_LONG_SLACK_MS;
		if ((double)t->play_ms[0] > limit || (double)t->play_ms[1] > limit)
			add_reason(why, why_size, "long");
	}
	return why;
}

/* Whether the study has the adaptive_trials table (an adaptive design). */
static int has_adaptive(sty *s)
{
	sqlite3_stmt *st;
	int has = 0;
	if ((st = sty_stmt(s, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'adaptive_trials'")))
		has = sqlite3_step(st) == SQLITE_ROW;
	sty_stmt_done(s, st);
	return has;
}

/* Appends the retake of trial `idx` (planned trial `orig`) to participant pid's plan: the same condition, order and
 * kind (an adaptive trial: the same group, its T chosen again when shown). */
static int append_retake(sty *s, int64_t pid, int64_t idx, int64_t orig, char *err, size_t err_size)
{
	sqlite3_stmt *st;
	int adaptive = has_adaptive(s);
	int64_t grp = -1;
	if (adaptive) {
		if (!(st = sty_stmt(s, "SELECT grp FROM adaptive_trials WHERE participant = ? AND idx = ?")))
			return sty_db_fail(s, err, err_size, "retake");
		sqlite3_bind_int64(st, 1, pid);
		sqlite3_bind_int64(st, 2, idx);
		if (sqlite3_step(st) == SQLITE_ROW)
			grp = sqlite3_column_int64(st, 0);
		sty_stmt_done(s, st);
	}
	if (!(st = sty_stmt(s,
			    "INSERT INTO trials(participant, idx, condition, ref_first, kind, break_before, retake_of)"
			    " SELECT ?1, (SELECT max(idx) + 1 FROM trials WHERE participant = ?1), CASE WHEN ?4 >= 0 THEN ?4 ELSE"
			    " condition END, ref_first, kind, 0, ?3 FROM trials WHERE participant = ?1 AND idx = ?2")))
		return sty_db_fail(s, err, err_size, "retake");
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, idx);
	sqlite3_bind_int64(st, 3, orig);
	sqlite3_bind_int64(st, 4, grp);
	int r = sqlite3_step(st);
	sty_stmt_done(s, st);
	if (r != SQLITE_DONE)
		return sty_db_fail(s, err, err_size, "retake");
	if (grp < 0)
		return TL_OK;
	if (!(st = sty_stmt(s, "INSERT INTO adaptive_trials(participant, idx, grp) SELECT ?1, max(idx), ?2 FROM trials"
				      " WHERE participant = ?1")))
		return sty_db_fail(s, err, err_size, "retake");
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, grp);
	r = sqlite3_step(st);
	sty_stmt_done(s, st);
	return r == SQLITE_DONE ? TL_OK : sty_db_fail(s, err, err_size, "retake");
}

int sty_telemetry_store(sty *s, int64_t pid, uint32_t trial, const sty_telemetry *t, char *broken_out, size_t broken_size,
			char *err, size_t err_size)
{
	char why[48] = "";
	if (broken_out && broken_size)
		broken_out[0] = 0;
	sqlite3_stmt *st;
	/* the trial: its clip duration, kind, planned trial and how often that one was retaken already */
	if (!(st = sty_stmt(s,
			    "SELECT c.clip_ms, t.kind, coalesce(t.retake_of, t.idx), (SELECT count(*) FROM trials r WHERE"
			    " r.participant = ?1 AND r.retake_of = coalesce(t.retake_of, t.idx)) FROM trials t JOIN conditions c"
			    " ON c.id = t.condition WHERE t.participant = ?1 AND t.idx = ?2")))
		return sty_db_fail(s, err, err_size, "telemetry");
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, trial);
	if (sqlite3_step(st) != SQLITE_ROW) {
		sty_stmt_done(s, st);
		return sty_db_fail(s, err, err_size, "telemetry");
	}
	double clip_ms = sqlite3_column_type(st, 0) == SQLITE_NULL ? NAN : sqlite3_column_double(st, 0);
	int training = !strcmp((const char *)sqlite3_column_text(st, 1), "training");
	int64_t orig = sqlite3_column_int64(st, 2), retakes = sqlite3_column_int64(st, 3);
	sty_stmt_done(s, st);
	sty_playback_verdict(t, clip_ms, why, sizeof why);
	if (!(st = sty_stmt(s,
			    "UPDATE answers SET play_a_ms = ?3, play_b_ms = ?4, dropped_frames = ?5, total_frames = ?6,"
			    " hidden = ?7, hidden_ms = ?8, hidden_play = ?9, fullscreen = ?10, broken = ?11"
			    " WHERE participant = ?1 AND idx = ?2")))
		return sty_db_fail(s, err, err_size, "telemetry");
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, trial);
	sqlite3_bind_int64(st, 3, t->play_ms[0]);
	sqlite3_bind_int64(st, 4, t->play_ms[1]);
	sqlite3_bind_int64(st, 5, t->dropped);
	sqlite3_bind_int64(st, 6, t->frames);
	sqlite3_bind_int64(st, 7, t->hidden);
	sqlite3_bind_int64(st, 8, t->hidden_ms);
	sqlite3_bind_int64(st, 9, t->hidden_play);
	sqlite3_bind_int(st, 10, t->fullscreen);
	if (why[0])
		sqlite3_bind_text(st, 11, why, -1, SQLITE_STATIC);
	else
		sqlite3_bind_null(st, 11);
	int r = sqlite3_step(st);
	sty_stmt_done(s, st);
	if (r != SQLITE_DONE)
		return sty_db_fail(s, err, err_size, "telemetry");
	if (broken_out && broken_size)
		snprintf(broken_out, broken_size, "%s", why);
	if (!why[0] || training || retakes >= STY_RETAKES_MAX)
		return TL_OK;
	return append_retake(s, pid, trial, orig, err, err_size);
}
