/* study_csv.c — ratings in and out: long-format CSV (DESIGN section 7) and pwcmp layout (study.h). */
#define _DEFAULT_SOURCE /* realpath */
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <unistd.h>

#include "study_internal.h"
#include "taslab/tl_fs.h"

/* The long format: DESIGN section 7's columns with period right after T (DESIGN section 4: T and period their own
 * columns). Import also reads files in the DESIGN section 7 layout without period (LONG_HEADER_NO_PERIOD). */
static const char *LONG_HEADER = "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,rt_ms";
static const char *LONG_HEADER_NO_PERIOD = "participant,trial,scene,camera,camera_motion,method,T,ref_first,answer,rating,rt_ms";

/* Issue 27.9: the export holds every answered trial (test, catch, gold and training) with its type, when it was answered and
 * whether the participant completed the session, so that screening can be redone after export -> import. */
static const char *LONG_HEADER_FULL = "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,rating,"
				      "rt_ms,trial_type,answered_at,completed";
/* Issue 28 (remote participants): the page's playback telemetry after them (empty when the answer came without it),
 * the server's verdict `broken` (empty: counted) and `retake_of` (the planned trial a retake repeats). Import reads
 * all three layouts. */
#define TELEMETRY_HEADER ",play_a_ms,play_b_ms,dropped_frames,total_frames,hidden,hidden_ms,hidden_play,fullscreen,broken," \
			 "retake_of"
#define N_TELEMETRY 8 /* the whole-number telemetry columns, play_a_ms .. fullscreen */
static const char *LONG_HEADER_TELEMETRY = "participant,trial,scene,camera,camera_motion,method,T,period,ref_first,answer,"
					   "rating,rt_ms,trial_type,answered_at,completed" TELEMETRY_HEADER;

/* Query of every answered trial, one row per answer, in participant / trial order (columns 0-10 shared by both
 * exports; 11-13: type, time, completed — "" when unknown, as for ratings imported from a file without the column).
 * pwcmp takes the test trials only. */
#define ANSWERS_COLUMNS \
	"SELECT p.label, t.idx, c.scene, c.camera, c.camera_motion, c.method, c.T, t.ref_first, a.answer, a.rt_ms, c.period," \
	" t.kind, a.at, coalesce((SELECT value FROM meta WHERE key = 'completed:' || p.label)," \
	" (SELECT count(*) FROM trials u WHERE u.participant = p.id) = (SELECT count(*) FROM answers v WHERE v.participant = p.id))," \
	" a.play_a_ms, a.play_b_ms, a.dropped_frames, a.total_frames, a.hidden, a.hidden_ms, a.hidden_play, a.fullscreen," \
	" a.broken, t.retake_of" \
	" FROM answers a JOIN trials t ON t.participant = a.participant AND t.idx = a.idx" \
	" JOIN conditions c ON c.id = t.condition JOIN participants p ON p.id = a.participant"
static const char *ANSWERS_SQL = ANSWERS_COLUMNS " WHERE t.kind = 'test' AND a.broken IS NULL ORDER BY p.id, t.idx";
static const char *ALL_ANSWERS_SQL = ANSWERS_COLUMNS " ORDER BY p.id, t.idx";

int sty_csv_formula(const char *s)
{
	return s[0] == '=' || s[0] == '+' || s[0] == '-' || s[0] == '@' || s[0] == '\t' || s[0] == '\r';
}

const char *sty_num_cell(double v, const char *fmt, char *buf, size_t n)
{
	if (isnan(v))
		snprintf(buf, n, "%s", "");
	else if (isinf(v))
		snprintf(buf, n, "%s", v > 0 ? "inf" : "-inf");
	else
		snprintf(buf, n, fmt, v);
	return buf;
}

const char *sty_csv_cell(const char *s, char *buf, size_t n)
{
	/* OWASP "CSV injection": a spreadsheet runs a cell starting with = + - @ (and TAB/CR before them) as a
	 * formula; a leading ' makes it text. RFC 4180: a cell holding , " CR or LF is quoted, " doubled. */
	int quote = strpbrk(s, ",\"\r\n") != NULL;
	size_t k = 0;
	if (n == 0)
		return buf;
#define PUT(c) do { if (k + 1 < n) buf[k++] = (c); } while (0)
	if (quote)
		PUT('"');
	if (sty_csv_formula(s))
		PUT('\'');
	for (; *s; s++) {
		if (*s == '"')
			PUT('"');
		PUT(*s);
	}
	if (quote)
		PUT('"');
#undef PUT
	buf[k] = 0;
	return buf;
}

int sty_check_output(const sty *s, const char *path, char *err, size_t err_size)
{
	/* The database by the name it was opened with and by its real name (SQLite names its journals after the
	 * file a symlink leads to), and each with the journals SQLite keeps beside it. */
	static const char *const side[] = {"", "-wal", "-shm", "-journal"};
	char real[TL_PATH_MAX];
	const char *names[2] = {sty_path(s), realpath(sty_path(s), real) ? real : NULL};
	for (int k = 0; k < 2; k++)
		for (int i = 0; names[k] && i < 4; i++) {
			char p[TL_PATH_MAX + 16];
			snprintf(p, sizeof p, "%s%s", names[k], side[i]);
			if (tl_same_path(path, p))
				return tl_error(err, err_size, TL_ERR_ARG, "%s is the study database%s: writing there would destroy "
						"the answers (choose an --out outside the study's files)", path,
						i ? " journal" : "");
		}
	return TL_OK;
}

/* Column `i` of the answers query as a safe CSV text cell. */
#define CELL(st, i, buf) sty_csv_cell((const char *)sqlite3_column_text(st, i), buf, sizeof buf)

static void write_long(sqlite3_stmt *st, FILE *f, const char *ref)
{
	(void)ref;
	fprintf(f, "%s\n", LONG_HEADER_TELEMETRY);
	while (sqlite3_step(st) == SQLITE_ROW) {
		int ref_first = sqlite3_column_int(st, 7), answer = sqlite3_column_int(st, 8);
		char c0[160], c2[160], c3[160], c4[40], c5[80];
		fprintf(f, "%s,%d,%s,%s,%s,%s,", CELL(st, 0, c0), sqlite3_column_int(st, 1), CELL(st, 2, c2), CELL(st, 3, c3),
			CELL(st, 4, c4), CELL(st, 5, c5));
		if (sqlite3_column_type(st, 6) != SQLITE_NULL)
			fprintf(f, "%g", sqlite3_column_double(st, 6));
		fputc(',', f);
		if (sqlite3_column_type(st, 10) != SQLITE_NULL)
			fprintf(f, "%lld", (long long)sqlite3_column_int64(st, 10));
		fprintf(f, ",%d,%d,%d,", ref_first, answer, ref_first ? -answer : answer);
		if (sqlite3_column_type(st, 9) != SQLITE_NULL)
			fprintf(f, "%lld", (long long)sqlite3_column_int64(st, 9));
		char c11[40], c12[80], c13[8];
		fprintf(f, ",%s,%s,%s", CELL(st, 11, c11), CELL(st, 12, c12), CELL(st, 13, c13));
		for (int i = 14; i < 14 + N_TELEMETRY; i++) {
			fputc(',', f);
			if (sqlite3_column_type(st, i) != SQLITE_NULL)
				fprintf(f, "%lld", (long long)sqlite3_column_int64(st, i));
		}
		char c22[64];
		fprintf(f, ",%s,", sqlite3_column_type(st, 22) == SQLITE_NULL ? "" : CELL(st, 22, c22));
		if (sqlite3_column_type(st, 23) != SQLITE_NULL)
			fprintf(f, "%lld", (long long)sqlite3_column_int64(st, 23));
		fputc('\n', f);
	}
}

/* `ref`: the reference's condition name, its method name (issue 30.1: described, not written here). */
static void write_pwcmp(sqlite3_stmt *st, FILE *f, const char *ref)
{
	fprintf(f, "observer,scene,condition_A,condition_B,selected_A\n");
	while (sqlite3_step(st) == SQLITE_ROW) {
		/* The condition's name: METHOD, then _T<T> and _N<period> as the method has them (tfr_T8, rrc_N4). */
		char cond[96], grp[160], obs[160], cgrp[340], ccond[200];
		int k = snprintf(cond, sizeof cond, "%s", sqlite3_column_text(st, 5));
		if (sqlite3_column_type(st, 6) != SQLITE_NULL && k >= 0 && (size_t)k < sizeof cond)
			k += snprintf(cond + k, sizeof cond - (size_t)k, "_T%g", sqlite3_column_double(st, 6));
		if (sqlite3_column_type(st, 10) != SQLITE_NULL && k >= 0 && (size_t)k < sizeof cond)
			snprintf(cond + k, sizeof cond - (size_t)k, "_N%lld", (long long)sqlite3_column_int64(st, 10));
		snprintf(grp, sizeof grp, "%s/%s", sqlite3_column_text(st, 2), sqlite3_column_text(st, 3));
		sty_csv_cell(cond, ccond, sizeof ccond);
		sty_csv_cell(grp, cgrp, sizeof cgrp);
		CELL(st, 0, obs);
		int ref_first = sqlite3_column_int(st, 7), answer = sqlite3_column_int(st, 8);
		const char *a = ref_first ? ref : ccond, *b = ref_first ? ccond : ref;
		if (answer == 0) { /* "same": half a vote each way */
			fprintf(f, "%s,%s,%s,%s,1\n%s,%s,%s,%s,0\n", obs, cgrp, a, b, obs, cgrp, a, b);
		} else {
			fprintf(f, "%s,%s,%s,%s,%d\n", obs, cgrp, a, b, answer < 0 ? 1 : 0); /* answer < 0: first clip better */
		}
	}
}

int sty_export(sty *s, const char *long_path, const char *pwcmp_path, char *err, size_t err_size)
{
	const char *paths[2] = {long_path, pwcmp_path};
	void (*writers[2])(sqlite3_stmt *, FILE *, const char *) = {write_long, write_pwcmp};
	int rc = TL_OK;
	const char *ref = sty_reference_method(s);
	if (pwcmp_path && !ref)
		return tl_error(err, err_size, TL_ERR_INTERNAL, "pwcmp export: no reference method described (sty_describe_method)");
	/* Every check before anything is written: neither output is the database or its journal, nor the other. */
	for (int i = 0; i < 2; i++)
		if (paths[i] && (rc = sty_check_output(s, paths[i], err, err_size)))
			return rc;
	if (long_path && pwcmp_path && tl_same_path(long_path, pwcmp_path))
		return tl_error(err, err_size, TL_ERR_ARG, "--out and --pwcmp are the same file %s (give two files)", pwcmp_path);
	tl_atomic out[2] = {0};
	for (int i = 0; i < 2 && !rc; i++) {
		if (!paths[i])
			continue;
		sqlite3_stmt *st;
		tl_fs_clean_temps_beside(paths[i]);
		if ((rc = tl_atomic_open(&out[i], paths[i], err, err_size)))
			break;
		if (sqlite3_prepare_v2(s->db, i == 0 ? ALL_ANSWERS_SQL : ANSWERS_SQL, -1, &st, NULL)) {
			rc = sty_db_fail(s, err, err_size, "export");
			break;
		}
		writers[i](st, out[i].f, ref);
		if (sqlite3_finalize(st) != SQLITE_OK)
			rc = sty_db_fail(s, err, err_size, "export");
	}
	/* Both files or neither. */
	if (rc) {
		tl_atomic_abort_set(out, 2);
		return rc;
	}
	return tl_atomic_commit_set(out, 2, err, err_size);
}

int sty_export_long(sty *s, const char *path, char *err, size_t err_size)
{
	return sty_export(s, path, NULL, err, err_size);
}

int sty_export_pwcmp(sty *s, const char *path, char *err, size_t err_size)
{
	return sty_export(s, NULL, path, err, err_size);
}

/* ------------------------------------------------------------------ import */

typedef struct row {
	char participant[64], scene[64], camera[64], motion[16], method[32];
	long trial;
	double T; /* NAN: none */
	long period; /* 0: none */
	int ref_first, answer, rating;
	long long rt_ms; /* -1: none */
	char kind[16];   /* test, catch, gold, training (files without trial_type: test) */
	char at[40];     /* answered_at ("imported" for files without it) */
	int completed;   /* 0, 1; -1: unknown */
	long long tel[N_TELEMETRY]; /* play_a_ms .. fullscreen; -1: none */
	char broken[48]; /* the server's verdict ("": counted) */
	long retake_of;  /* -1: a planned trial */
} row;

static int split(char *line, char **f, int max)
{
	int n = 0;
	char *p = line;
	for (;;) {
		if (n == max)
			return max + 1;
		f[n++] = p;
		char *c = strchr(p, ',');
		if (!c)
			break;
		*c = 0;
		p = c + 1;
	}
	char *nl = strpbrk(f[n - 1], "\r\n");
	if (nl)
		*nl = 0;
	return n;
}

/* A whole number in [lo, hi] into *out; false when `s` is not one. */
static bool parse_long(const char *s, long lo, long hi, long *out)
{
	char *e;
	if (!(isdigit((unsigned char)s[0]) || (s[0] == '-' && isdigit((unsigned char)s[1])))) /* no blanks or '+' */
		return false;
	errno = 0;
	long v = strtol(s, &e, 10);
	if (*e || errno || v < lo || v > hi)
		return false;
	*out = v;
	return true;
}

/* A plain text cell: non-empty, fits, no quotes or control characters, and nothing a spreadsheet would run
 * as a formula (sty_csv_formula): such values are refused rather than stored. */
static int safe_name(const char *s, size_t max)
{
	size_t n = strlen(s);
	if (n == 0 || n >= max || sty_csv_formula(s))
		return 0;
	for (; *s; s++)
		if (*s == '"' || *s == '\'' || (unsigned char)*s < 32 || *s == 127)
			return 0;
	return 1;
}

enum { LAYOUT_NO_PERIOD, LAYOUT_PERIOD, LAYOUT_FULL, LAYOUT_TELEMETRY };

/* One data row in `layout`: LAYOUT_FULL (LONG_HEADER_FULL), LAYOUT_PERIOD (LONG_HEADER: type test, answered_at
 * "imported", completion unknown) or LAYOUT_NO_PERIOD (the DESIGN section 7 layout, which reads as if it had the period
 * column, empty). TL_OK, or TL_ERR_INPUT with the reason in `why`. */
static int parse_row(const sty *s, char *line, int layout, row *r, char *why, size_t why_size)
{
	static char none[1] = "";
	bool with_period = layout != LAYOUT_NO_PERIOD;
	char *c[32], *f[16];
	int cols = layout == LAYOUT_TELEMETRY ? 25 : layout == LAYOUT_FULL ? 15 : with_period ? 12 : 11;
	int n = split(line, c, cols);
	if (n != cols) {
		snprintf(why, why_size, "expected %d columns, found %d", cols, n > cols ? cols + 1 : n);
		return TL_ERR_INPUT;
	}
	/* f: the cells in the period layout (f[7] = period, "" when the file has none). */
	for (int i = 0; i < 12; i++)
		f[i] = i < 7 || with_period ? c[i] : i == 7 ? none : c[i - 1];
	long v;
	if (!safe_name(f[0], sizeof r->participant) || !safe_name(f[2], sizeof r->scene) ||
	    !safe_name(f[3], sizeof r->camera) || !safe_name(f[5], sizeof r->method)) {
		snprintf(why, why_size, "participant, scene, camera and method must be non-empty plain text (no quotes, control "
			 "characters, or a leading = + - @ that a spreadsheet would run as a formula)");
		return TL_ERR_INPUT;
	}
	snprintf(r->participant, sizeof r->participant, "%s", f[0]);
	snprintf(r->scene, sizeof r->scene, "%s", f[2]);
	snprintf(r->camera, sizeof r->camera, "%s", f[3]);
	snprintf(r->method, sizeof r->method, "%s", f[5]);
	if (!parse_long(f[1], 0, 1000000, &v)) {
		snprintf(why, why_size, "trial '%s' is not a whole number >= 0", f[1]);
		return TL_ERR_INPUT;
	}
	r->trial = v;
	if (strcmp(f[4], "stationary") && strcmp(f[4], "moving")) {
		snprintf(why, why_size, "camera_motion '%s' is not stationary or moving", f[4]);
		return TL_ERR_INPUT;
	}
	snprintf(r->motion, sizeof r->motion, "%s", f[4]);
	const run_method_facts *facts = sty_method_facts(s, r->method); /* described by the caller (issue 30.1) */
	if (!facts) /* the message of the rule below, before T and period are read */
		return sty_condition_rule(facts, r->method, NAN, 0, why, why_size);
	r->T = NAN;
	if (f[6][0]) {
		char *e;
		errno = 0;
		r->T = strtod(f[6], &e);
		if (*e || errno || !isfinite(r->T) || !(r->T > 0 && r->T <= 255) || isspace((unsigned char)f[6][0])) {
			snprintf(why, why_size, "T '%s' is not a number in (0, 255]", f[6]);
			return TL_ERR_INPUT;
		}
	}
	r->period = 0;
	if (f[7][0] && (!parse_long(f[7], 1, 8, &r->period) || !sty_period_valid(r->period))) {
		snprintf(why, why_size, "period '%s' is not 1, 2, 4 or 8", f[7]);
		return TL_ERR_INPUT;
	}
	/* T and period exactly as the method has them (the rule design applies to pairs.json). */
	if (sty_condition_rule(facts, r->method, r->T, r->period, why, why_size))
		return TL_ERR_INPUT;
	if (!parse_long(f[8], 0, 1, &v)) {
		snprintf(why, why_size, "ref_first '%s' is not 0 or 1", f[8]);
		return TL_ERR_INPUT;
	}
	r->ref_first = (int)v;
	if (!parse_long(f[9], -2, 2, &v)) {
		snprintf(why, why_size, "answer '%s' is not an integer from -2 to 2", f[9]);
		return TL_ERR_INPUT;
	}
	r->answer = (int)v;
	if (!parse_long(f[10], -2, 2, &v)) {
		snprintf(why, why_size, "rating '%s' is not an integer from -2 to 2", f[10]);
		return TL_ERR_INPUT;
	}
	r->rating = (int)v;
	if (r->rating != (r->ref_first ? -r->answer : r->answer)) {
		snprintf(why, why_size, "rating %d contradicts answer %d with ref_first %d (rating = ref_first ? -answer : answer)",
			 r->rating, r->answer, r->ref_first);
		return TL_ERR_INPUT;
	}
	r->rt_ms = -1;
	if (f[11][0]) {
		if (!parse_long(f[11], 0, STY_RT_MS_MAX, &v)) {
			snprintf(why, why_size, "rt_ms '%s' is not a whole number of milliseconds", f[11]);
			return TL_ERR_INPUT;
		}
		r->rt_ms = v;
	}
	snprintf(r->kind, sizeof r->kind, "test");
	snprintf(r->at, sizeof r->at, "imported");
	r->completed = -1;
	for (int i = 0; i < N_TELEMETRY; i++)
		r->tel[i] = -1;
	r->broken[0] = 0;
	r->retake_of = -1;
	if (layout < LAYOUT_FULL)
		return TL_OK;
	if (strcmp(c[12], "test") && strcmp(c[12], "catch") && strcmp(c[12], "gold") && strcmp(c[12], "training")) {
		snprintf(why, why_size, "trial_type '%s' is not test, catch, gold or training", c[12]);
		return TL_ERR_INPUT;
	}
	snprintf(r->kind, sizeof r->kind, "%s", c[12]);
	if (!strcmp(r->kind, "catch") && !facts->reference) {
		snprintf(why, why_size, "a catch trial compares the reference with itself: method %s is not the reference", r->method);
		return TL_ERR_INPUT;
	}
	if (!strcmp(r->kind, "gold") && facts->reference) {
		snprintf(why, why_size, "a gold trial compares the reference with a degraded variant: method %s is the reference",
			 r->method);
		return TL_ERR_INPUT;
	}
	/* an ISO 8601 time as the server writes it (2026-11-26T04:50:01.123Z), or "imported" */
	if (!c[13][0] || strlen(c[13]) >= sizeof r->at || strspn(c[13], "0123456789-:.TZ") != strlen(c[13]) ||
	    !isdigit((unsigned char)c[13][0])) {
		if (strcmp(c[13], "imported")) {
			snprintf(why, why_size, "answered_at '%.40s' is not a time like 2026-11-26T04:50:01.123Z (or 'imported')", c[13]);
			return TL_ERR_INPUT;
		}
	}
	snprintf(r->at, sizeof r->at, "%s", c[13]);
	long done;
	if (c[14][0] && !parse_long(c[14], 0, 1, &done)) {
		snprintf(why, why_size, "completed '%s' is not 0 or 1 (or empty: unknown)", c[14]);
		return TL_ERR_INPUT;
	}
	r->completed = c[14][0] ? (int)done : -1;
	if (layout != LAYOUT_TELEMETRY)
		return TL_OK;
	static const char *const tel_names[N_TELEMETRY] = {"play_a_ms", "play_b_ms", "dropped_frames", "total_frames", "hidden",
							  "hidden_ms", "hidden_play", "fullscreen"};
	for (int i = 0; i < N_TELEMETRY; i++)
		if (c[15 + i][0]) {
			if (!parse_long(c[15 + i], 0, i == 7 ? 1 : STY_RT_MS_MAX, &v)) {
				snprintf(why, why_size, "%s '%.20s' is not a whole number >= 0%s (or empty)", tel_names[i], c[15 + i],
					 i == 7 ? " (0 or 1)" : "");
				return TL_ERR_INPUT;
			}
			r->tel[i] = v;
		}
	/* the verdict: the server's reasons, ';'-joined (study_telemetry.h) */
	if (strlen(c[23]) >= sizeof r->broken || strspn(c[23], "abcdefghijklmnopqrstuvwxyz;") != strlen(c[23])) {
		snprintf(why, why_size, "broken '%.20s' is not a list of reasons such as dropped;hidden;long (or empty)", c[23]);
		return TL_ERR_INPUT;
	}
	snprintf(r->broken, sizeof r->broken, "%s", c[23]);
	if (c[24][0] && !parse_long(c[24], 0, 1000000, &r->retake_of)) {
		snprintf(why, why_size, "retake_of '%.20s' is not a trial number (or empty)", c[24]);
		return TL_ERR_INPUT;
	}
	return TL_OK;
}

/* Whether `line` is exactly `header` (then a line end or the end of the file). */
static bool header_is(const char *line, const char *header)
{
	size_t n = strlen(header);
	return !strncmp(line, header, n) && (line[n] == '\n' || line[n] == '\r' || !line[n]);
}

int sty_import_long(sty *s, const char *path, size_t *rows_out, char *err, size_t err_size)
{
	*rows_out = 0;
	FILE *f = fopen(path, "r");
	if (!f)
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: %s", path, strerror(errno));
	sqlite3_stmt *st;
	sqlite3_prepare_v2(s->db, "SELECT count(*) FROM participants", -1, &st, NULL);
	int used = sqlite3_step(st) == SQLITE_ROW && sqlite3_column_int(st, 0) > 0;
	sqlite3_finalize(st);
	if (used) {
		fclose(f);
		snprintf(err, err_size, "%s already holds participants; import into a new study database", s->path);
		return TL_ERR_ARG;
	}
	char line[4096], why[256];
	row *rows = NULL;
	size_t n = 0, lineno = 1;
	int rc = TL_ERR_INPUT; /* until the rows are stored: a malformed file */
	bool have = fgets(line, sizeof line, f) != NULL;
	int layout = !have ? -1 : header_is(line, LONG_HEADER_TELEMETRY) ? LAYOUT_TELEMETRY
		     : header_is(line, LONG_HEADER_FULL) ? LAYOUT_FULL : header_is(line, LONG_HEADER) ? LAYOUT_PERIOD
		     : header_is(line, LONG_HEADER_NO_PERIOD) ? LAYOUT_NO_PERIOD : -1;
	if (layout < 0) {
		snprintf(err, err_size, "%s:1: the header must be exactly: %s (or the same without the telemetry columns from "
			 "play_a_ms on, or, from before issue 27, without trial_type,answered_at,completed either, or from "
			 "before the period column without period either)", path, LONG_HEADER_TELEMETRY);
		goto done;
	}
	/* Validate everything before touching the database. */
	while (fgets(line, sizeof line, f)) {
		lineno++;
		if (!strchr(line, '\n') && !feof(f)) {
			snprintf(err, err_size, "%s:%zu: line longer than %zu characters", path, lineno, sizeof line - 1);
			goto done;
		}
		if (line[0] == '\n' || (line[0] == '\r' && line[1] == '\n'))
			continue;
		row *nr = realloc(rows, (n + 1) * sizeof *nr);
		if (!nr) {
			rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
			goto done;
		}
		rows = nr;
		int prc = parse_row(s, line, layout, &rows[n], why, sizeof why);
		if (prc) {
			rc = prc;
			snprintf(err, err_size, "%s:%zu: %s; nothing imported", path, lineno, why);
			goto done;
		}
		for (size_t k = 0; k < n; k++)
			if (rows[k].trial == rows[n].trial && !strcmp(rows[k].participant, rows[n].participant)) {
				snprintf(err, err_size, "%s:%zu: participant %s has trial %ld twice; nothing imported", path, lineno,
					 rows[n].participant, rows[n].trial);
				goto done;
			} else if (!strcmp(rows[k].participant, rows[n].participant) && rows[k].completed != rows[n].completed) {
				snprintf(err, err_size, "%s:%zu: participant %s has two values of completed; nothing imported", path,
					 lineno, rows[n].participant);
				goto done;
			}
		n++;
	}
	if (n == 0) {
		snprintf(err, err_size, "%s: no ratings after the header", path);
		goto done;
	}
	if (sqlite3_exec(s->db, "BEGIN IMMEDIATE", NULL, NULL, NULL) != SQLITE_OK) {
		rc = sty_db_fail(s, err, err_size, "import");
		goto done;
	}
	int ok = 1;
	sqlite3_stmt *fc, *ic, *fp, *ip, *it, *ia;
	sqlite3_prepare_v2(s->db, "SELECT id FROM conditions WHERE scene=? AND camera=? AND camera_motion=? AND method=? AND T IS ?"
				  " AND period IS ? AND is_catch = ?",
			   -1, &fc, NULL);
	sqlite3_prepare_v2(s->db, "INSERT INTO conditions(scene, camera, camera_motion, method, T, period, ref_clip, test_clip,"
				  " is_catch) VALUES(?,?,?,?,?,?,'','',?)", -1, &ic, NULL);
	sqlite3_prepare_v2(s->db, "SELECT id FROM participants WHERE label=?", -1, &fp, NULL);
	sqlite3_prepare_v2(s->db, "INSERT INTO participants(code, label) VALUES(?, ?)", -1, &ip, NULL);
	sqlite3_prepare_v2(s->db, "INSERT INTO trials(participant, idx, condition, ref_first, kind, retake_of)"
				  " VALUES(?,?,?,?,?,?)", -1, &it, NULL);
	sqlite3_prepare_v2(s->db, "INSERT INTO answers(participant, idx, answer, rt_ms, at, play_a_ms, play_b_ms,"
				  " dropped_frames, total_frames, hidden, hidden_ms, hidden_play, fullscreen, broken)"
				  " VALUES(?,?,?,?,?,?,?,?,?,?,?,?,?,?)", -1, &ia, NULL);
	for (size_t i = 0; ok && i < n; i++) {
		row *r = &rows[i];
		sqlite3_int64 cid = -1, pid = -1;
		sqlite3_reset(fc);
		sqlite3_bind_text(fc, 1, r->scene, -1, SQLITE_STATIC);
		sqlite3_bind_text(fc, 2, r->camera, -1, SQLITE_STATIC);
		sqlite3_bind_text(fc, 3, r->motion, -1, SQLITE_STATIC);
		sqlite3_bind_text(fc, 4, r->method, -1, SQLITE_STATIC);
		isnan(r->T) ? sqlite3_bind_null(fc, 5) : sqlite3_bind_double(fc, 5, r->T);
		r->period ? sqlite3_bind_int64(fc, 6, r->period) : sqlite3_bind_null(fc, 6);
		/* the condition's role (study_db.c): a gold trial's condition is kept apart from the test condition it copies */
		int role = !strcmp(r->kind, "gold") ? 2 : !strcmp(r->kind, "catch");
		sqlite3_bind_int(fc, 7, role);
		if (sqlite3_step(fc) == SQLITE_ROW)
			cid = sqlite3_column_int64(fc, 0);
		else {
			sqlite3_reset(ic);
			sqlite3_bind_text(ic, 1, r->scene, -1, SQLITE_STATIC);
			sqlite3_bind_text(ic, 2, r->camera, -1, SQLITE_STATIC);
			sqlite3_bind_text(ic, 3, r->motion, -1, SQLITE_STATIC);
			sqlite3_bind_text(ic, 4, r->method, -1, SQLITE_STATIC);
			isnan(r->T) ? sqlite3_bind_null(ic, 5) : sqlite3_bind_double(ic, 5, r->T);
			r->period ? sqlite3_bind_int64(ic, 6, r->period) : sqlite3_bind_null(ic, 6);
			sqlite3_bind_int(ic, 7, role);
			ok = sqlite3_step(ic) == SQLITE_DONE;
			cid = sqlite3_last_insert_rowid(s->db);
		}
		sqlite3_reset(fp);
		sqlite3_bind_text(fp, 1, r->participant, -1, SQLITE_STATIC);
		if (sqlite3_step(fp) == SQLITE_ROW)
			pid = sqlite3_column_int64(fp, 0);
		else {
			uint8_t b[16];
			char code[33];
			ok = ok && getrandom(b, sizeof b, 0) == (ssize_t)sizeof b;
			for (int k = 0; k < 16; k++)
				snprintf(code + 2 * k, 3, "%02x", b[k]);
			sqlite3_reset(ip);
			sqlite3_bind_text(ip, 1, code, -1, SQLITE_TRANSIENT);
			sqlite3_bind_text(ip, 2, r->participant, -1, SQLITE_STATIC);
			ok = ok && sqlite3_step(ip) == SQLITE_DONE;
			pid = sqlite3_last_insert_rowid(s->db);
			/* the session's completion as the file says it ("" unknown), for the next export (issue 27.9) */
			char key[96];
			snprintf(key, sizeof key, "completed:%s", r->participant);
			ok = ok && !sty_meta_set(s, key, r->completed < 0 ? "" : r->completed ? "1" : "0");
		}
		sqlite3_reset(it);
		sqlite3_bind_int64(it, 1, pid);
		sqlite3_bind_int64(it, 2, r->trial);
		sqlite3_bind_int64(it, 3, cid);
		sqlite3_bind_int(it, 4, r->ref_first);
		sqlite3_bind_text(it, 5, r->kind, -1, SQLITE_STATIC);
		r->retake_of >= 0 ? sqlite3_bind_int64(it, 6, r->retake_of) : sqlite3_bind_null(it, 6);
		ok = ok && sqlite3_step(it) == SQLITE_DONE;
		sqlite3_reset(ia);
		sqlite3_bind_int64(ia, 1, pid);
		sqlite3_bind_int64(ia, 2, r->trial);
		sqlite3_bind_int(ia, 3, r->answer);
		r->rt_ms >= 0 ? sqlite3_bind_int64(ia, 4, r->rt_ms) : sqlite3_bind_null(ia, 4);
		sqlite3_bind_text(ia, 5, r->at, -1, SQLITE_STATIC);
		for (int k = 0; k < N_TELEMETRY; k++)
			r->tel[k] >= 0 ? sqlite3_bind_int64(ia, 6 + k, r->tel[k]) : sqlite3_bind_null(ia, 6 + k);
		r->broken[0] ? sqlite3_bind_text(ia, 14, r->broken, -1, SQLITE_STATIC) : sqlite3_bind_null(ia, 14);
		ok = ok && sqlite3_step(ia) == SQLITE_DONE;
	}
	sqlite3_finalize(fc);
	sqlite3_finalize(ic);
	sqlite3_finalize(fp);
	sqlite3_finalize(ip);
	sqlite3_finalize(it);
	sqlite3_finalize(ia);
	if (!ok || sqlite3_exec(s->db, "COMMIT", NULL, NULL, NULL) != SQLITE_OK) {
		rc = sty_db_fail(s, err, err_size, "import");
		sqlite3_exec(s->db, "ROLLBACK", NULL, NULL, NULL);
		goto done;
	}
	*rows_out = n;
	rc = TL_OK;
done:
	free(rows);
	fclose(f);
	return rc;
}
