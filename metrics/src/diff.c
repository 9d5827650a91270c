/* diff.c — comparing two frame sequences into frames.csv / summary.json / heatmaps / plots (metrics_diff.h). */
#include "taslab/metrics_diff.h"

#include <dirent.h>
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "taslab/imageio.h"
#include "taslab/run.h"
#include "taslab/metrics_flip.h"
#include "taslab/tl_clock.h"
#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"
#include "taslab/tl_json.h"

typedef struct sequence {
	char dir[4096];
	char **names; /* sorted file names with the chosen extension */
	size_t n;
	uint32_t w, h; /* a run folder's frame size from its manifest; 0 for a folder of images */
} sequence;

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

static int is_dir(const char *p)
{
	struct stat sb;
	return stat(p, &sb) == 0 && S_ISDIR(sb.st_mode);
}

static void sequence_free(sequence *s)
{
	for (size_t i = 0; i < s->n; i++)
		free(s->names[i]);
	free(s->names);
	s->names = NULL;
	s->n = 0;
}

/* The views of PATH: 2 for a stereo run (frames/L, frames/R), 1 for a mono run or a folder of images. A run folder
 * without a manifest or with a bad one is reported by sequence_open. */
static uint32_t path_views(const char *path)
{
	char frames[4096], err[256];
	snprintf(frames, sizeof frames, "%s/frames", path);
	run_manifest m;
	if (!is_dir(frames) || run_manifest_read(path, &m, err, sizeof err))
		return 1;
	return m.views > 1 ? m.views : 1;
}

/* Opens view `view` of PATH (a run with `views` views, or a folder of images when `views` is 1 and PATH has no
 * frames/). */
static int sequence_open(const char *path, const char *ext, uint32_t views, uint32_t view, sequence *s, char *err,
			 size_t err_size)
{
	memset(s, 0, sizeof *s);
	char frames[4096];
	snprintf(frames, sizeof frames, "%s/frames", path);
	if (!is_dir(path))
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: not a folder (give a run folder or a folder of images)", path);
	/* A run folder (DESIGN section 5) holds exactly the frames of its manifest: an incomplete run (no manifest.json),
	 * frames outside the manifest's range (a stale longer run), missing ones (a --no-png run) and frames of another
	 * size are refused here or when decoded, instead of being compared. */
	if (is_dir(frames)) {
		char manifest[4200];
		snprintf(manifest, sizeof manifest, "%s/manifest.json", path);
		if (!tl_is_file(manifest))
			return tl_error(err, err_size, TL_ERR_INPUT, "%s: a run folder without manifest.json (an incomplete or failed "
					"render): render it again, or give %s to compare its images as they are", path, frames);
		run_manifest m;
		int rc = run_manifest_read(path, &m, err, err_size);
		if (rc || (rc = run_check_frames(path, &m, ext + 1, err, err_size)))
			return rc;
		s->w = m.width;
		s->h = m.height;
		snprintf(frames, sizeof frames, "%s/%s", path, run_view_dir(views, view));
	}
	snprintf(s->dir, sizeof s->dir, "%s", is_dir(frames) ? frames : path);
	DIR *d = opendir(s->dir);
	struct dirent *e;
	size_t el = strlen(ext);
	while (d && (e = readdir(d))) {
		size_t len = strlen(e->d_name);
		if (len > el && !strcmp(e->d_name + len - el, ext) && e->d_name[0] != '.') {
			char **nn = realloc(s->names, (s->n + 1) * sizeof *nn);
			char *dup = strdup(e->d_name);
			if (!nn || !dup) {
				free(dup);
				if (nn)
					s->names = nn;
				closedir(d);
				return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
			}
			s->names = nn;
			s->names[s->n++] = dup;
		}
	}
	if (d)
		closedir(d);
	if (s->n == 0)
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: no %s frames", s->dir, ext);
	qsort(s->names, s->n, sizeof *s->names, cmp_str);
	return 0;
}

/* A decoded frame pair, display-referred floats 0..255. */
typedef struct pair_buf {
	float *a, *b;
	uint32_t w, h;
	uint32_t wb, hb; /* size of b (equal to w, h unless the pair is refused) */
	int rc;
	char err[1024];
} pair_buf;

/* Decodes one frame into display floats. `reuse` (may be NULL) is a buffer of `reuse_n` floats from an earlier frame:
 * taken when large enough (fresh 25 MB buffers per 1080p frame cost page faults), freed otherwise. */
static int load_frame(const mtr_diff_desc *d, const char *path, float *reuse, size_t reuse_n, float **rgb, uint32_t *w,
		      uint32_t *h, char *err, size_t err_size)
{
	*rgb = NULL;
	if (d->format == MTR_FORMAT_PNG) {
		uint8_t *px = NULL;
		int rc = imageio_read_rgb8_as(path, IMAGEIO_FORMAT_PNG, w, h, &px, err, err_size);
		if (rc) {
			free(reuse);
			return rc;
		}
		size_t n = (size_t)*w * *h * 3;
		if (reuse && reuse_n >= n)
			*rgb = reuse;
		else
			free(reuse), *rgb = malloc(n * sizeof **rgb);
		if (*rgb)
			for (size_t i = 0; i < n; i++)
				(*rgb)[i] = px[i];
		free(px);
	} else {
		float *px = NULL;
		free(reuse);
		int rc = imageio_read_rgba_float_as(path, IMAGEIO_FORMAT_EXR, w, h, &px, 1, err, err_size);
		if (rc)
			return rc;
		size_t n = (size_t)*w * *h;
		colour_apply(d->colour, px, n, 4);
		*rgb = malloc(n * 3 * sizeof **rgb);
		if (*rgb)
			for (size_t i = 0; i < n; i++)
				for (int c = 0; c < 3; c++) {
					float v = px[i * 4 + c];
					(*rgb)[i * 3 + c] = 255.0f * (v < 0 ? 0 : (v > 1 ? 1 : v));
				}
		free(px);
	}
	if (!*rgb)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	return TL_OK;
}

typedef struct loader {
	const mtr_diff_desc *d;
	const sequence *ra, *rb;
	size_t index;
	pair_buf *out;
	float *reuse[2]; /* buffers of an earlier pair (owned by the loader from here on), or NULL */
	size_t reuse_n[2]; /* their sizes in floats */
} loader;

typedef struct frame_job {
	const mtr_diff_desc *d;
	char path[8192];
	float *reuse, *rgb;
	size_t reuse_n;
	uint32_t w, h;
	int rc;
	char err[1024];
} frame_job;

static void *frame_main(void *p)
{
	frame_job *j = p;
	j->rc = load_frame(j->d, j->path, j->reuse, j->reuse_n, &j->rgb, &j->w, &j->h, j->err, sizeof j->err);
	return NULL;
}

/* Decodes the pair's two frames in parallel (PNG decoding is most of the end-to-end time). */
static void load_pair(loader *l)
{
	pair_buf *o = l->out;
	frame_job *j = calloc(2, sizeof *j);
	if (!j) {
		free(l->reuse[0]);
		free(l->reuse[1]);
		o->rc = tl_error(o->err, sizeof o->err, TL_ERR_NOMEM, "out of memory");
		return;
	}
	j[0].d = j[1].d = l->d;
	j[0].reuse = l->reuse[0], j[1].reuse = l->reuse[1], j[0].reuse_n = l->reuse_n[0], j[1].reuse_n = l->reuse_n[1];
	snprintf(j[0].path, sizeof j[0].path, "%s/%s", l->ra->dir, l->ra->names[l->index]);
	snprintf(j[1].path, sizeof j[1].path, "%s/%s", l->rb->dir, l->rb->names[l->index]);
	pthread_t th;
	int threaded = pthread_create(&th, NULL, frame_main, &j[1]) == 0;
	frame_main(&j[0]);
	if (threaded)
		pthread_join(th, NULL);
	else
		frame_main(&j[1]);
	o->a = j[0].rgb;
	o->b = j[1].rgb;
	o->w = j[0].w;
	o->h = j[0].h;
	o->wb = j[1].w;
	o->hb = j[1].h;
	o->rc = j[0].rc ? j[0].rc : j[1].rc; /* the reader's code */
	if (o->rc)
		snprintf(o->err, sizeof o->err, "%s", j[0].rc ? j[0].err : j[1].err);
	else if (j[1].w != o->w || j[1].h != o->h) {
		snprintf(o->err, sizeof o->err, "%s is %ux%u but %s is %ux%u: compare frames of the same size", j[0].path,
			 o->w, o->h, j[1].path, j[1].w, j[1].h);
		o->rc = TL_ERR_INPUT;
	}
	for (int k = 0; k < 2 && !o->rc; k++) {
		const sequence *sq = k ? l->rb : l->ra;
		if (sq->w && (j[k].w != sq->w || j[k].h != sq->h)) {
			snprintf(o->err, sizeof o->err, "%s: size %ux%u differs from the run's %ux%u (manifest.json); render the run "
				 "again", j[k].path, j[k].w, j[k].h, sq->w, sq->h);
			o->rc = TL_ERR_INPUT;
		}
	}
	free(j);
}

static void *load_main(void *p)
{
	load_pair(p);
	return NULL;
}

static void csv_num(FILE *f, double v)
{
	if (isfinite(v))
		fprintf(f, "%.6g", v);
}

static json_t *num_or_null(double v) { return isfinite(v) ? json_real(v) : json_null(); }

static uint64_t cur_size(const pair_buf *p) { return (uint64_t)p->w * p->h; }


static int write_plots(const char *out, char *err, size_t err_size)
{
	char script[4096];
	mtr_plot plot;
	snprintf(script, sizeof script, "%s/plots/plots.gp", out);
	FILE *f = mtr_plot_begin(&plot, script, err, err_size);
	if (!f)
		return TL_ERR_OUTPUT;
	/* Per-frame series and exceedance, from frames.csv (columns per DESIGN section 6). */
	fprintf(f,
		"set datafile separator ','\n"
		"set terminal pngcairo size 960,540 font 'sans,10'\n"
		"set key outside right top\n"
		"set grid\n"
		"set output '%s/plots/frames.png'\n"
		"set title 'max-RGB difference per frame'\n"
		"set xlabel 'frame'; set ylabel 'code values (0-255)'\n"
		"plot '%s/frames.csv' using 1:2 every ::1 with lines title 'mean', "
		"'' using 1:4 every ::1 with lines title 'p95', '' using 1:5 every ::1 with lines title 'p99', "
		"'' using 1:6 every ::1 with lines title 'max', '' using 1:15 every ::1 with lines title 'flicker mean'\n"
		"set output '%s/plots/exceed.png'\n"
		"set title 'fraction of pixels with d > T per frame'\n"
		"set ylabel 'fraction'; set logscale y\n"
		"plot for [c=7:12] '%s/frames.csv' using 1:(column(c) > 0 ? column(c) : 1/0) every ::1 with lines "
		"title columnheader(c)\n"
		"set output '%s/plots/distribution.png'\n"
		"set title 'distribution of the max-RGB difference over all frames'\n"
		"set xlabel 'd (code values)'; set ylabel 'fraction of pixels'; set logscale y; set xrange [0:*]\n"
		"set style fill solid 0.6\n"
		"plot '%s/distribution.csv' using 1:($4 > 0 ? $4 : 1/0) every ::1 with boxes notitle\n",
		out, out, out, out, out, out);
	return mtr_plot_end(&plot, err, err_size);
}

/* One frames.csv row: the frame number, then every column of DESIGN section 6 (empty where not computed). */
static void csv_row(FILE *f, long frame, const mtr_frame_stats *s)
{
	fprintf(f, "%ld", frame);
	for (int c = 0; mtr_column_name(c); c++)
		if (mtr_column_where(c) & 1u) {
			fputc(',', f);
			csv_num(f, mtr_column_value(c, s));
		}
	fputc('\n', f);
}

/* Compares one view's frame pairs (two opened sequences of the same names) into OUT/frames.csv and, with
 * --heatmaps, OUT/heatmaps; stats[i] receives pair i, *pixels the frame size, *compute the time in statistics. */
static int diff_view(const mtr_diff_desc *d, const sequence *ra, const sequence *rb, const char *out, mtr_comparer *cmp,
		     mtr_frame_stats *stats, uint64_t *pixels, double *compute, char *err, size_t err_size)
{
	int rc;
	float *map = NULL, *flip_map = NULL;
	pair_buf cur = {0}, prev = {0}, next = {0};
	float *spare[2] = {NULL, NULL}; /* the buffers of the pair before prev, for the next decode */
	size_t spare_n[2] = {0, 0};
	FILE *csv = NULL;
	tl_atomic csv_file = {0};
	char path[4096];
	const int flip_index = mtr_metric_find("flip");
	const bool want_flip = flip_index >= 0 && ((mtr_comparer_selected(cmp) >> flip_index) & 1u);
	snprintf(path, sizeof path, "%s/%s", out, d->heatmaps ? (want_flip ? "heatmaps/flip" : "heatmaps") : "");
	if ((rc = tl_mkdirs(path, err, err_size)))
		goto done;
	if (d->plots) {
		snprintf(path, sizeof path, "%s/plots", out);
		if ((rc = tl_mkdirs(path, err, err_size)))
			goto done;
	}
	snprintf(path, sizeof path, "%s/frames.csv", out);
	if ((rc = tl_atomic_open(&csv_file, path, err, err_size)))
		goto done;
	rc = TL_ERR_INPUT;
	csv = csv_file.f;
	fputs("frame", csv);
	for (int c = 0; mtr_column_name(c); c++)
		if (mtr_column_where(c) & 1u)
			fprintf(csv, ",%s", mtr_column_name(c));
	fputc('\n', csv);
	loader l = {d, ra, rb, 0, &cur, {NULL, NULL}, {0, 0}};
	load_pair(&l);
	for (size_t i = 0; i < ra->n; i++) {
		if (cur.rc) {
			snprintf(err, err_size, "%s", cur.err);
			rc = cur.rc;
			goto done;
		}
		/* Overlap: decode pair i+1 on helper threads while pair i is measured. */
		pthread_t th;
		int threaded = 0;
		loader ln = {d, ra, rb, i + 1, &next, {NULL, NULL}, {spare_n[0], spare_n[1]}};
		if (i + 1 < ra->n) { /* the loader owns them from here */
			ln.reuse[0] = spare[0], ln.reuse[1] = spare[1];
			spare[0] = spare[1] = NULL;
		}
		memset(&next, 0, sizeof next);
		if (i + 1 < ra->n)
			threaded = pthread_create(&th, NULL, load_main, &ln) == 0;
		size_t npx = (size_t)cur.w * cur.h;
		if (d->heatmaps && ((!map && !(map = malloc(npx * sizeof *map))) ||
				    (want_flip && !flip_map && !(flip_map = malloc(npx * sizeof *flip_map))))) {
			rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
			if (threaded)
				pthread_join(th, NULL);
			goto done;
		}
		mtr_image a = {cur.w, cur.h, cur.a}, b = {cur.w, cur.h, cur.b};
		mtr_image ap = {prev.w, prev.h, prev.a}, bp = {prev.w, prev.h, prev.b};
		int have_prev = prev.a && prev.w == cur.w && prev.h == cur.h;
		double tc = tl_clock_s();
		int crc = mtr_comparer_frame(cmp, &a, &b, have_prev ? &ap : NULL, have_prev ? &bp : NULL, map, flip_map,
					     &stats[i], err, err_size);
		*compute += tl_clock_s() - tc;
		if (crc && i > 0 && (cur.w != prev.w || cur.h != prev.h))
			snprintf(err, err_size, "frame %s has another size than the previous frames", ra->names[i]);
		const int stem = (int)strlen(ra->names[i]) - 4;
		if (!crc && d->heatmaps) {
			snprintf(path, sizeof path, "%s/heatmaps/%.*s.png", out, stem, ra->names[i]);
			crc = mtr_heatmap_write(path, map, cur.w, cur.h, d->heatmap_max > 0 ? d->heatmap_max : 64, err, err_size);
		}
		if (!crc && d->heatmaps && want_flip) {
			snprintf(path, sizeof path, "%s/heatmaps/flip/%.*s.png", out, stem, ra->names[i]);
			crc = mtr_heatmap_write(path, flip_map, cur.w, cur.h, 1.0, err, err_size);
		}
		if (threaded)
			pthread_join(th, NULL);
		else if (i + 1 < ra->n)
			load_pair(&ln);
		if (crc) {
			rc = crc;
			goto done;
		}
		csv_row(csv, atol(ra->names[i]), &stats[i]);
		free(spare[0]);
		free(spare[1]);
		spare[0] = prev.a;
		spare[1] = prev.b;
		spare_n[0] = (size_t)prev.w * prev.h * 3;
		spare_n[1] = (size_t)prev.wb * prev.hb * 3;
		prev = cur;
		cur = next;
		memset(&next, 0, sizeof next);
	}
	*pixels = cur_size(&prev);
	csv = NULL;
	rc = tl_atomic_commit(&csv_file, err, err_size);
done:
	tl_atomic_abort(&csv_file);
	free(cur.a), free(cur.b), free(prev.a), free(prev.b), free(next.a), free(next.b), free(spare[0]), free(spare[1]);
	free(map);
	free(flip_map);
	return rc;
}

static const char *const eye_names[2] = {"L", "R"}; /* the run folder's frames/L, frames/R (run_view_dir) */

/* OUT/distribution.csv, OUT/summary.json (written last: the folder is complete) and the plots of n pooled pairs of
 * `pixels` pixels. `eye`: NULL (mono), "L" or "R" (one eye of a stereo diff) or "" (both eyes pooled). */
static int write_summary(const mtr_diff_desc *d, const char *out, mtr_comparer *cmp, const mtr_frame_stats *stats,
			 size_t n, size_t frames, uint64_t pixels, const char *eye, mtr_frame_stats *pooled, char *err,
			 size_t err_size)
{
	char path[4096];
	int rc;
	mtr_comparer_pool(cmp, stats, n, pooled);
	const mtr_frame_stats *p = pooled;
	static const char ref_key[] = "ref"; /* summary.json's key of the reference frames: not a method name */
	json_t *j = json_pack("{s:s, s:s, s:s, s:I}", ref_key, d->ref, "test", d->test, "format",
			      d->format == MTR_FORMAT_PNG ? "png" : "exr", "frames", (json_int_t)frames);
	if (eye && *eye)
		json_object_set_new(j, "eye", json_string(eye));
	else if (eye)
		json_object_set_new(j, "stereo", json_true());
	json_t *sel = json_array();
	for (int m = 0; mtr_metric_name(m); m++)
		if ((mtr_comparer_selected(cmp) >> m) & 1u)
			json_array_append_new(sel, json_string(mtr_metric_name(m)));
	json_object_set_new(j, "metrics", sel);
	for (int c = 0; mtr_column_name(c); c++)
		if (mtr_column_where(c) & 2u)
			json_object_set_new(j, mtr_column_name(c), num_or_null(mtr_column_value(c, p)));
	const int flip_index = mtr_metric_find("flip");
	if (flip_index >= 0 && ((mtr_comparer_selected(cmp) >> flip_index) & 1u)) {
		double ppd = MTR_FLIP_PPD_DEFAULT;
		for (size_t k = 0; k < d->option_count; k++)
			if (!strcmp(d->options[k].name, "ppd"))
				ppd = d->options[k].value;
		json_object_set_new(j, "flip_ppd", json_real(ppd));
	}
	json_object_set_new(j, "pooling",
			    json_string(eye && !*eye ?
					"stereo: each eye against the same eye (L/, R/), pooled here over both eyes' frames "
					"as over 2 x frames pairs (frames.csv: each frame's two eyes pooled): means; maxrgb_max: "
					"max; psnr: from the mean MSE; flicker_mean: over frames 2..n of each eye; flip_*: over "
					"all pixels of both eyes; metrics not selected: null" :
					"mean over frames; maxrgb_max: max; psnr: from the mean MSE; flicker_mean: over "
					"frames 2..n; flip_*: over all pixels of all frames (weighted quartiles from a "
					"histogram, within 2.5e-4 x the value); metrics not selected: null"));
	const uint64_t *hist = mtr_comparer_histogram(cmp);
	if (hist) {
		uint64_t hist_total = (uint64_t)n * pixels;
		tl_atomic hf;
		snprintf(path, sizeof path, "%s/distribution.csv", out);
		if ((rc = tl_atomic_open(&hf, path, err, err_size))) {
			json_decref(j);
			return rc;
		}
		fprintf(hf.f, "d_from,d_to,count,fraction\n");
		for (int b = 0; b < 256; b++)
			fprintf(hf.f, "%d,%d,%llu,%.9g\n", b, b + 1, (unsigned long long)hist[b],
				hist_total ? (double)hist[b] / (double)hist_total : 0.0);
		if ((rc = tl_atomic_commit(&hf, err, err_size))) {
			json_decref(j);
			return rc;
		}
	}
	snprintf(path, sizeof path, "%s/summary.json", out);
	rc = tl_json_write(path, j, err, err_size);
	json_decref(j);
	if (rc)
		return rc;
	if (d->plots && hist && write_plots(out, err, err_size))
		fprintf(stderr, "taslab metrics: note: %s\n", err);
	return TL_OK;
}

/* Both eyes pooled per frame into OUT/frames.csv (frames of the two views in stats[0], stats[1]). */
static int write_pooled_frames(const char *out, const sequence *ra, const mtr_frame_stats *const stats[2], char *err,
			       size_t err_size)
{
	char path[4096];
	tl_atomic f;
	snprintf(path, sizeof path, "%s/frames.csv", out);
	int rc = tl_atomic_open(&f, path, err, err_size);
	if (rc)
		return rc;
	fputs("frame", f.f);
	for (int c = 0; mtr_column_name(c); c++)
		if (mtr_column_where(c) & 1u)
			fprintf(f.f, ",%s", mtr_column_name(c));
	fputc('\n', f.f);
	for (size_t i = 0; i < ra->n; i++) {
		mtr_frame_stats two[2] = {stats[0][i], stats[1][i]}, p;
		mtr_pool(two, 2, &p);
		csv_row(f.f, atol(ra->names[i]), &p);
	}
	return tl_atomic_commit(&f, err, err_size);
}

int mtr_diff_run(const mtr_diff_desc *d, mtr_diff_result *res, char *err, size_t err_size)
{
	const char *ext = d->format == MTR_FORMAT_PNG ? ".png" : ".exr";
	sequence ra[2], rb[2];
	mtr_comparer *cmp[2] = {NULL, NULL};
	mtr_frame_stats *stats[2] = {NULL, NULL}, *both = NULL;
	char path[4096], out[4096];
	int rc = TL_OK;
	memset(res, 0, sizeof *res);
	memset(ra, 0, sizeof ra);
	memset(rb, 0, sizeof rb);
	if (d->format == MTR_FORMAT_EXR && !d->colour)
		return tl_error(err, err_size, TL_ERR_ARG, "EXR comparison needs a display transform");
	/* An old summary must not look like this comparison's result, also when the runs are refused below (a frame
	 * missing or of another size than the manifest's, issue 31.8). */
	for (int k = 0; k < 3; k++) {
		snprintf(path, sizeof path, "%s/%s%s", d->out, k ? eye_names[k - 1] : "", k ? "/summary.json" : "summary.json");
		unlink(path);
	}
	/* Stereo (STEREO.md "metrics per eye against ref's same eye, then pooled"): a stereo run against a mono one has
	 * no pairing that means anything. */
	const uint32_t views = path_views(d->ref), tviews = path_views(d->test);
	if (views != tviews || views > 2)
		return tl_error(err, err_size, TL_ERR_INPUT, "%s is %s but %s is %s: compare stereo runs with stereo runs (each eye "
				"against the same eye), or give RUN/frames/L or RUN/frames/R to compare one eye as images",
				d->ref, views > 1 ? "a stereo run" : "mono", d->test, tviews > 1 ? "a stereo run" : "mono");
	mtr_compare_desc cd = {.metrics = d->metrics, .options = d->options, .option_count = d->option_count,
			       .threads = d->threads};
	double t0 = tl_clock_s();
	uint64_t pixels = 0;
	for (uint32_t v = 0; v < views; v++) {
		if ((rc = mtr_comparer_create(&cd, &cmp[v], err, err_size)) ||
		    (rc = sequence_open(d->ref, ext, views, v, &ra[v], err, err_size)) ||
		    (rc = sequence_open(d->test, ext, views, v, &rb[v], err, err_size)))
			goto done;
		rc = TL_ERR_INPUT;
		if (ra[v].n != rb[v].n) {
			snprintf(err, err_size, "%s has %zu frames but %s has %zu: compare runs of the same frames", ra[v].dir,
				 ra[v].n, rb[v].dir, rb[v].n);
			goto done;
		}
		for (size_t i = 0; i < ra[v].n; i++)
			if (strcmp(ra[v].names[i], rb[v].names[i]) || (v && strcmp(ra[v].names[i], ra[0].names[i]))) {
				snprintf(err, err_size, "frame files differ: %s/%s vs %s/%s", ra[v].dir, ra[v].names[i],
					 v && strcmp(ra[v].names[i], ra[0].names[i]) ? ra[0].dir : rb[v].dir,
					 v && strcmp(ra[v].names[i], ra[0].names[i]) ? ra[0].names[i] : rb[v].names[i]);
				goto done;
			}
		if (v && ra[v].n != ra[0].n) {
			snprintf(err, err_size, "%s has %zu frames but %s has %zu", ra[v].dir, ra[v].n, ra[0].dir, ra[0].n);
			goto done;
		}
		if (!(stats[v] = calloc(ra[v].n, sizeof *stats[v]))) {
			rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
			goto done;
		}
		snprintf(out, sizeof out, "%s%s%s", d->out, views > 1 ? "/" : "", views > 1 ? eye_names[v] : "");
		if ((rc = diff_view(d, &ra[v], &rb[v], out, cmp[v], stats[v], &pixels, &res->compute_seconds, err, err_size)) ||
		    (rc = write_summary(d, out, cmp[v], stats[v], ra[v].n, ra[v].n, pixels, views > 1 ? eye_names[v] : NULL,
					views > 1 ? &res->eye[v] : &res->pooled, err, err_size)))
			goto done;
	}
	if (views > 1) { /* both eyes pooled: summary.json last, so the folder is complete only with it */
		const size_t n = ra[0].n;
		const mtr_frame_stats *const per_eye[2] = {stats[0], stats[1]};
		if (!(both = malloc(2 * n * sizeof *both))) {
			rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
			goto done;
		}
		memcpy(both, stats[0], n * sizeof *both);
		memcpy(both + n, stats[1], n * sizeof *both);
		if ((rc = mtr_comparer_merge(cmp[0], cmp[1], err, err_size)) ||
		    (rc = write_pooled_frames(d->out, &ra[0], per_eye, err, err_size)) ||
		    (rc = write_summary(d, d->out, cmp[0], both, 2 * n, n, pixels, "", &res->pooled, err, err_size)))
			goto done;
	}
	res->frames = ra[0].n;
	res->views = views;
	res->seconds = tl_clock_s() - t0;
	rc = TL_OK;
done:
	for (uint32_t v = 0; v < 2; v++) {
		free(stats[v]);
		mtr_comparer_destroy(&cmp[v]);
		sequence_free(&ra[v]);
		sequence_free(&rb[v]);
	}
	free(both);
	return rc;
}
