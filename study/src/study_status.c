/* study_status.c — a running study at a glance (study_status.h, issue 27.8): participants from the database, condition
 * statistics and the screening from the tally's own computation (sty_tally_compute on the answers so far), so the
 * status never disagrees with `taslab study tally`. */
#include <jansson.h>
#include <math.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "study_internal.h"
#include "taslab/study_result.h"
#include "taslab/study_status.h"

typedef struct part {
	char label[64], last[40];
	int answered, total, restarts;
	int flagged; /* 1, 0; -1: unknown (no test trial answered yet, so no tally) */
	int p910;    /* the P.910-crowd flags (STY_P910_*); -1: unknown, as flagged */
	int broken;  /* answers of broken playbacks (not counted; each retaken while retakes are left) */
	char broken_list[256]; /* "trial 7: hidden, trial 12: dropped;long": planned trial (1-based), the server's verdict */
} part;

typedef struct status {
	part *p;
	size_t n;
	sty_result *res; /* NULL when nothing can be tallied yet (note says why) */
	char note[512];
} status;

static bool has_table(sty *s, const char *name)
{
	sqlite3_stmt *st;
	bool has = false;
	if (sqlite3_prepare_v2(s->db, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?", -1, &st, NULL) == SQLITE_OK) {
		sqlite3_bind_text(st, 1, name, -1, SQLITE_STATIC);
		has = sqlite3_step(st) == SQLITE_ROW;
	}
	sqlite3_finalize(st);
	return has;
}

/* Collects the status from `s`, a handle of its own (collect). */
static int collect_on(sty *s, status *x, char *err, size_t err_size)
{
	int rc = TL_OK;
	sqlite3_stmt *st = NULL;
	char sql[1024];
	snprintf(sql, sizeof sql,
		 "SELECT p.label, (SELECT count(*) FROM answers a WHERE a.participant = p.id),"
		 " (SELECT count(*) FROM trials t WHERE t.participant = p.id),"
		 " (SELECT max(at) FROM answers a WHERE a.participant = p.id), %s,"
		 " (SELECT count(*) || '|' || coalesce(group_concat('trial ' || n || ': ' || broken, ', '), '') FROM (SELECT"
		 "  coalesce(t.retake_of, t.idx) + 1 AS n, a.broken FROM answers a JOIN trials t ON t.participant = a.participant"
		 "  AND t.idx = a.idx WHERE a.participant = p.id AND a.broken IS NOT NULL ORDER BY a.idx))"
		 " FROM participants p ORDER BY p.id",
		 has_table(s, "sessions") ? "(SELECT starts - 1 FROM sessions z WHERE z.participant = p.id)" : "0");
	if (sqlite3_prepare_v2(s->db, sql, -1, &st, NULL)) {
		rc = sty_db_fail(s, err, err_size, "status");
		goto out;
	}
	int r;
	while ((r = sqlite3_step(st)) == SQLITE_ROW) {
		part *np = realloc(x->p, (x->n + 1) * sizeof *np);
		if (!np) {
			rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
			break;
		}
		x->p = np;
		part *p = &np[x->n++];
		memset(p, 0, sizeof *p);
		snprintf(p->label, sizeof p->label, "%s", (const char *)sqlite3_column_text(st, 0));
		p->answered = sqlite3_column_int(st, 1);
		p->total = sqlite3_column_int(st, 2);
		if (sqlite3_column_type(st, 3) != SQLITE_NULL)
			snprintf(p->last, sizeof p->last, "%s", (const char *)sqlite3_column_text(st, 3));
		p->restarts = sqlite3_column_int(st, 4);
		const char *b = (const char *)sqlite3_column_text(st, 5), *bar = b ? strchr(b, '|') : NULL;
		p->broken = b ? atoi(b) : 0;
		snprintf(p->broken_list, sizeof p->broken_list, "%s", bar ? bar + 1 : "");
	}
	if (!rc && r != SQLITE_DONE)
		rc = sty_db_fail(s, err, err_size, "status");
	sqlite3_finalize(st);
	if (rc)
		goto out;
	/* The tally as `taslab study tally` computes it (flagged observers left out), without the JOD bootstrap. */
	sty_tally_desc td = {.bootstrap = 1, .seed = 1};
	for (size_t i = 0; i < x->n; i++)
		x->p[i].flagged = x->p[i].p910 = -1;
	sty_result *screen = NULL;
	char why[512];
	if (sty_tally_compute(s, &td, &x->res, x->note, sizeof x->note)) {
		x->res = NULL; /* e.g. no answered test trial yet, or only flagged observers': the note says so */
		td.keep_flagged = true; /* the screening alone, when there is something to tally */
		if (sty_tally_compute(s, &td, &screen, why, sizeof why))
			screen = NULL;
	} else {
		x->note[0] = 0;
	}
	const sty_result *sr = x->res ? x->res : screen;
	for (size_t i = 0; sr && i < sr->observer_count && i < x->n; i++)
		x->p[i].flagged = sr->observers[i].flagged, x->p[i].p910 = (int)sr->observers[i].p910; /* both in id order */
	sty_result_free(&screen);
out:
	return rc;
}

/* The status on a connection of its own, in one read transaction: WAL gives it a snapshot of what is committed, and
 * it takes no lock of the server's. The tally takes seconds for a lab's study (9.7 s for 200 participants x 22
 * trials, Release, 2026-11-28); before (found in review, 2026-11-28), it ran on the server's connection under the
 * lock every request takes, so each refresh of the status page stalled every participant that long, and it could
 * count answers of an open batch that a failing commit then took back. */
static int collect(sty *s, status *x, char *err, size_t err_size)
{
	memset(x, 0, sizeof *x);
	sty *r = NULL;
	int rc = sty_open(s->open_path, &r, err, err_size);
	if (rc)
		return rc;
	if (sqlite3_exec(r->db, "BEGIN", NULL, NULL, NULL) != SQLITE_OK) {
		rc = sty_db_fail(r, err, err_size, "status");
	} else {
		rc = collect_on(r, x, err, err_size);
		sqlite3_exec(r->db, "COMMIT", NULL, NULL, NULL);
	}
	sty_close(&r);
	return rc;
}

static void release(status *x)
{
	free(x->p);
	sty_result_free(&x->res);
}

/* The P.910-crowd flags by name, in observers.csv's order (study_result.h). */
static const struct {
	unsigned bit;
	const char *name;
} P910[] = {{STY_P910_CATCH, "catch"}, {STY_P910_GOLD, "gold"}, {STY_P910_VARIANCE, "variance"}};

static void p910_text(int flags, char *buf, size_t size)
{
	snprintf(buf, size, "%s", flags < 0 ? "-" : "");
	for (size_t k = 0, any = 0; flags > 0 && k < sizeof P910 / sizeof *P910; k++)
		if ((unsigned)flags & P910[k].bit) {
			size_t len = strlen(buf);
			snprintf(buf + len, size - len, "%s%s", any++ ? ";" : "", P910[k].name);
		}
}

static json_t *num(double v) { return isfinite(v) ? json_real(v) : json_null(); }

int sty_status_json(sty *s, char **json, char *err, size_t err_size)
{
	*json = NULL;
	status x;
	int rc = collect(s, &x, err, err_size);
	if (rc) {
		release(&x);
		return rc;
	}
	json_t *root = json_object(), *ps = json_array(), *cs = json_array();
	long answers = 0, trials = 0, completed = 0;
	for (size_t i = 0; i < x.n; i++) {
		const part *p = &x.p[i];
		answers += p->answered, trials += p->total, completed += p->total && p->answered == p->total;
		json_t *p910 = p->p910 < 0 ? json_null() : json_array();
		for (size_t k = 0; p->p910 > 0 && k < sizeof P910 / sizeof *P910; k++)
			if ((unsigned)p->p910 & P910[k].bit)
				json_array_append_new(p910, json_string(P910[k].name));
		json_array_append_new(ps, json_pack("{s:s, s:i, s:i, s:b, s:o, s:i, s:o, s:i, s:s, s:o}", "label", p->label,
						    "answered", p->answered, "total", p->total, "done",
						    p->total && p->answered == p->total, "last_activity",
						    p->last[0] ? json_string(p->last) : json_null(), "restarts", p->restarts,
						    "flagged", p->flagged < 0 ? json_null() : json_boolean(p->flagged), "broken",
						    p->broken, "broken_trials", p->broken_list, "p910", p910));
	}
	for (size_t i = 0; x.res && i < x.res->row_count; i++) {
		const sty_row *w = &x.res->rows[i];
		const sty_variant *v = &x.res->variants[w->variant];
		json_array_append_new(cs, json_pack("{s:s, s:o, s:o, s:s, s:s, s:I, s:o, s:o, s:o, s:o}", "method", v->method, "T",
						    num(v->T), "period", v->period ? json_integer(v->period) : json_null(), "scene",
						    w->scene, "camera", w->camera, "n", (json_int_t)w->n, "p_ref", num(w->j.p), "Q",
						    num(w->Q), "Q_lo", num(w->Q_lo), "Q_hi", num(w->Q_hi)));
	}
	json_object_set_new(root, "study", json_string(sty_path(s)));
	json_object_set_new(root, "participants_total", json_integer((json_int_t)x.n));
	json_object_set_new(root, "completed", json_integer(completed));
	json_object_set_new(root, "answers", json_integer(answers));
	json_object_set_new(root, "trials", json_integer(trials));
	json_object_set_new(root, "note", json_string(x.note));
	json_object_set_new(root, "participants", ps);
	json_object_set_new(root, "conditions", cs);
	*json = json_dumps(root, JSON_COMPACT);
	json_decref(root);
	release(&x);
	return *json ? TL_OK : tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
}

int sty_status_print(sty *s, FILE *f, char *err, size_t err_size)
{
	status x;
	int rc = collect(s, &x, err, err_size);
	if (rc) {
		release(&x);
		return rc;
	}
	long answers = 0, trials = 0, completed = 0;
	for (size_t i = 0; i < x.n; i++)
		answers += x.p[i].answered, trials += x.p[i].total, completed += x.p[i].total && x.p[i].answered == x.p[i].total;
	fprintf(f, "study %s: %zu participants, %ld completed, %ld of %ld trials answered\n\n", sty_path(s), x.n, completed,
		answers, trials);
	fprintf(f, "%-12s %10s  %-4s  %-24s  %8s  %-7s  %-20s  %s\n", "participant", "answered", "done", "last activity (UTC)",
		"restarts", "flagged", "p910", "broken playbacks (trial verdict)");
	for (size_t i = 0; i < x.n; i++) {
		const part *p = &x.p[i];
		char frac[32];
		snprintf(frac, sizeof frac, "%d/%d", p->answered, p->total);
		char flags[64];
		p910_text(p->p910, flags, sizeof flags);
		fprintf(f, "%-12s %10s  %-4s  %-24s  %8d  %-7s  %-20s  %s\n", p->label, frac,
			p->total && p->answered == p->total ? "yes" : "no", p->last[0] ? p->last : "-", p->restarts,
			p->flagged < 0 ? "-" : p->flagged ? "yes" : "no", flags[0] ? flags : "none", p->broken_list[0] ? p->broken_list : "-");
	}
	fprintf(f, "\n");
	if (!x.res) {
		fprintf(f, "conditions: %s\n", x.note);
	} else {
		fprintf(f, "%-14s %5s %6s  %-24s %6s %7s %7s\n", "method", "T", "period", "scene/camera", "n", "p_ref", "Q");
		for (size_t i = 0; i < x.res->row_count; i++) {
			const sty_row *w = &x.res->rows[i];
			const sty_variant *v = &x.res->variants[w->variant];
			char T[16] = "-", N[16] = "-", where[160];
			if (isfinite(v->T))
				snprintf(T, sizeof T, "%g", v->T);
			if (v->period)
				snprintf(N, sizeof N, "%u", v->period);
			snprintf(where, sizeof where, "%s/%s", w->scene, w->camera);
			fprintf(f, "%-14s %5s %6s  %-24s %6zu %7.3f %7.3f\n", v->method, T, N, where, w->n, w->j.p, w->Q);
		}
	}
	release(&x);
	return TL_OK;
}
