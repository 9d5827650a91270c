/* ids.c — the visibility (ids) pass (ids.h; [TAS] sec. 6.2 step 1): vertex pulling, one non-indexed draw of 3n
 * vertices per object so that each vertex knows its triangle and corner (common/ids.vert.in, common/ids.frag.in).
 * Moved out of methods/atlas.c so that the compacted sample path can use it too (issue 30.4). */
#include "ids.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Set 1 of the pass: the scene's vertex and index buffers, read by the vertex stage; multiview adds binding 2, the
 * right eye's state ring (its view_proj; the left eye's is the scene set's); with patch tables (the atlas methods)
 * bindings 3 and 4 are their object and triangle tables (common/ids.vert.in IDS_PATCHES). */
static int make_set(render *r, VkDescriptorSetLayout *layout, VkDescriptorSet *set, const vkdev_buffer *states_r,
		    const ids_patches *pt, char *err, size_t err_size)
{
	VkDevice d = r->dev->device;
	const vkdev_buffer *bufs[5] = {&r->vertices, &r->indices, states_r, pt ? pt->obj_info : NULL,
				       pt ? pt->tri_info : NULL};
	VkDescriptorSetLayoutBinding b[5];
	VkDescriptorBufferInfo bi[5];
	uint32_t n = 0;
	for (uint32_t i = 0; i < 5; i++) {
		if (!bufs[i])
			continue;
		b[n] = (VkDescriptorSetLayoutBinding){i, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, NULL};
		bi[n++] = (VkDescriptorBufferInfo){bufs[i]->buffer, 0, VK_WHOLE_SIZE};
	}
	VkDescriptorSetLayoutCreateInfo li = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
					      .bindingCount = n, .pBindings = b};
	VkResult res;
	if ((res = vkCreateDescriptorSetLayout(d, &li, NULL, layout)))
		return render_vk_error(err, err_size, "ids: descriptor set layout", res);
	VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
					  .descriptorPool = r->pool, .descriptorSetCount = 1, .pSetLayouts = layout};
	if ((res = vkAllocateDescriptorSets(d, &ai, set)))
		return render_vk_error(err, err_size, "ids: descriptor set", res);
	VkWriteDescriptorSet w[5];
	for (uint32_t i = 0; i < n; i++)
		w[i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = *set,
					      .dstBinding = b[i].binding, .descriptorCount = 1,
					      .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .pBufferInfo = &bi[i]};
	vkUpdateDescriptorSets(d, n, w, 0, NULL);
	return TL_OK;
}

int ids_make_pipelines(render *r, const ids_pipe_src *src, render_pipe_desc pd, render_pipeline *pipe,
		       render_pipeline *pipe_mask, const char *what, char *err, size_t err_size)
{
	uint32_t *vs = NULL, *fs = NULL, *fm = NULL;
	size_t vn = 0, fn = 0, mn = 0;
	char mask[256];
	snprintf(mask, sizeof mask, "%s%s", src->fs_defs, src->mask_def);
	int rc = render_compile_defs(r, src->vs, src->vs_defs, SHC_STAGE_VERTEX, &vs, &vn, err, err_size);
	if (!rc)
		rc = render_compile_defs(r, src->fs, src->fs_defs, SHC_STAGE_FRAGMENT, &fs, &fn, err, err_size);
	if (!rc)
		rc = render_compile_defs(r, src->fs, mask, SHC_STAGE_FRAGMENT, &fm, &mn, err, err_size);
	if (!rc) {
		pd.vs = vs, pd.vs_size = vn, pd.fs = fs, pd.fs_size = fn;
		VkResult res = render_make_graphics(r, &pd, pipe);
		if (!res) {
			pd.fs = fm;
			pd.fs_size = mn;
			res = render_make_graphics(r, &pd, pipe_mask);
		}
		if (res)
			rc = render_vk_error(err, err_size, what, res);
	}
	free(vs);
	free(fs);
	free(fm);
	return rc;
}

/* The ids pass's own pipelines; multiview (view_mask 0b11): common/ids.vert.in with IDS_MULTIVIEW; patch tables:
 * with IDS_PATCHES. */
static int make_pipeline(render *r, VkDescriptorSetLayout set_layout, uint32_t view_mask, bool patches,
			 render_pipeline *pipe, render_pipeline *pipe_mask, char *err, size_t err_size)
{
	char vdefs[128];
	snprintf(vdefs, sizeof vdefs, "%s%s", view_mask ? "#extension GL_EXT_multiview : require\n#define IDS_MULTIVIEW 1\n" : "",
		 patches ? "#define IDS_PATCHES 1\n" : "");
	ids_pipe_src src = {"common/ids.vert.in", vdefs, "common/ids.frag.in", "", "#define IDS_ALPHA_MASK 1\n"};
	render_pipe_desc pd = {.color = 1, .depth_write = 1, .depth_op = VK_COMPARE_OP_LESS_OR_EQUAL,
			       .color_format = VK_FORMAT_R32G32B32A32_UINT, .method_set = set_layout, .view_mask = view_mask};
	return ids_make_pipelines(r, &src, pd, pipe, pipe_mask, "ids: visibility pipeline", err, err_size);
}

int ids_pass_init(render *r, ids_pass *p, const ids_patches *pt, char *err, size_t err_size)
{
	VkResult res = vkdev_image_create(r->dev, r->desc.width, r->desc.height, 1, 1, VK_FORMAT_R32G32B32A32_UINT,
					  VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT |
						  VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
					  VK_IMAGE_ASPECT_COLOR_BIT, false, "ids", &p->image);
	if (res)
		return render_vk_error(err, err_size, "ids image", res);
	int rc = make_set(r, &p->set_layout, &p->set, NULL, pt, err, err_size);
	return rc ? rc : make_pipeline(r, p->set_layout, 0, pt != NULL, &p->pipe, &p->pipe_mask, err, err_size);
}

void ids_pass_finish(render *r, ids_pass *p)
{
	render_pipeline_destroy(r, &p->pipe);
	render_pipeline_destroy(r, &p->pipe_mask);
	if (p->set_layout)
		vkDestroyDescriptorSetLayout(r->dev->device, p->set_layout, NULL);
	if (p->layer_view) { /* a view of ids_multiview's image, which that one destroys */
		if (p->image.view)
			vkDestroyImageView(r->dev->device, p->image.view, NULL);
	} else {
		vkdev_image_destroy(r->dev, &p->image);
	}
	*p = (ids_pass){0};
}

/* A barrier on layers [base, base + count) of `image` (a multiview eye's layer; vkdev_barrier_image takes all). */
static void layer_barrier(VkCommandBuffer cmd, VkImage image, uint32_t base, uint32_t count, VkImageAspectFlags aspect,
			  VkImageLayout from, VkImageLayout to, VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access,
			  VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access)
{
	VkImageMemoryBarrier2 b = {.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2, .srcStageMask = src_stage,
				   .srcAccessMask = src_access, .dstStageMask = dst_stage, .dstAccessMask = dst_access,
				   .oldLayout = from, .newLayout = to, .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
				   .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED, .image = image,
				   .subresourceRange = {aspect, 0, 1, base, count}};
	VkDependencyInfo di = {.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO, .imageMemoryBarrierCount = 1,
			       .pImageMemoryBarriers = &b};
	vkCmdPipelineBarrier2(cmd, &di);
}

void ids_draw_objects(render *r, VkCommandBuffer cmd, VkDescriptorSet set, const render_pipeline *pipe,
		      const render_pipeline *pipe_mask, uint32_t slot, const uint32_t aux23[2])
{
	VkDescriptorSet sets[2] = {r->scene_set, set};
	const scene *sc = r->scene;
	const render_pipeline *bound = NULL;
	for (size_t i = 0; i < sc->object_count; i++) {
		const scene_object *o = &sc->objects[i];
		if (o->mesh < 0 || sc->materials[o->material].alpha_mode == SCENE_ALPHA_BLEND)
			continue;
		/* scene order is kept (the last drawn wins among coplanar surfaces); the pipeline follows the material */
		const render_pipeline *want = sc->materials[o->material].alpha_mode == SCENE_ALPHA_MASK ? pipe_mask : pipe;
		if (want != bound) {
			vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, want->pipeline);
			vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, want->layout, 0, 2, sets, 0, NULL);
			bound = want;
		}
		/* aux: where the object's mesh starts in the scene's index and vertex buffers (common/ids.vert.in) */
		gpu_push pc = {slot, (uint32_t)i, (uint32_t)sc->object_count, 0,
			       {r->mesh_first_index[o->mesh], r->mesh_vertex_offset[o->mesh], aux23[0], aux23[1]}};
		vkCmdPushConstants(cmd, bound->layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
				   sizeof pc, &pc);
		render_set_facing(r, cmd, slot, i);
		vkCmdDraw(cmd, sc->meshes[o->mesh].index_count, 1, 0, 0);
	}
}

void ids_begin(render *r, VkCommandBuffer cmd, const vkdev_image *const *images, uint32_t count,
	       const VkClearColorValue *clears)
{
	uint32_t w = r->desc.width, h = r->desc.height;
	VkRenderingAttachmentInfo ca[IDS_MAX_TARGETS];
	count = count < IDS_MAX_TARGETS ? count : IDS_MAX_TARGETS; /* as ids_end; its pipeline has as many (at most 4) */
	for (uint32_t i = 0; i < count; i++) {
		/* cleared to CLEARS[i] (0 without: background), depth to 1; the previous frame's compute reads (and writes:
		 * stu's g) of the image come first */
		vkdev_barrier_image(cmd, images[i], VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
				    VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
				    VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
				    VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
		ca[i] = (VkRenderingAttachmentInfo){.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
						    .imageView = images[i]->view,
						    .imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
						    .loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR, .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
						    .clearValue = {.color = clears ? clears[i] : (VkClearColorValue){{0}}}};
	}
	render_depth_discard(r, cmd);
	VkRenderingAttachmentInfo da = {.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO, .imageView = r->depth.view,
					.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
					.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR, .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
					.clearValue = {.depthStencil = {1.0f, 0}}};
	VkRenderingInfo ri = {.sType = VK_STRUCTURE_TYPE_RENDERING_INFO, .renderArea = {{0, 0}, {w, h}}, .layerCount = 1,
			      .colorAttachmentCount = count, .pColorAttachments = ca, .pDepthAttachment = &da};
	vkCmdBeginRendering(cmd, &ri);
	render_set_viewport(cmd, w, h);
}

void ids_end(VkCommandBuffer cmd, const vkdev_image *const *images, uint32_t count)
{
	count = count < IDS_MAX_TARGETS ? count : IDS_MAX_TARGETS; /* as ids_begin */
	vkCmdEndRendering(cmd);
	for (uint32_t i = 0; i < count; i++)
		vkdev_barrier_image(cmd, images[i], VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
				    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
				    VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
				    VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
}

void ids_pass_record(render *r, const ids_pass *p, VkCommandBuffer cmd, uint32_t slot)
{
	static const uint32_t no_aux[2] = {0, 0};
	const vkdev_image *image = &p->image;
	ids_begin(r, cmd, &image, 1, NULL);
	ids_draw_objects(r, cmd, p->set, &p->pipe, &p->pipe_mask, slot, no_aux);
	ids_end(cmd, &image, 1);
}

int ids_image_copy(render *r, const vkdev_image *image, uint32_t layer, uint32_t *ids, bool upload, char *err,
		   size_t err_size)
{
	VkDeviceSize size = (VkDeviceSize)r->desc.width * r->desc.height * 16;
	vkdev_buffer b = {0};
	VkCommandBuffer cmd;
	VkResult res = vkdev_buffer_create(r->dev, size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
					   true, "ids copy", &b);
	if (!res && upload)
		memcpy(b.mapped, ids, size);
	if (!res)
		res = vkdev_cmd_begin(r->dev, &cmd);
	if (res) {
		vkdev_buffer_destroy(r->dev, &b);
		return render_vk_error(err, err_size, "ids copy", res);
	}
	VkImageLayout tl = upload ? VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL : VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
	VkAccessFlags2 ta = upload ? VK_ACCESS_2_TRANSFER_WRITE_BIT : VK_ACCESS_2_TRANSFER_READ_BIT;
	layer_barrier(cmd, image->image, layer, 1, VK_IMAGE_ASPECT_COLOR_BIT,
		      upload ? VK_IMAGE_LAYOUT_UNDEFINED : VK_IMAGE_LAYOUT_GENERAL, tl, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
		      VK_ACCESS_2_MEMORY_WRITE_BIT, VK_PIPELINE_STAGE_2_COPY_BIT, ta);
	VkBufferImageCopy c = {.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, layer, 1},
			       .imageExtent = {r->desc.width, r->desc.height, 1}};
	if (upload)
		vkCmdCopyBufferToImage(cmd, b.buffer, image->image, tl, 1, &c);
	else
		vkCmdCopyImageToBuffer(cmd, image->image, tl, b.buffer, 1, &c);
	layer_barrier(cmd, image->image, layer, 1, VK_IMAGE_ASPECT_COLOR_BIT, tl, VK_IMAGE_LAYOUT_GENERAL,
		      VK_PIPELINE_STAGE_2_COPY_BIT, ta, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
		      VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
	render_barrier(cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
		       VK_ACCESS_2_HOST_READ_BIT);
	res = vkdev_cmd_submit_wait(r->dev, cmd);
	if (!res && !upload)
		memcpy(ids, b.mapped, size);
	vkdev_buffer_destroy(r->dev, &b);
	return res ? render_vk_error(err, err_size, "ids copy", res) : TL_OK;
}

int ids_pass_copy(render *r, const ids_pass *p, uint32_t *ids, bool upload, char *err, size_t err_size)
{
	return ids_image_copy(r, &p->image, p->layer, ids, upload, err, err_size);
}

/* ---- multiview (STEREO.md "Vulkan multiview") ---- */

int ids_multiview_init(render *r, ids_multiview *m, ids_pass eyes[2], const ids_patches *pt, char *err, size_t err_size)
{
	VkResult res = vkdev_image_create(r->dev, r->desc.width, r->desc.height, 2, 1, VK_FORMAT_R32G32B32A32_UINT,
					  VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT |
						  VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
					  VK_IMAGE_ASPECT_COLOR_BIT, true, "ids (multiview)", &m->ids);
	if (!res)
		res = vkdev_image_create(r->dev, r->desc.width, r->desc.height, 2, 1, RENDER_DEPTH_FORMAT,
					 VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
					 VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT, true, "depth (multiview)",
					 &m->depth);
	for (uint32_t v = 0; !res && v < 2; v++) {
		ids_pass *p = &eyes[v];
		*p = (ids_pass){.layer = v, .layer_view = true};
		p->image = m->ids;
		p->image.memory = VK_NULL_HANDLE;
		p->image.view = VK_NULL_HANDLE;
		p->image.layers = 1;
		VkImageViewCreateInfo vi = {.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO, .image = m->ids.image,
					    .viewType = VK_IMAGE_VIEW_TYPE_2D, .format = m->ids.format,
					    .subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, v, 1}};
		res = vkCreateImageView(r->dev->device, &vi, NULL, &p->image.view);
	}
	if (res)
		return render_vk_error(err, err_size, "ids (multiview) images", res);
	int rc = make_set(r, &m->set_layout, &m->set, &r->views[1].states, pt, err, err_size);
	return rc ? rc : make_pipeline(r, m->set_layout, 0x3u, pt != NULL, &m->pipe, &m->pipe_mask, err, err_size);
}

void ids_multiview_finish(render *r, ids_multiview *m)
{
	render_pipeline_destroy(r, &m->pipe);
	render_pipeline_destroy(r, &m->pipe_mask);
	if (m->set_layout)
		vkDestroyDescriptorSetLayout(r->dev->device, m->set_layout, NULL);
	vkdev_image_destroy(r->dev, &m->ids);
	vkdev_image_destroy(r->dev, &m->depth);
	*m = (ids_multiview){0};
}

void ids_multiview_record(render *r, const ids_multiview *m, VkCommandBuffer cmd, uint32_t slot)
{
	uint32_t w = r->desc.width, h = r->desc.height;
	const VkImageAspectFlags ds = VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT;
	const VkPipelineStageFlags2 tests = VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT |
					    VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT;
	/* both layers cleared as ids_pass_record clears one: the previous frame's compute reads (and depth copies) first */
	vkdev_barrier_image(cmd, &m->ids, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
			    VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			    VK_ACCESS_2_SHADER_STORAGE_READ_BIT, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
			    VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
	vkdev_barrier_image(cmd, &m->depth, ds, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
			    VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT, tests,
			    VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT);
	VkRenderingAttachmentInfo ca = {.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO, .imageView = m->ids.view,
					.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
					.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR, .storeOp = VK_ATTACHMENT_STORE_OP_STORE};
	VkRenderingAttachmentInfo da = {.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO, .imageView = m->depth.view,
					.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
					.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR, .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
					.clearValue = {.depthStencil = {1.0f, 0}}};
	/* viewMask 0b11: view v renders into layer v, the vertex shader taking eye v's view_proj by gl_ViewIndex */
	VkRenderingInfo ri = {.sType = VK_STRUCTURE_TYPE_RENDERING_INFO, .renderArea = {{0, 0}, {w, h}}, .layerCount = 1,
			      .viewMask = 0x3u, .colorAttachmentCount = 1, .pColorAttachments = &ca,
			      .pDepthAttachment = &da};
	vkCmdBeginRendering(cmd, &ri);
	render_set_viewport(cmd, w, h);
	static const uint32_t no_aux[2] = {0, 0};
	ids_draw_objects(r, cmd, m->set, &m->pipe, &m->pipe_mask, slot, no_aux);
	vkCmdEndRendering(cmd);
	vkdev_barrier_image(cmd, &m->ids, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
			    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
			    VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			    VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
	if (!r->blend_count)
		return; /* only the BLEND compositing reads an eye's depth after this pass */
	/* each eye's depth target gets its layer, as ids_pass_record leaves it there (depth and stencil) */
	vkdev_barrier_image(cmd, &m->depth, ds, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
			    VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, tests, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
			    VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
	uint32_t active = r->view;
	for (uint32_t v = 0; v < 2; v++) {
		render_use_view(r, v);
		vkdev_barrier_image(cmd, &r->depth, ds, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
				    tests, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
				    VK_ACCESS_2_TRANSFER_WRITE_BIT);
		VkImageCopy c[2] = {{.srcSubresource = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, v, 1},
				     .dstSubresource = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 0, 1}, .extent = {w, h, 1}},
				    {.srcSubresource = {VK_IMAGE_ASPECT_STENCIL_BIT, 0, v, 1},
				     .dstSubresource = {VK_IMAGE_ASPECT_STENCIL_BIT, 0, 0, 1}, .extent = {w, h, 1}}};
		vkCmdCopyImage(cmd, m->depth.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, r->depth.image,
			       VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 2, c);
		vkdev_barrier_image(cmd, &r->depth, ds, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
				    VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_COPY_BIT,
				    VK_ACCESS_2_TRANSFER_WRITE_BIT, tests,
				    VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
	}
	render_use_view(r, active);
}
