/* cmd_tonemap.c — `taslab tonemap`: scene-linear EXR frames to display PNGs through the CPU OpenColorIO
 * processor (the same view transform the renderer applies on the GPU; colour.h). */
#include <dirent.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <unistd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "commands.h"
#include "taslab/colour.h"
#include "taslab/imageio.h"
#include "taslab/run.h"
#include "taslab/tl_fs.h"

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

/* An OpenEXR file by its content (magic number 20000630), whatever its name. */
static bool is_exr(const char *path)
{
	unsigned char m[4] = {0};
	FILE *f = fopen(path, "rb");
	size_t n = f ? fread(m, 1, 4, f) : 0;
	if (f)
		fclose(f);
	return n == 4 && m[0] == 0x76 && m[1] == 0x2f && m[2] == 0x31 && m[3] == 0x01;
}

/* Tone-maps one frame into `out` (a tl_atomic of the set, detached: committed with the others by the caller). */
static int tonemap_one(const colour *c, const char *in, tl_atomic *out, char *err, size_t err_size)
{
	uint32_t w, h;
	float *px = NULL;
	/* The input is scene-linear: a PNG (or anything else) is display-referred already, and tone-mapping it again
	 * gives wrong colours that look like a result. */
	if (!is_exr(in))
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: not an OpenEXR file; tonemap converts scene-linear EXR frames "
				"(a PNG is display-referred already)", in);
	int rc = imageio_read_rgba_float(in, &w, &h, &px, 1, err, err_size);
	if (rc)
		return rc;
	colour_apply(c, px, (size_t)w * h, 4);
	uint8_t *rgb = malloc((size_t)w * h * 3);
	if (!rgb) {
		free(px);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	for (size_t i = 0; i < (size_t)w * h; i++)
		for (int ch = 0; ch < 3; ch++) {
			float v = px[i * 4 + ch];
			v = v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);
			rgb[i * 3 + ch] = (uint8_t)lrintf(v * 255.0f);
		}
	/* Written to a temporary file now (flushed and closed, so a full disk shows here), renamed with the others only
	 * when every frame succeeded. The lock is given up: a long run would hold one descriptor per frame. */
	char path[TL_PATH_MAX];
	snprintf(path, sizeof path, "%s", out->path);
	if ((rc = tl_atomic_open(out, path, err, err_size)) == TL_OK) {
		if ((rc = imageio_write_png_stream(out->f, path, w, h, rgb, err, err_size)))
			tl_atomic_abort(out);
		else if ((rc = tl_atomic_detach(out, err, err_size)) == TL_OK)
			tl_atomic_unlock(out);
	}
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
	tl_atomic *outs; /* one per frame: the set committed at the end */
	atomic_size_t next;
	atomic_int failed;
	int rc;
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
		char in[8192], err[1024];
		snprintf(in, sizeof in, "%s/%s", j->dir, j->names[i]);
		int rc = TL_OK;
		if (snprintf(j->outs[i].path, sizeof j->outs[i].path, "%s/%.*s.png", j->outd, (int)strlen(j->names[i]) - 4,
			     j->names[i]) >= (int)sizeof j->outs[i].path)
			rc = tl_error(err, sizeof err, TL_ERR_ARG, "%s: output path too long", j->names[i]);
		if (!rc)
			rc = tonemap_one(j->c, in, &j->outs[i], err, sizeof err);
		if (rc) {
			pthread_mutex_lock(&j->lock);
			if (!atomic_exchange(&j->failed, 1)) {
				snprintf(j->err, sizeof j->err, "%s", err);
				j->rc = rc;
			}
			pthread_mutex_unlock(&j->lock);
			return NULL;
		}
	}
}

static const cli_opt tonemap_options[] = {
	{.name = "out", .arg = "DIR",
	 .help = "output folder (default: INPUT/tonemapped, or next to a single file)",
	 .type = CLI_STRING, .offset = offsetof(tonemap_opts, out)},
	{0},
};

static int tonemap_main(void *opts, cli_ctx *ctx)
{
	tonemap_opts *o = opts;
	const char *input = ctx->pos[0], *out_dir = o->out;
	const colour *c = ctx->setup.colour;
	char *err = ctx->err;
	size_t err_size = sizeof ctx->err;
	char dir[4096], frames[4096], outd[4096];
	char **names = NULL;
	size_t n = 0;
	if (tl_is_dir(input)) {
		/* a run folder is checked against its manifest first: a missing, extra or mixed-size frame gave a gapped PNG
		 * sequence and exit 0 (issue 31.8) */
		snprintf(frames, sizeof frames, "%s/manifest.json", input);
		bool is_run = tl_is_file(frames);
		snprintf(frames, sizeof frames, "%s/frames", input);
		if (is_run || tl_is_dir(frames)) {
			run_manifest m;
			int crc = run_check(input, &m, err, err_size);
			if (!crc && !m.exr)
				crc = tl_error(err, err_size, TL_ERR_INPUT,
					       "%s: the run was rendered with --no-exr: no scene-linear frames to tone-map", input);
			if (crc)
				return crc;
		}
		snprintf(dir, sizeof dir, "%s", tl_is_dir(frames) ? frames : input);
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
		if (stat(input, &sb) != 0)
			return tl_error(err, err_size, TL_ERR_INPUT, "%s: no such file or folder", input);
		const char *slash = strrchr(input, '/');
		if (slash == input)
			snprintf(dir, sizeof dir, "/");
		else
			snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - input) : 1, slash ? input : ".");
		names = malloc(sizeof *names);
		names[n++] = strdup(slash ? slash + 1 : input);
		snprintf(outd, sizeof outd, "%s%s", out_dir ? out_dir : dir, out_dir ? "" : "/tonemapped");
	}
	int rc = TL_OK;
	if (n == 0) {
		rc = tl_error(err, err_size, TL_ERR_INPUT, "no .exr files in %s", dir);
		goto done;
	}
	/* Never write over the inputs: the PNGs of a run's frames folder are the renderer's own frames. */
	if (tl_same_path(outd, dir)) {
		rc = tl_error(err, err_size, TL_ERR_ARG,
			      "--out %s is the folder of the input frames: tone-mapped PNGs would replace the run's own PNGs "
			      "(choose another --out)", outd);
		goto done;
	}
	/* The PNGs appear together when every frame is done, or none does (a bad frame, a full disk): a failed
	 * tonemap leaves the folder as it was, and removes a folder it made. */
	bool made_dir = !tl_is_dir(outd);
	tl_atomic *outs = calloc(n, sizeof *outs);
	if (!outs) {
		rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		goto done;
	}
	if ((rc = tl_mkdirs(outd, err, err_size))) {
		free(outs);
		goto done;
	}
	qsort(names, n, sizeof *names, cmp_str);
	tonemap_job job = {.c = c, .dir = dir, .outd = outd, .names = names, .n = n, .outs = outs};
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
		rc = tl_error(err, err_size, job.rc, "%s", job.err);
		tl_atomic_abort_set(outs, n);
	} else {
		rc = tl_atomic_commit_set(outs, n, err, err_size);
	}
	free(outs);
	if (rc) {
		if (made_dir)
			rmdir(outd);
		goto done;
	}
	fprintf(stderr, "taslab: tone-mapped %zu frame(s) to %s (%s)\n", n, outd, colour_name(c));
done:
	for (size_t i = 0; i < n; i++)
		free(names[i]);
	free(names);
	return rc;
}

const cli_command cli_cmd_tonemap = {
	.name = "tonemap",
	.summary = "EXR frames to display PNGs through the CPU OpenColorIO processor",
	.synopsis = "taslab tonemap INPUT [--out DIR] [--ocio-config F] [--display D] [--view V]",
	.description = "Converts scene-linear EXR frames to display-referred 8-bit PNGs with the CPU OpenColorIO processor\n"
		       "(the same view transform the renderer applies on the GPU; the result matches within 1 code value).\n"
		       "INPUT is a run folder (its frames/*.exr), a folder of .exr files, or one .exr file.\n"
		       "Output: DIR/NAME.png for each NAME.exr. Default transform: $OCIO if set, else ACES 1.0 SDR-video\n"
		       "on an sRGB display.",
	.options = tonemap_options,
	.opts_size = sizeof(tonemap_opts),
	.needs = CLI_NEED_COLOUR,
	.min_pos = 1,
	.max_pos = 1,
	.pos_help = "INPUT (a run folder, a folder of .exr files or one .exr)",
	.run = tonemap_main,
};
