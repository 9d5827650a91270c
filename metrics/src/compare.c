/* compare.c — the comparer: the selected metric plug-ins run on each frame pair after one shared pixel pass
 * (metric.h), metric selection by name, option values from the plug-ins' tables, and the result columns in
 * registry order (metrics.h). */
#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "metric.h"

#define MTR_METRIC_MAX 32 /* bits of mtr_frame_stats.metrics */

struct mtr_comparer {
	uint32_t selected;
	unsigned pass; /* MTR_PASS_* of the selected metrics */
	int threads;
	void *state[MTR_METRIC_MAX];
	uint64_t hist[256]; /* max-RGB distribution over the frames compared */
	uint32_t width, height;
};

int mtr_metric_count(void)
{
	int n = 0;
	while (mtr_metric_registry[n])
		n++;
	return n;
}

const char *mtr_metric_name(int i)
{
	return i >= 0 && i < mtr_metric_count() ? mtr_metric_registry[i]->name : NULL;
}

int mtr_metric_find(const char *name)
{
	for (int i = 0; mtr_metric_registry[i]; i++)
		if (!strcmp(mtr_metric_registry[i]->name, name))
			return i;
	return -1; /* local sentinel: no such metric (an index, not an error) */
}

const char *mtr_metric_list(char *buf, size_t buf_size)
{
	size_t o = 0;
	if (buf_size)
		buf[0] = 0;
	for (int i = 0; mtr_metric_registry[i] && o < buf_size; i++)
		o += (size_t)snprintf(buf + o, buf_size - o, "%s%s", i ? "," : "", mtr_metric_registry[i]->name);
	return buf;
}

int mtr_metric_parse(const char *list, uint32_t *mask, char *err, size_t err_size)
{
	const int n = mtr_metric_count();
	*mask = 0;
	if (!list || !*list || !strcmp(list, "all")) {
		*mask = n >= 32 ? UINT32_MAX : (1u << n) - 1u;
		return TL_OK;
	}
	char known[256];
	mtr_metric_list(known, sizeof known);
	for (const char *p = list;;) {
		const char *e = strchr(p, ',');
		size_t len = e ? (size_t)(e - p) : strlen(p);
		if (len == 0) /* "maxrgb,,psnr", a trailing comma: a typo, not a metric named "" */
			return tl_error(err, err_size, TL_ERR_ARG, "--metrics: empty entry in '%s' (known: %s, or all)", list, known);
		int found = -1;
		for (int i = 0; i < n && found < 0; i++)
			if (strlen(mtr_metric_registry[i]->name) == len && !strncmp(mtr_metric_registry[i]->name, p, len))
				found = i;
		if (found < 0)
			return tl_error(err, err_size, TL_ERR_ARG, "--metrics: unknown metric '%.*s' (known: %s, or all)",
					(int)len, p, known);
		*mask |= 1u << found;
		if (!e)
			break;
		p = e + 1;
	}
	return TL_OK;
}

void mtr_metric_clear(const mtr_metric *m, mtr_frame_stats *s)
{
	for (const mtr_column *c = m->columns; c->name; c++)
		*(double *)((char *)s + c->offset) = NAN;
}

/* ---- columns ---- */

static const mtr_column *column_at(int i)
{
	if (i < 0)
		return NULL;
	for (int m = 0; mtr_metric_registry[m]; m++)
		for (const mtr_column *c = mtr_metric_registry[m]->columns; c->name; c++)
			if (i-- == 0)
				return c;
	return NULL;
}

const char *mtr_column_name(int i)
{
	const mtr_column *c = column_at(i);
	return c ? c->name : NULL;
}

double mtr_column_value(int i, const mtr_frame_stats *s)
{
	const mtr_column *c = column_at(i);
	return c ? *(const double *)((const char *)s + c->offset) : NAN;
}

unsigned mtr_column_where(int i)
{
	const mtr_column *c = column_at(i);
	return c ? c->where : 0;
}

/* ---- the comparer ---- */

void mtr_comparer_destroy(mtr_comparer **pc)
{
	if (!pc || !*pc)
		return;
	mtr_comparer *c = *pc;
	for (int i = 0; mtr_metric_registry[i]; i++)
		if (c->state[i]) {
			if (mtr_metric_registry[i]->destroy)
				mtr_metric_registry[i]->destroy(c->state[i]);
			free(c->state[i]);
		}
	free(c);
	*pc = NULL;
}

int mtr_comparer_create(const mtr_compare_desc *d, mtr_comparer **out, char *err, size_t err_size)
{
	*out = NULL;
	mtr_comparer *c = calloc(1, sizeof *c);
	if (!c)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	static_assert(sizeof(((mtr_frame_stats *)0)->metrics) * 8 >= MTR_METRIC_MAX, "metric bits");
	if (mtr_metric_count() > MTR_METRIC_MAX) {
		free(c);
		return tl_error(err, err_size, TL_ERR_INTERNAL, "more than %d metrics in the registry", MTR_METRIC_MAX);
	}
	int rc = mtr_metric_parse(d->metrics, &c->selected, err, err_size);
	if (rc)
		goto fail;
	c->threads = d->threads;
	/* Every option given must belong to some metric (selected or not: --ppd with --metrics maxrgb is harmless). */
	for (size_t k = 0; k < d->option_count; k++) {
		int known = 0;
		for (int i = 0; mtr_metric_registry[i]; i++)
			for (const mtr_metric_option *o = mtr_metric_registry[i]->options; o && o->name; o++)
				if (!strcmp(o->name, d->options[k].name)) {
					known = 1;
					if (!(d->options[k].value >= o->lo && d->options[k].value <= o->hi)) {
						rc = tl_error(err, err_size, TL_ERR_ARG, "--%s must be in [%g, %g], got %g", o->name,
							      o->lo, o->hi, d->options[k].value);
						goto fail;
					}
				}
		if (!known) {
			rc = tl_error(err, err_size, TL_ERR_ARG, "no metric has an option '%s'", d->options[k].name);
			goto fail;
		}
	}
	for (int i = 0; mtr_metric_registry[i]; i++) {
		const mtr_metric *m = mtr_metric_registry[i];
		if (!(c->selected & (1u << i)))
			continue;
		c->pass |= m->pixel_pass;
		if (!(c->state[i] = calloc(1, m->state_size ? m->state_size : 1))) {
			rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
			goto fail;
		}
		for (const mtr_metric_option *o = m->options; o && o->name; o++) {
			double v = o->def;
			for (size_t k = 0; k < d->option_count; k++)
				if (!strcmp(o->name, d->options[k].name))
					v = d->options[k].value;
			*(double *)((char *)c->state[i] + o->offset) = v;
		}
		if (m->create && (rc = m->create(c->state[i], err, err_size)))
			goto fail;
	}
	*out = c;
	return TL_OK;
fail:
	mtr_comparer_destroy(&c);
	return rc;
}

static int same_size(const mtr_image *a, const mtr_image *b)
{
	return a->width == b->width && a->height == b->height;
}

int mtr_comparer_frame(mtr_comparer *c, const mtr_image *a, const mtr_image *b, const mtr_image *a_prev,
		       const mtr_image *b_prev, float *map, float *flip_map, mtr_frame_stats *out, char *err,
		       size_t err_size)
{
	if (!a->width || !a->height || !same_size(a, b))
		return tl_error(err, err_size, TL_ERR_ARG, "image sizes differ: %ux%u vs %ux%u", a->width, a->height,
				b->width, b->height);
	if (!a->rgb || !b->rgb)
		return tl_error(err, err_size, TL_ERR_ARG, "image without pixels");
	if ((a_prev == NULL) != (b_prev == NULL) || (a_prev && (!same_size(a, a_prev) || !same_size(a, b_prev))))
		return tl_error(err, err_size, TL_ERR_ARG, "previous frames missing or of another size");
	if (c->width && (a->width != c->width || a->height != c->height))
		return tl_error(err, err_size, TL_ERR_ARG, "frame is %ux%u but the previous frames are %ux%u", a->width,
				a->height, c->width, c->height);
	c->width = a->width;
	c->height = a->height;
	memset(out, 0, sizeof *out);
	for (int i = 0; mtr_metric_registry[i]; i++)
		mtr_metric_clear(mtr_metric_registry[i], out);
	mtr_pixel_result px;
	memset(&px, 0, sizeof px);
	unsigned pass = c->pass & ~(a_prev ? 0u : (unsigned)MTR_PASS_FLICKER);
	if (pass || map) { /* the max-RGB map is produced by any pass */
		int rc = mtr_pixel_pass(a, b, a_prev, b_prev, pass, map, c->threads, &px);
		if (rc)
			return tl_error(err, err_size, rc, "out of memory");
		if (c->pass & MTR_PASS_MAXRGB)
			for (int k = 0; k < 256; k++)
				c->hist[k] += px.hist[k];
	}
	mtr_pair p = {.a = a, .b = b, .a_prev = a_prev, .b_prev = b_prev, .px = &px, .map = map, .flip_map = flip_map,
		      .threads = c->threads};
	for (int i = 0; mtr_metric_registry[i]; i++) {
		if (!(c->selected & (1u << i)))
			continue;
		int rc = mtr_metric_registry[i]->compute(c->state[i], &p, out, err, err_size);
		if (rc)
			return rc;
		out->metrics |= 1u << i;
	}
	return TL_OK;
}

void mtr_comparer_pool(mtr_comparer *c, const mtr_frame_stats *f, size_t n, mtr_frame_stats *p)
{
	mtr_pool(f, n, p);
	for (int i = 0; mtr_metric_registry[i]; i++)
		if ((c->selected & p->metrics & (1u << i)) && n)
			mtr_metric_registry[i]->pool(c->state[i], f, n, p);
}

int mtr_comparer_merge(mtr_comparer *into, const mtr_comparer *from, char *err, size_t err_size)
{
	if (into->selected != from->selected || (from->width && into->width &&
						 (into->width != from->width || into->height != from->height)))
		return tl_error(err, err_size, TL_ERR_ARG, "merging comparers of other metrics or frame sizes");
	for (int k = 0; k < 256; k++)
		into->hist[k] += from->hist[k];
	for (int i = 0; mtr_metric_registry[i]; i++)
		if ((into->selected & (1u << i)) && mtr_metric_registry[i]->merge)
			mtr_metric_registry[i]->merge(into->state[i], from->state[i]);
	return TL_OK;
}

const uint64_t *mtr_comparer_histogram(const mtr_comparer *c)
{
	return (c->pass & MTR_PASS_MAXRGB) ? c->hist : NULL;
}

uint32_t mtr_comparer_selected(const mtr_comparer *c)
{
	return c->selected;
}
