/* test_util.c — helpers shared by the tests. */
#include "test_util.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>

#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

const char *tu_tmpdir(const char *name)
{
	static char path[4096];
	const char *base = getenv("TASLAB_TMP");
	if (!base)
		base = "/tmp/taslab-tests";
	char cmd[8192];
	snprintf(path, sizeof path, "%s/%s", base, name);
	snprintf(cmd, sizeof cmd, "rm -rf '%s' && mkdir -p '%s'", path, path);
	if (system(cmd) != 0)
		fail_msg("cannot create %s", path);
	return path;
}

const char *tu_child_env(void)
{
	/* verify_asan_link_order=0: the preloaded pin library comes before the ASan runtime in the initial library list
	 * (it only calls dlopen). A small quarantine (also set for in-process tests in tests/CMakeLists.txt) keeps
	 * use-after-free checks for our allocations while lavapipe's large per-submission buffers bypass it: with the
	 * default 256 MB each of them lands on fresh pages, which made the TFR analysis 7x slower. */
	return "export LD_PRELOAD=" TASLAB_LSAN_PIN " ASAN_OPTIONS=detect_leaks=1:verify_asan_link_order=0:quarantine_size_mb=8;";
}

int tu_runf(char *out, size_t out_size, const char *fmt, ...)
{
	char cmd[16384];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(cmd, sizeof cmd, fmt, ap);
	va_end(ap);
	return tu_run(cmd, out, out_size);
}

int tu_run(const char *cmd, char *out, size_t out_size)
{
	char full[16384];
	snprintf(full, sizeof full, "%s %s 2>&1", tu_child_env(), cmd);
	FILE *p = popen(full, "r");
	if (!p)
		return -1;
	size_t n = fread(out, 1, out_size - 1, p);
	out[n] = 0;
	int st = pclose(p);
	return WIFEXITED(st) ? WEXITSTATUS(st) : 128;
}

int tu_file_exists(const char *path)
{
	struct stat sb;
	return stat(path, &sb) == 0;
}

char *tu_read_file(const char *path, size_t *len)
{
	FILE *f = fopen(path, "rb");
	if (!f)
		return NULL;
	fseek(f, 0, SEEK_END);
	long n = ftell(f);
	fseek(f, 0, SEEK_SET);
	char *buf = malloc((size_t)n + 1);
	if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) {
		free(buf);
		buf = NULL;
	}
	fclose(f);
	if (buf) {
		buf[n] = 0;
		if (len)
			*len = (size_t)n;
	}
	return buf;
}

int tu_count_lines(const char *s)
{
	int n = 0;
	for (; *s; s++)
		n += *s == '\n';
	return n;
}

int tu_http(int port, const char *method, const char *path, const char *headers, const char *body, char *resp,
	    size_t resp_size)
{
	int fd = socket(AF_INET, SOCK_STREAM, 0);
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	if (fd < 0 || connect(fd, (struct sockaddr *)&sa, sizeof sa)) {
		if (fd >= 0)
			close(fd);
		return -1;
	}
	char req[16384];
	size_t bl = body ? strlen(body) : 0;
	int n = snprintf(req, sizeof req, "%s %s HTTP/1.0\r\nHost: 127.0.0.1\r\nContent-Length: %zu\r\n%s\r\n", method, path, bl,
			 headers ? headers : "");
	if (write(fd, req, (size_t)n) != n || (bl && write(fd, body, bl) != (ssize_t)bl)) {
		close(fd);
		return -1;
	}
	size_t got = 0;
	ssize_t r;
	char *buf = malloc(1 << 20);
	while (buf && got < (1 << 20) - 1 && (r = read(fd, buf + got, (1 << 20) - 1 - got)) > 0)
		got += (size_t)r;
	close(fd);
	if (!buf)
		return -1;
	buf[got] = 0;
	int status = -1;
	sscanf(buf, "HTTP/1.%*d %d", &status);
	char *b = strstr(buf, "\r\n\r\n");
	snprintf(resp, resp_size, "%s", b ? b + 4 : "");
	free(buf);
	return status;
}

void tu_expect_cli_error(const char *args, const char *needle)
{
	char cmd[8192], out[8192];
	snprintf(cmd, sizeof cmd, "%s %s", TASLAB_BINARY, args);
	int st = tu_run(cmd, out, sizeof out);
	if (st == 0 || tu_count_lines(out) != 1 || !strstr(out, needle))
		fail_msg("'%s' (exit %d) printed:\n%s\nexpected a failure with one line containing '%s'", cmd, st, out, needle);
}

int tu_ci(void)
{
	const char *ci = getenv("CI");
	return ci && ci[0];
}

static char tu_skipped[4096];

int tu_require(int ok, const char *fmt, ...)
{
	if (ok)
		return 1;
	char what[1024];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(what, sizeof what, fmt, ap);
	va_end(ap);
	if (tu_ci())
		fail_msg("missing prerequisite (CI is set, so this fails instead of skipping): %s", what);
	fprintf(stderr, "SKIPPED: %s\n", what);
	size_t used = strlen(tu_skipped);
	snprintf(tu_skipped + used, sizeof tu_skipped - used, "SKIPPED: %s\n", what);
	return 0;
}

int tu_finish(int failures)
{
	if (failures || !tu_skipped[0])
		return failures;
	fprintf(stderr, "%s", tu_skipped);
	return TU_SKIPPED;
}

/* Value of column `col` (0-based) in the CSV row whose first `nkey` columns equal key[]. */
double tu_csv_lookup(const char *path, const char *const *key, int nkey, int col)
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

float tu_half_to_float(uint16_t h)
{
	uint32_t e = (h >> 10) & 31u, m = h & 1023u;
	float v = e == 0 ? ldexpf((float)m, -24) : ldexpf((float)(m | 1024u), (int)e - 25);
	return h & 0x8000u ? -v : v;
}
