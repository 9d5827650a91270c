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
#include <unistd.h>

#include "study_internal.h"
#include "taslab/pairs.h"
#include "taslab/tl_fs.h"

static const char *SCHEMA =
	"CREATE TABLE IF NOT EXISTS meta(key TEXT PRIMARY KEY, value TEXT NOT NULL);"
	"CREATE TABLE IF NOT EXISTS conditions(id INTEGER PRIMARY KEY, scene TEXT NOT NULL, camera TEXT NOT NULL,"
	" camera_motion TEXT NOT NULL CHECK(camera_motion IN ('stationary','moving')), method TEXT NOT NULL,"
	" T REAL, period INTEGER CHECK(period IS NULL OR period IN (1, 2, 4, 8)), ref_clip TEXT NOT NULL,"
	" test_clip TEXT NOT NULL, is_catch INTEGER NOT NULL DEFAULT 0);"
	"CREATE TABLE IF NOT EXISTS participants(id INTEGER PRIMARY KEY, code TEXT NOT NULL UNIQUE, label TEXT NOT NULL);"
	"CREATE TABLE IF NOT EXISTS trials(participant INTEGER NOT NULL REFERENCES participants(id),"
	" idx INTEGER NOT NULL, condition INTEGER NOT NULL REFERENCES conditions(id), ref_first INTEGER NOT NULL,"
	" kind TEXT NOT NULL CHECK(kind IN ('test','catch','training')), break_before INTEGER NOT NULL DEFAULT 0,"
	" PRIMARY KEY(participant, idx));"
	"CREATE TABLE IF NOT EXISTS answers(participant INTEGER NOT NULL, idx INTEGER NOT NULL,"
	" answer INTEGER NOT NULL CHECK(answer BETWEEN -2 AND 2), rt_ms INTEGER, at TEXT NOT NULL,"
	" PRIMARY KEY(participant, idx), FOREIGN KEY(participant, idx) REFERENCES trials(participant, idx));"
	/* The opaque clip names of the trials served so far: slot 0 is the clip shown first (A), 1 the second. */
	"CREATE TABLE IF NOT EXISTS clip_names(name TEXT PRIMARY KEY, participant INTEGER NOT NULL, idx INTEGER NOT NULL,"
	" slot INTEGER NOT NULL CHECK(slot IN (0, 1)), UNIQUE(participant, idx, slot),"
	" FOREIGN KEY(participant, idx) REFERENCES trials(participant, idx)) WITHOUT ROWID;";

int sty_db_fail(sty *s, char *err, size_t err_size, const char *what)
{
	return tl_error(err, err_size, TL_ERR_DB, "%s: %s: %s", s->path, what, s->db ? sqlite3_errmsg(s->db) : "not open");
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

int sty_random_hex(char out[33])
{
	uint8_t b[16];
	if (getrandom(b, sizeof b, 0) != (ssize_t)sizeof b)
		return -1;
	for (int i = 0; i < 16; i++)
		snprintf(out + 2 * i, 3, "%02x", b[i]);
	return 0;
}

/* Names SQLite does not treat as a file: "" (a temporary database), ":memory:", "file:" URIs. */
static int sqlite_special_name(const char *path)
{
	return !*path || !strcmp(path, ":memory:") || !strncmp(path, "file:", 5);
}

/* Whether the conditions table has the period column. */
static int has_period_column(sty *s)
{
	sqlite3_stmt *st;
	int has = 0;
	if (sqlite3_prepare_v2(s->db, "SELECT count(*) FROM pragma_table_info('conditions') WHERE name = 'period'", -1, &st,
			       NULL) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW)
		has = sqlite3_column_int(st, 0) > 0;
	sqlite3_finalize(st);
	return has;
}

/* Brings a study made by an earlier taslab up to date. Studies made before conditions carried a period (method
 * x T x scene x camera only) get the period column, NULL for every condition: right for every method but rrc
 * and sau, whose period was never stored, so a study holding rrc or sau conditions without a period is refused
 * (its rrc/4 and rrc/8 conditions could not be told apart). A study that is up to date is only read (so a
 * read-only file still opens); the column is added in one transaction, so concurrent openers (a server and a
 * tally) do not both add it. */
static int upgrade(sty *s, char *err, size_t err_size)
{
	int rc = TL_OK, missing = 0;
	if (!has_period_column(s)) {
		if (sqlite3_exec(s->db, "BEGIN IMMEDIATE", NULL, NULL, NULL) != SQLITE_OK)
			return sty_db_fail(s, err, err_size, "adding the period column");
		if (!has_period_column(s) &&
		    sqlite3_exec(s->db, "ALTER TABLE conditions ADD COLUMN period INTEGER"
					" CHECK(period IS NULL OR period IN (1, 2, 4, 8))", NULL, NULL, NULL) != SQLITE_OK)
			rc = sty_db_fail(s, err, err_size, "adding the period column");
		if (rc || sqlite3_exec(s->db, "COMMIT", NULL, NULL, NULL) != SQLITE_OK) {
			if (!rc)
				rc = sty_db_fail(s, err, err_size, "adding the period column");
			sqlite3_exec(s->db, "ROLLBACK", NULL, NULL, NULL);
			return rc;
		}
	}
	sqlite3_stmt *st;
	if (sqlite3_prepare_v2(s->db, "SELECT count(*) FROM conditions WHERE method IN ('rrc', 'sau') AND period IS NULL", -1,
			       &st, NULL) != SQLITE_OK)
		return sty_db_fail(s, err, err_size, "opening the study");
	if (sqlite3_step(st) == SQLITE_ROW)
		missing = sqlite3_column_int(st, 0);
	sqlite3_finalize(st);
	if (missing)
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: %d rrc/sau condition(s) without a period (a study made before "
				"taslab stored periods): set conditions.period with sqlite3, or make the study again", s->path,
				missing);
	return TL_OK;
}

/* Opens `file` (SQLite) for the study `s`, applies the pragmas and, when `init`, creates the schema, the admin
 * token and the markers; otherwise checks that it is a taslab study and brings the schema up to date. */
static int db_connect(sty *s, const char *file, bool init, char *err, size_t err_size)
{
	int flags = SQLITE_OPEN_READWRITE | (init ? SQLITE_OPEN_CREATE : 0) | SQLITE_OPEN_FULLMUTEX;
	if (sqlite3_open_v2(file, &s->db, flags, NULL) != SQLITE_OK)
		return tl_error(err, err_size, TL_ERR_DB, "%s: cannot open: %s", s->path,
				s->db ? sqlite3_errmsg(s->db) : "out of memory");
	sqlite3_busy_timeout(s->db, 5000);
	/* Durability: WAL with synchronous=FULL fsyncs the log at every commit, so an answer acknowledged after
	 * its COMMIT survives a crash of the server or the machine. */
	char *msg = NULL, mark[8];
	if (sqlite3_exec(s->db, "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL; PRAGMA foreign_keys=ON;", NULL, NULL,
			 &msg) != SQLITE_OK) {
		int rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: not a taslab study database (%s)", s->path, msg ? msg : "?");
		sqlite3_free(msg);
		return rc;
	}
	if (!init) {
		sqlite3_stmt *st;
		int has_meta = sqlite3_prepare_v2(s->db, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'meta'", -1,
						  &st, NULL) == SQLITE_OK &&
			       sqlite3_step(st) == SQLITE_ROW;
		sqlite3_finalize(st);
		if (!has_meta || meta_get(s, "taslab_study", mark, sizeof mark))
			return tl_error(err, err_size, TL_ERR_INPUT, "%s: not a taslab study database (made by 'taslab study design')",
					s->path);
	}
	if (sqlite3_exec(s->db, SCHEMA, NULL, NULL, &msg) != SQLITE_OK) {
		int rc = tl_error(err, err_size, TL_ERR_DB, "%s: cannot set up the study tables (%s)", s->path, msg ? msg : "?");
		sqlite3_free(msg);
		return rc;
	}
	if (!init) {
		int rc = upgrade(s, err, err_size);
		if (rc)
			return rc;
	}
	if (init && (sty_random_hex(s->token) || meta_set(s, "admin_token", s->token) || meta_set(s, "taslab_study", "1")))
		return tl_error(err, err_size, TL_ERR_DB, "%s: cannot initialise the study", s->path);
	if (meta_get(s, "admin_token", s->token, sizeof s->token) || strlen(s->token) != 32)
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: the study has no admin token (damaged?)", s->path);
	meta_get(s, "stimuli", s->stimuli, sizeof s->stimuli);
	meta_get(s, "served_url", s->served_url, sizeof s->served_url);
	return TL_OK;
}

static sty *sty_alloc(const char *path)
{
	sty *s = calloc(1, sizeof *s);
	if (!s)
		return NULL;
	snprintf(s->path, sizeof s->path, "%s", path);
	snprintf(s->open_path, sizeof s->open_path, "%s", path);
	pthread_mutex_init(&s->lock, NULL);
	return s;
}

int sty_open(const char *path, sty **out, char *err, size_t err_size)
{
	*out = NULL;
	if (!path || sqlite_special_name(path))
		return tl_error(err, err_size, TL_ERR_ARG, "--db '%s' is not a file name (SQLite would not keep the study in a file)",
				path ? path : "");
	if (strlen(path) >= TL_PATH_MAX)
		return tl_error(err, err_size, TL_ERR_ARG, "%.64s...: path too long", path);
	if (!tl_is_file(path))
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: no such study database (create one with 'taslab study design')",
				path);
	sty *s = sty_alloc(path);
	if (!s)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	int rc = db_connect(s, path, false, err, err_size);
	if (rc) {
		sty_close(&s);
		return rc;
	}
	*out = s;
	return TL_OK;
}

/* Removes SQLite's side files of a database file (best effort). */
static void unlink_side_files(const char *file)
{
	const char *suffix[3] = {"-wal", "-shm", "-journal"};
	char p[TL_PATH_MAX + 16];
	for (int i = 0; i < 3; i++) {
		snprintf(p, sizeof p, "%s%s", file, suffix[i]);
		unlink(p);
	}
}

/* TL_ERR_CONFLICT when `path` or a side file of a database by that name exists. */
static int check_free(const char *path, char *err, size_t err_size)
{
	struct stat sb;
	if (lstat(path, &sb) == 0)
		return tl_error(err, err_size, TL_ERR_CONFLICT, "%s exists: a study is never overwritten (choose a new --db file, "
				"or delete the old one first)", path);
	const char *suffix[3] = {"-wal", "-shm", "-journal"};
	char p[TL_PATH_MAX + 16];
	for (int i = 0; i < 3; i++) {
		snprintf(p, sizeof p, "%s%s", path, suffix[i]);
		if (lstat(p, &sb) == 0)
			return tl_error(err, err_size, TL_ERR_CONFLICT, "%s exists (left by a deleted study?): SQLite would apply it to "
					"the new study; remove it or choose another --db file", p);
	}
	return TL_OK;
}

int sty_create(const char *path, sty **out, char *err, size_t err_size)
{
	*out = NULL;
	if (!path || sqlite_special_name(path))
		return tl_error(err, err_size, TL_ERR_ARG, "--db '%s' is not a file name: give the file the study is kept in "
				"(\"\", \":memory:\" and file: URIs are not kept)", path ? path : "");
	if (strlen(path) >= TL_PATH_MAX - 32)
		return tl_error(err, err_size, TL_ERR_ARG, "%.64s...: path too long", path);
	int rc = check_free(path, err, err_size);
	if (rc)
		return rc;
	tl_fs_clean_temps_beside(path); /* what a design or import killed midway left */
	sty *s = sty_alloc(path);
	if (!s)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	/* tl_fs.h detach pattern: SQLite writes the temporary file by name; sty_commit renames it into place. */
	if ((rc = tl_atomic_open(&s->pending, path, err, err_size)) || (rc = tl_atomic_detach(&s->pending, err, err_size))) {
		sty_close(&s);
		return rc;
	}
	/* The study holds the admin token and every participant's link code: owner only. SQLite gives its -wal and
	 * -shm files the mode of the database file. */
	if (chmod(s->pending.tmp, 0600) != 0) {
		rc = tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot restrict the permissions: %s", path, strerror(errno));
		sty_close(&s);
		return rc;
	}
	snprintf(s->open_path, sizeof s->open_path, "%s", s->pending.tmp);
	if ((rc = db_connect(s, s->open_path, true, err, err_size))) {
		sty_close(&s);
		return rc;
	}
	*out = s;
	return TL_OK;
}

int sty_commit(sty *s, char *err, size_t err_size)
{
	if (!s->pending.open)
		return TL_OK;
	/* Closing the last connection checkpoints the WAL into the file and deletes it, so the one file holds
	 * the whole study before it is renamed. */
	if (sqlite3_close(s->db) != SQLITE_OK) {
		int rc = sty_db_fail(s, err, err_size, "closing the new study");
		return rc;
	}
	s->db = NULL;
	int rc = check_free(s->path, err, err_size);
	if (!rc)
		rc = tl_atomic_commit(&s->pending, err, err_size);
	unlink_side_files(s->pending.tmp);
	if (rc) {
		tl_atomic_abort(&s->pending);
		return rc;
	}
	snprintf(s->open_path, sizeof s->open_path, "%s", s->path);
	return db_connect(s, s->path, false, err, err_size);
}

void sty_close(sty **ps)
{
	if (!ps || !*ps)
		return;
	sty *s = *ps;
	if (s->db)
		sqlite3_close(s->db);
	if (s->pending.open) { /* never committed: the new study goes away */
		unlink_side_files(s->pending.tmp);
		tl_atomic_abort(&s->pending);
	}
	pthread_mutex_destroy(&s->lock);
	free(s);
	*ps = NULL;
}

const char *sty_stimuli(const sty *s) { return s->stimuli; }
const char *sty_path(const sty *s) { return s->path; }
const char *sty_admin_token(const sty *s) { return s->token; }
const char *sty_served_url(const sty *s) { return s->served_url; }

int sty_set_served_url(sty *s, const char *url, char *err, size_t err_size)
{
	if (strlen(url) >= sizeof s->served_url)
		return tl_error(err, err_size, TL_ERR_ARG, "served URL too long");
	pthread_mutex_lock(&s->lock);
	int bad = meta_set(s, "served_url", url);
	if (!bad)
		snprintf(s->served_url, sizeof s->served_url, "%s", url);
	pthread_mutex_unlock(&s->lock);
	return bad ? sty_db_fail(s, err, err_size, "storing the served URL") : TL_OK;
}

int sty_describe_method(sty *s, const char *method, const run_method_facts *facts, char *err, size_t err_size)
{
	size_t i = 0;
	while (i < s->method_count && strcmp(s->methods[i].name, method))
		i++;
	if (strlen(method) >= sizeof s->methods[0].name || i == STY_MAX_METHODS)
		return tl_error(err, err_size, TL_ERR_ARG, "method '%s': name too long, or more than %d methods", method,
				STY_MAX_METHODS);
	snprintf(s->methods[i].name, sizeof s->methods[i].name, "%s", method);
	s->methods[i].facts = *facts;
	s->methods[i].facts.known = true;
	if (i == s->method_count)
		s->method_count++;
	return TL_OK;
}

const run_method_facts *sty_method_facts(const sty *s, const char *method)
{
	for (size_t i = 0; i < s->method_count; i++)
		if (!strcmp(s->methods[i].name, method))
			return &s->methods[i].facts;
	return NULL;
}

const char *sty_reference_method(const sty *s)
{
	for (size_t i = 0; i < s->method_count; i++)
		if (s->methods[i].facts.reference)
			return s->methods[i].name;
	return NULL;
}

bool sty_period_valid(long period) { return period == 1 || period == 2 || period == 4 || period == 8; }

int sty_condition_rule(const run_method_facts *f, const char *method, double T, long period, char *why,
		       size_t why_size)
{
	bool has_T = f && f->takes_threshold, has_N = f && f->takes_period;
	if (!f || !f->known) /* issue 30.1: no list of names here; the registry or pairs.json describes each method */
		snprintf(why, why_size, "method '%s' is not one of the methods taslab knows (its method registry, or "
			 "pairs.json's method_facts)", method);
	else if (has_T && isnan(T))
		snprintf(why, why_size, "method %s needs a threshold T", method);
	else if (!has_T && !isnan(T))
		snprintf(why, why_size, "method %s has no threshold T (leave T empty)", method);
	else if (has_N && !period)
		snprintf(why, why_size, "method %s needs a period (1, 2, 4 or 8)", method);
	else if (!has_N && period)
		snprintf(why, why_size, "method %s has no period (leave period empty)", method);
	else if (has_N && !sty_period_valid(period))
		snprintf(why, why_size, "period %ld of method %s is not 1, 2, 4 or 8", period, method);
	else
		return 0;
	return -1;
}

/* ------------------------------------------------------------------ design */

typedef struct cond {
	char scene[64], camera[64], motion[16], method[32];
	double T;        /* NAN: none */
	uint32_t period; /* 0: none */
	char ref_clip[512], test_clip[512];
	int is_catch;
	char ref_method[32]; /* the reference's method name (pairs.json reference.method), for added catch trials */
} cond;

/* Reads one pairs.json (from `taslab pair`, output/pairs.h) into conditions; `rel` is its folder relative to
 * the stimuli. Every clip it names must exist, so a session never fails midway on a missing file. */
static int read_pairs(const sty *s, const char *file, const char *rel, cond **cs, size_t *n, char *err, size_t err_size)
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
	/* The same rule as import: T and period exactly as the method has them (DESIGN section 4). */
	for (size_t i = 0; i < set.count; i++) {
		const pairs_condition *c = &set.conditions[i];
		char why[160];
		const run_method_facts *f = c->facts.known ? &c->facts : sty_method_facts(s, c->method);
		if (sty_condition_rule(f, c->method, c->T, (long)c->period, why, sizeof why)) {
			rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: condition '%s': %s", file, c->id, why);
			pairs_free(&set);
			return rc;
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
		x->period = c->period;
		snprintf(x->ref_clip, sizeof x->ref_clip, "%s%s%s", rel, rel[0] ? "/" : "", set.ref_clip);
		snprintf(x->test_clip, sizeof x->test_clip, "%s%s%s", rel, rel[0] ? "/" : "", c->clip);
		/* reference against itself; the facts from the file, else the caller's (checked above) */
		x->is_catch = (c->facts.known ? &c->facts : sty_method_facts(s, c->method))->reference;
		const char *ref = set.ref_method[0] ? set.ref_method : sty_reference_method(s);
		snprintf(x->ref_method, sizeof x->ref_method, "%s", ref ? ref : "");
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
		if ((rc = read_pairs(s, p, sets[i], &cs, &nc, err, err_size)))
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
				if (!cs[i].ref_method[0]) {
					snprintf(err, err_size, "a pairs.json names no reference method (made by an older taslab); "
						 "make the set again with 'taslab pair'");
					goto done;
				}
				snprintf(cs[nc].method, sizeof cs[nc].method, "%s", cs[i].ref_method);
				cs[nc].T = NAN;
				cs[nc].period = 0;
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
	sqlite3_prepare_v2(s->db, "INSERT INTO conditions(id, scene, camera, camera_motion, method, T, ref_clip, test_clip, is_catch,"
				  " period) VALUES(?,?,?,?,?,?,?,?,?,?)", -1, &ic, NULL);
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
		if (cs[i].period)
			sqlite3_bind_int64(ic, 10, cs[i].period);
		else
			sqlite3_bind_null(ic, 10);
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
		if (sty_random_hex(code)) {
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

/* The extension a clip's opaque name keeps, so the browser knows the container: ".webm" / ".mp4", else none. */
static const char *clip_ext(const char *path)
{
	size_t n = strlen(path);
	if (n >= 5 && !strcmp(path + n - 5, ".webm"))
		return ".webm";
	if (n >= 4 && !strcmp(path + n - 4, ".mp4"))
		return ".mp4";
	return "";
}

/* The opaque name of side `slot` of trial (pid, idx), made (random, stored) when missing. Caller holds the lock
 * and an open transaction. */
static int clip_name(sty *s, int64_t pid, int64_t idx, int slot, const char *path, char *out, size_t n)
{
	sqlite3_stmt *st;
	if (sqlite3_prepare_v2(s->db, "SELECT name FROM clip_names WHERE participant = ? AND idx = ? AND slot = ?", -1, &st,
			       NULL))
		return -1;
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, idx);
	sqlite3_bind_int(st, 3, slot);
	int r = sqlite3_step(st);
	if (r == SQLITE_ROW)
		snprintf(out, n, "%s", (const char *)sqlite3_column_text(st, 0));
	sqlite3_finalize(st);
	if (r == SQLITE_ROW)
		return 0;
	if (r != SQLITE_DONE)
		return -1;
	char hex[33];
	if (sty_random_hex(hex))
		return -1;
	snprintf(out, n, "%s%s", hex, clip_ext(path));
	if (sqlite3_prepare_v2(s->db, "INSERT INTO clip_names(name, participant, idx, slot) VALUES(?, ?, ?, ?)", -1, &st, NULL))
		return -1;
	sqlite3_bind_text(st, 1, out, -1, SQLITE_STATIC);
	sqlite3_bind_int64(st, 2, pid);
	sqlite3_bind_int64(st, 3, idx);
	sqlite3_bind_int(st, 4, slot);
	r = sqlite3_step(st);
	sqlite3_finalize(st);
	return r == SQLITE_DONE ? 0 : -1;
}

int sty_next_trial(sty *s, const char *code, sty_trial *t, char *err, size_t err_size)
{
	memset(t, 0, sizeof *t);
	pthread_mutex_lock(&s->lock);
	int rc = TL_OK, in_tx = 0;
	int64_t pid = participant_id(s, code);
	sqlite3_stmt *st = NULL;
	if (pid < 0) {
		rc = tl_error(err, err_size, TL_ERR_NOTFOUND, "unknown participant");
		goto done;
	}
	/* One transaction: the clip names made for a trial shown for the first time are committed together. */
	if (sqlite3_exec(s->db, "BEGIN IMMEDIATE", NULL, NULL, NULL) != SQLITE_OK) {
		rc = sty_db_fail(s, err, err_size, "next trial");
		goto done;
	}
	in_tx = 1;
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
		t->index = (uint32_t)sqlite3_column_int64(st, 2);
		int ref_first = sqlite3_column_int(st, 3);
		snprintf(t->kind, sizeof t->kind, "%s", (const char *)sqlite3_column_text(st, 4));
		t->break_before = sqlite3_column_int(st, 5) != 0;
		char ref[TL_PATH_MAX], test[TL_PATH_MAX];
		snprintf(ref, sizeof ref, "%s", (const char *)sqlite3_column_text(st, 6));
		snprintf(test, sizeof test, "%s", (const char *)sqlite3_column_text(st, 7));
		sqlite3_finalize(st);
		st = NULL;
		if (clip_name(s, pid, t->index, 0, ref_first ? ref : test, t->clip_a, sizeof t->clip_a) ||
		    clip_name(s, pid, t->index, 1, ref_first ? test : ref, t->clip_b, sizeof t->clip_b)) {
			rc = sty_db_fail(s, err, err_size, "naming the clips");
			goto done;
		}
	} else if (r == SQLITE_DONE) {
		sqlite3_finalize(st);
		st = NULL;
		if (sqlite3_prepare_v2(s->db, "SELECT count(*) FROM trials WHERE participant = ?", -1, &st, NULL)) {
			rc = sty_db_fail(s, err, err_size, "next trial");
			goto done;
		}
		sqlite3_bind_int64(st, 1, pid);
		if (sqlite3_step(st) == SQLITE_ROW)
			t->total = t->answered = (uint32_t)sqlite3_column_int(st, 0);
		t->done = true;
	} else {
		rc = sty_db_fail(s, err, err_size, "next trial");
	}
done:
	sqlite3_finalize(st);
	if (in_tx && (rc || sqlite3_exec(s->db, "COMMIT", NULL, NULL, NULL) != SQLITE_OK)) {
		if (!rc)
			rc = sty_db_fail(s, err, err_size, "next trial");
		sqlite3_exec(s->db, "ROLLBACK", NULL, NULL, NULL);
	}
	if (rc)
		memset(t, 0, sizeof *t);
	pthread_mutex_unlock(&s->lock);
	return rc;
}

int sty_clip_file(sty *s, const char *name, char *rel, size_t rel_size, char *err, size_t err_size)
{
	rel[0] = 0;
	sqlite3_stmt *st;
	pthread_mutex_lock(&s->lock);
	int rc = TL_OK;
	if (sqlite3_prepare_v2(s->db,
			       "SELECT CASE WHEN (k.slot = 0) = (t.ref_first != 0) THEN c.ref_clip ELSE c.test_clip END"
			       " FROM clip_names k JOIN trials t ON t.participant = k.participant AND t.idx = k.idx"
			       " JOIN conditions c ON c.id = t.condition WHERE k.name = ?", -1, &st, NULL)) {
		rc = sty_db_fail(s, err, err_size, "clip");
		goto done;
	}
	sqlite3_bind_text(st, 1, name, -1, SQLITE_STATIC);
	int r = sqlite3_step(st);
	if (r == SQLITE_ROW && sqlite3_column_text(st, 0) && sqlite3_column_text(st, 0)[0])
		snprintf(rel, rel_size, "%s", (const char *)sqlite3_column_text(st, 0));
	else if (r == SQLITE_ROW || r == SQLITE_DONE)
		rc = tl_error(err, err_size, TL_ERR_NOTFOUND, "no such clip");
	else
		rc = sty_db_fail(s, err, err_size, "clip");
	sqlite3_finalize(st);
done:
	pthread_mutex_unlock(&s->lock);
	return rc;
}

int sty_answer(sty *s, const char *code, uint32_t trial, int64_t answer, int64_t rt_ms, char *err, size_t err_size)
{
	if (answer < -2 || answer > 2)
		return tl_error(err, err_size, TL_ERR_ARG, "answer must be an integer from -2 to 2");
	if (rt_ms < -1 || rt_ms > STY_RT_MS_MAX)
		return tl_error(err, err_size, TL_ERR_ARG, "rt_ms must be a whole number of milliseconds from 0 to %d",
				STY_RT_MS_MAX);
	pthread_mutex_lock(&s->lock);
	int rc = TL_OK;
	sqlite3_stmt *st = NULL;
	int64_t pid = participant_id(s, code);
	if (pid < 0) {
		rc = tl_error(err, err_size, TL_ERR_NOTFOUND, "unknown participant");
		goto done;
	}
	/* Does the trial exist, is it answered, and which trial is current (the lowest-index unanswered one). The
	 * lock serialises this check with the INSERT below against the other server threads. */
	if (sqlite3_prepare_v2(s->db,
			       "SELECT (SELECT count(*) FROM trials WHERE participant = ?1 AND idx = ?2),"
			       " (SELECT count(*) FROM answers WHERE participant = ?1 AND idx = ?2),"
			       " (SELECT min(idx) FROM trials WHERE participant = ?1 AND"
			       "  idx NOT IN (SELECT idx FROM answers WHERE participant = ?1))", -1, &st, NULL)) {
		rc = sty_db_fail(s, err, err_size, "answer");
		goto done;
	}
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, trial);
	if (sqlite3_step(st) != SQLITE_ROW) {
		rc = sty_db_fail(s, err, err_size, "answer");
		goto done;
	}
	if (sqlite3_column_int(st, 0) == 0) {
		rc = tl_error(err, err_size, TL_ERR_NOTFOUND, "no trial %u for this participant", trial);
		goto done;
	}
	if (sqlite3_column_int(st, 1) != 0) {
		rc = tl_error(err, err_size, TL_ERR_CONFLICT, "trial %u was answered already", trial);
		goto done;
	}
	if (sqlite3_column_int64(st, 2) != (sqlite3_int64)trial) {
		rc = tl_error(err, err_size, TL_ERR_ARG, "trial %u is not the current trial (%lld): trials are answered in order",
			      trial, (long long)sqlite3_column_int64(st, 2));
		goto done;
	}
	sqlite3_finalize(st);
	st = NULL;
	/* A single autocommit INSERT: when sqlite3_step returns DONE the row is committed (and, with
	 * synchronous=FULL, on disk); only then is the answer acknowledged. */
	if (sqlite3_prepare_v2(s->db, "INSERT INTO answers(participant, idx, answer, rt_ms, at)"
				      " VALUES(?, ?, ?, ?, strftime('%Y-%m-%dT%H:%M:%fZ','now'))", -1, &st, NULL)) {
		rc = sty_db_fail(s, err, err_size, "storing the answer");
		goto done;
	}
	sqlite3_bind_int64(st, 1, pid);
	sqlite3_bind_int64(st, 2, trial);
	sqlite3_bind_int64(st, 3, answer);
	if (rt_ms >= 0)
		sqlite3_bind_int64(st, 4, rt_ms);
	else
		sqlite3_bind_null(st, 4);
	int r = sqlite3_step(st);
	if (r == SQLITE_CONSTRAINT)
		rc = tl_error(err, err_size, TL_ERR_CONFLICT, "trial %u was answered already", trial);
	else if (r != SQLITE_DONE)
		rc = sty_db_fail(s, err, err_size, "storing the answer");
done:
	sqlite3_finalize(st);
	pthread_mutex_unlock(&s->lock);
	return rc;
}
