/* fuzz_tmp.h — the fuzz harnesses' private scratch folder: made once per process (in /dev/shm when there is one,
 * where fsync is cheap, else $TMPDIR or /tmp) and removed with everything in it at exit. Header-only: each harness is
 * its own program (tests/CMakeLists.txt, TASLAB_FUZZ). */
#ifndef TASLAB_FUZZ_TMP_H
#define TASLAB_FUZZ_TMP_H

#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

static char fuzz_dir[256];

static int fuzz_rm_one(const char *p, const struct stat *sb, int flag, struct FTW *ftw)
{
	(void)sb, (void)flag, (void)ftw;
	return remove(p);
}

/* Removes the folder and everything in it (a harness's own cleanup calls it after closing what it holds open). */
static void fuzz_tmp_remove(void)
{
	if (fuzz_dir[0])
		nftw(fuzz_dir, fuzz_rm_one, 8, FTW_DEPTH | FTW_PHYS);
}

/* Makes fuzz_dir = BASE/taslab-fuzz-NAME-XXXXXX and registers CLEANUP (fuzz_tmp_remove when NULL) to run at exit. */
static void fuzz_tmp_make(const char *name, void (*cleanup)(void))
{
	const char *base = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp";
	snprintf(fuzz_dir, sizeof fuzz_dir, "%s/taslab-fuzz-%s-XXXXXX", base, name);
	if (!mkdtemp(fuzz_dir))
		abort();
	atexit(cleanup ? cleanup : fuzz_tmp_remove);
}

#endif
