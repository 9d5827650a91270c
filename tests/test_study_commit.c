/* test_study_commit.c — the study server's group commit (study/src/study_commit.c, issue 32.3), white-box: a reply
 * never carries what a failed commit takes back.
 *
 * A trial's opaque clip names are made by the first GET /api/CODE/trial that shows it and committed with other
 * requests' writes. A second request for the same participant that arrives while that batch waits for its commit
 * finds the names and stores nothing itself; it used to reply at once, so when the commit then failed the page held
 * clip names that no longer existed. The test holds the study's lock as a writing request does, lets a concurrent
 * sty_next_trial queue behind it, stores the trial's clip names in the open batch, and makes SQLite's COMMIT fail
 * (sqlite3_commit_hook: a non-zero return turns the commit into a rollback, SQLite's documented behaviour). The
 * reader must then fail too, or return names that exist. With the commit succeeding, both succeed and the reader's
 * names are the stored ones. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "study_internal.h"
#include "taslab/study_serve.h"
#include "test_study_util.h"

static int fail_commits; /* how many of the next commits the hook fails */
static int commits_seen; /* commits the hook saw (it runs where SQLite commits) */

static int commit_delay_us; /* how long the hook holds each commit (the server stopping meanwhile) */

static void sleep_us(long us)
{
	struct timespec ts = {us / 1000000, us % 1000000 * 1000};
	nanosleep(&ts, NULL);
}

static int commit_hook(void *arg)
{
	(void)arg;
	__atomic_add_fetch(&commits_seen, 1, __ATOMIC_SEQ_CST);
	if (commit_delay_us)
		sleep_us(commit_delay_us);
	return fail_commits > 0 ? fail_commits--, 1 : 0;
}

typedef struct reader {
	sty *s;
	const char *code;
	sty_trial t;
	int rc;
	char err[1024];
} reader;

static void *read_trial(void *arg)
{
	reader *r = arg;
	r->rc = sty_next_trial(r->s, r->code, &r->t, r->err, sizeof r->err);
	return NULL;
}

/* The participant's id and its first unanswered trial (the one sty_next_trial shows). */
static void current_trial(sty *s, const char *code, long long *pid, long long *idx)
{
	sqlite3_stmt *st;
	assert_int_equal(sqlite3_prepare_v2(s->db,
					    "SELECT p.id, min(t.idx) FROM participants p JOIN trials t ON t.participant = p.id"
					    " WHERE p.code = ? AND NOT EXISTS (SELECT 1 FROM answers a"
					    " WHERE a.participant = t.participant AND a.idx = t.idx)",
					    -1, &st, NULL),
			 SQLITE_OK);
	sqlite3_bind_text(st, 1, code, -1, SQLITE_STATIC);
	assert_int_equal(sqlite3_step(st), SQLITE_ROW);
	*pid = sqlite3_column_int64(st, 0);
	*idx = sqlite3_column_int64(st, 1);
	sqlite3_finalize(st);
}

/* The clip name the test stores for slot `slot` in the round that fails (`fail`) or not: 32 hex digits, as the
 * server's, distinct from each other and from the server's random ones. */
static void name_of(int fail, int slot, char out[40])
{
	memset(out, fail ? 'f' : 'e', 31);
	snprintf(out + 31, 9, "%d.webm", slot);
}

/* One round: this thread, as a writing request, stores the clip names of `code`'s current trial in the open batch
 * while a concurrent sty_next_trial for `code` waits for the lock; then commits (failing when `fail`: that commit
 * alone). The reader gets in while this thread gathers the batch (up to 2 x 1 ms) if it is scheduled in time;
 * returns false when it was not (it then ran after the batch, made names of its own and committed them), so that
 * the caller can try again with another participant. */
static bool round_trip(sty *s, const char *code, int fail)
{
	char err[1024];
	long long pid, idx;
	current_trial(s, code, &pid, &idx);
	reader r = {.s = s, .code = code};
	pthread_t th;
	sty_batch_lock(s);
	assert_int_equal(pthread_create(&th, NULL, read_trial, &r), 0);
	/* until the reader waits for the lock (it announces itself first: the leader below gathers it into the batch) */
	for (int i = 0; i < 2000 && !__atomic_load_n(&s->batch.coming, __ATOMIC_SEQ_CST); i++)
		nanosleep(&(struct timespec){.tv_nsec = 1000 * 1000}, NULL);
	assert_int_not_equal(__atomic_load_n(&s->batch.coming, __ATOMIC_SEQ_CST), 0);
	nanosleep(&(struct timespec){.tv_nsec = 20 * 1000 * 1000}, NULL); /* ... and is blocked on it */
	assert_int_equal(sty_batch_join(s, err, sizeof err), TL_OK);
	char sql[256], a[40], b[40];
	name_of(fail, 0, a);
	name_of(fail, 1, b);
	snprintf(sql, sizeof sql,
		 "INSERT INTO clip_names(name, participant, idx, slot) VALUES('%s', %lld, %lld, 0), ('%s', %lld, %lld, 1)",
		 a, pid, idx, b, pid, idx);
	assert_int_equal(sqlite3_exec(s->db, sql, NULL, NULL, NULL), SQLITE_OK);
	fail_commits = fail;
	/* this request leads the batch: it lets the reader in (it is coming), then commits for both */
	int rc = sty_batch_leave(s, TL_OK, true, err, sizeof err);
	pthread_mutex_unlock(&s->lock);
	assert_int_equal(pthread_join(th, NULL), 0);
	fail_commits = 0;
	assert_int_equal(rc, fail ? TL_ERR_DB : TL_OK);
	if (fail) {
		/* the names were taken back: the reader must not have replied with them */
		char rel[4096], gone[40];
		name_of(1, 0, gone);
		if (r.rc == TL_OK && sty_clip_file(s, r.t.clip_a, rel, sizeof rel, err, sizeof err) != TL_OK)
			fail_msg("GET trial replied with clip name %s, which the failed commit took back", r.t.clip_a);
		if (r.rc == TL_OK) { /* it came after the batch: its own names, stored */
			assert_true(strcmp(r.t.clip_a, gone) && strcmp(r.t.clip_b, gone));
			return false;
		}
		assert_int_equal(r.rc, TL_ERR_DB); /* it read the batch and failed with it */
	} else {
		if (r.rc != TL_OK)
			fail_msg("%s", r.err);
		assert_int_equal(r.t.index, (uint32_t)idx);
		char want[40];
		name_of(0, 0, want);
		assert_true(!strcmp(r.t.clip_a, want) || !strcmp(r.t.clip_b, want)); /* the names the batch stored */
	}
	return true;
}

/* A study of 8 participants (design seed `seed`) from the four-set stimuli in a fresh folder `name`, and its codes. */
static sty *study_with_codes(const char *name, uint64_t seed, char ***codes, size_t *n)
{
	const char *dir = tu_tmpdir(name);
	char stim[4096], err[1024];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s = designed(dir, "s.db", seed, 8, &sm);
	assert_int_equal(sty_participant_codes(s, codes, n, err, sizeof err), TL_OK);
	return s;
}

static void test_reader_waits_for_the_batch(void **state)
{
	(void)state;
	char err[1024], **codes;
	size_t n;
	sty *s = study_with_codes("study_commit", 3, &codes, &n);
	sqlite3_commit_hook(s->db, commit_hook, NULL);
	/* the commit fails: the reader fails with it (a participant per try, until the reader got into the batch) */
	size_t used = 0;
	while (used + 1 < n && !round_trip(s, codes[used], 1))
		used++;
	if (used + 1 >= n)
		fail_msg("in %zu tries the reader never got into the batch while it was gathered", used);
	round_trip(s, codes[used + 1], 0); /* it succeeds: the reader shows the names the batch stored */
	/* after the failure nothing of it stayed: that participant's trial gets fresh names, once */
	sty_trial t;
	assert_int_equal(sty_next_trial(s, codes[used], &t, err, sizeof err), TL_OK);
	char rel[4096];
	assert_int_equal(sty_clip_file(s, t.clip_a, rel, sizeof rel, err, sizeof err), TL_OK);
	char gone[40];
	name_of(1, 0, gone);
	assert_int_not_equal(sty_clip_file(s, gone, rel, sizeof rel, err, sizeof err), TL_OK);
	sqlite3_commit_hook(s->db, NULL, NULL);
	free_codes(codes, n);
	sty_close(&s);
}

static int http(int port, const char *method, const char *path, const char *body, char *out, size_t size)
{
	int status = tu_http(port, method, path, NULL, body, out, size); /* the reply's body into out */
	assert_int_not_equal(status, -1);
	return status;
}

static char log_text[16384];
static void log_keep(void *cls, const char *line)
{
	(void)cls;
	size_t n = strlen(log_text);
	snprintf(log_text + n, sizeof log_text - n, "%s\n", line);
}

/* Issue 32.3: the server's replies wait for their commit without holding a thread (the committer thread commits,
 * the connection is suspended until then). Over HTTP, with one server thread: a commit that fails makes the
 * parked reply a 500 and stores nothing (the trial's clip names, an answer) and logs no answer; the next requests
 * succeed; every commit the server reports is one SQLite made (the hook counts them). */
static void test_parked_replies(void **state)
{
	(void)state;
	char err[1024], path[256], body[128], resp[8192], **codes;
	size_t n;
	sty *s = study_with_codes("study_commit_parked", 2, &codes, &n);
	sty_server *sv = NULL;
	sty_server_desc d = {.threads = 1, .log = log_keep};
	if (sty_server_start(s, &d, &sv, err, sizeof err))
		fail_msg("%s", err);
	sqlite3_commit_hook(s->db, commit_hook, NULL); /* after the start's own write (the served URL) */
	commits_seen = 0;
	int port = sty_server_port(sv);
	snprintf(path, sizeof path, "/api/%s/trial", codes[0]);
	fail_commits = 1; /* the trial's clip names are not stored: 500, and no names */
	assert_int_equal(http(port, "GET", path, "", resp, sizeof resp), 500);
	assert_null(strstr(resp, "clip_a"));
	if (!strstr(log_text, "a failed commit: its requests got 500"))
		fail_msg("the log has no line on the failed commit:\n%s", log_text);
	assert_int_equal(db_count(sty_path(s), "SELECT count(*) FROM clip_names"), 0);
	assert_int_equal(http(port, "GET", path, "", resp, sizeof resp), 200);
	assert_non_null(strstr(resp, "\"index\":0"));
	assert_int_equal(db_count(sty_path(s), "SELECT count(*) FROM clip_names"), 2);
	snprintf(path, sizeof path, "/api/%s/answer", codes[0]);
	snprintf(body, sizeof body, "{\"trial\": 0, \"answer\": 1, \"rt_ms\": 900}");
	fail_commits = 1; /* the answer is not stored: 500, and the trial is still to be answered */
	assert_int_equal(http(port, "POST", path, body, resp, sizeof resp), 500);
	assert_int_equal(db_count(sty_path(s), "SELECT count(*) FROM answers"), 0);
	if (strstr(log_text, "answered trial 0")) /* its log line waits for the commit, and goes with it */
		fail_msg("the log lists an answer that was not stored:\n%s", log_text);
	assert_int_equal(http(port, "POST", path, body, resp, sizeof resp), 200);
	assert_int_equal(db_count(sty_path(s), "SELECT count(*) FROM answers"), 1);
	assert_non_null(strstr(log_text, "answered trial 0 (1/"));
	snprintf(path, sizeof path, "/api/%s/session", codes[1]); /* a session's line waits for its commit too */
	fail_commits = 1;
	assert_int_equal(http(port, "POST", path, "{}", resp, sizeof resp), 500);
	if (strstr(log_text, "started a session"))
		fail_msg("the log lists a session that was not stored:\n%s", log_text);
	assert_int_equal(http(port, "POST", path, "{}", resp, sizeof resp), 200);
	assert_non_null(strstr(log_text, "started a session"));
	sty_server_stats st = sty_server_get_stats(sv);
	assert_int_equal(st.answers, 1);
	sty_server_stop(&sv);
	assert_int_equal(st.commits, (uint64_t)__atomic_load_n(&commits_seen, __ATOMIC_SEQ_CST));
	assert_true(st.commits >= 4);
	sqlite3_commit_hook(s->db, NULL, NULL);
	free_codes(codes, n);
	sty_close(&s);
}

typedef struct poster {
	int port, status;
	char path[256], resp[8192];
} poster;

static void *post_answer(void *arg)
{
	poster *p = arg;
	p->status = tu_http(p->port, "POST", p->path, "", "{\"trial\": 0, \"answer\": 2, \"rt_ms\": 700}", p->resp,
			     sizeof p->resp);
	return NULL;
}

/* The server stopped while a reply waits for its commit: the commit completes before the server stops, the answer
 * is stored and the log lists it, whether its reply still went out (here it does: the stop resumes the parked
 * connections before the daemon stops) or its connection closed with the reply held (on_completed). */
static void test_stop_with_a_parked_reply(void **state)
{
	(void)state;
	char err[1024], resp[8192], **codes;
	size_t n;
	sty *s = study_with_codes("study_commit_stop", 4, &codes, &n);
	sty_server *sv = NULL;
	log_text[0] = 0;
	sty_server_desc d = {.threads = 1, .log = log_keep};
	if (sty_server_start(s, &d, &sv, err, sizeof err))
		fail_msg("%s", err);
	poster p = {.port = sty_server_port(sv)};
	snprintf(p.path, sizeof p.path, "/api/%s/trial", codes[0]);
	assert_int_equal(http(p.port, "GET", p.path, "", resp, sizeof resp), 200);
	snprintf(p.path, sizeof p.path, "/api/%s/answer", codes[0]);
	int before = __atomic_load_n(&commits_seen, __ATOMIC_SEQ_CST);
	commit_delay_us = 300 * 1000;
	sqlite3_commit_hook(s->db, commit_hook, NULL);
	pthread_t th;
	assert_int_equal(pthread_create(&th, NULL, post_answer, &p), 0);
	for (int i = 0; i < 500 && __atomic_load_n(&commits_seen, __ATOMIC_SEQ_CST) == before; i++)
		sleep_us(10 * 1000); /* until the answer's commit is under way */
	assert_int_not_equal(__atomic_load_n(&commits_seen, __ATOMIC_SEQ_CST), before);
	sty_server_stop(&sv);
	pthread_join(th, NULL);
	commit_delay_us = 0;
	sqlite3_commit_hook(s->db, NULL, NULL);
	assert_int_equal(db_count(sty_path(s), "SELECT count(*) FROM answers"), 1);
	if (!strstr(log_text, "answered trial 0 (1/"))
		fail_msg("the stored answer is not in the log (its reply: HTTP %d):\n%s", p.status, log_text);
	free_codes(codes, n);
	sty_close(&s);
}

typedef struct participant {
	int port, failed;
	atomic_int requests, answered;
	atomic_int worst_us; /* the slowest request since it was last set to 0 */
	const char *code;
	atomic_int *stop;
} participant;

/* One request of a participant, timed: its status. */
static int timed(participant *p, const char *method, const char *path, const char *body, char *resp, size_t size)
{
	struct timespec t0, t1;
	clock_gettime(CLOCK_MONOTONIC, &t0);
	int status = tu_http(p->port, method, path, "", body, resp, size);
	clock_gettime(CLOCK_MONOTONIC, &t1);
	int us = (int)((t1.tv_sec - t0.tv_sec) * 1000000 + (t1.tv_nsec - t0.tv_nsec) / 1000);
	for (int w = atomic_load(&p->worst_us); us > w && !atomic_compare_exchange_weak(&p->worst_us, &w, us);)
		;
	if (status == 200)
		atomic_fetch_add(&p->requests, 1);
	else
		p->failed++;
	return status;
}

/* Answers its trials one after another (GET trial, POST answer); once done, asks for its trial again (a request
 * that takes the study's lock and finds it done) until told to stop. */
static void *participate(void *arg)
{
	participant *p = arg;
	char path[256], body[128], resp[8192];
	while (!atomic_load(p->stop)) {
		snprintf(path, sizeof path, "/api/%s/trial", p->code);
		if (timed(p, "GET", path, "", resp, sizeof resp) != 200)
			break;
		const char *idx = strstr(resp, "\"index\":");
		if (!idx) {
			sleep_us(5 * 1000);
			continue;
		}
		snprintf(path, sizeof path, "/api/%s/answer", p->code);
		snprintf(body, sizeof body, "{\"trial\": %d, \"answer\": 1, \"rt_ms\": 800}", atoi(idx + 8));
		if (timed(p, "POST", path, body, resp, sizeof resp) != 200)
			break;
		atomic_fetch_add(&p->answered, 1);
	}
	return NULL;
}

typedef struct reader_done {
	reader r;
	atomic_int done;
} reader_done;

static void *read_trial_flagged(void *arg)
{
	reader_done *d = arg;
	read_trial(&d->r);
	atomic_store(&d->done, 1);
	return NULL;
}

/* sty_batch_quiesce's promise, step by step: while a reader waits for a moment with no batch open (draining), a
 * request that would open a new batch waits, and goes on once the reader is done. */
static void test_no_batch_opens_while_draining(void **state)
{
	(void)state;
	char **codes;
	size_t n;
	sty *s = study_with_codes("study_commit_drain", 6, &codes, &n);
	pthread_mutex_lock(&s->lock);
	s->batch.draining = 1; /* as sty_batch_quiesce sets it while it waits */
	pthread_mutex_unlock(&s->lock);
	reader_done d = {.r = {.s = s, .code = codes[0]}};
	pthread_t th;
	assert_int_equal(pthread_create(&th, NULL, read_trial_flagged, &d), 0);
	sleep_us(200 * 1000);
	if (atomic_load(&d.done))
		fail_msg("a request opened a batch while a reader waited for none to be open");
	pthread_mutex_lock(&s->lock);
	assert_false(s->batch.open);
	s->batch.draining = 0; /* the reader has read: as sty_batch_quiesce ends */
	pthread_cond_broadcast(&s->batch.done);
	pthread_mutex_unlock(&s->lock);
	pthread_join(th, NULL);
	if (d.r.rc)
		fail_msg("%s", d.r.err);
	free_codes(codes, n);
	sty_close(&s);
}

/* SQLite may roll an open transaction back on its own (after SQLITE_FULL, IOERR, NOMEM) while the batch thinks it
 * is open: a request joining then fails instead of starting a transaction of its own (which its RELEASE would commit
 * outside the batch). Simulated with a ROLLBACK of the batch's transaction. */
static void test_join_after_sqlite_rolled_back(void **state)
{
	(void)state;
	char err[1024], **codes;
	size_t n;
	sty *s = study_with_codes("study_commit_rolled", 7, &codes, &n);
	pthread_mutex_lock(&s->lock);
	assert_int_equal(sty_batch_join(s, err, sizeof err), TL_OK);
	assert_int_equal(sty_exec(s, "RELEASE request"), SQLITE_OK);
	s->batch.members = 1; /* a member waits for this batch */
	assert_int_equal(sty_exec(s, "ROLLBACK"), SQLITE_OK); /* as SQLite does on its own after an I/O error */
	assert_int_equal(sty_batch_join(s, err, sizeof err), TL_ERR_DB);
	assert_non_null(strstr(err, "rolled back"));
	assert_int_equal(sqlite3_get_autocommit(s->db), 1); /* no transaction of its own */
	s->batch.members = 0, s->batch.open = false;
	pthread_mutex_unlock(&s->lock);
	sty_trial tr;
	assert_int_equal(sty_next_trial(s, codes[0], &tr, err, sizeof err), TL_OK);
	free_codes(codes, n);
	sty_close(&s);
}

static int requests_so_far(participant *ps, int n)
{
	int a = 0;
	for (int i = 0; i < n; i++)
		a += atomic_load(&ps[i].requests);
	return a;
}

/* Reads of committed data while participants answer without a pause and every commit takes 20 ms. The export waits
 * for a moment with no batch open, and meanwhile requests may join the open batch but open no new one, so a steady
 * stream of answers cannot keep it waiting (before, 2026-11-28: a woken export found the next batch open again, as
 * long as answers came). The status reads on a connection of its own, holds no lock of the server's and runs on a
 * thread of its own while its tally computes, so participants go on answering meanwhile, also with one server
 * thread (before: none could, for the whole tally; and on a server thread, its keep-alive connections stalled). */
static void test_reads_under_load(void **state)
{
	(void)state;
	char err[1024], resp[65536], **codes, auth[128];
	size_t n;
	sty *s = study_with_codes("study_commit_reads", 5, &codes, &n);
	for (size_t k = 6; k < n; k++) { /* two participants done before: a status with something to tally, for seconds */
		sty_trial tr;
		while (sty_next_trial(s, codes[k], &tr, err, sizeof err) == TL_OK && !tr.done)
			assert_int_equal(sty_answer(s, codes[k], tr.index, 1, 800, err, sizeof err), TL_OK);
	}
	sty_server *sv = NULL;
	log_text[0] = 0;
	sty_server_desc d = {.threads = 1, .log = log_keep}; /* one server thread: the status must not take it */
	if (sty_server_start(s, &d, &sv, err, sizeof err))
		fail_msg("%s", err);
	int port = sty_server_port(sv);
	snprintf(auth, sizeof auth, "Authorization: Bearer %s\r\n", sty_admin_token(s));
	commit_delay_us = 20 * 1000;
	sqlite3_commit_hook(s->db, commit_hook, NULL);
	atomic_int stop = 0;
	enum { P = 6 };
	participant ps[P];
	pthread_t th[P];
	for (int i = 0; i < P; i++) {
		ps[i] = (participant){.port = port, .code = codes[i], .stop = &stop};
		assert_int_equal(pthread_create(&th[i], NULL, participate, &ps[i]), 0);
	}
	sleep_us(200 * 1000); /* all answering */
	double export_worst = 0, status_took[2] = {0, 0}, request_worst[2] = {0, 0};
	int during_status[2] = {0, 0};
	for (int k = 0; k < 4; k++) {
		bool status = k % 2;
		struct timespec t0, t1;
		int before = requests_so_far(ps, P);
		for (int i = 0; i < P; i++)
			atomic_store(&ps[i].worst_us, 0);
		clock_gettime(CLOCK_MONOTONIC, &t0);
		assert_int_equal(tu_http(port, "GET", status ? "/admin/status" : "/admin/export.csv", auth, "", resp,
					  sizeof resp), 200);
		clock_gettime(CLOCK_MONOTONIC, &t1);
		double took = (double)(t1.tv_sec - t0.tv_sec) + (double)(t1.tv_nsec - t0.tv_nsec) / 1e9;
		if (status) {
			status_took[k / 2] = took, during_status[k / 2] = requests_so_far(ps, P) - before;
			for (int i = 0; i < P; i++)
				request_worst[k / 2] = fmax(request_worst[k / 2], atomic_load(&ps[i].worst_us) / 1e6);
		} else {
			export_worst = took > export_worst ? took : export_worst;
		}
	}
	int answered = 0;
	for (int i = 0; i < P; i++)
		answered += atomic_load(&ps[i].answered);
	atomic_store(&stop, 1);
	for (int i = 0; i < P; i++)
		pthread_join(th[i], NULL);
	sty_server_stop(&sv);
	commit_delay_us = 0;
	sqlite3_commit_hook(s->db, NULL, NULL);
	for (int i = 0; i < P; i++)
		assert_int_equal(ps[i].failed, 0);
	fprintf(stderr, "reads under load: exports within %.3f s; status reads %.3f s and %.3f s, %d and %d requests "
			"answered meanwhile, the slowest within %.3f s and %.3f s; %d answers stored\n", export_worst,
		status_took[0], status_took[1], during_status[0], during_status[1], request_worst[0], request_worst[1],
		answered);
	assert_true(answered > 0);
	if (export_worst > 1.0)
		fail_msg("an export waited %.3f s while participants answered", export_worst);
	for (int k = 0; k < 2; k++) /* a request waiting for the status's lock would wait about as long as the status */
		if (status_took[k] > 0.3 && (during_status[k] == 0 || request_worst[k] > 0.4 * status_took[k]))
			fail_msg("a request waited %.3f s during a status read of %.3f s (%d answered meanwhile)", request_worst[k],
				 status_took[k], during_status[k]);
	free_codes(codes, n);
	sty_close(&s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_reader_waits_for_the_batch),
		cmocka_unit_test(test_parked_replies),
		cmocka_unit_test(test_stop_with_a_parked_reply),
		cmocka_unit_test(test_reads_under_load),
		cmocka_unit_test(test_no_batch_opens_while_draining),
		cmocka_unit_test(test_join_after_sqlite_rolled_back),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
