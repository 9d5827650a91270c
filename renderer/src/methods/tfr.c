/* tfr.c — `tfr`: temporal forward rendering at threshold T (DESIGN section 4, paper sec. 3).
 *
 * Every visible sample is shaded twice: now (s_0) and as it was a frames ago (s_a, every input taken
 * from the state slot of frame t - a: object transforms, lights, camera, shadow maps), where a is the
 * sample's age, carried along with the surface point by reprojection. The sample shows s_a while
 * d(s_a, s_0) <= T and a < K, else it is reshaded (tfr.frag.in). The result isolates outdated shading
 * from visibility and sampling changes — the stimulus of the paper's first study (Fig. 3).
 *
 * State: a ring of K + 1 = 120 state slots with their shadow maps (render_shadow.c shares unchanged
 * layers), two age images used alternately (previous -> next), counters for stats.csv. Frames must
 * come in order; a jump (or the first frame) starts every sample at age 0. */
#include "../passes/passes.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>


#define TFR_MAX_AGE 119 /* K: TFR keeps shading inputs of up to 119 past frames (paper sec. 5) */
#define TFR_RING (TFR_MAX_AGE + 1)

/* Options (method.h): the threshold T of the age policy and the largest age K. */
typedef struct tfr_options {
	float threshold; /* T in 8-bit code values: reshade when d(s_a, s_0) > T (DESIGN section 3) */
	uint32_t max_age; /* K: reshade at the latest at this age */
	bool truth;       /* write late_samples (always 0: tfr reuses only what is within T of s_0) */
} tfr_options;

static const method_option tfr_option_table[] = {
	{.name = "threshold", .arg = "T", .help = "reshade when the shading differs by more than T code values",
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(tfr_options, threshold), .def = 8, .min = 1e-6, .max = 255,
	 .variant = '@', .variant_required = true},
	{.name = "max-age", .arg = "K", .help = "reshade at the latest at age K frames", .type = METHOD_OPT_UINT,
	 .offset = offsetof(tfr_options, max_age), .def = TFR_MAX_AGE, .min = 1, .max = TFR_MAX_AGE},
	{.name = "truth", .help = "write late_samples: reused samples more than T from the truth (0 for tfr by construction; "
				  "counted, not assumed)",
	 .type = METHOD_OPT_BOOL, .offset = offsetof(tfr_options, truth)},
};

static const tfr_options *options(const render *r) { return (const tfr_options *)r->config.values.bytes; }

typedef struct tfr_state {
	uint32_t K;
	vkdev_image age[2];           /* rgba32ui: age after the frame, object + 1, view distance */
	vkdev_buffer counters;        /* reshaded, reused, disoccluded, late */
	VkDescriptorSetLayout set_layout;
	VkDescriptorSet sets[2];      /* sets[i]: read age[i], write age[1 - i] */
	render_pipeline pipe;
	uint32_t parity;              /* age[parity] holds the previous frame */
	int64_t last_frame;           /* -1: none */
	int have_prev;
} tfr_state;

static const char *const tfr_passes[] = {"shadow", "depth", "shade", "display", "readback"};

#define CHECK(call, what)                                                                          \
	do {                                                                                       \
		VkResult vr_ = (call);                                                             \
		if (vr_ != VK_SUCCESS) {                                                           \
			snprintf(err, err_size, "tfr: %s failed: %s", what, vkdev_result_string(vr_)); \
			return TL_ERR_VULKAN;                                                  \
		}                                                                                  \
	} while (0)

/* The shading pipeline (tfr.frag.in with the OCIO display function). */
static int tfr_pipeline(render *r, char *err, size_t err_size)
{
	tfr_state *t = r->method_state;
	uint32_t *spv = NULL;
	size_t spv_size = 0;
	render_pipeline_destroy(r, &t->pipe);
	int rc = render_compile(r, "tfr/tfr.frag.in", SHC_STAGE_FRAGMENT, &spv, &spv_size, err, err_size);
	if (rc)
		return rc;
	VkResult vr = render_make_shade_pipeline(r, spv, spv_size, t->set_layout, &t->pipe);
	free(spv);
	CHECK(vr, "shading pipeline");
	return 0;
}

static int tfr_init(render *r, char *err, size_t err_size)
{
	uint32_t K = options(r)->max_age;
	tfr_state *t = calloc(1, sizeof *t);
	if (!t) {
		snprintf(err, err_size, "out of memory");
		return TL_ERR_NOMEM;
	}
	r->method_state = t;
	t->K = K;
	t->last_frame = -1;
	VkDevice d = r->dev->device;
	for (int i = 0; i < 2; i++)
		CHECK(vkdev_image_create(r->dev, r->desc.width, r->desc.height, 1, 1, VK_FORMAT_R32G32B32A32_UINT,
					 VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
					 false, i ? "tfr age 1" : "tfr age 0", &t->age[i]),
		      "age image");
	CHECK(vkdev_buffer_create(r->dev, 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, true,
				  "tfr counters", &t->counters),
	      "counter buffer");
	VkDescriptorSetLayoutBinding b[3] = {
		{0, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_FRAGMENT_BIT, NULL},
		{1, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_FRAGMENT_BIT, NULL},
		{2, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_FRAGMENT_BIT, NULL},
	};
	VkDescriptorSetLayoutCreateInfo li = {
		.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO, .bindingCount = 3, .pBindings = b};
	CHECK(vkCreateDescriptorSetLayout(d, &li, NULL, &t->set_layout), "descriptor set layout");
	VkDescriptorSetLayout layouts[2] = {t->set_layout, t->set_layout};
	VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
					  .descriptorPool = r->pool, .descriptorSetCount = 2, .pSetLayouts = layouts};
	CHECK(vkAllocateDescriptorSets(d, &ai, t->sets), "descriptor sets");
	VkDescriptorBufferInfo bi = {t->counters.buffer, 0, VK_WHOLE_SIZE};
	for (int i = 0; i < 2; i++) {
		VkDescriptorImageInfo ii[2] = {{VK_NULL_HANDLE, t->age[i].view, VK_IMAGE_LAYOUT_GENERAL},
					       {VK_NULL_HANDLE, t->age[1 - i].view, VK_IMAGE_LAYOUT_GENERAL}};
		VkWriteDescriptorSet w[3] = {
			{.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = t->sets[i], .dstBinding = 0,
			 .descriptorCount = 1, .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, .pImageInfo = &ii[0]},
			{.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = t->sets[i], .dstBinding = 1,
			 .descriptorCount = 1, .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, .pImageInfo = &ii[1]},
			{.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = t->sets[i], .dstBinding = 2,
			 .descriptorCount = 1, .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .pBufferInfo = &bi},
		};
		vkUpdateDescriptorSets(d, 3, w, 0, NULL);
	}
	int rc = tfr_pipeline(r, err, err_size);
	if (rc)
		return rc;
	VkCommandBuffer cmd;
	CHECK(vkdev_cmd_begin(r->dev, &cmd), "command buffer");
	for (int i = 0; i < 2; i++)
		vkdev_barrier_image(cmd, &t->age[i], VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
				    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
				    VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
	CHECK(vkdev_cmd_submit_wait(r->dev, cmd), "age image setup");
	return 0;
}

static uint32_t slot_of(int64_t frame) { return (uint32_t)(frame % TFR_RING); }

static int tfr_prepare(render *r, uint32_t frame, char *err, size_t err_size)
{
	tfr_state *t = r->method_state;
	t->have_prev = t->last_frame >= 0 && (int64_t)frame == t->last_frame + 1;
	render_update_state(r, slot_of(frame), (double)frame / (double)r->desc.fps);
	return render_shadow_plan(r, slot_of(frame), err, err_size);
}

static void tfr_record(render *r, VkCommandBuffer cmd, uint32_t frame)
{
	tfr_state *t = r->method_state;
	uint32_t slot = slot_of(frame);
	vkCmdFillBuffer(cmd, t->counters.buffer, 0, VK_WHOLE_SIZE, 0);
	VkClearColorValue zero = {{0}};
	VkImageSubresourceRange range = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
	vkCmdClearColorImage(cmd, t->age[1 - t->parity].image, VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &range);
	VkMemoryBarrier2 mb = {
		.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER_2,
		.srcStageMask = VK_PIPELINE_STAGE_2_CLEAR_BIT | VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
		.srcAccessMask = VK_ACCESS_2_TRANSFER_WRITE_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
		.dstStageMask = VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
		.dstAccessMask = VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
	};
	VkDependencyInfo di = {.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO, .memoryBarrierCount = 1, .pMemoryBarriers = &mb};
	vkCmdPipelineBarrier2(cmd, &di);

	render_ts(r, cmd);
	render_pass_shadows(r, cmd, slot);
	render_ts(r, cmd);
	render_pass_depth(r, cmd, slot);
	render_ts(r, cmd);
	float T = options(r)->threshold;
	uint32_t tbits;
	memcpy(&tbits, &T, sizeof tbits);
	r->push_aux[0] = slot_of(frame + (int64_t)TFR_RING - 1);
	r->push_aux[1] = t->K;
	r->push_aux[2] = TFR_RING | (t->have_prev ? 1u << 31 : 0u);
	r->push_aux[3] = tbits;
	render_pass_shade_with(r, cmd, slot, &t->pipe, t->sets[t->parity]);
	memset(r->push_aux, 0, sizeof r->push_aux);
	mb.srcStageMask = VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT;
	mb.srcAccessMask = VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT;
	mb.dstStageMask = VK_PIPELINE_STAGE_2_HOST_BIT | VK_PIPELINE_STAGE_2_CLEAR_BIT | VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT;
	mb.dstAccessMask = VK_ACCESS_2_HOST_READ_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT | VK_ACCESS_2_SHADER_STORAGE_READ_BIT;
	vkCmdPipelineBarrier2(cmd, &di);
	render_ts(r, cmd);
	render_pass_display(r, cmd);
	render_ts(r, cmd);
	render_pass_readback(r, cmd);
	render_ts(r, cmd);
	t->parity = 1 - t->parity;
	t->last_frame = frame;
}

static void tfr_collect(render *r, frame_stats *st)
{
	tfr_state *t = r->method_state;
	const uint32_t *c = t->counters.mapped;
	st->shaded_samples = c[0];
	st->reused_samples = c[1];
	st->visible_units = st->visible_samples;
	st->shaded_units = c[0];
	st->new_units = c[2];
	st->late_samples = options(r)->truth ? (int64_t)c[3] : -1;
}

static void tfr_finish(render *r)
{
	tfr_state *t = r->method_state;
	if (!t)
		return;
	render_pipeline_destroy(r, &t->pipe);
	if (t->set_layout)
		vkDestroyDescriptorSetLayout(r->dev->device, t->set_layout, NULL);
	for (int i = 0; i < 2; i++)
		vkdev_image_destroy(r->dev, &t->age[i]);
	vkdev_buffer_destroy(r->dev, &t->counters);
	free(t);
	r->method_state = NULL;
}

const render_method render_method_tfr = {
	.info = {.name = "tfr",
		 .summary = "temporal forward rendering at threshold T: shading reused while within T of the truth (DESIGN section 4)",
		 .available = true,
		 .family = "forward",
		 .options = tfr_option_table,
		 .option_count = sizeof tfr_option_table / sizeof tfr_option_table[0],
		 .options_size = sizeof(tfr_options)},
	.pass_names = tfr_passes,
	.pass_count = sizeof tfr_passes / sizeof tfr_passes[0],
	.state_ring = TFR_RING,
	.init = tfr_init,
	.prepare = tfr_prepare,
	.record = tfr_record,
	.collect = tfr_collect,
	.finish = tfr_finish,
};
