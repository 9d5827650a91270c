/* study_serve.h — the study's web server (libmicrohttpd), bound to 127.0.0.1 by default.
 *   GET  /p/<code>               the participant page (an unguessable 128-bit link code)
 *   GET  /api/<code>/trial       the current trial (JSON: index, total, answered, training, break_before and the
 *                                clip URLs clip_a/clip_b = /clips/<opaque name>), or {"done": true}; nothing that
 *                                tells a catch trial from a test trial (only training trials are marked)
 *   POST /api/<code>/session     a new session for this link ({"session": 32 hex digits}); the link's earlier
 *                                session is superseded (one browser at a time; the newest takes over)
 *   POST /api/<code>/answer      {"trial": i, "answer": -2..2, "rt_ms": 0..STY_RT_MS_MAX[, "session": id]}, exactly
 *                                these keys, JSON integers; committed to SQLite before the 200 reply. 400 malformed
 *                                or not the current trial (answers are given in order), 404 unknown participant or
 *                                trial, 409 answered already, or {"superseded": true} when the session is not the
 *                                link's current one (nothing stored); a session's retry of the answer it stored
 *                                already is 200 {"ok": true, "repeat": true}. 413 body larger than STY_MAX_BODY_B
 *   GET  /clips/<name>           the clips of trials served so far, by the opaque names of the trial API only;
 *                                every other name is 404 (nothing else under the stimulus folder is served).
 *                                Range (RFC 7233): one byte range -> 206; a range that is invalid (last < first)
 *                                or unsatisfiable -> 416 with a Content-Range naming the size; a header that does not
 *                                parse, another unit, several ranges, If-Range (we send no validators) or a method
 *                                other than GET -> the header is ignored and the whole file is sent (200; RFC 7233
 *                                section 3.1 lets a server ignore Range). Every clip of a scene x camera path is
 *                                served at one length (padded with the container's own padding, study_session.h).
 *   GET  /status                 the live status page (no data; it asks /admin/status with the token from #TOKEN)
 *   GET  /admin/status           the study's status as JSON (study_status.h)
 *   GET  /admin/export.csv, /admin/export-pwcmp.csv   with "Authorization: Bearer <admin token>" (RFC 6750;
 *                                compared in constant time); 401 otherwise. The token is never read from the URL.
 * Framing: conflicting duplicate Content-Length, or Content-Length with Transfer-Encoding -> 400 (RFC 7230
 * section 3.3.3); any Transfer-Encoding -> 400 (chunked not last), 501 (another coding) or 411 (chunked: bodies
 * need a Content-Length), at the head. Errors are JSON {"error": "..."}; a 500 says only "internal error" (the details, which may
 * name server paths, go to the log). A client address may hold at most max_per_client connections (no cap by
 * default), an idle connection is closed after timeout_s, a request must arrive within deadlines however slowly it trickles,
 * and the connections still reading a request are capped, so slow clients cannot lock the others out. */
#ifndef TASLAB_STUDY_SERVE_H
#define TASLAB_STUDY_SERVE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "taslab/study.h"

#ifdef __cplusplus
extern "C" {
#endif

#define STY_MAX_BODY_B 4096

typedef struct sty_server sty_server;

/* Server configuration; zero fields take the defaults in brackets. */
typedef struct sty_server_desc {
	const char *bind;         /* IPv4 address to listen on [127.0.0.1] */
	uint16_t port;            /* 0: any free port (see sty_server_port) */
	unsigned threads;         /* worker threads [4] */
	unsigned max_connections; /* connections in all [1024] */
	/* connections per client address [none: a lab behind one NAT or reverse proxy is one address, issue 32.3;
	 * one client's idle connections are bounded by the deadlines and max_reading below, whatever its address] */
	unsigned max_per_client;
	unsigned timeout_s;       /* an idle connection is closed after this many seconds [15] */
	/* Deadlines that a trickle of bytes does not reset (the idle timeout does not fire on one byte a second): a
	 * request head must be complete head_timeout_s after the connection opened or its previous reply was sent
	 * [10], a body body_timeout_s after its head [10]; else the connection is closed. At most max_reading
	 * connections may be reading a request at once: a new connection beyond that closes the one that has been
	 * reading longest [max_connections / 2], so slow clients cannot hold every slot (issue 31.3). A reply must be
	 * sent within send_timeout_s of the request's completion [120, the participant page's own limit per clip]:
	 * a client reading a clip a few bytes at a time keeps its connection no longer than that. */
	unsigned head_timeout_s, body_timeout_s, max_reading, send_timeout_s;
	/* One line per event worth a look (500 details, libmicrohttpd's messages), without a newline;
	 * NULL: "taslab study serve: LINE" on stderr. */
	void (*log)(void *cls, const char *line);
	void *log_cls;
} sty_server_desc;

/* Starts serving (own threads) and records the URL in the study (sty_set_served_url). The study must outlive
 * the server. TL_ERR_ARG for a bad address or a port that cannot be bound (the reason in `err`). */
int sty_server_start(sty *s, const sty_server_desc *desc, sty_server **out, char *err, size_t err_size);
/* A server that handles requests given to sty_server_handle but does not listen (tests, fuzzing). */
int sty_server_create(sty *s, const sty_server_desc *desc, sty_server **out, char *err, size_t err_size);
uint16_t sty_server_port(const sty_server *sv);
/* What the server did against slow clients, counted where it closes their connections. */
typedef struct sty_server_stats {
	uint64_t head_timeouts; /* closed: no complete request head within head_timeout_s */
	uint64_t body_timeouts; /* closed: no complete body within body_timeout_s of its head */
	uint64_t evicted;       /* closed: the longest-reading connection, to make room under max_reading */
	uint64_t send_timeouts; /* closed: a reply not sent within send_timeout_s */
	/* Answers acknowledged (POST /api/CODE/answer, 200; a repeat of a stored answer included) and the server's own
	 * time for them, from the complete request to its reply queued (its batch's commit and, after that, its turn on
	 * a server thread included; not the time before the request was read): the median and the 99th percentile, in
	 * ms, to within 9 % (a histogram of 8 buckets per octave). */
	uint64_t answers;
	double answer_ms_p50, answer_ms_p99;
	uint64_t commits; /* the group commit's transactions (answers, clip names, sessions share them) */
} sty_server_stats;
sty_server_stats sty_server_get_stats(sty_server *sv);
/* Stops listening, waits for the threads, frees. Accepts NULL, nulls the pointer. */
void sty_server_stop(sty_server **sv);

/* ---- request handling without sockets (the libmicrohttpd callback is a thin adapter around it) ---- */
typedef struct sty_http_field {
	const char *name, *value;
} sty_http_field;

typedef struct sty_request {
	const char *method;            /* "GET", "POST", ... */
	const char *path;              /* the decoded path, without the query string */
	const sty_http_field *headers; /* every header field as received, duplicates kept */
	size_t header_count;
	const char *body;              /* NULL: only the head has arrived (framing checks; see status 0 below) */
	size_t body_size;
	bool body_too_large;           /* the body was longer than STY_MAX_BODY_B (and was not kept) */
} sty_request;

typedef struct sty_response {
	unsigned status;               /* 0 only for a head-only request that may go on (read the body, ask again) */
	const char *content_type;      /* static string */
	char *body;                    /* malloc'ed; or NULL with fd >= 0 */
	size_t body_size;
	int fd;                        /* >= 0: send file_size bytes of this file from file_offset (owned) */
	uint64_t file_offset, file_size;
	/* after the file's bytes, pad_size bytes of padding from pad_offset into it (clips served at one length per scene x
	 * camera path, issue 27.6): pad_total bytes of the container pad_ext's own padding in all (study_session.h) */
	uint64_t pad_offset, pad_size, pad_total;
	const char *pad_ext;
	char content_range[96];        /* "" when none */
	bool accept_ranges;            /* Accept-Ranges: bytes */
	bool authenticate;             /* WWW-Authenticate: Bearer */
	bool cacheable;                /* false: Cache-Control: no-store */
	bool close;                    /* close the connection after the reply (framing errors) */
} sty_response;

/* Handles one request; always fills `resp` (release it with sty_response_release). Thread-safe. */
void sty_server_handle(sty_server *sv, const sty_request *rq, sty_response *resp);
void sty_response_release(sty_response *resp);

#ifdef __cplusplus
}
#endif
#endif
