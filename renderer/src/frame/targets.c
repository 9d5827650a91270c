/* targets.c — render targets (depth, HDR, display), samplers, readback buffers, queries, the command
 * buffer, and the scene and display descriptor sets (scene set: frame states, objects, materials, textures,
 * shadow maps — passes/shadow.c writes binding 5 — and the reference shading's counter, binding 6). */
#include "render_internal.h"

#include <stdio.h>
#include <stdlib.h>

int render_descriptors_create(render *r, char *err, size_t err_size)
{
	int rc = 0;
	VkDevice d = r->dev->device;
	VkShaderStageFlags gs = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT | VK_SHADER_STAGE_COMPUTE_BIT;
	VkDescriptorSetLayoutBinding sb[7] = {
		{0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, gs, NULL},
		{1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, gs, NULL},
		{2, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, gs, NULL},
		{3, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, gs, NULL},
		{4, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, gs, NULL},
		{5, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, GPU_SHADOW_CHUNKS, gs, NULL},
		/* the shading counter of the reference shading (ref/count.glsl), fragment stage only */
		{6, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_FRAGMENT_BIT, NULL},
	};
	VkDescriptorSetLayoutCreateInfo sl = {
		.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO, .bindingCount = 7, .pBindings = sb};
	CHECK_VK(vkCreateDescriptorSetLayout(d, &sl, NULL, &r->scene_set_layout));
	VkDescriptorSetLayoutBinding db[2] = {
		{0, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL},
		{1, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL},
	};
	VkDescriptorSetLayoutCreateInfo dl = {
		.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO, .bindingCount = 2, .pBindings = db};
	CHECK_VK(vkCreateDescriptorSetLayout(d, &dl, NULL, &r->display_set_layout));
	VkDescriptorPoolSize ps[3] = {
		{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 128},
		{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 128},
		{VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 128},
	};
	VkDescriptorPoolCreateInfo pi = {
		.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO, .maxSets = 32, .poolSizeCount = 3, .pPoolSizes = ps};
	CHECK_VK(vkCreateDescriptorPool(d, &pi, NULL, &r->pool));
	rc = render_descriptors_view_create(r, err, err_size);
fail:
	return rc;
}

int render_descriptors_view_create(render *r, char *err, size_t err_size)
{
	int rc = 0;
	VkDevice d = r->dev->device;
	VkDescriptorSetAllocateInfo ai = {
		.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
		.descriptorPool = r->pool,
		.descriptorSetCount = 1,
		.pSetLayouts = &r->scene_set_layout,
	};
	CHECK_VK(vkAllocateDescriptorSets(d, &ai, &r->scene_set));
	ai.pSetLayouts = &r->display_set_layout;
	CHECK_VK(vkAllocateDescriptorSets(d, &ai, &r->display_set));
	VkDescriptorBufferInfo bi[4] = {
		{r->states.buffer, 0, VK_WHOLE_SIZE},
		{r->objects.buffer, 0, VK_WHOLE_SIZE},
		{r->materials.buffer, 0, VK_WHOLE_SIZE},
		{r->shade_count.buffer, 0, VK_WHOLE_SIZE},
	};
	VkDescriptorImageInfo ii[2] = {
		{r->tex_sampler, r->color_tex.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL},
		{r->tex_sampler, r->data_tex.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL},
	}; /* binding 5 (shadow maps): render_shadow.c */
	VkDescriptorImageInfo si[2] = {
		{VK_NULL_HANDLE, r->hdr.view, VK_IMAGE_LAYOUT_GENERAL},
		{VK_NULL_HANDLE, r->display.view, VK_IMAGE_LAYOUT_GENERAL},
	};
	VkWriteDescriptorSet w[8];
	for (uint32_t i = 0; i < 3; i++)
		w[i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = r->scene_set,
					      .dstBinding = i, .descriptorCount = 1,
					      .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .pBufferInfo = &bi[i]};
	for (uint32_t i = 0; i < 2; i++)
		w[3 + i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = r->scene_set,
						  .dstBinding = 3 + i, .descriptorCount = 1,
						  .descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
						  .pImageInfo = &ii[i]};
	for (uint32_t i = 0; i < 2; i++)
		w[5 + i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = r->display_set,
						  .dstBinding = i, .descriptorCount = 1,
						  .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, .pImageInfo = &si[i]};
	w[7] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = r->scene_set,
				      .dstBinding = 6, .descriptorCount = 1,
				      .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .pBufferInfo = &bi[3]};
	vkUpdateDescriptorSets(d, 8, w, 0, NULL);
fail:
	return rc;
}

int render_targets_create(render *r, char *err, size_t err_size)
{
	int rc = 0;
	const scene *s = r->scene;
	VkSamplerCreateInfo si = {
		.sType = VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO,
		.magFilter = VK_FILTER_LINEAR,
		.minFilter = VK_FILTER_LINEAR,
		.mipmapMode = VK_SAMPLER_MIPMAP_MODE_LINEAR,
		.addressModeU = VK_SAMPLER_ADDRESS_MODE_REPEAT,
		.addressModeV = VK_SAMPLER_ADDRESS_MODE_REPEAT,
		.addressModeW = VK_SAMPLER_ADDRESS_MODE_REPEAT,
		.maxLod = VK_LOD_CLAMP_NONE,
	};
	CHECK_VK(vkCreateSampler(r->dev->device, &si, NULL, &r->tex_sampler));
	VkSamplerCreateInfo sh = si;
	sh.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
	sh.addressModeU = sh.addressModeV = sh.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
	sh.compareEnable = VK_TRUE;
	sh.compareOp = VK_COMPARE_OP_LESS_OR_EQUAL;
	sh.maxLod = 0.0f;
	CHECK_VK(vkCreateSampler(r->dev->device, &sh, NULL, &r->shadow_sampler));

	r->light_shadow_layer = calloc(s->light_count + 1, sizeof *r->light_shadow_layer);
	if (!r->light_shadow_layer) {
		rc = TL_ERR_NOMEM;
		snprintf(err, err_size, "out of memory");
		goto fail;
	}
	for (size_t i = 0; i < s->light_count; i++) {
		r->light_shadow_layer[i] = s->lights[i].casts_shadow ? (int)r->shadow.layers : -1;
		if (s->lights[i].casts_shadow)
			r->shadow.layers += s->lights[i].kind == SCENE_LIGHT_POINT ? 6 : 1;
	}
	rc = render_targets_view_create(r, err, err_size);
fail:
	return rc;
}

int render_targets_view_create(render *r, char *err, size_t err_size)
{
	int rc = 0;
	uint32_t w = r->desc.width, h = r->desc.height;
	/* multiview: the eye's layer of the visibility pass's depth is copied in (passes/ids.c ids_multiview_record) */
	VkImageUsageFlags du = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | (r->multiview ? VK_IMAGE_USAGE_TRANSFER_DST_BIT : 0);
	CHECK_VK(vkdev_image_create(r->dev, w, h, 1, 1, RENDER_DEPTH_FORMAT, du,
				    VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT, false, "depth", &r->depth));
	CHECK_VK(vkdev_image_create(r->dev, w, h, 1, 1, VK_FORMAT_R16G16B16A16_SFLOAT,
				    VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT |
				    VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
				    false, "hdr", &r->hdr));
	CHECK_VK(vkdev_image_create(r->dev, w, h, 1, 1, VK_FORMAT_R8G8B8A8_UNORM,
				    VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
				    false, "display", &r->display));
	r->row_pitch_hdr_B = (w * 8 + 255) & ~255u;
	r->row_pitch_display_B = (w * 4 + 255) & ~255u;
	CHECK_VK(vkdev_buffer_create(r->dev, (VkDeviceSize)r->row_pitch_hdr_B * h, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true,
				     "readback hdr", &r->readback_hdr));
	CHECK_VK(vkdev_buffer_create(r->dev, (VkDeviceSize)r->row_pitch_display_B * h, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
				     true, "readback display", &r->readback_display));
	r->hdr_packed = malloc((size_t)w * h * 8);
	r->display_packed = malloc((size_t)w * h * 4);
	if (!r->hdr_packed || !r->display_packed) {
		rc = TL_ERR_NOMEM;
		snprintf(err, err_size, "out of memory for %ux%u frame buffers", w, h);
	}
fail:
	return rc;
}

void render_targets_destroy(render *r)
{
	VkDevice d = r->dev->device;
	if (r->pool)
		vkDestroyDescriptorPool(d, r->pool, NULL);
	if (r->scene_set_layout)
		vkDestroyDescriptorSetLayout(d, r->scene_set_layout, NULL);
	if (r->display_set_layout)
		vkDestroyDescriptorSetLayout(d, r->display_set_layout, NULL);
	if (r->tex_sampler)
		vkDestroySampler(d, r->tex_sampler, NULL);
	if (r->shadow_sampler)
		vkDestroySampler(d, r->shadow_sampler, NULL);
	vkdev_image_destroy(r->dev, &r->depth);
	vkdev_image_destroy(r->dev, &r->hdr);
	vkdev_image_destroy(r->dev, &r->display);
	vkdev_buffer_destroy(r->dev, &r->readback_hdr);
	vkdev_buffer_destroy(r->dev, &r->readback_display);
	free(r->light_shadow_layer);
	free(r->hdr_packed);
	free(r->display_packed);
	r->light_shadow_layer = NULL;
	r->hdr_packed = NULL;
	r->display_packed = NULL;
}
