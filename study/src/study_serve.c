/* study_serve.c — the study web server (study_serve.h). sty_server_handle answers one parsed request (routing,
 * the answer API, clips by opaque name with RFC 7233 ranges, the token-protected exports); the libmicrohttpd
 * callback only collects the request (headers, a body of at most STY_MAX_BODY_B) and sends the response. Keeping
 * the sockets out of the request logic lets tests and the fuzzer (tests/fuzz/fuzz_serve.c) drive all of it. */
#define _DEFAULT_SOURCE /* realpath, mkdtemp, strncasecmp */
#include "taslab/study_serve.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <limits.h>
#include <microhttpd.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "study_internal.h"
#include "taslab/tl_fs.h"
#include "web/study_html.h"

#define MAX_HEADERS 64
#define LOG_LINES_PER_S 10 /* more log lines than this in one second are counted, not printed */

struct sty_server {
	sty *study;
	struct MHD_Daemon *mhd;
	char root[PATH_MAX]; /* realpath of the stimulus folder */
	uint16_t port;
	sty_server_desc desc;
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
};

/* ------------------------------------------------------------------ log */

static void default_log(void *cls, const char *line)
{
	(void)cls;
	fprintf(stderr, "taslab study serve: %s\n", line);
}

/* One line to the configured log, at most LOG_LINES_PER_S per second (a flood of bad requests must not become a
 * flood on the terminal). */
static void sv_log(struct sty_server *sv, const char *fmt, ...)
{
	char line[512];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(line, sizeof line, fmt, ap);
	va_end(ap);
	for (char *c = line; *c; c++)
		if (*c == '\n' || *c == '\r')
			*c = ' ';
	size_t n = strlen(line);
	while (n && line[n - 1] == ' ')
		line[--n] = 0;
	pthread_mutex_lock(&sv->log_lock);
	if (sv->starting) {
		snprintf(sv->start_msg, sizeof sv->start_msg, "%s", line);
		pthread_mutex_unlock(&sv->log_lock);
		return;
	}
	time_t now = time(NULL);
	unsigned dropped = 0;
	int print = 1;
	if (now != sv->log_second) {
		dropped = sv->log_dropped;
		sv->log_second = now;
		sv->log_count = sv->log_dropped = 0;
	}
	if (++sv->log_count > LOG_LINES_PER_S) {
		sv->log_dropped++;
		print = 0;
	}
	void (*log)(void *, const char *) = sv->desc.log ? sv->desc.log : default_log;
	if (dropped) {
		char note[64];
		snprintf(note, sizeof note, "(%u more messages not shown)", dropped);
		log(sv->desc.log_cls, note);
	}
	if (print)
		log(sv->desc.log_cls, line);
	pthread_mutex_unlock(&sv->log_lock);
}

/* libmicrohttpd's error log (MHD_OPTION_EXTERNAL_LOGGER): through sv_log, one line each. */
static void mhd_log(void *cls, const char *fmt, va_list ap)
{
	char msg[400];
	vsnprintf(msg, sizeof msg, fmt, ap);
	sv_log(cls, "%s", msg);
}

/* ------------------------------------------------------------------ responses */

static void resp_init(sty_response *r)
{
	memset(r, 0, sizeof *r);
	r->fd = -1;
	r->content_type = "application/json";
}

void sty_response_release(sty_response *r)
{
	if (!r)
		return;
	free(r->body);
	r->body = NULL;
	if (r->fd >= 0)
		close(r->fd);
	r->fd = -1;
}

static void set_body(sty_response *r, unsigned status, const char *type, const char *text, size_t len)
{
	free(r->body);
	r->status = status;
	r->content_type = type;
	r->body = malloc(len + 1);
	r->body_size = r->body ? len : 0;
	if (r->body) {
		memcpy(r->body, text, len);
		r->body[len] = 0;
	} else {
		r->status = 500;
	}
}

static void set_error(sty_response *r, unsigned status, const char *msg)
{
	json_t *j = json_pack("{s:s}", "error", msg);
	char *s = j ? json_dumps(j, JSON_COMPACT) : NULL;
	const char *text = s ? s : "{\"error\":\"?\"}";
	set_body(r, status, "application/json", text, strlen(text));
	free(s);
	json_decref(j);
}

/* A 500: the client learns nothing about the server (paths, SQLite messages); the details go to the log. */
static void set_internal(struct sty_server *sv, sty_response *r, const sty_request *rq, const char *detail)
{
	sv_log(sv, "%s %.40s...: %s", rq->method, rq->path, detail);
	set_error(r, 500, "internal error");
}

static void set_json(sty_response *r, json_t *j)
{
	char *s = j ? json_dumps(j, JSON_COMPACT) : NULL;
	json_decref(j);
	if (!s) {
		set_error(r, 500, "internal error");
		return;
	}
	set_body(r, 200, "application/json", s, strlen(s));
	free(s);
}

/* ------------------------------------------------------------------ request helpers */

static const char *header(const sty_request *rq, const char *name, size_t *count)
{
	const char *v = NULL;
	size_t n = 0;
	for (size_t i = 0; i < rq->header_count; i++)
		if (rq->headers[i].name && !strcasecmp(rq->headers[i].name, name)) {
			if (!n)
				v = rq->headers[i].value ? rq->headers[i].value : "";
			n++;
		}
	if (count)
		*count = n;
	return v;
}

static int is_ows(char c) { return c == ' ' || c == '\t'; }
static int is_digit(char c) { return c >= '0' && c <= '9'; }

/* 1*DIGIT at *p, saturating at UINT64_MAX; advances *p. 0 when there is no digit. */
static int parse_digits(const char **p, uint64_t *v)
{
	const char *s = *p;
	uint64_t x = 0;
	if (!is_digit(*s))
		return 0;
	for (; is_digit(*s); s++) {
		uint64_t d = (uint64_t)(*s - '0');
		x = x > (UINT64_MAX - d) / 10 ? UINT64_MAX : x * 10 + d;
	}
	*p = s;
	*v = x;
	return 1;
}

/* Message framing, RFC 7230 section 3.3.3: Content-Length fields (each possibly a list, "42, 42") must all be
 * 1*DIGIT and equal, and may not come with Transfer-Encoding; otherwise the framing is invalid and the request
 * gets 400 with the connection closed. *length = the declared length (UINT64_MAX: none). */
static int framing_ok(const sty_request *rq, uint64_t *length)
{
	*length = UINT64_MAX;
	int seen = 0;
	for (size_t i = 0; i < rq->header_count; i++) {
		if (!rq->headers[i].name || strcasecmp(rq->headers[i].name, "Content-Length"))
			continue;
		const char *p = rq->headers[i].value ? rq->headers[i].value : "";
		for (;;) {
			while (is_ows(*p))
				p++;
			uint64_t v;
			if (!parse_digits(&p, &v))
				return 0;
			if (seen && v != *length)
				return 0;
			*length = v, seen = 1;
			while (is_ows(*p))
				p++;
			if (!*p)
				break;
			if (*p++ != ',')
				return 0;
		}
	}
	size_t te;
	header(rq, "Transfer-Encoding", &te);
	return !(seen && te);
}

/* Transfer-Encoding of a request (issue 31.9). libmicrohttpd 0.9.75 decodes "chunked" alone and reads the body of
 * any other coding until the connection closes, and it checks no chunk size against anything: "gzip, chunked" or a
 * chunk of 2^64-1 bytes kept a connection reading for ever. Our requests are small JSON bodies that every browser
 * sends with a Content-Length, so a request with Transfer-Encoding is refused at its head, before any of its body is
 * read: 400 when chunked is not the final coding (RFC 9112 section 6.3: the length cannot be determined), 501 for a
 * coding we do not implement (section 6.1), 411 for chunked alone (RFC 9110 section 15.5.12: the server refuses a
 * request without a defined Content-Length). 0: no Transfer-Encoding. */
static unsigned transfer_coding_status(const sty_request *rq, const char **why)
{
	size_t n;
	const char *v = header(rq, "Transfer-Encoding", &n);
	if (!n)
		return 0;
	/* the last coding of the last field (RFC 9110 section 5.3: repeated fields are one list, in order) */
	for (size_t i = 0; i < rq->header_count; i++)
		if (rq->headers[i].name && !strcasecmp(rq->headers[i].name, "Transfer-Encoding"))
			v = rq->headers[i].value ? rq->headers[i].value : "";
	const char *last = strrchr(v, ',');
	last = last ? last + 1 : v;
	while (is_ows(*last))
		last++;
	size_t len = strlen(last);
	while (len && is_ows(last[len - 1]))
		len--;
	int chunked_last = len == 7 && !strncasecmp(last, "chunked", 7);
	if (!chunked_last) {
		*why = "Transfer-Encoding must end with chunked (RFC 9112 section 6.3); send the body with a Content-Length";
		return 400;
	}
	if (n > 1 || last != v + strspn(v, " \t")) {
		*why = "only the chunked transfer coding is implemented (RFC 9112 section 6.1); send the body with a Content-Length";
		return 501;
	}
	*why = "request bodies need a Content-Length (at most 4096 bytes), not chunked transfer coding";
	return 411;
}

/* A 32-hex-digit code (anything else is rejected before touching the database). */
static int valid_hex32(const char *s, size_t len)
{
	if (len != 32)
		return 0;
	for (size_t i = 0; i < len; i++)
		if (!((s[i] >= '0' && s[i] <= '9') || (s[i] >= 'a' && s[i] <= 'f')))
			return 0;
	return 1;
}

/* Compares the presented token with the admin token in time that does not depend on where they differ. */
static int token_equal(const char *given, size_t given_len, const char *token)
{
	size_t n = strlen(token);
	volatile unsigned char d = (unsigned char)(given_len != n);
	for (size_t i = 0; i < n; i++)
		d |= (unsigned char)((i < given_len ? given[i] : 0) ^ token[i]);
	return d == 0;
}

/* "Authorization: Bearer <token>" (RFC 6750 section 2.1; the scheme is case-insensitive, RFC 7235). Exactly one
 * Authorization field. */
static int authorised(struct sty_server *sv, const sty_request *rq)
{
	size_t n;
	const char *v = header(rq, "Authorization", &n);
	if (n != 1 || strncasecmp(v, "Bearer", 6) || !is_ows(v[6]))
		return 0;
	v += 6;
	while (is_ows(*v))
		v++;
	size_t len = strlen(v);
	while (len && is_ows(v[len - 1]))
		len--;
	return token_equal(v, len, sty_admin_token(sv->study));
}

/* ------------------------------------------------------------------ clips */

enum { RANGE_IGNORE, RANGE_ONE, RANGE_416 };

/* The Range header of a GET for a representation of `size` bytes (RFC 7233 section 2.1, 3.1):
 *   byte-ranges-specifier = bytes-unit "=" byte-range-set; byte-range-set = 1#( byte-range-spec / suffix-byte-range-spec )
 * A header that does not match the grammar (or another unit) is ignored: RANGE_IGNORE, send the whole file.
 * More than one range is ignored as well ("A server MAY ignore the Range header field", section 3.1): no
 * multipart/byteranges, which also keeps many small ranges from multiplying the work. One range that is invalid
 * (last-byte-pos < first-byte-pos, section 2.1) or unsatisfiable (first-byte-pos >= size, or a zero suffix) is
 * RANGE_416 ("the server SHOULD send a 416", section 3.1). Otherwise RANGE_ONE with [*first, *last]. */
static int parse_range(const char *h, uint64_t size, uint64_t *first, uint64_t *last)
{
	if (strncasecmp(h, "bytes=", 6)) /* range units are case-insensitive */
		return RANGE_IGNORE;
	const char *p = h + 6;
	size_t n = 0;
	int kind = RANGE_IGNORE;
	/* The list rule (RFC 7230 section 7): elements separated by "," with optional whitespace, empty ones allowed. */
	for (;;) {
		while (is_ows(*p) || *p == ',')
			p++;
		if (!*p)
			break;
		uint64_t a = 0, b = 0;
		int has_a = parse_digits(&p, &a);
		if (*p++ != '-')
			return RANGE_IGNORE;
		int has_b = parse_digits(&p, &b);
		if (!has_a && !has_b)
			return RANGE_IGNORE;
		while (is_ows(*p))
			p++;
		if (*p && *p != ',')
			return RANGE_IGNORE;
		if (++n > 1)
			continue; /* still checked for syntax; several ranges are ignored below */
		if (has_a) {                   /* first-byte-pos "-" [ last-byte-pos ] */
			if (has_b && b < a)
				kind = RANGE_416;      /* invalid */
			else if (a >= size)
				kind = RANGE_416;      /* unsatisfiable */
			else
				kind = RANGE_ONE, *first = a, *last = has_b && b < size - 1 ? b : size - 1;
		} else if (b == 0) {           /* "-" suffix-length: the last b bytes */
			kind = RANGE_416;
		} else if (size == 0) {
			kind = RANGE_IGNORE;           /* nothing to send a part of */
		} else {
			kind = RANGE_ONE, *first = b >= size ? 0 : size - b, *last = size - 1;
		}
	}
	if (n != 1)
		return RANGE_IGNORE;
	return kind;
}

static const char *clip_type(const char *path)
{
	size_t n = strlen(path);
	if (n >= 5 && !strcmp(path + n - 5, ".webm"))
		return "video/webm";
	if (n >= 4 && !strcmp(path + n - 4, ".mp4"))
		return "video/mp4";
	return "application/octet-stream";
}

/* /clips/<name>: only names handed out by the trial API (sty_clip_file), and only files inside the stimulus
 * folder (realpath), so nothing else there (a study database, pairs.json, manifests) is ever served. */
static void serve_clip(struct sty_server *sv, const sty_request *rq, const char *name, sty_response *r)
{
	size_t hexlen = strspn(name, "0123456789abcdef");
	const char *ext = name + hexlen;
	if (!valid_hex32(name, hexlen) || (*ext && strcmp(ext, ".webm") && strcmp(ext, ".mp4"))) {
		set_error(r, 404, "no such clip");
		return;
	}
	char rel[TL_PATH_MAX], err[512];
	int rc = sty_clip_file(sv->study, name, rel, sizeof rel, err, sizeof err);
	if (rc == TL_ERR_NOTFOUND) {
		set_error(r, 404, "no such clip");
		return;
	}
	if (rc) {
		set_internal(sv, r, rq, err);
		return;
	}
	char path[PATH_MAX + TL_PATH_MAX + 2], real[PATH_MAX];
	snprintf(path, sizeof path, "%s/%s", sv->root, rel);
	struct stat sb;
	int fd = -1;
	if (!realpath(path, real) || !tl_path_inside(real, sv->root) || (fd = open(real, O_RDONLY | O_CLOEXEC)) < 0 ||
	    fstat(fd, &sb) || !S_ISREG(sb.st_mode)) {
		if (fd >= 0)
			close(fd);
		set_internal(sv, r, rq, "a clip of the design is missing or outside the stimulus folder");
		return;
	}
	uint64_t size = (uint64_t)sb.st_size, first = 0, last = size ? size - 1 : 0;
	size_t nrange, nifrange;
	const char *range = header(rq, "Range", &nrange);
	header(rq, "If-Range", &nifrange);
	/* Range only for GET (RFC 7233 section 3.1); If-Range cannot match since we send no validators (section 3.2:
	 * then the Range is ignored); a repeated Range field is not something we can interpret: ignore it. */
	int kind = range && nrange == 1 && !nifrange && !strcmp(rq->method, "GET") ? parse_range(range, size, &first, &last)
										  : RANGE_IGNORE;
	if (kind == RANGE_416) {
		close(fd);
		set_body(r, 416, "text/plain", "", 0);
		snprintf(r->content_range, sizeof r->content_range, "bytes */%llu", (unsigned long long)size);
		return;
	}
	if (kind == RANGE_IGNORE)
		first = 0, last = size ? size - 1 : 0;
	r->status = kind == RANGE_ONE ? 206 : 200;
	r->content_type = clip_type(real);
	r->fd = fd;
	r->file_offset = first;
	r->file_size = size ? last - first + 1 : 0;
	r->accept_ranges = true;
	r->cacheable = false;
	if (kind == RANGE_ONE)
		snprintf(r->content_range, sizeof r->content_range, "bytes %llu-%llu/%llu", (unsigned long long)first,
			 (unsigned long long)last, (unsigned long long)size);
}

/* ------------------------------------------------------------------ API */

static void serve_export(struct sty_server *sv, const sty_request *rq, int pwcmp, sty_response *r)
{
	/* A private folder (0700) for the file, removed before replying; the open descriptor is what is sent. */
	const char *tmp = getenv("TMPDIR");
	char dir[TL_PATH_MAX], file[TL_PATH_MAX + 16], err[1024];
	snprintf(dir, sizeof dir, "%s/taslab-export-XXXXXX", tmp && *tmp ? tmp : "/tmp");
	if (!mkdtemp(dir)) {
		set_internal(sv, r, rq, "cannot create a temporary folder for the export");
		return;
	}
	snprintf(file, sizeof file, "%s/export.csv", dir);
	int rc = pwcmp ? sty_export_pwcmp(sv->study, file, err, sizeof err) : sty_export_long(sv->study, file, err, sizeof err);
	int fd = rc ? -1 : open(file, O_RDONLY | O_CLOEXEC);
	unlink(file);
	rmdir(dir);
	struct stat sb;
	if (fd < 0 || fstat(fd, &sb)) {
		if (fd >= 0)
			close(fd);
		set_internal(sv, r, rq, rc ? err : "export failed");
		return;
	}
	r->status = 200;
	r->content_type = "text/csv; charset=utf-8";
	r->fd = fd;
	r->file_offset = 0;
	r->file_size = (uint64_t)sb.st_size;
}

/* POST /api/<code>/answer: exactly {"trial": int, "answer": int, "rt_ms": int} (JSON integers, no other keys, no
 * duplicates), range-checked before any narrowing conversion; the storage rules are sty_answer's. */
static void serve_answer(struct sty_server *sv, const sty_request *rq, const char *code, sty_response *r)
{
	if (rq->body_too_large) {
		set_error(r, 413, "request body larger than 4096 bytes");
		return;
	}
	json_error_t je;
	json_t *j = json_loadb(rq->body, rq->body_size, JSON_REJECT_DUPLICATES, &je);
	const char *why = NULL;
	json_t *t = json_object_get(j, "trial"), *a = json_object_get(j, "answer"), *rt = json_object_get(j, "rt_ms");
	if (!json_is_object(j))
		why = "body must be a JSON object {\"trial\": int, \"answer\": int, \"rt_ms\": int}";
	else if (json_object_size(j) != 3 || !t || !a || !rt)
		why = "body must have exactly the keys trial, answer and rt_ms";
	else if (!json_is_integer(t) || json_integer_value(t) < 0 || json_integer_value(t) > UINT32_MAX)
		why = "trial must be a whole number >= 0";
	else if (!json_is_integer(a) || json_integer_value(a) < -2 || json_integer_value(a) > 2)
		why = "answer must be an integer from -2 to 2";
	else if (!json_is_integer(rt) || json_integer_value(rt) < 0 || json_integer_value(rt) > STY_RT_MS_MAX)
		why = "rt_ms must be a whole number of milliseconds from 0 to 86400000";
	if (why) {
		json_decref(j);
		set_error(r, 400, why);
		return;
	}
	char err[512];
	int rc = sty_answer(sv->study, code, (uint32_t)json_integer_value(t), (int64_t)json_integer_value(a),
			    (int64_t)json_integer_value(rt), err, sizeof err);
	json_decref(j);
	switch (rc) {
	case TL_OK: set_json(r, json_pack("{s:b}", "ok", 1)); break;
	case TL_ERR_ARG: set_error(r, 400, err); break;
	case TL_ERR_NOTFOUND: set_error(r, 404, err); break;
	case TL_ERR_CONFLICT: set_error(r, 409, err); break;
	default: set_internal(sv, r, rq, err);
	}
}

static void serve_trial(struct sty_server *sv, const sty_request *rq, const char *code, sty_response *r)
{
	sty_trial t;
	char err[512];
	int rc = sty_next_trial(sv->study, code, &t, err, sizeof err);
	if (rc == TL_ERR_NOTFOUND) {
		set_error(r, 404, "unknown participant");
		return;
	}
	if (rc) {
		set_internal(sv, r, rq, err);
		return;
	}
	if (t.done) {
		set_json(r, json_pack("{s:b, s:i, s:i}", "done", 1, "total", (json_int_t)t.total, "answered",
				      (json_int_t)t.answered));
		return;
	}
	char a[64], b[64];
	snprintf(a, sizeof a, "/clips/%s", t.clip_a);
	snprintf(b, sizeof b, "/clips/%s", t.clip_b);
	set_json(r, json_pack("{s:b, s:I, s:I, s:I, s:s, s:s, s:s, s:b}", "done", 0, "index", (json_int_t)t.index, "total",
			      (json_int_t)t.total, "answered", (json_int_t)t.answered, "clip_a", a, "clip_b", b, "kind", t.kind,
			      "break_before", t.break_before));
}

void sty_server_handle(sty_server *sv, const sty_request *rq, sty_response *r)
{
	resp_init(r);
	const char *method = rq->method ? rq->method : "", *url = rq->path ? rq->path : "";
	uint64_t length;
	if (!framing_ok(rq, &length)) {
		set_error(r, 400, "conflicting or invalid Content-Length (RFC 7230 section 3.3.3)");
		r->close = true;
		return;
	}
	const char *why;
	unsigned te = transfer_coding_status(rq, &why);
	if (te) {
		set_error(r, te, why);
		r->close = true;
		return;
	}
	if (!rq->body) { /* head only: refuse what can be refused before reading a body */
		if (length != UINT64_MAX && length > STY_MAX_BODY_B) {
			set_error(r, 413, "request body larger than 4096 bytes");
			r->close = true;
		}
		return;
	}
	int get = !strcmp(method, "GET") || !strcmp(method, "HEAD"), post = !strcmp(method, "POST");
	if (!get && !post) {
		set_error(r, 405, "only GET, HEAD and POST");
		return;
	}
	if (!strncmp(url, "/p/", 3)) {
		if (!get) {
			set_error(r, 405, "GET only");
			return;
		}
		sty_trial t;
		char err[512];
		int rc = valid_hex32(url + 3, strlen(url + 3)) ? sty_next_trial(sv->study, url + 3, &t, err, sizeof err)
							       : TL_ERR_NOTFOUND;
		if (rc == TL_ERR_NOTFOUND)
			set_error(r, 404, "unknown participant link");
		else if (rc)
			set_internal(sv, r, rq, err);
		else
			set_body(r, 200, "text/html; charset=utf-8", study_html, strlen(study_html));
		return;
	}
	if (!strncmp(url, "/api/", 5)) {
		const char *code = url + 5, *slash = strchr(code, '/');
		if (!slash || !valid_hex32(code, (size_t)(slash - code))) {
			set_error(r, 404, "unknown participant");
			return;
		}
		char cb[33];
		memcpy(cb, code, 32);
		cb[32] = 0;
		if (!strcmp(slash, "/trial") && get)
			serve_trial(sv, rq, cb, r);
		else if (!strcmp(slash, "/answer") && post)
			serve_answer(sv, rq, cb, r);
		else if (!strcmp(slash, "/trial") || !strcmp(slash, "/answer"))
			set_error(r, 405, "GET /trial, POST /answer");
		else
			set_error(r, 404, "no such endpoint");
		return;
	}
	if (!strncmp(url, "/clips/", 7)) {
		if (get)
			serve_clip(sv, rq, url + 7, r);
		else
			set_error(r, 405, "GET only");
		return;
	}
	if (!strncmp(url, "/admin/", 7)) {
		if (!get) {
			set_error(r, 405, "GET only");
		} else if (!authorised(sv, rq)) {
			set_error(r, 401, "admin endpoints need the header 'Authorization: Bearer TOKEN' (the token is printed by "
					  "'taslab study serve')");
			r->authenticate = true;
		} else if (!strcmp(url, "/admin/export.csv")) {
			serve_export(sv, rq, 0, r);
		} else if (!strcmp(url, "/admin/export-pwcmp.csv")) {
			serve_export(sv, rq, 1, r);
		} else {
			set_error(r, 404, "no such endpoint (export.csv, export-pwcmp.csv)");
		}
		return;
	}
	if (!strcmp(url, "/") && get) {
		const char *text = "taslab study server: open your participant link (/p/<code>).\n";
		set_body(r, 200, "text/plain; charset=utf-8", text, strlen(text));
		return;
	}
	set_error(r, 404, "not found");
}

/* ------------------------------------------------------------------ libmicrohttpd adapter */

typedef struct conn_state {
	char body[STY_MAX_BODY_B + 1];
	size_t len;
	bool too_large;
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

static enum MHD_Result queue(struct MHD_Connection *c, sty_response *r)
{
	struct MHD_Response *m;
	if (r->fd >= 0) {
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
 * reading a head, reading a body, answering. A watchdog thread closes those whose head or body is overdue, and a
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
static unsigned max_reading(const struct sty_server *sv)
{
	unsigned all = sv->desc.max_connections ? sv->desc.max_connections : 256u;
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

/* Closes a reading connection (conn_lock held): libmicrohttpd sees the end of its stream and cleans it up. */
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

/* Closes the connections whose head or body is overdue, four times a second, until the server stops. */
static void *watchdog_main(void *arg)
{
	struct sty_server *sv = arg;
	uint64_t evicted_logged = 0;
	pthread_mutex_lock(&sv->conn_lock);
	while (!sv->stopping) {
		struct timespec now, wake;
		clock_gettime(CLOCK_MONOTONIC, &now);
		unsigned heads = 0, bodies = 0;
		for (conn_track *t = sv->conns; t; t = t->next) {
			double age = elapsed_s(&t->since, &now);
			if (t->phase == CONN_HEAD && age > head_timeout_s(sv))
				conn_close(sv, t), heads++;
			else if (t->phase == CONN_BODY && age > body_timeout_s(sv))
				conn_close(sv, t), bodies++;
		}
		sv->stats.head_timeouts += heads;
		sv->stats.body_timeouts += bodies;
		uint64_t evicted = sv->stats.evicted - evicted_logged;
		evicted_logged = sv->stats.evicted;
		if (heads || bodies || evicted) {
			pthread_mutex_unlock(&sv->conn_lock);
			sv_log(sv, "slow clients: closed %u connection(s) without a complete request head within %u s, %u without "
				   "a complete body within %u s, %llu reading longest when more than %u were reading",
			       heads, head_timeout_s(sv), bodies, body_timeout_s(sv), (unsigned long long)evicted, max_reading(sv));
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

sty_server_stats sty_server_get_stats(sty_server *sv)
{
	pthread_mutex_lock(&sv->conn_lock);
	sty_server_stats st = sv->stats;
	pthread_mutex_unlock(&sv->conn_lock);
	return st;
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
		resp_init(&r);
		set_error(&r, 431, "too many header fields");
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
	track_phase(sv, c, CONN_ANSWER);
	rq.body = cs->body;
	rq.body_size = cs->len;
	rq.body_too_large = cs->too_large;
	sty_server_handle(sv, &rq, &r);
	if (r.status == 0) { /* cannot happen with a body; be safe */
		resp_init(&r);
		set_error(&r, 500, "internal error");
	}
	return queue(c, &r);
}

static void on_completed(void *cls, struct MHD_Connection *c, void **con_cls, enum MHD_RequestTerminationCode toe)
{
	(void)toe;
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
	if (desc)
		sv->desc = *desc;
	pthread_mutex_init(&sv->log_lock, NULL);
	pthread_mutex_init(&sv->conn_lock, NULL);
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
	const char *bind = d->bind ? d->bind : "127.0.0.1";
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons(d->port)};
	if (inet_pton(AF_INET, bind, &sa.sin_addr) != 1) {
		sty_server_stop(&sv);
		return tl_error(err, err_size, TL_ERR_ARG, "--bind '%s' is not an IPv4 address", bind);
	}
	sv->starting = 1;
	/* Limits against one client locking the others out: connections per client address and in all, an idle
	 * timeout (silent connections are closed), and the head/body deadlines and the cap on reading connections of
	 * on_connection and the watchdog (trickling connections are closed). */
	/* The logger comes first, or MHD prints the messages of the options before it itself. */
	sv->mhd = MHD_start_daemon(MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_AUTO | MHD_USE_ERROR_LOG, 0, NULL, NULL,
				   on_request, sv, MHD_OPTION_EXTERNAL_LOGGER, mhd_log, sv, MHD_OPTION_SOCK_ADDR,
				   (struct sockaddr *)&sa, MHD_OPTION_THREAD_POOL_SIZE, d->threads ? d->threads : 4u,
				   MHD_OPTION_NOTIFY_COMPLETED, on_completed, sv, MHD_OPTION_NOTIFY_CONNECTION, on_connection, sv,
				   MHD_OPTION_CONNECTION_TIMEOUT,
				   d->timeout_s ? d->timeout_s : 15u, MHD_OPTION_CONNECTION_LIMIT,
				   d->max_connections ? d->max_connections : 256u, MHD_OPTION_PER_IP_CONNECTION_LIMIT,
				   d->max_per_client ? d->max_per_client : 32u, MHD_OPTION_END);
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
	if (sv->mhd)
		MHD_stop_daemon(sv->mhd);
	pthread_cond_destroy(&sv->conn_wake);
	pthread_mutex_destroy(&sv->conn_lock);
	pthread_mutex_destroy(&(*psv)->log_lock);
	free(*psv);
	*psv = NULL;
}
