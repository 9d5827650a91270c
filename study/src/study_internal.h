/* study_internal.h (private) — the study handle and helpers shared by the study module's files: the database
 * (study_db.c), the design (study_design.c), trial selection (study_select.h), CSV files (study_csv.c), the tally
 * (study_tally.c), the server (study_serve*.c) and the sweep report (study_report*.c). */
#ifndef TASLAB_STUDY_INTERNAL_H
#define TASLAB_STUDY_INTERNAL_H

#include <pthread.h>
#include <sqlite3.h>

#include "taslab/study.h"
#include "taslab/tl_fs.h"

#define STY_STMTS 64 /* prepared statements kept per handle (sty_stmt); the server uses about 40 */
#define STY_BATCH_RESULTS 64 /* results of the last batches kept for members that wake late (study_commit.c) */

struct sty {
	sqlite3 *db;
	char path[TL_PATH_MAX];      /* the study's name (messages, exports' self-check) */
	char open_path[TL_PATH_MAX]; /* the file SQLite has open: path, or the temporary file of a new study */
	tl_atomic pending;           /* a new study not yet committed (pending.open) */
	char stimuli[TL_PATH_MAX];
	char token[33];
	char served_url[256];
	char display[16];            /* "stereo": the sets' clips are side by side (pairs.json display); "" mono */
	pthread_mutex_t lock; /* serialises read-check-write sequences of concurrent server threads */
	struct sty_batch {    /* group commit of the server's writes (study_commit.c), under lock */
		bool open, leading;   /* a transaction is open; a request is gathering it before its commit */
		unsigned members;     /* requests waiting for the open batch's commit: those whose change is in it, and those that
				 * read it (sty_batch_leave) */
		unsigned coming;      /* requests waiting for the lock (atomic) */
		unsigned draining;    /* readers waiting for no open batch (sty_batch_quiesce): no new batch opens */
		uint64_t epoch;       /* batches committed (or failed) so far */
		int results[STY_BATCH_RESULTS];
		char why[256];        /* SQLite's message of the last failed commit */
		pthread_cond_t joined, done;
		/* The committer thread (sty_batch_committer_start): it commits, requests on a deferring thread do not wait */
		bool committer, stopping;
		pthread_t thread;
		pthread_cond_t work; /* a deferred member joined, or stop */
		void (*on_commit)(void *ctx, uint64_t epoch, int rc, const char *why);
		void *ctx;
	} batch;
	struct sty_stmt_slot { /* sty_stmt's cache: the SQL's address and its prepared statement */
		const char *sql;
		sqlite3_stmt *st;
	} stmts[STY_STMTS];
	unsigned stmt_count;
	struct sty_method {   /* the caller's method descriptions (sty_describe_method, issue 30.1) */
		char name[32];
		run_method_facts facts;
	} methods[STY_MAX_METHODS];
	size_t method_count;
};

/* The server's per-request SQL, prepared once per handle (study_db.c, issue 32.3): preparing a statement costs
 * SQLite several times what running one of these does. `sql` is a string constant (the cache knows it by its
 * address, and checks the text). Returns the statement reset with no bindings, or NULL (sqlite3_errmsg says why);
 * hand it back with sty_stmt_done (NULL is fine there). Under s->lock, or on a handle no other thread uses. */
sqlite3_stmt *sty_stmt(sty *s, const char *sql);
void sty_stmt_done(sty *s, sqlite3_stmt *st);
/* sty_stmt + sqlite3_step + sty_stmt_done for a statement without results (transaction control): SQLite's code. */
int sty_exec(sty *s, const char *sql);

/* Group commit (study_commit.c, issue 32.3). A server request that writes:
 *   sty_batch_lock(s);                          // instead of pthread_mutex_lock(&s->lock)
 *   rc = sty_batch_join(s, err, n);             // into the open transaction, inside a savepoint
 *   if (!rc) rc = ...its reads and writes...;
 *   rc = sty_batch_leave(s, rc, wrote, err, n); // undone on error; else returns once committed (fsync) with others
 *   pthread_mutex_unlock(&s->lock);
 * sty_batch_leave returns rc, or TL_ERR_DB when the commit failed (then nothing of the batch was stored). A request
 * with wrote = false also waits for (and fails with) the open batch's commit when other requests' writes are in it:
 * it may have read them. */
void sty_batch_init(sty *s);
void sty_batch_destroy(sty *s);
void sty_batch_lock(sty *s);
int sty_batch_join(sty *s, char *err, size_t err_size);
int sty_batch_leave(sty *s, int rc, bool wrote, char *err, size_t err_size);

/* Deferred replies (the server, issue 32.3). While a committer thread runs, a request handled between
 * sty_batch_defer_begin and sty_batch_defer_end on its thread does not wait in sty_batch_leave for its commit: that
 * returns TL_OK at once, and sty_batch_defer_end returns true with the batch's epoch in *ticket. The caller must not
 * send the reply before on_commit(ctx, ticket, rc, why) has been called for that epoch (from the committer thread,
 * s->lock not held; rc TL_OK, or TL_ERR_DB and SQLite's message: nothing of the batch was stored). So a waiting
 * request no longer holds its server thread, and a batch gathers every request that arrives during a commit. */
int sty_batch_committer_start(sty *s, void (*on_commit)(void *ctx, uint64_t epoch, int rc, const char *why), void *ctx);
/* Commits what is open, reports it, stops the thread; requests afterwards wait for their commits again. */
void sty_batch_committer_stop(sty *s);
/* For a reader of committed data only on the writers' connection (an export, the status), s->lock held: returns
 * with no batch open, so the connection shows what is on disk, and no write can start until s->lock is released.
 * While it waits, requests join the open batch but open no new one, so a steady stream of them cannot keep a batch
 * open forever. */
void sty_batch_quiesce(sty *s);
void sty_batch_defer_begin(void);
bool sty_batch_defer_end(uint64_t *ticket);

/* Formats "DB: what: sqlite message" into err; returns TL_ERR_DB. */
int sty_db_fail(sty *s, char *err, size_t err_size, const char *what);

/* Stores a value in the study's meta table (study_db.c; the design stores the stimulus folder and seed there).
 * Returns TL_OK, or TL_ERR_DB when SQLite fails (sty_db_fail says why). */
int sty_meta_set(sty *s, const char *key, const char *val);

/* The DESIGN section 4 rule for a condition, shared by design (pairs.json) and import: a described method (`f`: its
 * facts from pairs.json or sty_method_facts; NULL or not known: an unknown method), T (NAN: none) exactly when the
 * method takes a threshold, period (0: none) exactly when it takes one, 1/2/4/8.
 * Returns 0, or TL_ERR_INPUT with the reason in `why` ("method rrc needs a period (1, 2, 4 or 8)"). */
int sty_condition_rule(const run_method_facts *f, const char *method, double T, long period, char *why,
		       size_t why_size);

/* 128 random bits from the kernel as 32 lowercase hex digits (codes, tokens, clip names must be unguessable);
 * false when the kernel gives none (the caller reports it). */
bool sty_random_hex(char out[33]);

/* A text cell for a CSV file a spreadsheet may open (OWASP CSV injection; RFC 4180): a leading = + - @ TAB or
 * CR gets a ' in front; a cell holding , " CR or LF is quoted with "" for ". Returns buf (truncated to n). */
const char *sty_csv_cell(const char *s, char *buf, size_t n);

/* A number as every study output writes it (issue 27.10, one NaN convention): `fmt` (one double) when finite,
 * "inf" / "-inf" when infinite, "" when undefined (NaN) — an empty CSV cell; Markdown writers show "" as "–" and
 * JSON writers write null (and the strings "inf", "-inf"). Returns buf. */
const char *sty_num_cell(double v, const char *fmt, char *buf, size_t n);

/* True when a text value would be read as a formula by a spreadsheet (first character = + - @ TAB CR). */
int sty_csv_formula(const char *s);

#endif
