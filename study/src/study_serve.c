/* study_serve.c — the study web server (libmicrohttpd): participant pages, the answer API, clips with HTTP
 * Range support from the stimulus folder only, and token-protected export endpoints (study_serve.h). */
#define _DEFAULT_SOURCE /* realpath, getrandom */
#include "taslab/study_serve.h"

#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <limits.h>
#include <microhttpd.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "study_internal.h"
#include "web/study_html.h"

#define MAX_BODY 4096

struct sty_server {
	sty *study;
	struct MHD_Daemon *mhd;
	char root[PATH_MAX]; /* realpath of the stimulus folder */
	uint16_t port;
};

typedef struct req {
	char body[MAX_BODY + 1];
	size_t len;
	int too_large;
} req;

static enum MHD_Result send_text(struct MHD_Connection *c, unsigned code, const char *type, const char *text)
{
	struct MHD_Response *r = MHD_create_response_from_buffer(strlen(text), (void *)text, MHD_RESPMEM_MUST_COPY);
	MHD_add_response_header(r, "Content-Type", type);
	MHD_add_response_header(r, "Cache-Control", "no-store");
	enum MHD_Result ret = MHD_queue_response(c, code, r);
	MHD_destroy_response(r);
	return ret;
}

static enum MHD_Result send_error(struct MHD_Connection *c, unsigned code, const char *msg)
{
	char buf[512];
	json_t *j = json_pack("{s:s}", "error", msg);
	char *s = json_dumps(j, JSON_COMPACT);
	snprintf(buf, sizeof buf, "%s", s ? s : "{\"error\":\"?\"}");
	free(s);
	json_decref(j);
	return send_text(c, code, "application/json", buf);
}

static enum MHD_Result send_json(struct MHD_Connection *c, json_t *j)
{
	char *s = json_dumps(j, JSON_COMPACT);
	json_decref(j);
	enum MHD_Result r = send_text(c, 200, "application/json", s ? s : "{}");
	free(s);
	return r;
}

/* A 32-hex-digit participant code (anything else is rejected before touching the database). */
static int valid_code(const char *s, size_t len)
{
	if (len != 32)
		return 0;
	for (size_t i = 0; i < len; i++)
		if (!((s[i] >= '0' && s[i] <= '9') || (s[i] >= 'a' && s[i] <= 'f')))
			return 0;
	return 1;
}

/* Serves ROOT/rel with single-range support; only regular files whose real path lies inside ROOT. */
static enum MHD_Result send_clip(struct sty_server *sv, struct MHD_Connection *c, const char *rel)
{
	if (!*rel || rel[0] == '/' || strstr(rel, "..") || strchr(rel, '\\') || strlen(rel) > 1024)
		return send_error(c, 403, "clip paths are relative to the stimulus folder and may not contain '..'");
	char path[PATH_MAX + 1100], real[PATH_MAX];
	snprintf(path, sizeof path, "%s/%s", sv->root, rel);
	size_t rl = strlen(sv->root);
	if (!realpath(path, real) || strncmp(real, sv->root, rl) || real[rl] != '/')
		return send_error(c, 404, "no such clip");
	int fd = open(real, O_RDONLY | O_CLOEXEC);
	struct stat sb;
	if (fd < 0 || fstat(fd, &sb) || !S_ISREG(sb.st_mode)) {
		if (fd >= 0)
			close(fd);
		return send_error(c, 404, "no such clip");
	}
	uint64_t size = (uint64_t)sb.st_size, start = 0, end = size ? size - 1 : 0;
	int partial = 0;
	const char *range = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Range");
	if (range) {
		unsigned long long a = 0, b = 0;
		int n = 0;
		if (sscanf(range, "bytes=%llu-%n", &a, &n) == 1 && n > 0) {
			const char *rest = range + n;
			if (*rest && sscanf(rest, "%llu", &b) == 1)
				end = b < end ? b : end;
			start = a;
		} else if (sscanf(range, "bytes=-%llu", &b) == 1 && b > 0) {
			start = b >= size ? 0 : size - b;
		} else {
			close(fd);
			return send_error(c, 416, "unsupported Range (one bytes=a-b range)");
		}
		if (start >= size || start > end) {
			close(fd);
			char cr[64];
			snprintf(cr, sizeof cr, "bytes */%llu", (unsigned long long)size);
			struct MHD_Response *r = MHD_create_response_from_buffer(0, NULL, MHD_RESPMEM_PERSISTENT);
			MHD_add_response_header(r, "Content-Range", cr);
			enum MHD_Result ret = MHD_queue_response(c, 416, r);
			MHD_destroy_response(r);
			return ret;
		}
		partial = 1;
	}
	struct MHD_Response *r = MHD_create_response_from_fd_at_offset64(end - start + 1, fd, start);
	if (!r) {
		close(fd);
		return send_error(c, 500, "cannot serve the file");
	}
	const char *type = strstr(real, ".webm") ? "video/webm" : strstr(real, ".png") ? "image/png" : "application/octet-stream";
	MHD_add_response_header(r, "Content-Type", type);
	MHD_add_response_header(r, "Accept-Ranges", "bytes");
	if (partial) {
		char cr[96];
		snprintf(cr, sizeof cr, "bytes %llu-%llu/%llu", (unsigned long long)start, (unsigned long long)end,
			 (unsigned long long)size);
		MHD_add_response_header(r, "Content-Range", cr);
	}
	enum MHD_Result ret = MHD_queue_response(c, partial ? 206 : 200, r);
	MHD_destroy_response(r);
	return ret;
}

static enum MHD_Result send_export(struct sty_server *sv, struct MHD_Connection *c, int pwcmp)
{
	char tmp[] = "/tmp/taslab-export-XXXXXX", err[512];
	int fd = mkstemp(tmp);
	if (fd < 0)
		return send_error(c, 500, "cannot create a temporary file");
	close(fd);
	int rc = pwcmp ? sty_export_pwcmp(sv->study, tmp, err, sizeof err) : sty_export_long(sv->study, tmp, err, sizeof err);
	fd = rc ? -1 : open(tmp, O_RDONLY | O_CLOEXEC);
	unlink(tmp);
	struct stat sb;
	if (fd < 0 || fstat(fd, &sb)) {
		if (fd >= 0)
			close(fd);
		return send_error(c, 500, rc ? err : "export failed");
	}
	struct MHD_Response *r = MHD_create_response_from_fd((size_t)sb.st_size, fd);
	MHD_add_response_header(r, "Content-Type", "text/csv");
	MHD_add_response_header(r, "Cache-Control", "no-store");
	enum MHD_Result ret = MHD_queue_response(c, 200, r);
	MHD_destroy_response(r);
	return ret;
}

static enum MHD_Result handle_answer(struct sty_server *sv, struct MHD_Connection *c, const char *code, req *rq)
{
	if (rq->too_large)
		return send_error(c, 413, "request body larger than 4096 bytes");
	json_error_t je;
	json_t *j = json_loadb(rq->body, rq->len, JSON_REJECT_DUPLICATES, &je);
	json_t *t = json_object_get(j, "trial"), *a = json_object_get(j, "answer"), *rt = json_object_get(j, "rt_ms");
	if (!json_is_object(j) || !json_is_integer(t) || !json_is_integer(a) || (rt && !json_is_integer(rt) && !json_is_null(rt)) ||
	    json_integer_value(t) < 0 || json_integer_value(t) > 1000000 || json_object_size(j) > 3) {
		json_decref(j);
		return send_error(c, 400, "body must be JSON {\"trial\": int, \"answer\": int -2..2, \"rt_ms\": int}");
	}
	char err[256];
	int rc = sty_answer(sv->study, code, (uint32_t)json_integer_value(t), (int)json_integer_value(a),
			    json_is_integer(rt) ? json_integer_value(rt) : -1, err, sizeof err);
	json_decref(j);
	switch (rc) {
	case TL_OK: return send_json(c, json_pack("{s:b}", "ok", 1));
	case TL_ERR_ARG: return send_error(c, 400, err);
	case TL_ERR_NOTFOUND: return send_error(c, 404, err);
	case TL_ERR_CONFLICT: return send_error(c, 409, err);
	default: return send_error(c, 500, err);
	}
}

static enum MHD_Result handler(void *cls, struct MHD_Connection *c, const char *url, const char *method,
			       const char *version, const char *upload_data, size_t *upload_size, void **con_cls)
{
	(void)version;
	struct sty_server *sv = cls;
	int post = !strcmp(method, "POST");
	if (!*con_cls) { /* first call for this request */
		req *rq = calloc(1, sizeof *rq);
		if (!rq)
			return MHD_NO;
		*con_cls = rq;
		return MHD_YES;
	}
	req *rq = *con_cls;
	if (*upload_size) {
		if (rq->len + *upload_size > MAX_BODY)
			rq->too_large = 1;
		else {
			memcpy(rq->body + rq->len, upload_data, *upload_size);
			rq->len += *upload_size;
		}
		*upload_size = 0;
		return MHD_YES;
	}
	if (strcmp(method, "GET") && strcmp(method, "HEAD") && !post)
		return send_error(c, 405, "only GET and POST");
	if (!strncmp(url, "/p/", 3)) {
		if (post)
			return send_error(c, 405, "GET only");
		if (!valid_code(url + 3, strlen(url + 3)))
			return send_error(c, 404, "unknown participant link");
		sty_trial t;
		char err[256];
		if (sty_next_trial(sv->study, url + 3, &t, err, sizeof err))
			return send_error(c, 404, "unknown participant link");
		return send_text(c, 200, "text/html; charset=utf-8", study_html);
	}
	if (!strncmp(url, "/api/", 5)) {
		const char *code = url + 5, *slash = strchr(code, '/');
		if (!slash || !valid_code(code, (size_t)(slash - code)))
			return send_error(c, 404, "unknown participant");
		char cb[33];
		memcpy(cb, code, 32);
		cb[32] = 0;
		if (!strcmp(slash, "/trial") && !post) {
			sty_trial t;
			char err[256];
			int rc = sty_next_trial(sv->study, cb, &t, err, sizeof err);
			if (rc)
				return send_error(c, rc == TL_ERR_NOTFOUND ? 404 : 500, err);
			if (t.done)
				return send_json(c, json_pack("{s:b, s:i, s:i}", "done", 1, "total", t.total, "answered", t.answered));
			return send_json(c, json_pack("{s:b, s:i, s:i, s:i, s:s, s:s, s:s, s:b}", "done", 0, "index", t.index, "total",
						      t.total, "answered", t.answered, "clip_a", t.clip_a, "clip_b", t.clip_b, "kind",
						      t.kind, "break_before", t.break_before));
		}
		if (!strcmp(slash, "/answer") && post)
			return handle_answer(sv, c, cb, rq);
		return send_error(c, 404, "no such endpoint");
	}
	if (!strncmp(url, "/clips/", 7) && !post)
		return send_clip(sv, c, url + 7);
	if (!strncmp(url, "/admin/", 7) && !post) {
		const char *tok = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "token");
		if (!tok || strcmp(tok, sty_admin_token(sv->study)))
			return send_error(c, 403, "admin endpoints need ?token= (printed by 'taslab study serve')");
		if (!strcmp(url, "/admin/export.csv"))
			return send_export(sv, c, 0);
		if (!strcmp(url, "/admin/export-pwcmp.csv"))
			return send_export(sv, c, 1);
		return send_error(c, 404, "no such endpoint (export.csv, export-pwcmp.csv)");
	}
	if (!strcmp(url, "/") && !post)
		return send_text(c, 200, "text/plain", "taslab study server: open your participant link (/p/<code>).\n");
	return send_error(c, 404, "not found");
}

static void completed(void *cls, struct MHD_Connection *c, void **con_cls, enum MHD_RequestTerminationCode toe)
{
	(void)cls, (void)c, (void)toe;
	free(*con_cls);
	*con_cls = NULL;
}

int sty_server_start(sty *s, const char *bind_addr, uint16_t port, unsigned threads, sty_server **out, char *err,
		     size_t err_size)
{
	*out = NULL;
	if (!sty_stimuli(s)[0]) {
		snprintf(err, err_size, "this study has no stimulus folder (an imported study cannot be served)");
		return TL_ERR_ARG;
	}
	sty_server *sv = calloc(1, sizeof *sv);
	if (!sv) {
		snprintf(err, err_size, "out of memory");
		return TL_ERR_ARG;
	}
	sv->study = s;
	if (!realpath(sty_stimuli(s), sv->root)) {
		snprintf(err, err_size, "%s: stimulus folder missing: %s", sty_stimuli(s), strerror(errno));
		free(sv);
		return TL_ERR_ARG;
	}
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons(port)};
	if (inet_pton(AF_INET, bind_addr ? bind_addr : "127.0.0.1", &sa.sin_addr) != 1) {
		snprintf(err, err_size, "--bind '%s' is not an IPv4 address", bind_addr);
		free(sv);
		return TL_ERR_ARG;
	}
	sv->mhd = MHD_start_daemon(MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_ERROR_LOG, 0, NULL, NULL, handler, sv,
				   MHD_OPTION_SOCK_ADDR, (struct sockaddr *)&sa, MHD_OPTION_THREAD_POOL_SIZE,
				   (unsigned)(threads ? threads : 4), MHD_OPTION_NOTIFY_COMPLETED, completed, sv,
				   MHD_OPTION_CONNECTION_TIMEOUT, (unsigned)30, MHD_OPTION_END);
	if (!sv->mhd) {
		snprintf(err, err_size, "cannot listen on %s:%u (port in use?)", bind_addr ? bind_addr : "127.0.0.1", port);
		free(sv);
		return TL_ERR_ARG;
	}
	const union MHD_DaemonInfo *info = MHD_get_daemon_info(sv->mhd, MHD_DAEMON_INFO_BIND_PORT);
	sv->port = info ? info->port : port;
	*out = sv;
	return TL_OK;
}

uint16_t sty_server_port(const sty_server *sv) { return sv->port; }

void sty_server_stop(sty_server **psv)
{
	if (!psv || !*psv)
		return;
	MHD_stop_daemon((*psv)->mhd);
	free(*psv);
	*psv = NULL;
}
