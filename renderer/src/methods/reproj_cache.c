/* reproj_cache.c — the reprojection cache of rrc and tarc (reproj_cache.h; TAS-METHODS sections 1-3, 8).
 *
 * Frame t, in order (state slots t and t - 1, consecutive frames; a jump or the first frame starts over):
 *   shadow maps                                     (shared pass)
 *   pre-pass   the shared pre-pass's depths (LESS_OR_EQUAL), clears the stencil, and writes per sample the record
 *              of the lookup (object, previous position, both view distances: reproj/prepass.frag.in; its
 *              vertex shader reproject.vert computes them per vertex, so no fragment reads a matrix)
 *   reproject  screen space (reproj/reproject.comp.in; issue 32.1, lever 3): from the record, C' and the
 *              provisional state into the next cache (its colour cleared to the sky first)
 *   filter     tarc: G (the steady samples' gradients, read from the provisional state by
 *              reproj/max_down_state.comp) -> 8x8 max -> 9x9 max = F (passes/tas_filter.c, as the TFR analysis)
 *   mark       full-screen: stencil = 1 where the sample is reshaded (discard elsewhere)
 *   shade      scene geometry, depth EQUAL + stencil EQUAL 1: the reference shading into the next cache only
 *              (oracle: every sample, no stencil test); then the next cache colour, now the opaque frame, is
 *              copied into the HDR target (copy_colour_to_hdr)
 *   compose    rrc --payload (BASELINES A5): the shading pass above computes the payload only (reproj/payload.frag.in),
 *              into the next cache, whose colour channels then hold it; this pass shades every sample with it into the
 *              HDR target (reproj/compose.frag.in, depth EQUAL, no stencil test), in place of the copy
 *   truth      --truth: stencil EQUAL 0, counts reused samples more than T from the truth
 *   blend      glTF BLEND objects with the reference shading on top (excluded from the counters)
 *   display, readback
 * Reused samples launch no shading: the decision is a stencil mask coherent over 16x16 tiles (rrc) or the
 * 8x8 tiles of the filter (tarc), and lavapipe skips 4x2 pixel groups that fail the stencil test. */
#include "reproj_cache.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "method_debug.h"
#include "shaders/reproj/max_down_state_comp.h"
#include "shaders/reproj/reproject_mask_vert.h"
#include "shaders/reproj/reproject_vert.h"

/* DISP0/1: tarc's display values of the cached colour (reproj.glsl KEEP_DISP, fixed point in RG32UI: disp_pack); one
 * texel each for rrc and the oracle.
 * RECORD: the pre-pass record (reproj.glsl prepass_record), a colour attachment of the pre-pass. */
enum { IMG_COLOUR0, IMG_COLOUR1, IMG_STATE0, IMG_STATE1, IMG_RECORD, IMG_L1, IMG_F, IMG_DISP0, IMG_DISP1, IMG_COUNT };
/* reproj.glsl prepass_record: 22 bits of object + 1, 21 bits per axis of the lookup position (< 64 * (size + 1)) */
#define REPROJ_MAX_OBJECTS ((1u << 22) - 2u)
#define REPROJ_MAX_SIZE 32766u

typedef struct reproj_state {
	reproj_variant v;
	vkdev_image img[IMG_COUNT];
	vkdev_buffer counters; /* 8 uints, host visible (Counters in reproj.glsl) */
	vkdev_buffer decision_buf; /* render --decisions: the next cache state, host visible */
	uint8_t *decision_codes;   /* frame_decision per pixel, unpacked from decision_buf */
	VkDescriptorSetLayout set_layout;
	VkDescriptorSet sets[2]; /* sets[p]: read cache p, write cache 1 - p */
	render_pipeline prepass, prepass_mask, mark, shade, truth, compose;
	VkPipelineLayout reproject_layout; /* set 0 the scene set, set 1 set_layout; compute push constants */
	VkPipeline reproject;
	tas_filter filter;
	VkDescriptorSet filter_sets[2]; /* filter_sets[p]: reads cache state p (the one the frame writes) */
	uint32_t parity;         /* cache `parity` holds the previous frame */
	int64_t last_frame;      /* -1: none */
	bool have_prev;
} reproj_state;

static reproj_state *state_of(render *r) { return r->method_state; }

/* The counters' defines for the shaders (reproj.glsl COUNT): one atomic per subgroup where the device allows, as
 * ref counts its shading (render_count_mode_of; TASLAB_COUNT_ATOMICS=1: one per fragment, test_reuse compares). */
/* compute: for the screen-space reproject pass, which has no helper invocations and needs subgroup operations in
 * the compute stage. */
static const char *count_defines(VkPhysicalDevice pd, bool compute)
{
	render_count_mode mode;
	if (compute) /* (compute has no helper invocations) */
		mode = render_compute_ballot(pd) ? RENDER_COUNT_SUBGROUP_NO_HELPERS : RENDER_COUNT_ATOMIC;
	else
		mode = render_count_mode_of(pd);
	switch (mode) {
	case RENDER_COUNT_SUBGROUP_NO_HELPERS:
		return "#define TL_SUBGROUP 1\n#define TL_NO_HELPERS 1\n";
	case RENDER_COUNT_SUBGROUP:
		return "#define TL_SUBGROUP 1\n";
	default:
		return "";
	}
}

/* The pre-pass pipelines: depth writes, LESS_OR_EQUAL (the same depths as the shared pre-pass's LESS, and the record
 * of the last drawn of the nearest fragments, as the EQUAL pass it replaces left), the stencil attached (the pass
 * clears it), the record as an RGBA32UI colour attachment; masked objects alpha-tested (MASK). */
static int make_prepass(render *r, reproj_state *s, const char *defs, char *err, size_t err_size)
{
	for (int mask = 0; mask < 2; mask++) {
		if (mask && !render_has_alpha_mode(r, SCENE_ALPHA_MASK))
			break;
		char d[224];
		snprintf(d, sizeof d, "%s%s", defs, mask ? "#define MASK 1\n" : "");
		uint32_t *spv = NULL;
		size_t spv_size = 0;
		int rc = render_compile_defs(r, "reproj/prepass.frag.in", d, SHC_STAGE_FRAGMENT, &spv, &spv_size, err, err_size);
		if (rc)
			return rc;
		render_pipe_desc pd = {.vs = mask ? reproject_mask_vert : reproject_vert,
				       .vs_size = mask ? sizeof reproject_mask_vert : sizeof reproject_vert,
				       .fs = spv, .fs_size = spv_size,
				       .attributes = RENDER_ATTR_POSITION | (mask ? RENDER_ATTR_UV : 0u), .color = 1,
				       .color_format = VK_FORMAT_R32G32B32A32_UINT, .depth_write = 1,
				       .depth_op = VK_COMPARE_OP_LESS_OR_EQUAL, .stencil = RENDER_STENCIL_ATTACHED};
		VkResult res = render_make_graphics(r, &pd, mask ? &s->prepass_mask : &s->prepass);
		free(spv);
		if (res)
			return render_vk_error(err, err_size, "reproj/prepass.frag.in", res);
	}
	return TL_OK;
}

static int make_reproject(render *r, reproj_state *s, const char *defs, char *err, size_t err_size)
{
	VkDescriptorSetLayout layouts[2] = {r->scene_set_layout, s->set_layout};
	VkPushConstantRange pcr = {VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(gpu_push)};
	VkPipelineLayoutCreateInfo pl = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 2,
					 .pSetLayouts = layouts, .pushConstantRangeCount = 1, .pPushConstantRanges = &pcr};
	VkResult res = vkCreatePipelineLayout(r->dev->device, &pl, NULL, &s->reproject_layout);
	if (res)
		return render_vk_error(err, err_size, "reproject pass: pipeline layout", res);
	char d[224];
	snprintf(d, sizeof d, "%s%s", defs, count_defines(r->dev->physical, true));
	return render_compute_defs(r, "reproj/reproject.comp.in", d, s->reproject_layout, &s->reproject, err, err_size);
}

static int make_pipelines(render *r, reproj_state *s, char *err, size_t err_size)
{
	char defs[256], vdefs[160];
	static const char *const payload_defs[] = {"", "#define PAYLOAD 1\n#define PAYLOAD_SHADOW 1\n",
						   "#define PAYLOAD 1\n#define PAYLOAD_DIFFUSE 1\n"};
	snprintf(vdefs, sizeof vdefs, "%s%s%s%s", s->v.tarc ? "#define TARC 1\n" : "", s->v.oracle ? "#define ORACLE 1\n" : "",
		 s->v.nearest ? "#define NEAREST 1\n" : "", payload_defs[s->v.payload]);
	snprintf(defs, sizeof defs, "%s%s", vdefs, count_defines(r->dev->physical, false));
	int rc = make_prepass(r, s, vdefs, err, err_size);
	if (!rc)
		rc = make_reproject(r, s, vdefs, err, err_size);
	if (rc)
		return rc;
	const char *shade = s->v.payload ? "reproj/payload.frag.in" : "reproj/shade.frag.in";
	if ((rc = render_make_template_pipeline(r, shade, defs, s->set_layout,
						s->v.oracle ? RENDER_STENCIL_ATTACHED : RENDER_STENCIL_EQUAL_ONE, 0, 0, &s->shade,
						err, err_size)))
		return rc;
	if (s->v.payload && (rc = render_make_template_pipeline(r, "reproj/compose.frag.in", defs, s->set_layout,
								RENDER_STENCIL_NONE, 1, 0, &s->compose, err, err_size)))
		return rc;
	if (!s->v.oracle && (rc = render_make_template_pipeline(r, "reproj/mark.frag.in", defs, s->set_layout,
								RENDER_STENCIL_WRITE_ONE, 0, 1, &s->mark, err, err_size)))
		return rc;
	if (s->v.truth && !s->v.oracle &&
	    (rc = render_make_template_pipeline(r, "reproj/truth.frag.in", defs, s->set_layout, RENDER_STENCIL_EQUAL_ZERO,
						0, 0, &s->truth, err, err_size)))
		return rc;
	return TL_OK;
}

static int make_sets(render *r, reproj_state *s, char *err, size_t err_size)
{
	VkDevice d = r->dev->device;
	VkResult res;
	VkShaderStageFlags st = VK_SHADER_STAGE_FRAGMENT_BIT | VK_SHADER_STAGE_COMPUTE_BIT;
	/* bindings 0-3, 5 and 7-9 images, 6 the counters (reproj.glsl; 9 the pre-pass record; no binding 4) */
	static const uint32_t nums[9] = {0, 1, 2, 3, 5, 7, 8, 9, 6};
	VkDescriptorSetLayoutBinding b[9];
	for (uint32_t i = 0; i < 9; i++)
		b[i] = (VkDescriptorSetLayoutBinding){nums[i], nums[i] == 6 ? VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
									   : VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
						      1, st, NULL};
	VkDescriptorSetLayoutCreateInfo li = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
					      .bindingCount = 9, .pBindings = b};
	if ((res = vkCreateDescriptorSetLayout(d, &li, NULL, &s->set_layout)))
		return render_vk_error(err, err_size, "reprojection cache: descriptor set layout", res);
	VkDescriptorSetLayout layouts[2] = {s->set_layout, s->set_layout};
	VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
					  .descriptorPool = r->pool, .descriptorSetCount = 2, .pSetLayouts = layouts};
	if ((res = vkAllocateDescriptorSets(d, &ai, s->sets)))
		return render_vk_error(err, err_size, "reprojection cache: descriptor sets", res);
	for (int p = 0; p < 2; p++) {
		const vkdev_image *im[8] = {&s->img[IMG_COLOUR0 + p], &s->img[IMG_STATE0 + p], &s->img[IMG_COLOUR0 + 1 - p],
					    &s->img[IMG_STATE0 + 1 - p], &s->img[IMG_F],
					    &s->img[IMG_DISP0 + p], &s->img[IMG_DISP0 + 1 - p], &s->img[IMG_RECORD]};
		VkDescriptorImageInfo ii[8];
		VkWriteDescriptorSet w[9];
		for (uint32_t i = 0; i < 8; i++) {
			ii[i] = (VkDescriptorImageInfo){VK_NULL_HANDLE, im[i]->view, VK_IMAGE_LAYOUT_GENERAL};
			w[i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET,
								 .dstSet = s->sets[p], .dstBinding = nums[i],
								 .descriptorCount = 1,
								 .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
								 .pImageInfo = &ii[i]};
		}
		VkDescriptorBufferInfo bi = {s->counters.buffer, 0, VK_WHOLE_SIZE};
		w[8] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = s->sets[p],
					      .dstBinding = 6, .descriptorCount = 1,
					      .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .pBufferInfo = &bi};
		vkUpdateDescriptorSets(d, 9, w, 0, NULL);
	}
	return TL_OK;
}

int reproj_init(render *r, const reproj_variant *v, char *err, size_t err_size)
{
	reproj_state *s = calloc(1, sizeof *s);
	if (!s)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	r->method_state = s;
	s->v = *v;
	s->last_frame = -1;
	uint32_t w = r->desc.width, h = r->desc.height, lw = (w + 7) / 8, lh = (h + 7) / 8;
	if (r->scene->object_count > REPROJ_MAX_OBJECTS || w > REPROJ_MAX_SIZE || h > REPROJ_MAX_SIZE)
		return tl_error(err, err_size, TL_ERR_UNSUPPORTED,
				"rrc/tarc take at most %u objects and %u pixels a side (the pre-pass record packs both), not %zu "
				"objects at %ux%u",
				REPROJ_MAX_OBJECTS, REPROJ_MAX_SIZE, (size_t)r->scene->object_count, w, h);
	static const char *const names[IMG_COUNT] = {"cache colour 0", "cache colour 1", "cache state 0", "cache state 1",
						      "pre-pass record", "tarc L1", "tarc F", "tarc disp 0", "tarc disp 1"};
	VkResult res;
	for (int i = 0; i < IMG_COUNT; i++) {
		int low = i == IMG_L1 || i == IMG_F, arr = low, disp = i >= IMG_DISP0;
		/* --payload: the colour images hold the payload, 32 bits per channel (reproj.glsl PAYLOAD) */
		VkFormat f = i <= IMG_COLOUR1 ? (v->payload ? VK_FORMAT_R32G32B32A32_UINT : VK_FORMAT_R16G16B16A16_SFLOAT)
			     : i <= IMG_RECORD ? VK_FORMAT_R32G32B32A32_UINT
			     : disp ? VK_FORMAT_R32G32_UINT : VK_FORMAT_R32G32B32A32_SFLOAT;
		/* rrc never reads F, rrc and the oracle no disp: one texel each keeps the descriptor set uniform */
		bool tiny = (arr && !v->tarc) || (disp && (!v->tarc || v->oracle));
		uint32_t iw = tiny ? 1 : low ? lw : w, ih = tiny ? 1 : low ? lh : h;
		VkImageUsageFlags use = VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
		if (i == IMG_RECORD)
			use = VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
		if (i <= IMG_COLOUR1) /* copied into the HDR target (copy_colour_to_hdr) */
			use |= VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
		if (r->desc.decisions && (i == IMG_STATE0 || i == IMG_STATE1))
			use |= VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
		if ((res = vkdev_image_create(r->dev, iw, ih, 1, 1, f, use, VK_IMAGE_ASPECT_COLOR_BIT, arr, names[i], &s->img[i])))
			return render_vk_error(err, err_size, names[i], res);
	}
	if ((res = vkdev_buffer_create(r->dev, 32, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, true,
				       "cache counters", &s->counters)))
		return render_vk_error(err, err_size, "counter buffer", res);
	if (r->desc.decisions) {
		if ((res = vkdev_buffer_create(r->dev, (VkDeviceSize)w * h * 16, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true,
					       "decision readback", &s->decision_buf)))
			return render_vk_error(err, err_size, "decision readback buffer", res);
		if (!(s->decision_codes = malloc((size_t)w * h)))
			return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	int rc = make_sets(r, s, err, err_size);
	if (!rc && v->tarc)
		rc = tas_filter_init_down(r, &s->filter, max_down_state_comp, sizeof max_down_state_comp, err, err_size);
	for (int p = 0; p < 2 && !rc && v->tarc; p++)
		rc = tas_filter_bind(r, &s->filter, &s->img[IMG_STATE0 + p], &s->img[IMG_L1], &s->img[IMG_F],
				     &s->filter_sets[p], err, err_size);
	if (!rc)
		rc = make_pipelines(r, s, err, err_size);
	if (rc)
		return rc;
	VkCommandBuffer cmd;
	if ((res = vkdev_cmd_begin(r->dev, &cmd)))
		return render_vk_error(err, err_size, "command buffer", res);
	for (int i = 0; i < IMG_COUNT; i++)
		vkdev_barrier_image(cmd, &s->img[i], VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
				    VK_PIPELINE_STAGE_2_NONE, 0, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
				    VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
	if ((res = vkdev_cmd_submit_wait(r->dev, cmd)))
		return render_vk_error(err, err_size, "cache image setup", res);
	return TL_OK;
}

int reproj_prepare(render *r, uint32_t frame, char *err, size_t err_size)
{
	reproj_state *s = state_of(r);
	s->have_prev = s->last_frame >= 0 && (int64_t)frame == s->last_frame + 1;
	render_update_state(r, frame & 1u, (double)frame / (double)r->desc.fps);
	return render_shadow_plan(r, frame & 1u, err, err_size);
}

/* Every pass of the frame reads what the one before wrote (storage images, attachments, the stencil). */
static void barrier_all(VkCommandBuffer cmd)
{
	VkPipelineStageFlags2 st = VK_PIPELINE_STAGE_2_ALL_GRAPHICS_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT |
				   VK_PIPELINE_STAGE_2_TRANSFER_BIT;
	render_barrier(cmd, st, VK_ACCESS_2_MEMORY_WRITE_BIT, st, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
}

/* The depth pre-pass with the record (make_prepass): depth and stencil cleared (1, 0), the record cleared to 0
 * (background); opaque then masked objects in scene order, culled per material, as passes/depth.c draws them. */
static void record_prepass(render *r, reproj_state *s, VkCommandBuffer cmd, uint32_t slot)
{
	render_depth_discard(r, cmd);
	VkRenderingAttachmentInfo ca = {.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
					.imageView = s->img[IMG_RECORD].view, .imageLayout = VK_IMAGE_LAYOUT_GENERAL,
					.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR, .storeOp = VK_ATTACHMENT_STORE_OP_STORE};
	VkRenderingAttachmentInfo da = {.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO, .imageView = r->depth.view,
					.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
					.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR, .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
					.clearValue = {.depthStencil = {1.0f, 0}}};
	VkRenderingInfo ri = {.sType = VK_STRUCTURE_TYPE_RENDERING_INFO,
			      .renderArea = {{0, 0}, {r->desc.width, r->desc.height}},
			      .layerCount = 1, .colorAttachmentCount = 1, .pColorAttachments = &ca,
			      .pDepthAttachment = &da, .pStencilAttachment = &da};
	vkCmdBeginRendering(cmd, &ri);
	render_set_viewport(cmd, r->desc.width, r->desc.height);
	render_draw_depth_objects(r, cmd, &s->prepass, &s->prepass_mask, slot, 0, NULL);
	vkCmdEndRendering(cmd);
}

/* The screen-space reproject pass (reproj/reproject.comp.in): the next cache colour cleared to the sky (what the
 * scene passes clear the HDR target to, coverage 0), C' stored into it per covered pixel. */
static void record_reproject(render *r, reproj_state *s, VkCommandBuffer cmd, uint32_t slot)
{
	const scene *sc = r->scene;
	VkImageSubresourceRange range = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
	VkClearColorValue sky = {{sc->sky[0] * sc->exposure, sc->sky[1] * sc->exposure, sc->sky[2] * sc->exposure, 0.0f}};
	if (s->v.payload) /* a payload, not a colour: the compose pass clears the HDR target to the sky */
		sky = (VkClearColorValue){.uint32 = {0, 0, 0, 0}};
	vkCmdClearColorImage(cmd, s->img[IMG_COLOUR0 + 1 - s->parity].image, VK_IMAGE_LAYOUT_GENERAL, &sky, 1, &range);
	barrier_all(cmd);
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s->reproject);
	VkDescriptorSet sets[2] = {r->scene_set, s->sets[s->parity]};
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s->reproject_layout, 0, 2, sets, 0, NULL);
	gpu_push pc = {slot, 0, (uint32_t)sc->object_count, 0, {r->push_aux[0], r->push_aux[1], r->push_aux[2], r->push_aux[3]}};
	vkCmdPushConstants(cmd, s->reproject_layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof pc, &pc);
	vkCmdDispatch(cmd, (r->desc.width + 7) / 8, (r->desc.height + 7) / 8, 1);
	barrier_all(cmd);
}

/* After the shading pass the next cache colour is the opaque frame (C' or the new shading per covered pixel, the sky
 * elsewhere): copied into the HDR target, for the BLEND objects and the display. The shading pass writes the
 * cache only, so a reshaded sample is stored once, not twice (issue 32.1, lever 3). */
static void copy_colour_to_hdr(render *r, reproj_state *s, VkCommandBuffer cmd)
{
	VkImageCopy c = {.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
			 .dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
			 .extent = {r->desc.width, r->desc.height, 1}};
	vkdev_image *colour = &s->img[IMG_COLOUR0 + 1 - s->parity];
	vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
			    VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0,
			    VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
	vkdev_barrier_image(cmd, colour, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL,
			    VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_GRAPHICS_BIT,
			    VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
	vkCmdCopyImage(cmd, colour->image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, r->hdr.image,
		       VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &c);
	vkdev_barrier_image(cmd, colour, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
			    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT,
			    VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
	vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
			    VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_COPY_BIT,
			    VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
			    VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
}

void reproj_record(render *r, VkCommandBuffer cmd, uint32_t frame)
{
	reproj_state *s = state_of(r);
	uint32_t slot = frame & 1u, next = 1 - s->parity;
	VkDescriptorSet set = s->sets[s->parity];
	vkCmdFillBuffer(cmd, s->counters.buffer, 0, VK_WHOLE_SIZE, 0);
	barrier_all(cmd);
	float T = s->v.threshold;
	memcpy(&r->push_aux[3], &T, sizeof T);
	r->push_aux[0] = 1 - slot;
	r->push_aux[1] = (s->have_prev ? 1u : 0u) | (s->v.force ? 2u : 0u) | (s->v.period & 0xFFu) << 8 | s->v.max_age << 16;

	render_ts(r, cmd);
	render_pass_shadows(r, cmd, slot);
	render_ts(r, cmd);
	r->push_aux[2] = r->desc.width | r->desc.height << 16; /* prepass.frag.in */
	record_prepass(r, s, cmd, slot);
	r->push_aux[2] = frame;
	barrier_all(cmd);
	render_ts(r, cmd);
	record_reproject(r, s, cmd, slot);
	render_ts(r, cmd);
	if (s->v.tarc && !s->v.oracle) {
		tas_filter_record(&s->filter, cmd, s->filter_sets[next], r->desc.width, r->desc.height, 1);
		barrier_all(cmd);
	}
	render_ts(r, cmd);
	if (!s->v.oracle) {
		render_pass_scene(r, cmd, slot,
				  &(render_scene_pass){.pipe = &s->mark, .set = set, .stencil = RENDER_STENCIL_PASS_LOAD,
						       .fullscreen = 1});
		barrier_all(cmd);
	}
	render_ts(r, cmd);
	render_pass_scene(r, cmd, slot,
			  &(render_scene_pass){.pipe = &s->shade, .set = set, .stencil = RENDER_STENCIL_PASS_LOAD, .query = 1});
	barrier_all(cmd);
	if (!s->v.payload)
		copy_colour_to_hdr(r, s, cmd);
	render_ts(r, cmd);
	if (s->v.payload) {
		render_pass_scene(r, cmd, slot, &(render_scene_pass){.pipe = &s->compose, .set = set, .hdr = RENDER_HDR_CLEAR});
		barrier_all(cmd);
	}
	if (!s->v.tarc) /* rrc's passes have "compose" (empty without --payload) */
		render_ts(r, cmd);
	if (s->truth.pipeline) {
		render_pass_scene(r, cmd, slot,
				  &(render_scene_pass){.pipe = &s->truth, .set = set, .stencil = RENDER_STENCIL_PASS_LOAD});
		barrier_all(cmd);
	}
	if (s->decision_buf.buffer) {
		VkBufferImageCopy c = {.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
				       .imageExtent = {r->desc.width, r->desc.height, 1}};
		vkdev_image *im = &s->img[IMG_STATE0 + next];
		vkdev_barrier_image(cmd, im, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL,
				    VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_GRAPHICS_BIT,
				    VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
				    VK_ACCESS_2_TRANSFER_READ_BIT);
		vkCmdCopyImageToBuffer(cmd, im->image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, s->decision_buf.buffer, 1, &c);
		vkdev_barrier_image(cmd, im, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
				    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT,
				    VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
				    VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
	}
	render_ts(r, cmd);
	if (r->blend_count) {
		memset(r->push_aux, 0, sizeof r->push_aux);
		render_pass_scene(r, cmd, slot, &(render_scene_pass){.hdr = RENDER_HDR_LOAD, .blend = 1});
	}
	memset(r->push_aux, 0, sizeof r->push_aux);
	render_ts(r, cmd);
	render_pass_display(r, cmd);
	render_ts(r, cmd);
	render_pass_readback(r, cmd);
	render_ts(r, cmd);
	s->parity = next;
	s->last_frame = frame;
}

void reproj_collect(render *r, frame_stats *st)
{
	reproj_state *s = state_of(r);
	const uint32_t *c = s->counters.mapped;
	/* covered: opaque and masked samples, one per pixel (the pre-pass record); BLEND-only coverage is excluded from
	 * every counter (TAS-METHODS 0). Where two surfaces lie at exactly the same depth the shading pass (depth EQUAL,
	 * as ref's) shades and counts both fragments, so covered - shaded is one low per such pixel reshaded: never
	 * below 0 (frame 0 shades everything). */
	st->shaded_samples = c[1];
	st->reused_samples = c[0] > c[1] ? (int64_t)c[0] - (int64_t)c[1] : 0;
	st->visible_units = st->visible_samples;
	st->shaded_units = c[1];
	st->new_units = c[2];
	st->late_samples = s->v.truth ? (int64_t)c[3] : -1;
	if (s->v.payload && st->extra_count < FRAME_MAX_EXTRA) {
		/* shaded_samples counts the payload's evaluations, this the shadings completed with it */
		st->extra_names[st->extra_count] = "composed_samples";
		st->extra[st->extra_count++] = c[5];
	}
	if (s->v.tarc && !s->v.oracle && st->extra_count < FRAME_MAX_EXTRA) {
		st->extra_names[st->extra_count] = "forced_samples";
		st->extra[st->extra_count++] = c[4];
	}
}

/* state.z bits 24..26 (reproj.glsl DEC_*): the frame's decision per pixel; background pixels hold 0. */
const uint8_t *reproj_decisions(render *r)
{
	reproj_state *s = state_of(r);
	const uint32_t *st = s->decision_buf.mapped;
	for (size_t i = 0, n = (size_t)r->desc.width * r->desc.height; i < n; i++)
		s->decision_codes[i] = (uint8_t)((st[i * 4 + 2] >> 24) & 7u);
	return s->decision_codes;
}

const uint32_t *reproj_debug_state(render *r)
{
	return state_of(r)->decision_buf.mapped;
}

void reproj_finish(render *r)
{
	reproj_state *s = state_of(r);
	if (!s)
		return;
	vkdev_buffer_destroy(r->dev, &s->decision_buf);
	free(s->decision_codes);
	render_pipeline *pipes[6] = {&s->prepass, &s->prepass_mask, &s->mark, &s->shade, &s->truth, &s->compose};
	for (int i = 0; i < 6; i++)
		render_pipeline_destroy(r, pipes[i]);
	if (s->reproject)
		vkDestroyPipeline(r->dev->device, s->reproject, NULL);
	if (s->reproject_layout)
		vkDestroyPipelineLayout(r->dev->device, s->reproject_layout, NULL);
	tas_filter_finish(r, &s->filter);
	if (s->set_layout)
		vkDestroyDescriptorSetLayout(r->dev->device, s->set_layout, NULL);
	for (int i = 0; i < IMG_COUNT; i++)
		vkdev_image_destroy(r->dev, &s->img[i]);
	vkdev_buffer_destroy(r->dev, &s->counters);
	free(s);
	r->method_state = NULL;
}
