/* test_study.c — the study module:
 *  - statistics against R (tests/reference/study_reference.csv from study_reference.R on study_ratings.csv):
 *    Q and its t.test CI, JND via qnorm, rm-ANOVA F/p from aov, Greenhouse-Geisser epsilon and p from
 *    anova.mlm(test = "Spherical"); tolerance 1e-6 (epsilon 1e-4: R prints it with 4 decimals);
 *  - import/export round trip and all-or-nothing validation with line numbers;
 *  - randomisation: reproducible from the seed, every pair in both orders (exactly half each for even N);
 *  - the server: answers stored exactly once, bad requests 4xx changing nothing, no path outside the
 *    stimulus folder, admin token, and crash safety (SIGKILL: every acknowledged answer survives). */
#include <math.h>
#include <signal.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "taslab/study.h"
#include "taslab/study_serve.h"
#include "test_util.h"

#define REF_DIR TASLAB_SOURCE_DIR "/tests/reference"

static char out[1 << 16];

/* Value of column `col` (0-based) in the CSV row whose first `nkey` columns equal key[]. */
static double csv_lookup(const char *path, const char *const *key, int nkey, int col)
{
	FILE *f = fopen(path, "r");
	char line[1024];
	double v = NAN;
	while (f && fgets(line, sizeof line, f)) {
		char *fld[32];
		int n = 0;
		for (char *p = line, *c; n < 32; p = c + 1) {
			fld[n++] = p;
			if (!(c = strpbrk(p, ",\n")))
				break;
			int end = *c == '\n';
			*c = 0;
			if (end)
				break;
		}
		int ok = n > col;
		for (int k = 0; k < nkey && ok; k++) {
			char *x = fld[k];
			if (*x == '"')
				x++, x[strlen(x) - 1] = 0;
			ok = !strcmp(x, key[k]);
		}
		if (ok) {
			v = fld[col][0] ? strtod(fld[col], NULL) : NAN;
			break;
		}
	}
	if (f)
		fclose(f);
	return v;
}

static void test_tally_vs_r(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_tally");
	char db[4096], res[4096], err[1024], p[4096];
	snprintf(db, sizeof db, "%s/s.db", dir);
	snprintf(res, sizeof res, "%s/out", dir);
	sty *s = NULL;
	assert_int_equal(sty_open(db, true, &s, err, sizeof err), 0);
	size_t rows;
	if (sty_import_long(s, REF_DIR "/study_ratings.csv", &rows, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(rows, 144);
	sty_tally_desc td = {.out = res, .bootstrap = 200, .seed = 3};
	if (sty_tally(s, &td, err, sizeof err))
		fail_msg("%s", err);
	sty_close(&s);
	const char *ref = REF_DIR "/study_reference.csv";
	snprintf(p, sizeof p, "%s/conditions.csv", res);
	const char *Ts[2] = {"8", "16"}, *scenes[3] = {"calm", "dynamic", "moderate"}, *cams[2] = {"still", "walk"};
	int checked = 0;
	for (int t = 0; t < 2; t++)
		for (int sc = 0; sc < 3; sc++)
			for (int c = 0; c < 2; c++) {
				char k[64];
				snprintf(k, sizeof k, "%s/%s", scenes[sc], cams[c]);
				const char *ours[4] = {"tfr", Ts[t], scenes[sc], cams[c]};
				const char *kinds[4] = {"Q", "Q_lo", "Q_hi", "jnd"};
				int cols[4] = {5, 6, 7, 11};
				for (int q = 0; q < 4; q++) {
					const char *rk[3] = {kinds[q], Ts[t], k};
					double want = csv_lookup(ref, rk, 3, 3), got = csv_lookup(p, ours, 4, cols[q]);
					if (!(fabs(want - got) <= 1e-6))
						fail_msg("%s T=%s %s: ours %.9g, R %.9g", kinds[q], Ts[t], k, got, want);
					checked++;
				}
			}
	snprintf(p, sizeof p, "%s/anova.csv", res);
	const char *effects[3] = {"camera", "scene", "camera:scene"};
	for (int t = 0; t < 2; t++)
		for (int e = 0; e < 3; e++) {
			const char *ours[3] = {"tfr", Ts[t], effects[e]};
			const char *kinds[6] = {"df1", "df2", "F", "p", "p_gg", "epsilon_gg"};
			int cols[6] = {3, 4, 5, 6, 7, 8};
			for (int q = 0; q < 6; q++) {
				const char *rk[3] = {kinds[q], Ts[t], effects[e]};
				double want = csv_lookup(ref, rk, 3, 3), got = csv_lookup(p, ours, 3, cols[q]);
				if (isnan(want) && e == 0 && q >= 4) /* camera has 2 levels: sphericity holds, epsilon 1 */
					want = q == 4 ? csv_lookup(p, ours, 3, 6) : 1.0;
				double tol = q == 5 ? 1e-4 : 1e-6 * fmax(1.0, fabs(want));
				if (!(fabs(want - got) <= tol))
					fail_msg("%s T=%s %s: ours %.9g, R %.9g", kinds[q], Ts[t], effects[e], got, want);
				checked++;
			}
		}
	fprintf(stderr, "%d statistics checked against R\n", checked);
	/* Pooled rows exist, and the other outputs are there. */
	const char *pooled[4] = {"tfr", "8", "all", "all"};
	snprintf(p, sizeof p, "%s/conditions.csv", res);
	assert_false(isnan(csv_lookup(p, pooled, 4, 5)));
	const char *files[5] = {"posthoc.csv", "observers.csv", "jod.csv", "tables.md", "conditions.json"};
	for (int i = 0; i < 5; i++) {
		snprintf(p, sizeof p, "%s/%s", res, files[i]);
		assert_true(tu_file_exists(p));
	}
}

static void test_import_export(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_io");
	char db[4096], exp[4096], bad[4096], err[1024];
	snprintf(db, sizeof db, "%s/s.db", dir);
	snprintf(exp, sizeof exp, "%s/export.csv", dir);
	sty *s = NULL;
	size_t rows;
	assert_int_equal(sty_open(db, true, &s, err, sizeof err), 0);
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
			snprintf(row, sizeof row, "P03,5,moderate,walk,moving,tfr,8,0,1,-1,900"); /* rating contradicts answer */
		else if (i == 1)
			snprintf(row, sizeof row, "P07,2,moderate,still,sideways,tfr,8,1,0,0,900");
		else
			snprintf(row, sizeof row, "P10,11,dynamic,walk,moving,tfr,16,0,3,3,900");
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
	int ties = 0; /* rows whose rating (10th field) is 0 */
	for (const char *line = strchr(src, '\n'); line && line[1]; line = strchr(line + 1, '\n')) {
		const char *f = line + 1;
		for (int k = 0; k < 9; k++)
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
	sty *s = NULL;
	assert_int_equal(sty_open(db, true, &s, err, sizeof err), 0);
	sty_design_desc d = {.stimuli = stim, .participants = participants, .seed = seed, .training = 1, .catch_trials = 2,
			     .break_every = 4};
	if (sty_design(s, &d, sm, err, sizeof err))
		fail_msg("%s", err);
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

static void test_server(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_server");
	char stim[4096], err[1024], path[512], body[256];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	sty_design_summary sm;
	sty *s = designed(dir, "s.db", 5, 2, &sm);
	sty_server *sv = NULL;
	if (sty_server_start(s, NULL, 0, 2, &sv, err, sizeof err))
		fail_msg("%s", err);
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
	/* Bad requests: 4xx, and nothing stored. */
	snprintf(path, sizeof path, "/api/%s/answer", codes[0]);
	char big[6000];
	memset(big, ' ', sizeof big - 1);
	big[sizeof big - 1] = 0;
	memcpy(big, "{\"trial\":0,\"answer\":1}", 22);
	struct {
		const char *path, *body;
		int status;
	} bad[] = {
		{path, "{not json", 400},
		{path, "{\"trial\":0,\"answer\":7}", 400},
		{path, "{\"trial\":\"0\",\"answer\":1}", 400},
		{path, "{\"trial\":0,\"answer\":1,\"extra\":1,\"more\":2}", 400},
		{path, "{\"trial\":999,\"answer\":1}", 404},
		{path, big, 413},
		{"/api/00000000000000000000000000000000/answer", "{\"trial\":0,\"answer\":1}", 404},
		{"/api/xyz/answer", "{\"trial\":0,\"answer\":1}", 404},
	};
	for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
		int st = tu_http(port, "POST", bad[i].path, NULL, bad[i].body, out, sizeof out);
		if (st != bad[i].status)
			fail_msg("POST %s %.40s: %d, expected %d (%s)", bad[i].path, bad[i].body, st, bad[i].status, out);
	}
	snprintf(path, sizeof path, "/api/%s/trial", codes[0]);
	tu_http(port, "GET", path, NULL, NULL, out, sizeof out);
	assert_non_null(strstr(out, "\"answered\":0"));
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
	/* Clips: in the stimulus folder only; ranges. */
	assert_int_equal(tu_http(port, "GET", "/clips/calm-still/clips/ref.webm", "Range: bytes=5-7\r\n", NULL, out, sizeof out), 206);
	assert_string_equal(out, "ref");
	assert_int_equal(tu_http(port, "GET", "/clips/calm-still/clips/ref.webm", "Range: bytes=9999-\r\n", NULL, out, sizeof out), 416);
	assert_int_equal(tu_http(port, "GET", "/clips/../secret.txt", NULL, NULL, out, sizeof out), 403);
	assert_int_equal(tu_http(port, "GET", "/clips/calm-still/../../secret.txt", NULL, NULL, out, sizeof out), 403);
	assert_int_equal(tu_http(port, "GET", "/clips/%2e%2e/secret.txt", NULL, NULL, out, sizeof out), 403);
	assert_int_equal(tu_http(port, "GET", "/clips//etc/passwd", NULL, NULL, out, sizeof out), 403);
	assert_null(strstr(out, "root:"));
	/* Admin: token required. */
	assert_int_equal(tu_http(port, "GET", "/admin/export.csv", NULL, NULL, out, sizeof out), 403);
	assert_int_equal(tu_http(port, "GET", "/admin/export.csv?token=00", NULL, NULL, out, sizeof out), 403);
	snprintf(path, sizeof path, "/admin/export.csv?token=%s", sty_admin_token(s));
	assert_int_equal(tu_http(port, "GET", path, NULL, NULL, out, sizeof out), 200);
	assert_int_equal(tu_count_lines(out), 1 + 8); /* header + the 8 test trials (training and catch excluded) */
	sty_server_stop(&sv);
	for (size_t i = 0; i < n; i++)
		free(codes[i]);
	free(codes);
	sty_close(&s);
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
		if (sty_open(db, false, &cs, err, sizeof err) || sty_server_start(cs, NULL, 0, 4, &sv, err, sizeof err))
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

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_tally_vs_r), cmocka_unit_test(test_import_export), cmocka_unit_test(test_randomisation),
		cmocka_unit_test(test_server),     cmocka_unit_test(test_crash_safety),  cmocka_unit_test(test_cli),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
