/* shade.c — forward shading of the visible samples (depth EQUAL after the pre-pass) and "over" compositing
 * of glTF BLEND surfaces, sorted back to front per object. */
#include "passes.h"

#include <stdio.h>
#include <stdlib.h>

#include "shaders/ref/shade_frag.h"
#include "shaders/ref/shade_sg_frag.h"
#include "shaders/ref/shade_sg_nohelp_frag.h"
#include "shaders/ref/trivial_frag.h"

void render_pass_shade(render *r, VkCommandBuffer cmd, uint32_t slot)
{
	render_pass_shade_with(r, cmd, slot, &r->shade_pipe, VK_NULL_HANDLE);
}

void render_pass_shade_with(render *r, VkCommandBuffer cmd, uint32_t slot, const render_pipeline *opaque,
			    VkDescriptorSet method_set)
{
	render_scene_pass p = {.pipe = opaque, .set = method_set, .hdr = RENDER_HDR_CLEAR, .blend = 1, .query = 1};
	render_pass_scene(r, cmd, slot, &p);
}

/* glTF BLEND: "over" compositing after the opaque surfaces, objects sorted back to front by the distance of
 * their bounds centre from the camera (per object, not per triangle). */
static void draw_blend(render *r, VkCommandBuffer cmd, uint32_t slot)
{
	const scene *sc = r->scene;
	float *dist = malloc(r->blend_count * sizeof *dist);
	uint32_t n = 0;
	for (size_t i = 0; dist && i < sc->object_count; i++) {
		const scene_object *o = &sc->objects[i];
		if (o->mesh < 0 || sc->materials[o->material].alpha_mode != SCENE_ALPHA_BLEND)
			continue;
		const scene_mesh *m = &sc->meshes[o->mesh];
		tlm_vec3 c = tlm_mat4_mul_point(r->world[i], tlm_v3_scale(tlm_v3_add(m->bounds_min, m->bounds_max), 0.5f));
		uint32_t k = n++;
		float d = tlm_v3_length(tlm_v3_sub(c, r->eye));
		while (k > 0 && dist[k - 1] < d) { /* insertion sort, farthest first; ties keep scene order */
			dist[k] = dist[k - 1];
			r->blend_order[k] = r->blend_order[k - 1];
			k--;
		}
		dist[k] = d;
		r->blend_order[k] = (uint32_t)i;
	}
	free(dist);
	render_bind_scene(r, cmd, &r->shade_blend_pipe);
	for (uint32_t k = 0; k < n; k++)
		render_draw_object(r, cmd, &r->shade_blend_pipe, slot, 0, r->blend_order[k], 1);
}

void render_pass_scene(render *r, VkCommandBuffer cmd, uint32_t slot, const render_scene_pass *p)
{
	uint32_t w = r->desc.width, h = r->desc.height;
	const scene *s = r->scene;
	if (p->hdr == RENDER_HDR_CLEAR)
		vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
				    VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_COPY_BIT, 0,
				    VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
	else if (p->hdr == RENDER_HDR_LOAD)
		render_barrier(cmd, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
			       VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
			       VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
	/* Background: sky radiance (times exposure), coverage 0. */
	VkRenderingAttachmentInfo ca = {
		.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
		.imageView = r->hdr.view,
		.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
		.loadOp = p->hdr == RENDER_HDR_LOAD ? VK_ATTACHMENT_LOAD_OP_LOAD : VK_ATTACHMENT_LOAD_OP_CLEAR,
		.storeOp = VK_ATTACHMENT_STORE_OP_STORE,
		.clearValue = {.color = {{s->sky[0] * s->exposure, s->sky[1] * s->exposure, s->sky[2] * s->exposure, 0.0f}}},
	};
	VkRenderingAttachmentInfo da = {
		.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
		.imageView = r->depth.view,
		.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
		.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD,
		.storeOp = VK_ATTACHMENT_STORE_OP_STORE,
	};
	VkRenderingAttachmentInfo sa = da;
	sa.loadOp = p->stencil == RENDER_STENCIL_PASS_CLEAR ? VK_ATTACHMENT_LOAD_OP_CLEAR : VK_ATTACHMENT_LOAD_OP_LOAD;
	sa.clearValue = (VkClearValue){.depthStencil = {1.0f, 0}};
	VkRenderingInfo ri = {
		.sType = VK_STRUCTURE_TYPE_RENDERING_INFO,
		.renderArea = {{0, 0}, {w, h}},
		.layerCount = 1,
		.colorAttachmentCount = p->hdr ? 1u : 0u,
		.pColorAttachments = &ca,
		.pDepthAttachment = &da,
		.pStencilAttachment = p->stencil ? &sa : NULL,
	};
	if (p->query)
		render_stats_begin(r, cmd);
	vkCmdBeginRendering(cmd, &ri);
	render_set_viewport(cmd, w, h);
	if (p->fullscreen) {
		vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p->pipe->pipeline);
		vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p->pipe->layout, 0, 1, &r->scene_set, 0, NULL);
		if (p->set)
			vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p->pipe->layout, 1, 1, &p->set, 0, NULL);
		gpu_push pc = {slot, 0, (uint32_t)s->object_count, 0, {r->push_aux[0], r->push_aux[1], r->push_aux[2], r->push_aux[3]}};
		vkCmdPushConstants(cmd, p->pipe->layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof pc,
				   &pc);
		vkCmdDraw(cmd, 3, 1, 0, 0);
	} else if (p->pipe) {
		render_bind_scene(r, cmd, p->pipe);
		if (p->set)
			vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p->pipe->layout, 1, 1, &p->set, 0, NULL);
		render_draw_objects(r, cmd, p->pipe, slot, 0, RENDER_OPAQUE_BIT | RENDER_MASK_BIT, NULL, 1);
	}
	if (p->blend && r->blend_count)
		draw_blend(r, cmd, slot);
	vkCmdEndRendering(cmd);
	if (p->query)
		render_stats_end(r, cmd);
}

/* The reference shading pipelines (opaque/masked and BLEND). */
static VkResult make_shade_pipelines(render *r)
{
	/* the shading counts its own fragments, one atomic per subgroup where the device allows (ref/count.glsl) */
	render_count_mode cm = render_count_mode_of(r->dev->physical);
	render_pipe_desc shade = {.attributes = RENDER_ATTR_ALL, .color = 1, .depth_op = VK_COMPARE_OP_EQUAL,
				  .fs = cm == RENDER_COUNT_SUBGROUP_NO_HELPERS ? shade_sg_nohelp_frag
					: cm == RENDER_COUNT_SUBGROUP	     ? shade_sg_frag
									     : shade_frag,
				  .fs_size = cm == RENDER_COUNT_SUBGROUP_NO_HELPERS ? sizeof shade_sg_nohelp_frag
					     : cm == RENDER_COUNT_SUBGROUP	    ? sizeof shade_sg_frag
										    : sizeof shade_frag};
	if (r->desc.trivial_shading) {
		shade.fs = trivial_frag;
		shade.fs_size = sizeof trivial_frag;
	}
	VkResult res = render_make_graphics(r, &shade, &r->shade_pipe);
	if (!res && render_has_alpha_mode(r, SCENE_ALPHA_BLEND)) {
		render_pipe_desc sb = shade;
		sb.depth_op = VK_COMPARE_OP_LESS_OR_EQUAL;
		sb.blend = 1;
		sb.fs_alpha_blend = !r->desc.trivial_shading;
		res = render_make_graphics(r, &sb, &r->shade_blend_pipe);
	}
	return res;
}

int render_shade_init(render *r, char *err, size_t err_size)
{
	int rc = 0;
	CHECK_VK(make_shade_pipelines(r));
	if (render_has_alpha_mode(r, SCENE_ALPHA_BLEND)) {
		for (size_t i = 0; i < r->scene->object_count; i++) {
			const scene_object *o = &r->scene->objects[i];
			r->blend_count += o->mesh >= 0 && r->scene->materials[o->material].alpha_mode == SCENE_ALPHA_BLEND;
		}
		if (!(r->blend_order = calloc(r->blend_count, sizeof *r->blend_order)))
			return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
fail:
	return rc;
}
