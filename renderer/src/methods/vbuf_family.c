/* vbuf_family.c — the frame of vref, the VRS rate methods and ads on the compacted sample path (vbuf_family.h). */
#include "vbuf_family.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *const vbuf_rate_passes[10] = {"shadow", "ids",   "rate",    "select",  "shade",
					  "resolve", "truth", "blend", "display", "readback"};
const char *const vbuf_vrs_passes[11] = {"shadow", "ids", "rate", "select", "shade", "resolve", "history", "truth",
					 "blend", "display", "readback"};
const char *const vbuf_ads_passes[8] = {"shadow", "ids", "shade", "resolve", "truth", "blend", "display", "readback"};

typedef struct vbuf_state {
	vbuf_variant v;
	vbuf_pass p;
	uint8_t *tile_rates; /* render --rate-images: the last frame's rates as frame_rate codes */
} vbuf_state;

static vbuf_state *state_of(render *r) { return r->method_state; }

vbuf_pass *vbuf_family_pass(render *r) { return &state_of(r)->p; }
void *vbuf_family_user(render *r) { return state_of(r)->v.user; }

int vbuf_family_init(render *r, const vbuf_variant *v, char *err, size_t err_size)
{
	vbuf_state *s = calloc(1, sizeof *s);
	if (!s)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	r->method_state = s;
	s->v = *v;
	s->p.centroid = v->centroid && !v->force;
	s->p.truth = v->truth;
	s->p.truth_t = v->truth_t;
	int rc = vbuf_init(r, &s->p, v->ads, err, err_size);
	if (!rc && v->rate_init && !v->force)
		rc = v->rate_init(r, &s->p, v->user, err, err_size);
	return rc;
}

int vbuf_family_prepare(render *r, uint32_t frame, char *err, size_t err_size)
{
	vbuf_state *s = state_of(r);
	render_update_state(r, 0, (double)frame / (double)r->desc.fps);
	/* slot 1: the previous frame's state, for the screen motion of the VRS history (the same at frame 0) */
	if (r->state_ring > 1)
		render_update_state(r, 1, (double)(frame ? frame - 1 : 0) / (double)r->desc.fps);
	if (s->v.rate_prepare && !s->v.force)
		s->v.rate_prepare(r, &s->p, s->v.user, frame);
	return render_shadow_plan(r, 0, err, err_size);
}

void vbuf_family_record(render *r, VkCommandBuffer cmd, uint32_t frame)
{
	vbuf_state *s = state_of(r);
	vbuf_pass *p = &s->p;
	vbuf_record_begin(r, p, cmd);
	render_ts(r, cmd);
	render_pass_shadows(r, cmd, 0);
	render_ts(r, cmd);
	if (s->v.ids_record && !s->v.force)
		s->v.ids_record(r, p, s->v.user, cmd, frame);
	else
		ids_pass_record(r, &p->ids, cmd, 0);
	vbuf_barrier(cmd);
	render_ts(r, cmd);
	if (!s->v.ads) {
		if (s->v.rate_record && !s->v.force)
			s->v.rate_record(r, p, s->v.user, cmd, frame);
		vbuf_barrier(cmd);
		render_ts(r, cmd);
		vbuf_record_select(r, p, cmd);
		render_ts(r, cmd);
		vbuf_record_shade(r, p, cmd, 0);
	} else {
		/* level 0, then per step s = s0 .. 2 its diamond and square sub-steps, each a select and a shade */
		float S = s->v.force ? -1.0f : s->v.S;
		vbuf_record_ads_step(r, p, cmd, s->v.step, 0, S, s->v.edge_guard, false);
		for (uint32_t step = s->v.step; step >= 2; step /= 2)
			for (uint32_t kind = 1; kind <= 2; kind++)
				vbuf_record_ads_step(r, p, cmd, step, kind, S, s->v.edge_guard, step == 2 && kind == 2);
	}
	render_ts(r, cmd);
	vbuf_record_resolve(r, p, cmd);
	if (!s->v.ads && s->v.rate_after) { /* its own interval ("history"; vbuf_vrs_passes): reads the resolved frame */
		vbuf_barrier(cmd);
		render_ts(r, cmd);
		if (!s->v.force)
			s->v.rate_after(r, p, s->v.user, cmd, frame);
		vbuf_barrier(cmd);
	}
	render_ts(r, cmd);
	vbuf_record_truth(r, p, cmd); /* its own interval, left out of the frame time (render.c) */
	render_ts(r, cmd);
	vbuf_record_finish(r, cmd);
}

static void put_extra(frame_stats *st, const char *name, double v)
{
	if (st->extra_count < FRAME_MAX_EXTRA) {
		st->extra_names[st->extra_count] = name;
		st->extra[st->extra_count++] = v;
	}
}

void vbuf_family_collect(render *r, frame_stats *st)
{
	vbuf_state *s = state_of(r);
	const uint32_t *c = s->p.counters.mapped;
	st->shaded_samples = c[VBUF_C_SHADED];
	st->reused_samples = st->visible_samples >= 0 ? st->visible_samples - st->shaded_samples : -1;
	st->visible_units = st->visible_samples;
	st->shaded_units = st->shaded_samples;
	st->new_units = -1;
	st->late_samples = s->v.truth ? (int64_t)c[VBUF_C_LATE] : -1;
	put_extra(st, "interpolated_samples", s->v.ads ? (double)c[VBUF_C_INTERPOLATED] : 0.0);
	put_extra(st, "filled_samples", (double)c[VBUF_C_FILLED]);
	/* the tile-rate histogram of the rates the select read (rate methods; empty for ads) */
	double hist[4] = {NAN, NAN, NAN, NAN};
	if (!s->v.ads) {
		hist[0] = hist[1] = hist[2] = hist[3] = 0;
		const uint32_t *rates = s->p.rates.mapped;
		for (uint32_t t = 0; t < s->p.tiles_x * s->p.tiles_y; t++) {
			uint32_t code = rates[t];
			hist[code == VBUF_RATE(1, 1) ? 0 : code == VBUF_RATE(2, 2) ? 1 : code == VBUF_RATE(4, 4) ? 2 : 3] += 1;
		}
	}
	put_extra(st, "tiles_1x1", hist[0]);
	put_extra(st, "tiles_2x2", hist[1]);
	put_extra(st, "tiles_4x4", hist[2]);
	put_extra(st, "tiles_other", hist[3]);
	put_extra(st, "listed_samples", (double)c[VBUF_C_LISTED]);
}

/* The frame_rate of a rate code of the path (w | h << 8); FRAME_RATE_COUNT for a code outside the palette. */
static uint8_t frame_rate_of(uint32_t code)
{
	static const uint32_t codes[FRAME_RATE_COUNT] = {
		[FRAME_RATE_4X4] = VBUF_RATE(4, 4), [FRAME_RATE_4X2] = VBUF_RATE(4, 2), [FRAME_RATE_2X4] = VBUF_RATE(2, 4),
		[FRAME_RATE_2X2] = VBUF_RATE(2, 2), [FRAME_RATE_2X1] = VBUF_RATE(2, 1), [FRAME_RATE_1X2] = VBUF_RATE(1, 2),
		[FRAME_RATE_1X1] = VBUF_RATE(1, 1)};
	uint8_t i = 0;
	while (i < FRAME_RATE_COUNT && codes[i] != code)
		i++;
	return i;
}

/* The rates the select of the last frame read, straight from the GPU's rate buffer (host visible), one frame_rate per
 * tile; NULL for ads (no tile rates) or when out of memory. */
const uint8_t *vbuf_family_tile_rates(render *r, uint32_t *tiles_x, uint32_t *tiles_y)
{
	vbuf_state *s = state_of(r);
	uint32_t n = s->p.tiles_x * s->p.tiles_y;
	*tiles_x = s->p.tiles_x, *tiles_y = s->p.tiles_y;
	if (s->v.ads || !s->p.rates.mapped)
		return NULL;
	if (!s->tile_rates && !(s->tile_rates = malloc(n)))
		return NULL;
	const uint32_t *rates = s->p.rates.mapped;
	for (uint32_t t = 0; t < n; t++)
		s->tile_rates[t] = frame_rate_of(rates[t]); /* outside the palette: FRAME_RATE_COUNT (no colour) */
	return s->tile_rates;
}

void vbuf_family_finish(render *r)
{
	vbuf_state *s = state_of(r);
	if (!s)
		return;
	free(s->tile_rates);
	if (s->v.rate_finish)
		s->v.rate_finish(r, &s->p, s->v.user);
	vbuf_finish(r, &s->p);
	free(s);
	r->method_state = NULL;
}
