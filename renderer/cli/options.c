/* options.c — option parsing for the taslab CLI (see cli.h). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"

#ifndef TASLAB_SCENES_DIR
#define TASLAB_SCENES_DIR "scenes"
#endif

static int parse_u32(const char *s, const char **end, uint32_t *out)
{
	if (*s < '0' || *s > '9')
		return -1;
	errno = 0;
	char *e;
	unsigned long v = strtoul(s, &e, 10);
	if (errno || v > 0xFFFFFFFFul)
		return -1;
	*out = (uint32_t)v;
	*end = e;
	return 0;
}

int cli_parse_size(const char *s, uint32_t *w, uint32_t *h, char *err, size_t err_size)
{
	const char *e;
	if (!s || parse_u32(s, &e, w) || (*e != 'x' && *e != 'X') || parse_u32(e + 1, &e, h) || *e ||
	    *w < 1 || *h < 1 || *w > 16384 || *h > 16384) {
		snprintf(err, err_size, "--size '%s' is not WIDTHxHEIGHT with each 1..16384 (e.g. --size 960x540)", s ? s : "");
		return -1;
	}
	return 0;
}

int cli_parse_frames(const char *s, uint32_t *a, uint32_t *b_inout, bool *b_given, char *err, size_t err_size)
{
	const char *e = s;
	uint32_t lo = 0, hi = *b_inout;
	*b_given = false;
	if (!s || !*s)
		goto bad;
	if (*e != ':' && parse_u32(e, &e, &lo))
		goto bad;
	if (*e == 0) { /* single frame */
		if (e == s)
			goto bad;
		hi = lo + 1;
		*b_given = true;
	} else if (*e == ':') {
		e++;
		if (*e) {
			if (parse_u32(e, &e, &hi) || *e)
				goto bad;
			*b_given = true;
		}
	} else {
		goto bad;
	}
	if (hi <= lo) {
		snprintf(err, err_size, "--frames '%s' is empty: A:B renders frames A..B-1, so B must exceed A", s);
		return -1;
	}
	*a = lo;
	*b_inout = hi;
	return 0;
bad:
	snprintf(err, err_size, "--frames '%s' is not A:B, A, :B or A: (e.g. --frames 0:60 for frames 0..59)", s ? s : "");
	return -1;
}

int cli_parse_float(const char *s, const char *what, double lo, double hi, double *out, char *err, size_t err_size)
{
	char *e;
	errno = 0;
	double v = s ? strtod(s, &e) : NAN;
	if (!s || !*s || *e || errno || !isfinite(v) || v < lo || v > hi) {
		snprintf(err, err_size, "%s '%s' must be a number in [%g, %g]", what, s ? s : "", lo, hi);
		return -1;
	}
	*out = v;
	return 0;
}

static int is_file(const char *p)
{
	struct stat sb;
	return stat(p, &sb) == 0 && S_ISREG(sb.st_mode);
}

int cli_resolve_scene(const char *arg, char *path, size_t path_size, char *err, size_t err_size)
{
	if (!arg || !*arg) {
		snprintf(err, err_size, "--scene needs a scene file or a built-in scene name (see 'taslab render --help')");
		return -1;
	}
	if (strchr(arg, '/') || strstr(arg, ".json") || strstr(arg, ".gltf") || strstr(arg, ".glb")) {
		snprintf(path, path_size, "%s", arg); /* a path: loading reports a missing file */
		return 0;
	}
	const char *dirs[2] = {getenv("TASLAB_SCENES"), TASLAB_SCENES_DIR};
	for (int i = 0; i < 2; i++) {
		if (!dirs[i] || !*dirs[i])
			continue;
		snprintf(path, path_size, "%s/%s.json", dirs[i], arg);
		if (is_file(path))
			return 0;
	}
	snprintf(err, err_size, "no built-in scene named '%s' in %s (give a path to a scene file, or see scenes/README.md)",
		 arg, TASLAB_SCENES_DIR);
	return -1;
}

int cli_no_args(int argc, char **argv, void (*usage)(FILE *out))
{
	if (argc > 1 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
		usage(stdout);
		return CLI_EXIT_OK;
	}
	if (argc > 1) {
		fprintf(stderr, "taslab %s: unexpected argument '%s' (see 'taslab %s --help')\n", argv[0], argv[1], argv[0]);
		return CLI_EXIT_USAGE;
	}
	return -1;
}

int cli_parse_frame_list(const char *s, uint32_t end, uint32_t *frames, size_t max, size_t *n, char *err, size_t err_size)
{
	*n = 0;
	const char *p = s;
	while (*p) {
		uint32_t a, b, step = 1;
		const char *e;
		if (parse_u32(p, &e, &a))
			goto bad;
		b = a + 1;
		if (*e == ':') {
			if (parse_u32(e + 1, &e, &b))
				goto bad;
			if (*e == ':' && (parse_u32(e + 1, &e, &step) || step == 0))
				goto bad;
			if (b <= a)
				goto bad;
		}
		if (*e && *e != ',')
			goto bad;
		for (uint32_t f = a; f < b; f += step) {
			if (f >= end) {
				snprintf(err, err_size, "analysis frame %u is outside the clip (frames 0..%u)", f, end - 1);
				return -1;
			}
			if (*n == max) {
				snprintf(err, err_size, "at most %zu analysis frames", max);
				return -1;
			}
			frames[(*n)++] = f;
		}
		p = *e ? e + 1 : e;
	}
	if (*n)
		return 0;
bad:
	snprintf(err, err_size, "bad frame list '%s' (expected comma-separated F, A:B or A:B:STEP, e.g. 60,120 or 60:300:60)", s);
	return -1;
}

int cli_parse_float_list(const char *s, const char *what, double lo, double hi, float *out, size_t max, size_t *n,
			 char *err, size_t err_size)
{
	char buf[512], *save = NULL;
	*n = 0;
	snprintf(buf, sizeof buf, "%s", s);
	for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
		double v;
		if (*n == max) {
			snprintf(err, err_size, "%s: at most %zu values", what, max);
			return -1;
		}
		if (cli_parse_float(tok, what, lo, hi, &v, err, err_size))
			return -1;
		out[(*n)++] = (float)v;
	}
	if (!*n) {
		snprintf(err, err_size, "%s: empty list", what);
		return -1;
	}
	return 0;
}
