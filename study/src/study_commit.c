/* study_commit.c — group commit of the study server's writes (issue 32.3).
 *
 * An answer is acknowledged only when it is on disk (WAL, synchronous=FULL: one fsync of the log per commit). On
 * the 2-core test machine an fsync costs about 4 ms, so with one commit per answer the server topped out near 250
 * answers per second and 50 concurrent participants queued behind each other's fsyncs (p99 102 ms). Here the writes
 * of concurrent requests share one transaction and one fsync: each request joins the open batch (BEGIN IMMEDIATE
 * when none is open), makes its change inside a savepoint (undone alone if it fails), and waits until a commit that
 * includes it has finished. The first waiter that finds no commit under way leads: it waits up to a millisecond or
 * two while other requests are still on their way into the batch, then commits for everybody and wakes them with
 * the batch's result. A failed commit rolls the whole batch back and every member reports the failure: nothing is
 * acknowledged that is not on disk.
 *
 * SQLite allows one writer, so a commit cannot overlap the next batch's writes anyway; the leader keeps s->lock
 * through the COMMIT, and the requests that arrive meanwhile form the next batch.
 *
 * The server runs a committer thread instead of leaders (sty_batch_committer_start, 2026-11-28): a waiting request
 * held its server thread, so a batch had at most one request per thread (about three on average with four
 * threads). Now a request handled on a deferring thread stores its change, takes the batch's epoch as a ticket and
 * returns; the server suspends its connection, and the committer commits each batch and reports it, which resumes
 * the batch's connections with their replies (or a 500 when the commit failed). Other callers (commands, tests, a
 * request handled with no deferral) still wait for their commit, which the committer then makes. */
#include <errno.h>
#include <time.h>

#include "study_internal.h"

enum { GATHER_ROUNDS = 2, GATHER_NS = 1000 * 1000 }; /* the leader waits at most 2 x 1 ms for requests on their way */

void sty_batch_init(sty *s)
{
	pthread_cond_init(&s->batch.joined, NULL);
	pthread_cond_init(&s->batch.done, NULL);
	pthread_cond_init(&s->batch.work, NULL);
}

void sty_batch_destroy(sty *s)
{
	pthread_cond_destroy(&s->batch.joined);
	pthread_cond_destroy(&s->batch.done);
	pthread_cond_destroy(&s->batch.work);
}

/* The deferral state of this thread (sty_batch_defer_begin / _end). */
static __thread struct {
	bool on, taken;
	uint64_t ticket;
} defer;

void sty_batch_defer_begin(void)
{
	defer.on = true;
	defer.taken = false;
}

bool sty_batch_defer_end(uint64_t *ticket)
{
	defer.on = false;
	*ticket = defer.ticket;
	return defer.taken;
}

void sty_batch_lock(sty *s)
{
	__atomic_add_fetch(&s->batch.coming, 1, __ATOMIC_SEQ_CST); /* a leader gathering the batch waits for it */
	pthread_mutex_lock(&s->lock);
	__atomic_sub_fetch(&s->batch.coming, 1, __ATOMIC_SEQ_CST);
	pthread_cond_signal(&s->batch.joined);
}

int sty_batch_join(sty *s, char *err, size_t err_size)
{
	while (!s->batch.open && s->batch.draining) /* a reader waits for a moment with no batch: it reads first */
		pthread_cond_wait(&s->batch.done, &s->lock);
	if (s->batch.open && sqlite3_get_autocommit(s->db)) {
		/* SQLite rolled the batch's transaction back on its own (after SQLITE_FULL, IOERR, NOMEM): a savepoint now
		 * would start a transaction of its own, which its RELEASE commits outside the batch. This request fails; the
		 * batch's COMMIT fails and its members with it. */
		return tl_error(err, err_size, TL_ERR_DB, "%s: storing: SQLite rolled back the open transaction (%s)", s->path,
				sqlite3_errmsg(s->db));
	}
	if (!s->batch.open) {
		if (sty_exec(s, "BEGIN IMMEDIATE") != SQLITE_OK)
			return sty_db_fail(s, err, err_size, "starting a transaction");
		s->batch.open = true;
	}
	if (sty_exec(s, "SAVEPOINT request") != SQLITE_OK)
		return sty_db_fail(s, err, err_size, "starting a transaction");
	return TL_OK;
}

/* Waits (s->lock released meanwhile) up to GATHER_ROUNDS x GATHER_NS while requests are on their way into the batch. */
static void gather(sty *s)
{
	for (int round = 0; round < GATHER_ROUNDS && __atomic_load_n(&s->batch.coming, __ATOMIC_SEQ_CST); round++) {
		struct timespec until;
		clock_gettime(CLOCK_REALTIME, &until);
		until.tv_nsec += GATHER_NS;
		if (until.tv_nsec >= 1000000000)
			until.tv_sec++, until.tv_nsec -= 1000000000;
		while (__atomic_load_n(&s->batch.coming, __ATOMIC_SEQ_CST) &&
		       pthread_cond_timedwait(&s->batch.joined, &s->lock, &until) != ETIMEDOUT)
			;
	}
}

/* Commits the open batch (s->lock held) and publishes its result to the members. */
static void batch_commit(sty *s)
{
	int rc = TL_OK;
	if (sty_exec(s, "COMMIT") != SQLITE_OK) {
		rc = TL_ERR_DB;
		snprintf(s->batch.why, sizeof s->batch.why, "%s", sqlite3_errmsg(s->db));
		sty_exec(s, "ROLLBACK");
	}
	s->batch.open = false;
	s->batch.members = 0;
	s->batch.results[s->batch.epoch % STY_BATCH_RESULTS] = rc;
	s->batch.epoch++;
	pthread_cond_broadcast(&s->batch.done);
}

int sty_batch_leave(sty *s, int rc, bool wrote, char *err, size_t err_size)
{
	/* A request that stored nothing may still have read the open batch's writes of other requests, which wait for
	 * its commit (a trial's clip names made by a concurrent GET /api/CODE/trial of the same participant, an answer
	 * not yet on disk). It replies only once that commit is done, and fails with it: a reply never carries what a
	 * failed commit then took back (a clip name that no longer exists, a trial counted as answered). */
	bool saw_batch = !rc && !wrote && s->batch.open && s->batch.members > 0;
	if (rc || (!wrote && !saw_batch)) { /* nothing of this request stays: undo it, and close a batch nobody else is in */
		if (rc)
			sty_exec(s, "ROLLBACK TO request");
		sty_exec(s, "RELEASE request");
		if (s->batch.open && !s->batch.members && !s->batch.leading) {
			sty_exec(s, "COMMIT"); /* no change in it: no fsync */
			s->batch.open = false;
		}
		return rc;
	}
	if (sty_exec(s, "RELEASE request") != SQLITE_OK)
		return sty_db_fail(s, err, err_size, "storing");
	uint64_t mine = s->batch.epoch;
	s->batch.members++;
	if (s->batch.committer && defer.on && !defer.taken) { /* the reply waits instead (sty_batch_defer_end) */
		defer.taken = true;
		defer.ticket = mine;
		pthread_cond_signal(&s->batch.work);
		return TL_OK;
	}
	if (s->batch.committer)
		pthread_cond_signal(&s->batch.work);
	while (s->batch.epoch == mine) {
		if (s->batch.leading || s->batch.committer) { /* a request gathering this batch, or the committer, commits it */
			pthread_cond_wait(&s->batch.done, &s->lock);
			continue;
		}
		s->batch.leading = true;
		gather(s);
		s->batch.leading = false;
		if (s->batch.committer) { /* started meanwhile (it waits for no leader): it commits this batch */
			pthread_cond_signal(&s->batch.work);
			continue;
		}
		batch_commit(s);
	}
	/* A member reads its batch's result before STY_BATCH_RESULTS later batches overwrite it: members wait for
	 * the lock that every later batch needs, so they are at most a few batches behind. */
	if (s->batch.results[mine % STY_BATCH_RESULTS])
		return tl_error(err, err_size, TL_ERR_DB, "%s: storing: %s", s->path, s->batch.why);
	return TL_OK;
}

void sty_batch_quiesce(sty *s)
{
	s->batch.draining++;
	while (s->batch.open)
		pthread_cond_wait(&s->batch.done, &s->lock);
	if (--s->batch.draining == 0)
		pthread_cond_broadcast(&s->batch.done); /* the requests waiting to open a batch: after s->lock is released */
}

/* ------------------------------------------------------------------ the committer thread */

static void *committer_main(void *arg)
{
	sty *s = arg;
	pthread_mutex_lock(&s->lock);
	for (;;) {
		while (s->batch.leading || (!s->batch.stopping && !(s->batch.open && s->batch.members)))
			pthread_cond_wait(&s->batch.work, &s->lock);
		if (!(s->batch.open && s->batch.members))
			break; /* stopping, and nothing left to commit */
		gather(s);
		uint64_t epoch = s->batch.epoch;
		batch_commit(s);
		int rc = s->batch.results[epoch % STY_BATCH_RESULTS];
		char why[sizeof s->batch.why];
		snprintf(why, sizeof why, "%s", rc ? s->batch.why : "");
		pthread_mutex_unlock(&s->lock);
		s->batch.on_commit(s->batch.ctx, epoch, rc, why);
		pthread_mutex_lock(&s->lock);
	}
	s->batch.committer = false;
	pthread_mutex_unlock(&s->lock);
	return NULL;
}

int sty_batch_committer_start(sty *s, void (*on_commit)(void *ctx, uint64_t epoch, int rc, const char *why), void *ctx)
{
	pthread_mutex_lock(&s->lock);
	s->batch.on_commit = on_commit;
	s->batch.ctx = ctx;
	s->batch.stopping = false;
	s->batch.committer = true;
	int bad = pthread_create(&s->batch.thread, NULL, committer_main, s);
	if (bad)
		s->batch.committer = false;
	pthread_mutex_unlock(&s->lock);
	return bad ? TL_ERR_NOMEM : TL_OK;
}

void sty_batch_committer_stop(sty *s)
{
	pthread_mutex_lock(&s->lock);
	bool running = s->batch.committer;
	s->batch.stopping = true;
	pthread_cond_signal(&s->batch.work);
	pthread_mutex_unlock(&s->lock);
	if (running)
		pthread_join(s->batch.thread, NULL);
}
