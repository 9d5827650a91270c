/* test_study_adaptive.c — the adaptive design in the study database (issue 28; study_adaptive_db.c):
 *  - test_adaptive_plan: `--adaptive --trials N` gives every participant N test trials (+ training and catch), each
 *    aimed at a scene x camera path in turn; the T of a trial is chosen when it is shown, from the group's levels;
 *    the same seed and the same answers replay the same trials (conditions and presentation orders);
 *  - test_sigkill: a process that chose a trial is killed with SIGKILL; after reopening, the next trial is the same
 *    trial with the same condition and the same clip names;
 *  - test_adaptive_args: --adaptive without --trials (and --trials without --adaptive) is refused;
 *  - test_adaptive_prior: --prior MODEL.json stores each group's prior with the design and moves QUEST+'s first
 *    choice to the predicted level (8 or 16); a model without predictions, or --prior without --adaptive, is refused. */
#define _DEFAULT_SOURCE /* popen (test_study_util.h) */
#include <signal.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "taslab/study.h"
#include "test_study_util.h"

static sty *adaptive_study(const char *dir, const char *name, uint64_t seed)
{
	char db[4096], stim[4096], err[1024];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/%s", dir, name);
	sty *s = created(db);
	sty_design_summary sm;
	sty_design_desc d = {.stimuli = stim, .participants = 4, .seed = seed, .training = 1, .catch_trials = 2,
			     .adaptive = true, .trials = 6};
	if (sty_design(s, &d, &sm, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(sm.trials_per_participant, 1 + 6 + 2);
	commit(s);
	return s;
}

/* A simulated participant: T16 is seen (the reference preferred, +1 in its reference-relative rating), T8 is not
 * (the test clip preferred in one trial of three, else "same"); catch and training trials "same". Returns the
 * answer to give on the five-point scale as the page shows it. */
static int answer_for(sty *s, const sty_trial *t, int k)
{
	char rel_a[4096], rel_b[4096], err[256];
	assert_int_equal(sty_clip_file(s, t->clip_a, rel_a, sizeof rel_a, err, sizeof err), TL_OK);
	assert_int_equal(sty_clip_file(s, t->clip_b, rel_b, sizeof rel_b, err, sizeof err), TL_OK);
	int ref_first = strstr(rel_a, "/ref.webm") != NULL;
	const char *test = ref_first ? rel_b : rel_a;
	int rating = strstr(test, "T16") ? 1 : strstr(test, "T8") ? (k % 3 == 0 ? -1 : 0) : 0;
	return ref_first ? -rating : rating; /* + = second clip better */
}

/* Runs every participant of `s` to the end (participants in turn, one trial each); returns the plan afterwards. */
static char *run_all(sty *s, const char *db)
{
	char **codes, err[256];
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), TL_OK);
	for (int k = 0, busy = 1; busy; k++) {
		busy = 0;
		for (size_t i = 0; i < n; i++) {
			sty_trial t;
			if (sty_next_trial(s, codes[i], &t, err, sizeof err))
				fail_msg("%s", err);
			if (t.done)
				continue;
			busy = 1;
			if (sty_answer(s, codes[i], t.index, answer_for(s, &t, k), 900, err, sizeof err))
				fail_msg("%s", err);
		}
	}
	free_codes(codes, n);
	sqlite3 *h;
	sqlite3_stmt *st;
	assert_int_equal(sqlite3_open_v2(db, &h, SQLITE_OPEN_READONLY, NULL), SQLITE_OK);
	assert_int_equal(sqlite3_prepare_v2(h, "SELECT t.participant, t.idx, t.kind, c.scene, c.camera, c.T, t.ref_first,"
					       " g.scene, g.camera, a.resolved FROM trials t JOIN conditions c ON c.id ="
					       " t.condition LEFT JOIN adaptive_trials a ON a.participant = t.participant AND"
					       " a.idx = t.idx LEFT JOIN conditions g ON g.id = a.grp ORDER BY 1, 2", -1, &st,
					       NULL), SQLITE_OK);
	size_t cap = 1 << 16, len = 0;
	char *buf = calloc(cap, 1);
	int tests = 0, t16 = 0;
	while (sqlite3_step(st) == SQLITE_ROW && len + 128 < cap) {
		const char *kind = (const char *)sqlite3_column_text(st, 2);
		if (!strcmp(kind, "test")) { /* chosen (resolved), from its own group, at one of the group's levels */
			tests++;
			assert_int_equal(sqlite3_column_int(st, 9), 1);
			assert_string_equal(sqlite3_column_text(st, 3), sqlite3_column_text(st, 7));
			assert_string_equal(sqlite3_column_text(st, 4), sqlite3_column_text(st, 8));
			double T = sqlite3_column_double(st, 5);
			assert_true(T == 8 || T == 16);
			t16 += T == 16;
		}
		len += (size_t)snprintf(buf + len, cap - len, "%d %d %s %s/%s T%g %d\n", sqlite3_column_int(st, 0),
					sqlite3_column_int(st, 1), kind, sqlite3_column_text(st, 3), sqlite3_column_text(st, 4),
					sqlite3_column_double(st, 5), sqlite3_column_int(st, 6));
	}
	sqlite3_finalize(st);
	sqlite3_close(h);
	assert_int_equal(tests, 4 * 6);
	assert_true(t16 > 0 && t16 < tests); /* QUEST+ used both levels */
	return buf;
}

static void test_adaptive_plan(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_adaptive");
	char stim[4096], a[4096], b[4096];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	snprintf(a, sizeof a, "%s/a.db", dir);
	snprintf(b, sizeof b, "%s/b.db", dir);
	sty *s1 = adaptive_study(dir, "a.db", 5), *s2 = adaptive_study(dir, "b.db", 5);
	/* every test trial planned as adaptive, none chosen before it is shown */
	assert_int_equal(db_count(a, "SELECT count(*) FROM adaptive_trials WHERE resolved = 0"), 4 * 6);
	assert_int_equal(db_count(a, "SELECT count(*) FROM trials WHERE kind = 'test'"), 4 * 6);
	assert_int_equal(db_count(a, "SELECT count(*) FROM trials WHERE kind = 'catch'"), 4 * 2);
	/* each participant's 6 trials go to the 4 groups in turn: every group 1 or 2 times */
	assert_int_equal(db_count(a, "SELECT count(*) FROM (SELECT participant, grp, count(*) n FROM adaptive_trials GROUP"
				     " BY 1, 2) WHERE n NOT IN (1, 2)"), 0);
	char *p1 = run_all(s1, a), *p2 = run_all(s2, b);
	assert_string_equal(p1, p2); /* the same seed and answers: the same trials */
	sty_close(&s1);
	sty_close(&s2);
	/* the tally of an adaptive study fits thresholds from the chosen levels */
	sty *s = NULL;
	char err[1024], res[4096];
	snprintf(res, sizeof res, "%s/res", dir);
	assert_int_equal(sty_open(a, &s, err, sizeof err), TL_OK);
	assert_int_equal(tu_describe_methods(s), 0);
	sty_tally_desc td = {.out = res, .bootstrap = 10, .seed = 1, .no_plot = true};
	if (sty_tally(s, &td, err, sizeof err))
		fail_msg("%s", err);
	sty_close(&s);
	char path[4200];
	snprintf(path, sizeof path, "%s/thresholds.csv", res);
	const char *all[4] = {"tfr", "", "all", "all"};
	assert_int_equal((int)tu_csv_lookup(path, all, 4, 4), 24);
	free(p1);
	free(p2);
}

static void test_sigkill(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_adaptive_kill");
	char stim[4096], db[4096], err[1024];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	snprintf(db, sizeof db, "%s/k.db", dir);
	sty *s = adaptive_study(dir, "k.db", 9);
	char **codes;
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), TL_OK);
	/* answer participant 1's training trial and first two trials, so that the next one is chosen from answers */
	const char *next_is_test = "SELECT kind = 'test' AND idx > 2 FROM trials WHERE participant = 1 AND idx = (SELECT"
				   " min(idx) FROM trials WHERE participant = 1 AND idx NOT IN (SELECT idx FROM answers"
				   " WHERE participant = 1))";
	for (int k = 0; db_count(db, next_is_test) != 1; k++) {
		sty_trial t;
		assert_int_equal(sty_next_trial(s, codes[0], &t, err, sizeof err), TL_OK);
		assert_int_equal(sty_answer(s, codes[0], t.index, answer_for(s, &t, k), 900, err, sizeof err), TL_OK);
	}
	sty_close(&s);
	int fd[2];
	assert_int_equal(pipe(fd), 0);
	pid_t pid = fork();
	if (pid == 0) { /* the server: shows participant 1's next trial (an adaptive one), then dies without closing */
		sty *c = NULL;
		sty_trial t;
		char e[256];
		if (sty_open(db, &c, e, sizeof e) || tu_describe_methods(c) || sty_next_trial(c, codes[0], &t, e, sizeof e))
			_exit(3);
		if (write(fd[1], &t, sizeof t) != (ssize_t)sizeof t)
			_exit(4);
		kill(getpid(), SIGKILL);
	}
	close(fd[1]);
	sty_trial before, after;
	assert_int_equal(read(fd[0], &before, sizeof before), (ssize_t)sizeof before);
	close(fd[0]);
	int status;
	assert_int_equal(waitpid(pid, &status, 0), pid);
	assert_true(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
	char q[512];
	snprintf(q, sizeof q, "SELECT condition FROM trials t JOIN adaptive_trials a USING(participant, idx) WHERE"
		 " t.participant = 1 AND t.idx = %u AND a.resolved = 1", before.index);
	long long chosen = db_count(db, q);
	assert_true(chosen > 0);
	assert_int_equal(sty_open(db, &s, err, sizeof err), TL_OK);
	assert_int_equal(sty_next_trial(s, codes[0], &after, err, sizeof err), TL_OK);
	assert_int_equal(after.index, before.index);
	assert_string_equal(after.clip_a, before.clip_a);
	assert_string_equal(after.clip_b, before.clip_b);
	assert_int_equal(db_count(db, q), chosen);
	sty_close(&s);
	free_codes(codes, n);
}

static void test_adaptive_args(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_adaptive_args");
	char stim[4096], db[4096], err[1024];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	snprintf(db, sizeof db, "%s/x.db", dir);
	sty *s = created(db);
	sty_design_summary sm;
	sty_design_desc d = {.stimuli = stim, .participants = 2, .seed = 1, .adaptive = true};
	assert_int_equal(sty_design(s, &d, &sm, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "--trials"));
	d.adaptive = false;
	d.trials = 4;
	assert_int_equal(sty_design(s, &d, &sm, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "--adaptive"));
	sty_close(&s);
}

/* A MODEL.json as 'study model --predict' writes it (the members sty_model_prior reads): every group of make_stimuli
 * predicted at t_jnd = T with an interval of +-0.2 octave (prior SD 0.1 octave). */
static void write_model(const char *path, double T)
{
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	fprintf(f, "{\"metric\": \"flip_mean\", \"interval_half_width_log2\": 0.2, \"predictions\": [");
	const char *g[4][2] = {{"calm", "still"}, {"calm", "walk"}, {"dynamic", "still"}, {"dynamic", "walk"}};
	for (int i = 0; i < 4; i++)
		fprintf(f, "%s{\"method\": \"tfr\", \"period\": null, \"scene\": \"%s\", \"camera\": \"%s\", \"t_jnd\": %g, "
			   "\"t_jnd_lo\": 1, \"t_jnd_hi\": 100}", i ? ", " : "", g[i][0], g[i][1], T);
	fprintf(f, "]}\n");
	fclose(f);
}

/* Participant 1's first adaptive trial: its T once chosen (earlier trials answered "same"). */
static double first_adaptive_T(sty *s, const char *db)
{
	char **codes, err[256];
	size_t n;
	assert_int_equal(sty_participant_codes(s, &codes, &n, err, sizeof err), TL_OK);
	double T = 0;
	for (int k = 0; k < 20 && T == 0; k++) {
		sty_trial t;
		assert_int_equal(sty_next_trial(s, codes[0], &t, err, sizeof err), TL_OK);
		if (db_count(db, "SELECT count(*) FROM adaptive_trials WHERE resolved = 1") > 0)
			T = (double)db_count(db, "SELECT c.T FROM adaptive_trials a JOIN trials t USING(participant, idx) JOIN"
						 " conditions c ON c.id = t.condition WHERE a.resolved = 1");
		else
			assert_int_equal(sty_answer(s, codes[0], t.index, 0, 900, err, sizeof err), TL_OK);
	}
	free_codes(codes, n);
	return T;
}

/* design --adaptive --prior MODEL.json (issue 28): each group's prior is stored with the design and moves QUEST+'s
 * first choice to the level the model predicts; without --adaptive, or with a file that holds no predictions, the
 * design is refused with one line. */
static void test_adaptive_prior(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("study_adaptive_prior");
	char stim[4096], err[1024], m8[4096], m16[4096], db[3][4096];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	make_stimuli(stim);
	snprintf(m8, sizeof m8, "%s/m8.json", dir);
	snprintf(m16, sizeof m16, "%s/m16.json", dir);
	write_model(m8, 8);
	write_model(m16, 16);
	const char *models[3] = {m8, m16, NULL};
	double first[3];
	for (int i = 0; i < 3; i++) {
		snprintf(db[i], sizeof db[i], "%s/p%d.db", dir, i);
		sty *s = created(db[i]);
		sty_design_summary sm;
		sty_design_desc d = {.stimuli = stim, .participants = 2, .seed = 3, .adaptive = true, .trials = 4,
				     .prior = models[i]};
		if (sty_design(s, &d, &sm, err, sizeof err))
			fail_msg("%s", err);
		commit(s);
		assert_int_equal(sm.groups, 4);
		assert_int_equal(sm.priors, models[i] ? 4 : 0);
		assert_int_equal(db_count(db[i], "SELECT count(*) FROM adaptive_prior"), models[i] ? 4 : 0);
		first[i] = first_adaptive_T(s, db[i]);
		sty_close(&s);
	}
	printf("# first adaptive T: prior at 8 -> %g, prior at 16 -> %g, no prior -> %g\n", first[0], first[1], first[2]);
	assert_true(first[0] == 8 && first[1] == 16);

	char db4[4096], bad[4096];
	snprintf(db4, sizeof db4, "%s/x.db", dir);
	snprintf(bad, sizeof bad, "%s/bad.json", dir);
	FILE *f = fopen(bad, "w");
	fprintf(f, "{\"metric\": \"flip_mean\"}\n");
	fclose(f);
	sty *s = created(db4);
	sty_design_summary sm;
	sty_design_desc d = {.stimuli = stim, .participants = 2, .seed = 1, .adaptive = true, .trials = 4, .prior = bad};
	assert_int_equal(sty_design(s, &d, &sm, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "--predict"));
	d.adaptive = false, d.trials = 0, d.prior = m8;
	assert_int_equal(sty_design(s, &d, &sm, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "--prior goes with --adaptive"));
	sty_close(&s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_adaptive_plan),
		cmocka_unit_test(test_sigkill),
		cmocka_unit_test(test_adaptive_args),
		cmocka_unit_test(test_adaptive_prior),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
