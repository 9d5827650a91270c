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
/* Runs a shell command; returns its exit status; stdout+stderr captured into `out`. */
int tu_run(const char *cmd, char *out, size_t out_size);
int tu_file_exists(const char *path);
/* Reads a whole file; caller frees. */
char *tu_read_file(const char *path, size_t *len);
/* Number of '\n'-terminated lines in s. */
int tu_count_lines(const char *s);
/* Runs `taslab ARGS` (TASLAB_BINARY) and fails the test unless it exits non-zero with exactly one line of output
 * containing `needle`. */
void tu_expect_cli_error(const char *args, const char *needle);


/* Minimal HTTP/1.0 client for loopback tests: sends METHOD PATH (with BODY and extra header lines
 * `headers`, may be NULL) to 127.0.0.1:port; returns the status code (or -1) and the response body. */
int tu_http(int port, const char *method, const char *path, const char *headers, const char *body, char *resp,
	    size_t resp_size);

#endif
