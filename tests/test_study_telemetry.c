/* test_study_telemetry.c — remote participants' playback (issue 28; study_telemetry.h, README "Telemetry and
 * screening"), through the server's request logic (sty_server_handle, the code behind the libmicrohttpd adapter):
 *  - test_verdict_and_retake: the answer API takes the page's telemetry and stores it; the server's limits at their
 *    boundaries (dropped frames: more than 1 % of the frames and more than two; hidden while a clip played, not
 *    while the answer panel showed; a clip played longer than 1.5 x its 1 s duration + 1 s), a broken trial stored
 *    but not counted, its progress unchanged, retaken at the end of the plan at most twice, the tally and export
 *    honouring it; malformed telemetry refused with 400 and nothing stored;
 *  - test_older_study: a study made before the telemetry columns opens (columns added) and takes telemetry;
 *  - test_adaptive_retake: a broken adaptive trial comes back as an adaptive trial of the same group, its T chosen
 *    again when shown. */
#define _DEFAULT_SOURCE
#include <jansson.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/study.h"
#include "taslab/study_serve.h"
#include "test_study_util.h"

static void quiet(void *cls, const char *line)
{
	(void)cls;
	(void)line;
}

/* One request through the server's logic; the reply's status, its body (JSON) in *reply (may be NULL). */
static unsigned request(sty_server *sv, const char *method, const char *path, const char *body, json_t **reply)
{
	sty_request rq = {.method = method, .path = path, .body = body ? body : "", .body_size = body ? strlen(body) : 0};
	sty_response r;
	sty_server_handle(sv, &rq, &r);
	unsigned status = r.status;
	if (reply)
		*reply = r.body ? json_loadb(r.body, r.body_size, 0, NULL) : NULL;
	sty_response_release(&r);
	return status;
}

typedef struct trial_info {
	int index, answered, total, done;
} trial_info;

static trial_info next_trial(sty_server *sv, const char *code)
{
	char path[128];
	snprintf(path, sizeof path, "/api/%s/trial", code);
	json_t *j;
	assert_int_equal(request(sv, "GET", path, NULL, &j), 200);
	trial_info t = {(int)json_integer_value(json_object_get(j, "index")),
			(int)json_integer_value(json_object_get(j, "answered")),
			(int)json_integer_value(json_object_get(j, "total")), json_is_true(json_object_get(j, "done"))};
	json_decref(j);
	return t;
}

/* Telemetry: play_ms of clips A and B, dropped of frames, hidden (of them hidden_play during playback). */
static unsigned answer(sty_server *sv, const char *code, const char *session, int trial, const char *telemetry)
{
	char path[128], body[1024];
	snprintf(path, sizeof path, "/api/%s/answer", code);
	snprintf(body, sizeof body, "{\"trial\": %d, \"answer\": 1, \"rt_ms\": 900, \"session\": \"%s\"%s%s}", trial, session,
		 telemetry ? ", \"telemetry\": " : "", telemetry ? telemetry : "");
	return request(sv, "POST", path, body, NULL);
}

static const char *tel(char *buf, size_t n, int a_ms, int b_ms, int dropped, int frames, int hidden, int hidden_play)
{
	snprintf(buf, n,
		 "{\"play_ms\": [%d, %d], \"dropped\": %d, \"frames\": %d, \"hidden\": %d, \"hidden_ms\": %d, \"hidden_play\": %d,"
		 " \"fullscreen\": 1}", a_ms, b_ms, dropped, frames, hidden, hidden * 700, hidden_play);
	return buf;
}

static void start_session(sty_server *sv, const char *code, char session[33])
{
	char path[128];
	snprintf(path, sizeof path, "/api/%s/session", code);
	json_t *j;
	assert_int_equal(request(sv, "POST", path, "{}", &j), 200);
	snprintf(session, 33, "%s", json_string_value(json_object_get(j, "session")));
	json_decref(j);
}

static long long count(const char *db, const char *sql) { return db_count(db, sql); }

static void test_verdict_and_retake(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_telemetry");
	char stim[4200], db[4200], err[1024], buf[512], session[33], p[4400];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/s.db", dir);
	make_stimuli(stim); /* 8 test conditions; every clip 60 frames at 60 fps: 1000 ms */
	sty *s = created(db);
	sty_design_desc d = {.stimuli = stim, .participants = 2, .seed = 11, .catch_trials = 1};
	sty_design_summary sm;
	if (sty_design(s, &d, &sm, err, sizeof err))
		fail_msg("%s", err);
	commit(s);
	assert_int_equal(count(db, "SELECT count(*) FROM conditions WHERE clip_ms = 1000"), 12);
	sty_server_desc sd = {.log = quiet};
	sty_server *sv = NULL;
	if (sty_server_create(s, &sd, &sv, err, sizeof err))
		fail_msg("%s", err);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	start_session(sv, codes[0], session);
	/* Malformed telemetry: 400, nothing stored. */
	const char *bad[] = {
		"{\"play_ms\": [1000, 1000], \"dropped\": 5, \"frames\": 4, \"hidden\": 0, \"hidden_ms\": 0, \"hidden_play\": 0, \"fullscreen\": 0}",
		"{\"play_ms\": [1000], \"dropped\": 0, \"frames\": 4, \"hidden\": 0, \"hidden_ms\": 0, \"hidden_play\": 0, \"fullscreen\": 0}",
		"{\"play_ms\": [1000, 1000], \"dropped\": 0, \"frames\": 4, \"hidden\": 0, \"hidden_ms\": 0, \"hidden_play\": 0, \"fullscreen\": 2}",
		"{\"play_ms\": [1000, -1], \"dropped\": 0, \"frames\": 4, \"hidden\": 0, \"hidden_ms\": 0, \"hidden_play\": 0, \"fullscreen\": 0}",
		"{\"play_ms\": [1000, 1000], \"dropped\": 0, \"frames\": 4, \"hidden\": 0, \"hidden_ms\": 0, \"hidden_play\": 1, \"fullscreen\": 0}",
		"{\"play_ms\": [1000, 1000], \"dropped\": 0, \"frames\": 4, \"hidden\": 0, \"hidden_ms\": 0, \"hidden_play\": 0, \"fullscreen\": 0, \"x\": 1}",
		"{\"play_ms\": [1000, 1000], \"dropped\": 0, \"frames\": 4, \"hidden\": 0, \"hidden_ms\": 0, \"hidden_play\": 0}",
		"[1000, 1000]",
	};
	trial_info t = next_trial(sv, codes[0]);
	for (size_t i = 0; i < sizeof bad / sizeof *bad; i++)
		assert_int_equal(answer(sv, codes[0], session, t.index, bad[i]), 400);
	assert_int_equal(count(db, "SELECT count(*) FROM answers"), 0);
	/* What each planned trial gets, in plan order, and whether the server must count it. The limits at their
	 * boundaries: 2 dropped of 100 frames allowed (two always are), 3 of 100 not, 3 of 300 allowed (1 %); 2500 ms
	 * (1.5 x 1000 + 1000) allowed, 2501 not; hidden outside playback allowed, during playback not. */
	struct {
		int a, b, dropped, frames, hidden, hidden_play, counted;
		const char *why;
	} plan[9] = {
		{1010, 1005, 2, 100, 0, 0, 1, NULL},     {1010, 1005, 3, 100, 0, 0, 0, "dropped"},
		{2500, 2500, 3, 300, 0, 0, 1, NULL},     {1000, 2501, 0, 120, 0, 0, 0, "long"},
		{1000, 1000, 0, 120, 2, 0, 1, NULL},     {1000, 1000, 0, 120, 1, 1, 0, "hidden"},
		{3000, 1000, 9, 100, 1, 1, 0, "dropped;hidden;long"}, {1000, 1000, 0, 0, 0, 0, 1, NULL},
		{1000, 1000, 0, 120, 0, 0, 1, NULL},
	};
	assert_int_equal(t.total, 9);
	for (int k = 0; k < 9; k++) {
		t = next_trial(sv, codes[0]);
		assert_int_equal(t.index, k);
		assert_int_equal(t.total, 9);
		int before = t.answered;
		assert_int_equal(answer(sv, codes[0], session, t.index, tel(buf, sizeof buf, plan[k].a, plan[k].b,
			plan[k].dropped, plan[k].frames, plan[k].hidden, plan[k].hidden_play)), 200);
		snprintf(p, sizeof p, "SELECT broken IS NULL FROM answers WHERE participant = 1 AND idx = %d", k);
		assert_int_equal(count(db, p), plan[k].counted);
		if (plan[k].why) {
			snprintf(p, sizeof p, "SELECT count(*) FROM answers WHERE participant = 1 AND idx = %d AND broken = '%s'", k,
				 plan[k].why);
			assert_int_equal(count(db, p), 1);
		}
		/* progress counts planned trials: a broken one is shown again, its number unchanged */
		t = next_trial(sv, codes[0]);
		assert_int_equal(t.answered, before + plan[k].counted);
		assert_int_equal(t.total, 9);
	}
	/* The four broken trials come again after the plan, in order, with their condition and order. */
	assert_int_equal(count(db, "SELECT count(*) FROM trials WHERE participant = 1 AND retake_of IS NOT NULL"), 4);
	assert_int_equal(count(db, "SELECT count(*) FROM trials r JOIN trials o ON o.participant = r.participant AND"
				   " o.idx = r.retake_of WHERE r.participant = 1 AND r.condition = o.condition AND"
				   " r.ref_first = o.ref_first AND r.kind = o.kind AND r.break_before = 0"), 4);
	assert_int_equal(count(db, "SELECT count(*) FROM trials WHERE participant = 1 AND (idx, retake_of) IN"
				   " (VALUES (9, 1), (10, 3), (11, 5), (12, 6))"), 4);
	/* Trial 1's retakes broken again: it comes back once more (idx 13), then not (at most twice); the others counted. */
	for (int k = 9; k < 13; k++) {
		t = next_trial(sv, codes[0]);
		assert_int_equal(t.index, k);
		int broken = k == 9;
		assert_int_equal(answer(sv, codes[0], session, k, tel(buf, sizeof buf, 1000, 1000, 0, 120, broken, broken)), 200);
	}
	t = next_trial(sv, codes[0]);
	assert_int_equal(t.index, 13);
	assert_int_equal(count(db, "SELECT retake_of FROM trials WHERE participant = 1 AND idx = 13"), 1);
	assert_int_equal(answer(sv, codes[0], session, 13, tel(buf, sizeof buf, 1000, 1000, 50, 120, 0, 0)), 200);
	t = next_trial(sv, codes[0]);
	assert_int_equal(t.done, 1);
	assert_int_equal(t.answered, 9);
	assert_int_equal(t.total, 9);
	assert_int_equal(count(db, "SELECT count(*) FROM trials WHERE participant = 1"), 14);
	assert_int_equal(count(db, "SELECT count(*) FROM answers WHERE participant = 1 AND broken IS NOT NULL"), 6);
	assert_int_equal(count(db, "SELECT count(*) FROM answers WHERE participant = 1 AND fullscreen = 1 AND"
				   " total_frames IS NOT NULL AND play_a_ms > 0"), 14);
	/* Participant 2 answers every trial without telemetry (an API client): every answer counts. */
	start_session(sv, codes[1], session);
	for (t = next_trial(sv, codes[1]); !t.done; t = next_trial(sv, codes[1]))
		assert_int_equal(answer(sv, codes[1], session, t.index, NULL), 200);
	assert_int_equal(count(db, "SELECT count(*) FROM answers WHERE participant = 2 AND broken IS NULL"), 9);
	/* The tally leaves the broken answers out: n of the pooled rows sums the counted test answers. */
	long long counted = count(db, "SELECT count(*) FROM answers a JOIN trials t USING(participant, idx) WHERE"
				      " t.kind = 'test' AND a.broken IS NULL");
	long long all = count(db, "SELECT count(*) FROM answers a JOIN trials t USING(participant, idx) WHERE t.kind = 'test'");
	assert_true(all > counted);
	char res[4300];
	snprintf(res, sizeof res, "%s/tally", dir);
	sty_tally_desc td = {.out = res, .bootstrap = 10, .seed = 1, .no_plot = true, .keep_flagged = true};
	if (sty_tally(s, &td, err, sizeof err))
		fail_msg("%s", err);
	snprintf(p, sizeof p, "%s/conditions.csv", res);
	double pooled = 0;
	const char *Ts[2] = {"8", "16"};
	for (int i = 0; i < 2; i++) {
		const char *key[5] = {"tfr", Ts[i], "", "all", "all"};
		pooled += tu_csv_lookup(p, key, 5, 5);
	}
	assert_int_equal((long long)pooled, counted);
	snprintf(p, sizeof p, "%s/observers.csv", res);
	const char *key1[1] = {"P001"}, *key2[1] = {"P002"};
	assert_int_equal((int)tu_csv_lookup(p, key1, 1, 5), 6); /* broken */
	assert_int_equal((int)tu_csv_lookup(p, key2, 1, 5), 0);
	/* The export carries every answer with its telemetry and verdict; the pwcmp export only counted test answers. */
	char csv[4300];
	snprintf(csv, sizeof csv, "%s/export.csv", dir);
	assert_int_equal(sty_export_long(s, csv, err, sizeof err), 0);
	char *text = tu_read_file(csv, NULL);
	assert_non_null(strstr(text, ",hidden_play,fullscreen,broken,retake_of\n"));
	assert_non_null(strstr(text, ",1000,2501,0,120,0,0,0,1,long,\n"));
	assert_non_null(strstr(text, ",1000,1000,50,120,0,0,0,1,dropped,1\n"));
	free(text);
	/* ... and reads back: a new study from the export has the same answers, verdicts and retakes. */
	char db2[4300];
	snprintf(db2, sizeof db2, "%s/back.db", dir);
	sty *s2 = created(db2);
	size_t rows;
	if (sty_import_long(s2, csv, &rows, err, sizeof err))
		fail_msg("%s", err);
	commit(s2);
	assert_int_equal(rows, 14 + 9);
	assert_int_equal(count(db2, "SELECT count(*) FROM answers WHERE broken IS NOT NULL"), 6);
	assert_int_equal(count(db2, "SELECT count(*) FROM trials WHERE retake_of IS NOT NULL"), 5);
	assert_int_equal(count(db2, "SELECT sum(play_b_ms) FROM answers WHERE broken = 'long'"), 2501);
	char csv2[4300];
	snprintf(csv2, sizeof csv2, "%s/export2.csv", dir);
	assert_int_equal(sty_export_long(s2, csv2, err, sizeof err), 0);
	char *a = tu_read_file(csv, NULL), *b = tu_read_file(csv2, NULL);
	assert_string_equal(strchr(a, '\n'), strchr(b, '\n')); /* participants keep their labels */
	free(a);
	free(b);
	sty_close(&s2);
	free_codes(codes, n);
	sty_server_stop(&sv);
	sty_close(&s);
}

/* A study made before issue 28's columns (dropped here as an older taslab never had them) opens with them added. */
static void test_older_study(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_telemetry_old");
	char stim[4200], err[1024], buf[512], session[33];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s = designed(dir, "old.db", 3, 1, &sm);
	sty_close(&s);
	char db[4300];
	snprintf(db, sizeof db, "%s/old.db", dir);
	sqlite3 *h;
	assert_int_equal(sqlite3_open(db, &h), SQLITE_OK);
	const char *drop = "ALTER TABLE conditions DROP COLUMN clip_ms; ALTER TABLE trials DROP COLUMN retake_of;"
			   "ALTER TABLE answers DROP COLUMN play_a_ms; ALTER TABLE answers DROP COLUMN play_b_ms;"
			   "ALTER TABLE answers DROP COLUMN dropped_frames; ALTER TABLE answers DROP COLUMN total_frames;"
			   "ALTER TABLE answers DROP COLUMN hidden; ALTER TABLE answers DROP COLUMN hidden_ms;"
			   "ALTER TABLE answers DROP COLUMN hidden_play; ALTER TABLE answers DROP COLUMN fullscreen;"
			   "ALTER TABLE answers DROP COLUMN broken;";
	assert_int_equal(sqlite3_exec(h, drop, NULL, NULL, NULL), SQLITE_OK);
	sqlite3_close(h);
	assert_int_equal(count(db, "SELECT count(*) FROM pragma_table_info('answers') WHERE name = 'broken'"), 0);
	if (sty_open(db, &s, err, sizeof err) || tu_describe_methods(s))
		fail_msg("%s", err);
	assert_int_equal(count(db, "SELECT count(*) FROM pragma_table_info('answers') WHERE name = 'broken'"), 1);
	assert_int_equal(count(db, "SELECT count(*) FROM pragma_table_info('trials') WHERE name = 'retake_of'"), 1);
	assert_int_equal(count(db, "SELECT count(*) FROM conditions WHERE clip_ms IS NULL"), 12);
	sty_server_desc sd = {.log = quiet};
	sty_server *sv = NULL;
	if (sty_server_create(s, &sd, &sv, err, sizeof err))
		fail_msg("%s", err);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	start_session(sv, codes[0], session);
	/* no clip duration known: no "long" verdict, the others still apply */
	trial_info t = next_trial(sv, codes[0]);
	assert_int_equal(answer(sv, codes[0], session, t.index, tel(buf, sizeof buf, 60000, 60000, 0, 10, 0, 0)), 200);
	t = next_trial(sv, codes[0]);
	assert_int_equal(answer(sv, codes[0], session, t.index, tel(buf, sizeof buf, 1000, 1000, 0, 10, 1, 1)), 200);
	assert_int_equal(count(db, "SELECT count(*) FROM answers WHERE broken IS NULL AND play_a_ms = 60000"), 1);
	assert_int_equal(count(db, "SELECT count(*) FROM answers WHERE broken = 'hidden'"), 1);
	free_codes(codes, n);
	sty_server_stop(&sv);
	sty_close(&s);
}

/* An adaptive trial whose playback was broken comes back as an adaptive trial of the same group. */
static void test_adaptive_retake(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_telemetry_adaptive");
	char stim[4200], db[4200], err[1024], buf[512], session[33];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/a.db", dir);
	make_stimuli(stim);
	sty *s = created(db);
	sty_design_desc d = {.stimuli = stim, .participants = 1, .seed = 5, .adaptive = true, .trials = 2};
	sty_design_summary sm;
	if (sty_design(s, &d, &sm, err, sizeof err))
		fail_msg("%s", err);
	commit(s);
	sty_server_desc sd = {.log = quiet};
	sty_server *sv = NULL;
	if (sty_server_create(s, &sd, &sv, err, sizeof err))
		fail_msg("%s", err);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), 0);
	start_session(sv, codes[0], session);
	trial_info t = next_trial(sv, codes[0]);
	assert_int_equal(t.index, 0);
	assert_int_equal(answer(sv, codes[0], session, 0, tel(buf, sizeof buf, 1000, 1000, 0, 120, 1, 1)), 200);
	assert_int_equal(count(db, "SELECT count(*) FROM adaptive_trials a JOIN adaptive_trials o ON o.participant ="
				   " a.participant AND o.idx = 0 WHERE a.idx = 2 AND a.grp = o.grp AND a.resolved = 0"), 1);
	t = next_trial(sv, codes[0]);
	assert_int_equal(answer(sv, codes[0], session, t.index, tel(buf, sizeof buf, 1000, 1000, 0, 120, 0, 0)), 200);
	t = next_trial(sv, codes[0]);
	assert_int_equal(t.index, 2);
	assert_int_equal(t.answered, 1);
	assert_int_equal(t.total, 2);
	/* shown: its T chosen now, from the group's levels */
	assert_int_equal(count(db, "SELECT resolved FROM adaptive_trials WHERE idx = 2"), 1);
	assert_int_equal(count(db, "SELECT count(*) FROM trials t JOIN conditions c ON c.id = t.condition JOIN trials o ON"
				   " o.participant = t.participant AND o.idx = 0 JOIN conditions g ON g.id = o.condition WHERE"
				   " t.idx = 2 AND c.scene = g.scene AND c.camera = g.camera AND c.method = g.method"), 1);
	assert_int_equal(answer(sv, codes[0], session, 2, tel(buf, sizeof buf, 1000, 1000, 0, 120, 0, 0)), 200);
	assert_int_equal(next_trial(sv, codes[0]).done, 1);
	free_codes(codes, n);
	sty_server_stop(&sv);
	sty_close(&s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_verdict_and_retake),
		cmocka_unit_test(test_older_study),
		cmocka_unit_test(test_adaptive_retake),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
