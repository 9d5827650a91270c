/* study_internal.h (private) — the study handle shared by the study module's files. */
#ifndef TASLAB_STUDY_INTERNAL_H
#define TASLAB_STUDY_INTERNAL_H

#include <pthread.h>
#include <sqlite3.h>

#include "taslab/study.h"

struct sty {
	sqlite3 *db;
	char path[4096];
	char stimuli[4096];
	char token[33];
	pthread_mutex_t lock; /* serialises read-check-write sequences of concurrent server threads */
};

/* Formats "DB: what: sqlite message" into err; returns TL_ERR_DB. */
int sty_db_fail(sty *s, char *err, size_t err_size, const char *what);

#endif
