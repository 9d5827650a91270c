/* study_internal.h (private) — the study handle and helpers shared by the study module's files. */
#ifndef TASLAB_STUDY_INTERNAL_H
#define TASLAB_STUDY_INTERNAL_H

#include <pthread.h>
#include <sqlite3.h>

#include "taslab/study.h"
#include "taslab/tl_fs.h"

struct sty {
	sqlite3 *db;
	char path[TL_PATH_MAX];      /* the study's name (messages, exports' self-check) */
	char open_path[TL_PATH_MAX]; /* the file SQLite has open: path, or the temporary file of a new study */
	tl_atomic pending;           /* a new study not yet committed (pending.open) */
	char stimuli[TL_PATH_MAX];
	char token[33];
	char served_url[256];
	pthread_mutex_t lock; /* serialises read-check-write sequences of concurrent server threads */
};

/* Formats "DB: what: sqlite message" into err; returns TL_ERR_DB. */
int sty_db_fail(sty *s, char *err, size_t err_size, const char *what);

/* 128 random bits from the kernel as 32 lowercase hex digits (codes, tokens, clip names must be unguessable). */
int sty_random_hex(char out[33]);

/* A text cell for a CSV file a spreadsheet may open (OWASP CSV injection; RFC 4180): a leading = + - @ TAB or
 * CR gets a ' in front; a cell holding , " CR or LF is quoted with "" for ". Returns buf (truncated to n). */
const char *sty_csv_cell(const char *s, char *buf, size_t n);

/* True when a text value would be read as a formula by a spreadsheet (first character = + - @ TAB CR). */
int sty_csv_formula(const char *s);

#endif
