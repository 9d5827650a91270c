/* tas_filter.c — the spatial max filter of the TAS framework (passes.h; paper secs. 5.3 and 6.1): 8x8 max
 * downsample then a 9x9 max kernel (tas/max_down.comp, tas/max_kernel.comp). One definition shared by the
 * TFR analysis' filtered predictors (Figs. 8, 9) and tarc's reshading decision. */
#include "passes.h"

#include "shaders/tas/max_down_comp.h"
#include "shaders/tas/max_kernel_comp.h"

int tas_filter_init(render *r, tas_filter *f, char *err, size_t err_size)
{
	return tas_filter_init_down(r, f, max_down_comp, sizeof max_down_comp, err, err_size);
}

int tas_filter_init_down(render *r, tas_filter *f, const uint32_t *down_spv, size_t down_size, char *err,
			 size_t err_size)
{
	VkDevice d = r->dev->device;
	VkResult res;
	VkDescriptorSetLayoutBinding b[3];
	for (uint32_t i = 0; i < 3; i++)
		b[i] = (VkDescriptorSetLayoutBinding){i, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL};
	VkDescriptorSetLayoutCreateInfo li = {
		.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO, .bindingCount = 3, .pBindings = b};
	VkPushConstantRange pcr = {VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(uint32_t)};
	if ((res = vkCreateDescriptorSetLayout(d, &li, NULL, &f->set_layout)))
		return render_vk_error(err, err_size, "max filter: descriptor set layout", res);
	VkPipelineLayoutCreateInfo pl = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO,
		.setLayoutCount = 1,
		.pSetLayouts = &f->set_layout,
		.pushConstantRangeCount = 1,
		.pPushConstantRanges = &pcr,
	};
	if ((res = vkCreatePipelineLayout(d, &pl, NULL, &f->layout)) ||
	    (res = render_make_compute(r, down_spv, down_size, f->layout, &f->down)) ||
	    (res = render_make_compute(r, max_kernel_comp, sizeof max_kernel_comp, f->layout, &f->kernel)))
		return render_vk_error(err, err_size, "max filter: pipelines", res);
	return TL_OK;
}

void tas_filter_finish(render *r, tas_filter *f)
{
	VkDevice d = r->dev->device;
	if (f->down)
		vkDestroyPipeline(d, f->down, NULL);
	if (f->kernel)
		vkDestroyPipeline(d, f->kernel, NULL);
	if (f->layout)
		vkDestroyPipelineLayout(d, f->layout, NULL);
	if (f->set_layout)
		vkDestroyDescriptorSetLayout(d, f->set_layout, NULL);
	*f = (tas_filter){0};
}

int tas_filter_bind(render *r, tas_filter *f, const vkdev_image *src, const vkdev_image *mid, const vkdev_image *dst,
		    VkDescriptorSet *out, char *err, size_t err_size)
{
	VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
					  .descriptorPool = r->pool, .descriptorSetCount = 1, .pSetLayouts = &f->set_layout};
	VkResult res = vkAllocateDescriptorSets(r->dev->device, &ai, out);
	if (res)
		return render_vk_error(err, err_size, "max filter: descriptor set", res);
	const vkdev_image *imgs[3] = {src, mid, dst};
	VkDescriptorImageInfo ii[3];
	VkWriteDescriptorSet w[3];
	for (uint32_t i = 0; i < 3; i++) {
		ii[i] = (VkDescriptorImageInfo){VK_NULL_HANDLE, imgs[i]->view, VK_IMAGE_LAYOUT_GENERAL};
		w[i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = *out, .dstBinding = i,
					      .descriptorCount = 1, .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
					      .pImageInfo = &ii[i]};
	}
	vkUpdateDescriptorSets(r->dev->device, 3, w, 0, NULL);
	return TL_OK;
}

void tas_filter_record(const tas_filter *f, VkCommandBuffer cmd, VkDescriptorSet set, uint32_t w, uint32_t h,
		       uint32_t layers)
{
	uint32_t lw = (w + 7) / 8, lh = (h + 7) / 8;
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, f->layout, 0, 1, &set, 0, NULL);
	vkCmdPushConstants(cmd, f->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof layers, &layers);
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, f->down);
	vkCmdDispatch(cmd, (lw + 7) / 8, (lh + 7) / 8, 1);
	render_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
		       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, f->kernel);
	vkCmdDispatch(cmd, (lw + 7) / 8, (lh + 7) / 8, 1);
}
