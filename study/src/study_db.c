/* study_db.c — the study database: schema, opening, creating and committing a study, its meta values (study.h).
 * The design is in study_design.c, trial selection in study_select.c. */
#define _DEFAULT_SOURCE /* getrandom, lstat */
#include <errno.h>
#include <pthread.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include "study_internal.h"
#include "taslab/tl_fs.h"

static const char *SCHEMA =
	"CREATE TABLE IF NOT EXISTS meta(key TEXT PRIMARY KEY, value TEXT NOT NULL);"
	"CREATE TABLE IF NOT EXISTS conditions(id INTEGER PRIMARY KEY, scene TEXT NOT NULL, camera TEXT NOT NULL,"
	" camera_motion TEXT NOT NULL CHECK(camera_motion IN ('stationary','moving')), method TEXT NOT NULL,"
	" T REAL, period INTEGER CHECK(period IS NULL OR period IN (1, 2, 4, 8)), ref_clip TEXT NOT NULL,"
	" test_clip TEXT NOT NULL, is_catch INTEGER NOT NULL DEFAULT 0, clip_ms REAL);" /* is_catch: 0 test, 1 catch, 2 gold */
	"CREATE TABLE IF NOT EXISTS participants(id INTEGER PRIMARY KEY, code TEXT NOT NULL UNIQUE, label TEXT NOT NULL);"
	"CREATE TABLE IF NOT EXISTS trials(participant INTEGER NOT NULL REFERENCES participants(id),"
	" idx INTEGER NOT NULL, condition INTEGER NOT NULL REFERENCES conditions(id), ref_first INTEGER NOT NULL,"
	" kind TEXT NOT NULL CHECK(kind IN ('test','catch','gold','training')), break_before INTEGER NOT NULL DEFAULT 0,"
	" retake_of INTEGER, PRIMARY KEY(participant, idx));"
	"CREATE TABLE IF NOT EXISTS answers(participant INTEGER NOT NULL, idx INTEGER NOT NULL,"
	" answer INTEGER NOT NULL CHECK(answer BETWEEN -2 AND 2), rt_ms INTEGER, at TEXT NOT NULL,"
	" play_a_ms INTEGER, play_b_ms INTEGER, dropped_frames INTEGER, total_frames INTEGER, hidden INTEGER, hidden_ms INTEGER,"
	" hidden_play INTEGER, fullscreen INTEGER, broken TEXT,"
	" PRIMARY KEY(participant, idx), FOREIGN KEY(participant, idx) REFERENCES trials(participant, idx));"
	/* The opaque clip names of the trials served so far: slot 0 is the clip shown first (A), 1 the second. */
	"CREATE TABLE IF NOT EXISTS clip_names(name TEXT PRIMARY KEY, participant INTEGER NOT NULL, idx INTEGER NOT NULL,"
	" slot INTEGER NOT NULL CHECK(slot IN (0, 1)), UNIQUE(participant, idx, slot),"
	" FOREIGN KEY(participant, idx) REFERENCES trials(participant, idx)) WITHOUT ROWID;";

int sty_db_fail(sty *s, char *err, size_t err_size, const char *what)
{
	return tl_error(err, err_size, TL_ERR_DB, "%s: %s: %s", s->path, what, s->db ? sqlite3_errmsg(s->db) : "not open");
}

/* The value of `key` in the meta table into `val` ("" and false when there is none or it cannot be read). */
static bool meta_get(sty *s, const char *key, char *val, size_t size)
{
	sqlite3_stmt *st;
	val[0] = 0;
	if (sqlite3_prepare_v2(s->db, "SELECT value FROM meta WHERE key = ?", -1, &st, NULL))
		return false;
	sqlite3_bind_text(st, 1, key, -1, SQLITE_STATIC);
	bool found = sqlite3_step(st) == SQLITE_ROW;
	if (found)
		snprintf(val, size, "%s", (const char *)sqlite3_column_text(st, 0));
	sqlite3_finalize(st);
	return found;
}

int sty_meta_set(sty *s, const char *key, const char *val)
{
	sqlite3_stmt *st;
	if (sqlite3_prepare_v2(s->db, "INSERT OR REPLACE INTO meta(key, value) VALUES(?, ?)", -1, &st, NULL))
		return TL_ERR_DB;
	sqlite3_bind_text(st, 1, key, -1, SQLITE_STATIC);
	sqlite3_bind_text(st, 2, val, -1, SQLITE_STATIC);
	int rc = sqlite3_step(st) == SQLITE_DONE ? TL_OK : TL_ERR_DB;
	sqlite3_finalize(st);
	return rc;
}

bool sty_random_hex(char out[33])
{
	uint8_t b[16];
	if (getrandom(b, sizeof b, 0) != (ssize_t)sizeof b)
		return false;
	for (int i = 0; i < 16; i++)
		snprintf(out + 2 * i, 3, "%02x", b[i]);
	return true;
}

/* Names SQLite does not treat as a file: "" (a temporary database), ":memory:", "file:" URIs. */
static int sqlite_special_name(const char *path)
{
	return !*path || !strcmp(path, ":memory:") || !strncmp(path, "file:", 5);
}

/* Whether `table` has the column `column`. */
static int has_column(sty *s, const char *table, const char *column)
{
	sqlite3_stmt *st;
	int has = 0;
	if (sqlite3_prepare_v2(s->db, "SELECT count(*) FROM pragma_table_info(?) WHERE name = ?", -1, &st, NULL) == SQLITE_OK) {
		sqlite3_bind_text(st, 1, table, -1, SQLITE_STATIC);
		sqlite3_bind_text(st, 2, column, -1, SQLITE_STATIC);
		if (sqlite3_step(st) == SQLITE_ROW)
			has = sqlite3_column_int(st, 0) > 0;
	}
	sqlite3_finalize(st);
	return has;
}

/* Columns added to the schema after studies were made with it: table, column, its declaration. The period (issue 27)
 * and, for remote participants (issue 28), each condition's clip duration, a retake's planned trial and the playback
 * telemetry of each answer (study_telemetry.c); NULL in rows made before. */
static const char *const ADDED[][3] = {
	{"conditions", "period", "period INTEGER CHECK(period IS NULL OR period IN (1, 2, 4, 8))"},
	{"conditions", "clip_ms", "clip_ms REAL"},
	{"trials", "retake_of", "retake_of INTEGER"},
	{"answers", "play_a_ms", "play_a_ms INTEGER"},
	{"answers", "play_b_ms", "play_b_ms INTEGER"},
	{"answers", "dropped_frames", "dropped_frames INTEGER"},
	{"answers", "total_frames", "total_frames INTEGER"},
	{"answers", "hidden", "hidden INTEGER"},
	{"answers", "hidden_ms", "hidden_ms INTEGER"},
	{"answers", "hidden_play", "hidden_play INTEGER"},
	{"answers", "fullscreen", "fullscreen INTEGER"},
	{"answers", "broken", "broken TEXT"},
};
#define N_ADDED (sizeof ADDED / sizeof ADDED[0])

static int schema_current(sty *s)
{
	for (size_t i = 0; i < N_ADDED; i++)
		if (!has_column(s, ADDED[i][0], ADDED[i][1]))
			return 0;
	return 1;
}

/* Brings a study made by an earlier taslab up to date: the columns of ADDED it lacks are added (empty). Studies made
 * before conditions carried a period (method x T x scene x camera only) get the period column, NULL for every
 * condition: right for every method but rrc and sau, whose period was never stored, so a study holding rrc or sau
 * conditions without a period is refused (its rrc/4 and rrc/8 conditions could not be told apart). A study that is
 * up to date is only read (so a read-only file still opens); the columns are added in one transaction, so concurrent
 * openers (a server and a tally) do not both add them. */
static int upgrade(sty *s, char *err, size_t err_size)
{
	int rc = TL_OK, missing = 0;
	if (!schema_current(s)) {
		if (sqlite3_exec(s->db, "BEGIN IMMEDIATE", NULL, NULL, NULL) != SQLITE_OK)
			return sty_db_fail(s, err, err_size, "adding columns of a newer taslab");
		for (size_t i = 0; !rc && i < N_ADDED; i++) {
			char sql[256];
			snprintf(sql, sizeof sql, "ALTER TABLE %s ADD COLUMN %s", ADDED[i][0], ADDED[i][2]);
			if (!has_column(s, ADDED[i][0], ADDED[i][1]) && sqlite3_exec(s->db, sql, NULL, NULL, NULL) != SQLITE_OK)
				rc = sty_db_fail(s, err, err_size, "adding columns of a newer taslab");
		}
		if (rc || sqlite3_exec(s->db, "COMMIT", NULL, NULL, NULL) != SQLITE_OK) {
			if (!rc)
				rc = sty_db_fail(s, err, err_size, "adding columns of a newer taslab");
			sqlite3_exec(s->db, "ROLLBACK", NULL, NULL, NULL);
			return rc;
		}
	}
	sqlite3_stmt *st;
	if (sqlite3_prepare_v2(s->db, "SELECT count(*) FROM conditions WHERE method IN ('rrc', 'sau') AND period IS NULL", -1,
			       &st, NULL) != SQLITE_OK)
		return sty_db_fail(s, err, err_size, "opening the study");
	if (sqlite3_step(st) == SQLITE_ROW)
		missing = sqlite3_column_int(st, 0);
	sqlite3_finalize(st);
	if (missing)
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: %d rrc/sau condition(s) without a period (a study made before "
				"taslab stored periods): set conditions.period with sqlite3, or make the study again", s->path,
				missing);
	return TL_OK;
}

/* Opens `file` (SQLite) for the study `s`, applies the pragmas and, when `init`, creates the schema, the admin
 * token and the markers; otherwise checks that it is a taslab study and brings the schema up to date. */
static int db_connect(sty *s, const char *file, bool init, char *err, size_t err_size)
{
	int flags = SQLITE_OPEN_READWRITE | (init ? SQLITE_OPEN_CREATE : 0) | SQLITE_OPEN_FULLMUTEX;
	if (sqlite3_open_v2(file, &s->db, flags, NULL) != SQLITE_OK)
		return tl_error(err, err_size, TL_ERR_DB, "%s: cannot open: %s", s->path,
				s->db ? sqlite3_errmsg(s->db) : "out of memory");
	sqlite3_busy_timeout(s->db, 5000);
	/* Durability: WAL with synchronous=FULL fsyncs the log at every commit, so an answer acknowledged after
	 * its COMMIT survives a crash of the server or the machine. */
	char *msg = NULL, mark[8];
	if (sqlite3_exec(s->db, "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL; PRAGMA foreign_keys=ON;", NULL, NULL,
			 &msg) != SQLITE_OK) {
		int rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: not a taslab study database (%s)", s->path, msg ? msg : "?");
		sqlite3_free(msg);
		return rc;
	}
	if (!init) {
		sqlite3_stmt *st;
		int has_meta = sqlite3_prepare_v2(s->db, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'meta'", -1,
						  &st, NULL) == SQLITE_OK &&
			       sqlite3_step(st) == SQLITE_ROW;
		sqlite3_finalize(st);
		if (!has_meta || !meta_get(s, "taslab_study", mark, sizeof mark))
			return tl_error(err, err_size, TL_ERR_INPUT, "%s: not a taslab study database (made by 'taslab study design')",
					s->path);
	}
	if (sqlite3_exec(s->db, SCHEMA, NULL, NULL, &msg) != SQLITE_OK) {
		int rc = tl_error(err, err_size, TL_ERR_DB, "%s: cannot set up the study tables (%s)", s->path, msg ? msg : "?");
		sqlite3_free(msg);
		return rc;
	}
	if (!init) {
		int rc = upgrade(s, err, err_size);
		if (rc)
			return rc;
	}
	if (init && (!sty_random_hex(s->token) || sty_meta_set(s, "admin_token", s->token) ||
		     sty_meta_set(s, "taslab_study", "1")))
		return tl_error(err, err_size, TL_ERR_DB, "%s: cannot initialise the study", s->path);
	if (!meta_get(s, "admin_token", s->token, sizeof s->token) || strlen(s->token) != 32)
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: the study has no admin token (damaged?)", s->path);
	meta_get(s, "stimuli", s->stimuli, sizeof s->stimuli);
	meta_get(s, "served_url", s->served_url, sizeof s->served_url);
	meta_get(s, "display", s->display, sizeof s->display);
	return TL_OK;
}

static sty *sty_alloc(const char *path)
{
	sty *s = calloc(1, sizeof *s);
	if (!s)
		return NULL;
	snprintf(s->path, sizeof s->path, "%s", path);
	snprintf(s->open_path, sizeof s->open_path, "%s", path);
	pthread_mutex_init(&s->lock, NULL);
	sty_batch_init(s);
	return s;
}

int sty_open(const char *path, sty **out, char *err, size_t err_size)
{
	*out = NULL;
	if (!path || sqlite_special_name(path))
		return tl_error(err, err_size, TL_ERR_ARG, "--db '%s' is not a file name (SQLite would not keep the study in a file)",
				path ? path : "");
	if (strlen(path) >= TL_PATH_MAX)
		return tl_error(err, err_size, TL_ERR_ARG, "%.64s...: path too long", path);
	if (!tl_is_file(path))
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: no such study database (create one with 'taslab study design')",
				path);
	sty *s = sty_alloc(path);
	if (!s)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	int rc = db_connect(s, path, false, err, err_size);
	if (rc) {
		sty_close(&s);
		return rc;
	}
	*out = s;
	return TL_OK;
}

/* Removes SQLite's side files of a database file (best effort). */
static void unlink_side_files(const char *file)
{
	const char *suffix[3] = {"-wal", "-shm", "-journal"};
	char p[TL_PATH_MAX + 16];
	for (int i = 0; i < 3; i++) {
		snprintf(p, sizeof p, "%s%s", file, suffix[i]);
		unlink(p);
	}
}

/* TL_ERR_CONFLICT when `path` or a side file of a database by that name exists. */
static int check_free(const char *path, char *err, size_t err_size)
{
	struct stat sb;
	if (lstat(path, &sb) == 0)
		return tl_error(err, err_size, TL_ERR_CONFLICT, "%s exists: a study is never overwritten (choose a new --db file, "
				"or delete the old one first)", path);
	const char *suffix[3] = {"-wal", "-shm", "-journal"};
	char p[TL_PATH_MAX + 16];
	for (int i = 0; i < 3; i++) {
		snprintf(p, sizeof p, "%s%s", path, suffix[i]);
		if (lstat(p, &sb) == 0)
			return tl_error(err, err_size, TL_ERR_CONFLICT, "%s exists (left by a deleted study?): SQLite would apply it to "
					"the new study; remove it or choose another --db file", p);
	}
	return TL_OK;
}

int sty_create(const char *path, sty **out, char *err, size_t err_size)
{
	*out = NULL;
	if (!path || sqlite_special_name(path))
		return tl_error(err, err_size, TL_ERR_ARG, "--db '%s' is not a file name: give the file the study is kept in "
				"(\"\", \":memory:\" and file: URIs are not kept)", path ? path : "");
	if (strlen(path) >= TL_PATH_MAX - 32)
		return tl_error(err, err_size, TL_ERR_ARG, "%.64s...: path too long", path);
	int rc = check_free(path, err, err_size);
	if (rc)
		return rc;
	tl_fs_clean_temps_beside(path); /* what a design or import killed midway left */
	sty *s = sty_alloc(path);
	if (!s)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	/* tl_fs.h detach pattern: SQLite writes the temporary file by name; sty_commit renames it into place. */
	if ((rc = tl_atomic_open(&s->pending, path, err, err_size)) || (rc = tl_atomic_detach(&s->pending, err, err_size))) {
		sty_close(&s);
		return rc;
	}
	/* The study holds the admin token and every participant's link code: owner only. SQLite gives its -wal and
	 * -shm files the mode of the database file. */
	if (chmod(s->pending.tmp, 0600) != 0) {
		rc = tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot restrict the permissions: %s", path, strerror(errno));
		sty_close(&s);
		return rc;
	}
	snprintf(s->open_path, sizeof s->open_path, "%s", s->pending.tmp);
	if ((rc = db_connect(s, s->open_path, true, err, err_size))) {
		sty_close(&s);
		return rc;
	}
	*out = s;
	return TL_OK;
}

/* sty_stmt's statements finalized (before the connection closes: SQLite refuses to close with any left). */
static void stmts_finalize(sty *s)
{
	for (unsigned i = 0; i < s->stmt_count; i++)
		sqlite3_finalize(s->stmts[i].st);
	s->stmt_count = 0;
}

int sty_commit(sty *s, char *err, size_t err_size)
{
	if (!s->pending.open)
		return TL_OK;
	/* Closing the last connection checkpoints the WAL into the file and deletes it, so the one file holds
	 * the whole study before it is renamed. */
	stmts_finalize(s);
	if (sqlite3_close(s->db) != SQLITE_OK) {
		int rc = sty_db_fail(s, err, err_size, "closing the new study");
		return rc;
	}
	s->db = NULL;
	int rc = check_free(s->path, err, err_size);
	if (!rc)
		rc = tl_atomic_commit(&s->pending, err, err_size);
	unlink_side_files(s->pending.tmp);
	if (rc) {
		tl_atomic_abort(&s->pending);
		return rc;
	}
	snprintf(s->open_path, sizeof s->open_path, "%s", s->path);
	return db_connect(s, s->path, false, err, err_size);
}

sqlite3_stmt *sty_stmt(sty *s, const char *sql)
{
	for (unsigned i = 0; i < s->stmt_count; i++)
		if (s->stmts[i].sql == sql && !strcmp(sqlite3_sql(s->stmts[i].st), sql))
			return s->stmts[i].st;
	sqlite3_stmt *st = NULL;
	if (sqlite3_prepare_v3(s->db, sql, -1, s->stmt_count < STY_STMTS ? SQLITE_PREPARE_PERSISTENT : 0, &st, NULL)) {
		sqlite3_finalize(st);
		return NULL;
	}
	if (s->stmt_count < STY_STMTS) /* else used once and finalized by sty_stmt_done */
		s->stmts[s->stmt_count++] = (struct sty_stmt_slot){sql, st};
	return st;
}

void sty_stmt_done(sty *s, sqlite3_stmt *st)
{
	if (!st)
		return;
	for (unsigned i = 0; i < s->stmt_count; i++)
		if (s->stmts[i].st == st) {
			sqlite3_reset(st);
			sqlite3_clear_bindings(st);
			return;
		}
	sqlite3_finalize(st);
}

int sty_exec(sty *s, const char *sql)
{
	sqlite3_stmt *st = sty_stmt(s, sql);
	if (!st)
		return sqlite3_errcode(s->db);
	int r = sqlite3_step(st);
	sty_stmt_done(s, st);
	return r == SQLITE_DONE || r == SQLITE_ROW ? SQLITE_OK : r;
}

void sty_close(sty **ps)
{
	if (!ps || !*ps)
		return;
	sty *s = *ps;
	stmts_finalize(s);
	if (s->db)
		sqlite3_close(s->db);
	if (s->pending.open) { /* never committed: the new study goes away */
		unlink_side_files(s->pending.tmp);
		tl_atomic_abort(&s->pending);
	}
	pthread_mutex_destroy(&s->lock);
	sty_batch_destroy(s);
	free(s);
	*ps = NULL;
}

const char *sty_stimuli(const sty *s) { return s->stimuli; }
const char *sty_path(const sty *s) { return s->path; }
const char *sty_admin_token(const sty *s) { return s->token; }
const char *sty_served_url(const sty *s) { return s->served_url; }

int sty_set_served_url(sty *s, const char *url, char *err, size_t err_size)
{
	if (strlen(url) >= sizeof s->served_url)
		return tl_error(err, err_size, TL_ERR_ARG, "served URL too long");
	pthread_mutex_lock(&s->lock);
	int bad = sty_meta_set(s, "served_url", url);
	if (!bad)
		snprintf(s->served_url, sizeof s->served_url, "%s", url);
	pthread_mutex_unlock(&s->lock);
	return bad ? sty_db_fail(s, err, err_size, "storing the served URL") : TL_OK;
}
