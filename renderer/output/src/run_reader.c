/* run_reader.c — reading a run folder: manifest.json, the frame set, stats.csv (run.h). The only place
 * that parses these files; clip, metrics and sweeps call it. */
#include "taslab/run.h"

#include <dirent.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"
#include "taslab/tl_json.h"

static void copy_str(json_t *o, const char *key, char *dst, size_t n)
{
	const char *v = json_string_value(json_object_get(o, key));
	snprintf(dst, n, "%s", v ? v : "");
}

int run_manifest_read(const char *dir, run_manifest *m, char *err, size_t err_size)
{
	memset(m, 0, sizeof *m);
	char path[TL_PATH_MAX];
	snprintf(path, sizeof path, "%s/manifest.json", dir);
	if (!tl_is_file(path))
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: not a complete run (no manifest.json); render it first", dir);
	json_t *j = NULL;
	int rc = tl_json_read(path, &j, err, err_size);
	if (rc)
		return rc;
	json_t *in = json_object_get(j, "inputs"), *fr = json_object_get(in, "frames"), *sz = json_object_get(in, "size");
	json_t *fps = json_object_get(in, "fps"), *T = json_object_get(in, "threshold"), *N = json_object_get(in, "period");
	json_t *out = json_object_get(j, "outputs"), *tot = json_object_get(j, "totals");
	if (!json_is_object(in) || !json_is_string(json_object_get(in, "method")) || json_array_size(fr) != 2 ||
	    json_array_size(sz) != 2 || !json_is_number(fps)) {
		json_decref(j);
		return tl_error(err, err_size, TL_ERR_INPUT,
				"%s: not a taslab run manifest (needs inputs.method, frames, size, fps); render the run again", path);
	}
	copy_str(in, "scene", m->scene, sizeof m->scene);
	copy_str(in, "scene_path", m->scene_path, sizeof m->scene_path);
	copy_str(in, "camera", m->camera, sizeof m->camera);
	copy_str(in, "camera_motion", m->camera_motion, sizeof m->camera_motion);
	copy_str(in, "method", m->method, sizeof m->method);
	copy_str(in, "variant", m->variant, sizeof m->variant);
	if (!m->variant[0])
		snprintf(m->variant, sizeof m->variant, "%s", m->method);
	copy_str(json_object_get(j, "device"), "name", m->device, sizeof m->device);
	copy_str(out, "display_transform", m->display_transform, sizeof m->display_transform);
	m->threshold = json_is_number(T) ? json_number_value(T) : NAN;
	m->period = json_is_integer(N) && json_integer_value(N) > 0 ? (uint32_t)json_integer_value(N) : 0;
	json_int_t a = json_integer_value(json_array_get(fr, 0)), b = json_integer_value(json_array_get(fr, 1));
	json_int_t w = json_integer_value(json_array_get(sz, 0)), h = json_integer_value(json_array_get(sz, 1));
	m->fps = json_number_value(fps);
	json_t *png = json_object_get(out, "png"), *exr = json_object_get(out, "exr");
	m->png = png ? json_is_true(png) : true;
	m->exr = exr ? json_is_true(exr) : true;
	m->frames = (uint64_t)json_integer_value(json_object_get(tot, "frames"));
	m->visible_samples = (uint64_t)json_integer_value(json_object_get(tot, "visible_samples"));
	m->shaded_samples = (uint64_t)json_integer_value(json_object_get(tot, "shaded_samples"));
	m->gpu_ms_median = json_number_value(json_object_get(tot, "gpu_ms_median"));
	m->wall_s = json_number_value(json_object_get(tot, "wall_s"));
	json_decref(j);
	if (a < 0 || b < a || b > 0xffffffffLL || w < 1 || h < 1 || w > 16384 || h > 16384 || !(m->fps > 0) || m->fps > 1000)
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: impossible frames, size or fps; render the run again", path);
	m->first_frame = (uint32_t)a;
	m->last_frame = (uint32_t)b;
	m->width = (uint32_t)w;
	m->height = (uint32_t)h;
	return TL_OK;
}

/* NNNNNN.ext with at least six digits: the frame number, else -1. */
static long frame_number(const char *name, const char *ext)
{
	size_t d = 0, el = strlen(ext);
	while (name[d] >= '0' && name[d] <= '9')
		d++;
	if (d < 6 || d > 10 || name[d] != '.' || strcmp(name + d + 1, ext) || strlen(name) != d + 1 + el)
		return -1;
	return strtol(name, NULL, 10);
}

int run_check_frames(const char *dir, const run_manifest *m, const char *ext, char *err, size_t err_size)
{
	char path[TL_PATH_MAX];
	snprintf(path, sizeof path, "%s/frames", dir);
	size_t count = (size_t)(m->last_frame - m->first_frame) + 1;
	unsigned char *seen = calloc(count, 1);
	if (!seen)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	DIR *d = opendir(path);
	int rc = TL_OK;
	if (!d)
		rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: no frames folder; render the run again", dir);
	struct dirent *e;
	while (!rc && (e = readdir(d))) {
		long f = frame_number(e->d_name, ext);
		if (f < 0)
			continue;
		if (f < (long)m->first_frame || f > (long)m->last_frame)
			rc = tl_error(err, err_size, TL_ERR_INPUT,
				      "%s/%s: not a frame of this run (frames %u..%u); render the run again into an empty folder",
				      path, e->d_name, m->first_frame, m->last_frame);
		else
			seen[f - m->first_frame] = 1;
	}
	if (d)
		closedir(d);
	for (size_t i = 0; !rc && i < count; i++)
		if (!seen[i])
			rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: frame %06zu.%s is missing (run frames %u..%u)%s", path,
				      m->first_frame + i, ext, m->first_frame, m->last_frame,
				      !strcmp(ext, "png") && !m->png   ? "; the run was rendered with --no-png"
				      : !strcmp(ext, "exr") && !m->exr ? "; the run was rendered with --no-exr"
								       : "; render the run again");
	free(seen);
	return rc;
}

void run_stats_free(run_stats *s)
{
	for (size_t i = 0; s->names && i < s->cols; i++)
		free(s->names[i]);
	free(s->names);
	free(s->values);
	memset(s, 0, sizeof *s);
}

int run_stats_col(const run_stats *s, const char *name)
{
	for (size_t i = 0; i < s->cols; i++)
		if (!strcmp(s->names[i], name))
			return (int)i;
	return -1;
}

double run_stats_get(const run_stats *s, size_t row, const char *name)
{
	int c = run_stats_col(s, name);
	return c < 0 || row >= s->rows ? NAN : s->values[row * s->cols + (size_t)c];
}

#define STATS_MAX_COLS 128

int run_stats_read(const char *dir, run_stats *s, char *err, size_t err_size)
{
	memset(s, 0, sizeof *s);
	char path[TL_PATH_MAX], *text = NULL;
	snprintf(path, sizeof path, "%s/stats.csv", dir);
	int rc = tl_read_file(path, 256u << 20, &text, NULL, err, err_size);
	if (rc)
		return rc;
	char *line = text, *next;
	size_t cap = 0, lineno = 1;
	for (; line && *line; line = next, lineno++) {
		next = strchr(line, '\n');
		if (next)
			*next++ = 0;
		size_t len = strlen(line);
		if (len && line[len - 1] == '\r')
			line[--len] = 0;
		if (!len)
			continue;
		if (!s->names) { /* header */
			s->names = calloc(STATS_MAX_COLS, sizeof *s->names);
			if (!s->names)
				goto nomem;
			for (char *p = line;; p++) {
				char *c = strchr(p, ',');
				if (c)
					*c = 0;
				if (s->cols == STATS_MAX_COLS || !*p) {
					rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: bad header (empty or more than %d columns)", path,
						      STATS_MAX_COLS);
					goto fail;
				}
				if (!(s->names[s->cols++] = strdup(p)))
					goto nomem;
				if (!c)
					break;
				p = c;
			}
			continue;
		}
		if (s->rows == cap) {
			cap = cap ? cap * 2 : 256;
			double *v = realloc(s->values, cap * s->cols * sizeof *v);
			if (!v)
				goto nomem;
			s->values = v;
		}
		double *row = s->values + s->rows * s->cols;
		size_t c = 0;
		for (char *p = line; c < s->cols; c++) {
			char *e = strchr(p, ',');
			if (e)
				*e = 0;
			char *end;
			row[c] = *p ? strtod(p, &end) : NAN;
			if (*p && (*end || !isfinite(row[c]))) {
				rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: row %zu: '%s' in column %s is not a number", path, lineno, p,
					      s->names[c]);
				goto fail;
			}
			if (!e) {
				c++;
				break;
			}
			p = e + 1;
			if (c + 1 == s->cols) {
				rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: row %zu has more than %zu columns", path, lineno, s->cols);
				goto fail;
			}
		}
		if (c != s->cols) {
			rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: row %zu has %zu of %zu columns", path, lineno, c, s->cols);
			goto fail;
		}
		s->rows++;
	}
	if (!s->names) {
		rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: empty", path);
		goto fail;
	}
	free(text);
	return TL_OK;
nomem:
	rc = tl_error(err, err_size, TL_ERR_NOMEM, "%s: out of memory", path);
fail:
	free(text);
	run_stats_free(s);
	return rc;
}
