/* study_serve_internal.h (private) — the server handle shared by the request logic (study_serve.c) and the
 * libmicrohttpd adapter with its connection tracking and lifecycle (study_serve_mhd.c). */
#ifndef TASLAB_STUDY_SERVE_INTERNAL_H
#define TASLAB_STUDY_SERVE_INTERNAL_H

#include <limits.h>
#include <pthread.h>
#include <stdbool.h>
#include <time.h>

#include "taslab/study_serve.h"

#define STY_ANSWER_BUCKETS 216 /* 8 per octave from 1 us to 2^27 us (134 s) */

#define STY_PARK_RESULTS 4096 /* epochs whose result a reply parked late can still find */

struct MHD_Daemon;
struct conn_track;

struct sty_server {
	sty *study;
	struct MHD_Daemon *mhd;
	char root[PATH_MAX]; /* realpath of the stimulus folder */
	uint16_t port;
	sty_server_desc desc;
	int lock_fd; /* the database file, flock'ed while serving (one server per study); -1: none */
	pthread_mutex_t log_lock;
	int starting;        /* while MHD_start_daemon runs, its messages explain a failure: keep the last */
	char start_msg[256];
	time_t log_second;
	unsigned log_count, log_dropped;
	/* Connections still reading a request (issue 31.3), for the head/body deadlines and the cap on them. */
	pthread_mutex_t conn_lock;
	pthread_cond_t conn_wake;
	struct conn_track *conns; /* every open connection, newest first */
	unsigned reading;         /* of them, in CONN_HEAD or CONN_BODY */
	bool watching;            /* the watchdog thread runs */
	bool stopping;
	pthread_t watchdog;
	sty_server_stats stats;
	uint64_t answer_us[STY_ANSWER_BUCKETS]; /* answers by handling time, bucket floor(8 log2 us) (atomic) */
	/* Replies waiting for their batch's commit, their connections suspended (study_serve_mhd.c, issue 32.3). */
	pthread_mutex_t park_lock;
	struct conn_state *parked;
	uint64_t reported;               /* the committer has reported every epoch below this */
	int results[STY_PARK_RESULTS];   /* their results, by epoch modulo STY_PARK_RESULTS */
	bool committing;                 /* the committer thread runs */
	uint64_t commits;                /* batches the committer committed (atomic) */
	/* Replies computed on threads of their own (sty_slow_pending), under park_lock: how many run; signalled as each
	 * ends (the stop waits for none). */
	unsigned slow_running;
	bool slow_closed; /* stopping: no more start */
	pthread_cond_t slow_done;
};

/* A reply that takes long to compute (the status's tally: seconds for a large study) would stall every connection of
 * the server thread that computes it. When the thread's sty_slow_allowed is set (the libmicrohttpd adapter), the
 * handler leaves the work in sty_slow_pending instead (its own response is a placeholder to release), and the
 * adapter runs it on a thread of its own with the connection suspended. */
#define STY_SLOW_MAX 2 /* such replies computed at once; more get 503 */
extern __thread bool sty_slow_allowed;
extern __thread void (*sty_slow_pending)(struct sty_server *sv, sty_response *r);

/* Event lines (answers stored, sessions started or completed) of a request whose reply may wait for its commit
 * (study_serve_mhd.c): held here while the thread's sty_events_held points at them, and logged once the commit is
 * done, or dropped when it failed (its own line says so) — the log never lists an answer that was not stored. */
typedef struct sty_held_events {
	char text[1024]; /* lines: 'E' (an event, never rate-limited) or 'L' (rate-limited), the line, '\n' */
	size_t len;
} sty_held_events;
extern __thread sty_held_events *sty_events_held;
/* The held lines to the log (never rate-limited), emptied. */
void sty_serve_events_flush(struct sty_server *sv, sty_held_events *h);
/* A line that is never rate-limited (a failed commit). */
void sty_serve_event(struct sty_server *sv, const char *fmt, ...);

/* One line to the server's log (desc.log, else stderr), at most 10 a second; newlines become spaces. */
void sty_serve_log(struct sty_server *sv, const char *fmt, ...);
/* `r` initialised to a JSON error {"error": msg} with `status`. */
void sty_response_error(sty_response *r, unsigned status, const char *msg);

#endif
