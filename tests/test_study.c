/* test_study.c — the study module:
 *  - (the statistics against R and the observer screening are in test_study_stats.c);
 *  - import/export round trip and all-or-nothing validation with line numbers;
 *  - randomisation: reproducible from the seed, every pair in both orders (exactly half each for even N);
 *  - the server: answers stored exactly once, bad requests 4xx changing nothing, no path outside the
 *    stimulus folder, admin token, and crash safety (SIGKILL: every acknowledged answer survives);
 *  - careless and hostile input (issue 12), one test per class: strict answers (test_answer_strict), opaque
 *    clip names and nothing else served (test_clips_blind), private database / bearer token / generic 500s
 *    (test_private_db_and_admin), RFC 7233 ranges and RFC 7230 framing (test_range, test_framing), per-client
 *    connection limit and idle timeout (test_connection_limit), new studies built aside and never overwriting
 *    (test_create_refuses), import rules and CSV formulas (test_import_rules, test_export_formulas), the links'
 *    base (test_links_served_url), one-line server messages and the page text (test_serve_messages), no output
 *    over the study's own files and no partial tally (test_outputs_not_inputs);
 *  - variants with a period (DESIGN section 4): rrc/4, rrc/8 and tarc@8 stay distinct conditions through design,
 *    answers, export, import and tally (test_period_conditions); design's T/period rule on pairs.json
 *    (test_design_period_rule; import's in test_import_rules); studies made before the period column
 *    (test_old_study_schema). */
#define _DEFAULT_SOURCE /* usleep, struct timeval */
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "taslab/pairs.h"
#include "taslab/study.h"
#include "taslab/study_serve.h"
#include "test_study_util.h"

static char out[1 << 16];

/* Sends `req` (len bytes) as is to 127.0.0.1:port from source address `from` (NULL: 127.0.0.1); returns the
 * status code or -1; the whole response (head and body) in resp. */
static int raw_http(int port, const char *from, const char *req, size_t len, char *resp, size_t resp_size)
{
	int fd = socket(AF_INET, SOCK_STREAM, 0);
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)}, src = {.sin_family = AF_INET};
	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	resp[0] = 0;
	if (from) {
		inet_pton(AF_INET, from, &src.sin_addr);
		if (bind(fd, (struct sockaddr *)&src, sizeof src)) {
			close(fd);
			return -1;
		}
	}
	struct timeval tv = {.tv_sec = 10};
	setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
	if (fd < 0 || connect(fd, (struct sockaddr *)&sa, sizeof sa) || write(fd, req, len) != (ssize_t)len) {
		if (fd >= 0)
			close(fd);
		return -1;
	}
	size_t got = 0;
	ssize_t r;
	while (got + 1 < resp_size && (r = read(fd, resp + got, resp_size - 1 - got)) > 0)
		got += (size_t)r;
	close(fd);
	resp[got] = 0;
	int status = -1;
	sscanf(resp, "HTTP/1.%*d %d", &status);
	return status;
}

/* GET path with extra header lines; status, the whole response in resp. */
static int get_full(int port, const char *path, const char *headers, char *resp, size_t n)
{
	char req[4096];
	int len = snprintf(req, sizeof req, "GET %s HTTP/1.0\r\nHost: 127.0.0.1\r\n%s\r\n", path, headers ? headers : "");
	return raw_http(port, NULL, req, (size_t)len, resp, n);
}

/* The body of a whole response. */
static const char *body_of(const char *resp)
{
	const char *b = strstr(resp, "\r\n\r\n");
	return b ? b + 4 : "";
}

/* The string value of "key" in a flat JSON text (test helper; no escapes in our values). */
static void json_str(const char *json, const char *key, char *val, size_t n)
{
	char k[64];
	snprintf(k, sizeof k, "\"%s\":\"", key);
	const char *p = strstr(json, k);
	val[0] = 0;
	if (p) {
		p += strlen(k);
		size_t len = strcspn(p, "\"");
		snprintf(val, n, "%.*s", (int)len, p);
	}
}

static long long db_count(const char *db, const char *sql)
{
	sqlite3 *h;
	sqlite3_stmt *st;
	long long v = -1;
	if (sqlite3_open_v2(db, &h, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK &&
	    sqlite3_prepare_v2(h, sql, -1, &st, NULL) == SQLITE_OK) {
		if (sqlite3_step(st) == SQLITE_ROW)
			v = sqlite3_column_int64(st, 0);
		sqlite3_finalize(st);
	}
	sqlite3_close(h);
	return v;
}

static void test_import_export(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_io");
	char db[4096], exp[4096], bad[4096], err[1024];
	snprintf(db, sizeof db, "%s/s.db", dir);
	snprintf(exp, sizeof exp, "%s/export.csv", dir);
	sty *s = created(db);
	size_t rows;
	/* A bad row anywhere rejects the whole file, naming the line; nothing is imported. */
	snprintf(bad, sizeof bad, "%s/bad.csv", dir);
	char *src = tu_read_file(REF_DIR "/study_ratings.csv", NULL);
	assert_non_null(src);
	const char *cases[][2] = {{"P03,5,", "rating"}, {"P07,2,", "camera_motion"}, {"P10,11,", "answer"}};
	for (int i = 0; i < 3; i++) {
		char *copy = strdup(src), *at = strstr(copy, cases[i][0]);
		assert_non_null(at);
		char *lineend = strchr(at, '\n');
		size_t line = 1;
		for (char *c = copy; c < at; c++)
			line += *c == '\n';
		char row[256];
		if (i == 0)
			snprintf(row, sizeof row, "P03,5,moderate,walk,moving,tfr,8,,0,1,-1,900"); /* rating contradicts answer */
		else if (i == 1)
			snprintf(row, sizeof row, "P07,2,moderate,still,sideways,tfr,8,,1,0,0,900");
		else
			snprintf(row, sizeof row, "P10,11,dynamic,walk,moving,tfr,16,,0,3,3,900");
		FILE *f = fopen(bad, "w");
		fprintf(f, "%.*s%s%s", (int)(at - copy), copy, row, lineend);
		fclose(f);
		assert_int_not_equal(sty_import_long(s, bad, &rows, err, sizeof err), 0);
		char want[64];
		snprintf(want, sizeof want, "bad.csv:%zu:", line);
		if (!strstr(err, want) || !strstr(err, cases[i][1]) || !strstr(err, "nothing imported"))
			fail_msg("message '%s' lacks '%s' / '%s'", err, want, cases[i][1]);
		free(copy);
	}
	assert_int_equal(sty_export_long(s, exp, err, sizeof err), 0);
	char *empty = tu_read_file(exp, NULL);
	assert_int_equal(tu_count_lines(empty), 1); /* header only: nothing was imported */
	free(empty);
	/* The good file imports; exporting gives the same bytes back. */
	assert_int_equal(sty_import_long(s, REF_DIR "/study_ratings.csv", &rows, err, sizeof err), 0);
	assert_int_equal(sty_export_long(s, exp, err, sizeof err), 0);
	char *back = tu_read_file(exp, NULL);
	assert_string_equal(back, src);
	free(back);
	/* pwcmp: ties become two rows. */
	snprintf(exp, sizeof exp, "%s/pwcmp.csv", dir);
	assert_int_equal(sty_export_pwcmp(s, exp, err, sizeof err), 0);
	char *pw = tu_read_file(exp, NULL);
	assert_true(strncmp(pw, "observer,scene,condition_A,condition_B,selected_A\n", 50) == 0);
	int ties = 0; /* rows whose rating (11th field) is 0 */
	for (const char *line = strchr(src, '\n'); line && line[1]; line = strchr(line + 1, '\n')) {
		const char *f = line + 1;
		for (int k = 0; k < 10; k++)
			f = strchr(f, ',') + 1;
		ties += f[0] == '0' && f[1] == ',';
	}
	assert_int_equal(tu_count_lines(pw), 1 + 144 + ties);
	free(pw);
	/* A second import into a used study is refused. */
	assert_int_not_equal(sty_import_long(s, REF_DIR "/study_ratings.csv", &rows, err, sizeof err), 0);
	free(src);
	sty_close(&s);
}

/* Four pair sets (2 scenes x stationary/moving), conditions tfr@8 and tfr@16, small files as clips. */
static void make_stimuli(const char *root)
{
	const char *sets[4][3] = {{"calm-still", "calm", "stationary"}, {"calm-walk", "calm", "moving"},
				  {"dyn-still", "dynamic", "stationary"}, {"dyn-walk", "dynamic", "moving"}};
	for (int i = 0; i < 4; i++) {
		char p[4096];
		snprintf(p, sizeof p, "mkdir -p %s/%s/clips", root, sets[i][0]);
		assert_int_equal(system(p), 0);
		const char *clips[3] = {"ref", "tfr-T8", "tfr-T16"};
		for (int c = 0; c < 3; c++) {
			snprintf(p, sizeof p, "%s/%s/clips/%s.webm", root, sets[i][0], clips[c]);
			FILE *f = fopen(p, "w");
			fprintf(f, "clip %s of %s: 0123456789abcdefghijklmnopqrstuvwxyz", clips[c], sets[i][0]);
			fclose(f);
		}
		snprintf(p, sizeof p, "%s/%s/pairs.json", root, sets[i][0]);
		FILE *f = fopen(p, "w");
		fprintf(f, "{\"taslab_pairs\": 1, \"scene\": \"%s\", \"camera\": \"%s\", \"camera_motion\": \"%s\", \"fps\": 60,"
			   " \"frames\": [0, 59], \"reference\": {\"clip\": \"clips/ref.webm\"}, \"conditions\": ["
			   "{\"method\": \"tfr\", \"T\": 8, \"clip\": \"clips/tfr-T8.webm\"},"
			   "{\"method\": \"tfr\", \"T\": 16, \"clip\": \"clips/tfr-T16.webm\"}]}",
			sets[i][1], strchr(sets[i][0], '-') + 1, sets[i][2]);
		fclose(f);
	}
	FILE *f = fopen(root, "r"); /* a secret next to the stimuli must never be served */
	(void)f;
	char p[4096];
	snprintf(p, sizeof p, "%s/../secret.txt", root);
	f = fopen(p, "w");
	fputs("secret", f);
	fclose(f);
}

static char *plan_dump(const char *db)
{
	sqlite3 *h;
	sqlite3_open(db, &h);
	sqlite3_stmt *st;
	sqlite3_prepare_v2(h, "SELECT participant, idx, condition, ref_first, kind, break_before FROM trials ORDER BY 1, 2", -1,
			   &st, NULL);
	size_t cap = 1 << 16, len = 0;
	char *buf = calloc(cap, 1);
	while (sqlite3_step(st) == SQLITE_ROW && len + 64 < cap)
		len += (size_t)snprintf(buf + len, cap - len, "%d %d %d %d %s %d\n", sqlite3_column_int(st, 0),
					sqlite3_column_int(st, 1), sqlite3_column_int(st, 2), sqlite3_column_int(st, 3),
					sqlite3_column_text(st, 4), sqlite3_column_int(st, 5));
	sqlite3_finalize(st);
	sqlite3_close(h);
	return buf;
}

static sty *designed(const char *dir, const char *name, uint64_t seed, uint32_t participants, sty_design_summary *sm)
{
	char db[4096], stim[4096], err[1024];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/%s", dir, name);
	sty *s = created(db);
	sty_design_desc d = {.stimuli = stim, .participants = participants, .seed = seed, .training = 1, .catch_trials = 2,
			     .break_every = 4};
	if (sty_design(s, &d, sm, err, sizeof err))
		fail_msg("%s", err);
	commit(s);
	return s;
}

static void test_randomisation(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_design");
	char stim[4096], a[4096], b[4096], c[4096];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s1 = designed(dir, "a.db", 42, 10, &sm), *s2 = designed(dir, "b.db", 42, 10, &sm), *s3 = designed(dir, "c.db", 43, 10, &sm);
	/* 8 test conditions + 4 catch pairs; 1 training + 8 tests + 2 catch trials each. */
	assert_int_equal(sm.conditions, 12);
	assert_int_equal(sm.trials_per_participant, 11);
	assert_true(sm.session_minutes > 11 * 2 / 60.0);
	sty_close(&s1), sty_close(&s2), sty_close(&s3);
	snprintf(a, sizeof a, "%s/a.db", dir);
	snprintf(b, sizeof b, "%s/b.db", dir);
	snprintf(c, sizeof c, "%s/c.db", dir);
	char *pa = plan_dump(a), *pb = plan_dump(b), *pc = plan_dump(c);
	assert_string_equal(pa, pb);          /* same seed, same plan */
	assert_string_not_equal(pa, pc);      /* another seed, another plan */
	/* Balance: each test condition is shown reference-first to exactly half of the 10 participants, and trial
	 * orders differ between participants. */
	sqlite3 *h;
	sqlite3_open(a, &h);
	sqlite3_stmt *st;
	sqlite3_prepare_v2(h, "SELECT condition, sum(ref_first), count(*) FROM trials WHERE kind = 'test' GROUP BY condition", -1,
			   &st, NULL);
	int conds = 0;
	while (sqlite3_step(st) == SQLITE_ROW) {
		assert_int_equal(sqlite3_column_int(st, 2), 10);
		assert_int_equal(sqlite3_column_int(st, 1), 5);
		conds++;
	}
	sqlite3_finalize(st);
	assert_int_equal(conds, 8);
	sqlite3_prepare_v2(h, "SELECT count(DISTINCT o) FROM (SELECT group_concat(condition) AS o FROM"
			      " (SELECT participant, condition FROM trials ORDER BY participant, idx) GROUP BY participant)", -1, &st, NULL);
	assert_int_equal(sqlite3_step(st), SQLITE_ROW);
	assert_true(sqlite3_column_int(st, 0) >= 9); /* 10 participants, (essentially) all orders distinct */
	sqlite3_finalize(st);
	sqlite3_close(h);
	free(pa), free(pb), free(pc);
}

/* A server on a free port for the study `s` (threads 2), small limits where a test needs them. */
static sty_server *served(sty *s, const sty_server_desc *over)
{
	char err[1024];
	sty_server_desc d = {.threads = 2};
	if (over)
		d = *over;
	sty_server *sv = NULL;
	if (sty_server_start(s, &d, &sv, err, sizeof err))
		fail_msg("%s", err);
	return sv;
}

static void free_codes(char **codes, size_t n)
{
	for (size_t i = 0; i < n; i++)
		free(codes[i]);
	free(codes);
}

static void test_server(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_server");
	char stim[4096], err[1024], path[512], body[256], clip[128], auth[128];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s = designed(dir, "s.db", 5, 2, &sm);
	sty_server *sv = served(s, NULL);
	int port = sty_server_port(sv);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	assert_int_equal(n, 2);
	/* Page and the first trial. */
	snprintf(path, sizeof path, "/p/%s", codes[0]);
	assert_int_equal(tu_http(port, "GET", path, NULL, NULL, out, sizeof out), 200);
	assert_non_null(strstr(out, "Which clip looked better?"));
	snprintf(path, sizeof path, "/api/%s/trial", codes[0]);
	assert_int_equal(tu_http(port, "GET", path, NULL, NULL, out, sizeof out), 200);
	assert_non_null(strstr(out, "\"index\":0"));
	json_str(out, "clip_a", clip, sizeof clip);
	/* Bad requests: 4xx, and nothing stored. */
	snprintf(path, sizeof path, "/api/%s/answer", codes[0]);
	char big[6000];
	memset(big, ' ', sizeof big - 1);
	big[sizeof big - 1] = 0;
	memcpy(big, "{\"trial\":0,\"answer\":1,\"rt_ms\":5}", 32);
	struct {
		const char *path, *body;
		int status;
	} bad[] = {
		{path, "{not json", 400},
		{path, "{\"trial\":0,\"answer\":7,\"rt_ms\":5}", 400},
		{path, "{\"trial\":\"0\",\"answer\":1,\"rt_ms\":5}", 400},
		{path, "{\"trial\":0,\"answer\":1,\"extra\":1,\"more\":2}", 400},
		{path, "{\"trial\":999,\"answer\":1,\"rt_ms\":5}", 404},
		{path, big, 413},
		{"/api/00000000000000000000000000000000/answer", "{\"trial\":0,\"answer\":1,\"rt_ms\":5}", 404},
		{"/api/xyz/answer", "{\"trial\":0,\"answer\":1,\"rt_ms\":5}", 404},
	};
	for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
		int st = tu_http(port, "POST", bad[i].path, NULL, bad[i].body, out, sizeof out);
		if (st != bad[i].status)
			fail_msg("POST %s %.40s: %d, expected %d (%s)", bad[i].path, bad[i].body, st, bad[i].status, out);
	}
	snprintf(path, sizeof path, "/api/%s/trial", codes[0]);
	tu_http(port, "GET", path, NULL, NULL, out, sizeof out);
	assert_non_null(strstr(out, "\"answered\":0"));
	/* A clip of the current trial, with a range. */
	assert_int_equal(tu_http(port, "GET", clip, "Range: bytes=5-7\r\n", NULL, out, sizeof out), 206);
	assert_true(!strcmp(out, "ref") || !strcmp(out, "tfr"));
	assert_int_equal(tu_http(port, "GET", clip, "Range: bytes=9999-\r\n", NULL, out, sizeof out), 416);
	/* Answer every trial; a repeated answer is 409 and stored once. */
	for (uint32_t t = 0; t < sm.trials_per_participant; t++) {
		snprintf(path, sizeof path, "/api/%s/answer", codes[0]);
		snprintf(body, sizeof body, "{\"trial\":%u,\"answer\":%d,\"rt_ms\":%u}", t, (int)(t % 5) - 2, 500 + t);
		assert_int_equal(tu_http(port, "POST", path, NULL, body, out, sizeof out), 200);
		assert_int_equal(tu_http(port, "POST", path, NULL, body, out, sizeof out), 409);
	}
	snprintf(path, sizeof path, "/api/%s/trial", codes[0]);
	tu_http(port, "GET", path, NULL, NULL, out, sizeof out);
	assert_non_null(strstr(out, "\"done\":true"));
	/* Nothing but the opaque clip names. */
	assert_int_equal(tu_http(port, "GET", "/clips/calm-still/clips/ref.webm", NULL, NULL, out, sizeof out), 404);
	assert_int_equal(tu_http(port, "GET", "/clips/../secret.txt", NULL, NULL, out, sizeof out), 404);
	assert_int_equal(tu_http(port, "GET", "/clips/calm-still/../../secret.txt", NULL, NULL, out, sizeof out), 404);
	assert_int_equal(tu_http(port, "GET", "/clips/%2e%2e/secret.txt", NULL, NULL, out, sizeof out), 404);
	assert_int_equal(tu_http(port, "GET", "/clips//etc/passwd", NULL, NULL, out, sizeof out), 404);
	assert_null(strstr(out, "root:"));
	/* Admin: the bearer token is required. */
	assert_int_equal(tu_http(port, "GET", "/admin/export.csv", NULL, NULL, out, sizeof out), 401);
	assert_int_equal(tu_http(port, "GET", "/admin/export.csv", "Authorization: Bearer 00\r\n", NULL, out, sizeof out), 401);
	snprintf(auth, sizeof auth, "Authorization: Bearer %s\r\n", sty_admin_token(s));
	assert_int_equal(tu_http(port, "GET", "/admin/export.csv", auth, NULL, out, sizeof out), 200);
	assert_int_equal(tu_count_lines(out), 1 + 8); /* header + the 8 test trials (training and catch excluded) */
	sty_server_stop(&sv);
	free_codes(codes, n);
	sty_close(&s);
}

/* Issue 12.1: answers are parsed strictly (before any narrowing), and only the current trial can be answered. */
static void test_answer_strict(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_answers");
	char stim[4096], db[4096], err[1024], path[512];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s = designed(dir, "s.db", 5, 1, &sm);
	sty_server *sv = served(s, NULL);
	int port = sty_server_port(sv);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	snprintf(path, sizeof path, "/api/%s/answer", codes[0]);
	const char *bad[] = {
		"{\"trial\":0,\"answer\":4294967296,\"rt_ms\":5}",   /* was stored as 0 */
		"{\"trial\":0,\"answer\":-4294967294,\"rt_ms\":5}",  /* was stored as +2 */
		"{\"trial\":0,\"answer\":99999999999999999999999,\"rt_ms\":5}",
		"{\"trial\":0,\"answer\":1.0,\"rt_ms\":5}",
		"{\"trial\":0,\"answer\":1.5,\"rt_ms\":5}",
		"{\"trial\":0,\"answer\":\"1\",\"rt_ms\":5}",
		"{\"trial\":0,\"answer\":true,\"rt_ms\":5}",
		"{\"trial\":0,\"answer\":null,\"rt_ms\":5}",
		"{\"trial\":0,\"answer\":1e0,\"rt_ms\":5}",
		"{\"trial\":0,\"answer\":1,\"rt_ms\":5,\"note\":\"x\"}", /* unknown key */
		"{\"trial\":0,\"answer\":1,\"answer\":2,\"rt_ms\":5}",   /* duplicate key */
		"{\"trial\":0,\"answer\":1}",                          /* rt_ms missing */
		"{\"trial\":0,\"answer\":1,\"rt_ms\":-1}",
		"{\"trial\":0,\"answer\":1,\"rt_ms\":86400001}",
		"{\"trial\":0,\"answer\":1,\"rt_ms\":1.5}",
		"{\"trial\":0,\"answer\":1,\"rt_ms\":null}",
		"{\"trial\":-1,\"answer\":1,\"rt_ms\":5}",
		"{\"trial\":4294967296,\"answer\":1,\"rt_ms\":5}",
		"{\"trial\":0.0,\"answer\":1,\"rt_ms\":5}",
		"[0,1,5]",
		"{\"trial\":0,\"answer\":1,\"rt_ms\":5} trailing",
		"{\"trial\":1,\"answer\":1,\"rt_ms\":5}",               /* not shown yet: trial 0 is current */
		"{\"trial\":5,\"answer\":-2,\"rt_ms\":5}",
	};
	for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
		int st = tu_http(port, "POST", path, NULL, bad[i], out, sizeof out);
		if (st != 400 || !strstr(out, "\"error\""))
			fail_msg("POST %s: %d %s, expected 400 with an error", bad[i], st, out);
	}
	assert_int_equal(db_count(db, "SELECT count(*) FROM answers"), 0);
	/* The current trial, then the next one, in order; the library applies the same rules. */
	assert_int_equal(tu_http(port, "POST", path, NULL, "{\"trial\":0,\"answer\":-2,\"rt_ms\":0}", out, sizeof out), 200);
	assert_int_equal(tu_http(port, "POST", path, NULL, "{\"rt_ms\":86400000,\"answer\":2,\"trial\":1}", out, sizeof out), 200);
	assert_int_equal(tu_http(port, "POST", path, NULL, "{\"trial\":3,\"answer\":0,\"rt_ms\":9}", out, sizeof out), 400);
	assert_int_equal(sty_answer(s, codes[0], 3, 0, 9, err, sizeof err), TL_ERR_ARG);
	assert_int_equal(sty_answer(s, codes[0], 2, 4294967296LL, 9, err, sizeof err), TL_ERR_ARG);
	assert_int_equal(sty_answer(s, codes[0], 2, 1, STY_RT_MS_MAX + 1LL, err, sizeof err), TL_ERR_ARG);
	assert_int_equal(sty_answer(s, codes[0], 0, 1, 9, err, sizeof err), TL_ERR_CONFLICT);
	assert_int_equal(db_count(db, "SELECT count(*) FROM answers"), 2);
	assert_int_equal(db_count(db, "SELECT answer FROM answers WHERE idx = 0"), -2);
	assert_int_equal(db_count(db, "SELECT answer FROM answers WHERE idx = 1"), 2);
	assert_int_equal(db_count(db, "SELECT rt_ms FROM answers WHERE idx = 1"), 86400000);
	sty_server_stop(&sv);
	free_codes(codes, n);
	sty_close(&s);
}

/* Issue 12.2: /clips/ serves the clips of the trials shown, by names that do not tell which is the reference;
 * a study database kept in the stimulus folder, its -wal, pairs.json and the clips' real names are all 404. */
static void test_clips_blind(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_clips");
	char stim[4096], db[4096], err[1024], path[512], a[128], b[128], resp[4096];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	snprintf(db, sizeof db, "%s/study.db", stim); /* the database inside the stimulus folder */
	sty *s = created(db);
	sty_design_desc d = {.stimuli = stim, .participants = 2, .seed = 3};
	sty_design_summary sm;
	if (sty_design(s, &d, &sm, err, sizeof err))
		fail_msg("%s", err);
	commit(s);
	sty_server *sv = served(s, NULL);
	int port = sty_server_port(sv);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	const char *hidden[] = {"/clips/study.db", "/clips/study.db-wal", "/clips/study.db-shm", "/clips/calm-still/pairs.json",
				"/clips/calm-still/clips/ref.webm", "/clips/calm-still/clips/tfr-T16.webm", "/clips/ref.webm",
				"/clips/tfr-T16.webm", "/clips/", "/clips/00000000000000000000000000000000.webm"};
	for (size_t i = 0; i < sizeof hidden / sizeof *hidden; i++) {
		int st = tu_http(port, "GET", hidden[i], NULL, NULL, out, sizeof out);
		if (st != 404)
			fail_msg("GET %s: %d, expected 404", hidden[i], st);
	}
	/* Every trial of a session: two names, /clips/<32 hex>.webm, none seen before (the reference's name does not
	 * recur), serving the clip the design put on that side. */
	char seen[64][48];
	size_t nseen = 0;
	for (uint32_t t = 0; t < sm.trials_per_participant; t++) {
		snprintf(path, sizeof path, "/api/%s/trial", codes[0]);
		assert_int_equal(tu_http(port, "GET", path, NULL, NULL, out, sizeof out), 200);
		json_str(out, "clip_a", a, sizeof a);
		json_str(out, "clip_b", b, sizeof b);
		assert_null(strstr(out, "ref"));
		assert_null(strstr(out, "tfr"));
		for (const char *u = a; u; u = u == a ? b : NULL) {
			assert_int_equal(strlen(u), strlen("/clips/") + 32 + strlen(".webm"));
			assert_int_equal(strncmp(u, "/clips/", 7), 0);
			assert_int_equal(strspn(u + 7, "0123456789abcdef"), 32);
			for (size_t k = 0; k < nseen; k++)
				assert_string_not_equal(seen[k], u);
			snprintf(seen[nseen++], sizeof seen[0], "%s", u);
		}
		/* The same names on a reload. */
		char a2[128];
		tu_http(port, "GET", path, NULL, NULL, out, sizeof out);
		json_str(out, "clip_a", a2, sizeof a2);
		assert_string_equal(a, a2);
		char ca[256], cb[256];
		assert_int_equal(get_full(port, a, NULL, resp, sizeof resp), 200);
		assert_non_null(strstr(resp, "Content-Type: video/webm"));
		snprintf(ca, sizeof ca, "%s", body_of(resp));
		assert_int_equal(tu_http(port, "GET", b, NULL, NULL, cb, sizeof cb), 200);
		int ref_a = !strncmp(ca, "clip ref", 8), ref_b = !strncmp(cb, "clip ref", 8);
		assert_true(ref_a || ref_b); /* a test pair: the reference on one side */
		assert_int_equal(db_count(db, "SELECT 1"), 1);
		char q[256];
		snprintf(q, sizeof q, "SELECT ref_first FROM trials WHERE participant = 1 AND idx = %u", t);
		if (!(ref_a && ref_b))
			assert_int_equal(db_count(db, q), ref_a);
		snprintf(path, sizeof path, "/api/%s/answer", codes[0]);
		char body[128];
		snprintf(body, sizeof body, "{\"trial\":%u,\"answer\":0,\"rt_ms\":1}", t);
		assert_int_equal(tu_http(port, "POST", path, NULL, body, out, sizeof out), 200);
	}
	/* Another participant's names differ for the same trials. */
	snprintf(path, sizeof path, "/api/%s/trial", codes[1]);
	tu_http(port, "GET", path, NULL, NULL, out, sizeof out);
	json_str(out, "clip_a", a, sizeof a);
	for (size_t k = 0; k < nseen; k++)
		assert_string_not_equal(seen[k], a);
	sty_server_stop(&sv);
	free_codes(codes, n);
	sty_close(&s);
}

/* Issue 12.3: the database is private (0600), the admin token comes in an Authorization header (not the URL),
 * and a 500 tells the client nothing about the server (paths, SQLite messages). */
static void log_to_buffer(void *cls, const char *line)
{
	char *buf = cls;
	size_t n = strlen(buf);
	snprintf(buf + n, 4096 - n, "%s\n", line);
}

static void test_private_db_and_admin(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_private");
	char stim[4096], db[4096], wal[4200], err[1024], path[512], auth[128], logbuf[4096] = "";
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	snprintf(wal, sizeof wal, "%s-wal", db);
	make_stimuli(stim);
	sty_design_summary sm;
	mode_t old = umask(022);
	sty *s = designed(dir, "s.db", 5, 1, &sm);
	umask(old);
	struct stat sb;
	assert_int_equal(stat(db, &sb), 0);
	if (sb.st_mode & 077)
		fail_msg("%s has mode %o; expected 0600", db, (unsigned)(sb.st_mode & 0777));
	sty_server_desc d = {.threads = 2, .log = log_to_buffer, .log_cls = logbuf};
	sty_server *sv = served(s, &d);
	int port = sty_server_port(sv);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	snprintf(path, sizeof path, "/api/%s/answer", codes[0]);
	assert_int_equal(tu_http(port, "POST", path, NULL, "{\"trial\":0,\"answer\":1,\"rt_ms\":5}", out, sizeof out), 200);
	assert_int_equal(stat(wal, &sb), 0);
	assert_int_equal(sb.st_mode & 077, 0);
	/* The token: in the header (scheme case-insensitive), never from ?token=. */
	snprintf(path, sizeof path, "/admin/export.csv?token=%s", sty_admin_token(s));
	assert_int_equal(tu_http(port, "GET", path, NULL, NULL, out, sizeof out), 401);
	snprintf(auth, sizeof auth, "Authorization: bearer %s\r\n", sty_admin_token(s));
	assert_int_equal(tu_http(port, "GET", "/admin/export.csv", auth, NULL, out, sizeof out), 200);
	snprintf(auth, sizeof auth, "Authorization: Bearer %.31s\r\n", sty_admin_token(s)); /* a prefix */
	assert_int_equal(tu_http(port, "GET", "/admin/export.csv", auth, NULL, out, sizeof out), 401);
	snprintf(auth, sizeof auth, "Authorization: Bearer %sx\r\n", sty_admin_token(s));
	assert_int_equal(tu_http(port, "GET", "/admin/export.csv", auth, NULL, out, sizeof out), 401);
	snprintf(auth, sizeof auth, "Authorization: Basic %s\r\n", sty_admin_token(s));
	assert_int_equal(get_full(port, "/admin/export.csv", auth, out, sizeof out), 401);
	assert_non_null(strstr(out, "WWW-Authenticate: Bearer"));
	/* A broken database: 500 with a generic message; the details (naming the database) only in the log. */
	sqlite3 *h;
	assert_int_equal(sqlite3_open(db, &h), SQLITE_OK);
	assert_int_equal(sqlite3_exec(h, "ALTER TABLE conditions RENAME TO conditions_gone", NULL, NULL, NULL), SQLITE_OK);
	sqlite3_close(h);
	snprintf(path, sizeof path, "/api/%s/trial", codes[0]);
	assert_int_equal(tu_http(port, "GET", path, NULL, NULL, out, sizeof out), 500);
	assert_string_equal(out, "{\"error\":\"internal error\"}");
	snprintf(auth, sizeof auth, "Authorization: Bearer %s\r\n", sty_admin_token(s));
	assert_int_equal(tu_http(port, "GET", "/admin/export.csv", auth, NULL, out, sizeof out), 500);
	assert_string_equal(out, "{\"error\":\"internal error\"}");
	sty_server_stop(&sv);
	assert_non_null(strstr(logbuf, "s.db"));
	assert_non_null(strstr(logbuf, "conditions"));
	free_codes(codes, n);
	sty_close(&s);
}

/* Issue 12.4: Range per RFC 7233; conflicting Content-Length per RFC 7230 section 3.3.3. */
static void test_range(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_range");
	char stim[4096], err[1024], path[512], clip[128], resp[4096], hdr[256];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s = designed(dir, "s.db", 5, 1, &sm);
	sty_server *sv = served(s, NULL);
	int port = sty_server_port(sv);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	snprintf(path, sizeof path, "/api/%s/trial", codes[0]);
	assert_int_equal(tu_http(port, "GET", path, NULL, NULL, out, sizeof out), 200);
	json_str(out, "clip_a", clip, sizeof clip);
	assert_int_equal(get_full(port, clip, NULL, resp, sizeof resp), 200);
	char whole[256];
	snprintf(whole, sizeof whole, "%s", body_of(resp));
	size_t size = strlen(whole);
	assert_true(size > 40);
	struct {
		const char *range;
		int status;
		long first, last; /* the part sent (-1: whole file; for 416 nothing) */
	} cases[] = {
		{"bytes=0-0", 206, 0, 0},
		{"bytes=5-7", 206, 5, 7},
		{"BYTES=5-7", 206, 5, 7},              /* range units are case-insensitive */
		{"bytes=5-", 206, 5, -2},
		{"bytes=5-99999999999999999999999", 206, 5, -2}, /* last past the end: clamped */
		{"bytes=-3", 206, -3, -2},               /* suffix */
		{"bytes=-99999999999999999999", 206, 0, -2},
		{"bytes= 5-7", 206, 5, 7},               /* list syntax: whitespace and empty elements */
		{"bytes=,5-7,", 206, 5, 7},
		{"bytes=0--5", 200, -1, -1},             /* does not parse: ignored */
		{"bytes=--5", 200, -1, -1},
		{"bytes=a-b", 200, -1, -1},
		{"bytes=5", 200, -1, -1},
		{"bytes=-", 200, -1, -1},
		{"bytes=", 200, -1, -1},
		{"bytes 5-7", 200, -1, -1},
		{"items=0-5", 200, -1, -1},              /* unknown unit */
		{"bytes=0-1,3-4", 200, -1, -1},          /* several ranges: ignored (no multipart) */
		{"bytes=0-1, 99999-", 200, -1, -1},
		{"bytes=7-5", 416, 0, 0},                /* invalid: last < first */
		{"bytes=9999-", 416, 0, 0},              /* unsatisfiable */
		{"bytes=99999999999999999999999-", 416, 0, 0},
		{"bytes=-0", 416, 0, 0},
	};
	for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
		snprintf(hdr, sizeof hdr, "Range: %s\r\n", cases[i].range);
		int st = get_full(port, clip, hdr, resp, sizeof resp);
		if (st != cases[i].status)
			fail_msg("Range: %s -> %d, expected %d", cases[i].range, st, cases[i].status);
		const char *b = body_of(resp);
		if (st == 416) {
			char cr[64];
			snprintf(cr, sizeof cr, "Content-Range: bytes */%zu", size);
			assert_non_null(strstr(resp, cr));
			continue;
		}
		long first = cases[i].first < -1 ? (long)size + cases[i].first : cases[i].first;
		long last = cases[i].last == -2 ? (long)size - 1 : cases[i].last;
		if (st == 200) {
			assert_string_equal(b, whole);
			assert_null(strstr(resp, "Content-Range"));
		} else {
			char want[256], cr[96];
			snprintf(want, sizeof want, "%.*s", (int)(last - first + 1), whole + first);
			if (strcmp(b, want))
				fail_msg("Range: %s -> '%s', expected '%s'", cases[i].range, b, want);
			snprintf(cr, sizeof cr, "Content-Range: bytes %ld-%ld/%zu", first, last, size);
			assert_non_null(strstr(resp, cr));
		}
	}
	/* If-Range (we send no validators, so it cannot match) and HEAD: Range ignored. */
	assert_int_equal(get_full(port, clip, "Range: bytes=5-7\r\nIf-Range: \"x\"\r\n", resp, sizeof resp), 200);
	assert_string_equal(body_of(resp), whole);
	sty_server_stop(&sv);
	free_codes(codes, n);
	sty_close(&s);
}

static void test_framing(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_framing");
	char stim[4096], db[4096], err[1024], req[1024], resp[4096];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s = designed(dir, "s.db", 5, 1, &sm);
	sty_server *sv = served(s, NULL);
	int port = sty_server_port(sv);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	const char *body = "{\"trial\":0,\"answer\":1,\"rt_ms\":5}";
	const char *heads[] = {
		"Content-Length: %zu\r\nContent-Length: 2\r\n",             /* conflicting duplicates */
		"Content-Length: 2\r\nContent-Length: %zu\r\n",
		"Content-Length: %zu, 3\r\n",                              /* a conflicting list */
		"Content-Length: %zu\r\nTransfer-Encoding: chunked\r\n",    /* both */
	};
	for (size_t i = 0; i < sizeof heads / sizeof *heads; i++) {
		char h[256];
		snprintf(h, sizeof h, heads[i], strlen(body));
		int len = snprintf(req, sizeof req, "POST /api/%s/answer HTTP/1.1\r\nHost: 127.0.0.1\r\n%sConnection: close\r\n\r\n%s",
				   codes[0], h, body);
		int st = raw_http(port, NULL, req, (size_t)len, resp, sizeof resp);
		if (st != 400)
			fail_msg("request %zu with %s: %d, expected 400", i, h, st);
	}
	assert_int_equal(db_count(db, "SELECT count(*) FROM answers"), 0);
	/* Equal duplicates are one length (RFC 7230 section 3.3.2 allows either); the answer is stored. */
	int len = snprintf(req, sizeof req, "POST /api/%s/answer HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: %zu\r\n"
			   "Connection: close\r\n\r\n%s", codes[0], strlen(body), body);
	assert_int_equal(raw_http(port, NULL, req, (size_t)len, resp, sizeof resp), 200);
	assert_int_equal(db_count(db, "SELECT count(*) FROM answers"), 1);
	sty_server_stop(&sv);
	free_codes(codes, n);
	sty_close(&s);
}

/* Issue 12.4: one client holding many idle connections does not lock others out (per-client limit), and idle
 * connections are closed after the timeout. The limits are small here so that 60 sockets exceed them. */
static void test_connection_limit(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_limit");
	char stim[4096], resp[4096];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s = designed(dir, "s.db", 5, 1, &sm);
	sty_server_desc d = {.threads = 2, .max_connections = 40, .max_per_client = 8, .timeout_s = 2};
	sty_server *sv = served(s, &d);
	int port = sty_server_port(sv);
	enum { IDLE = 60 };
	int fds[IDLE];
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	for (int i = 0; i < IDLE; i++) {
		fds[i] = socket(AF_INET, SOCK_STREAM, 0);
		assert_true(fds[i] >= 0);
		assert_int_equal(connect(fds[i], (struct sockaddr *)&sa, sizeof sa), 0);
		assert_int_equal(write(fds[i], "GET / HTTP/1.1\r\n", 16), 16); /* a request that never ends */
	}
	/* Another client (127.0.0.2: the loopback range is ours) is served at once. */
	const char *req = "GET / HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n";
	assert_int_equal(raw_http(port, "127.0.0.2", req, strlen(req), resp, sizeof resp), 200);
	/* The server closed every idle socket beyond the per-client limit at once ... */
	usleep(300 * 1000);
	int closed = 0;
	for (int i = 0; i < IDLE; i++) {
		struct pollfd p = {.fd = fds[i], .events = POLLIN};
		char c;
		if (poll(&p, 1, 0) == 1 && read(fds[i], &c, 1) <= 0)
			closed++;
	}
	if (closed < IDLE - 8)
		fail_msg("%d of %d idle connections from one client were closed; expected at least %d", closed, IDLE, IDLE - 8);
	/* ... and the rest after the idle timeout. */
	struct timespec t0, t1;
	clock_gettime(CLOCK_MONOTONIC, &t0);
	for (int i = 0; i < IDLE; i++) {
		struct pollfd p = {.fd = fds[i], .events = POLLIN};
		char c;
		if (poll(&p, 1, 8000) != 1 || read(fds[i], &c, 1) > 0)
			fail_msg("idle connection %d still open after the timeout", i);
		close(fds[i]);
	}
	clock_gettime(CLOCK_MONOTONIC, &t1);
	assert_true(t1.tv_sec - t0.tv_sec <= 6);
	assert_int_equal(raw_http(port, NULL, req, strlen(req), resp, sizeof resp), 200);
	sty_server_stop(&sv);
	sty_close(&s);
}

/* Issue 12.5: design/import refuse non-file names and existing databases, build aside and leave nothing behind
 * on failure; design refuses sets whose clips are missing. */
static int dir_entries(const char *dir)
{
	char cmd[4200];
	snprintf(cmd, sizeof cmd, "ls -A '%s' | wc -l", dir);
	FILE *p = popen(cmd, "r");
	int n = -1;
	if (p && fscanf(p, "%d", &n) != 1)
		n = -1;
	if (p)
		pclose(p);
	return n;
}

static void test_create_refuses(void **state)
{
	(void)state;
	const char *dir0 = tu_tmpdir("study_create");
	char dir[4096], stim[4096], db[4200], dbs[4200], err[1024], cmd[16384], bad[4200], p[4200];
	snprintf(dir, sizeof dir, "%s", dir0);
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	snprintf(dbs, sizeof dbs, "%s/dbs", dir);
	mkdir(dbs, 0755);
	sty *s = NULL;
	const char *names[] = {"", ":memory:", "file:x.db?mode=memory"};
	for (int i = 0; i < 3; i++) {
		assert_int_equal(sty_create(names[i], &s, err, sizeof err), TL_ERR_ARG);
		assert_null(s);
		assert_int_not_equal(sty_open(names[i], &s, err, sizeof err), 0);
	}
	snprintf(cmd, sizeof cmd, "cd %s && %s study design --db :memory: --stimuli %s --participants 2", dbs, TASLAB_BINARY, stim);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	assert_non_null(strstr(out, "not a file name"));
	assert_null(strstr(out, "conditions"));
	/* A design that fails (a missing clip) leaves nothing, not even a temporary file. */
	snprintf(p, sizeof p, "%s/dyn-walk/clips/tfr-T16.webm", stim);
	assert_int_equal(unlink(p), 0);
	snprintf(db, sizeof db, "%s/a.db", dbs);
	snprintf(cmd, sizeof cmd, "%s study design --db %s --stimuli %s --participants 2", TASLAB_BINARY, db, stim);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	assert_non_null(strstr(out, "tfr-T16.webm does not exist"));
	assert_int_equal(dir_entries(dbs), 0);
	s = created(db);
	sty_design_desc d = {.stimuli = stim, .participants = 2, .seed = 1};
	sty_design_summary sm;
	assert_int_equal(sty_design(s, &d, &sm, err, sizeof err), TL_ERR_INPUT);
	sty_close(&s);
	assert_int_equal(dir_entries(dbs), 0);
	FILE *f = fopen(p, "w");
	fputs("clip tfr-T16 again", f);
	fclose(f);
	/* A failed import leaves nothing either. */
	snprintf(bad, sizeof bad, "%s/bad.csv", dir);
	f = fopen(bad, "w");
	fputs("participant,trial,scene,camera,camera_motion,method,T,ref_first,answer,rating,rt_ms\nP1,0,calm,still,stationary,tfr,8,1,3,-3,5\n", f);
	fclose(f);
	snprintf(cmd, sizeof cmd, "%s study import --db %s %s", TASLAB_BINARY, db, bad);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	assert_int_equal(dir_entries(dbs), 0);
	/* A good design appears; a second design or an import onto it is refused and changes nothing. */
	snprintf(cmd, sizeof cmd, "%s study design --db %s --stimuli %s --participants 2", TASLAB_BINARY, db, stim);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s", out);
	assert_true(tu_file_exists(db));
	char *before = plan_dump(db);
	snprintf(cmd, sizeof cmd, "%s study design --db %s --stimuli %s --participants 3 --seed 9", TASLAB_BINARY, db, stim);
	assert_int_equal(tu_run(cmd, out, sizeof out), 1); /* TL_ERR_CONFLICT */
	assert_non_null(strstr(out, "never overwritten"));
	snprintf(cmd, sizeof cmd, "%s study import --db %s %s/study_ratings.csv", TASLAB_BINARY, db, REF_DIR);
	assert_int_equal(tu_run(cmd, out, sizeof out), 1);
	char *after = plan_dump(db);
	assert_string_equal(before, after);
	free(before);
	free(after);
	assert_int_equal(sty_create(db, &s, err, sizeof err), TL_ERR_CONFLICT);
	/* A leftover -wal of a deleted study would be applied to a new one by SQLite: refused. */
	snprintf(p, sizeof p, "%s/b.db-wal", dbs);
	f = fopen(p, "w");
	fputs("stale", f);
	fclose(f);
	snprintf(p, sizeof p, "%s/b.db", dbs);
	assert_int_equal(sty_create(p, &s, err, sizeof err), TL_ERR_CONFLICT);
	assert_non_null(strstr(err, "-wal"));
	/* Uncommitted: closing removes the new study and its temporary files. */
	snprintf(p, sizeof p, "%s/c.db", dbs);
	s = created(p);
	sty_close(&s);
	assert_false(tu_file_exists(p));
	assert_int_equal(dir_entries(dbs), 2); /* a.db, b.db-wal */
}

/* Issue 12.6: T exactly for methods with a threshold, period exactly for methods with a period (DESIGN section 4);
 * text cells that a spreadsheet would run are refused. */
static void test_import_rules(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_import_rules");
	char db[4096], csv[4096], err[1024];
	snprintf(csv, sizeof csv, "%s/r.csv", dir);
	const char *rows[][2] = {
		{"P1,0,calm,still,stationary,tfr,,,1,1,-1,5", "needs a threshold"},
		{"P1,0,calm,still,stationary,tarc-oracle,,,1,1,-1,5", "needs a threshold"},
		{"P1,0,calm,still,stationary,tasa,,,1,1,-1,5", "needs a threshold"},
		{"P1,0,calm,still,stationary,ref,8,,1,1,-1,5", "has no threshold"},
		{"P1,0,calm,still,stationary,sau,4,,1,1,-1,5", "has no threshold"},
		{"P1,0,calm,still,stationary,rrc,4,4,1,1,-1,5", "has no threshold"},
		{"P1,0,calm,still,stationary,rrc,,,1,1,-1,5", "method rrc needs a period"},
		{"P1,0,calm,still,stationary,sau,,,1,1,-1,5", "method sau needs a period"},
		{"P1,0,calm,still,stationary,tarc,8,4,1,1,-1,5", "method tarc has no period"},
		{"P1,0,calm,still,stationary,tfr,8,8,1,1,-1,5", "method tfr has no period"},
		{"P1,0,calm,still,stationary,sa,,2,1,1,-1,5", "method sa has no period"},
		{"P1,0,calm,still,stationary,ref,,1,1,1,-1,5", "method ref has no period"},
		{"P1,0,calm,still,stationary,rrc,,3,1,1,-1,5", "period '3'"},
		{"P1,0,calm,still,stationary,rrc,,16,1,1,-1,5", "period '16'"},
		{"P1,0,calm,still,stationary,rrc,,0,1,1,-1,5", "period '0'"},
		{"P1,0,calm,still,stationary,rrc,,-4,1,1,-1,5", "period '-4'"},
		{"P1,0,calm,still,stationary,rrc,, 4,1,1,-1,5", "period ' 4'"},
		{"P1,0,calm,still,stationary,rrc,,4.0,1,1,-1,5", "period '4.0'"},
		{"P1,0,calm,still,stationary,rrc,,4,1,1,-1", "expected 12 columns"},
		{"P1,0,calm,still,stationary,warp,8,,1,1,-1,5", "is not one of"},
		{"P1,0,calm,still,stationary,tfr,300,,1,1,-1,5", "T '300'"},
		{"P1,0,calm,still,stationary,tfr, 8,,1,1,-1,5", "T ' 8'"},
		{"=HYPERLINK(\"http://x\"),0,calm,still,stationary,tfr,8,,1,1,-1,5", "formula"},
		{"P1,0,=1+1,still,stationary,tfr,8,,1,1,-1,5", "formula"},
		{"P1,0,calm,+still,stationary,tfr,8,,1,1,-1,5", "formula"},
		{"P1,0,calm,-still,stationary,tfr,8,,1,1,-1,5", "formula"},
		{"@P1,0,calm,still,stationary,tfr,8,,1,1,-1,5", "formula"},
		{"\tP1,0,calm,still,stationary,tfr,8,,1,1,-1,5", "formula"},
		{"P1,+0,calm,still,stationary,tfr,8,,1,1,-1,5", "trial"},
		{"P1,0,calm,still,stationary,tfr,8,,1, 1,-1,5", "answer"},
	};
	for (size_t i = 0; i < sizeof rows / sizeof *rows; i++) {
		FILE *f = fopen(csv, "w");
		fprintf(f, "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms\n"
			   "P0,0,calm,still,stationary,tfr,8,,1,1,-1,5\n%s\n", rows[i][0]);
		fclose(f);
		snprintf(db, sizeof db, "%s/s%zu.db", dir, i);
		sty *s = created(db);
		size_t n;
		int rc = sty_import_long(s, csv, &n, err, sizeof err);
		if (!rc || !strstr(err, rows[i][1]) || !strstr(err, "r.csv:3:"))
			fail_msg("row '%s': rc %d, message '%s' (expected '%s')", rows[i][0], rc, err, rows[i][1]);
		sty_close(&s);
	}
	/* Files in the DESIGN section 7 layout without the period column (from before it) still import; as they
	 * cannot say a period, their rrc and sau rows are refused. */
	const char *old_header = "participant,trial,scene,camera,camera_motion,method,T,ref_first,answer,rating,rt_ms\n";
	const char *old_rows[][2] = {
		{"P1,0,calm,still,stationary,rrc,,1,1,-1,5", "method rrc needs a period"},
		{"P1,0,calm,still,stationary,sau,,1,1,-1,5", "method sau needs a period"},
		{"P1,0,calm,still,stationary,tfr,,1,1,-1,5", "needs a threshold"},
		{"P1,0,calm,still,stationary,tfr,8,,1,1,-1,5", "expected 11 columns"},
	};
	for (size_t i = 0; i < sizeof old_rows / sizeof *old_rows; i++) {
		FILE *f = fopen(csv, "w");
		fprintf(f, "%sP0,0,calm,still,stationary,tfr,8,1,1,-1,5\n%s\n", old_header, old_rows[i][0]);
		fclose(f);
		snprintf(db, sizeof db, "%s/o%zu.db", dir, i);
		sty *s = created(db);
		size_t n;
		int rc = sty_import_long(s, csv, &n, err, sizeof err);
		if (!rc || !strstr(err, old_rows[i][1]) || !strstr(err, "r.csv:3:"))
			fail_msg("old-layout row '%s': rc %d, message '%s' (expected '%s')", old_rows[i][0], rc, err, old_rows[i][1]);
		sty_close(&s);
	}
	FILE *f = fopen(csv, "w");
	fprintf(f, "%sP0,0,calm,still,stationary,tfr,8,1,1,-1,5\nP0,1,calm,still,stationary,sa,,0,1,1,\n", old_header);
	fclose(f);
	snprintf(db, sizeof db, "%s/old.db", dir);
	sty *s = created(db);
	size_t n;
	if (sty_import_long(s, csv, &n, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(n, 2);
	sty_close(&s);
	/* Every method with T and period as it has them imports, and rrc/4, rrc/8 stay two conditions. */
	f = fopen(csv, "w");
	fprintf(f, "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms\n"
		   "P0,0,calm,still,stationary,tfr,8,,1,1,-1,5\nP0,1,calm,still,stationary,sau,,1,0,1,1,\n"
		   "P0,2,calm,still,stationary,tasa-oracle,16,,0,-2,-2,86400000\nP0,3,calm,still,stationary,rrc,,4,0,1,1,7\n"
		   "P0,4,calm,still,stationary,rrc,,8,0,1,1,7\nP0,5,calm,still,stationary,sau,,2,0,1,1,7\n"
		   "P0,6,calm,still,stationary,sa,,,0,1,1,7\nP0,7,calm,still,stationary,ref,,,0,1,1,7\n");
	fclose(f);
	snprintf(db, sizeof db, "%s/good.db", dir);
	s = created(db);
	if (sty_import_long(s, csv, &n, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(n, 8);
	commit(s);
	sty_close(&s);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions"), 8);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE method = 'rrc' AND T IS NULL AND period IN (4, 8)"), 2);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE period IS NOT NULL AND method NOT IN ('rrc', 'sau')"), 0);
}

/* Issue 12.6: names from a design (pairs.json) that a spreadsheet would run are neutralised on export. */
static void test_export_formulas(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_formulas");
	char stim[4096], db[4096], err[1024], p[4200], res[4200];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(p, sizeof p, "mkdir -p %s/clips", stim);
	assert_int_equal(system(p), 0);
	const char *clips[2] = {"ref", "tfr8"};
	for (int c = 0; c < 2; c++) {
		snprintf(p, sizeof p, "%s/clips/%s.webm", stim, clips[c]);
		FILE *f = fopen(p, "w");
		fputs("clip", f);
		fclose(f);
	}
	snprintf(p, sizeof p, "%s/pairs.json", stim);
	FILE *f = fopen(p, "w");
	fputs("{\"taslab_pairs\": 1, \"scene\": \"=HYPERLINK(\\\"http://evil\\\",\\\"x\\\")\", \"camera\": \"@cam,1\","
	      " \"camera_motion\": \"moving\", \"fps\": 60, \"frames\": [0, 59], \"reference\": {\"clip\": \"clips/ref.webm\"},"
	      " \"conditions\": [{\"method\": \"tfr\", \"T\": 8, \"clip\": \"clips/tfr8.webm\"}]}", f);
	fclose(f);
	snprintf(db, sizeof db, "%s/s.db", dir);
	sty *s = created(db);
	sty_design_desc d = {.stimuli = stim, .participants = 2, .seed = 1};
	sty_design_summary sm;
	if (sty_design(s, &d, &sm, err, sizeof err))
		fail_msg("%s", err);
	commit(s);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	sty_trial t;
	for (size_t i = 0; i < n; i++) {
		assert_int_equal(sty_next_trial(s, codes[i], &t, err, sizeof err), 0);
		assert_int_equal(sty_answer(s, codes[i], t.index, 1, 700, err, sizeof err), 0);
	}
	free_codes(codes, n);
	snprintf(p, sizeof p, "%s/long.csv", dir);
	assert_int_equal(sty_export_long(s, p, err, sizeof err), 0);
	char *csv = tu_read_file(p, NULL);
	if (!strstr(csv, ",\"'=HYPERLINK(\"\"http://evil\"\",\"\"x\"\")\",\"'@cam,1\",moving,tfr,8,"))
		fail_msg("export not neutralised:\n%s", csv);
	free(csv);
	snprintf(p, sizeof p, "%s/pwcmp.csv", dir);
	assert_int_equal(sty_export_pwcmp(s, p, err, sizeof err), 0);
	csv = tu_read_file(p, NULL);
	if (!strstr(csv, ",\"'=HYPERLINK(\"\"http://evil\"\",\"\"x\"\")/@cam,1\","))
		fail_msg("pwcmp export not neutralised:\n%s", csv);
	free(csv);
	snprintf(res, sizeof res, "%s/tally", dir);
	sty_tally_desc td = {.out = res, .bootstrap = 10, .seed = 1, .keep_flagged = true};
	sty_tally(s, &td, err, sizeof err); /* two answers: statistics are mostly empty, the rows are there */
	snprintf(p, sizeof p, "%s/conditions.csv", res);
	csv = tu_read_file(p, NULL);
	if (csv && strstr(csv, ",=HYPERLINK"))
		fail_msg("tally not neutralised:\n%s", csv);
	free(csv);
	sty_close(&s);
}

/* Issue 12.7: `links` uses the URL the server last listened on; --base overrides. */
static void test_links_served_url(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_links");
	char stim[4096], db[4096], cmd[8192], want[128];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s = designed(dir, "s.db", 5, 2, &sm);
	assert_string_equal(sty_served_url(s), "");
	sty_server *sv = served(s, NULL);
	snprintf(want, sizeof want, "http://127.0.0.1:%u/p/", (unsigned)sty_server_port(sv));
	sty_server_stop(&sv);
	sty_close(&s);
	snprintf(cmd, sizeof cmd, "%s study links --db %s", TASLAB_BINARY, db);
	assert_int_equal(tu_run(cmd, out, sizeof out), 0);
	assert_int_equal(tu_count_lines(out), 2);
	if (!strstr(out, want))
		fail_msg("links '%s' do not use %s", out, want);
	snprintf(cmd, sizeof cmd, "%s study links --db %s --base https://study.example", TASLAB_BINARY, db);
	assert_int_equal(tu_run(cmd, out, sizeof out), 0);
	assert_non_null(strstr(out, " https://study.example/p/"));
}

/* Issue 12.8: libmicrohttpd's messages do not reach the terminal raw: a port in use is one line of ours. The
 * participant page shows no literal HTML entities (script text is not HTML). */
static void test_serve_messages(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_messages");
	char stim[4096], db[4096], cmd[8192], err[1024];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s = designed(dir, "s.db", 5, 1, &sm);
	sty_server *sv = served(s, NULL);
	snprintf(cmd, sizeof cmd, "%s study serve --db %s --port %u", TASLAB_BINARY, db, (unsigned)sty_server_port(sv));
	int st = tu_run(cmd, out, sizeof out);
	assert_int_not_equal(st, 0);
	if (tu_count_lines(out) != 1 || strncmp(out, "taslab study serve: cannot listen", 33) || !strstr(out, "in use"))
		fail_msg("expected one line of ours, got:\n%s", out);
	/* The same through the library: the reason is in the message, nothing is printed. */
	sty_server *sv2 = NULL;
	sty_server_desc d = {.port = sty_server_port(sv)};
	assert_int_equal(sty_server_start(s, &d, &sv2, err, sizeof err), TL_ERR_ARG);
	if (!strstr(err, "Address already in use"))
		fail_msg("%s", err);
	/* The page: no entity inside the script. */
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	char path[128];
	snprintf(path, sizeof path, "/p/%s", codes[0]);
	assert_int_equal(tu_http(sty_server_port(sv), "GET", path, NULL, NULL, out, sizeof out), 200);
	const char *script = strstr(out, "<script>");
	assert_non_null(script);
	for (const char *amp = strchr(script, '&'); amp; amp = strchr(amp + 1, '&')) {
		size_t k = 1;
		while (amp[k] && ((amp[k] >= 'a' && amp[k] <= 'z') || amp[k] == '#' || (amp[k] >= '0' && amp[k] <= '9')))
			k++;
		if (k > 1 && amp[k] == ';')
			fail_msg("an HTML entity in the page's script is shown literally: %.12s", amp);
	}
	free_codes(codes, n);
	sty_server_stop(&sv);
	sty_close(&s);
}

/* ------------------------------------------------------------------ variants with a period (DESIGN section 4) */

/* The variants of the period tests: rrc/4 and rrc/8 differ only by period, tarc@8 has a threshold. `base` is the
 * reference-relative rating the simulated participants give (plus 0 or 1, see period_rating). */
static const struct {
	const char *id, *method, *variant;
	double T;
	uint32_t period;
	int base;
} period_variants[3] = {
	{"rrc-N4", "rrc", "rrc/4", NAN, 4, -1}, {"rrc-N8", "rrc", "rrc/8", NAN, 8, 1}, {"tarc-T8", "tarc", "tarc@8", 8, 0, 0}};

/* Participant p's rating of variant v in set k: base + (p + k) % 2, so each participant's mean over the two sets is
 * base + 0.5 (pooled Q: rrc/4 -0.5, rrc/8 1.5, tarc@8 0.5; rrc/4 and rrc/8 merged would give 0.5). */
static int period_rating(int v, int p, int k) { return period_variants[v].base + (p + k) % 2; }

/* Two sets of scene calm (path still: stationary, walk: moving), each with rrc/4, rrc/8 and tarc@8, written by the
 * pairs.json writer `taslab pair` uses; small files as clips. */
static void make_period_stimuli(const char *root)
{
	const char *sets[2][3] = {{"calm-still", "still", "stationary"}, {"calm-walk", "walk", "moving"}};
	char p[4096], err[1024];
	for (int k = 0; k < 2; k++) {
		snprintf(p, sizeof p, "mkdir -p %s/%s/clips", root, sets[k][0]);
		assert_int_equal(system(p), 0);
		pairs_condition c[3];
		memset(c, 0, sizeof c);
		for (int v = 0; v <= 3; v++) {
			const char *id = v < 3 ? period_variants[v].id : "ref";
			snprintf(p, sizeof p, "%s/%s/clips/%s.webm", root, sets[k][0], id);
			FILE *f = fopen(p, "w");
			fprintf(f, "clip %s of %s", id, sets[k][0]);
			fclose(f);
			if (v == 3)
				break;
			snprintf(c[v].id, sizeof c[v].id, "%s", id);
			snprintf(c[v].method, sizeof c[v].method, "%s", period_variants[v].method);
			snprintf(c[v].variant, sizeof c[v].variant, "%s", period_variants[v].variant);
			c[v].T = period_variants[v].T;
			c[v].period = period_variants[v].period;
			snprintf(c[v].clip, sizeof c[v].clip, "clips/%s.webm", id);
		}
		pairs_set set = {.fps = 60, .first_frame = 0, .last_frame = 59, .width = 16, .height = 16, .conditions = c,
				 .count = 3};
		snprintf(set.scene, sizeof set.scene, "calm");
		snprintf(set.camera, sizeof set.camera, "%s", sets[k][1]);
		snprintf(set.camera_motion, sizeof set.camera_motion, "%s", sets[k][2]);
		snprintf(set.ref_clip, sizeof set.ref_clip, "clips/ref.webm");
		snprintf(set.ref_run, sizeof set.ref_run, "runs/ref");
		snprintf(p, sizeof p, "%s/%s/pairs.json", root, sets[k][0]);
		if (pairs_write(p, &set, err, sizeof err))
			fail_msg("%s", err);
	}
}

/* Lines of `text` containing `needle`. */
static int count_lines_with(const char *text, const char *needle)
{
	int n = 0;
	for (const char *l = text; l && *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : NULL) {
		const char *e = strchr(l, '\n'), *hit = strstr(l, needle);
		n += hit && (!e || hit < e);
	}
	return n;
}

/* The first line of a file. */
static void first_line(const char *path, char *line, size_t n)
{
	FILE *f = fopen(path, "r");
	line[0] = 0;
	if (f && fgets(line, (int)n, f))
		line[strcspn(line, "\n")] = 0;
	if (f)
		fclose(f);
}

/* Checks a tally of the period study in `res`: one row per variant (rrc/4 and rrc/8 apart) in conditions.csv with
 * the expected pooled Q, an ANOVA, post hoc and JOD row per variant, and period right after T in every CSV. */
static void check_period_tally(const char *res)
{
	char p[4200], line[512];
	const char *heads[6][2] = {
		{"conditions.csv", "method,T,period,scene,camera,n,Q,Q_lo,Q_hi,p_ref,p_ref_lo,p_ref_hi,jnd"},
		{"anova.csv", "method,T,period,effect,df1,df2,F,p,p_gg,epsilon_gg"},
		{"posthoc.csv", "method,T,period,factor,level_1,level_2,t,df,p,p_bonferroni"},
		{"jod.csv", "method,T,period,scene,camera,jod,jod_lo,jod_hi,participants"},
		{"fig3.csv", "method,T,period,Q,Q_lo,Q_hi,p_ref_percent,p_ref_lo_percent,p_ref_hi_percent"},
		{"observers.csv", "participant,catch_n,catch_mean_abs_answer,catch_much_better,flagged"},
	};
	for (int i = 0; i < 6; i++) {
		snprintf(p, sizeof p, "%s/%s", res, heads[i][0]);
		first_line(p, line, sizeof line);
		assert_string_equal(line, heads[i][1]);
	}
	const char *keys[3][3] = {{"rrc", "", "4"}, {"rrc", "", "8"}, {"tarc", "8", ""}};
	for (int v = 0; v < 3; v++) {
		const char *pooled[5] = {keys[v][0], keys[v][1], keys[v][2], "all", "all"};
		const char *still[5] = {keys[v][0], keys[v][1], keys[v][2], "calm", "still"};
		const char *effect[4] = {keys[v][0], keys[v][1], keys[v][2], "camera"};
		snprintf(p, sizeof p, "%s/conditions.csv", res);
		double Q = tu_csv_lookup(p, pooled, 5, 6), n = tu_csv_lookup(p, pooled, 5, 5);
		if (!(fabs(Q - (period_variants[v].base + 0.5)) < 1e-9) || n != 8)
			fail_msg("%s: pooled Q %g over %g ratings, expected %g over 8", period_variants[v].variant, Q, n,
				 period_variants[v].base + 0.5);
		assert_true(tu_csv_lookup(p, still, 5, 5) == 4);
		snprintf(p, sizeof p, "%s/anova.csv", res);
		assert_true(tu_csv_lookup(p, effect, 4, 4) == 1); /* df1 of Camera: its own ANOVA per variant */
		snprintf(p, sizeof p, "%s/posthoc.csv", res);
		assert_false(isnan(tu_csv_lookup(p, effect, 4, 8)));
		snprintf(p, sizeof p, "%s/jod.csv", res);
		assert_false(isnan(tu_csv_lookup(p, pooled, 5, 5)));
	}
	snprintf(p, sizeof p, "%s/conditions.csv", res);
	char *csv = tu_read_file(p, NULL);
	assert_int_equal(tu_count_lines(csv), 1 + 3 * 3); /* per variant: 2 sets + pooled */
	free(csv);
	snprintf(p, sizeof p, "%s/anova.csv", res);
	csv = tu_read_file(p, NULL);
	assert_int_equal(tu_count_lines(csv), 1 + 3);
	free(csv);
	snprintf(p, sizeof p, "%s/conditions.json", res);
	csv = tu_read_file(p, NULL);
	assert_non_null(strstr(csv, "\"period\": 4"));
	assert_non_null(strstr(csv, "\"period\": 8"));
	free(csv);
}

/* rrc/4, rrc/8 and tarc@8 in one set are distinct conditions from design through answers, export, import and
 * tally (DESIGN section 4: T and period their own columns). */
static void test_period_conditions(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_period");
	char stim[4096], db[4096], db2[4096], err[1024], exp[4200], exp2[4200], pw[4200], res[4200], res2[4200];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	snprintf(db2, sizeof db2, "%s/imported.db", dir);
	make_period_stimuli(stim);
	/* Design: 3 variants x 2 sets, plus the 2 catch pairs; the period stored as given, NULL for the others. */
	sty *s = created(db);
	sty_design_desc d = {.stimuli = stim, .participants = 4, .seed = 11, .training = 1, .catch_trials = 2};
	sty_design_summary sm;
	if (sty_design(s, &d, &sm, err, sizeof err))
		fail_msg("%s", err);
	commit(s);
	assert_int_equal(sm.conditions, 8);
	assert_int_equal(sm.trials_per_participant, 1 + 6 + 2);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE method = 'rrc' AND T IS NULL AND period = 4"), 2);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE method = 'rrc' AND T IS NULL AND period = 8"), 2);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE method = 'tarc' AND T = 8 AND period IS NULL"), 2);
	assert_int_equal(db_count(db, "SELECT count(*) FROM conditions WHERE method = 'ref' AND is_catch AND period IS NULL"), 2);
	assert_int_equal(db_count(db, "SELECT count(DISTINCT method || '/' || ifnull(T, '') || '/' || ifnull(period, '') || '/'"
				      " || camera) FROM conditions WHERE NOT is_catch"), 6);
	/* Answers: the simulated participants tell the clips apart by what they serve (sty_clip_file). */
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	assert_int_equal(n, 4);
	for (size_t pi = 0; pi < n; pi++) {
		sty_trial t;
		for (;;) {
			assert_int_equal(sty_next_trial(s, codes[pi], &t, err, sizeof err), 0);
			if (t.done)
				break;
			char a[4096], b[4096];
			assert_int_equal(sty_clip_file(s, t.clip_a, a, sizeof a, err, sizeof err), 0);
			assert_int_equal(sty_clip_file(s, t.clip_b, b, sizeof b, err, sizeof err), 0);
			int ref_first = strstr(a, "/ref.webm") != NULL, answer = 0;
			const char *test = ref_first ? b : a;
			if (!strcmp(t.kind, "test")) {
				int v = 0;
				while (v < 3 && !strstr(test, period_variants[v].id))
					v++;
				assert_true(v < 3);
				int r = period_rating(v, (int)pi, strstr(test, "calm-walk") != NULL);
				answer = ref_first ? -r : r;
			}
			assert_int_equal(sty_answer(s, codes[pi], t.index, answer, 800, err, sizeof err), 0);
		}
	}
	free_codes(codes, n);
	/* Export: T and period in their own columns; 4 participants x 2 sets per variant. */
	snprintf(exp, sizeof exp, "%s/ratings.csv", dir);
	snprintf(pw, sizeof pw, "%s/pwcmp.csv", dir);
	assert_int_equal(sty_export_long(s, exp, err, sizeof err), 0);
	assert_int_equal(sty_export_pwcmp(s, pw, err, sizeof err), 0);
	char *csv = tu_read_file(exp, NULL);
	const char *head = "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms\n";
	assert_int_equal(strncmp(csv, head, strlen(head)), 0);
	assert_int_equal(tu_count_lines(csv), 1 + 4 * 6);
	assert_int_equal(count_lines_with(csv, ",rrc,,4,"), 8);
	assert_int_equal(count_lines_with(csv, ",rrc,,8,"), 8);
	assert_int_equal(count_lines_with(csv, ",tarc,8,,"), 8);
	free(csv);
	char *pwc = tu_read_file(pw, NULL);
	assert_true(count_lines_with(pwc, ",rrc_N4,") + count_lines_with(pwc, ",rrc_N4\n") >= 8);
	assert_true(count_lines_with(pwc, "rrc_N8,") >= 8);
	assert_true(count_lines_with(pwc, "tarc_T8,") >= 8);
	assert_int_equal(count_lines_with(pwc, ",rrc,"), 0);
	free(pwc);
	snprintf(res, sizeof res, "%s/tally", dir);
	sty_tally_desc td = {.out = res, .bootstrap = 50, .seed = 1, .no_plot = true};
	if (sty_tally(s, &td, err, sizeof err))
		fail_msg("%s", err);
	sty_close(&s);
	check_period_tally(res);
	/* Import of the export: the same conditions and the same bytes back, and the same statistics. */
	s = created(db2);
	size_t rows;
	if (sty_import_long(s, exp, &rows, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(rows, 24);
	commit(s);
	assert_int_equal(db_count(db2, "SELECT count(*) FROM conditions"), 6);
	assert_int_equal(db_count(db2, "SELECT count(DISTINCT ifnull(period, 0)) FROM conditions WHERE method = 'rrc'"), 2);
	snprintf(exp2, sizeof exp2, "%s/ratings2.csv", dir);
	assert_int_equal(sty_export_long(s, exp2, err, sizeof err), 0);
	char *x1 = tu_read_file(exp, NULL), *x2 = tu_read_file(exp2, NULL);
	assert_string_equal(x1, x2);
	free(x1), free(x2);
	snprintf(res2, sizeof res2, "%s/tally2", dir);
	td.out = res2;
	if (sty_tally(s, &td, err, sizeof err))
		fail_msg("%s", err);
	sty_close(&s);
	check_period_tally(res2);
	const char *same[2] = {"conditions.csv", "anova.csv"};
	for (int i = 0; i < 2; i++) {
		char pa[4300], pb[4300];
		snprintf(pa, sizeof pa, "%s/%s", res, same[i]);
		snprintf(pb, sizeof pb, "%s/%s", res2, same[i]);
		x1 = tu_read_file(pa, NULL), x2 = tu_read_file(pb, NULL);
		assert_string_equal(x1, x2);
		free(x1), free(x2);
	}
}

/* Design applies the import rule to pairs.json: period exactly for rrc and sau (1, 2, 4, 8), T exactly for the
 * methods with a threshold. */
static void test_design_period_rule(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_design_period");
	const struct {
		const char *method;
		double T;
		uint32_t period;
		const char *why;
	} bad[] = {
		{"rrc", NAN, 0, "method rrc needs a period"},   {"sau", NAN, 0, "method sau needs a period"},
		{"tarc", 8, 4, "method tarc has no period"},    {"tarc-oracle", 8, 8, "method tarc-oracle has no period"},
		{"sa", NAN, 2, "method sa has no period"},      {"rrc", NAN, 3, "period 3 is not"},
		{"rrc", NAN, 16, "period 16 is not"},    {"rrc", 8, 4, "method rrc has no threshold"},
		{"tasa", NAN, 0, "method tasa needs a threshold"},
	};
	char err[1024];
	for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
		char stim[4200], p[4300], db[4200];
		snprintf(stim, sizeof stim, "%s/stim%zu", dir, i);
		snprintf(p, sizeof p, "mkdir -p %s", stim);
		assert_int_equal(system(p), 0);
		const char *clips[2] = {"ref.webm", "x.webm"};
		for (int c = 0; c < 2; c++) {
			snprintf(p, sizeof p, "%s/%s", stim, clips[c]);
			FILE *f = fopen(p, "w");
			fputs("clip", f);
			fclose(f);
		}
		pairs_condition c = {.T = bad[i].T, .period = bad[i].period};
		snprintf(c.id, sizeof c.id, "cond%zu", i);
		snprintf(c.method, sizeof c.method, "%s", bad[i].method);
		snprintf(c.variant, sizeof c.variant, "%s", bad[i].method);
		snprintf(c.clip, sizeof c.clip, "x.webm");
		pairs_set set = {.fps = 60, .last_frame = 59, .width = 16, .height = 16, .conditions = &c, .count = 1};
		snprintf(set.scene, sizeof set.scene, "calm");
		snprintf(set.camera, sizeof set.camera, "still");
		snprintf(set.camera_motion, sizeof set.camera_motion, "stationary");
		snprintf(set.ref_clip, sizeof set.ref_clip, "ref.webm");
		snprintf(set.ref_run, sizeof set.ref_run, "runs/ref");
		snprintf(p, sizeof p, "%s/pairs.json", stim);
		if (pairs_write(p, &set, err, sizeof err))
			fail_msg("%s", err);
		snprintf(db, sizeof db, "%s/s%zu.db", dir, i);
		sty *s = created(db);
		sty_design_desc d = {.stimuli = stim, .participants = 2, .seed = 1};
		sty_design_summary sm;
		int rc = sty_design(s, &d, &sm, err, sizeof err);
		char id[32];
		snprintf(id, sizeof id, "'cond%zu'", i);
		if (rc != TL_ERR_INPUT || !strstr(err, bad[i].why) || !strstr(err, id) || strchr(err, '\n'))
			fail_msg("%s T %g period %u: rc %d, '%s' (expected '%s')", bad[i].method, bad[i].T, bad[i].period, rc, err,
				 bad[i].why);
		sty_close(&s);
		assert_false(tu_file_exists(db));
	}
}

/* Studies made before the period column: opened, the column is added (NULL), and they work on; one holding rrc or
 * sau conditions (period never stored) is refused with one line. */
static void test_old_study_schema(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_old_schema");
	char stim[4096], db[4096], err[1024], p[4200], cmd[16384];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	for (int with_rrc = 0; with_rrc < 2; with_rrc++) {
		sty_design_summary sm;
		char name[16];
		snprintf(name, sizeof name, "old%d.db", with_rrc);
		snprintf(db, sizeof db, "%s/%s", dir, name);
		sty *s = designed(dir, name, 5, 2, &sm);
		char **codes;
		size_t n;
		assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
		sty_trial t;
		for (int k = 0; k < 3; k++) {
			assert_int_equal(sty_next_trial(s, codes[0], &t, err, sizeof err), 0);
			assert_int_equal(sty_answer(s, codes[0], t.index, 1, 900, err, sizeof err), 0);
		}
		free_codes(codes, n);
		sty_close(&s);
		/* The conditions table as studies had it before: no period column (an rrc condition in the second). */
		sqlite3 *h;
		assert_int_equal(sqlite3_open(db, &h), SQLITE_OK);
		char *msg = NULL;
		const char *sql = with_rrc ? "ALTER TABLE conditions DROP COLUMN period; UPDATE conditions SET method = 'rrc', T = NULL"
					     " WHERE id = (SELECT min(id) FROM conditions WHERE method = 'tfr')"
					   : "ALTER TABLE conditions DROP COLUMN period";
		if (sqlite3_exec(h, sql, NULL, NULL, &msg) != SQLITE_OK)
			fail_msg("%s", msg);
		sqlite3_close(h);
		assert_int_equal(db_count(db, "SELECT count(*) FROM pragma_table_info('conditions') WHERE name = 'period'"), 0);
		int rc = sty_open(db, &s, err, sizeof err);
		if (with_rrc) {
			assert_int_equal(rc, TL_ERR_INPUT);
			assert_null(s);
			if (!strstr(err, "without a period") || strchr(err, '\n'))
				fail_msg("%s", err);
			snprintf(cmd, sizeof cmd, "%s study export --db %s --out %s/x.csv", TASLAB_BINARY, db, dir);
			assert_int_equal(tu_run(cmd, out, sizeof out), 2);
			if (tu_count_lines(out) != 1 || !strstr(out, "without a period"))
				fail_msg("expected one line, got:\n%s", out);
			continue;
		}
		if (rc)
			fail_msg("%s", err);
		sty_close(&s);
		assert_int_equal(db_count(db, "SELECT count(*) FROM pragma_table_info('conditions') WHERE name = 'period'"), 1);
		snprintf(p, sizeof p, "%s/old.csv", dir);
		snprintf(cmd, sizeof cmd, "%s study export --db %s --out %s && %s study tally --db %s --out %s/t --bootstrap 20",
			 TASLAB_BINARY, db, p, TASLAB_BINARY, db, dir);
		if (tu_run(cmd, out, sizeof out))
			fail_msg("%s", out);
		char *csv = tu_read_file(p, NULL);
		const char *head = "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,";
		assert_int_equal(strncmp(csv, head, strlen(head)), 0);
		free(csv);
	}
}

static void test_crash_safety(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_crash");
	char stim[4096], db[4096], err[1024];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s = designed(dir, "s.db", 9, 3, &sm);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	sty_close(&s);
	int fds[2];
	assert_int_equal(pipe(fds), 0);
	pid_t child = fork();
	if (child == 0) { /* the server process */
		sty *cs = NULL;
		sty_server *sv = NULL;
		sty_server_desc sd = {.threads = 4};
		if (sty_open(db, &cs, err, sizeof err) || sty_server_start(cs, &sd, &sv, err, sizeof err))
			_exit(3);
		int port = sty_server_port(sv);
		if (write(fds[1], &port, sizeof port) != sizeof port)
			_exit(4);
		for (;;)
			pause();
	}
	int port = 0;
	assert_int_equal(read(fds[0], &port, sizeof port), (ssize_t)sizeof port);
	/* Participants answer in turns; after the 17th acknowledged answer the server is killed without warning. */
	int acked[3][32] = {{0}}, total = 0;
	for (uint32_t t = 0; t < sm.trials_per_participant && total < 17; t++)
		for (size_t p = 0; p < n && total < 17; p++) {
			char path[128], body[128];
			snprintf(path, sizeof path, "/api/%s/answer", codes[p]);
			snprintf(body, sizeof body, "{\"trial\":%u,\"answer\":%d,\"rt_ms\":700}", t, (int)((t + p) % 5) - 2);
			if (tu_http(port, "POST", path, NULL, body, out, sizeof out) == 200) {
				acked[p][t] = 1;
				total++;
			}
		}
	assert_int_equal(kill(child, SIGKILL), 0);
	int st;
	waitpid(child, &st, 0);
	assert_true(WIFSIGNALED(st));
	/* Every acknowledged answer is in the database, exactly once, with its value. */
	sqlite3 *h;
	assert_int_equal(sqlite3_open(db, &h), SQLITE_OK);
	sqlite3_stmt *q;
	sqlite3_prepare_v2(h, "SELECT p.code, a.idx, a.answer, count(*) OVER (PARTITION BY a.participant, a.idx) FROM answers a"
			      " JOIN participants p ON p.id = a.participant", -1, &q, NULL);
	int found = 0;
	while (sqlite3_step(q) == SQLITE_ROW) {
		size_t p = 0;
		while (p < n && strcmp(codes[p], (const char *)sqlite3_column_text(q, 0)))
			p++;
		int t = sqlite3_column_int(q, 1);
		assert_true(p < n && acked[p][t]);
		assert_int_equal(sqlite3_column_int(q, 2), (int)((t + p) % 5) - 2);
		assert_int_equal(sqlite3_column_int(q, 3), 1);
		found++;
	}
	sqlite3_finalize(q);
	sqlite3_close(h);
	assert_int_equal(found, 17);
	for (size_t i = 0; i < n; i++)
		free(codes[i]);
	free(codes);
	close(fds[0]);
	close(fds[1]);
}

static void test_cli(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_cli");
	char cmd[8192];
	snprintf(cmd, sizeof cmd, "%s study design --db %s/x.db --stimuli %s/nowhere --participants 2", TASLAB_BINARY, dir, dir);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	assert_int_equal(tu_count_lines(out), 1);
	snprintf(cmd, sizeof cmd, "%s study tally --db %s/missing.db --out %s/o", TASLAB_BINARY, dir, dir);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	assert_non_null(strstr(out, "no such study database"));
	snprintf(cmd, sizeof cmd, "%s study import --db %s/i.db %s/study_ratings.csv && %s study tally --db %s/i.db --out %s/t "
		 "--bootstrap 50 && %s study export --db %s/i.db --out %s/e.csv", TASLAB_BINARY, dir, REF_DIR, TASLAB_BINARY,
		 dir, dir, TASLAB_BINARY, dir, dir);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s", out);
	snprintf(cmd, sizeof cmd, "%s/t/anova.csv", dir);
	assert_true(tu_file_exists(cmd));
}


/* Issue 12, data loss: no study command writes over the study (export --out S, --pwcmp S, the journal, a symlink or
 * hard link to S, a tally folder where S sits under an output's name), export's two files are checked before either
 * is written, and a tally that fails leaves no output: not an empty folder, not the tables written before a full
 * disk (the full-disk case needs root for a small tmpfs; skipped with a message otherwise). */
static void test_outputs_not_inputs(void **state)
{
	(void)state;
	const char *dir0 = tu_tmpdir("study_outputs");
	char dir[4096], db[4200], p[4300], q[4300], args[16384], cmd[16384];
	snprintf(dir, sizeof dir, "%s", dir0);
	snprintf(db, sizeof db, "%s/s.db", dir);
	snprintf(cmd, sizeof cmd, "%s study import --db %s %s/study_ratings.csv", TASLAB_BINARY, db, REF_DIR);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s", out);
	size_t len0, len1;
	char *before = tu_read_file(db, &len0);
	snprintf(p, sizeof p, "%s/link.db", dir);
	assert_int_equal(symlink("s.db", p), 0);
	snprintf(p, sizeof p, "%s/hard.db", dir);
	assert_int_equal(link(db, p), 0);
	const char *outs[] = {"%s/s.db", "%s/./s.db", "%s/link.db", "%s/hard.db", "%s/s.db-wal", "%s/s.db-shm"};
	for (size_t i = 0; i < sizeof outs / sizeof *outs; i++) {
		snprintf(p, sizeof p, outs[i], dir);
		snprintf(args, sizeof args, "study export --db %s --out %s", db, p);
		tu_expect_cli_error(args, "is the study database");
	}
	/* The database by another name, and --pwcmp: refused before the long file is written. */
	snprintf(args, sizeof args, "study export --db %s/link.db --out %s/s.db", dir, dir);
	tu_expect_cli_error(args, "is the study database");
	snprintf(args, sizeof args, "study export --db %s --out %s/long.csv --pwcmp %s", db, dir, db);
	tu_expect_cli_error(args, "is the study database");
	snprintf(args, sizeof args, "study export --db %s --out %s/both.csv --pwcmp %s/./both.csv", db, dir, dir);
	tu_expect_cli_error(args, "the same file");
	snprintf(p, sizeof p, "%s/long.csv", dir);
	assert_false(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/both.csv", dir);
	assert_false(tu_file_exists(p));
	/* A tally folder holding the study under one of the tally's file names. */
	snprintf(p, sizeof p, "%s/t", dir);
	mkdir(p, 0755);
	snprintf(q, sizeof q, "%s/t/conditions.csv", dir);
	snprintf(cmd, sizeof cmd, "cp %s %s", db, q);
	assert_int_equal(system(cmd), 0);
	snprintf(args, sizeof args, "study tally --db %s --out %s --bootstrap 10", q, p);
	tu_expect_cli_error(args, "is the study database");
	char *copy = tu_read_file(q, &len1);
	assert_true(len1 == len0 && !memcmp(copy, before, len0));
	free(copy);
	assert_int_equal(dir_entries(p), 1);
	char *after = tu_read_file(db, &len1);
	assert_true(len1 == len0 && !memcmp(after, before, len0));
	free(after);
	free(before);
	/* A tally that fails (a study without answers) leaves no folder behind. */
	snprintf(q, sizeof q, "%s/empty.db", dir);
	sty *s = created(q);
	commit(s);
	sty_close(&s);
	snprintf(args, sizeof args, "study tally --db %s --out %s/none --bootstrap 10", q, dir);
	tu_expect_cli_error(args, "no answered test trials");
	snprintf(p, sizeof p, "%s/none", dir);
	assert_false(tu_file_exists(p));
	/* A full disk halfway through: none of the tables appear. */
	snprintf(p, sizeof p, "%s/full", dir);
	mkdir(p, 0755);
	snprintf(cmd, sizeof cmd, "mount -t tmpfs -o size=8k tmpfs %s 2>/dev/null", p);
	if (!tu_require(geteuid() == 0 && system(cmd) == 0,
			"test_outputs_not_inputs: a tally on a full disk (needs root to mount an 8 KiB tmpfs on %s)", p))
		return;
	snprintf(cmd, sizeof cmd, "%s study tally --db %s --out %s/t --bootstrap 10", TASLAB_BINARY, db, p);
	int st = tu_run(cmd, out, sizeof out);
	int entries = dir_entries(p);
	snprintf(cmd, sizeof cmd, "umount %s", p);
	assert_int_equal(system(cmd), 0);
	if (st == 0 || tu_count_lines(out) != 1 || !strstr(out, "No space"))
		fail_msg("tally on a full disk: exit %d, printed:\n%s", st, out);
	assert_int_equal(entries, 0);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_import_export), cmocka_unit_test(test_randomisation),
		cmocka_unit_test(test_server),     cmocka_unit_test(test_crash_safety),  cmocka_unit_test(test_cli),
		cmocka_unit_test(test_answer_strict), cmocka_unit_test(test_clips_blind), cmocka_unit_test(test_private_db_and_admin),
		cmocka_unit_test(test_range),      cmocka_unit_test(test_framing),       cmocka_unit_test(test_connection_limit),
		cmocka_unit_test(test_create_refuses), cmocka_unit_test(test_import_rules), cmocka_unit_test(test_export_formulas),
		cmocka_unit_test(test_links_served_url), cmocka_unit_test(test_serve_messages),
		cmocka_unit_test(test_period_conditions), cmocka_unit_test(test_design_period_rule),
		cmocka_unit_test(test_old_study_schema), cmocka_unit_test(test_outputs_not_inputs),
	};
	return tu_finish(cmocka_run_group_tests(tests, NULL, NULL));
}
