/* run.c — run folder writer (see run.h; DESIGN section 5). */
#include "taslab/run.h"

#include <errno.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "taslab/imageio.h"
#include "taslab/version.h"

struct run_writer {
	char *dir;
	run_info info;
	char stats_tmp[4096], stats_final[4096];
	FILE *stats;
	uint32_t frames;
	int64_t visible_total, shaded_total, fs_total;
	double *gpu_ms;
	size_t gpu_ms_cap;
};

int run_mkdirs(const char *path, char *err, size_t err_size)
{
	char buf[4096];
	if (snprintf(buf, sizeof buf, "%s", path) >= (int)sizeof buf) {
		snprintf(err, err_size, "%s: path too long", path);
		return -1;
	}
	for (char *p = buf + 1;; p++) {
		if (*p == '/' || *p == 0) {
			char c = *p;
			*p = 0;
			if (mkdir(buf, 0777) != 0 && errno != EEXIST) {
				snprintf(err, err_size, "%s: cannot create folder: %s (choose a writable --out)", buf, strerror(errno));
				return -1;
			}
			struct stat sb;
			if (stat(buf, &sb) != 0 || !S_ISDIR(sb.st_mode)) {
				snprintf(err, err_size, "%s: exists and is not a folder (choose another --out)", buf);
				return -1;
			}
			*p = c;
			if (!c)
				break;
		}
	}
	return 0;
}

int run_writer_create(const char *dir, const run_info *info, run_writer **out, char *err, size_t err_size)
{
	*out = NULL;
	char frames[4096], manifest[4096];
	snprintf(frames, sizeof frames, "%s/frames", dir);
	snprintf(manifest, sizeof manifest, "%s/manifest.json", dir);
	if (run_mkdirs(frames, err, err_size))
		return -1;
	if (unlink(manifest) != 0 && errno != ENOENT) {
		snprintf(err, err_size, "%s: cannot remove the old manifest: %s", manifest, strerror(errno));
		return -1;
	}
	run_writer *w = calloc(1, sizeof *w);
	if (!w || !(w->dir = strdup(dir))) {
		free(w);
		snprintf(err, err_size, "out of memory");
		return -1;
	}
	w->info = *info;
	snprintf(w->stats_final, sizeof w->stats_final, "%s/stats.csv", dir);
	snprintf(w->stats_tmp, sizeof w->stats_tmp, "%s/.stats.csv.tmp%ld", dir, (long)getpid());
	w->stats = fopen(w->stats_tmp, "w");
	if (!w->stats) {
		snprintf(err, err_size, "%s: cannot write: %s (choose a writable --out)", w->stats_tmp, strerror(errno));
		run_writer_destroy(&w);
		return -1;
	}
	*out = w;
	return 0;
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

int run_writer_frame(run_writer *w, const render_image *img, const render_stats *st, char *err, size_t err_size)
{
	char path[4096], val[8][64];
	if (w->frames == 0) {
		/* DESIGN section 5 columns, then one gpu_ms_<pass> per pass of the method. */
		fprintf(w->stats, "frame,time_s,visible_samples,shaded_samples,visible_units,shaded_units,new_units,"
				  "reuse_fraction,fs_invocations,cs_invocations,gpu_ms_total");
		for (uint32_t p = 0; p < st->pass_count; p++)
			fprintf(w->stats, ",gpu_ms_%s", st->pass_names[p]);
		fprintf(w->stats, ",reused_samples\n"); /* taslab addition: visible samples shown from reuse */
	}
	if (w->info.write_exr) {
		snprintf(val[0], sizeof val[0], "%u", st->frame);
		snprintf(val[1], sizeof val[1], "%.9g", st->time_s);
		snprintf(val[2], sizeof val[2], "%g", (double)w->info.threshold);
		imageio_attr attrs[] = {
			{"taslab:scene", w->info.scene_name}, {"taslab:camera", w->info.camera},
			{"taslab:method", w->info.method},    {"taslab:threshold", val[2]},
			{"taslab:frame", val[0]},             {"taslab:time_s", val[1]},
		};
		snprintf(path, sizeof path, "%s/frames/%06u.exr", w->dir, st->frame);
		if (imageio_write_exr_half(path, img->width, img->height, img->hdr_rgba_half, attrs,
					   sizeof attrs / sizeof attrs[0], err, err_size))
			return -1;
	}
	if (w->info.write_png) {
		snprintf(path, sizeof path, "%s/frames/%06u.png", w->dir, st->frame);
		if (imageio_write_png_rgb8(path, img->width, img->height, img->display_rgba, err, err_size))
			return -1;
	}
	FILE *f = w->stats;
	double reuse = st->visible_samples > 0 && st->shaded_samples >= 0
			       ? 1.0 - (double)st->shaded_samples / (double)st->visible_samples
			       : 0.0;
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
	fputc('\n', f);
	if (ferror(f)) {
		snprintf(err, err_size, "%s: write error", w->stats_tmp);
		return -1;
	}
	if (w->frames == w->gpu_ms_cap) {
		size_t cap = w->gpu_ms_cap ? w->gpu_ms_cap * 2 : 64;
		double *n = realloc(w->gpu_ms, cap * sizeof *n);
		if (!n) {
			snprintf(err, err_size, "out of memory");
			return -1;
		}
		w->gpu_ms = n;
		w->gpu_ms_cap = cap;
	}
	w->gpu_ms[w->frames] = st->gpu_ms_total;
	w->frames++;
	w->visible_total += st->visible_samples > 0 ? st->visible_samples : 0;
	w->shaded_total += st->shaded_samples > 0 ? st->shaded_samples : 0;
	w->fs_total += st->fs_invocations > 0 ? st->fs_invocations : 0;
	return 0;
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

int run_writer_finish(run_writer *w, double wall_s, char *err, size_t err_size)
{
	int bad = fclose(w->stats) != 0;
	w->stats = NULL;
	if (bad || rename(w->stats_tmp, w->stats_final) != 0) {
		snprintf(err, err_size, "%s: cannot finish stats.csv: %s", w->dir, strerror(errno));
		return -1;
	}
	double median = -1.0;
	if (w->frames) {
		qsort(w->gpu_ms, w->frames, sizeof *w->gpu_ms, cmp_double);
		median = w->frames % 2 ? w->gpu_ms[w->frames / 2]
				       : 0.5 * (w->gpu_ms[w->frames / 2 - 1] + w->gpu_ms[w->frames / 2]);
	}
	char created[32];
	time_t now = time(NULL);
	struct tm tmv;
	gmtime_r(&now, &tmv);
	strftime(created, sizeof created, "%Y-%m-%dT%H:%M:%SZ", &tmv);
	const run_info *in = &w->info;
	json_t *m = json_pack("{s:s, s:s, s:{s:s, s:s, s:s, s:s, s:f, s:[i,i], s:[i,i], s:f}, "
			      "s:{s:s, s:s, s:b}, s:{s:b, s:b}, s:{s:i, s:I, s:I, s:I, s:f, s:f}, s:s}",
			      "taslab_version", TASLAB_VERSION_STRING, "created_utc", created,
			      "inputs", "scene", in->scene_name, "scene_path", in->scene_path, "camera", in->camera,
			      "method", in->method, "threshold", (double)in->threshold, "frames", (int)in->first_frame,
			      (int)in->last_frame, "size", (int)in->width, (int)in->height, "fps", (double)in->fps,
			      "device", "name", in->device, "driver", in->driver, "validation", in->validation,
			      "outputs", "exr", in->write_exr, "png", in->write_png,
			      "totals", "frames", (int)w->frames, "visible_samples", (json_int_t)w->visible_total,
			      "shaded_samples", (json_int_t)w->shaded_total, "fs_invocations", (json_int_t)w->fs_total,
			      "gpu_ms_median", median, "wall_s", wall_s,
			      "command", in->command_line ? in->command_line : "");
	json_object_set_new(json_object_get(m, "inputs"), "camera_motion", json_string(in->camera_motion));
	json_object_set_new(json_object_get(m, "outputs"), "display_transform",
			    json_string(in->display_transform ? in->display_transform : ""));
	if (!m) {
		snprintf(err, err_size, "cannot build manifest.json");
		return -1;
	}
	char tmp[4096], fin[4096];
	snprintf(tmp, sizeof tmp, "%s/.manifest.json.tmp%ld", w->dir, (long)getpid());
	snprintf(fin, sizeof fin, "%s/manifest.json", w->dir);
	int rc = json_dump_file(m, tmp, JSON_INDENT(2) | JSON_SORT_KEYS);
	json_decref(m);
	if (rc != 0 || rename(tmp, fin) != 0) {
		unlink(tmp);
		snprintf(err, err_size, "%s: cannot write manifest.json", w->dir);
		return -1;
	}
	return 0;
}

void run_writer_destroy(run_writer **pw)
{
	if (!pw || !*pw)
		return;
	run_writer *w = *pw;
	if (w->stats) {
		fclose(w->stats);
		unlink(w->stats_tmp);
	}
	free(w->gpu_ms);
	free(w->dir);
	free(w);
	*pw = NULL;
}
