/* ref.c — `ref`: forward shading of every visible sample every frame (DESIGN section 4),
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
	/* the shading counter (ref/count.glsl), zeroed before and made visible to the host after the shading */
	vkCmdFillBuffer(cmd, r->shade_count.buffer, 0, VK_WHOLE_SIZE, 0);
	render_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
		       VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT |
		       VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
	render_ts(r, cmd);
	render_pass_shadows(r, cmd, slot);
	render_ts(r, cmd);
	render_pass_depth(r, cmd, slot);
	render_ts(r, cmd);
	render_pass_shade(r, cmd, slot);
	render_barrier(cmd, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
		       VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
	render_ts(r, cmd);
	render_pass_display(r, cmd);
	render_ts(r, cmd);
	render_pass_readback(r, cmd);
	render_ts(r, cmd);
}

static void ref_collect(render *r, frame_stats *st)
{
	/* Every visible sample is its own reuse unit and is shaded every frame. shaded_samples is counted by the
	 * shading pass itself (issue 24.3); equal to the visible samples where no BLEND surface covers the
	 * background (test_counters checks that on the goldens' scenes). */
	st->shaded_samples = (int64_t)*(const uint32_t *)r->shade_count.mapped;
	st->reused_samples = 0;
	st->visible_units = st->visible_samples;
	st->shaded_units = st->shaded_samples;
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
