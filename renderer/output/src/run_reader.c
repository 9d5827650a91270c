/* run_reader.c — reading a run folder: manifest.json, the frame set, stats.csv (run.h). The only place
 * that parses these files; clip, metrics and sweeps call it. */
#include "taslab/run.h"

#include <dirent.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"
#include "taslab/tl_json.h"

#include "method_facts.h"

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
	copy_str(in, "scene_digest", m->scene_digest, sizeof m->scene_digest);
	copy_str(in, "colour_digest", m->colour_digest, sizeof m->colour_digest);
	copy_str(json_object_get(j, "versions"), "build", m->build_digest, sizeof m->build_digest);
	copy_str(in, "camera", m->camera, sizeof m->camera);
	copy_str(in, "camera_motion", m->camera_motion, sizeof m->camera_motion);
	copy_str(in, "method", m->method, sizeof m->method);
	copy_str(in, "variant", m->variant, sizeof m->variant);
	if (!m->variant[0])
		snprintf(m->variant, sizeof m->variant, "%s", m->method);
	copy_str(json_object_get(j, "device"), "name", m->device, sizeof m->device);
	copy_str(out, "display_transform", m->display_transform, sizeof m->display_transform);
	if (method_facts_read(json_object_get(in, "method_facts"), &m->facts)) {
		json_decref(j);
		return tl_error(err, err_size, TL_ERR_INPUT, "%s: inputs.method_facts is not a valid object; render the run again",
				path);
	}
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
	json_t *stereo = json_object_get(in, "stereo"), *ipd = json_object_get(in, "ipd");
	m->views = json_is_true(stereo) ? 2 : 1;
	m->ipd = m->views > 1 && json_is_number(ipd) ? json_number_value(ipd) : 0.0;
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
		return -1; /* local sentinel: not a frame file's name */
	return strtol(name, NULL, 10);
}

static uint32_t be32(const unsigned char *p) { return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3]; }
static int32_t le32(const unsigned char *p) { return (int32_t)((uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24); }

/* The pixel size a frame file declares, from its header alone (cheap enough for every frame of a run): a PNG's IHDR
 * (PNG spec 11.2.2: the first chunk, width and height big-endian), an OpenEXR's dataWindow attribute (OpenEXR file
 * layout: magic 76 2f 31 01, version, then name\0 type\0 int32 size, value ...; box2i = xMin yMin xMax yMax). true
 * when it declares one, false when the header cannot be read. */
static bool frame_file_size(const char *path, bool exr, uint32_t *w, uint32_t *h)
{
	unsigned char b[4096];
	int fd;
	uint64_t fsize;
	char e[256];
	/* regular files only: opening a FIFO would wait for a writer (issue 31.6); anything else is left to the image
	 * reader, whose message says what the path is */
	if (tl_open_regular(path, UINT64_MAX, &fd, &fsize, e, sizeof e))
		return false;
	ssize_t got = read(fd, b, sizeof b);
	close(fd);
	if (got < 0)
		return false;
	size_t n = (size_t)got;
	if (!exr) {
		static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
		if (n < 24 || memcmp(b, sig, 8) || memcmp(b + 12, "IHDR", 4))
			return false;
		*w = be32(b + 16), *h = be32(b + 20);
		return true;
	}
	if (n < 8 || b[0] != 0x76 || b[1] != 0x2f || b[2] != 0x31 || b[3] != 0x01)
		return false;
	for (size_t i = 8; i < n && b[i];) {
		const unsigned char *name = b + i, *nul = memchr(name, 0, n - i);
		if (!nul)
			return false;
		const unsigned char *type = nul + 1, *tnul = type < b + n ? memchr(type, 0, (size_t)(b + n - type)) : NULL;
		if (!tnul || tnul + 5 > b + n)
			return false;
		int32_t size = le32(tnul + 1);
		const unsigned char *value = tnul + 5;
		if (size < 0 || value + size > b + n)
			return false;
		if (!strcmp((const char *)name, "dataWindow") && !strcmp((const char *)type, "box2i") && size == 16) {
			int64_t x0 = le32(value), y0 = le32(value + 4), x1 = le32(value + 8), y1 = le32(value + 12);
			if (x1 < x0 || y1 < y0)
				return false;
			*w = (uint32_t)(x1 - x0 + 1), *h = (uint32_t)(y1 - y0 + 1);
			return true;
		}
		i = (size_t)(value + size - b);
	}
	return false;
}

static int check_frames_in(const char *dir, const char *sub, const run_manifest *m, const char *ext, char *err,
			   size_t err_size)
{
	char path[TL_PATH_MAX];
	snprintf(path, sizeof path, "%s/%s", dir, sub);
	size_t count = (size_t)(m->last_frame - m->first_frame) + 1;
	unsigned char *seen = calloc(count, 1);
	if (!seen)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	DIR *d = opendir(path);
	int rc = TL_OK;
	if (!d)
		rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: no %s folder; render the run again", dir, sub);
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
	/* every frame of the manifest's size: a frame copied in from another run is not one of this run's (issue 31.8) */
	for (size_t i = 0; !rc && i < count; i++) {
		char f[TL_PATH_MAX + 32];
		uint32_t w = 0, h = 0;
		snprintf(f, sizeof f, "%s/%06zu.%s", path, m->first_frame + i, ext);
		/* (a header that does not parse is left to the image reader, whose message says what is wrong with it) */
		if (frame_file_size(f, !strcmp(ext, "exr"), &w, &h) && (w != m->width || h != m->height))
			rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: size %ux%u differs from the run's %ux%u; render the run again",
				      f, w, h, m->width, m->height);
	}
	free(seen);
	return rc;
}

int run_check_frames(const char *dir, const run_manifest *m, const char *ext, char *err, size_t err_size)
{
	int rc = TL_OK;
	for (uint32_t v = 0; !rc && v < (m->views > 1 ? m->views : 1); v++)
		rc = check_frames_in(dir, run_view_dir(m->views, v), m, ext, err, err_size);
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
	return -1; /* local sentinel: no such column (an index, not an error) */
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

int run_check(const char *dir, run_manifest *m, char *err, size_t err_size)
{
	int rc = run_manifest_read(dir, m, err, err_size);
	if (!rc && m->png)
		rc = run_check_frames(dir, m, "png", err, err_size);
	if (!rc && m->exr)
		rc = run_check_frames(dir, m, "exr", err, err_size);
	if (!rc && !m->png && !m->exr)
		rc = tl_error(err, err_size, TL_ERR_INPUT, "%s: the run has no frames (neither PNG nor EXR)", dir);
	return rc;
}
