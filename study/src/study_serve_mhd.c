/* study_serve_mhd.c — the study server on libmicrohttpd (study_serve.h): the adapter that collects a request and
 * sends sty_server_handle's response, the tracking of connections against slow clients, and the server's lifecycle.
 * The request logic is study_serve.c's. */
#define _DEFAULT_SOURCE /* realpath */
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <microhttpd.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "study_internal.h"
#include "study_serve_internal.h"
#include "study_session.h"

#define MAX_HEADERS 64

/* libmicrohttpd's error log (MHD_OPTION_EXTERNAL_LOGGER): through sty_serve_log, one line each. */
static void mhd_log(void *cls, const char *fmt, va_list ap)
{
	char msg[400];
	vsnprintf(msg, sizeof msg, fmt, ap);
	sty_serve_log(cls, "%s", msg);
}

/* ------------------------------------------------------------------ libmicrohttpd adapter */

typedef struct conn_state {
	char body[STY_MAX_BODY_B + 1];
	size_t len;
	bool too_large;
	/* a reply parked until its batch's commit (on_commit resumes the connection) */
	bool resumed, answer, holding; /* holding: `reply` is this state's until it is queued */
	sty_held_events events;        /* its log lines, logged once its commit is done */
	int commit_rc;
	uint64_t ticket;
	sty_response reply;
	struct timespec t0;
	struct MHD_Connection *c;
	struct conn_state *next;
} conn_state;

typedef struct header_list {
	sty_http_field f[MAX_HEADERS];
	size_t n;
	bool overflow;
} header_list;

static enum MHD_Result collect_header(void *cls, enum MHD_ValueKind kind, const char *key, const char *value)
{
	(void)kind;
	header_list *h = cls;
	if (h->n == MAX_HEADERS) {
		h->overflow = true;
		return MHD_NO;
	}
	h->f[h->n++] = (sty_http_field){key, value};
	return MHD_YES;
}

/* A clip followed by its padding (study_session.h): file_size bytes of the file from file_offset, then pad_size bytes
 * of the padding from pad_offset into it. */
typedef struct padded_body {
	int fd;
	uint64_t file_offset, file_size, pad_offset, pad_total;
	const char *pad_ext;
} padded_body;

static ssize_t padded_read(void *cls, uint64_t pos, char *buf, size_t max)
{
	padded_body *p = cls;
	if (pos < p->file_size) {
		size_t n = p->file_size - pos < max ? (size_t)(p->file_size - pos) : max;
		ssize_t got = pread(p->fd, buf, n, (off_t)(p->file_offset + pos));
		return got > 0 ? got : MHD_CONTENT_READER_END_WITH_ERROR; /* the file shrank or failed: end the reply */
	}
	sty_pad_bytes(p->pad_ext, p->pad_total, p->pad_offset + (pos - p->file_size), (uint8_t *)buf, max);
	return (ssize_t)max; /* MHD asks no further than the size it was given */
}

static void padded_free(void *cls)
{
	padded_body *p = cls;
	close(p->fd);
	free(p);
}

static enum MHD_Result queue(struct MHD_Connection *c, sty_response *r)
{
	struct MHD_Response *m;
	padded_body *pb;
	if (r->fd >= 0 && r->pad_size) {
		m = NULL;
		if ((pb = malloc(sizeof *pb))) {
			*pb = (padded_body){r->fd, r->file_offset, r->file_size, r->pad_offset, r->pad_total, r->pad_ext};
			m = MHD_create_response_from_callback(r->file_size + r->pad_size, 64 * 1024, padded_read, pb, padded_free);
		}
		if (m)
			r->fd = -1; /* padded_free closes it */
		else
			free(pb);
	} else if (r->fd >= 0) {
		m = MHD_create_response_from_fd_at_offset64(r->file_size, r->fd, r->file_offset);
		if (m)
			r->fd = -1; /* MHD closes it */
	} else {
		m = MHD_create_response_from_buffer(r->body_size, r->body ? r->body : (char *)"", MHD_RESPMEM_MUST_COPY);
	}
	if (!m) {
		sty_response_release(r);
		return MHD_NO;
	}
	MHD_add_response_header(m, "Content-Type", r->content_type);
	MHD_add_response_header(m, "X-Content-Type-Options", "nosniff");
	if (!r->cacheable)
		MHD_add_response_header(m, "Cache-Control", "no-store");
	if (r->accept_ranges)
		MHD_add_response_header(m, "Accept-Ranges", "bytes");
	if (r->content_range[0])
		MHD_add_response_header(m, "Content-Range", r->content_range);
	if (r->authenticate)
		MHD_add_response_header(m, "WWW-Authenticate", "Bearer realm=\"taslab study\"");
	if (r->close)
		MHD_add_response_header(m, "Connection", "close");
	enum MHD_Result ret = MHD_queue_response(c, r->status, m);
	MHD_destroy_response(m);
	sty_response_release(r);
	return ret;
}

/* ------------------------------------------------------------------ slow clients (issue 31.3)
 * libmicrohttpd's timeout (MHD_OPTION_CONNECTION_TIMEOUT) is an idle timeout: every byte resets it, so a client
 * sending a header byte a second keeps its connection for ever, and a few hundred such connections (under the
 * per-address cap, from a few addresses) filled every slot while real participants waited. Version 0.9.75 has no
 * deadline of its own, so each connection is tracked here (MHD_OPTION_NOTIFY_CONNECTION) through its phases:
 * reading a head, reading a body, answering. A watchdog thread closes those whose head, body or reply is overdue
 * (a reply read a few bytes at a time holds a connection as long as a trickled head would), and a
 * new connection beyond max_reading closes the one that has been reading longest (a participant's browser sends its
 * head at once, so it is never the oldest for long). Closing is shutdown(2) on the socket, which libmicrohttpd's
 * own loop then sees as the client going away; the entry leaves the list in the CLOSED notification, which
 * libmicrohttpd sends before it closes the descriptor, and both happen under conn_lock, so a shutdown never hits a
 * reused descriptor. */
enum { CONN_HEAD, CONN_BODY, CONN_ANSWER, CONN_CLOSING };

typedef struct conn_track {
	struct conn_track *prev, *next;
	int fd;
	int phase;
	struct timespec since; /* when the phase began */
} conn_track;

static double elapsed_s(const struct timespec *since, const struct timespec *now)
{
	return (double)(now->tv_sec - since->tv_sec) + (double)(now->tv_nsec - since->tv_nsec) * 1e-9;
}

static unsigned head_timeout_s(const struct sty_server *sv) { return sv->desc.head_timeout_s ? sv->desc.head_timeout_s : 10u; }
static unsigned body_timeout_s(const struct sty_server *sv) { return sv->desc.body_timeout_s ? sv->desc.body_timeout_s : 10u; }
static unsigned send_timeout_s(const struct sty_server *sv) { return sv->desc.send_timeout_s ? sv->desc.send_timeout_s : 120u; }
static unsigned max_reading(const struct sty_server *sv)
{
	unsigned all = sv->desc.max_connections ? sv->desc.max_connections : 1024u;
	return sv->desc.max_reading ? sv->desc.max_reading : (all / 2 ? all / 2 : 1);
}

/* Moves a connection to `phase` (conn_lock held), keeping the count of those reading. */
static void conn_phase(struct sty_server *sv, conn_track *t, int phase)
{
	int was = t->phase <= CONN_BODY, is = phase <= CONN_BODY;
	sv->reading += (unsigned)is - (unsigned)was;
	t->phase = phase;
	clock_gettime(CLOCK_MONOTONIC, &t->since);
}

/* Closes an overdue connection (conn_lock held): libmicrohttpd sees the end of its stream and cleans it up. */
static void conn_close(struct sty_server *sv, conn_track *t)
{
	shutdown(t->fd, SHUT_RDWR);
	conn_phase(sv, t, CONN_CLOSING);
}

static void on_connection(void *cls, struct MHD_Connection *c, void **socket_context, enum MHD_ConnectionNotificationCode toe)
{
	struct sty_server *sv = cls;
	conn_track *t = *socket_context;
	if (toe == MHD_CONNECTION_NOTIFY_STARTED) {
		const union MHD_ConnectionInfo *ci = MHD_get_connection_info(c, MHD_CONNECTION_INFO_CONNECTION_FD);
		if (!ci || !(t = calloc(1, sizeof *t)))
			return; /* untracked: only the idle timeout applies to it */
		t->fd = ci->connect_fd;
		t->phase = CONN_ANSWER;
		pthread_mutex_lock(&sv->conn_lock);
		if (sv->reading >= max_reading(sv)) {
			conn_track *oldest = NULL; /* the longest in its reading phase (phases restart on keep-alive) */
			for (conn_track *o = sv->conns; o; o = o->next)
				if (o->phase <= CONN_BODY && (!oldest || elapsed_s(&o->since, &oldest->since) > 0))
					oldest = o;
			if (oldest) {
				conn_close(sv, oldest);
				sv->stats.evicted++;
			}
		}
		conn_phase(sv, t, CONN_HEAD);
		t->next = sv->conns;
		if (sv->conns)
			sv->conns->prev = t;
		sv->conns = t;
		pthread_mutex_unlock(&sv->conn_lock);
		*socket_context = t;
		return;
	}
	if (!t)
		return;
	pthread_mutex_lock(&sv->conn_lock);
	conn_phase(sv, t, CONN_CLOSING);
	if (t->prev)
		t->prev->next = t->next;
	else
		sv->conns = t->next;
	if (t->next)
		t->next->prev = t->prev;
	pthread_mutex_unlock(&sv->conn_lock);
	free(t);
	*socket_context = NULL;
}

/* The tracked connection of a request (NULL when untracked). */
static conn_track *tracked(struct MHD_Connection *c)
{
	const union MHD_ConnectionInfo *ci = MHD_get_connection_info(c, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
	return ci ? ci->socket_context : NULL;
}

static void track_phase(struct sty_server *sv, struct MHD_Connection *c, int phase)
{
	conn_track *t = tracked(c);
	if (!t)
		return;
	pthread_mutex_lock(&sv->conn_lock);
	if (t->phase != CONN_CLOSING && t->phase != phase)
		conn_phase(sv, t, phase);
	pthread_mutex_unlock(&sv->conn_lock);
}

/* Closes the connections whose head, body or reply is overdue, four times a second, until the server stops. */
static void *watchdog_main(void *arg)
{
	struct sty_server *sv = arg;
	uint64_t evicted_logged = 0;
	pthread_mutex_lock(&sv->conn_lock);
	while (!sv->stopping) {
		struct timespec now, wake;
		clock_gettime(CLOCK_MONOTONIC, &now);
		unsigned heads = 0, bodies = 0, sends = 0;
		for (conn_track *t = sv->conns; t; t = t->next) {
			double age = elapsed_s(&t->since, &now);
			if (t->phase == CONN_HEAD && age > head_timeout_s(sv))
				conn_close(sv, t), heads++;
			else if (t->phase == CONN_BODY && age > body_timeout_s(sv))
				conn_close(sv, t), bodies++;
			else if (t->phase == CONN_ANSWER && age > send_timeout_s(sv)) {
				/* and what the kernel still holds of the reply is dropped (a reset when libmicrohttpd closes
				 * the socket) rather than trickled out after the deadline */
				setsockopt(t->fd, SOL_SOCKET, SO_LINGER, &(struct linger){.l_onoff = 1, .l_linger = 0},
					   sizeof(struct linger));
				conn_close(sv, t), sends++;
			}
		}
		sv->stats.head_timeouts += heads;
		sv->stats.body_timeouts += bodies;
		sv->stats.send_timeouts += sends;
		uint64_t evicted = sv->stats.evicted - evicted_logged;
		evicted_logged = sv->stats.evicted;
		if (heads || bodies || sends || evicted) {
			pthread_mutex_unlock(&sv->conn_lock);
			sty_serve_log(sv, "slow clients: closed %u connection(s) without a complete request head within %u s, %u without "
				   "a complete body within %u s, %u whose reply was still being read after %u s, %llu reading longest "
				   "when more than %u were reading",
			       heads, head_timeout_s(sv), bodies, body_timeout_s(sv), sends, send_timeout_s(sv),
			       (unsigned long long)evicted, max_reading(sv));
			pthread_mutex_lock(&sv->conn_lock);
		}
		clock_gettime(CLOCK_MONOTONIC, &wake);
		wake.tv_nsec += 250 * 1000 * 1000;
		if (wake.tv_nsec >= 1000000000)
			wake.tv_sec++, wake.tv_nsec -= 1000000000;
		pthread_cond_timedwait(&sv->conn_wake, &sv->conn_lock, &wake);
	}
	pthread_mutex_unlock(&sv->conn_lock);
	return NULL;
}

/* ------------------------------------------------------------------ answers' handling time */

static void answer_timed(struct sty_server *sv, const struct timespec *since)
{
	struct timespec now;
	clock_gettime(CLOCK_MONOTONIC, &now);
	double us = elapsed_s(since, &now) * 1e6;
	int b = us < 1 ? 0 : (int)(8 * log2(us));
	__atomic_add_fetch(&sv->answer_us[b < STY_ANSWER_BUCKETS ? b : STY_ANSWER_BUCKETS - 1], 1, __ATOMIC_RELAXED);
}

/* The upper edge, in ms, of the bucket holding the answer of rank ceil(q n) (1-based) of `n`. */
static double answer_quantile_ms(const uint64_t *counts, uint64_t n, double q)
{
	uint64_t rank = (uint64_t)ceil(q * (double)n), seen = 0;
	for (int b = 0; b < STY_ANSWER_BUCKETS; b++)
		if ((seen += counts[b]) >= rank && seen)
			return exp2((b + 1) / 8.0) / 1e3;
	return 0;
}

sty_server_stats sty_server_get_stats(sty_server *sv)
{
	pthread_mutex_lock(&sv->conn_lock);
	sty_server_stats st = sv->stats;
	pthread_mutex_unlock(&sv->conn_lock);
	uint64_t counts[STY_ANSWER_BUCKETS];
	st.answers = 0;
	for (int b = 0; b < STY_ANSWER_BUCKETS; b++)
		st.answers += counts[b] = __atomic_load_n(&sv->answer_us[b], __ATOMIC_RELAXED);
	st.answer_ms_p50 = answer_quantile_ms(counts, st.answers, 0.5);
	st.answer_ms_p99 = answer_quantile_ms(counts, st.answers, 0.99);
	st.commits = __atomic_load_n(&sv->commits, __ATOMIC_RELAXED);
	return st;
}

/* A parked reply, once its batch is committed: as it was, or a 500 when the commit failed (nothing was stored). */
static enum MHD_Result deliver(struct sty_server *sv, struct MHD_Connection *c, conn_state *cs)
{
	cs->resumed = cs->holding = false;
	if (cs->commit_rc) {
		cs->events.len = 0; /* not stored: on_commit's line says so */
		sty_response_release(&cs->reply);
		sty_response_error(&cs->reply, 500, "internal error");
	} else {
		sty_serve_events_flush(sv, &cs->events);
		if (cs->answer)
			answer_timed(sv, &cs->t0);
	}
	return queue(c, &cs->reply);
}

/* The committer's report (sty_batch_committer_start): the replies parked for this batch go out. */
static void on_commit(void *ctx, uint64_t epoch, int rc, const char *why)
{
	struct sty_server *sv = ctx;
	__atomic_add_fetch(&sv->commits, 1, __ATOMIC_RELAXED);
	pthread_mutex_lock(&sv->park_lock);
	sv->results[epoch % STY_PARK_RESULTS] = rc;
	sv->reported = epoch + 1;
	if (rc) /* logged before the replies go out */
		sty_serve_event(sv, "storing: %s (a failed commit: its requests got 500, nothing of them was stored)", why);
	for (conn_state **p = &sv->parked; *p;) {
		conn_state *cs = *p;
		if (cs->ticket > epoch) {
			p = &cs->next;
			continue;
		}
		*p = cs->next;
		cs->commit_rc = rc;
		cs->resumed = true;
		MHD_resume_connection(cs->c);
	}
	pthread_mutex_unlock(&sv->park_lock);
}

/* A reply computed on a thread of its own (sty_slow_pending), its connection suspended until it is done. */
typedef struct slow_job {
	struct sty_server *sv;
	conn_state *cs;
	void (*run)(struct sty_server *sv, sty_response *r);
} slow_job;

static void *slow_main(void *arg)
{
	slow_job *j = arg;
	j->run(j->sv, &j->cs->reply);
	pthread_mutex_lock(&j->sv->park_lock);
	j->cs->resumed = true;
	MHD_resume_connection(j->cs->c);
	j->sv->slow_running--;
	pthread_cond_broadcast(&j->sv->slow_done);
	pthread_mutex_unlock(&j->sv->park_lock);
	free(j);
	return NULL;
}

/* Starts `run` for connection c (its handler's thread; the connection is suspended first, so the resume comes after
 * it). Returns false, nothing started, when STY_SLOW_MAX run already or no thread can be made. */
static bool slow_start(struct sty_server *sv, struct MHD_Connection *c, conn_state *cs,
		       void (*run)(struct sty_server *sv, sty_response *r))
{
	slow_job *j = malloc(sizeof *j);
	if (!j)
		return false;
	*j = (slow_job){sv, cs, run};
	pthread_mutex_lock(&sv->park_lock);
	bool ok = sv->slow_running < STY_SLOW_MAX && !sv->slow_closed;
	if (ok) {
		cs->c = c;
		cs->holding = true;
		MHD_suspend_connection(c);
		pthread_attr_t a;
		pthread_attr_init(&a);
		pthread_attr_setdetachstate(&a, PTHREAD_CREATE_DETACHED);
		pthread_t th;
		if (pthread_create(&th, &a, slow_main, j)) { /* resumed at once, with a 500 */
			sty_response_error(&cs->reply, 500, "internal error");
			cs->resumed = true;
			MHD_resume_connection(c); /* j is freed below */
		} else {
			sv->slow_running++;
			j = NULL; /* the thread's */
		}
		pthread_attr_destroy(&a);
	}
	pthread_mutex_unlock(&sv->park_lock);
	free(j);
	return ok;
}

static enum MHD_Result on_request(void *cls, struct MHD_Connection *c, const char *url, const char *method,
				  const char *version, const char *upload_data, size_t *upload_size, void **con_cls)
{
	(void)version;
	struct sty_server *sv = cls;
	conn_state *cs = *con_cls;
	if (cs && *upload_size) { /* a piece of the body: keep up to STY_MAX_BODY_B */
		if (cs->len + *upload_size > STY_MAX_BODY_B)
			cs->too_large = true;
		else {
			memcpy(cs->body + cs->len, upload_data, *upload_size);
			cs->len += *upload_size;
		}
		*upload_size = 0;
		return MHD_YES;
	}
	header_list h = {.n = 0};
	MHD_get_connection_values(c, MHD_HEADER_KIND, collect_header, &h);
	sty_response r;
	if (h.overflow) {
		track_phase(sv, c, CONN_ANSWER);
		sty_response_error(&r, 431, "too many header fields");
		r.close = true;
		return queue(c, &r);
	}
	sty_request rq = {.method = method, .path = url, .headers = h.f, .header_count = h.n};
	if (!cs) { /* first call: the head has arrived */
		if (!(cs = calloc(1, sizeof *cs)))
			return MHD_NO;
		*con_cls = cs;
		sty_server_handle(sv, &rq, &r);
		if (r.status == 0) {
			track_phase(sv, c, CONN_BODY);
			return MHD_YES;
		}
		track_phase(sv, c, CONN_ANSWER);
		return queue(c, &r);
	}
	if (cs->resumed)
		return deliver(sv, c, cs);
	track_phase(sv, c, CONN_ANSWER);
	rq.body = cs->body;
	rq.body_size = cs->len;
	rq.body_too_large = cs->too_large;
	clock_gettime(CLOCK_MONOTONIC, &cs->t0);
	sty_batch_defer_begin();
	cs->events.len = 0;
	sty_events_held = &cs->events;
	sty_slow_allowed = true;
	sty_slow_pending = NULL;
	sty_server_handle(sv, &rq, &r);
	sty_slow_allowed = false;
	sty_events_held = NULL;
	uint64_t ticket;
	bool parked = sty_batch_defer_end(&ticket);
	if (sty_slow_pending && !parked) { /* the reply is computed on a thread of its own: this thread goes on */
		sty_response_release(&r);
		if (slow_start(sv, c, cs, sty_slow_pending))
			return MHD_YES;
		sty_response_error(&r, 503, "busy: try again in a few seconds");
		return queue(c, &r);
	}
	if (r.status == 0) { /* cannot happen with a body; be safe */
		sty_response_error(&r, 500, "internal error");
	}
	size_t n = strlen(url);
	cs->answer = r.status == 200 && !strcmp(method, "POST") && n > 7 && !strcmp(url + n - 7, "/answer");
	if (parked) { /* the reply waits for the commit, the thread goes on with other connections */
		cs->reply = r;
		cs->holding = true;
		cs->ticket = ticket;
		cs->c = c;
		pthread_mutex_lock(&sv->park_lock);
		if (ticket >= sv->reported) {
			cs->next = sv->parked;
			sv->parked = cs;
			MHD_suspend_connection(c);
			pthread_mutex_unlock(&sv->park_lock);
			return MHD_YES;
		}
		cs->commit_rc = sv->results[ticket % STY_PARK_RESULTS]; /* committed already */
		pthread_mutex_unlock(&sv->park_lock);
		return deliver(sv, c, cs);
	}
	sty_serve_events_flush(sv, &cs->events);
	if (cs->answer)
		answer_timed(sv, &cs->t0);
	return queue(c, &r);
}

static void on_completed(void *cls, struct MHD_Connection *c, void **con_cls, enum MHD_RequestTerminationCode toe)
{
	(void)toe;
	conn_state *cs = *con_cls;
	struct sty_server *sv = cls;
	if (cs && cs->holding && !cs->resumed) { /* still parked (not seen to happen: the stop resumes them first) */
		pthread_mutex_lock(&sv->park_lock);
		for (conn_state **p = &sv->parked; *p; p = &(*p)->next)
			if (*p == cs) {
				*p = cs->next;
				break;
			}
		pthread_mutex_unlock(&sv->park_lock);
	}
	if (cs && cs->holding) { /* a parked reply never sent (the server stopping) */
		if (cs->resumed && !cs->commit_rc) /* its change is stored: the log lists it all the same */
			sty_serve_events_flush(sv, &cs->events);
		sty_response_release(&cs->reply);
	}
	free(*con_cls);
	*con_cls = NULL;
	track_phase(cls, c, CONN_HEAD); /* kept alive: the next request's head is due from now */
}

/* ------------------------------------------------------------------ lifecycle */

int sty_server_create(sty *s, const sty_server_desc *desc, sty_server **out, char *err, size_t err_size)
{
	*out = NULL;
	if (!sty_stimuli(s)[0])
		return tl_error(err, err_size, TL_ERR_ARG, "this study has no stimulus folder (an imported study cannot be served)");
	sty_server *sv = calloc(1, sizeof *sv);
	if (!sv)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	sv->study = s;
	sv->lock_fd = -1;
	if (desc)
		sv->desc = *desc;
	pthread_mutex_init(&sv->log_lock, NULL);
	pthread_mutex_init(&sv->conn_lock, NULL);
	pthread_mutex_init(&sv->park_lock, NULL);
	pthread_cond_init(&sv->slow_done, NULL);
	pthread_condattr_t ca;
	pthread_condattr_init(&ca);
	pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
	pthread_cond_init(&sv->conn_wake, &ca);
	pthread_condattr_destroy(&ca);
	if (!realpath(sty_stimuli(s), sv->root)) {
		int rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: stimulus folder missing: %s", sty_stimuli(s), strerror(errno));
		sty_server_stop(&sv);
		return rc;
	}
	*out = sv;
	return TL_OK;
}

int sty_server_start(sty *s, const sty_server_desc *desc, sty_server **out, char *err, size_t err_size)
{
	sty_server *sv;
	int rc = sty_server_create(s, desc, &sv, err, err_size);
	if (rc)
		return rc;
	const sty_server_desc *d = &sv->desc;
	/* One server per study (issue 27.5): an exclusive flock(2) on the database file, held until the server stops (or
	 * its process dies). flock, not fcntl: SQLite's own POSIX locks on the file are independent of it, and closing
	 * this descriptor does not release them. */
	sv->lock_fd = open(sty_path(s), O_RDONLY | O_CLOEXEC);
	if (sv->lock_fd < 0 || flock(sv->lock_fd, LOCK_EX | LOCK_NB)) {
		int busy = sv->lock_fd >= 0 && errno == EWOULDBLOCK;
		rc = busy ? tl_error(err, err_size, TL_ERR_CONFLICT, "%s is being served already (by another 'taslab study serve'%s%s); "
				     "stop that server first: one server per study", sty_path(s), sty_served_url(s)[0] ? " on " : "",
				     sty_served_url(s))
			  : tl_error(err, err_size, TL_ERR_INPUT, "%s: cannot open the study to lock it: %s", sty_path(s),
				     strerror(errno));
		sty_server_stop(&sv);
		return rc;
	}
	const char *bind = d->bind ? d->bind : "127.0.0.1";
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons(d->port)};
	if (inet_pton(AF_INET, bind, &sa.sin_addr) != 1) {
		sty_server_stop(&sv);
		return tl_error(err, err_size, TL_ERR_ARG, "--bind '%s' is not an IPv4 address", bind);
	}
	/* The group commit's committer (study_commit.c): a request waiting for its commit gives its thread back. */
	pthread_mutex_lock(&s->lock);
	sv->reported = s->batch.epoch;
	pthread_mutex_unlock(&s->lock);
	if (sty_batch_committer_start(s, on_commit, sv)) {
		sty_server_stop(&sv);
		return tl_error(err, err_size, TL_ERR_NOMEM, "cannot start the server's commit thread");
	}
	sv->committing = true;
	sv->starting = 1;
	/* Limits against one client locking the others out: connections per client address and in all, an idle
	 * timeout (silent connections are closed), and the head/body deadlines and the cap on reading connections of
	 * on_connection and the watchdog (trickling connections are closed). */
	/* The logger comes first, or MHD prints the messages of the options before it itself. */
	sv->mhd = MHD_start_daemon(MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_AUTO | MHD_USE_ERROR_LOG |
					   MHD_ALLOW_SUSPEND_RESUME, 0, NULL, NULL,
				   on_request, sv, MHD_OPTION_EXTERNAL_LOGGER, mhd_log, sv, MHD_OPTION_SOCK_ADDR,
				   (struct sockaddr *)&sa, MHD_OPTION_THREAD_POOL_SIZE, d->threads ? d->threads : 4u,
				   MHD_OPTION_NOTIFY_COMPLETED, on_completed, sv, MHD_OPTION_NOTIFY_CONNECTION, on_connection, sv,
				   MHD_OPTION_CONNECTION_TIMEOUT,
				   d->timeout_s ? d->timeout_s : 15u, MHD_OPTION_CONNECTION_LIMIT,
				   d->max_connections ? d->max_connections : 1024u, MHD_OPTION_PER_IP_CONNECTION_LIMIT,
				   d->max_per_client, MHD_OPTION_END);
	pthread_mutex_lock(&sv->log_lock);
	sv->starting = 0;
	pthread_mutex_unlock(&sv->log_lock);
	if (!sv->mhd) {
		/* MHD's own words ("Failed to bind to port 0: Address already in use" — it names the port it was given
		 * apart from the address, 0): keep the system's reason and say what to do. */
		const char *why = strrchr(sv->start_msg, ':') ? strrchr(sv->start_msg, ':') + 1 : sv->start_msg;
		while (*why == ' ')
			why++;
		const char *hint = strstr(why, "in use") ? "choose another --port, or --port 0 for any free one"
				   : strstr(why, "assign") ? "--bind must be an address of this machine"
				   : "see the message";
		if (!*why)
			why = "libmicrohttpd could not start";
		rc = tl_error(err, err_size, TL_ERR_ARG, "cannot listen on %s:%u: %s (%s)", bind, (unsigned)d->port, why, hint);
		sty_server_stop(&sv);
		return rc;
	}
	if (pthread_create(&sv->watchdog, NULL, watchdog_main, sv)) {
		sty_server_stop(&sv);
		return tl_error(err, err_size, TL_ERR_NOMEM, "cannot start the server's watchdog thread");
	}
	sv->watching = true;
	const union MHD_DaemonInfo *info = MHD_get_daemon_info(sv->mhd, MHD_DAEMON_INFO_BIND_PORT);
	sv->port = info ? info->port : d->port;
	char url[128];
	snprintf(url, sizeof url, "http://%s:%u", bind, (unsigned)sv->port);
	if ((rc = sty_set_served_url(s, url, err, err_size))) {
		sty_server_stop(&sv);
		return rc;
	}
	*out = sv;
	return TL_OK;
}

uint16_t sty_server_port(const sty_server *sv) { return sv->port; }

void sty_server_stop(sty_server **psv)
{
	if (!psv || !*psv)
		return;
	struct sty_server *sv = *psv;
	if (sv->watching) { /* first, so that no shutdown(2) meets a descriptor the daemon closes while stopping */
		pthread_mutex_lock(&sv->conn_lock);
		sv->stopping = true;
		pthread_cond_signal(&sv->conn_wake);
		pthread_mutex_unlock(&sv->conn_lock);
		pthread_join(sv->watchdog, NULL);
	}
	if (sv->committing) /* commits what is open and resumes its parked replies; later requests wait as before */
		sty_batch_committer_stop(sv->study);
	pthread_mutex_lock(&sv->park_lock); /* the replies computed on threads of their own: resumed before the stop */
	sv->slow_closed = true;
	while (sv->slow_running)
		pthread_cond_wait(&sv->slow_done, &sv->park_lock);
	pthread_mutex_unlock(&sv->park_lock);
	if (sv->mhd)
		MHD_stop_daemon(sv->mhd);
	if (sv->lock_fd >= 0)
		close(sv->lock_fd); /* releases the study's serve lock */
	pthread_cond_destroy(&sv->conn_wake);
	pthread_mutex_destroy(&sv->conn_lock);
	pthread_mutex_destroy(&sv->park_lock);
	pthread_cond_destroy(&sv->slow_done);
	pthread_mutex_destroy(&(*psv)->log_lock);
	free(*psv);
	*psv = NULL;
}
