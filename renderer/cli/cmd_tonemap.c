/* cmd_tonemap.c — `taslab tonemap`: scene-linear EXR frames to display PNGs through the CPU OpenColorIO
 * processor (the same view transform the renderer applies on the GPU; colour.h). */
#include <dirent.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <unistd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "taslab/colour.h"
#include "taslab/imageio.h"
#include "taslab/run.h"

static void tonemap_usage(FILE *out)
{
	fprintf(out, "usage: taslab tonemap INPUT [--out DIR] [--ocio-config F] [--display D] [--view V]\n\n"
		     "Converts scene-linear EXR frames to display-referred 8-bit PNGs with the CPU OpenColorIO processor.\n"
		     "INPUT is a run folder (its frames/*.exr), a folder of .exr files, or one .exr file.\n"
		     "Output: DIR/NAME.png for each NAME.exr (default DIR: INPUT/tonemapped, or next to a single file).\n"
		     "Default transform: $OCIO if set, else ACES 1.0 SDR-video on an sRGB display.\n");
}

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

static int is_dir(const char *p)
{
	struct stat sb;
	return stat(p, &sb) == 0 && S_ISDIR(sb.st_mode);
}

static int tonemap_one(const colour *c, const char *in, const char *out, char *err, size_t err_size)
{
	uint32_t w, h;
	float *px = NULL;
	if (imageio_read_rgba_float(in, &w, &h, &px, 1, err, err_size))
		return -1;
	colour_apply(c, px, (size_t)w * h, 4);
	uint8_t *rgb = malloc((size_t)w * h * 3);
	if (!rgb) {
		free(px);
		snprintf(err, err_size, "out of memory");
		return -1;
	}
	for (size_t i = 0; i < (size_t)w * h; i++)
		for (int ch = 0; ch < 3; ch++) {
			float v = px[i * 4 + ch];
			v = v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);
			rgb[i * 3 + ch] = (uint8_t)lrintf(v * 255.0f);
		}
	int rc = imageio_write_png_rgb8_packed(out, w, h, rgb, err, err_size);
	free(rgb);
	free(px);
	return rc;
}

/* Frames are independent: worker threads take the next frame index until done or one fails. */
typedef struct tonemap_job {
	const colour *c;
	const char *dir, *outd;
	char **names;
	size_t n;
	atomic_size_t next;
	atomic_int failed;
	pthread_mutex_t lock;
	char err[1024];
} tonemap_job;

static void *tonemap_worker(void *arg)
{
	tonemap_job *j = arg;
	for (;;) {
		size_t i = atomic_fetch_add(&j->next, 1);
		if (i >= j->n || atomic_load(&j->failed))
			return NULL;
		char in[8192], out[8192], err[1024];
		snprintf(in, sizeof in, "%s/%s", j->dir, j->names[i]);
		snprintf(out, sizeof out, "%s/%.*s.png", j->outd, (int)strlen(j->names[i]) - 4, j->names[i]);
		if (tonemap_one(j->c, in, out, err, sizeof err)) {
			pthread_mutex_lock(&j->lock);
			if (!atomic_exchange(&j->failed, 1))
				snprintf(j->err, sizeof j->err, "%s", err);
			pthread_mutex_unlock(&j->lock);
			return NULL;
		}
	}
}

static int tonemap_run(int argc, char **argv)
{
	const char *input = NULL, *out_dir = NULL;
	colour_desc cd = {0};
	char err[1024];
	for (int i = 1; i < argc; i++) {
		const char **dst = NULL;
		if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
			tonemap_usage(stdout);
			return CLI_EXIT_OK;
		} else if (!strcmp(argv[i], "--out"))
			dst = &out_dir;
		else if (!strcmp(argv[i], "--ocio-config"))
			dst = &cd.config_path;
		else if (!strcmp(argv[i], "--display"))
			dst = &cd.display;
		else if (!strcmp(argv[i], "--view"))
			dst = &cd.view;
		else if (argv[i][0] == '-') {
			fprintf(stderr, "taslab tonemap: unknown option '%s' (see 'taslab tonemap --help')\n", argv[i]);
			return CLI_EXIT_USAGE;
		} else if (!input) {
			input = argv[i];
			continue;
		} else {
			fprintf(stderr, "taslab tonemap: one INPUT only ('%s' is extra)\n", argv[i]);
			return CLI_EXIT_USAGE;
		}
		if (i + 1 >= argc) {
			fprintf(stderr, "taslab tonemap: %s needs a value\n", argv[i]);
			return CLI_EXIT_USAGE;
		}
		*dst = argv[++i];
	}
	if (!input) {
		fprintf(stderr, "taslab tonemap: INPUT is required (a run folder, a folder of .exr files or one .exr)\n");
		return CLI_EXIT_USAGE;
	}
	char dir[4096], frames[4096], outd[4096];
	char **names = NULL;
	size_t n = 0;
	if (is_dir(input)) {
		snprintf(frames, sizeof frames, "%s/frames", input);
		snprintf(dir, sizeof dir, "%s", is_dir(frames) ? frames : input);
		DIR *d = opendir(dir);
		struct dirent *e;
		while (d && (e = readdir(d))) {
			size_t len = strlen(e->d_name);
			if (len > 4 && !strcmp(e->d_name + len - 4, ".exr") && e->d_name[0] != '.') {
				char **nn = realloc(names, (n + 1) * sizeof *names);
				if (!nn)
					break;
				names = nn;
				names[n++] = strdup(e->d_name);
			}
		}
		if (d)
			closedir(d);
		snprintf(outd, sizeof outd, "%s", out_dir ? out_dir : input);
		if (!out_dir)
			strncat(outd, "/tonemapped", sizeof outd - strlen(outd) - 1);
	} else {
		struct stat sb;
		if (stat(input, &sb) != 0) {
			fprintf(stderr, "taslab tonemap: %s: no such file or folder\n", input);
			return CLI_EXIT_USAGE;
		}
		const char *slash = strrchr(input, '/');
		if (slash == input)
			snprintf(dir, sizeof dir, "/");
		else
			snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - input) : 1, slash ? input : ".");
		names = malloc(sizeof *names);
		names[n++] = strdup(slash ? slash + 1 : input);
		snprintf(outd, sizeof outd, "%s", out_dir ? out_dir : dir);
	}
	int status = CLI_EXIT_OK;
	colour *c = NULL;
	if (n == 0) {
		fprintf(stderr, "taslab tonemap: no .exr files in %s\n", dir);
		status = CLI_EXIT_USAGE;
		goto done;
	}
	if (colour_create(&cd, &c, err, sizeof err)) {
		fprintf(stderr, "taslab tonemap: %s\n", err);
		status = CLI_EXIT_USAGE;
		goto done;
	}
	if (run_mkdirs(outd, err, sizeof err)) {
		fprintf(stderr, "taslab tonemap: %s\n", err);
		status = CLI_EXIT_FAILURE;
		goto done;
	}
	qsort(names, n, sizeof *names, cmp_str);
	tonemap_job job = {.c = c, .dir = dir, .outd = outd, .names = names, .n = n};
	pthread_mutex_init(&job.lock, NULL);
	long cores = sysconf(_SC_NPROCESSORS_ONLN);
	size_t nt = cores < 1 ? 1 : (size_t)cores > n ? n : (size_t)(cores > 16 ? 16 : cores);
	pthread_t th[16];
	size_t started = 0;
	for (; started < nt; started++)
		if (pthread_create(&th[started], NULL, tonemap_worker, &job))
			break;
	if (started == 0)
		tonemap_worker(&job);
	for (size_t t = 0; t < started; t++)
		pthread_join(th[t], NULL);
	pthread_mutex_destroy(&job.lock);
	if (atomic_load(&job.failed)) {
		fprintf(stderr, "taslab tonemap: %s\n", job.err);
		status = CLI_EXIT_FAILURE;
		goto done;
	}
	fprintf(stderr, "taslab: tone-mapped %zu frame(s) to %s (%s)\n", n, outd, colour_name(c));
done:
	for (size_t i = 0; i < n; i++)
		free(names[i]);
	free(names);
	colour_destroy(&c);
	return status;
}

const cli_command cli_cmd_tonemap = {"tonemap", "EXR frames to display PNGs through the CPU OpenColorIO processor",
				     tonemap_run, tonemap_usage};
