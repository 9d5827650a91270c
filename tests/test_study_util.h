/* test_study_util.h — helpers shared by the study tests (test_study.c, test_study_stats.c): a new study that must
 * exist afterwards and a commit that fails the test on error. Header-only (static inline): each test links only
 * the study library. */
#ifndef TASLAB_TEST_STUDY_UTIL_H
#define TASLAB_TEST_STUDY_UTIL_H

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

#endif
