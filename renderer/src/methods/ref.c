/* ref.c — `ref`: forward shading of every visible sample every frame (DESIGN section 4),
 * the reference all TAS methods are compared against. Passes: shadow maps, depth pre-pass
 * (so each visible sample is shaded exactly once, as in the paper's Forward+ baseline),
 * shading, display encoding, readback.
 *
 * `--ssaa K` (BASELINES.md A3, the target of amortized supersampling): the depth pre-pass and the shading run at
 * K*W x K*H into the method's own targets (every subsample shaded: shaded_samples counts K^2 per covered pixel), then
 * a K x K box filter in linear HDR ("downsample") writes the W x H target; coverage (alpha) is the covered fraction. */
#include "../passes/passes.h"

#include <stddef.h>
#include <stdlib.h>
#include <string.h>

typedef struct ref_options {
	uint32_t ssaa; /* K: subsamples per axis */
} ref_options;

static const uint32_t ssaa_factors[] = {1, 2, 3, 4, 0};

static const method_option ref_option_table[] = {
	{.name = "ssaa", .arg = "K", .help = "supersample: shade K x K samples per pixel, box-filtered in linear HDR "
					     "(1: plain ref)",
	 .type = METHOD_OPT_UINT, .offset = offsetof(ref_options, ssaa), .def = 1, .allowed = ssaa_factors, .variant = '-'},
};

typedef struct ref_state {
	uint32_t k;
	vkdev_image hdr, depth; /* K*W x K*H */
	VkDescriptorSetLayout set_layout;
	VkDescriptorSet set;
	VkPipelineLayout layout;
	VkPipeline down;
} ref_state;

static const char *const ref_passes[] = {"shadow", "depth", "shade", "display", "readback"};

static void ref_finish(render *r)
{
	ref_state *s = r->method_state;
	if (!s)
		return;
	VkDevice d = r->dev->device;
	if (s->down)
		vkDestroyPipeline(d, s->down, NULL);
	if (s->layout)
		vkDestroyPipelineLayout(d, s->layout, NULL);
	if (s->set_layout)
		vkDestroyDescriptorSetLayout(d, s->set_layout, NULL);
	vkdev_image_destroy(r->dev, &s->hdr);
	vkdev_image_destroy(r->dev, &s->depth);
	free(s);
	r->method_state = NULL;
}

static int ref_init(render *r, char *err, size_t err_size)
{
	const ref_options *o = (const ref_options *)r->config.values.bytes;
	if (o->ssaa <= 1)
		return TL_OK;
	ref_state *s = calloc(1, sizeof *s);
	if (!s)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	r->method_state = s;
	s->k = o->ssaa;
	uint32_t w = r->desc.width * s->k, h = r->desc.height * s->k;
	VkDevice d = r->dev->device;
	VkResult res;
	if ((res = vkdev_image_create(r->dev, w, h, 1, 1, RENDER_DEPTH_FORMAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
				      VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT, false, "ssaa depth", &s->depth)) ||
	    (res = vkdev_image_create(r->dev, w, h, 1, 1, VK_FORMAT_R16G16B16A16_SFLOAT,
				      VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT,
				      VK_IMAGE_ASPECT_COLOR_BIT, false, "ssaa hdr", &s->hdr)))
		return render_vk_error(err, err_size, "ssaa targets", res);
	VkDescriptorSetLayoutBinding b[2] = {
		{0, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL},
		{1, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL},
	};
	VkDescriptorSetLayoutCreateInfo li = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
					      .bindingCount = 2, .pBindings = b};
	if ((res = vkCreateDescriptorSetLayout(d, &li, NULL, &s->set_layout)))
		return render_vk_error(err, err_size, "ssaa: descriptor set layout", res);
	VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
					  .descriptorPool = r->pool, .descriptorSetCount = 1, .pSetLayouts = &s->set_layout};
	if ((res = vkAllocateDescriptorSets(d, &ai, &s->set)))
		return render_vk_error(err, err_size, "ssaa: descriptor set", res);
	const vkdev_image *imgs[2] = {&s->hdr, &r->hdr};
	const vkdev_buffer *bufs[2] = {NULL, NULL};
	vkdev_write_storage_set(d, s->set, 2, bufs, imgs);
	VkPipelineLayoutCreateInfo pl = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 1,
					 .pSetLayouts = &s->set_layout};
	if ((res = vkCreatePipelineLayout(d, &pl, NULL, &s->layout)))
		return render_vk_error(err, err_size, "ssaa: pipeline layout", res);
	char defs[48];
	snprintf(defs, sizeof defs, "#define SSAA_K %u\n", s->k);
	uint32_t *spv = NULL;
	size_t n = 0;
	int rc = render_compile_defs(r, "ref/ssaa_down.comp.in", defs, SHC_STAGE_COMPUTE, &spv, &n, err, err_size);
	if (rc)
		return rc;
	res = render_make_compute(r, spv, n, s->layout, &s->down);
	free(spv);
	return res ? render_vk_error(err, err_size, "ssaa downsample pipeline", res) : TL_OK;
}

static int ref_prepare(render *r, uint32_t frame, char *err, size_t err_size)
{
	render_update_state(r, 0, (double)frame / (double)r->desc.fps);
	return render_shadow_plan(r, 0, err, err_size);
}

/* The supersampled depth pre-pass and shading: the render's targets and size swapped for the method's own while
 * they record (the passes draw into r->depth / r->hdr over r->desc's size), then swapped back. */
static void record_supersampled(render *r, ref_state *s, VkCommandBuffer cmd, uint32_t slot)
{
	vkdev_image hdr = r->hdr, depth = r->depth;
	uint32_t w = r->desc.width, h = r->desc.height;
	r->hdr = s->hdr, r->depth = s->depth;
	r->desc.width = w * s->k, r->desc.height = h * s->k;
	render_pass_depth(r, cmd, slot);
	render_ts(r, cmd);
	render_pass_shade(r, cmd, slot);
	r->hdr = hdr, r->depth = depth;
	r->desc.width = w, r->desc.height = h;
	render_barrier(cmd, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
		       VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
	/* the box filter, inside the "shade" interval (the pass list is the method's, not the option's) */
	vkdev_barrier_image(cmd, &s->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
			    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
			    VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			    VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
	vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
			    VK_PIPELINE_STAGE_2_COPY_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			    VK_ACCESS_2_TRANSFER_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_READ_BIT,
			    VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s->down);
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s->layout, 0, 1, &s->set, 0, NULL);
	vkCmdDispatch(cmd, (w + 7) / 8, (h + 7) / 8, 1);
	/* the display pass takes the HDR target from the colour-attachment layout, as after ref's shading */
	vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL,
			    VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			    VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
			    VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
}

static void ref_record(render *r, VkCommandBuffer cmd, uint32_t frame)
{
	(void)frame;
	uint32_t slot = 0;
	ref_state *s = r->method_state;
	/* the shading counter (ref/count.glsl), zeroed before and made visible to the host after the shading */
	vkCmdFillBuffer(cmd, r->shade_count.buffer, 0, VK_WHOLE_SIZE, 0);
	render_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
		       VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT |
		       VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
	render_ts(r, cmd);
	render_pass_shadows(r, cmd, slot);
	render_ts(r, cmd);
	if (s) {
		record_supersampled(r, s, cmd, slot);
	} else {
		render_pass_depth(r, cmd, slot);
		render_ts(r, cmd);
		render_pass_shade(r, cmd, slot);
		render_barrier(cmd, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
			       VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
	}
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
	 * background (test_counters checks that on the goldens' scenes). With --ssaa K it counts every shaded
	 * subsample (about K^2 per covered pixel). */
	st->shaded_samples = (int64_t)*(const uint32_t *)r->shade_count.mapped;
	st->reused_samples = 0;
	st->visible_units = st->visible_samples;
	st->shaded_units = st->shaded_samples;
	st->new_units = -1; /* no temporal tracking in ref */
}

const render_method render_method_ref = {
	.info = {.name = "ref",
		 .summary = "forward shading of every visible sample every frame (the reference); --ssaa K supersampled",
		 .available = true,
		 .family = "reference",
		 .reference = true,
		 .options = ref_option_table,
		 .option_count = sizeof ref_option_table / sizeof ref_option_table[0],
		 .options_size = sizeof(ref_options)},
	.pass_names = ref_passes,
	.pass_count = sizeof ref_passes / sizeof ref_passes[0],
	.init = ref_init,
	.prepare = ref_prepare,
	.record = ref_record,
	.collect = ref_collect,
	.finish = ref_finish,
};
