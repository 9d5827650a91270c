/* study_serve.c — the study web server (study_serve.h), its request logic: sty_server_handle answers one parsed
 * request (routing, the answer API, clips by opaque name with RFC 7233 ranges, the token-protected exports); the
 * libmicrohttpd adapter (study_serve_mhd.c) only collects the request (headers, a body of at most STY_MAX_BODY_B)
 * and sends the response. Keeping the sockets out of the request logic lets tests and the fuzzer
 * (tests/fuzz/fuzz_serve.c) drive all of it. */
#define _DEFAULT_SOURCE /* realpath, mkdtemp, strncasecmp */
#include "taslab/study_serve.h"

#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <limits.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "study_internal.h"
#include "study_serve_internal.h"
#include "study_session.h"
#include "study_telemetry.h"
#include "taslab/study_status.h"
#include "taslab/tl_fs.h"
#include "web/status_html.h"
#include "web/study_html.h"

#define LOG_LINES_PER_S 10 /* more log lines than this in one second are counted, not printed */

/* ------------------------------------------------------------------ log */

static void default_log(void *cls, const char *line)
{
	(void)cls;
	fprintf(stderr, "taslab study serve: %s\n", line);
}

/* One line to the configured log, at most LOG_LINES_PER_S per second when `limited` (a flood of bad requests must not
 * become a flood on the terminal). */
static void serve_vlog(struct sty_server *sv, bool limited, const char *fmt, va_list ap)
{
	char line[512];
	vsnprintf(line, sizeof line, fmt, ap);
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
	if (limited && ++sv->log_count > LOG_LINES_PER_S) {
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

void sty_serve_log(struct sty_server *sv, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	serve_vlog(sv, true, fmt, ap);
	va_end(ap);
}

__thread sty_held_events *sty_events_held;

/* A line of a request whose reply may wait for its commit: held while the thread's sty_events_held is set (its
 * first byte says whether it is rate-limited), else logged at once. */
static void serve_vhold(struct sty_server *sv, bool limited, const char *fmt, va_list ap)
{
	sty_held_events *h = sty_events_held;
	if (h) {
		char line[512];
		va_list aq;
		va_copy(aq, ap);
		vsnprintf(line, sizeof line, fmt, aq);
		va_end(aq);
		size_t n = strlen(line);
		if (h->len + n + 2 < sizeof h->text) {
			h->text[h->len++] = limited ? 'L' : 'E';
			for (size_t k = 0; k < n; k++) /* one line each: serve_vlog makes these spaces too */
				h->text[h->len++] = line[k] == '\n' || line[k] == '\r' ? ' ' : line[k];
			h->text[h->len++] = '\n';
			return;
		}
	}
	serve_vlog(sv, limited, fmt, ap);
}

/* A stored answer or a completed session (issue 27.8): never dropped by the rate limit — there are at most as many as
 * the study has trials, whoever sends them. Held while the reply waits for its commit (sty_events_held). */
static void serve_event(struct sty_server *sv, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	serve_vhold(sv, false, fmt, ap);
	va_end(ap);
}

/* A rate-limited line about a change (a session started), held like serve_event's. */
static void serve_note(struct sty_server *sv, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	serve_vhold(sv, true, fmt, ap);
	va_end(ap);
}

void sty_serve_event(struct sty_server *sv, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	serve_vlog(sv, false, fmt, ap);
	va_end(ap);
}

void sty_serve_events_flush(struct sty_server *sv, sty_held_events *h)
{
	for (size_t at = 0; at < h->len;) {
		char *end = memchr(h->text + at, '\n', h->len - at);
		size_t n = end ? (size_t)(end - (h->text + at)) : h->len - at;
		if (n) {
			if (h->text[at] == 'L')
				sty_serve_log(sv, "%.*s", (int)n - 1, h->text + at + 1);
			else
				sty_serve_event(sv, "%.*s", (int)n - 1, h->text + at + 1);
		}
		at += n + 1;
	}
	h->len = 0;
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

void sty_response_error(sty_response *r, unsigned status, const char *msg)
{
	resp_init(r);
	set_error(r, status, msg);
}

/* A 500: the client learns nothing about the server (paths, SQLite messages); the details go to the log. */
static void set_internal(struct sty_server *sv, sty_response *r, const sty_request *rq, const char *detail)
{
	sty_serve_log(sv, "%s %.40s...: %s", rq->method, rq->path, detail);
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
	/* Blinding by size (issue 27.6): the representation is the file and then its container's padding up to the
	 * length every clip of this scene x camera path is served at. */
	uint64_t fsize = (uint64_t)sb.st_size, padded = 0;
	if (sty_clip_padded_size(sv->study, sv->root, name, rel, &padded, err, sizeof err)) {
		close(fd);
		set_internal(sv, r, rq, err);
		return;
	}
	uint64_t size = padded > fsize ? padded : fsize, first = 0, last = size ? size - 1 : 0;
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
	r->file_offset = first < fsize ? first : fsize;
	r->file_size = size && first < fsize ? (last < fsize ? last : fsize - 1) - first + 1 : 0;
	if (size > fsize && last >= fsize) { /* the part of [first, last] past the file's end is padding */
		r->pad_total = size - fsize;
		size_t rl = strlen(rel);
		r->pad_ext = rl >= 5 && !strcmp(rel + rl - 5, ".webm") ? ".webm" : ".mp4"; /* padded only these two */
		r->pad_offset = first > fsize ? first - fsize : 0;
		r->pad_size = last - fsize + 1 - r->pad_offset;
	}
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
	/* Only committed answers: the export reads the connection the answers are written on, so it waits, holding the
	 * lock the writers take, until no batch is open (study_commit.c), and no write can start while it reads. Before
	 * (found in review, 2026-11-27) it read inside an open batch: rows a failing COMMIT then rolled back could be
	 * exported, and a request caught between its answer and its telemetry. */
	sty *st = sv->study;
	pthread_mutex_lock(&st->lock);
	sty_batch_quiesce(st); /* and no new batch opens while it waits (found in review, 2026-11-28) */
	int rc = pwcmp ? sty_export_pwcmp(st, file, err, sizeof err) : sty_export_long(st, file, err, sizeof err);
	pthread_mutex_unlock(&st->lock);
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

/* The page's playback telemetry (issue 28; study_telemetry.h): exactly {"play_ms": [a, b], "dropped": n, "frames": n,
 * "hidden": n, "hidden_ms": n, "hidden_play": n, "fullscreen": 0|1}, whole numbers within sane bounds. NULL when
 * valid, else why not. */
static const char *parse_telemetry(const json_t *j, sty_telemetry *t)
{
	static const char *const keys[] = {"dropped", "frames", "hidden", "hidden_ms", "hidden_play", "fullscreen"};
	int64_t *dst[] = {&t->dropped, &t->frames, &t->hidden, &t->hidden_ms, &t->hidden_play, NULL};
	const json_int_t max[] = {10000000, 10000000, 100000, STY_RT_MS_MAX, 100000, 1};
	const char *why = "telemetry must be {\"play_ms\": [int, int], \"dropped\", \"frames\", \"hidden\", \"hidden_ms\", "
			  "\"hidden_play\": whole numbers >= 0, \"fullscreen\": 0 or 1}";
	const json_t *pm = json_object_get(j, "play_ms");
	memset(t, 0, sizeof *t);
	if (!json_is_object(j) || json_object_size(j) != 7 || !json_is_array(pm) || json_array_size(pm) != 2)
		return why;
	for (size_t i = 0; i < 2; i++) {
		const json_t *v = json_array_get(pm, i);
		if (!json_is_integer(v) || json_integer_value(v) < 0 || json_integer_value(v) > STY_RT_MS_MAX)
			return why;
		t->play_ms[i] = (int64_t)json_integer_value(v);
	}
	for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++) {
		const json_t *v = json_object_get(j, keys[i]);
		if (!json_is_integer(v) || json_integer_value(v) < 0 || json_integer_value(v) > max[i])
			return why;
		if (dst[i])
			*dst[i] = (int64_t)json_integer_value(v);
		else
			t->fullscreen = (int)json_integer_value(v);
	}
	if (t->dropped > t->frames || t->hidden_play > t->hidden)
		return "telemetry: dropped must be <= frames and hidden_play <= hidden";
	return NULL;
}

/* POST /api/<code>/answer: exactly {"trial": int, "answer": int, "rt_ms": int} and optionally "session": the id from
 * /session and "telemetry" (parse_telemetry) (JSON integers and a string, no other keys, no duplicates),
 * range-checked before any narrowing conversion; the storage rules are sty_answer's and sty_session_answer's. Each
 * stored answer is a log line, and so is a completed session (issue 27.8); a broken playback says so. */
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
	json_t *ses = json_object_get(j, "session"), *tel = json_object_get(j, "telemetry");
	sty_telemetry tm;
	if (!json_is_object(j))
		why = "body must be a JSON object {\"trial\": int, \"answer\": int, \"rt_ms\": int}";
	else if (json_object_size(j) != 3u + (ses != NULL) + (tel != NULL) || !t || !a || !rt)
		why = "body must have exactly the keys trial, answer and rt_ms (and session, telemetry)";
	else if (!json_is_integer(t) || json_integer_value(t) < 0 || json_integer_value(t) > UINT32_MAX)
		why = "trial must be a whole number >= 0";
	else if (!json_is_integer(a) || json_integer_value(a) < -2 || json_integer_value(a) > 2)
		why = "answer must be an integer from -2 to 2";
	else if (!json_is_integer(rt) || json_integer_value(rt) < 0 || json_integer_value(rt) > STY_RT_MS_MAX)
		why = "rt_ms must be a whole number of milliseconds from 0 to 86400000";
	else if (ses && (!json_is_string(ses) || !valid_hex32(json_string_value(ses), strlen(json_string_value(ses)))))
		why = "session must be the id POST /api/<code>/session returned";
	else if (tel)
		why = parse_telemetry(tel, &tm);
	if (why) {
		json_decref(j);
		set_error(r, 400, why);
		return;
	}
	char err[512], session[33] = "";
	if (ses)
		snprintf(session, sizeof session, "%s", json_string_value(ses));
	uint32_t trial = (uint32_t)json_integer_value(t);
	sty_session_info info;
	int rc = sty_session_answer(sv->study, code, ses ? session : NULL, trial, (int64_t)json_integer_value(a),
				    (int64_t)json_integer_value(rt), tel ? &tm : NULL, &info, err, sizeof err);
	json_decref(j);
	switch (rc) {
	case TL_OK:
		set_json(r, info.repeat ? json_pack("{s:b, s:b}", "ok", 1, "repeat", 1) : json_pack("{s:b}", "ok", 1));
		if (!info.repeat && info.broken[0])
			serve_event(sv, "%s answered trial %u with a broken playback (%s): not counted (%u/%u)", info.label, trial,
				    info.broken, info.answered, info.total);
		else if (!info.repeat)
			serve_event(sv, "%s answered trial %u (%u/%u)", info.label, trial, info.answered, info.total);
		if (!info.repeat && info.total && info.answered == info.total)
			serve_event(sv, "%s completed the session (%u trials)", info.label, info.total);
		break;
	case TL_ERR_ARG: set_error(r, 400, err); break;
	case TL_ERR_NOTFOUND: set_error(r, 404, err); break;
	case TL_ERR_CONFLICT:
		if (info.superseded) {
			json_t *e = json_pack("{s:s, s:b}", "error", err, "superseded", 1);
			set_json(r, e);
			r->status = 409;
			sty_serve_log(sv, "%s: an answer to trial %u from a superseded session refused (the link is open in another window)",
				      info.label, trial);
		} else {
			set_error(r, 409, err);
		}
		break;
	default: set_internal(sv, r, rq, err);
	}
}

/* POST /api/<code>/session: a new session for the link (the page's Start); the earlier one is superseded. A log line
 * says so when the link had one (a reload, or a second browser: "restart"). The body is not read. */
static void serve_session(struct sty_server *sv, const sty_request *rq, const char *code, sty_response *r)
{
	if (rq->body_too_large) {
		set_error(r, 413, "request body larger than 4096 bytes");
		return;
	}
	char session[33], err[512];
	sty_session_info info;
	int rc = sty_session_start(sv->study, code, session, &info, err, sizeof err);
	if (rc == TL_ERR_NOTFOUND) {
		set_error(r, 404, "unknown participant");
		return;
	}
	if (rc) {
		set_internal(sv, r, rq, err);
		return;
	}
	serve_note(sv, "%s %s (%u/%u answered)", info.label,
		      info.restart ? "restarted: a new session took over the link" : "started a session", info.answered,
		      info.total);
	set_json(r, json_pack("{s:s}", "session", session));
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
	/* No trial kind but training (issue 27.6): a catch trial looks like any other trial to the browser. */
	set_json(r, json_pack("{s:b, s:I, s:I, s:I, s:s, s:s, s:b, s:b, s:s}", "done", 0, "index", (json_int_t)t.index,
			      "total", (json_int_t)t.total, "answered", (json_int_t)t.answered, "clip_a", a, "clip_b", b,
			      "training", !strcmp(t.kind, "training"), "break_before", t.break_before, "display",
			      t.stereo ? "stereo" : "mono"));
}

/* GET /admin/status: the study's status as JSON (study_status.h), for the live status page. */
__thread bool sty_slow_allowed;
__thread void (*sty_slow_pending)(struct sty_server *sv, sty_response *r);

static void status_reply(struct sty_server *sv, sty_response *r)
{
	char err[512];
	char *text = NULL;
	resp_init(r);
	int rc = sty_status_json(sv->study, &text, err, sizeof err);
	if (rc) {
		set_internal(sv, r, &(sty_request){.method = "GET", .path = "/admin/status"}, err);
		return;
	}
	set_body(r, 200, "application/json", text, strlen(text));
	free(text);
}

static void serve_status(struct sty_server *sv, sty_response *r)
{
	if (sty_slow_allowed) { /* computed on a thread of its own (study_serve_mhd.c) */
		sty_slow_pending = status_reply;
		set_error(r, 503, "the status is being computed");
		return;
	}
	status_reply(sv, r);
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
		else if (!strcmp(slash, "/session") && post)
			serve_session(sv, rq, cb, r);
		else if (!strcmp(slash, "/trial") || !strcmp(slash, "/answer") || !strcmp(slash, "/session"))
			set_error(r, 405, "GET /trial, POST /answer, POST /session");
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
		} else if (!strcmp(url, "/admin/status")) {
			serve_status(sv, r);
		} else {
			set_error(r, 404, "no such endpoint (status, export.csv, export-pwcmp.csv)");
		}
		return;
	}
	if (!strcmp(url, "/status") && get) { /* the page only: its data come from /admin/status with the token */
		set_body(r, 200, "text/html; charset=utf-8", status_html, strlen(status_html));
		return;
	}
	if (!strcmp(url, "/") && get) {
		const char *text = "taslab study server: open your participant link (/p/<code>).\n";
		set_body(r, 200, "text/plain; charset=utf-8", text, strlen(text));
		return;
	}
	set_error(r, 404, "not found");
}
