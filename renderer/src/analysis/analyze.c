/* analyze.c — TFR analysis of single frames (see taslab/analyze.h; DESIGN section 4, paper secs. 4.1, 5).
 *
 * Device work per analysis frame t, all in the frame pipeline's passes (render.c):
 *   k = 0:   depth pre-pass at t - 1 + visibility records (tfa_vis.frag.in); shadow maps and depth
 *            pre-pass at t; s_0 and the visibility test (tfa_step.frag.in, k = 0)
 *   k >= 1:  shadow maps at t - k and t - k +- h; one shading pass of frame t's visible samples with
 *            the inputs of t - k (tfa_step.frag.in), updating the per-pixel scan state
 *   then:    gradients and coherence histogram (tfa_grad.comp), spatial max filter (passes/tas_filter.c,
 *            tas/max_*.comp), classification counters (tfa_classify.comp)
 * State slots: 0 = t, 1 = t - 1, 2 = t - k, 3 = t - k + h, 4 = t - k - h. Only the counters (and the
 * gradient images when asked) are read back. */
#include "taslab/analyze.h"

#include "../passes/passes.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shaders/analysis/tfa_classify_comp.h"
#include "shaders/analysis/tfa_grad_comp.h"

/* std430 mirror of `Analysis` in shaders/tfa.glsl */
typedef struct tfa_buffer {
	float thresholds[ANALYZE_MAX_T];
	uint32_t threshold_count, visible, visible_prev, want_inst, need_inst, pad[3];
	uint32_t hist[ANALYZE_MAX_T * (ANALYZE_HISTORY + 1)];
	uint32_t classes[ANALYZE_MAX_T * ANALYZE_PREDICTORS * ANALYZE_CLASSES];
} tfa_buffer;
_Static_assert(sizeof(tfa_buffer) == 64 + 4 * ANALYZE_MAX_T * (ANALYZE_HISTORY + 1 + ANALYZE_PREDICTORS * ANALYZE_CLASSES),
	       "std430 Analysis");

enum { IMG_S0, IMG_PREV, IMG_A, IMG_B, IMG_VIS, IMG_G, IMG_L1, IMG_L2, IMG_COUNT };
enum { COMP_GRAD, COMP_CLASSIFY, COMP_COUNT };

struct analyze {
	vkdev *dev;
	render *r;
	size_t nT;
	float T[ANALYZE_MAX_T];
	float h;
	uint64_t inst_passes;
	bool keep, inst;
	uint32_t lw, lh; /* filtered (8x8 downsampled) size */
	vkdev_image img[IMG_COUNT];
	vkdev_buffer buf, readback_g, readback_l2;
	VkDescriptorSetLayout set_layout;
	VkDescriptorSet set;
	render_pipeline vis_pipe, step_pipe;
	VkPipelineLayout comp_layout;
	VkPipeline comp[COMP_COUNT];
	tas_filter filter;            /* G -> L1 (8x8 max) -> L2 (9x9 max): the shared spatial max filter */
	VkDescriptorSet filter_set;
};



static const render_method analysis_ops = {
	.info = {.name = "tfr-analysis", .summary = "TFR analysis passes (internal)", .available = true},
	.state_ring = 5,
};

#define CHECK(call, what)                                                                                  \
	do {                                                                                               \
		VkResult vr_ = (call);                                                                     \
		if (vr_ != VK_SUCCESS) {                                                                   \
			snprintf(err, err_size, "analysis: %s failed: %s", what, vkdev_result_string(vr_)); \
			rc = TL_ERR_VULKAN;                                                            \
			goto fail;                                                                         \
		}                                                                                          \
	} while (0)

static int make_fragment(analyze *a, const char *template_path, render_pipeline *out, char *err, size_t err_size)
{
	uint32_t *spv = NULL;
	size_t n = 0;
	int rc = render_compile(a->r, template_path, SHC_STAGE_FRAGMENT, &spv, &n, err, err_size);
	if (rc)
		return rc;
	VkResult res = render_make_shade_pipeline(a->r, spv, n, a->set_layout, out);
	free(spv);
	if (res) {
		snprintf(err, err_size, "analysis: pipeline creation failed: %s", vkdev_result_string(res));
		return TL_ERR_VULKAN;
	}
	return 0;
}

static void barrier_all(VkCommandBuffer cmd)
{
	VkMemoryBarrier2 mb = {
		.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER_2,
		.srcStageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
		.srcAccessMask = VK_ACCESS_2_MEMORY_WRITE_BIT,
		.dstStageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
		.dstAccessMask = VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT,
	};
	VkDependencyInfo di = {.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO, .memoryBarrierCount = 1, .pMemoryBarriers = &mb};
	vkCmdPipelineBarrier2(cmd, &di);
}

int analyze_create(vkdev *dev, const analyze_desc *desc, analyze **out, char *err, size_t err_size)
{
	int rc = 0;
	*out = NULL;
	if (!desc->threshold_count || desc->threshold_count > ANALYZE_MAX_T || !desc->thresholds) {
		snprintf(err, err_size, "analysis needs 1..%d thresholds", ANALYZE_MAX_T);
		return TL_ERR_ARG;
	}
	for (size_t i = 0; i < desc->threshold_count; i++)
		if (!(desc->thresholds[i] > 0.0f) || desc->thresholds[i] > 255.0f) {
			snprintf(err, err_size, "threshold %g out of range: T must be > 0 and <= 255 (8-bit code values)",
				 (double)desc->thresholds[i]);
			return TL_ERR_ARG;
		}
	if (desc->inst_step < 0.0f || desc->inst_step > 0.5f) {
		snprintf(err, err_size, "instantaneous step h = %g frames out of range (0 < h <= 0.5)", (double)desc->inst_step);
		return TL_ERR_ARG;
	}
	analyze *a = calloc(1, sizeof *a);
	if (!a) {
		snprintf(err, err_size, "out of memory");
		return TL_ERR_NOMEM;
	}
	a->dev = dev;
	a->nT = desc->threshold_count;
	memcpy(a->T, desc->thresholds, a->nT * sizeof *a->T);
	a->h = desc->inst_step > 0.0f ? desc->inst_step : 0.125f;
	a->keep = desc->keep_gradients;
	a->inst = desc->predictors;
	render_desc rd = {.scene = desc->scene, .camera = desc->camera, .width = desc->width, .height = desc->height,
			  .fps = desc->fps, .colour = desc->colour};
	if ((rc = render_create_ops(dev, &rd, &analysis_ops, &a->r, err, err_size)))
		goto fail;
	uint32_t w = desc->width, h = desc->height, nT = (uint32_t)a->nT;
	a->lw = (w + 7) / 8;
	a->lh = (h + 7) / 8;
	static const char *names[IMG_COUNT] = {"tfa s0", "tfa prev", "tfa A", "tfa B", "tfa vis", "tfa G", "tfa L1", "tfa L2"};
	for (int i = 0; i < IMG_COUNT; i++) {
		int low = i == IMG_L1 || i == IMG_L2, arr = i == IMG_A || i == IMG_B || i >= IMG_G;
		CHECK(vkdev_image_create(dev, low ? a->lw : w, low ? a->lh : h, arr ? nT : 1, 1,
					 i == IMG_VIS ? VK_FORMAT_R32G32B32A32_UINT : VK_FORMAT_R32G32B32A32_SFLOAT,
					 VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
					 VK_IMAGE_ASPECT_COLOR_BIT, arr, names[i], &a->img[i]),
		      "image creation");
	}
	CHECK(vkdev_buffer_create(dev, sizeof(tfa_buffer), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true, "tfa counters", &a->buf),
	      "buffer creation");
	if (a->keep) {
		CHECK(vkdev_buffer_create(dev, (VkDeviceSize)w * h * nT * 16, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true,
					  "tfa gradients", &a->readback_g),
		      "buffer creation");
		CHECK(vkdev_buffer_create(dev, (VkDeviceSize)a->lw * a->lh * nT * 16, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true,
					  "tfa filtered gradients", &a->readback_l2),
		      "buffer creation");
	}
	VkShaderStageFlags st = VK_SHADER_STAGE_FRAGMENT_BIT | VK_SHADER_STAGE_COMPUTE_BIT;
	VkDescriptorSetLayoutBinding b[IMG_COUNT + 1];
	for (uint32_t i = 0; i < IMG_COUNT; i++)
		b[i] = (VkDescriptorSetLayoutBinding){i, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, st, NULL};
	b[IMG_COUNT] = (VkDescriptorSetLayoutBinding){IMG_COUNT, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, st, NULL};
	VkDescriptorSetLayoutCreateInfo li = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
					      .bindingCount = IMG_COUNT + 1, .pBindings = b};
	CHECK(vkCreateDescriptorSetLayout(dev->device, &li, NULL, &a->set_layout), "descriptor set layout");
	VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
					  .descriptorPool = a->r->pool, .descriptorSetCount = 1, .pSetLayouts = &a->set_layout};
	CHECK(vkAllocateDescriptorSets(dev->device, &ai, &a->set), "descriptor set");
	VkDescriptorImageInfo ii[IMG_COUNT];
	VkWriteDescriptorSet wr[IMG_COUNT + 1];
	for (uint32_t i = 0; i < IMG_COUNT; i++) {
		ii[i] = (VkDescriptorImageInfo){VK_NULL_HANDLE, a->img[i].view, VK_IMAGE_LAYOUT_GENERAL};
		wr[i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = a->set,
					       .dstBinding = i, .descriptorCount = 1,
					       .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, .pImageInfo = &ii[i]};
	}
	VkDescriptorBufferInfo bi = {a->buf.buffer, 0, VK_WHOLE_SIZE};
	wr[IMG_COUNT] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = a->set,
					       .dstBinding = IMG_COUNT, .descriptorCount = 1,
					       .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .pBufferInfo = &bi};
	vkUpdateDescriptorSets(dev->device, IMG_COUNT + 1, wr, 0, NULL);

	if ((rc = make_fragment(a, "analysis/tfa_vis.frag.in", &a->vis_pipe, err, err_size)) ||
	    (rc = make_fragment(a, "analysis/tfa_step.frag.in", &a->step_pipe, err, err_size)))
		goto fail;
	VkDescriptorSetLayout sets[2] = {a->r->scene_set_layout, a->set_layout};
	VkPipelineLayoutCreateInfo pl = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 2,
					 .pSetLayouts = sets};
	CHECK(vkCreatePipelineLayout(dev->device, &pl, NULL, &a->comp_layout), "pipeline layout");
	CHECK(render_make_compute(a->r, tfa_grad_comp, sizeof tfa_grad_comp, a->comp_layout, &a->comp[COMP_GRAD]), "compute pipeline");
	CHECK(render_make_compute(a->r, tfa_classify_comp, sizeof tfa_classify_comp, a->comp_layout, &a->comp[COMP_CLASSIFY]), "compute pipeline");
	if ((rc = tas_filter_init(a->r, &a->filter, err, err_size)) ||
	    (rc = tas_filter_bind(a->r, &a->filter, &a->img[IMG_G], &a->img[IMG_L1], &a->img[IMG_L2], &a->filter_set, err,
				  err_size)))
		goto fail;

	VkCommandBuffer cmd;
	CHECK(vkdev_cmd_begin(dev, &cmd), "command buffer");
	for (int i = 0; i < IMG_COUNT; i++)
		vkdev_barrier_image(cmd, &a->img[i], VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
				    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
				    VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
	CHECK(vkdev_cmd_submit_wait(dev, cmd), "image setup");
	*out = a;
	return 0;
fail:
	analyze_destroy(&a);
	return rc;
}

void analyze_destroy(analyze **pa)
{
	if (!pa || !*pa)
		return;
	analyze *a = *pa;
	VkDevice d = a->dev->device;
	vkDeviceWaitIdle(d);
	for (int i = 0; i < COMP_COUNT; i++)
		if (a->comp[i])
			vkDestroyPipeline(d, a->comp[i], NULL);
	if (a->comp_layout)
		vkDestroyPipelineLayout(d, a->comp_layout, NULL);
	if (a->r) {
		tas_filter_finish(a->r, &a->filter);
		render_pipeline_destroy(a->r, &a->vis_pipe);
		render_pipeline_destroy(a->r, &a->step_pipe);
	}
	if (a->set_layout)
		vkDestroyDescriptorSetLayout(d, a->set_layout, NULL);
	for (int i = 0; i < IMG_COUNT; i++)
		vkdev_image_destroy(a->dev, &a->img[i]);
	vkdev_buffer_destroy(a->dev, &a->buf);
	vkdev_buffer_destroy(a->dev, &a->readback_g);
	vkdev_buffer_destroy(a->dev, &a->readback_l2);
	if (a->r && getenv("TASLAB_DEBUG_SHADOWS"))
		fprintf(stderr, "analysis: derivative passes %llu\n", (unsigned long long)a->inst_passes);
	render_destroy(&a->r);
	free(a);
	*pa = NULL;
}

/* State slot `slot` at frame time `f` (may be fractional or negative), with its shadow maps planned. */
static int set_slot(analyze *a, uint32_t slot, double f, char *err, size_t err_size)
{
	render_update_state(a->r, slot, f / (double)a->r->desc.fps);
	return render_shadow_plan(a->r, slot, err, err_size);
}

static void dispatch(analyze *a, VkCommandBuffer cmd, int which, uint32_t w, uint32_t h)
{
	VkDescriptorSet sets[2] = {a->r->scene_set, a->set};
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, a->comp[which]);
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, a->comp_layout, 0, 2, sets, 0, NULL);
	vkCmdDispatch(cmd, (w + 7) / 8, (h + 7) / 8, 1);
	barrier_all(cmd);
}

int analyze_frame(analyze *a, uint32_t frame, analyze_result *out, char *err, size_t err_size)
{
	int rc = 0;
	render *r = a->r;
	uint32_t w = r->desc.width, h = r->desc.height;
	VkCommandBuffer cmd = r->cmd;
	memset(out, 0, sizeof *out);
	tfa_buffer *buf = a->buf.mapped;
	memset(buf, 0, sizeof *buf);
	buf->threshold_count = (uint32_t)a->nT;
	buf->want_inst = a->inst;
	for (size_t i = 0; i < a->nT; i++)
		buf->thresholds[i] = a->T[i];
	uint32_t hbits;
	memcpy(&hbits, &a->h, sizeof hbits);

	/* k = 0: visibility at t - 1, then frame t's depth and s_0. */
	if ((rc = set_slot(a, 0, frame, err, err_size)))
		goto fail;
	render_update_state(r, 1, ((double)frame - 1.0) / (double)r->desc.fps);
	CHECK(render_cmd_begin(r), "command buffer");
	VkClearColorValue zero = {{0}};
	for (int i = 0; i < IMG_COUNT; i++) {
		VkImageSubresourceRange range = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, a->img[i].layers};
		vkCmdClearColorImage(cmd, a->img[i].image, VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &range);
	}
	barrier_all(cmd);
	render_pass_depth(r, cmd, 1);
	render_pass_shade_with(r, cmd, 1, &a->vis_pipe, a->set);
	barrier_all(cmd);
	render_pass_shadows(r, cmd, 0);
	render_pass_depth(r, cmd, 0);
	r->push_aux[0] = 0;
	r->push_aux[1] = hbits;
	render_pass_shade_with(r, cmd, 0, &a->step_pipe, a->set);
	barrier_all(cmd);
	CHECK(render_cmd_submit_wait(r), "k = 0 submission");

	/* k = 1..120: shading of t's visible samples with the inputs of t - k; when some sample finds its
	 * first exceedance at k, a second pass evaluates the instantaneous derivatives at t - k (the states
	 * and shadow maps at t - k +- h are only rendered then). */
	for (uint32_t k = 1; k <= ANALYZE_HISTORY; k++) {
		double fk = (double)frame - (double)k;
		if ((rc = set_slot(a, 2, fk, err, err_size)))
			goto fail;
		CHECK(render_cmd_begin(r), "command buffer");
		render_pass_shadows(r, cmd, 2);
		r->push_aux[0] = k;
		r->push_aux[1] = hbits;
		r->push_aux[2] = 0;
		render_pass_shade_with(r, cmd, 0, &a->step_pipe, a->set);
		barrier_all(cmd);
		CHECK(render_cmd_submit_wait(r), "history step submission");
		if (!buf->need_inst)
			continue;
		buf->need_inst = 0;
		a->inst_passes++;
		if ((rc = set_slot(a, 3, fk + a->h, err, err_size)) || (rc = set_slot(a, 4, fk - a->h, err, err_size)))
			goto fail;
		CHECK(render_cmd_begin(r), "command buffer");
		render_pass_shadows(r, cmd, 3);
		render_pass_shadows(r, cmd, 4);
		r->push_aux[2] = 1;
		render_pass_shade_with(r, cmd, 0, &a->step_pipe, a->set);
		barrier_all(cmd);
		CHECK(render_cmd_submit_wait(r), "derivative pass submission");
	}
	memset(r->push_aux, 0, sizeof r->push_aux);

	/* Gradients, filter, classification. */
	CHECK(render_cmd_begin(r), "command buffer");
	dispatch(a, cmd, COMP_GRAD, w, h);
	tas_filter_record(&a->filter, cmd, a->filter_set, w, h, (uint32_t)a->nT);
	barrier_all(cmd);
	dispatch(a, cmd, COMP_CLASSIFY, w, h);
	if (a->keep) {
		uint32_t nT = (uint32_t)a->nT;
		VkBufferImageCopy g = {.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, nT}, .imageExtent = {w, h, 1}};
		VkBufferImageCopy l = {.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, nT},
				       .imageExtent = {a->lw, a->lh, 1}};
		for (int i = IMG_G; i <= IMG_L2; i += IMG_L2 - IMG_G)
			vkdev_barrier_image(cmd, &a->img[i], VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL,
					    VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
					    VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
					    VK_ACCESS_2_TRANSFER_READ_BIT);
		vkCmdCopyImageToBuffer(cmd, a->img[IMG_G].image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, a->readback_g.buffer, 1, &g);
		vkCmdCopyImageToBuffer(cmd, a->img[IMG_L2].image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, a->readback_l2.buffer, 1, &l);
		for (int i = IMG_G; i <= IMG_L2; i += IMG_L2 - IMG_G)
			vkdev_barrier_image(cmd, &a->img[i], VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
					    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT,
					    VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
	}
	VkMemoryBarrier2 mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER_2,
			       .srcStageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
			       .srcAccessMask = VK_ACCESS_2_MEMORY_WRITE_BIT,
			       .dstStageMask = VK_PIPELINE_STAGE_2_HOST_BIT,
			       .dstAccessMask = VK_ACCESS_2_HOST_READ_BIT};
	VkDependencyInfo di = {.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO, .memoryBarrierCount = 1, .pMemoryBarriers = &mb};
	vkCmdPipelineBarrier2(cmd, &di);
	CHECK(render_cmd_submit_wait(r), "resolve submission");

	out->frame = frame;
	out->width = w;
	out->height = h;
	out->threshold_count = a->nT;
	out->visible = buf->visible;
	out->visible_prev = buf->visible_prev;
	for (size_t i = 0; i < a->nT; i++) {
		/* unchanged[k] = samples whose coherent length L >= k */
		uint64_t acc = 0;
		for (int k = ANALYZE_HISTORY; k >= 0; k--) {
			acc += buf->hist[i * (ANALYZE_HISTORY + 1) + (size_t)k];
			out->unchanged[i][k] = acc;
		}
		for (int p = 0; p < ANALYZE_PREDICTORS; p++)
			for (int c = 0; c < ANALYZE_CLASSES; c++)
				out->classes[i][p][c] = buf->classes[(i * ANALYZE_PREDICTORS + (size_t)p) * ANALYZE_CLASSES + (size_t)c];
	}
	if (a->keep) {
		size_t ng = (size_t)w * h * a->nT * 4, nl = (size_t)a->lw * a->lh * a->nT * 4;
		out->gradients = malloc(ng * sizeof(float));
		out->gradients_filtered = malloc(nl * sizeof(float));
		if (!out->gradients || !out->gradients_filtered) {
			analyze_result_free(out);
			snprintf(err, err_size, "out of memory for the gradient images");
			return TL_ERR_NOMEM;
		}
		memcpy(out->gradients, a->readback_g.mapped, ng * sizeof(float));
		memcpy(out->gradients_filtered, a->readback_l2.mapped, nl * sizeof(float));
		out->filtered_width = a->lw;
		out->filtered_height = a->lh;
	}
	return 0;
fail:
	memset(r->push_aux, 0, sizeof r->push_aux);
	return rc;
}
