/* test_util.h — helpers shared by the tests. */
#ifndef TASLAB_TEST_UTIL_H
#define TASLAB_TEST_UTIL_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

/* A fresh empty folder under the build tree (TASLAB_TMP) for one test; returns its path. */
const char *tu_tmpdir(const char *name);
/* The environment for the taslab processes a test starts ("export VAR=value; ..." to put before a shell command):
 * LeakSanitizer on (with LSAN_OPTIONS from the test's environment: lsan.supp, intercept_tls_get_addr=0), lavapipe
 * and the validation layer pinned by the preloaded lsan_pin.c, a small quarantine. A leak makes the process exit
 * non-zero, so the test that ran it fails. */
const char *tu_child_env(void);
/* Runs a shell command (with tu_child_env); returns its exit status; stdout+stderr captured into `out`. */
int tu_run(const char *cmd, char *out, size_t out_size);
/* tu_run of a printf-formatted command. */
int tu_runf(char *out, size_t out_size, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
int tu_file_exists(const char *path);
/* Reads a whole file; caller frees. */
char *tu_read_file(const char *path, size_t *len);
/* Number of '\n'-terminated lines in s. */
int tu_count_lines(const char *s);
/* Value of column `col` (0-based) in the CSV row of `path` whose first `nkey` columns equal key[] (quotes around a
 * key cell ignored); NaN when there is no such row or the cell is empty. */
double tu_csv_lookup(const char *path, const char *const *key, int nkey, int col);
/* An IEEE half float (the HDR frames' and EXR's storage) as a float: normals, subnormals and signed zero exactly;
 * exponent 31 (inf, NaN) is not decoded (the frames hold none). */
float tu_half_to_float(uint16_t h);
/* Runs `taslab ARGS` (TASLAB_BINARY) and fails the test unless it exits non-zero with exactly one line of output
 * containing `needle`. */
void tu_expect_cli_error(const char *args, const char *needle);

/* Missing prerequisites (../shared, root, a tmpfs mount, ...). A test that passes when what it tests is absent proves
 * nothing, so under CI (the environment variable CI set and non-empty) a missing prerequisite fails the test; outside
 * CI the part that needs it is skipped and says so. tu_require(ok, fmt, ...) returns 1 when ok (go on); otherwise,
 * under CI it fails the current test with "missing prerequisite (CI): <what>", outside CI it prints
 * "SKIPPED: <what>", remembers it and returns 0 (the caller leaves its part out, or calls skip()).
 * `what` says what was left out and how to provide it. tu_finish(failures) ends main: with no failure but a skipped
 * part it prints the SKIPPED lines again and returns TU_SKIPPED (ctest's SKIP_RETURN_CODE, tests/CMakeLists.txt), so
 * ctest's summary lists the test as skipped; scripts/test prints every SKIPPED line after the summary. */
#define TU_SKIPPED 77
int tu_ci(void);
int tu_require(int ok, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
int tu_finish(int failures);


/* Minimal HTTP/1.0 client for loopback tests: sends METHOD PATH (with BODY and extra header lines
 * `headers`, may be NULL) to 127.0.0.1:port; returns the status code (or -1) and the response body. */
int tu_http(int port, const char *method, const char *path, const char *headers, const char *body, char *resp,
	    size_t resp_size);

#endif
