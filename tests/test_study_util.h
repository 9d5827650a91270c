/* test_study_util.h — helpers shared by the study tests (test_study*.c): a new study that must exist afterwards, a
 * commit that fails the test on error, a count from the database, the four-set stimulus folder and a study designed
 * from it, and small file helpers. Header-only (static inline): each test links only the study library. */
#ifndef TASLAB_TEST_STUDY_UTIL_H
#define TASLAB_TEST_STUDY_UTIL_H

#include <sqlite3.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/study.h"
#include "test_study_methods.h"
#include "test_util.h"

#define REF_DIR TASLAB_SOURCE_DIR "/tests/reference"

/* A new study at `db` (must not exist), knowing the registry's methods as `taslab study` does. */
static inline sty *created(const char *db)
{
	char err[1024] = "describing the methods failed";
	sty *s = NULL;
	if (sty_create(db, &s, err, sizeof err) || tu_describe_methods(s))
		fail_msg("%s", err);
	return s;
}

static inline void commit(sty *s)
{
	char err[1024];
	if (sty_commit(s, err, sizeof err))
		fail_msg("%s", err);
}

/* The one integer a query on the database file `db` returns (read-only), -1 on error. */
static inline long long db_count(const char *db, const char *sql)
{
	sqlite3 *h;
	sqlite3_stmt *st;
	long long v = -1;
	if (sqlite3_open_v2(db, &h, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK &&
	    sqlite3_prepare_v2(h, sql, -1, &st, NULL) == SQLITE_OK) {
		if (sqlite3_step(st) == SQLITE_ROW)
			v = sqlite3_column_int64(st, 0);
		sqlite3_finalize(st);
	}
	sqlite3_close(h);
	return v;
}

/* Four pair sets (2 scenes x stationary/moving), conditions tfr@8 and tfr@16, small files as clips. */
static inline void make_stimuli(const char *root)
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

/* A committed study `dir`/`name` designed from `dir`/stimuli (make_stimuli): 1 training trial, 2 catch trials, a break
 * every 4. */
static inline sty *designed(const char *dir, const char *name, uint64_t seed, uint32_t participants, sty_design_summary *sm)
{
	char db[4096], stim[4096], err[1024];
	snprintf(stim, sizeof stim, "%s/stimuli", dir);
	snprintf(db, sizeof db, "%s/%s", dir, name);
	sty *s = created(db);
	sty_design_desc d = {.stimuli = stim, .participants = participants, .seed = seed, .training = 1, .catch_trials = 2,
			     .break_every = 4};
	if (sty_design(s, &d, sm, err, sizeof err))
		fail_msg("%s", err);
	commit(s);
	return s;
}

/* Frees what sty_participant_codes returned. */
static inline void free_codes(char **codes, size_t n)
{
	for (size_t i = 0; i < n; i++)
		free(codes[i]);
	free(codes);
}

/* Entries of a folder (ls -A), -1 when it cannot be listed. */
static inline int dir_entries(const char *dir)
{
	char cmd[4200];
	snprintf(cmd, sizeof cmd, "ls -A '%s' | wc -l", dir);
	FILE *p = popen(cmd, "r");
	int n = -1;
	if (p && fscanf(p, "%d", &n) != 1)
		n = -1;
	if (p)
		pclose(p);
	return n;
}

#endif
