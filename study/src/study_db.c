/* study_db.c — the study database: schema, design (randomisation), participants, trials, answers (study.h). */
#define _DEFAULT_SOURCE /* realpath, getrandom */
#include <dirent.h>
#include <errno.h>
#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>
#include <jansson.h>
#include <math.h>
#include <pthread.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <sys/stat.h>

#include "study_internal.h"
#include "taslab/pairs.h"
#include "taslab/tl_fs.h"

static const char *SCHEMA =
	"CREATE TABLE IF NOT EXISTS meta(key TEXT PRIMARY KEY, value TEXT NOT NULL);"
	"CREATE TABLE IF NOT EXISTS conditions(id INTEGER PRIMARY KEY, scene TEXT NOT NULL, camera TEXT NOT NULL,"
	" camera_motion TEXT NOT NULL CHECK(camera_motion IN ('stationary','moving')), method TEXT NOT NULL,"
	" T REAL, ref_clip TEXT NOT NULL, test_clip TEXT NOT NULL, is_catch INTEGER NOT NULL DEFAULT 0);"
	"CREATE TABLE IF NOT EXISTS participants(id INTEGER PRIMARY KEY, code TEXT NOT NULL UNIQUE, label TEXT NOT NULL);"
	"CREATE TABLE IF NOT EXISTS trials(participant INTEGER NOT NULL REFERENCES participants(id),"
	" idx INTEGER NOT NULL, condition INTEGER NOT NULL REFERENCES conditions(id), ref_first INTEGER NOT NULL,"
	" kind TEXT NOT NULL CHECK(kind IN ('test','catch','training')), break_before INTEGER NOT NULL DEFAULT 0,"
	" PRIMARY KEY(participant, idx));"
	"CREATE TABLE IF NOT EXISTS answers(participant INTEGER NOT NULL, idx INTEGER NOT NULL,"
	" answer INTEGER NOT NULL CHECK(answer BETWEEN -2 AND 2), rt_ms INTEGER, at TEXT NOT NULL,"
	" PRIMARY KEY(participant, idx), FOREIGN KEY(participant, idx) REFERENCES trials(participant, idx));";

int sty_db_fail(sty *s, char *err, size_t err_size, const char *what)
{
	snprintf(err, err_size, "%s: %s: %s", s->path, what, sqlite3_errmsg(s->db));
	return TL_ERR_DB;
}

static int meta_get(sty *s, const char *key, char *val, size_t size)
{
	sqlite3_stmt *st;
	val[0] = 0;
	if (sqlite3_prepare_v2(s->db, "SELECT value FROM meta WHERE key = ?", -1, &st, NULL))
		return -1;
	sqlite3_bind_text(st, 1, key, -1, SQLITE_STATIC);
	int found = sqlite3_step(st) == SQLITE_ROW;
	if (found)
		snprintf(val, size, "%s", (const char *)sqlite3_column_text(st, 0));
	sqlite3_finalize(st);
	return found ? 0 : -1;
}

static int meta_set(sty *s, const char *key, const char *val)
{
	sqlite3_stmt *st;
	if (sqlite3_prepare_v2(s->db, "INSERT OR REPLACE INTO meta(key, value) VALUES(?, ?)", -1, &st, NULL))
		return -1;
	sqlite3_bind_text(st, 1, key, -1, SQLITE_STATIC);
	sqlite3_bind_text(st, 2, val, -1, SQLITE_STATIC);
	int rc = sqlite3_step(st) == SQLITE_DONE ? 0 : -1;
	sqlite3_finalize(st);
	return rc;
}

/* 128 random bits as 32 hex digits, from the kernel (link codes and tokens must be unguessable). */
static int random_hex(char out[33])
{
	uint8_t b[16];
	if (getrandom(b, sizeof b, 0) != (ssize_t)sizeof b)
		return -1;
	for (int i = 0; i < 16; i++)
		snprintf(out + 2 * i, 3, "%02x", b[i]);
	return 0;
}

int sty_open(const char *path, bool create, sty **out, char *err, size_t err_size)
{
	*out = NULL;
	struct stat sb;
	if (!create && stat(path, &sb) != 0) {
		snprintf(err, err_size, "%s: no such study database (create one with 'taslab study design')", path);
		return TL_ERR_ARG;
	}
	sty *s = calloc(1, sizeof *s);
	if (!s) {
		snprintf(err, err_size, "out of memory");
		return TL_ERR_ARG;
	}
	snprintf(s->path, sizeof s->path, "%s", path);
	pthread_mutex_init(&s->lock, NULL);
	int flags = SQLITE_OPEN_READWRITE | (create ? SQLITE_OPEN_CREATE : 0) | SQLITE_OPEN_FULLMUTEX;
	if (sqlite3_open_v2(path, &s->db, flags, NULL) != SQLITE_OK) {
		snprintf(err, err_size, "%s: cannot open: %s", path, s->db ? sqlite3_errmsg(s->db) : "out of memory");
		sty_close(&s);
		return TL_ERR_DB;
	}
	sqlite3_busy_timeout(s->db, 5000);
	/* Durability: WAL with synchronous=FULL fsyncs the log at every commit, so an answer acknowledged after
	 * its COMMIT survives a crash of the server or the machine. */
	char *msg = NULL;
	if (sqlite3_exec(s->db, "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL; PRAGMA foreign_keys=ON;", NULL, NULL,
			 &msg) != SQLITE_OK ||
	    sqlite3_exec(s->db, SCHEMA, NULL, NULL, &msg) != SQLITE_OK) {
		snprintf(err, err_size, "%s: not a taslab study database (%s)", path, msg ? msg : "?");
		sqlite3_free(msg);
		sty_close(&s);
		return TL_ERR_DB;
	}
	if (meta_get(s, "admin_token", s->token, sizeof s->token)) {
		if (random_hex(s->token) || meta_set(s, "admin_token", s->token) || meta_set(s, "taslab_study", "1")) {
			snprintf(err, err_size, "%s: cannot initialise the study", path);
			sty_close(&s);
			return TL_ERR_DB;
		}
	}
	meta_get(s, "stimuli", s->stimuli, sizeof s->stimuli);
	*out = s;
	return TL_OK;
}

void sty_close(sty **ps)
{
	if (!ps || !*ps)
		return;
	sty *s = *ps;
	if (s->db)
		sqlite3_close(s->db);
	pthread_mutex_destroy(&s->lock);
	free(s);
	*ps = NULL;
}

const char *sty_stimuli(const sty *s) { return s->stimuli; }
const char *sty_path(const sty *s) { return s->path; }
const char *sty_admin_token(const sty *s) { return s->token; }

/* ------------------------------------------------------------------ design */

typedef struct cond {
	char scene[64], camera[64], motion[16], method[32];
	double T;
	char ref_clip[512], test_clip[512];
	int is_catch;
} cond;

/* Reads one pairs.json (from `taslab pair`, output/pairs.h) into conditions; `rel` is its folder relative to
 * the stimuli. Every clip it names must exist, so a session never fails midway on a missing file. */
static int read_pairs(const char *file, const char *rel, cond **cs, size_t *n, char *err, size_t err_size)
{
	pairs_set set;
	int rc = pairs_read(file, &set, err, err_size);
	if (rc)
		return rc;
	if (strcmp(set.camera_motion, "stationary") && strcmp(set.camera_motion, "moving")) {
		pairs_free(&set);
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: camera_motion must be stationary or moving", file);
	}
	char dir[TL_PATH_MAX], clip[TL_PATH_MAX];
	snprintf(dir, sizeof dir, "%s", file);
	char *slash = strrchr(dir, '/');
	if (slash)
		*slash = 0;
	else
		snprintf(dir, sizeof dir, ".");
	for (size_t i = 0; i <= set.count; i++) {
		snprintf(clip, sizeof clip, "%s/%s", dir, i < set.count ? set.conditions[i].clip : set.ref_clip);
		if (!tl_is_file(clip)) {
			pairs_free(&set);
			return tl_error(err, err_size, TL_ERR_INPUT, "%s: clip %s does not exist (render the set again with 'taslab pair')",
					file, clip);
		}
	}
	for (size_t i = 0; i < set.count; i++) {
		const pairs_condition *c = &set.conditions[i];
		cond *nc = realloc(*cs, (*n + 1) * sizeof *nc);
		if (!nc) {
			pairs_free(&set);
			return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		}
		*cs = nc;
		cond *x = &nc[(*n)++];
		memset(x, 0, sizeof *x);
		snprintf(x->scene, sizeof x->scene, "%s", set.scene);
		snprintf(x->camera, sizeof x->camera, "%s", set.camera);
		snprintf(x->motion, sizeof x->motion, "%s", set.camera_motion);
		snprintf(x->method, sizeof x->method, "%s", c->method);
		x->T = c->T;
		snprintf(x->ref_clip, sizeof x->ref_clip, "%s%s%s", rel, rel[0] ? "/" : "", set.ref_clip);
		snprintf(x->test_clip, sizeof x->test_clip, "%s%s%s", rel, rel[0] ? "/" : "", c->clip);
		x->is_catch = !strcmp(c->method, "ref"); /* reference against itself */
	}
	pairs_free(&set);
	return TL_OK;
}

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

int sty_design(sty *s, const sty_design_desc *d, sty_design_summary *out, char *err, size_t err_size)
{
	cond *cs = NULL;
	size_t nc = 0;
	int rc = TL_ERR_ARG;
	char **sets = NULL;
	size_t nsets = 0;
	gsl_rng *rng = NULL;
	memset(out, 0, sizeof *out);
	if (!d->stimuli || d->participants < 1 || d->participants > 100000) {
		snprintf(err, err_size, "need --stimuli DIR and 1..100000 --participants");
		return TL_ERR_ARG;
	}
	sqlite3_stmt *cnt;
	sqlite3_prepare_v2(s->db, "SELECT (SELECT count(*) FROM conditions) + (SELECT count(*) FROM participants)", -1, &cnt, NULL);
	int used = sqlite3_step(cnt) == SQLITE_ROW && sqlite3_column_int(cnt, 0) > 0;
	sqlite3_finalize(cnt);
	if (used) {
		snprintf(err, err_size, "%s already holds a study design; use a new --db file", s->path);
		return TL_ERR_ARG;
	}
	char root[4096];
	if (!realpath(d->stimuli, root)) {
		snprintf(err, err_size, "%s: %s (give the folder that holds the pairs.json sets)", d->stimuli, strerror(errno));
		return TL_ERR_ARG;
	}
	/* Sets: ROOT/pairs.json and ROOT/<name>/pairs.json, in name order. */
	char p[8192];
	struct stat sb;
	snprintf(p, sizeof p, "%s/pairs.json", root);
	if (stat(p, &sb) == 0 && (sets = malloc(sizeof *sets)))
		sets[nsets++] = strdup("");
	DIR *dir = opendir(root);
	struct dirent *e;
	while (dir && (e = readdir(dir))) {
		if (e->d_name[0] == '.')
			continue;
		snprintf(p, sizeof p, "%s/%s/pairs.json", root, e->d_name);
		if (stat(p, &sb) == 0) {
			char **ns = realloc(sets, (nsets + 1) * sizeof *ns);
			if (!ns)
				break;
			sets = ns;
			sets[nsets++] = strdup(e->d_name);
		}
	}
	if (dir)
		closedir(dir);
	if (nsets == 0) {
		snprintf(err, err_size, "%s: no pairs.json here or one folder below (make sets with 'taslab pair')", root);
		goto done;
	}
	qsort(sets, nsets, sizeof *sets, cmp_str);
	for (size_t i = 0; i < nsets; i++) {
		snprintf(p, sizeof p, "%s%s%s/pairs.json", root, sets[i][0] ? "/" : "", sets[i]);
		if ((rc = read_pairs(p, sets[i], &cs, &nc, err, err_size)))
			goto done;
		rc = TL_ERR_ARG;
	}
	size_t ntest = 0, ncatch = 0;
	for (size_t i = 0; i < nc; i++)
		cs[i].is_catch ? ncatch++ : ntest++;
	if (ntest == 0 && d->catch_trials == 0) {
		snprintf(err, err_size, "%s: the sets hold only reference-vs-reference pairs; add variants with 'taslab pair --variants'", root);
		goto done;
	}
	/* Catch trials use reference-vs-reference pairs; every set can provide one from its reference clip. */
	if (d->catch_trials)
		for (size_t i = 0, n0 = nc; i < n0; i++) {
			int have = 0;
			for (size_t j = 0; j < nc; j++)
				have |= cs[j].is_catch && !strcmp(cs[j].ref_clip, cs[i].ref_clip);
			if (!have) {
				cond *ncs = realloc(cs, (nc + 1) * sizeof *ncs);
				if (!ncs)
					goto done;
				cs = ncs;
				cs[nc] = cs[i];
				snprintf(cs[nc].method, sizeof cs[nc].method, "ref");
				cs[nc].T = NAN;
				snprintf(cs[nc].test_clip, sizeof cs[nc].test_clip, "%s", cs[i].ref_clip);
				cs[nc].is_catch = 1;
				nc++;
				ncatch++;
			}
		}
	if (d->catch_trials && ncatch == 0) {
		snprintf(err, err_size, "no reference clips for catch trials");
		goto done;
	}
	char *msg = NULL;
	if (sqlite3_exec(s->db, "BEGIN IMMEDIATE", NULL, NULL, &msg) != SQLITE_OK) {
		sqlite3_free(msg);
		rc = sty_db_fail(s, err, err_size, "begin");
		goto done;
	}
	sqlite3_stmt *ic, *ip, *it;
	sqlite3_prepare_v2(s->db, "INSERT INTO conditions(id, scene, camera, camera_motion, method, T, ref_clip, test_clip, is_catch)"
				  " VALUES(?,?,?,?,?,?,?,?,?)", -1, &ic, NULL);
	sqlite3_prepare_v2(s->db, "INSERT INTO participants(id, code, label) VALUES(?,?,?)", -1, &ip, NULL);
	sqlite3_prepare_v2(s->db, "INSERT INTO trials(participant, idx, condition, ref_first, kind, break_before)"
				  " VALUES(?,?,?,?,?,?)", -1, &it, NULL);
	int ok = 1;
	for (size_t i = 0; i < nc && ok; i++) {
		sqlite3_reset(ic);
		sqlite3_bind_int64(ic, 1, (sqlite3_int64)i + 1);
		sqlite3_bind_text(ic, 2, cs[i].scene, -1, SQLITE_STATIC);
		sqlite3_bind_text(ic, 3, cs[i].camera, -1, SQLITE_STATIC);
		sqlite3_bind_text(ic, 4, cs[i].motion, -1, SQLITE_STATIC);
		sqlite3_bind_text(ic, 5, cs[i].method, -1, SQLITE_STATIC);
		if (isnan(cs[i].T))
			sqlite3_bind_null(ic, 6);
		else
			sqlite3_bind_double(ic, 6, cs[i].T);
		sqlite3_bind_text(ic, 7, cs[i].ref_clip, -1, SQLITE_STATIC);
		sqlite3_bind_text(ic, 8, cs[i].test_clip, -1, SQLITE_STATIC);
		sqlite3_bind_int(ic, 9, cs[i].is_catch);
		ok = sqlite3_step(ic) == SQLITE_DONE;
	}
	/* Plan per participant: [training] then shuffled (test conditions + catch trials). */
	rng = gsl_rng_alloc(gsl_rng_mt19937);
	size_t per = ntest + d->catch_trials;
	size_t *order = calloc(per + d->training + 1, sizeof *order);
	int *flip = calloc(nc + 1, sizeof *flip);
	size_t *tests = calloc(ntest + 1, sizeof *tests), *catches = calloc(ncatch + 1, sizeof *catches);
	if (!rng || !order || !flip || !tests || !catches)
		ok = 0;
	for (size_t i = 0, a = 0, b = 0; ok && i < nc; i++)
		cs[i].is_catch ? (catches[b++] = i) : (tests[a++] = i);
	uint32_t breaks = 0;
	for (uint32_t pi = 0; ok && pi < d->participants; pi++) {
		char code[33], label[32];
		if (random_hex(code)) {
			ok = 0;
			break;
		}
		snprintf(label, sizeof label, "P%03u", pi + 1);
		sqlite3_reset(ip);
		sqlite3_bind_int64(ip, 1, pi + 1);
		sqlite3_bind_text(ip, 2, code, -1, SQLITE_TRANSIENT);
		sqlite3_bind_text(ip, 3, label, -1, SQLITE_TRANSIENT);
		ok = sqlite3_step(ip) == SQLITE_DONE;
		/* Each pair of participants (2k, 2k+1) shares one seeded draw of in-pair orders, the second taking the
		 * complement: orders are random per participant and each pair appears in both orders. */
		gsl_rng_set(rng, (unsigned long)(d->seed * 1000003ull + (pi / 2) * 2654435761ull + 1));
		for (size_t c = 0; c < nc; c++)
			flip[c] = (int)gsl_rng_uniform_int(rng, 2) ^ (int)(pi % 2);
		gsl_rng_set(rng, (unsigned long)(d->seed * 1000003ull + pi * 40503ull + 7777));
		size_t n = 0;
		for (size_t k = 0; k < d->training; k++)
			order[n++] = ntest ? tests[gsl_rng_uniform_int(rng, ntest)] : catches[0];
		size_t start = n;
		for (size_t k = 0; k < ntest; k++)
			order[n++] = tests[k];
		size_t off = ncatch ? gsl_rng_uniform_int(rng, ncatch) : 0; /* which catch pairs: rotates per participant */
		for (size_t k = 0; k < d->catch_trials; k++)
			order[n++] = catches[(k + off) % ncatch];
		gsl_ran_shuffle(rng, order + start, n - start, sizeof *order);
		for (size_t k = 0; ok && k < n; k++) {
			size_t c = order[k];
			const char *kind = k < start ? "training" : cs[c].is_catch ? "catch" : "test";
			int brk = d->break_every && k > 0 && k % d->break_every == 0;
			breaks += brk && pi == 0;
			sqlite3_reset(it);
			sqlite3_bind_int64(it, 1, pi + 1);
			sqlite3_bind_int64(it, 2, (sqlite3_int64)k);
			sqlite3_bind_int64(it, 3, (sqlite3_int64)c + 1);
			sqlite3_bind_int(it, 4, flip[c]);
			sqlite3_bind_text(it, 5, kind, -1, SQLITE_STATIC);
			sqlite3_bind_int(it, 6, brk);
			ok = sqlite3_step(it) == SQLITE_DONE;
		}
		out->trials_per_participant = (uint32_t)n;
	}
	sqlite3_finalize(ic);
	sqlite3_finalize(ip);
	sqlite3_finalize(it);
	free(order);
	free(flip);
	free(tests);
	free(catches);
	char seedbuf[32];
	snprintf(seedbuf, sizeof seedbuf, "%llu", (unsigned long long)d->seed);
	ok = ok && !meta_set(s, "stimuli", root) && !meta_set(s, "seed", seedbuf);
	if (!ok || sqlite3_exec(s->db, "COMMIT", NULL, NULL, NULL) != SQLITE_OK) {
		rc = sty_db_fail(s, err, err_size, "writing the design");
		sqlite3_exec(s->db, "ROLLBACK", NULL, NULL, NULL);
		goto done;
	}
	snprintf(s->stimuli, sizeof s->stimuli, "%s", root);
	/* Session length: clip durations from the first set's pairs.json frames and fps. */
	double clip_s = 5.0;
	snprintf(p, sizeof p, "%s%s%s/pairs.json", root, sets[0][0] ? "/" : "", sets[0]);
	pairs_set first;
	char why[256];
	if (!pairs_read(p, &first, why, sizeof why)) {
		clip_s = (double)(first.last_frame - first.first_frame + 1) / first.fps;
		pairs_free(&first);
	}
	double ans = d->answer_s > 0 ? d->answer_s : 4.0, gap = d->gap_s > 0 ? d->gap_s : 0.5;
	out->conditions = (uint32_t)nc;
	out->sets = (uint32_t)nsets;
	out->participants = d->participants;
	out->breaks = breaks;
	out->session_minutes = (out->trials_per_participant * (2 * clip_s + gap + ans) + 30.0 * breaks) / 60.0;
	rc = TL_OK;
done:
	gsl_rng_free(rng);
	for (size_t i = 0; i < nsets; i++)
		free(sets[i]);
	free(sets);
	free(cs);
	return rc;
}

int sty_participant_codes(sty *s, char ***codes, size_t *n, char *err, size_t err_size)
{
	sqlite3_stmt *st;
	*codes = NULL;
	*n = 0;
	if (sqlite3_prepare_v2(s->db, "SELECT code FROM participants ORDER BY id", -1, &st, NULL))
		return sty_db_fail(s, err, err_size, "participants");
	while (sqlite3_step(st) == SQLITE_ROW) {
		char **nc = realloc(*codes, (*n + 1) * sizeof *nc);
		if (!nc)
			break;
		*codes = nc;
		(*codes)[(*n)++] = strdup((const char *)sqlite3_column_text(st, 0));
	}
	sqlite3_finalize(st);
	return TL_OK;
}

static int64_t participant_id(sty *s, const char *code)
{
	sqlite3_stmt *st;
	int64_t id = -1;
	if (sqlite3_prepare_v2(s->db, "SELECT id FROM participants WHERE code = ?", -1, &st, NULL))
		return -1;
	sqlite3_bind_text(st, 1, code, -1, SQLITE_STATIC);
	if (sqlite3_step(st) == SQLITE_ROW)
		id = sqlite3_column_int64(st, 0);
	sqlite3_finalize(st);
	return id;
}

int sty_next_trial(sty *s, const char *code, sty_trial *t, char *err, size_t err_size)
{
	memset(t, 0, sizeof *t);
	pthread_mutex_lock(&s->lock);
	int rc = TL_OK;
	int64_t pid = participant_id(s, code);
	sqlite3_stmt *st = NULL;
	if (pid < 0) {
		snprintf(err, err_size, "unknown participant");
		rc = TL_ERR_NOTFOUND;
		goto done;
	}
	if (sqlite3_prepare_v2(s->db,
			       "SELECT (SELECT count(*) FROM trials WHERE participant = ?1),"
			       " (SELECT count(*) FROM answers WHERE participant = ?1),"
			       " t.idx, t.ref_first, t.kind, t.break_before, c.ref_clip, c.test_clip"
			       " FROM trials t JOIN conditions c ON c.id = t.condition"
			       " WHERE t.participant = ?1 AND t.idx NOT IN (SELECT idx FROM answers WHERE participant = ?1)"
			       " ORDER BY t.idx LIMIT 1", -1, &st, NULL)) {
		rc = sty_db_fail(s, err, err_size, "next trial");
		goto done;
	}
	sqlite3_bind_int64(st, 1, pid);
	int r = sqlite3_step(st);
	if (r == SQLITE_ROW) {
		t->total = (uint32_t)sqlite3_column_int(st, 0);
		t->answered = (uint32_t)sqlite3_column_int(st, 1);
		t->index = (uint32_t)sqlite3_column_int(st, 2);
		int ref_first = sqlite3_column_int(st, 3);
		snprintf(t->kind, sizeof t->kind, "%s", (const char *)sqlite3_column_text(st, 4));
		t->break_before = sqlite3_column_int(st, 5) != 0;
		const char *ref = (const char *)sqlite3_column_text(st, 6), *test = (const char *)sqlite3_column_text(st, 7);
		snprintf(t->clip_a, sizeof t->clip_a, "%s", ref_first ? ref : test);
		snprintf(t->clip_b, sizeof t->clip_b, "%s", ref_first ? test : ref);
	} else if (r == SQLITE_DONE) {
		sqlite3_finalize(st);
		st = NULL;
		sqlite3_prepare_v2(s->db, "SELECT count(*) FROM trials WHERE participant = ?", -1, &st, NULL);
		sqlite3_bind_int64(st, 1, pid);
		if (sqlite3_step(st) == SQLITE_ROW)
			t->total = t->answered = (uint32_t)sqlite3_column_int(st, 0);
		t->done = true;
	} else {
		rc = sty_db_fail(s, err, err_size, "next trial");
	}
done:
	sqlite3_finalize(st);
	pthread_mutex_unlock(&s->lock);
	return rc;
}

int sty_answer(sty *s, const char *code, uint32_t trial, int answer, int64_t rt_ms, char *err, size_t err_size)
{
	if (answer < -2 || answer > 2) {
		snprintf(err, err_size, "answer must be an integer from -2 to 2");
		return TL_ERR_ARG;
	}
	pthread_mutex_lock(&s->lock);
	int rc = TL_OK;
	sqlite3_stmt *st = NULL;
	int64_t pid = participant_id(s, code);
	if (pid < 0) {
		snprintf(err, err_size, "unknown participant");
		rc = TL_ERR_NOTFOUND;
		goto done;
	}
	sqlite3_prepare_v2(s->db, "SELECT (SELECT count(*) FROM trials WHERE participant = ?1 AND idx = ?2),"
				  " (SELECT count(*) FROM answers WHERE participant = ?1 AND idx = ?2)", -1, &st, NULL);
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, trial);
	if (sqlite3_step(st) != SQLITE_ROW) {
		rc = sty_db_fail(s, err, err_size, "answer");
		goto done;
	}
	if (sqlite3_column_int(st, 0) == 0) {
		snprintf(err, err_size, "no trial %u for this participant", trial);
		rc = TL_ERR_NOTFOUND;
		goto done;
	}
	if (sqlite3_column_int(st, 1) != 0) {
		snprintf(err, err_size, "trial %u was answered already", trial);
		rc = TL_ERR_CONFLICT;
		goto done;
	}
	sqlite3_finalize(st);
	/* A single autocommit INSERT: when sqlite3_step returns DONE the row is committed (and, with
	 * synchronous=FULL, on disk); only then is the answer acknowledged. */
	sqlite3_prepare_v2(s->db, "INSERT INTO answers(participant, idx, answer, rt_ms, at)"
				  " VALUES(?, ?, ?, ?, strftime('%Y-%m-%dT%H:%M:%fZ','now'))", -1, &st, NULL);
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, trial);
	sqlite3_bind_int(st, 3, answer);
	if (rt_ms >= 0)
		sqlite3_bind_int64(st, 4, rt_ms);
	else
		sqlite3_bind_null(st, 4);
	int r = sqlite3_step(st);
	if (r == SQLITE_CONSTRAINT) {
		snprintf(err, err_size, "trial %u was answered already", trial);
		rc = TL_ERR_CONFLICT;
	} else if (r != SQLITE_DONE) {
		rc = sty_db_fail(s, err, err_size, "storing the answer");
	}
done:
	sqlite3_finalize(st);
	pthread_mutex_unlock(&s->lock);
	return rc;
}
