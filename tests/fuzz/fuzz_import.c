/* fuzz_import.c — libFuzzer harness for the ratings importer (untrusted input: a long-format CSV from elsewhere,
 * DESIGN section 7). Each input goes into a fresh study database (sty_create, never committed, so closing deletes
 * it). Properties checked beyond "no crash, leak or hang" (ASan + UBSan via scripts/fuzz import):
 *   - every failure is one line naming the file, and a failed import stores nothing;
 *   - an accepted file round-trips: export -> import into another new study -> export gives the same bytes;
 *   - the statistics (tally, without the plot) run on whatever was accepted without failing.
 * Temporary files live in a private folder (in /dev/shm when there is one: fsync is cheap there). */
#define _GNU_SOURCE /* mkdtemp, nftw */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "taslab/study.h"
#include "../test_study_methods.h"
#include "fuzz_tmp.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);


static void setup(void)
{
	fuzz_tmp_make("import", NULL);
}

static void one_line(const char *err)
{
	if (!err[0] || strchr(err, '\n'))
		__builtin_trap(); /* messages are one non-empty line */
}

/* Imports `csv` into a new study at `db`; returns the study (NULL when refused) and the exported CSV in `exp`. */
static sty *import_export(const char *csv, const char *db, const char *exp, size_t *rows, int *rc)
{
	char err[1024] = "";
	sty *s = NULL;
	if (sty_create(db, &s, err, sizeof err) || tu_describe_methods(s))
		__builtin_trap(); /* the previous input's study was deleted on close */
	*rc = sty_import_long(s, csv, rows, err, sizeof err);
	if (*rc) {
		one_line(err);
		if (!strstr(err, csv))
			__builtin_trap(); /* the message names the file */
		if (sty_export_long(s, exp, err, sizeof err))
			__builtin_trap();
		FILE *f = fopen(exp, "r");
		char line[256];
		int lines = 0;
		while (f && fgets(line, sizeof line, f))
			lines++;
		if (f)
			fclose(f);
		if (lines != 1)
			__builtin_trap(); /* all or nothing: only the header */
		sty_close(&s);
		return NULL;
	}
	if (sty_export_long(s, exp, err, sizeof err))
		__builtin_trap();
	return s;
}

static char *slurp(const char *path)
{
	FILE *f = fopen(path, "rb");
	if (!f)
		return NULL;
	fseek(f, 0, SEEK_END);
	long n = ftell(f);
	fseek(f, 0, SEEK_SET);
	char *b = malloc((size_t)n + 1);
	if (b && fread(b, 1, (size_t)n, f) != (size_t)n) {
		free(b);
		b = NULL;
	}
	if (b)
		b[n] = 0;
	fclose(f);
	return b;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	if (!fuzz_dir[0])
		setup();
	char csv[300], db[300], db2[300], e1[300], e2[300], pw[300], out[300], err[1024];
	snprintf(csv, sizeof csv, "%s/ratings.csv", fuzz_dir);
	snprintf(db, sizeof db, "%s/a.db", fuzz_dir);
	snprintf(db2, sizeof db2, "%s/b.db", fuzz_dir);
	snprintf(e1, sizeof e1, "%s/e1.csv", fuzz_dir);
	snprintf(e2, sizeof e2, "%s/e2.csv", fuzz_dir);
	snprintf(pw, sizeof pw, "%s/pw.csv", fuzz_dir);
	snprintf(out, sizeof out, "%s/tally", fuzz_dir);
	FILE *f = fopen(csv, "wb");
	if (!f || fwrite(data, 1, size, f) != size || fclose(f))
		abort();
	size_t rows = 0, rows2 = 0;
	int rc;
	sty *s = import_export(csv, db, e1, &rows, &rc);
	if (s) {
		if (sty_export_pwcmp(s, pw, err, sizeof err))
			__builtin_trap();
		mkdir(out, 0755);
		sty_tally_desc td = {.out = out, .bootstrap = 20, .seed = 1, .no_plot = true};
		if (sty_tally(s, &td, err, sizeof err))
			one_line(err); /* e.g. nothing to tally; never a crash */
		/* Round trip through the export. */
		sty *s2 = import_export(e1, db2, e2, &rows2, &rc);
		if (!s2 || rows2 != rows)
			__builtin_trap();
		char *a = slurp(e1), *b = slurp(e2);
		if (!a || !b || strcmp(a, b))
			__builtin_trap();
		free(a);
		free(b);
		sty_close(&s2);
		sty_close(&s);
	}
	return 0;
}
