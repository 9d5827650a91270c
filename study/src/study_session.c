/* study_session.c — one session per participant link, answers tied to it, and clips padded to one byte length per
 * scene x camera path (study_session.h; issue 27). */
#include <pthread.h>
#include <sqlite3.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "study_select.h"
#include "study_session.h"
#include "study_telemetry.h"

/* Made on first use, so that a study file made before sessions existed still opens read-only elsewhere (status,
 * tally). last_idx/last_answer: the answer this session stored last (a retry of it is recognised). */
static const char *SESSIONS =
	"CREATE TABLE IF NOT EXISTS sessions(participant INTEGER PRIMARY KEY REFERENCES participants(id),"
	" token TEXT NOT NULL, started TEXT NOT NULL, starts INTEGER NOT NULL, last_idx INTEGER, last_answer INTEGER)";

/* label, answered and total of participant `pid` into `info`. */
static void fill_info(sty *s, int64_t pid, sty_session_info *info)
{
	sqlite3_stmt *st;
	if (!(st = sty_stmt(s,
			    "SELECT (SELECT label FROM participants WHERE id = ?1), count(*) FILTER (WHERE retake_of IS NULL) -"
			    " count(*) FILTER (WHERE NOT EXISTS (SELECT 1 FROM answers a WHERE a.participant = ?1"
			    "  AND a.idx = t.idx)),"
			    " count(*) FILTER (WHERE retake_of IS NULL) FROM trials t WHERE t.participant = ?1"))) /* one pass */
		return;
	sqlite3_bind_int64(st, 1, pid);
	if (sqlite3_step(st) == SQLITE_ROW && sqlite3_column_text(st, 0)) {
		snprintf(info->label, sizeof info->label, "%s", (const char *)sqlite3_column_text(st, 0));
		info->answered = (uint32_t)sqlite3_column_int(st, 1);
		info->total = (uint32_t)sqlite3_column_int(st, 2);
	}
	sty_stmt_done(s, st);
}

/* Within the caller's transaction: the session row of participant `pid` made or taken over by a new token. */
static int start_in_tx(sty *s, int64_t pid, char session[33], sty_session_info *info, char *err, size_t err_size)
{
	sqlite3_stmt *st = NULL;
	if (sty_exec(s, SESSIONS) != SQLITE_OK ||
	    !(st = sty_stmt(s, "SELECT starts FROM sessions WHERE participant = ?")))
		return sty_db_fail(s, err, err_size, "session");
	sqlite3_bind_int64(st, 1, pid);
	info->restart = sqlite3_step(st) == SQLITE_ROW;
	sty_stmt_done(s, st);
	if (!sty_random_hex(session))
		return tl_error(err, err_size, TL_ERR_INTERNAL, "no random bits from the kernel");
	if (!(st = sty_stmt(s,
			    "INSERT INTO sessions(participant, token, started, starts) VALUES(?1, ?2,"
			    " strftime('%Y-%m-%dT%H:%M:%fZ','now'), 1) ON CONFLICT(participant) DO UPDATE SET token = ?2,"
			    " started = excluded.started, starts = starts + 1, last_idx = NULL, last_answer = NULL")))
		return sty_db_fail(s, err, err_size, "session");
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_text(st, 2, session, -1, SQLITE_STATIC);
	int rc = sqlite3_step(st) == SQLITE_DONE ? TL_OK : sty_db_fail(s, err, err_size, "session");
	sty_stmt_done(s, st);
	return rc;
}

int sty_session_start(sty *s, const char *code, char session[33], sty_session_info *info, char *err, size_t err_size)
{
	memset(info, 0, sizeof *info);
	session[0] = 0;
	sty_batch_lock(s); /* the server's writes share commits (study_commit.c) */
	int rc = TL_OK;
	int64_t pid = sty_select_participant(s, code);
	if (pid < 0)
		rc = tl_error(err, err_size, TL_ERR_NOTFOUND, "unknown participant");
	else {
		rc = sty_batch_join(s, err, err_size);
		if (!rc)
			rc = start_in_tx(s, pid, session, info, err, err_size);
		rc = sty_batch_leave(s, rc, true, err, err_size);
		if (!rc)
			fill_info(s, pid, info);
	}
	if (rc)
		session[0] = 0;
	pthread_mutex_unlock(&s->lock);
	return rc;
}

/* Within the caller's transaction: the session check, the answer, the session's memory of it. */
static int answer_in_session(sty *s, int64_t pid, const char *session, uint32_t trial, int64_t answer, int64_t rt_ms,
			     const sty_telemetry *tm, sty_session_info *info, char *err, size_t err_size)
{
	sqlite3_stmt *st;
	if (sty_exec(s, SESSIONS) != SQLITE_OK ||
	    !(st = sty_stmt(s, "SELECT token, last_idx, last_answer FROM sessions WHERE participant = ?")))
		return sty_db_fail(s, err, err_size, "session");
	sqlite3_bind_int64(st, 1, pid);
	int r = sqlite3_step(st), current = 0;
	int64_t last_idx = -1, last_answer = 0;
	if (r == SQLITE_ROW) {
		current = !strcmp((const char *)sqlite3_column_text(st, 0), session);
		if (sqlite3_column_type(st, 1) != SQLITE_NULL)
			last_idx = sqlite3_column_int64(st, 1), last_answer = sqlite3_column_int64(st, 2);
	}
	sty_stmt_done(s, st);
	if (r != SQLITE_ROW && r != SQLITE_DONE)
		return sty_db_fail(s, err, err_size, "session");
	if (!current) {
		info->superseded = true;
		return tl_error(err, err_size, TL_ERR_CONFLICT, "this link was opened in another window, which has taken over the "
				"session; this answer was not stored");
	}
	int rc = sty_select_answer(s, pid, trial, answer, rt_ms, err, err_size);
	if (rc == TL_ERR_CONFLICT && last_idx == (int64_t)trial && last_answer == answer) {
		info->repeat = true;
		return TL_OK;
	}
	if (!rc && tm)
		rc = sty_telemetry_store(s, pid, trial, tm, info->broken, sizeof info->broken, err, err_size);
	if (rc)
		return rc;
	if (!(st = sty_stmt(s, "UPDATE sessions SET last_idx = ?, last_answer = ? WHERE participant = ?")))
		return sty_db_fail(s, err, err_size, "session");
	sqlite3_bind_int64(st, 1, trial);
	sqlite3_bind_int64(st, 2, answer);
	sqlite3_bind_int64(st, 3, pid);
	rc = sqlite3_step(st) == SQLITE_DONE ? TL_OK : sty_db_fail(s, err, err_size, "session");
	sty_stmt_done(s, st);
	return rc;
}

int sty_session_answer(sty *s, const char *code, const char *session, uint32_t trial, int64_t answer, int64_t rt_ms,
		       const sty_telemetry *tm, sty_session_info *info, char *err, size_t err_size)
{
	memset(info, 0, sizeof *info);
	if (answer < -2 || answer > 2)
		return tl_error(err, err_size, TL_ERR_ARG, "answer must be an integer from -2 to 2");
	if (rt_ms < -1 || rt_ms > STY_RT_MS_MAX)
		return tl_error(err, err_size, TL_ERR_ARG, "rt_ms must be a whole number of milliseconds from 0 to %d",
				STY_RT_MS_MAX);
	sty_batch_lock(s);
	int rc;
	int64_t pid = sty_select_participant(s, code);
	if (pid < 0)
		rc = tl_error(err, err_size, TL_ERR_NOTFOUND, "unknown participant");
	else {
		/* In the group commit (study_commit.c): acknowledged only once committed. A repeat (the answer this session
		 * stored already) waits for that commit too: its first request may still be waiting for it. */
		rc = sty_batch_join(s, err, err_size);
		if (!rc)
			rc = session ? answer_in_session(s, pid, session, trial, answer, rt_ms, tm, info, err, err_size)
				     : sty_select_answer(s, pid, trial, answer, rt_ms, err, err_size);
		if (!rc && !session && tm)
			rc = sty_telemetry_store(s, pid, trial, tm, info->broken, sizeof info->broken, err, err_size);
		rc = sty_batch_leave(s, rc, true, err, err_size);
	}
	if (pid >= 0)
		fill_info(s, pid, info);
	pthread_mutex_unlock(&s->lock);
	return rc;
}

/* ------------------------------------------------------------------ padding */

static const char *container(const char *path)
{
	size_t n = strlen(path);
	if (n >= 5 && !strcmp(path + n - 5, ".webm"))
		return ".webm";
	if (n >= 4 && !strcmp(path + n - 4, ".mp4"))
		return ".mp4";
	return NULL;
}

int sty_clip_padded_size(sty *s, const char *root, const char *name, const char *rel, uint64_t *padded, char *err,
			 size_t err_size)
{
	*padded = 0;
	if (!container(rel))
		return TL_OK;
	sqlite3_stmt *st;
	pthread_mutex_lock(&s->lock);
	int rc = TL_OK;
	uint64_t largest = 0;
	/* every clip of the conditions that share this clip's reference: one scene x camera path, catch pairs included */
	if (!(st = sty_stmt(s,
			    "SELECT c2.ref_clip, c2.test_clip FROM clip_names k JOIN trials t ON t.participant = k.participant"
			    " AND t.idx = k.idx JOIN conditions c ON c.id = t.condition"
			    " JOIN conditions c2 ON c2.ref_clip = c.ref_clip"
			    " WHERE k.name = ?"))) {
		rc = sty_db_fail(s, err, err_size, "clip size");
		goto out;
	}
	sqlite3_bind_text(st, 1, name, -1, SQLITE_STATIC);
	int r;
	while ((r = sqlite3_step(st)) == SQLITE_ROW)
		for (int c = 0; c < 2; c++) {
			char path[2 * TL_PATH_MAX + 2];
			struct stat sb;
			snprintf(path, sizeof path, "%s/%s", root, (const char *)sqlite3_column_text(st, c));
			if (stat(path, &sb) == 0 && (uint64_t)sb.st_size > largest)
				largest = (uint64_t)sb.st_size;
		}
	sty_stmt_done(s, st);
	if (r != SQLITE_DONE)
		rc = sty_db_fail(s, err, err_size, "clip size");
	else
		*padded = largest + STY_PAD_MIN_B;
out:
	pthread_mutex_unlock(&s->lock);
	return rc;
}

void sty_pad_bytes(const char *ext, uint64_t pad_total, uint64_t offset, uint8_t *buf, size_t len)
{
	uint8_t head[16] = {0};
	size_t head_len;
	if (!strcmp(ext, ".webm")) {
		/* EBML Void (ID 0xEC, RFC 8794 section 11.3.2; Matroska lets it stand at any level), an 8-byte size
		 * (marker 0x01, then 56 bits) and zeros. */
		uint64_t data = pad_total - 9;
		head[0] = 0xEC;
		head[1] = 0x01;
		for (int i = 0; i < 7; i++)
			head[2 + i] = (uint8_t)(data >> (8 * (6 - i)));
		head_len = 9;
	} else if (pad_total <= 0xffffffffull) {
		/* ISO/IEC 14496-12 section 8.1.2: a 'free' box, ignored by readers; 32-bit size */
		for (int i = 0; i < 4; i++)
			head[i] = (uint8_t)(pad_total >> (8 * (3 - i)));
		memcpy(head + 4, "free", 4);
		head_len = 8;
	} else { /* size 1: a 64-bit largesize follows the type */
		head[3] = 1;
		memcpy(head + 4, "free", 4);
		for (int i = 0; i < 8; i++)
			head[8 + i] = (uint8_t)(pad_total >> (8 * (7 - i)));
		head_len = 16;
	}
	for (size_t i = 0; i < len; i++)
		buf[i] = offset + i < head_len ? head[offset + i] : 0;
}
