/* method_ref.c — `ref`: forward shading of every visible sample every frame (DESIGN section 4),
 * the reference all TAS methods are compared against. Passes: shadow maps, depth pre-pass
 * (so each visible sample is shaded exactly once, as in the paper's Forward+ baseline),
 * shading, display encoding, readback. */
#include "../passes/passes.h"

static const char *const ref_passes[] = {"shadow", "depth", "shade", "display", "readback"};

static int ref_prepare(render *r, uint32_t frame, char *err, size_t err_size)
{
	render_update_state(r, 0, (double)frame / (double)r->desc.fps);
	return render_shadow_plan(r, 0, err, err_size);
}

static void ref_record(render *r, VkCommandBuffer cmd, uint32_t frame)
{
	(void)frame;
	uint32_t slot = 0;
	render_ts(r, cmd);
	render_pass_shadows(r, cmd, slot);
	render_ts(r, cmd);
	render_pass_depth(r, cmd, slot);
	render_ts(r, cmd);
	render_pass_shade(r, cmd, slot);
	render_ts(r, cmd);
	render_pass_display(r, cmd);
	render_ts(r, cmd);
	render_pass_readback(r, cmd);
	render_ts(r, cmd);
}

static void ref_collect(render *r, frame_stats *st)
{
	(void)r;
	/* Every visible sample is its own reuse unit and is shaded every frame. */
	st->shaded_samples = st->visible_samples;
	st->reused_samples = 0;
	st->visible_units = st->visible_samples;
	st->shaded_units = st->visible_samples;
	st->new_units = -1; /* no temporal tracking in ref */
}

const render_method render_method_ref = {
	.info = {.name = "ref",
		 .summary = "forward shading of every visible sample every frame (the reference)",
		 .available = true,
		 .family = "reference",
		 .reference = true},
	.pass_names = ref_passes,
	.pass_count = sizeof ref_passes / sizeof ref_passes[0],
	.prepare = ref_prepare,
	.record = ref_record,
	.collect = ref_collect,
};
