/* test_study_live.c — a study that is running (issue 27; the page itself is tests/browser/study_recovery.mjs):
 *  - sessions: one per link, a newer one takes over, the older's answers refused and marked superseded, a session's
 *    retry of its own stored answer acknowledged once, any other answered trial a 409 (test_sessions, 27.4);
 *  - blinding: both clips of every trial (all clips of a scene x camera path) served at one byte length, padded with
 *    an EBML Void element, ranges over the padding, no trial kind but training (test_blind_sizes, 27.6);
 *  - one server per study (test_second_serve, 27.5);
 *  - participants added to a designed study get the plans `design` would have made, existing ones untouched; design
 *    on an existing study exits 2 (test_add_participants, 27.7);
 *  - `study status`, /admin/status (token only), /status, and the log lines (test_status, 27.8). */
#define _GNU_SOURCE /* memmem, strcasestr */
#include <arpa/inet.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <unistd.h>

#include "taslab/study.h"
#include "taslab/study_serve.h"
#include "taslab/study_status.h"
#include "test_study_util.h"

static char out[1 << 16];

/* GET path (extra header lines `headers`) from 127.0.0.1:port: status; the raw response in resp, its length in *len. */
static int get_raw(int port, const char *path, const char *headers, char *resp, size_t size, size_t *len)
{
	char req[1024];
	int n = snprintf(req, sizeof req, "GET %s HTTP/1.0\r\nHost: 127.0.0.1\r\n%s\r\n", path, headers ? headers : "");
	int fd = socket(AF_INET, SOCK_STREAM, 0);
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	struct timeval tv = {.tv_sec = 10};
	setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
	*len = 0;
	if (connect(fd, (struct sockaddr *)&sa, sizeof sa) || write(fd, req, (size_t)n) != n) {
		close(fd);
		return -1;
	}
	ssize_t r;
	while (*len < size && (r = read(fd, resp + *len, size - *len)) > 0)
		*len += (size_t)r;
	close(fd);
	int status = -1;
	sscanf(resp, "HTTP/1.%*d %d", &status);
	return status;
}

/* The body of a raw response and its length. */
static const char *body(const char *resp, size_t len, size_t *blen)
{
	const char *b = memmem(resp, len, "\r\n\r\n", 4);
	*blen = b ? len - (size_t)(b + 4 - resp) : 0;
	return b ? b + 4 : resp + len;
}

static void json_str(const char *json, const char *key, char *val, size_t n)
{
	char k[64];
	snprintf(k, sizeof k, "\"%s\":\"", key);
	const char *p = strstr(json, k);
	val[0] = 0;
	if (p) {
		p += strlen(k);
		snprintf(val, n, "%.*s", (int)strcspn(p, "\""), p);
	}
}

static long json_int(const char *json, const char *key)
{
	char k[64];
	snprintf(k, sizeof k, "\"%s\":", key);
	const char *p = strstr(json, k);
	return p ? strtol(p + strlen(k), NULL, 10) : -999;
}

static char logbuf[1 << 14];
static void log_line(void *cls, const char *line)
{
	(void)cls;
	size_t n = strlen(logbuf);
	snprintf(logbuf + n, sizeof logbuf - n, "%s\n", line);
}

static sty_server *served(sty *s)
{
	char err[1024];
	sty_server_desc d = {.threads = 2, .log = log_line};
	sty_server *sv = NULL;
	if (sty_server_start(s, &d, &sv, err, sizeof err))
		fail_msg("%s", err);
	return sv;
}

static int post(int port, const char *code, const char *what, const char *json)
{
	char path[128];
	snprintf(path, sizeof path, "/api/%s/%s", code, what);
	return tu_http(port, "POST", path, NULL, json, out, sizeof out);
}

static long current(int port, const char *code)
{
	char path[128];
	snprintf(path, sizeof path, "/api/%s/trial", code);
	assert_int_equal(tu_http(port, "GET", path, NULL, NULL, out, sizeof out), 200);
	return json_int(out, "index");
}

static void test_sessions(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_sessions");
	char stim[4096], db[4096], err[1024], s1[64], s2[64], b[256];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s = designed(dir, "s.db", 4, 1, &sm);
	sty_server *sv = served(s);
	int port = sty_server_port(sv);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	assert_int_equal(post(port, codes[0], "session", "{}"), 200);
	json_str(out, "session", s1, sizeof s1);
	assert_int_equal(strlen(s1), 32);
	long t = current(port, codes[0]);
	snprintf(b, sizeof b, "{\"trial\":%ld,\"answer\":1,\"rt_ms\":5,\"session\":\"%s\"}", t, s1);
	assert_int_equal(post(port, codes[0], "answer", b), 200);
	assert_null(strstr(out, "repeat"));
	/* the same request again (its reply lost): acknowledged, stored once */
	assert_int_equal(post(port, codes[0], "answer", b), 200);
	assert_non_null(strstr(out, "\"repeat\":true"));
	assert_int_equal(db_count(db, "SELECT count(*) FROM answers"), 1);
	/* another answer to the same trial from the same session is no retry: 409, not superseded */
	snprintf(b, sizeof b, "{\"trial\":%ld,\"answer\":-2,\"rt_ms\":5,\"session\":\"%s\"}", t, s1);
	assert_int_equal(post(port, codes[0], "answer", b), 409);
	assert_null(strstr(out, "superseded"));
	/* a second browser takes the link over: the first one's answers are refused, marked, not stored */
	assert_int_equal(post(port, codes[0], "session", "{}"), 200);
	json_str(out, "session", s2, sizeof s2);
	assert_string_not_equal(s1, s2);
	t = current(port, codes[0]);
	snprintf(b, sizeof b, "{\"trial\":%ld,\"answer\":2,\"rt_ms\":5,\"session\":\"%s\"}", t, s1);
	assert_int_equal(post(port, codes[0], "answer", b), 409);
	assert_non_null(strstr(out, "\"superseded\":true"));
	assert_int_equal(db_count(db, "SELECT count(*) FROM answers"), 1);
	snprintf(b, sizeof b, "{\"trial\":%ld,\"answer\":2,\"rt_ms\":5,\"session\":\"%s\"}", t, s2);
	assert_int_equal(post(port, codes[0], "answer", b), 200);
	/* malformed session ids are 400; the API without a session still answers (scripts, the benchmark) */
	t = current(port, codes[0]);
	snprintf(b, sizeof b, "{\"trial\":%ld,\"answer\":0,\"rt_ms\":5,\"session\":\"x\"}", t);
	assert_int_equal(post(port, codes[0], "answer", b), 400);
	snprintf(b, sizeof b, "{\"trial\":%ld,\"answer\":0,\"rt_ms\":5}", t);
	assert_int_equal(post(port, codes[0], "answer", b), 200);
	assert_int_equal(db_count(db, "SELECT count(*) FROM answers"), 3);
	assert_int_equal(db_count(db, "SELECT starts FROM sessions WHERE participant = 1"), 2);
	/* the log: one line per answer, a restart, a refused superseded answer */
	assert_non_null(strstr(logbuf, "P001 started a session"));
	assert_non_null(strstr(logbuf, "P001 restarted"));
	assert_non_null(strstr(logbuf, "P001 answered trial"));
	assert_non_null(strstr(logbuf, "superseded session refused"));
	sty_server_stop(&sv);
	free_codes(codes, n);
	sty_close(&s);
}

/* The Content-Length of a raw response (-1: none). */
static long content_length(const char *resp)
{
	const char *p = strcasestr(resp, "\r\nContent-Length:");
	return p ? strtol(p + 17, NULL, 10) : -1;
}

static void test_blind_sizes(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_blind_sizes");
	char stim[4096], err[1024], path[256], a[128], b[128], range[128];
	static char ra[1 << 14], rb[1 << 14];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim); /* clip files of different lengths: "clip ref of ...", "clip tfr-T16 of ..." */
	sty_design_summary sm;
	sty *s = designed(dir, "s.db", 6, 2, &sm);
	sty_server *sv = served(s);
	int port = sty_server_port(sv);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	for (uint32_t t = 0; t < sm.trials_per_participant; t++) {
		snprintf(path, sizeof path, "/api/%s/trial", codes[0]);
		assert_int_equal(tu_http(port, "GET", path, NULL, NULL, out, sizeof out), 200);
		if (strstr(out, "\"kind\"") || strstr(out, "catch") || !strstr(out, "\"training\":"))
			fail_msg("the trial JSON tells more than training: %s", out);
		json_str(out, "clip_a", a, sizeof a);
		json_str(out, "clip_b", b, sizeof b);
		size_t la, lb, ba, bb;
		assert_int_equal(get_raw(port, a, NULL, ra, sizeof ra, &la), 200);
		assert_int_equal(get_raw(port, b, NULL, rb, sizeof rb, &lb), 200);
		const char *pa = body(ra, la, &ba), *pb = body(rb, lb, &bb);
		if (ba != bb || content_length(ra) != (long)ba || content_length(rb) != (long)bb)
			fail_msg("trial %u: clips of %zu and %zu bytes", t, ba, bb);
		/* the set's largest clip + STY_PAD_MIN_B (the set named in the clip's text: "clip ref of calm-walk: ...") */
		char set[64] = "", file[4400];
		sscanf(strstr(pa, " of ") + 4, "%63[^:]", set);
		long longest = 0;
		for (int c = 0; c < 3; c++) {
			struct stat sb;
			snprintf(file, sizeof file, "%s/%s/clips/%s.webm", stim, set, c == 0 ? "ref" : c == 1 ? "tfr-T8" : "tfr-T16");
			assert_int_equal(stat(file, &sb), 0);
			longest = sb.st_size > longest ? (long)sb.st_size : longest;
		}
		assert_int_equal((long)ba, longest + 16);
		/* the file, then an EBML Void element (0xEC, 8-byte size 0x01 + 56 bits) covering the rest */
		for (const char *p = pa; p; p = p == pa ? pb : NULL) {
			const char *pad = memchr(p, 0xEC, ba); /* the clip files are text */
			assert_non_null(pad);
			size_t flen = (size_t)(pad - p);
			assert_true(!strncmp(p, "clip ", 5) && flen < ba - 9);
			const unsigned char *v = (const unsigned char *)p + flen;
			assert_int_equal(v[0], 0xEC);
			assert_int_equal(v[1], 0x01);
			uint64_t size = 0;
			for (int i = 2; i < 9; i++)
				size = size << 8 | v[i];
			assert_int_equal(size, ba - flen - 9);
		}
		/* a range across the file's end and into the padding: the same bytes as the whole */
		size_t lr, br;
		static char rr[1 << 14];
		size_t fa = (size_t)((const char *)memchr(pa, 0xEC, ba) - pa);
		snprintf(range, sizeof range, "Range: bytes=%zu-%zu\r\n", fa - 3, ba - 2);
		assert_int_equal(get_raw(port, a, range, rr, sizeof rr, &lr), 206);
		const char *pr = body(rr, lr, &br);
		assert_int_equal(br, ba - 2 - (fa - 3) + 1);
		assert_memory_equal(pr, pa + fa - 3, br);
		char cr[96];
		snprintf(cr, sizeof cr, "Content-Range: bytes %zu-%zu/%zu", fa - 3, ba - 2, ba);
		assert_non_null(strstr(rr, cr));
		snprintf(path, sizeof path, "/api/%s/answer", codes[0]);
		char js[96];
		snprintf(js, sizeof js, "{\"trial\":%u,\"answer\":0,\"rt_ms\":1}", t);
		assert_int_equal(tu_http(port, "POST", path, NULL, js, out, sizeof out), 200);
	}
	sty_server_stop(&sv);
	free_codes(codes, n);
	sty_close(&s);
}

static void test_second_serve(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_second_serve");
	char stim[4096], db[4096], cmd[8192], err[1024];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s = designed(dir, "s.db", 5, 1, &sm);
	sty_server *sv = served(s);
	/* another process, any port: refused in one line, before it listens or records its address */
	snprintf(cmd, sizeof cmd, "%s study serve --db %s --port 0", TASLAB_BINARY, db);
	int st = tu_run(cmd, out, sizeof out);
	assert_int_not_equal(st, 0);
	if (tu_count_lines(out) != 1 || !strstr(out, "is being served already"))
		fail_msg("expected one line, got:\n%s", out);
	char url[64];
	snprintf(url, sizeof url, "http://127.0.0.1:%u", (unsigned)sty_server_port(sv));
	snprintf(cmd, sizeof cmd, "%s study links --db %s", TASLAB_BINARY, db);
	assert_int_equal(tu_run(cmd, out, sizeof out), 0);
	assert_non_null(strstr(out, url)); /* links still point at the server that runs */
	/* the library: TL_ERR_CONFLICT; once the first server stops, a new one starts */
	sty_server *sv2 = NULL;
	sty_server_desc d = {.threads = 1};
	assert_int_equal(sty_server_start(s, &d, &sv2, err, sizeof err), TL_ERR_CONFLICT);
	sty_server_stop(&sv);
	assert_int_equal(sty_server_start(s, &d, &sv2, err, sizeof err), TL_OK);
	sty_server_stop(&sv2);
	sty_close(&s);
}

/* Every trial of every plan of the study file `db` as text (malloc'ed). */
static char *plans(const char *db)
{
	sqlite3 *h;
	sqlite3_stmt *st;
	char *text = NULL;
	if (sqlite3_open_v2(db, &h, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK &&
	    sqlite3_prepare_v2(h, "SELECT group_concat(participant||':'||idx||':'||condition||':'||ref_first||':'||kind||':'||"
				  "break_before, ' ') FROM (SELECT * FROM trials ORDER BY participant, idx)", -1, &st, NULL) == SQLITE_OK) {
		if (sqlite3_step(st) == SQLITE_ROW && sqlite3_column_text(st, 0))
			text = strdup((const char *)sqlite3_column_text(st, 0));
		sqlite3_finalize(st);
	}
	sqlite3_close(h);
	return text ? text : strdup("");
}

static void test_add_participants(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_add");
	char stim[4096], cmd[8192], err[1024];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *all = designed(dir, "all.db", 11, 5, &sm); /* five at once */
	sty *grown = designed(dir, "grown.db", 11, 2, &sm); /* two, then three more */
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(grown, &codes, &n, err, sizeof err), 0);
	assert_int_equal(sty_answer(grown, codes[0], 0, 1, 100, err, sizeof err), TL_OK);
	uint32_t first = 0;
	assert_int_equal(sty_add_participants(grown, 3, &first, err, sizeof err), TL_OK);
	assert_int_equal(first, 3);
	char **codes2;
	size_t n2;
	assert_int_equal(sty_participant_codes(grown, &codes2, &n2, err, sizeof err), 0);
	assert_int_equal(n2, 5);
	assert_string_equal(codes[0], codes2[0]); /* existing participants untouched */
	assert_string_equal(codes[1], codes2[1]);
	free_codes(codes, n);
	free_codes(codes2, n2);
	sty_close(&all);
	sty_close(&grown);
	/* every plan as `design --participants 5` made it */
	char a[4096], g[4096], *want, *got;
	snprintf(a, sizeof a, "%s/all.db", dir);
	snprintf(g, sizeof g, "%s/grown.db", dir);
	want = plans(a);
	got = plans(g);
	assert_true(strlen(want) > 100);
	assert_string_equal(got, want);
	free(want);
	free(got);
	assert_int_equal(db_count(g, "SELECT count(*) FROM answers WHERE participant = 1 AND idx = 0 AND answer = 1"), 1);
	/* the command line: add prints the new labels; design on the existing study is bad input (exit 2, one line) */
	snprintf(cmd, sizeof cmd, "%s study add --db %s --participants 2", TASLAB_BINARY, g);
	assert_int_equal(tu_run(cmd, out, sizeof out), 0);
	assert_non_null(strstr(out, "P006..P007"));
	assert_int_equal(db_count(g, "SELECT count(*) FROM participants"), 7);
	snprintf(cmd, sizeof cmd, "%s study design --db %s --stimuli %s --participants 2", TASLAB_BINARY, g, stim);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	if (tu_count_lines(out) != 1 || !strstr(out, "study add"))
		fail_msg("%s", out);
	assert_int_equal(db_count(g, "SELECT count(*) FROM participants"), 7);
}

static void test_status(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_status");
	char stim[4096], db[4096], cmd[8192], err[1024], path[256], auth[128];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s = designed(dir, "s.db", 7, 3, &sm);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	/* nothing answered: the status says why there are no condition statistics */
	snprintf(cmd, sizeof cmd, "%s study status --db %s", TASLAB_BINARY, db);
	assert_int_equal(tu_run(cmd, out, sizeof out), 0);
	assert_non_null(strstr(out, "no answered test trials"));
	sty_server *sv = served(s);
	int port = sty_server_port(sv);
	/* P001 completes answering "B much better" to everything, P002 "same" to all but the last trial */
	for (int p = 0; p < 2; p++)
		for (uint32_t t = 0; t + (uint32_t)p < sm.trials_per_participant; t++) {
			snprintf(path, sizeof path, "/api/%s/answer", codes[p]);
			char js[96];
			snprintf(js, sizeof js, "{\"trial\":%u,\"answer\":%d,\"rt_ms\":1}", t, p ? 0 : 2);
			assert_int_equal(tu_http(port, "POST", path, NULL, js, out, sizeof out), 200);
		}
	assert_non_null(strstr(logbuf, "P001 completed the session"));
	assert_null(strstr(logbuf, "P002 completed"));
	/* the admin JSON: the token only */
	assert_int_equal(tu_http(port, "GET", "/admin/status", NULL, NULL, out, sizeof out), 401);
	snprintf(auth, sizeof auth, "Authorization: Bearer %s\r\n", sty_admin_token(s));
	assert_int_equal(tu_http(port, "GET", "/admin/status", auth, NULL, out, sizeof out), 200);
	if (!strstr(out, "\"label\":\"P001\"") || !strstr(out, "\"done\":true") || !strstr(out, "\"completed\":1") ||
	    !strstr(out, "\"answers\":" ) || !strstr(out, "\"method\":\"tfr\"") || !strstr(out, "\"scene\":\"all\""))
		fail_msg("%s", out);
	assert_int_equal(json_int(out, "answers"), 2 * (long)sm.trials_per_participant - 1);
	/* catch answers all "much better": P001 is flagged by the screening, as the tally flags it */
	const char *p1 = strstr(out, "\"label\":\"P001\"");
	assert_non_null(strstr(p1, "\"flagged\":true"));
	/* the page carries no data, and the text status agrees while the server runs */
	assert_int_equal(tu_http(port, "GET", "/status", NULL, NULL, out, sizeof out), 200);
	assert_non_null(strstr(out, "/admin/status"));
	assert_null(strstr(out, "P001"));
	assert_int_equal(tu_run(cmd, out, sizeof out), 0);
	char want[64];
	snprintf(want, sizeof want, "%u/%u", sm.trials_per_participant, sm.trials_per_participant);
	if (!strstr(out, "P001") || !strstr(out, want) || !strstr(out, "1 completed") || !strstr(out, "tfr"))
		fail_msg("%s", out);
	sty_server_stop(&sv);
	free_codes(codes, n);
	sty_close(&s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_sessions),
		cmocka_unit_test(test_blind_sizes),
		cmocka_unit_test(test_second_serve),
		cmocka_unit_test(test_add_participants),
		cmocka_unit_test(test_status),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
