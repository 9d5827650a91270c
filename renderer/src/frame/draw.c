/* draw.c — drawing the scene's objects, timestamps and the render's command buffer. */
#include "render_internal.h"

#include <stdio.h>

/* A pass boundary. llvmpipe (lavapipe's rasteriser) does not write a timestamp when the command is reached: it bins
 * the write into its current rasteriser scene, and the value is taken when that scene is next flushed — at the next
 * barrier, the next timestamp, or a dispatch or copy that touches an attachment of the scene's framebuffer. A compute
 * pass that binds none of the last render pass's attachments therefore ran before the timestamp that opens it was
 * taken, and its time went to the pass before (stereo atlas runs: eye 1's visibility pass was the last framebuffer and
 * the shading binds eye 0's set, so gpu_ms_alloc held the shading and gpu_ms_shade ~0.1 ms; mono was right only
 * because its shading binds the ids image, its framebuffer's attachment). The execution barrier after the write
 * flushes the scene there, so the value is taken at the boundary (test_stereo's timestamp probe); on a GPU it only
 * keeps the passes from overlapping across the boundary, which per-pass times assume anyway. */
void render_ts(render *r, VkCommandBuffer cmd)
{
	if (r->ts_pool) {
		vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, r->ts_pool, r->ts_count);
		render_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0);
	}
	r->ts_count++;
}

void render_bind_scene(render *r, VkCommandBuffer cmd, const render_pipeline *p)
{
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p->pipeline);
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p->layout, 0, 1, &r->scene_set, 0, NULL);
	VkDeviceSize zero = 0;
	vkCmdBindVertexBuffers(cmd, 0, 1, &r->vertices.buffer, &zero);
	vkCmdBindIndexBuffer(cmd, r->indices.buffer, 0, VK_INDEX_TYPE_UINT32);
}

void render_set_viewport(VkCommandBuffer cmd, uint32_t w, uint32_t h)
{
	VkViewport vp = {0, 0, (float)w, (float)h, 0.0f, 1.0f};
	VkRect2D sc = {{0, 0}, {w, h}};
	vkCmdSetViewport(cmd, 0, 1, &vp);
	vkCmdSetScissor(cmd, 0, 1, &sc);
}

void render_draw_object(render *r, VkCommandBuffer cmd, const render_pipeline *p, uint32_t slot, uint32_t layer,
			size_t i, int set_cull)
{
	const scene *s = r->scene;
	const scene_object *o = &s->objects[i];
	gpu_push pc = {slot, (uint32_t)i, (uint32_t)s->object_count, layer, {r->push_aux[0], r->push_aux[1], r->push_aux[2], r->push_aux[3]}};
	vkCmdPushConstants(cmd, p->layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof pc, &pc);
	if (set_cull)
		render_set_facing(r, cmd, slot, i);
	const scene_mesh *m = &s->meshes[o->mesh];
	vkCmdDrawIndexed(cmd, m->index_count, 1, r->mesh_first_index[o->mesh], (int32_t)r->mesh_vertex_offset[o->mesh], 0);
}

/* Draws the objects whose material alpha mode is in `modes` (RENDER_ALPHA_BIT set), in scene order. */
void render_draw_objects(render *r, VkCommandBuffer cmd, const render_pipeline *p, uint32_t slot, uint32_t layer,
			 unsigned modes, const uint8_t *only, int set_cull)
{
	const scene *s = r->scene;
	for (size_t i = 0; i < s->object_count; i++) {
		const scene_object *o = &s->objects[i];
		if (o->mesh < 0 || (only && !(only[i / 8] & (1u << (i % 8)))))
			continue; /* transform-only node, or not selected */
		if (modes & RENDER_ALPHA_BIT(s->materials[o->material].alpha_mode))
			render_draw_object(r, cmd, p, slot, layer, i, set_cull);
	}
}

bool render_object_mirrored(const render *r, uint32_t slot, size_t i)
{
	/* the flag the shaders read (state.c writes it with the slot's world matrices), so that the rasterizer's front
	 * face and the shaders' winding tests cannot disagree; a 4-byte read of the host-visible ring per draw, as
	 * shadow.c reads the slot's world matrices */
	return ((const gpu_object *)r->objects.mapped)[(size_t)slot * r->scene->object_count + i].material[1] != 0;
}

void render_set_facing(const render *r, VkCommandBuffer cmd, uint32_t slot, size_t i)
{
	const scene_object *o = &r->scene->objects[i];
	vkCmdSetCullMode(cmd, r->scene->materials[o->material].double_sided ? VK_CULL_MODE_NONE : VK_CULL_MODE_BACK_BIT);
	vkCmdSetFrontFace(cmd, render_object_mirrored(r, slot, i) ? VK_FRONT_FACE_CLOCKWISE : VK_FRONT_FACE_COUNTER_CLOCKWISE);
}

int render_has_alpha_mode(const render *r, scene_alpha_mode mode)
{
	for (size_t i = 0; i < r->scene->object_count; i++) {
		const scene_object *o = &r->scene->objects[i];
		if (o->mesh >= 0 && r->scene->materials[o->material].alpha_mode == mode)
			return 1;
	}
	return 0;
}

VkResult render_cmd_begin(render *r)
{
	VkCommandBufferBeginInfo bi = {
		.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
		.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT,
	};
	VkResult res = vkResetCommandBuffer(r->cmd, 0);
	return res ? res : vkBeginCommandBuffer(r->cmd, &bi);
}

VkResult render_cmd_submit_wait(render *r)
{
	VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO, .commandBufferCount = 1, .pCommandBuffers = &r->cmd};
	VkResult res = vkEndCommandBuffer(r->cmd);
	if (!res)
		res = vkResetFences(r->dev->device, 1, &r->fence);
	if (!res)
		res = vkQueueSubmit(r->dev->queue, 1, &si, r->fence);
	return res ? res : vkWaitForFences(r->dev->device, 1, &r->fence, VK_TRUE, UINT64_MAX);
}

void render_stats_begin(render *r, VkCommandBuffer cmd)
{
	if (!r->stats_pool)
		return;
	/* reset here so any number of shading passes may run per command buffer (the last one counts) */
	vkCmdResetQueryPool(cmd, r->stats_pool, 0, 1);
	vkCmdBeginQuery(cmd, r->stats_pool, 0, 0);
	r->stats_recorded = true;
}

void render_stats_end(render *r, VkCommandBuffer cmd)
{
	if (r->stats_pool)
		vkCmdEndQuery(cmd, r->stats_pool, 0);
}

void render_barrier(VkCommandBuffer cmd, VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access,
		    VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access)
{
	VkMemoryBarrier2 mb = {
		.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER_2,
		.srcStageMask = src_stage,
		.srcAccessMask = src_access,
		.dstStageMask = dst_stage,
		.dstAccessMask = dst_access,
	};
	VkDependencyInfo di = {.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO, .memoryBarrierCount = 1, .pMemoryBarriers = &mb};
	vkCmdPipelineBarrier2(cmd, &di);
}

int render_vk_error(char *err, size_t err_size, const char *what, VkResult res)
{
	return tl_error(err, err_size, TL_ERR_VULKAN, "%s failed: %s", what, vkdev_result_string(res));
}

int render_storage_buffer(render *r, VkDeviceSize size, VkBufferUsageFlags extra, bool host, const char *name,
			  vkdev_buffer *out, char *err, size_t err_size)
{
	VkDeviceSize range = r->dev->props.limits.maxStorageBufferRange;
	if (size > range)
		return tl_error(err, err_size, TL_ERR_UNSUPPORTED,
				"%s needs %.1f MiB at %ux%u, more than this device's storage buffer range (%.1f MiB): "
				"use a smaller --size",
				name, (double)size / 1048576.0, r->desc.width, r->desc.height, (double)range / 1048576.0);
	VkResult res = vkdev_buffer_create(r->dev, size, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | extra, host, name, out);
	return res ? render_vk_error(err, err_size, name, res) : TL_OK;
}
