/* test_study_http.c — the study server against hostile HTTP clients on loopback (issue 31; test_study.c has the
 * rest of the server):
 *  - slow clients (31.3): 300 connections from 10 loopback addresses (under the per-address cap), each trickling
 *    one header byte a second and reconnecting when closed, while a participant's requests must each be answered
 *    within a second; a trickled head or body is closed at its deadline (test_slow_clients); a clip read a few
 *    bytes at a time is reset at the send deadline (test_slow_reader);
 *  - one address (32.3): a lab of 120 participants behind one address is served; one client holding 300 unfinished
 *    requests from that address, or 300 idle connections (nothing sent), does not stop another request
 *    (test_one_address);
 *  - framing (31.9): request bodies with a Transfer-Encoding (another coding, chunked not last, chunked with a chunk
 *    size of 2^64-1) are refused at their head with one status line, at once (test_hostile_framing).
 * Every client here binds an address of 127.0.0.0/8; counts and times are bounded, and the test stops by itself. */
#define _DEFAULT_SOURCE /* usleep */
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "taslab/study.h"
#include "taslab/study_serve.h"
#include "test_study_methods.h"
#include "test_util.h"

static double now_s(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

/* A designed study of one participant over a minimal stimulus folder (one set: ref and one condition). */
static sty *study_of_one(const char *dir, char *code, size_t code_size)
{
	char p[4096], err[1024];
	snprintf(p, sizeof p, "mkdir -p %s/stimuli/calm-walk/clips", dir);
	assert_int_equal(system(p), 0);
	const char *clips[2] = {"ref", "tfr-T8"};
	for (int c = 0; c < 2; c++) {
		snprintf(p, sizeof p, "%s/stimuli/calm-walk/clips/%s.webm", dir, clips[c]);
		FILE *f = fopen(p, "w");
		assert_non_null(f);
		fprintf(f, "clip %s", clips[c]);
		fclose(f);
	}
	snprintf(p, sizeof p, "%s/stimuli/calm-walk/pairs.json", dir);
	FILE *f = fopen(p, "w");
	assert_non_null(f);
	fputs("{\"taslab_pairs\": 1, \"scene\": \"calm\", \"camera\": \"walk\", \"camera_motion\": \"moving\", \"fps\": 60,"
	      " \"frames\": [0, 59], \"reference\": {\"clip\": \"clips/ref.webm\"}, \"conditions\": ["
	      "{\"method\": \"tfr\", \"T\": 8, \"clip\": \"clips/tfr-T8.webm\"}]}",
	      f);
	fclose(f);
	char db[4096], stim[4096];
	snprintf(db, sizeof db, "%s/s.db", dir);
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	sty *s = NULL;
	sty_design_desc d = {.stimuli = stim, .participants = 1, .seed = 1, .training = 1, .catch_trials = 0};
	sty_design_summary sm;
	if (sty_create(db, &s, err, sizeof err) || tu_describe_methods(s) || sty_design(s, &d, &sm, err, sizeof err) ||
	    sty_commit(s, err, sizeof err))
		fail_msg("%s", err);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	assert_int_equal(n, 1);
	snprintf(code, code_size, "%s", codes[0]);
	free(codes[0]);
	free(codes);
	return s;
}

/* A connection to 127.0.0.1:port from `from` (a 127.0.0.0/8 address; NULL: 127.0.0.1), or -1. */
static int connect_from(int port, const char *from)
{
	int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)}, src = {.sin_family = AF_INET};
	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	if (fd >= 0 && from) {
		inet_pton(AF_INET, from, &src.sin_addr);
		if (bind(fd, (struct sockaddr *)&src, sizeof src)) {
			close(fd);
			return -1;
		}
	}
	if (fd >= 0 && connect(fd, (struct sockaddr *)&sa, sizeof sa)) {
		close(fd);
		return -1;
	}
	return fd;
}

/* Sends `req` and reads the whole response within `limit_s` seconds; the status (-1: none in time), the response in
 * resp (NUL-terminated). */
static int request_within(int port, const char *req, size_t len, double limit_s, char *resp, size_t resp_size)
{
	double t0 = now_s();
	int fd = connect_from(port, NULL);
	resp[0] = 0;
	if (fd < 0 || send(fd, req, len, MSG_NOSIGNAL) != (ssize_t)len) {
		if (fd >= 0)
			close(fd);
		return -1;
	}
	size_t got = 0;
	for (;;) {
		int left_ms = (int)((t0 + limit_s - now_s()) * 1000);
		struct pollfd p = {.fd = fd, .events = POLLIN};
		if (left_ms <= 0 || poll(&p, 1, left_ms) != 1)
			break;
		ssize_t r = read(fd, resp + got, resp_size - 1 - got);
		if (r <= 0)
			break;
		got += (size_t)r;
		if (got + 1 >= resp_size)
			break;
	}
	close(fd);
	resp[got] = 0;
	int status = -1;
	if (sscanf(resp, "HTTP/1.%*d %d", &status) != 1)
		status = -1;
	return status;
}

/* ------------------------------------------------------------------ slow clients */

enum { SLOW_ADDRS = 10, SLOW_PER_ADDR = 30, SLOW_N = SLOW_ADDRS * SLOW_PER_ADDR, SLOW_RECONNECTS = 20 * SLOW_N };

typedef struct trickle {
	int port;
	atomic_int stop; /* set by the test thread, read by the trickler */
	int fd[SLOW_N];
	size_t sent[SLOW_N];
	unsigned closed, reconnects, connect_failures;
} trickle;

static const char SLOW_HEAD[] = "GET /api/00000000000000000000000000000000/trial HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: "
				"aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa";

static void trickle_connect(trickle *t, int i)
{
	char from[32];
	snprintf(from, sizeof from, "127.0.0.%d", 2 + i / SLOW_PER_ADDR);
	t->fd[i] = connect_from(t->port, from);
	t->sent[i] = 0;
	if (t->fd[i] < 0)
		t->connect_failures++;
}

/* Each connection sends one byte of a head that never ends every second; a connection the server closed is opened
 * again at the next second (at most SLOW_RECONNECTS in all), as a determined attacker would. */
static void *trickle_main(void *arg)
{
	trickle *t = arg;
	for (int i = 0; i < SLOW_N; i++)
		trickle_connect(t, i);
	double next_byte = now_s();
	while (!t->stop) {
		int second = now_s() >= next_byte;
		if (second)
			next_byte += 1.0;
		for (int i = 0; i < SLOW_N && !t->stop; i++) {
			if (t->fd[i] < 0) {
				if (second && t->reconnects < SLOW_RECONNECTS)
					t->reconnects++, trickle_connect(t, i);
				continue;
			}
			struct pollfd p = {.fd = t->fd[i], .events = POLLIN};
			char c[256];
			int gone = poll(&p, 1, 0) == 1 && read(t->fd[i], c, sizeof c) <= 0;
			if (!gone && second && t->sent[i] + 1 < sizeof SLOW_HEAD)
				gone = send(t->fd[i], SLOW_HEAD + t->sent[i]++, 1, MSG_NOSIGNAL) != 1;
			if (gone) {
				close(t->fd[i]);
				t->fd[i] = -1;
				t->closed++;
			}
		}
		usleep(50 * 1000);
	}
	for (int i = 0; i < SLOW_N; i++)
		if (t->fd[i] >= 0)
			close(t->fd[i]);
	return NULL;
}

static void log_quiet(void *cls, const char *line)
{
	(void)cls;
	(void)line;
}

/* Issue 31.3. With the limits of then (256 connections, 32 per address, head and body deadlines of 10 s), 300
 * trickling connections from 127.0.0.2..11 used to take every slot: the participant's requests timed out for as
 * long as they trickled (the idle timeout never fires on a byte a second). Now the connections still reading a
 * request are capped (128 = half the connections; the one reading longest is closed to make room), so the
 * participant is answered within a second, every time, for the 6 s the attack lasts. Then, with deadlines of 2 s: a
 * head trickled a byte a second and a body trickled after its head are each closed at their deadline (between 2 and
 * 4 s: the watchdog looks four times a second), counted by the server. */
static void test_slow_clients(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_slow");
	char code[64], req[512], resp[8192];
	sty *s = study_of_one(dir, code, sizeof code);
	char err[1024];
	sty_server *sv = NULL;
	sty_server_desc d = {.threads = 2, .max_connections = 256, .log = log_quiet};
	if (sty_server_start(s, &d, &sv, err, sizeof err))
		fail_msg("%s", err);
	int port = sty_server_port(sv);
	int len = snprintf(req, sizeof req, "GET /api/%s/trial HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n", code);
	assert_int_equal(request_within(port, req, (size_t)len, 1.0, resp, sizeof resp), 200);

	trickle *t = calloc(1, sizeof *t);
	assert_non_null(t);
	t->port = port;
	pthread_t th;
	assert_int_equal(pthread_create(&th, NULL, trickle_main, t), 0);
	usleep(1500 * 1000); /* all 300 connected and trickling */
	double t_end = now_s() + 6.0, worst = 0;
	int asked = 0, late = 0;
	while (now_s() < t_end) {
		double t0 = now_s();
		int st = request_within(port, req, (size_t)len, 1.0, resp, sizeof resp);
		double took = now_s() - t0;
		worst = took > worst ? took : worst;
		asked++;
		if (st != 200)
			late++;
		usleep(300 * 1000);
	}
	t->stop = 1;
	pthread_join(th, NULL);
	sty_server_stats st = sty_server_get_stats(sv);
	fprintf(stderr, "slow clients: %d participant requests, %d not answered within 1 s (worst %.3f s); %u trickling "
			"connections closed by the server, %u reopened, %u connects failed; server: %llu evicted\n",
		asked, late, worst, t->closed, t->reconnects, t->connect_failures, (unsigned long long)st.evicted);
	unsigned closed = t->closed;
	free(t);
	if (late)
		fail_msg("%d of %d participant requests were not answered within a second while slow clients trickled", late,
			 asked);
	assert_true(asked >= 10);
	assert_true(st.evicted > 0 && st.evicted <= closed); /* the cap is what made room */
	sty_server_stop(&sv);

	/* the deadlines */
	d.head_timeout_s = 2;
	d.body_timeout_s = 2;
	if (sty_server_start(s, &d, &sv, err, sizeof err))
		fail_msg("%s", err);
	port = sty_server_port(sv);
	int head = connect_from(port, NULL), body = connect_from(port, NULL);
	assert_true(head >= 0 && body >= 0);
	char post[512];
	int plen = snprintf(post, sizeof post, "POST /api/%s/answer HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 100\r\n\r\n{",
			    code);
	assert_int_equal(send(body, post, (size_t)plen, MSG_NOSIGNAL), plen);
	double t0 = now_s(), head_closed = 0, body_closed = 0;
	size_t sent = 0;
	while ((!head_closed || !body_closed) && now_s() - t0 < 8.0) {
		char c[4096];
		struct pollfd p[2] = {{.fd = head, .events = POLLIN}, {.fd = body, .events = POLLIN}};
		poll(p, 2, 100);
		if (!head_closed && (p[0].revents && read(head, c, sizeof c) <= 0))
			head_closed = now_s() - t0;
		if (!body_closed && (p[1].revents && read(body, c, sizeof c) <= 0))
			body_closed = now_s() - t0;
		if (now_s() - t0 >= (double)sent) { /* a byte a second on each */
			if (!head_closed)
				send(head, SLOW_HEAD + sent, 1, MSG_NOSIGNAL);
			if (!body_closed)
				send(body, " ", 1, MSG_NOSIGNAL);
			sent++;
		}
	}
	close(head);
	close(body);
	st = sty_server_get_stats(sv);
	fprintf(stderr, "deadlines of 2 s: trickled head closed after %.2f s, trickled body after %.2f s; server: %llu head, "
			"%llu body timeouts\n",
		head_closed, body_closed, (unsigned long long)st.head_timeouts, (unsigned long long)st.body_timeouts);
	/* the server's 2 s run from its accept, the client's clock from just after its connect returned: a close
	 * measured a few ms under 2 s (seen: 2.00 printed, the assertion failing under load) is still the deadline */
	assert_true(head_closed >= 1.9 && head_closed < 4.0);
	assert_true(body_closed >= 1.9 && body_closed < 4.0);
	assert_int_equal(st.head_timeouts, 1);
	assert_int_equal(st.body_timeouts, 1);
	/* and an ordinary participant still gets an answer */
	assert_int_equal(request_within(port, req, (size_t)len, 1.0, resp, sizeof resp), 200);
	sty_server_stop(&sv);
	sty_close(&s);
}

/* A reply read a few bytes at a time (a clip, issue 32.3's "slow /clips readers"): every read resets libmicrohttpd's
 * idle timeout, so such a client held its connection for as long as it liked. With a send deadline of 2 s the server
 * closes it 2 s after the request (+ up to 0.25 s: the watchdog looks four times a second; + the few KiB the client
 * had queued), long before the 64 MiB clip is through, and counts it; an ordinary request is still answered. With
 * the deadline left out (the code before), the client reads on for the whole 8 s the test waits. */
static void test_slow_reader(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_slow_reader");
	char code[64], req[512], resp[8192], err[1024], p[4096];
	sty *s = study_of_one(dir, code, sizeof code);
	const char *clips[2] = {"ref", "tfr-T8"};
	for (int c = 0; c < 2; c++) { /* 64 MiB each (sparse): far more than the socket buffers hold */
		snprintf(p, sizeof p, "%s/stimuli/calm-walk/clips/%s.webm", dir, clips[c]);
		assert_int_equal(truncate(p, 64 << 20), 0);
	}
	sty_server *sv = NULL;
	sty_server_desc d = {.threads = 2, .send_timeout_s = 2, .log = log_quiet};
	if (sty_server_start(s, &d, &sv, err, sizeof err))
		fail_msg("%s", err);
	int port = sty_server_port(sv);
	int len = snprintf(req, sizeof req, "GET /api/%s/trial HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n", code);
	assert_int_equal(request_within(port, req, (size_t)len, 5.0, resp, sizeof resp), 200);
	char clip[128];
	const char *at = strstr(resp, "\"clip_a\":");
	assert_non_null(at);
	assert_int_equal(sscanf(at, "\"clip_a\":\"%127[^\"]\"", clip), 1);
	int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
	int small = 4096; /* a small receive window, set before connecting */
	setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	assert_int_equal(connect(fd, (struct sockaddr *)&sa, sizeof sa), 0);
	char get[256];
	int glen = snprintf(get, sizeof get, "GET %s HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", clip);
	double t0 = now_s(), closed = 0;
	assert_int_equal(send(fd, get, (size_t)glen, MSG_NOSIGNAL), glen);
	size_t got = 0;
	while (!closed && now_s() - t0 < 8.0) { /* 256 bytes every 50 ms: 5 KiB/s, a 64 MiB clip in 3.6 hours */
		char buf[256];
		ssize_t r = read(fd, buf, sizeof buf);
		if (r <= 0)
			closed = now_s() - t0;
		else
			got += (size_t)r;
		usleep(50 * 1000);
	}
	close(fd);
	sty_server_stats st = sty_server_get_stats(sv);
	fprintf(stderr, "send deadline of 2 s: a reader of 5 KiB/s closed after %.2f s (%zu bytes read); server: %llu send "
			"timeouts\n", closed, got, (unsigned long long)st.send_timeouts);
	if (!closed)
		fail_msg("a clip read at 5 KiB/s kept its connection for 8 s (%zu bytes read) with a send deadline of 2 s", got);
	assert_true(closed >= 1.9 && closed < 6.0); /* + the watchdog's 0.25 s, + what the client had queued */
	assert_true(got > 0 && got < (size_t)(64 << 20));
	assert_int_equal(st.send_timeouts, 1);
	assert_int_equal(request_within(port, req, (size_t)len, 1.0, resp, sizeof resp), 200);
	sty_server_stop(&sv);
	sty_close(&s);
}

/* ------------------------------------------------------------------ one address (issue 32.3) */

/* A lab behind one NAT or reverse proxy is one client address: 120 participants' connections from 127.0.0.1, each
 * with a request in flight at once, are all answered (the per-address cap of then, 32, refused 88 of them). And one
 * client among them holding hundreds of connections that never finish a request does not stop the others: with
 * 64 connections in all (32 may be reading a request), 300 such connections from the same address do not keep a
 * participant's request from being answered within a second — the one reading longest is closed to make room. */
static void test_one_address(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_one_address");
	char code[64], req[512], resp[8192], err[1024];
	sty *s = study_of_one(dir, code, sizeof code);
	sty_server *sv = NULL;
	sty_server_desc d = {.threads = 2, .log = log_quiet}; /* the defaults: no per-address cap */
	if (sty_server_start(s, &d, &sv, err, sizeof err))
		fail_msg("%s", err);
	int port = sty_server_port(sv);
	int len = snprintf(req, sizeof req, "GET /api/%s/trial HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", code);
	enum { LAB = 120, HOG = 300 };
	int fds[HOG];
	for (int i = 0; i < LAB; i++) {
		assert_true((fds[i] = connect_from(port, NULL)) >= 0);
		assert_int_equal(send(fds[i], req, (size_t)len, MSG_NOSIGNAL), len);
	}
	int answered = 0;
	for (int i = 0; i < LAB; i++) {
		struct pollfd p = {.fd = fds[i], .events = POLLIN};
		ssize_t n = poll(&p, 1, 5000) == 1 ? recv(fds[i], resp, sizeof resp - 1, 0) : -1;
		if (n > 12 && !strncmp(resp, "HTTP/1.1 200", 12))
			answered++;
		close(fds[i]);
	}
	if (answered != LAB)
		fail_msg("%d of %d participants behind one address were answered", answered, LAB);
	sty_server_stop(&sv);

	d.max_connections = 64;
	if (sty_server_start(s, &d, &sv, err, sizeof err))
		fail_msg("%s", err);
	port = sty_server_port(sv);
	for (int i = 0; i < HOG; i++) {
		assert_true((fds[i] = connect_from(port, NULL)) >= 0);
		send(fds[i], SLOW_HEAD, 20, MSG_NOSIGNAL); /* a head that never ends (the server may close it at once) */
	}
	len = snprintf(req, sizeof req, "GET /api/%s/trial HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n", code);
	for (int k = 0; k < 5; k++) {
		int st = request_within(port, req, (size_t)len, 1.0, resp, sizeof resp);
		if (st != 200)
			fail_msg("request %d from the hog's address: %d within 1 s, expected 200", k, st);
	}
	sty_server_stats st = sty_server_get_stats(sv);
	assert_true(st.evicted > 0); /* the reading cap made the room */
	for (int i = 0; i < HOG; i++)
		close(fds[i]);
	/* idle connections (issue 32.3's wording): the hog connects HOG times and sends nothing at all */
	for (int i = 0; i < HOG; i++)
		assert_true((fds[i] = connect_from(port, NULL)) >= 0);
	for (int k = 0; k < 5; k++) {
		int code_k = request_within(port, req, (size_t)len, 1.0, resp, sizeof resp);
		if (code_k != 200)
			fail_msg("request %d beside %d idle connections from its address: %d within 1 s, expected 200", k, HOG,
				 code_k);
	}
	for (int i = 0; i < HOG; i++)
		close(fds[i]);
	sty_server_stop(&sv);
	sty_close(&s);
}

/* Occurrences of `needle` in `s`. */
static int count_of(const char *s, const char *needle)
{
	int n = 0;
	for (const char *p = s; (p = strstr(p, needle)); p += strlen(needle))
		n++;
	return n;
}

/* Issue 31.9: request bodies with a Transfer-Encoding are refused at their head, at once and with one status line:
 * a coding other than chunked (libmicrohttpd read such a body until the connection closed: no answer), chunked not
 * last, and chunked itself, whatever chunk size follows (2^64-1 was read for ever). Nothing is stored. */
static void test_hostile_framing(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_hostile_framing");
	char code[64], req[1024], resp[8192], err[1024];
	sty *s = study_of_one(dir, code, sizeof code);
	sty_server *sv = NULL;
	sty_server_desc d = {.threads = 2, .log = log_quiet};
	if (sty_server_start(s, &d, &sv, err, sizeof err))
		fail_msg("%s", err);
	int port = sty_server_port(sv);
	static const struct {
		const char *head, *body;
		int status;
	} cases[] = {
		{"Transfer-Encoding: gzip, chunked\r\n", "5\r\nhello\r\n0\r\n\r\n", 501},
		{"Transfer-Encoding: gzip\r\nTransfer-Encoding: chunked\r\n", "5\r\nhello\r\n0\r\n\r\n", 501},
		{"Transfer-Encoding: chunked, gzip\r\n", "5\r\nhello\r\n0\r\n\r\n", 400},
		{"Transfer-Encoding: identity\r\n", "{}", 400},
		{"Transfer-Encoding: chunked\r\n", "ffffffffffffffff\r\nabc", 411},
		{"Transfer-Encoding: chunked\r\n", "10000000000000000\r\nabc", 411},
		{"Transfer-Encoding: CHUNKED\r\n", "21\r\n{\"trial\":0,\"answer\":1,\"rt_ms\":5}\r\n0\r\n\r\n", 411},
	};
	for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
		int len = snprintf(req, sizeof req, "POST /api/%s/answer HTTP/1.1\r\nHost: 127.0.0.1\r\n%s\r\n%s", code,
				   cases[i].head, cases[i].body);
		double t0 = now_s();
		int st = request_within(port, req, (size_t)len, 2.0, resp, sizeof resp);
		double took = now_s() - t0;
		if (st != cases[i].status || count_of(resp, "HTTP/1.1 ") != 1 || took > 1.0)
			fail_msg("case %zu (%s): status %d in %.2f s, expected %d at once with one status line:\n%s", i,
				 cases[i].head, st, took, cases[i].status, resp);
		assert_non_null(strstr(resp, "{\"error\":"));
	}
	/* nothing was stored: the participant is still at trial 0 with no answers */
	int len = snprintf(req, sizeof req, "GET /api/%s/trial HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n", code);
	assert_int_equal(request_within(port, req, (size_t)len, 2.0, resp, sizeof resp), 200);
	assert_non_null(strstr(resp, "\"answered\":0"));
	/* the server's count and time of acknowledged answers (issue 32.3): none of the refused ones; then one answer,
	 * timed to within the histogram's 9 % of what the client waited for it */
	sty_server_stats st = sty_server_get_stats(sv);
	assert_int_equal(st.answers, 0);
	const char *body = "{\"trial\": 0, \"answer\": 1, \"rt_ms\": 5}";
	len = snprintf(req, sizeof req, "POST /api/%s/answer HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: %zu\r\n"
		       "Connection: close\r\n\r\n%s", code, strlen(body), body);
	double t0 = now_s();
	assert_int_equal(request_within(port, req, (size_t)len, 2.0, resp, sizeof resp), 200);
	double waited_ms = (now_s() - t0) * 1e3;
	st = sty_server_get_stats(sv);
	assert_int_equal(st.answers, 1);
	if (!(st.answer_ms_p50 > 0 && st.answer_ms_p50 == st.answer_ms_p99 && st.answer_ms_p99 <= waited_ms * 1.1))
		fail_msg("one answer: server time p50 %.3f ms, p99 %.3f ms; the client waited %.3f ms", st.answer_ms_p50,
			 st.answer_ms_p99, waited_ms);
	sty_server_stop(&sv);
	sty_close(&s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_slow_clients),
		cmocka_unit_test(test_slow_reader),
		cmocka_unit_test(test_one_address),
		cmocka_unit_test(test_hostile_framing),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
