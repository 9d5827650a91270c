/* depth.c — depth-only rendering: the depth pre-pass (so the EQUAL shading pass shades each visible sample
 * once, like the paper's Forward+ baseline) and shadow-map layers. Alpha-masked objects are alpha-tested. */
#include "passes.h"

#include "shaders/common/depth_mask_frag.h"
#include "shaders/common/shadow_mask_vert.h"
#include "shaders/common/shadow_vert.h"

/* One depth-only rendering into `view` (cleared to 1): shadow layers and the depth pre-pass. Opaque
 * objects use `pipe`; alpha-masked ones `mask_pipe` (alpha test in the fragment shader); blended
 * objects write no depth and cast no shadow. */
void render_depth_only_pass(render *r, VkCommandBuffer cmd, VkImageView view, VkImageLayout layout, uint32_t w,
			    uint32_t h, const render_pipeline *pipe, const render_pipeline *mask_pipe, uint32_t slot,
			    uint32_t layer, const uint8_t *casters)
{
	VkRenderingAttachmentInfo da = {
		.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
		.imageView = view,
		.imageLayout = layout,
		.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR,
		.storeOp = VK_ATTACHMENT_STORE_OP_STORE,
		.clearValue = {.depthStencil = {1.0f, 0}},
	};
	VkRenderingInfo ri = {
		.sType = VK_STRUCTURE_TYPE_RENDERING_INFO,
		.renderArea = {{0, 0}, {w, h}},
		.layerCount = 1,
		.pDepthAttachment = &da,
	};
	vkCmdBeginRendering(cmd, &ri);
	render_set_viewport(cmd, w, h);
	render_draw_depth_objects(r, cmd, pipe, mask_pipe, slot, layer, casters);
	vkCmdEndRendering(cmd);
}

void render_draw_depth_objects(render *r, VkCommandBuffer cmd, const render_pipeline *pipe,
			       const render_pipeline *mask_pipe, uint32_t slot, uint32_t layer, const uint8_t *casters)
{
	/* Shadow passes draw the casters reaching into the layer with culling off; the pre-pass culls per material. */
	render_bind_scene(r, cmd, pipe);
	render_draw_objects(r, cmd, pipe, slot, layer, RENDER_OPAQUE_BIT, casters, !casters);
	if (mask_pipe->pipeline) {
		render_bind_scene(r, cmd, mask_pipe);
		render_draw_objects(r, cmd, mask_pipe, slot, layer, RENDER_MASK_BIT, casters, !casters);
	}
}

void render_depth_discard(render *r, VkCommandBuffer cmd)
{
	vkdev_barrier_image(cmd, &r->depth, VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
			    VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
			    VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
			    VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT,
			    VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
			    VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT);
}

void render_pass_depth(render *r, VkCommandBuffer cmd, uint32_t slot)
{
	uint32_t w = r->desc.width, h = r->desc.height;
	render_depth_discard(r, cmd);
	render_depth_only_pass(r, cmd, r->depth.view, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, w, h, &r->depth_pipe,
			       &r->depth_mask_pipe, slot, 0, NULL);
	VkMemoryBarrier2 mb = {
		.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER_2,
		.srcStageMask = VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
		.srcAccessMask = VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
		.dstStageMask = VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
		.dstAccessMask = VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT,
	};
	VkDependencyInfo di = {.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO, .memoryBarrierCount = 1, .pMemoryBarriers = &mb};
	vkCmdPipelineBarrier2(cmd, &di);
}

/* Depth-only pipelines: shadow layers (shadow casters, culling off, slope-scaled bias) and the pre-pass
 * (culling per material); alpha-masked variants test alpha in the fragment shader. */
int render_depth_init(render *r, char *err, size_t err_size)
{
	int rc = 0;
	render_pipe_desc shadow = {.vs = shadow_vert, .vs_size = sizeof shadow_vert, .attributes = RENDER_ATTR_POSITION,
				   .depth_write = 1, .depth_op = VK_COMPARE_OP_LESS, .bias = 1,
				   .depth_format = VK_FORMAT_D32_SFLOAT};
	render_pipe_desc depth = {.attributes = RENDER_ATTR_ALL, .depth_write = 1, .depth_op = VK_COMPARE_OP_LESS};
	CHECK_VK(render_make_graphics(r, &shadow, &r->shadow_pipe));
	CHECK_VK(render_make_graphics(r, &depth, &r->depth_pipe));
	if (render_has_alpha_mode(r, SCENE_ALPHA_MASK)) {
		render_pipe_desc sm = shadow, dm = depth;
		sm.vs = shadow_mask_vert, sm.vs_size = sizeof shadow_mask_vert;
		sm.attributes = RENDER_ATTR_POSITION | RENDER_ATTR_UV;
		sm.fs = dm.fs = depth_mask_frag;
		sm.fs_size = dm.fs_size = sizeof depth_mask_frag;
		CHECK_VK(render_make_graphics(r, &sm, &r->shadow_mask_pipe));
		CHECK_VK(render_make_graphics(r, &dm, &r->depth_mask_pipe));
	}
fail:
	return rc;
}
