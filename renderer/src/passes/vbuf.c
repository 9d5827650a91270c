/* vbuf.c — the compacted sample path (vbuf.h; BASELINES.md section 0): buffers, the descriptor set, the select /
 * args / shade / resolve pipelines (shaders/vbuf/) and their recording. */
#include "vbuf.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { VBUF_BINDINGS = 10 };
static bool is_image(uint32_t i) { return i >= 6; }

static int make_set(render *r, vbuf_pass *v, char *err, size_t err_size)
{
	VkDevice d = r->dev->device;
	VkDescriptorSetLayoutBinding b[VBUF_BINDINGS];
	for (uint32_t i = 0; i < VBUF_BINDINGS; i++)
		b[i] = (VkDescriptorSetLayoutBinding){i, is_image(i) ? VK_DESCRIPTOR_TYPE_STORAGE_IMAGE
							     : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
						      1, VK_SHADER_STAGE_COMPUTE_BIT, NULL};
	VkDescriptorSetLayoutCreateInfo li = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
					      .bindingCount = VBUF_BINDINGS, .pBindings = b};
	VkResult res;
	if ((res = vkCreateDescriptorSetLayout(d, &li, NULL, &v->set_layout)))
		return render_vk_error(err, err_size, "vbuf: descriptor set layout", res);
	VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
					  .descriptorPool = r->pool, .descriptorSetCount = 1, .pSetLayouts = &v->set_layout};
	if ((res = vkAllocateDescriptorSets(d, &ai, &v->set)))
		return render_vk_error(err, err_size, "vbuf: descriptor set", res);
	const vkdev_buffer *bufs[VBUF_BINDINGS] = {&r->vertices, &r->indices, &v->objinfo, &v->list, &v->counters, &v->rates};
	/* binding 9, the display values, is ads's alone (the other passes do not declare it: svals stands in) */
	const vkdev_image *imgs[VBUF_BINDINGS] = {[6] = &v->ids.image, [7] = &v->svals, [8] = &r->hdr,
						  [9] = v->ads ? &v->sdisp : &v->svals};
	vkdev_write_storage_set(d, v->set, VBUF_BINDINGS, bufs, imgs);
	return TL_OK;
}

int vbuf_make_compute(render *r, vbuf_pass *v, const char *path, const char *defs, VkPipeline *out, char *err,
		      size_t err_size)
{
	return render_compute_defs(r, path, defs, v->layout, out, err, err_size);
}

int vbuf_init(render *r, vbuf_pass *v, bool ads, char *err, size_t err_size)
{
	const scene *sc = r->scene;
	uint32_t w = r->desc.width, h = r->desc.height;
	v->ads = ads;
	v->tiles_x = (w + VBUF_TILE - 1) / VBUF_TILE;
	v->tiles_y = (h + VBUF_TILE - 1) / VBUF_TILE;
	size_t objects = sc->object_count ? sc->object_count : 1;
	const struct {
		vkdev_buffer *b;
		VkDeviceSize size;
		VkBufferUsageFlags extra;
		bool host; /* written or read by the CPU; the sample list is the GPU's alone (device-local on a GPU) */
		const char *name;
	} spec[4] = {
		{&v->objinfo, objects * 16, 0, true, "vbuf object info"},
		{&v->list, (VkDeviceSize)w * h * 8, 0, false, "vbuf sample list"},
		{&v->counters, 16 * 4, VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, true, "vbuf counters"},
		{&v->rates, (VkDeviceSize)v->tiles_x * v->tiles_y * 4, 0, true, "vbuf tile rates"},
	};
	for (int i = 0; i < 4; i++) {
		int rc = render_storage_buffer(r, spec[i].size, VK_BUFFER_USAGE_TRANSFER_DST_BIT | spec[i].extra, spec[i].host,
					       spec[i].name, spec[i].b, err, err_size);
		if (rc)
			return rc;
	}
	uint32_t *oi = v->objinfo.mapped;
	for (size_t o = 0; o < sc->object_count; o++) {
		int m = sc->objects[o].mesh;
		oi[4 * o] = m >= 0 ? r->mesh_first_index[m] : 0;
		oi[4 * o + 1] = m >= 0 ? r->mesh_vertex_offset[m] : 0;
		oi[4 * o + 2] = oi[4 * o + 3] = 0;
	}
	uint32_t *rates = v->rates.mapped;
	for (uint32_t t = 0; t < v->tiles_x * v->tiles_y; t++)
		rates[t] = VBUF_RATE(1, 1);
	VkResult res = vkdev_image_create(r->dev, w, h, 1, 1, VK_FORMAT_R16G16B16A16_SFLOAT,
					  VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
					  false, "vbuf samples", &v->svals);
	if (res)
		return render_vk_error(err, err_size, "vbuf samples image", res);
	if (ads && (res = vkdev_image_create(r->dev, w, h, 1, 1, VK_FORMAT_R32G32_UINT, VK_IMAGE_USAGE_STORAGE_BIT,
					     VK_IMAGE_ASPECT_COLOR_BIT, false, "vbuf display values", &v->sdisp)))
		return render_vk_error(err, err_size, "vbuf display values image", res);
	int rc = ids_pass_init(r, &v->ids, NULL, err, err_size);
	if (!rc)
		rc = make_set(r, v, err, err_size);
	if (rc)
		return rc;
	VkDescriptorSetLayout sets[2] = {r->scene_set_layout, v->set_layout};
	VkPushConstantRange pcr = {VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(gpu_push)};
	VkPipelineLayoutCreateInfo li = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 2,
					 .pSetLayouts = sets, .pushConstantRangeCount = 1, .pPushConstantRanges = &pcr};
	if ((res = vkCreatePipelineLayout(r->dev->device, &li, NULL, &v->layout)))
		return render_vk_error(err, err_size, "vbuf: pipeline layout", res);
	const char *mode = ads ? "#define ADS 1\n" : "";
	/* TASLAB_VBUF_GRADIENTS=analytic (diagnostic, README "Compacted sample path"): analytic texture gradients */
	const char *g = getenv("TASLAB_VBUF_GRADIENTS");
	char shade_defs[128];
	snprintf(shade_defs, sizeof shade_defs, "%s%s%s", mode,
		 g && !strcmp(g, "analytic") ? "#define VBUF_ANALYTIC_GRADIENTS 1\n" : "",
		 v->centroid ? "#define VBUF_CENTROID 1\n" : "");
	const char *plain_defs = shade_defs + strlen(mode); /* the same without ADS */
	if ((rc = vbuf_make_compute(r, v, "vbuf/args.comp.in", mode, &v->args, err, err_size)) ||
	    (rc = vbuf_make_compute(r, v, "vbuf/shade.comp.in", shade_defs, &v->shade, err, err_size)) ||
	    (rc = vbuf_make_compute(r, v, "vbuf/resolve.comp.in", mode, &v->resolve, err, err_size)) ||
	    (rc = vbuf_make_compute(r, v, ads ? "vbuf/ads_select.comp.in" : "vbuf/select.comp.in", mode,
				    ads ? &v->ads_select : &v->select, err, err_size)) ||
	    (ads && (rc = vbuf_make_compute(r, v, "vbuf/ads_display.comp.in", mode, &v->ads_display, err, err_size))) ||
	    (ads && (rc = vbuf_make_compute(r, v, "vbuf/shade.comp.in", plain_defs, &v->shade_last, err, err_size))) ||
	    (v->truth && (rc = vbuf_make_compute(r, v, "vbuf/truth.comp.in", shade_defs, &v->truth_pipe, err, err_size))))
		return rc;
	/* the samples image starts at 0 in GENERAL layout */
	VkCommandBuffer cmd;
	if ((res = vkdev_cmd_begin(r->dev, &cmd)))
		return render_vk_error(err, err_size, "command buffer", res);
	VkClearColorValue zero = {{0}};
	VkImageSubresourceRange range = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
	vkdev_barrier_image(cmd, &v->svals, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
			    VK_PIPELINE_STAGE_2_NONE, 0, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
	vkCmdClearColorImage(cmd, v->svals.image, VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &range);
	if (ads) { /* written before it is read in every frame (vbuf.glsl): GENERAL only */
		vkdev_barrier_image(cmd, &v->sdisp, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
				    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
				    VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
	}
	vbuf_barrier(cmd);
	if ((res = vkdev_cmd_submit_wait(r->dev, cmd)))
		return render_vk_error(err, err_size, "vbuf setup", res);
	return TL_OK;
}

void vbuf_finish(render *r, vbuf_pass *v)
{
	VkDevice d = r->dev->device;
	VkPipeline p[8] = {v->select, v->args,        v->shade,      v->resolve,
			   v->ads_select, v->ads_display, v->truth_pipe, v->shade_last};
	for (size_t i = 0; i < sizeof p / sizeof p[0]; i++)
		if (p[i])
			vkDestroyPipeline(d, p[i], NULL);
	if (v->layout)
		vkDestroyPipelineLayout(d, v->layout, NULL);
	if (v->set_layout)
		vkDestroyDescriptorSetLayout(d, v->set_layout, NULL);
	vkdev_buffer *b[4] = {&v->objinfo, &v->list, &v->counters, &v->rates};
	for (int i = 0; i < 4; i++)
		vkdev_buffer_destroy(r->dev, b[i]);
	vkdev_image_destroy(r->dev, &v->svals);
	vkdev_image_destroy(r->dev, &v->sdisp);
	ids_pass_finish(r, &v->ids);
	memset(v, 0, sizeof *v);
}

void vbuf_barrier(VkCommandBuffer cmd)
{
	VkPipelineStageFlags2 st = VK_PIPELINE_STAGE_2_ALL_GRAPHICS_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT |
				   VK_PIPELINE_STAGE_2_TRANSFER_BIT | VK_PIPELINE_STAGE_2_HOST_BIT |
				   VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT;
	render_barrier(cmd, st, VK_ACCESS_2_MEMORY_WRITE_BIT, st, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
}

void vbuf_bind(render *r, const vbuf_pass *v, VkCommandBuffer cmd, VkPipeline p, uint32_t slot, const uint32_t aux[4])
{
	VkDescriptorSet sets[2] = {r->scene_set, v->set};
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p);
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, v->layout, 0, 2, sets, 0, NULL);
	gpu_push pc = {slot, 0, (uint32_t)r->scene->object_count, 0, {0, 0, 0, 0}};
	if (aux)
		memcpy(pc.aux, aux, sizeof pc.aux);
	vkCmdPushConstants(cmd, v->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof pc, &pc);
}

void vbuf_record_begin(render *r, vbuf_pass *v, VkCommandBuffer cmd)
{
	vkCmdFillBuffer(cmd, v->counters.buffer, 0, VK_WHOLE_SIZE, 0);
	vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
			    VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT, VK_PIPELINE_STAGE_2_CLEAR_BIT,
			    VK_ACCESS_2_TRANSFER_WRITE_BIT);
	vbuf_barrier(cmd);
}

static void record_args(render *r, vbuf_pass *v, VkCommandBuffer cmd)
{
	vbuf_barrier(cmd);
	vbuf_bind(r, v, cmd, v->args, 0, NULL);
	vkCmdDispatch(cmd, 1, 1, 1);
	vbuf_barrier(cmd);
}

void vbuf_record_select(render *r, vbuf_pass *v, VkCommandBuffer cmd)
{
	vbuf_bind(r, v, cmd, v->select, 0, NULL);
	vkCmdDispatch(cmd, (r->desc.width + 7) / 8, (r->desc.height + 7) / 8, 1);
	record_args(r, v, cmd);
}

void vbuf_record_ads_step(render *r, vbuf_pass *v, VkCommandBuffer cmd, uint32_t s, uint32_t kind, float S,
			  bool edge_guard, bool last)
{
	uint32_t sbits;
	memcpy(&sbits, &S, sizeof sbits);
	uint32_t aux[4] = {s, kind, sbits, edge_guard ? 1u : 0u};
	/* lattice points per axis: offsets 0 (level 0) or s/2; the square step's two layers share the larger count */
	uint32_t off = kind == 1 ? s / 2 : 0;
	uint32_t nx = (r->desc.width - off + s - 1) / s, ny = (r->desc.height - off + s - 1) / s;
	if (r->desc.width <= off || r->desc.height <= off)
		nx = ny = 0;
	vbuf_bind(r, v, cmd, v->ads_select, 0, aux);
	if (nx && ny)
		vkCmdDispatch(cmd, (nx + 7) / 8, (ny + 7) / 8, kind == 2 ? 2 : 1);
	record_args(r, v, cmd);
	/* the interpolated pixels' display values, before the next step reads them (ads_display.comp.in); the shaded
	 * pixels' are stored by the shade. The last step's pixels are no step's neighbours: neither (half the pixels
	 * of a frame, each a display transform and a store; 2026-11-27 README bench-ads-last) */
	if (!last) {
		vbuf_bind(r, v, cmd, v->ads_display, 0, NULL);
		vkCmdDispatchIndirect(cmd, v->counters.buffer, 12 * sizeof(uint32_t));
		vbuf_barrier(cmd);
	}
	vbuf_bind(r, v, cmd, last ? v->shade_last : v->shade, 0, NULL);
	vkCmdDispatchIndirect(cmd, v->counters.buffer, 2 * sizeof(uint32_t));
	vbuf_barrier(cmd);
}

void vbuf_record_shade(render *r, vbuf_pass *v, VkCommandBuffer cmd, uint32_t slot)
{
	vbuf_bind(r, v, cmd, v->shade, slot, NULL);
	vkCmdDispatchIndirect(cmd, v->counters.buffer, 2 * sizeof(uint32_t));
	vbuf_barrier(cmd);
}

void vbuf_record_resolve(render *r, vbuf_pass *v, VkCommandBuffer cmd)
{
	const scene *sc = r->scene;
	VkClearColorValue sky = {{sc->sky[0] * sc->exposure, sc->sky[1] * sc->exposure, sc->sky[2] * sc->exposure, 0.0f}};
	VkImageSubresourceRange range = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
	vkCmdClearColorImage(cmd, r->hdr.image, VK_IMAGE_LAYOUT_GENERAL, &sky, 1, &range);
	render_barrier(cmd, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
		       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
	vbuf_bind(r, v, cmd, v->resolve, 0, NULL);
	vkCmdDispatch(cmd, (r->desc.width + 7) / 8, (r->desc.height + 7) / 8, 1);
	vbuf_barrier(cmd);
}

void vbuf_record_truth(render *r, vbuf_pass *v, VkCommandBuffer cmd)
{
	if (v->truth_pipe) {
		uint32_t aux[4] = {0, 0, 0, 0};
		memcpy(&aux[0], &v->truth_t, sizeof aux[0]);
		vbuf_bind(r, v, cmd, v->truth_pipe, 0, aux);
		vkCmdDispatch(cmd, (r->desc.width + 7) / 8, (r->desc.height + 7) / 8, 1);
		vbuf_barrier(cmd);
	}
	vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL,
			    VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			    VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
			    VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
	vbuf_barrier(cmd);
}

void vbuf_record_finish(render *r, VkCommandBuffer cmd)
{
	if (r->blend_count)
		render_pass_scene(r, cmd, 0, &(render_scene_pass){.hdr = RENDER_HDR_LOAD, .blend = 1});
	render_ts(r, cmd);
	render_pass_display(r, cmd);
	render_ts(r, cmd);
	render_pass_readback(r, cmd);
	vbuf_barrier(cmd);
	render_ts(r, cmd);
}
