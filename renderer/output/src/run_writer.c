/* run_writer.c — writing a run folder (run.h; DESIGN section 5). */
#include "taslab/run.h"

#include <dirent.h>
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "taslab/imageio.h"
#include "taslab/tl_clock.h"
#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"
#include "taslab/tl_hash.h"
#include "taslab/tl_json.h"
#include "taslab/version.h"

#include "method_facts.h"

struct run_writer {
	char dir[TL_PATH_MAX];
	run_info info;
	json_t *inputs;        /* run_info as JSON, built at create (the strings of run_info are borrowed) */
	tl_atomic stats;
	uint32_t frames;
	int64_t visible_total, shaded_total, fs_total;
	double *gpu_ms;
	size_t gpu_ms_cap;
	char header[4096];     /* stats.csv header of the first frame; later frames must match */
};

/* A frame file of a run: NNNNNN.png or NNNNNN.exr (six or more digits). */
static bool is_frame_name(const char *n)
{
	size_t len = strlen(n), d = 0;
	while (n[d] >= '0' && n[d] <= '9')
		d++;
	return d >= 6 && len == d + 4 && (!strcmp(n + d, ".png") || !strcmp(n + d, ".exr"));
}

/* Removes what a previous run left in the folder: frames, stats.csv, manifest.json (first), temporary files. */
static int clear_run(const char *dir, char *err, size_t err_size)
{
	char p[TL_PATH_MAX];
	const char *names[2] = {"manifest.json", "stats.csv"};
	for (int i = 0; i < 2; i++) {
		snprintf(p, sizeof p, "%s/%s", dir, names[i]);
		if (unlink(p) != 0 && errno != ENOENT)
			return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot remove the previous run's file: %s", p,
					strerror(errno));
	}
	tl_fs_clean_temps(dir);
	int rc = TL_OK;
	const char *subdirs[6] = {"frames", "decisions", "rates", "frames/L", "frames/R", "sbs"};
	for (int i = 0; i < 6 && !rc; i++) {
		snprintf(p, sizeof p, "%s/%s", dir, subdirs[i]);
		tl_fs_clean_temps(p);
		DIR *d = opendir(p);
		struct dirent *e;
		while (d && (e = readdir(d)) && !rc) {
			char f[TL_PATH_MAX];
			if (is_frame_name(e->d_name) && snprintf(f, sizeof f, "%s/%s", p, e->d_name) < (int)sizeof f &&
			    unlink(f) != 0)
				rc = tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot remove the previous run's frame: %s", f,
					      strerror(errno));
		}
		if (d)
			closedir(d);
	}
	return rc;
}

/* Decision map colours (run.h): black background, grey reused, cyan new, blue second frame, red predicted,
 * yellow scheduled. */
static const uint8_t decision_rgb[FRAME_DECISION_COUNT][3] = {
	{0, 0, 0}, {96, 96, 96}, {0, 220, 255}, {40, 90, 255}, {255, 48, 0}, {255, 210, 0}, {255, 0, 255},
};

int run_decision_code(const uint8_t rgb[3])
{
	for (int c = 0; c < FRAME_DECISION_COUNT; c++)
		if (!memcmp(rgb, decision_rgb[c], 3))
			return c;
	return -1; /* local sentinel: no decision colour (a code, not an error) */
}

/* Rate image colours (run.h), by frame_rate: red 4x4, orange 4x2, yellow 2x4, green 2x2, light blue 2x1, blue 1x2,
 * black 1x1 (coarser = warmer; full rate dark, so a frame of 1x1 tiles reads as "nothing saved"). */
static const uint8_t rate_rgb[FRAME_RATE_COUNT][3] = {
	{255, 0, 0}, {255, 150, 0}, {255, 255, 0}, {0, 200, 0}, {0, 160, 255}, {0, 0, 255}, {0, 0, 0},
};

int run_rate_code(const uint8_t rgb[3])
{
	for (int c = 0; c < FRAME_RATE_COUNT; c++)
		if (!memcmp(rgb, rate_rgb[c], 3))
			return c;
	return -1; /* local sentinel: no rate colour (a code, not an error) */
}

static int write_rates(const char *path, const frame_image *img, char *err, size_t err_size)
{
	size_t n = (size_t)img->tiles_x * img->tiles_y;
	uint8_t *rgb = malloc(n * 3);
	if (!rgb)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	for (size_t i = 0; i < n; i++) {
		if (img->tile_rates[i] >= FRAME_RATE_COUNT) {
			free(rgb);
			return tl_error(err, err_size, TL_ERR_INTERNAL, "%s: tile %zu has a rate outside the palette", path, i);
		}
		memcpy(rgb + i * 3, rate_rgb[img->tile_rates[i]], 3);
	}
	int rc = imageio_write_png_rgb8_packed(path, img->tiles_x, img->tiles_y, rgb, err, err_size);
	free(rgb);
	return rc;
}

static int write_decisions(const char *path, const frame_image *img, char *err, size_t err_size)
{
	size_t n = (size_t)img->width * img->height;
	uint8_t *rgb = malloc(n * 3);
	if (!rgb)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	for (size_t i = 0; i < n; i++) {
		uint8_t c = img->decisions[i] < FRAME_DECISION_COUNT ? img->decisions[i] : 0;
		memcpy(rgb + i * 3, decision_rgb[c], 3);
	}
	int rc = imageio_write_png_rgb8_packed(path, img->width, img->height, rgb, err, err_size);
	free(rgb);
	return rc;
}

static json_t *option_json(const run_option *o)
{
	switch (o->type) {
	case RUN_VALUE_BOOL: return json_boolean(o->boolean);
	case RUN_VALUE_STRING: return json_string(o->string ? o->string : "");
	case RUN_VALUE_INTEGER: /* a whole number in json_int_t's range; anything else stays a real */
		if (o->number == floor(o->number) && fabs(o->number) < 9007199254740992.0)
			return json_integer((json_int_t)o->number);
		return isfinite(o->number) ? json_real(o->number) : json_null();
	default: return isfinite(o->number) ? json_real(o->number) : json_null();
	}
}

static json_t *inputs_json(const run_info *in)
{
	json_t *opts = json_object(), *derived = json_object();
	for (size_t i = 0; i < in->option_count; i++)
		json_object_set_new(opts, in->options[i].key, option_json(&in->options[i]));
	for (size_t i = 0; i < in->derived_count; i++)
		json_object_set_new(derived, in->derived[i].key, option_json(&in->derived[i]));
	/* Frames as 64-bit JSON integers: a frame number is a uint32_t (an int turned frames >= 2^31 negative). */
	json_t *j = json_pack("{s:s, s:s?, s:s?, s:s, s:s, s:s?, s:s, s:s?, s:o, s:o, s:o, s:o, s:[I,I], s:[i,i], s:f}", "scene",
			 in->scene_name, "scene_digest", in->scene_digest, "colour_digest", in->colour_digest, "scene_path",
			 in->scene_path, "camera", in->camera, "camera_motion",
			 in->camera_motion, "method", in->method, "variant", in->variant, "threshold",
			 isfinite(in->threshold) ? json_real(in->threshold) : json_null(), "period",
			 in->period ? json_integer(in->period) : json_null(), "method_options", opts, "method_derived", derived, "frames",
			 (json_int_t)in->first_frame, (json_int_t)in->last_frame, "size", (int)in->width, (int)in->height, "fps",
			 (double)in->fps);
	/* What metrics and studies need to know of the method, so they need not know its name (issue 30.1). */
	if (j && in->facts.known)
		json_object_set_new(j, "method_facts", method_facts_json(&in->facts));
	if (j && in->views > 1) { /* stereo (STEREO.md); mono manifests stay as they were */
		json_object_set_new(j, "stereo", json_true());
		json_object_set_new(j, "ipd", json_real(in->ipd));
	}
	return j;
}

int run_writer_create(const char *dir, const run_info *info, run_writer **out, char *err, size_t err_size)
{
	*out = NULL;
	char frames[TL_PATH_MAX];
	if (snprintf(frames, sizeof frames, "%s/frames/L", dir) >= (int)sizeof frames)
		return tl_error(err, err_size, TL_ERR_ARG, "%s: path too long", dir);
	frames[strlen(frames) - 2] = 0; /* mono: DIR/frames */
	int rc = tl_mkdirs(frames, err, err_size);
	for (uint32_t v = 0; !rc && info->views > 1 && v < 3; v++) {
		snprintf(frames, sizeof frames, "%s/%s", dir, v < 2 ? run_view_dir(2, v) : "sbs");
		rc = tl_mkdirs(frames, err, err_size);
	}
	if (rc || (rc = clear_run(dir, err, err_size)))
		return rc;
	if (info->write_decisions) {
		snprintf(frames, sizeof frames, "%s/decisions", dir);
		if ((rc = tl_mkdirs(frames, err, err_size)))
			return rc;
	}
	if (info->write_rates) {
		snprintf(frames, sizeof frames, "%s/rates", dir);
		if ((rc = tl_mkdirs(frames, err, err_size)))
			return rc;
	}
	run_writer *w = calloc(1, sizeof *w);
	if (!w)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	snprintf(w->dir, sizeof w->dir, "%s", dir);
	w->info = *info;
	w->info.options = NULL; /* borrowed only during create: kept as JSON */
	w->info.option_count = 0;
	w->info.derived = NULL;
	w->info.derived_count = 0;
	w->inputs = inputs_json(info);
	if (!w->inputs) {
		run_writer_destroy(&w);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory describing the run");
	}
	char path[TL_PATH_MAX];
	snprintf(path, sizeof path, "%s/stats.csv", dir);
	if ((rc = tl_atomic_open(&w->stats, path, err, err_size))) {
		run_writer_destroy(&w);
		return rc;
	}
	*out = w;
	return TL_OK;
}

static void csv_int(FILE *f, int64_t v)
{
	if (v >= 0)
		fprintf(f, "%lld", (long long)v);
}

static void csv_ms(FILE *f, double v)
{
	if (v >= 0.0)
		fprintf(f, "%.4f", v);
}

static void stats_header(const frame_stats *st, char *h, size_t n)
{
	/* DESIGN section 5 columns, then one gpu_ms_<pass> per pass of the method, then taslab's additions. */
	size_t len = (size_t)snprintf(h, n, "frame,time_s,visible_samples,shaded_samples,visible_units,shaded_units,"
					    "new_units,reuse_fraction,fs_invocations,cs_invocations,gpu_ms_total");
	for (uint32_t p = 0; p < st->pass_count && len < n; p++)
		len += (size_t)snprintf(h + len, n - len, ",gpu_ms_%s", st->pass_names[p]);
	if (len < n)
		len += (size_t)snprintf(h + len, n - len, ",reused_samples,allocated_samples,late_samples");
	for (uint32_t e = 0; e < st->extra_count && len < n; e++)
		len += (size_t)snprintf(h + len, n - len, ",%s", st->extra_names[e]);
}

const char *run_view_dir(uint32_t views, uint32_t v)
{
	return views < 2 ? "frames" : v == 0 ? "frames/L" : "frames/R";
}

static int check_header(run_writer *w, const frame_stats *st, char *err, size_t err_size)
{
	char header[sizeof w->header];
	stats_header(st, header, sizeof header);
	if (w->frames == 0) {
		snprintf(w->header, sizeof w->header, "%s", header);
		fprintf(w->stats.f, "%s\n", header);
	} else if (strcmp(header, w->header)) {
		return tl_error(err, err_size, TL_ERR_INTERNAL, "frame %u: statistics columns changed within the run", st->frame);
	}
	return TL_OK;
}

/* One view's EXR and PNG into DIR/`sub`. */
static int write_images(run_writer *w, const char *sub, const frame_image *img, const frame_stats *st, char *err,
			size_t err_size)
{
	char path[TL_PATH_MAX], val[3][64];
	int rc;
	if (w->info.write_exr) {
		snprintf(val[0], sizeof val[0], "%u", st->frame);
		snprintf(val[1], sizeof val[1], "%.9g", st->time_s);
		if (isfinite(w->info.threshold))
			snprintf(val[2], sizeof val[2], "%g", w->info.threshold);
		else
			val[2][0] = 0;
		imageio_attr attrs[] = {
			{"taslab:scene", w->info.scene_name}, {"taslab:camera", w->info.camera},
			{"taslab:method", w->info.method},    {"taslab:threshold", val[2]},
			{"taslab:frame", val[0]},             {"taslab:time_s", val[1]},
		};
		snprintf(path, sizeof path, "%s/%s/%06u.exr", w->dir, sub, st->frame);
		if ((rc = imageio_write_exr_half(path, img->width, img->height, img->hdr_rgba_half, attrs,
						 sizeof attrs / sizeof attrs[0], err, err_size)))
			return rc;
	}
	if (w->info.write_png) {
		snprintf(path, sizeof path, "%s/%s/%06u.png", w->dir, sub, st->frame);
		if ((rc = imageio_write_png_rgb8(path, img->width, img->height, img->display_rgba, err, err_size)))
			return rc;
	}
	return TL_OK;
}

static int write_stats_row(run_writer *w, const frame_stats *st, char *err, size_t err_size);

int run_writer_frame(run_writer *w, const frame_image *img, const frame_stats *st, char *err, size_t err_size)
{
	char path[TL_PATH_MAX];
	int rc;
	if (w->info.views > 1)
		return tl_error(err, err_size, TL_ERR_ARG, "frame %u: a stereo run takes both eyes (run_writer_frame_views)", st->frame);
	if ((rc = check_header(w, st, err, err_size)) || (rc = write_images(w, "frames", img, st, err, err_size)))
		return rc;
	if (w->info.write_decisions) {
		if (!img->decisions)
			return tl_error(err, err_size, TL_ERR_INTERNAL, "frame %u: no decision map", st->frame);
		snprintf(path, sizeof path, "%s/decisions/%06u.png", w->dir, st->frame);
		if ((rc = write_decisions(path, img, err, err_size)))
			return rc;
	}
	if (w->info.write_rates) {
		uint32_t tx = (w->info.width + 15) / 16, ty = (w->info.height + 15) / 16;
		if (!img->tile_rates || img->tiles_x != tx || img->tiles_y != ty)
			return tl_error(err, err_size, TL_ERR_INTERNAL, "frame %u: no %ux%u tile-rate image", st->frame, tx, ty);
		snprintf(path, sizeof path, "%s/rates/%06u.png", w->dir, st->frame);
		if ((rc = write_rates(path, img, err, err_size)))
			return rc;
	}
	return write_stats_row(w, st, err, err_size);
}

int run_writer_frame_views(run_writer *w, const frame_image *imgs, uint32_t views, const frame_stats *st, char *err,
			   size_t err_size)
{
	if (w->info.views < 2 || views != w->info.views || views != 2)
		return tl_error(err, err_size, TL_ERR_ARG, "frame %u: %u views for a run of %u", st->frame, views,
				w->info.views ? w->info.views : 1);
	if (imgs[0].width != imgs[1].width || imgs[0].height != imgs[1].height)
		return tl_error(err, err_size, TL_ERR_ARG, "frame %u: the eyes differ in size", st->frame);
	int rc = check_header(w, st, err, err_size);
	for (uint32_t v = 0; !rc && v < views; v++)
		rc = write_images(w, run_view_dir(views, v), &imgs[v], st, err, err_size);
	if (rc)
		return rc;
	/* sbs/NNNNNN.png: left | right, the display PNGs' pixels side by side */
	uint32_t W = imgs[0].width, H = imgs[0].height;
	uint8_t *sbs = malloc((size_t)2 * W * H * 4);
	if (!sbs)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory for a %ux%u side-by-side frame", 2 * W, H);
	for (uint32_t y = 0; y < H; y++)
		for (uint32_t v = 0; v < 2; v++)
			memcpy(sbs + ((size_t)y * 2 * W + (size_t)v * W) * 4, imgs[v].display_rgba + (size_t)y * W * 4, (size_t)W * 4);
	char path[TL_PATH_MAX];
	snprintf(path, sizeof path, "%s/sbs/%06u.png", w->dir, st->frame);
	rc = imageio_write_png_rgb8(path, 2 * W, H, sbs, err, err_size);
	free(sbs);
	return rc ? rc : write_stats_row(w, st, err, err_size);
}

static int write_stats_row(run_writer *w, const frame_stats *st, char *err, size_t err_size)
{
	FILE *f = w->stats.f;
	/* reuse_fraction: 1 - shaded / denominator, the denominator being the allocated atlas texels for atlas
	 * methods ("fraction of the total allocated space in the atlas", paper sec. 4.3) and the visible
	 * samples for pixel methods (DESIGN section 5). */
	int64_t denom = st->allocated_samples >= 0 ? st->allocated_samples : st->visible_samples;
	double reuse = denom > 0 && st->shaded_samples >= 0 ? 1.0 - (double)st->shaded_samples / (double)denom : 0.0;
	fprintf(f, "%u,%.6f,", st->frame, st->time_s);
	csv_int(f, st->visible_samples), fputc(',', f);
	csv_int(f, st->shaded_samples), fputc(',', f);
	csv_int(f, st->visible_units), fputc(',', f);
	csv_int(f, st->shaded_units), fputc(',', f);
	csv_int(f, st->new_units), fputc(',', f);
	fprintf(f, "%.6f,", reuse);
	csv_int(f, st->fs_invocations), fputc(',', f);
	csv_int(f, st->cs_invocations), fputc(',', f);
	csv_ms(f, st->gpu_ms_total);
	for (uint32_t p = 0; p < st->pass_count; p++)
		fputc(',', f), csv_ms(f, st->gpu_ms[p]);
	fputc(',', f), csv_int(f, st->reused_samples);
	fputc(',', f), csv_int(f, st->allocated_samples);
	fputc(',', f), csv_int(f, st->late_samples);
	for (uint32_t e = 0; e < st->extra_count; e++) {
		fputc(',', f);
		if (isfinite(st->extra[e]))
			fprintf(f, "%.10g", st->extra[e]);
	}
	fputc('\n', f);
	if (ferror(f))
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s/stats.csv: write error: %s", w->dir, strerror(errno));
	if (w->frames == w->gpu_ms_cap) {
		size_t cap = w->gpu_ms_cap ? w->gpu_ms_cap * 2 : 64;
		double *n = realloc(w->gpu_ms, cap * sizeof *n);
		if (!n)
			return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		w->gpu_ms = n;
		w->gpu_ms_cap = cap;
	}
	w->gpu_ms[w->frames] = st->gpu_ms_total;
	w->frames++;
	w->visible_total += st->visible_samples > 0 ? st->visible_samples : 0;
	w->shaded_total += st->shaded_samples > 0 ? st->shaded_samples : 0;
	w->fs_total += st->fs_invocations > 0 ? st->fs_invocations : 0;
	return TL_OK;
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

int run_writer_finish(run_writer *w, double wall_s, char *err, size_t err_size)
{
	int rc = tl_atomic_commit(&w->stats, err, err_size);
	if (rc)
		return rc;
	double median = -1.0;
	if (w->frames) {
		qsort(w->gpu_ms, w->frames, sizeof *w->gpu_ms, cmp_double);
		median = w->frames % 2 ? w->gpu_ms[w->frames / 2]
				       : 0.5 * (w->gpu_ms[w->frames / 2 - 1] + w->gpu_ms[w->frames / 2]);
	}
	char created[32];
	tl_clock_utc(created, sizeof created);
	const run_info *in = &w->info;
	json_t *m = json_pack("{s:s, s:{s:s, s:s, s:s?, s:s?, s:s?}, s:s, s:O, s:{s:s, s:s, s:b}, "
			      "s:{s:b, s:b, s:b, s:b, s:s}, s:{s:I, s:I, s:I, s:I, s:f, s:f}, s:s}",
			      "taslab_version", TASLAB_VERSION_STRING, "versions", "taslab", TASLAB_VERSION_STRING, "build",
			      tl_build_digest(),
			      "opencolorio", in->ocio_version, "vulkan_api", in->vulkan_api, "vulkan_driver", in->driver,
			      "created_utc", created, "inputs", w->inputs,
			      "device", "name", in->device, "driver", in->driver, "validation", in->validation, "outputs",
			      "exr", in->write_exr, "png", in->write_png, "decisions", in->write_decisions, "rates", in->write_rates, "display_transform",
			      in->display_transform ? in->display_transform : "", "totals", "frames", (json_int_t)w->frames,
			      "visible_samples", (json_int_t)w->visible_total, "shaded_samples", (json_int_t)w->shaded_total,
			      "fs_invocations", (json_int_t)w->fs_total, "gpu_ms_median", median, "wall_s", wall_s,
			      "command", in->command_line ? in->command_line : "");
	char path[TL_PATH_MAX];
	snprintf(path, sizeof path, "%s/manifest.json", w->dir);
	rc = tl_json_write(path, m, err, err_size);
	json_decref(m);
	return rc;
}

void run_writer_destroy(run_writer **pw)
{
	if (!pw || !*pw)
		return;
	run_writer *w = *pw;
	tl_atomic_abort(&w->stats);
	json_decref(w->inputs);
	free(w->gpu_ms);
	free(w);
	*pw = NULL;
}
