/* ids.c — the visibility (ids) pass (ids.h; [TAS] sec. 6.2 step 1): vertex pulling, one non-indexed draw of 3n
 * vertices per object so that each vertex knows its triangle and corner (common/ids.vert.in, common/ids.frag.in).
 * Moved out of methods/atlas.c so that the compacted sample path can use it too (issue 30.4). */
#include "ids.h"

#include <stdlib.h>
#include <string.h>

/* Set 1 of the pass: the scene's vertex and index buffers, read by the vertex stage. */
static int make_set(render *r, ids_pass *p, char *err, size_t err_size)
{
	VkDevice d = r->dev->device;
	VkDescriptorSetLayoutBinding b[2] = {
		{0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, NULL},
		{1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_VERTEX_BIT, NULL},
	};
	VkDescriptorSetLayoutCreateInfo li = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
					      .bindingCount = 2, .pBindings = b};
	VkResult res;
	if ((res = vkCreateDescriptorSetLayout(d, &li, NULL, &p->set_layout)))
		return render_vk_error(err, err_size, "ids: descriptor set layout", res);
	VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
					  .descriptorPool = r->pool, .descriptorSetCount = 1, .pSetLayouts = &p->set_layout};
	if ((res = vkAllocateDescriptorSets(d, &ai, &p->set)))
		return render_vk_error(err, err_size, "ids: descriptor set", res);
	VkDescriptorBufferInfo bi[2] = {{r->vertices.buffer, 0, VK_WHOLE_SIZE}, {r->indices.buffer, 0, VK_WHOLE_SIZE}};
	VkWriteDescriptorSet w[2];
	for (uint32_t i = 0; i < 2; i++)
		w[i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = p->set, .dstBinding = i,
					      .descriptorCount = 1, .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
					      .pBufferInfo = &bi[i]};
	vkUpdateDescriptorSets(d, 2, w, 0, NULL);
	return TL_OK;
}

static int make_pipeline(render *r, ids_pass *p, char *err, size_t err_size)
{
	uint32_t *vs = NULL, *fs = NULL, *fm = NULL;
	size_t vn = 0, fn = 0, mn = 0;
	int rc = render_compile_defs(r, "common/ids.vert.in", "", SHC_STAGE_VERTEX, &vs, &vn, err, err_size);
	if (!rc)
		rc = render_compile_defs(r, "common/ids.frag.in", "", SHC_STAGE_FRAGMENT, &fs, &fn, err, err_size);
	if (!rc)
		rc = render_compile_defs(r, "common/ids.frag.in", "#define IDS_ALPHA_MASK 1\n", SHC_STAGE_FRAGMENT, &fm, &mn,
					 err, err_size);
	if (!rc) {
		render_pipe_desc pd = {.vs = vs, .vs_size = vn, .fs = fs, .fs_size = fn, .color = 1, .depth_write = 1,
				       .depth_op = VK_COMPARE_OP_LESS_OR_EQUAL, .color_format = VK_FORMAT_R32G32B32A32_UINT,
				       .method_set = p->set_layout};
		VkResult res = render_make_graphics(r, &pd, &p->pipe);
		if (!res) {
			pd.fs = fm;
			pd.fs_size = mn;
			res = render_make_graphics(r, &pd, &p->pipe_mask);
		}
		if (res)
			rc = render_vk_error(err, err_size, "ids: visibility pipeline", res);
	}
	free(vs);
	free(fs);
	free(fm);
	return rc;
}

int ids_pass_init(render *r, ids_pass *p, char *err, size_t err_size)
{
	VkResult res = vkdev_image_create(r->dev, r->desc.width, r->desc.height, 1, 1, VK_FORMAT_R32G32B32A32_UINT,
					  VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT |
						  VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
					  VK_IMAGE_ASPECT_COLOR_BIT, false, "ids", &p->image);
	if (res)
		return render_vk_error(err, err_size, "ids image", res);
	int rc = make_set(r, p, err, err_size);
	return rc ? rc : make_pipeline(r, p, err, err_size);
}

void ids_pass_finish(render *r, ids_pass *p)
{
	render_pipeline_destroy(r, &p->pipe);
	render_pipeline_destroy(r, &p->pipe_mask);
	if (p->set_layout)
		vkDestroyDescriptorSetLayout(r->dev->device, p->set_layout, NULL);
	vkdev_image_destroy(r->dev, &p->image);
	*p = (ids_pass){0};
}

void ids_pass_record(render *r, const ids_pass *p, VkCommandBuffer cmd, uint32_t slot)
{
	uint32_t w = r->desc.width, h = r->desc.height;
	/* ids cleared to 0 (background), depth to 1; the previous frame's compute reads of the image come first */
	vkdev_barrier_image(cmd, &p->image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
			    VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			    VK_ACCESS_2_SHADER_STORAGE_READ_BIT, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
			    VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
	render_depth_discard(r, cmd);
	VkRenderingAttachmentInfo ca = {.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO, .imageView = p->image.view,
					.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
					.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR, .storeOp = VK_ATTACHMENT_STORE_OP_STORE};
	VkRenderingAttachmentInfo da = {.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO, .imageView = r->depth.view,
					.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
					.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR, .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
					.clearValue = {.depthStencil = {1.0f, 0}}};
	VkRenderingInfo ri = {.sType = VK_STRUCTURE_TYPE_RENDERING_INFO, .renderArea = {{0, 0}, {w, h}}, .layerCount = 1,
			      .colorAttachmentCount = 1, .pColorAttachments = &ca, .pDepthAttachment = &da};
	vkCmdBeginRendering(cmd, &ri);
	render_set_viewport(cmd, w, h);
	VkDescriptorSet sets[2] = {r->scene_set, p->set};
	const scene *sc = r->scene;
	const render_pipeline *bound = NULL;
	for (size_t i = 0; i < sc->object_count; i++) {
		const scene_object *o = &sc->objects[i];
		if (o->mesh < 0 || sc->materials[o->material].alpha_mode == SCENE_ALPHA_BLEND)
			continue;
		/* scene order is kept (the last drawn wins among coplanar surfaces); the pipeline follows the material */
		const render_pipeline *want = sc->materials[o->material].alpha_mode == SCENE_ALPHA_MASK ? &p->pipe_mask : &p->pipe;
		if (want != bound) {
			vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, want->pipeline);
			vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, want->layout, 0, 2, sets, 0, NULL);
			bound = want;
		}
		/* aux: where the object's mesh starts in the scene's index and vertex buffers (common/ids.vert.in) */
		gpu_push pc = {slot, (uint32_t)i, (uint32_t)sc->object_count, 0,
			       {r->mesh_first_index[o->mesh], r->mesh_vertex_offset[o->mesh], 0, 0}};
		vkCmdPushConstants(cmd, bound->layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
				   sizeof pc, &pc);
		vkCmdSetCullMode(cmd, sc->materials[o->material].double_sided ? VK_CULL_MODE_NONE : VK_CULL_MODE_BACK_BIT);
		vkCmdDraw(cmd, sc->meshes[o->mesh].index_count, 1, 0, 0);
	}
	vkCmdEndRendering(cmd);
	vkdev_barrier_image(cmd, &p->image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
			    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
			    VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			    VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
}

int ids_pass_copy(render *r, const ids_pass *p, uint32_t *ids, bool upload, char *err, size_t err_size)
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
	vkdev_barrier_image(cmd, &p->image, VK_IMAGE_ASPECT_COLOR_BIT,
			    upload ? VK_IMAGE_LAYOUT_UNDEFINED : VK_IMAGE_LAYOUT_GENERAL, tl,
			    VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_WRITE_BIT, VK_PIPELINE_STAGE_2_COPY_BIT, ta);
	VkBufferImageCopy c = {.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
			       .imageExtent = {r->desc.width, r->desc.height, 1}};
	if (upload)
		vkCmdCopyBufferToImage(cmd, b.buffer, p->image.image, tl, 1, &c);
	else
		vkCmdCopyImageToBuffer(cmd, p->image.image, tl, b.buffer, 1, &c);
	vkdev_barrier_image(cmd, &p->image, VK_IMAGE_ASPECT_COLOR_BIT, tl, VK_IMAGE_LAYOUT_GENERAL,
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
