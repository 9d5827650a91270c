/* colour_gpu.c — evaluates the OpenColorIO GLSL of a view transform on the Vulkan device (colour.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shader_compile.h"
#include "taslab/colour_gpu.h"
#include "taslab/vkdev.h"

static const char *const SRC_HEAD = "#version 460\n";
static const char *const SRC_MAIN =
	"layout(local_size_x = 64) in;\n"
	"layout(std430, set = 0, binding = 0) buffer Pixels { vec4 px[]; };\n"
	"layout(push_constant) uniform P { uint n; } pc;\n"
	"void main() {\n"
	"  uint i = gl_GlobalInvocationID.x;\n"
	"  if (i < pc.n) px[i] = vec4(ocio_display(vec4(px[i].rgb, 1.0)).rgb, px[i].a);\n"
	"}\n";

int colour_apply_gpu(vkdev *dev, const colour *c, float *rgba, size_t n, char *err, size_t err_size)
{
	int rc = -1;
	VkResult vr;
	const char *fn = colour_glsl(c);
	size_t len = strlen(SRC_HEAD) + strlen(fn) + strlen(SRC_MAIN) + 1;
	char *src = malloc(len);
	uint32_t *spv = NULL;
	size_t spv_size = 0;
	vkdev_buffer buf = {0};
	VkShaderModule mod = VK_NULL_HANDLE;
	VkDescriptorSetLayout dsl = VK_NULL_HANDLE;
	VkPipelineLayout pl = VK_NULL_HANDLE;
	VkPipeline pipe = VK_NULL_HANDLE;
	VkDescriptorPool pool = VK_NULL_HANDLE;
	if (!src || n == 0 || n > (1u << 26)) {
		snprintf(err, err_size, n ? "out of memory" : "no pixels");
		goto done;
	}
	snprintf(src, len, "%s%s%s", SRC_HEAD, fn, SRC_MAIN);
	if (shc_compile(src, SHC_STAGE_COMPUTE, &spv, &spv_size, err, err_size))
		goto done;
	VkDevice d = dev->device;
	VkDescriptorSetLayoutBinding b = {0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL};
	VkDescriptorSetLayoutCreateInfo dli = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
					       .bindingCount = 1, .pBindings = &b};
	VkPushConstantRange pcr = {VK_SHADER_STAGE_COMPUTE_BIT, 0, 4};
	VkDescriptorPoolSize ps = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1};
	VkDescriptorPoolCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO, .maxSets = 1,
					 .poolSizeCount = 1, .pPoolSizes = &ps};
	if ((vr = vkdev_buffer_create(dev, n * 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true, "colour probe", &buf)) ||
	    (vr = vkdev_shader_module(dev, spv, spv_size, &mod)) ||
	    (vr = vkCreateDescriptorSetLayout(d, &dli, NULL, &dsl)))
		goto vkfail;
	VkPipelineLayoutCreateInfo pli = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 1,
					  .pSetLayouts = &dsl, .pushConstantRangeCount = 1, .pPushConstantRanges = &pcr};
	if ((vr = vkCreatePipelineLayout(d, &pli, NULL, &pl)))
		goto vkfail;
	VkComputePipelineCreateInfo ci = {
		.sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
		.stage = {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_COMPUTE_BIT,
			  .module = mod, .pName = "main"},
		.layout = pl,
	};
	if ((vr = vkCreateComputePipelines(d, VK_NULL_HANDLE, 1, &ci, NULL, &pipe)) ||
	    (vr = vkCreateDescriptorPool(d, &pi, NULL, &pool)))
		goto vkfail;
	VkDescriptorSet set;
	VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO, .descriptorPool = pool,
					  .descriptorSetCount = 1, .pSetLayouts = &dsl};
	if ((vr = vkAllocateDescriptorSets(d, &ai, &set)))
		goto vkfail;
	VkDescriptorBufferInfo bi = {buf.buffer, 0, VK_WHOLE_SIZE};
	VkWriteDescriptorSet w = {.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = set, .dstBinding = 0,
				  .descriptorCount = 1, .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .pBufferInfo = &bi};
	vkUpdateDescriptorSets(d, 1, &w, 0, NULL);
	memcpy(buf.mapped, rgba, n * 16);
	VkCommandBuffer cmd;
	if ((vr = vkdev_cmd_begin(dev, &cmd)))
		goto vkfail;
	uint32_t count = (uint32_t)n;
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe);
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pl, 0, 1, &set, 0, NULL);
	vkCmdPushConstants(cmd, pl, VK_SHADER_STAGE_COMPUTE_BIT, 0, 4, &count);
	vkCmdDispatch(cmd, (count + 63) / 64, 1, 1);
	VkMemoryBarrier2 mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER_2,
			       .srcStageMask = VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			       .srcAccessMask = VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
			       .dstStageMask = VK_PIPELINE_STAGE_2_HOST_BIT, .dstAccessMask = VK_ACCESS_2_HOST_READ_BIT};
	VkDependencyInfo di = {.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO, .memoryBarrierCount = 1, .pMemoryBarriers = &mb};
	vkCmdPipelineBarrier2(cmd, &di);
	if ((vr = vkdev_cmd_submit_wait(dev, cmd)))
		goto vkfail;
	memcpy(rgba, buf.mapped, n * 16);
	rc = 0;
	goto done;
vkfail:
	snprintf(err, err_size, "colour_apply_gpu: Vulkan error %s", vkdev_result_string(vr));
done:
	if (pool)
		vkDestroyDescriptorPool(dev->device, pool, NULL);
	if (pipe)
		vkDestroyPipeline(dev->device, pipe, NULL);
	if (pl)
		vkDestroyPipelineLayout(dev->device, pl, NULL);
	if (dsl)
		vkDestroyDescriptorSetLayout(dev->device, dsl, NULL);
	if (mod)
		vkDestroyShaderModule(dev->device, mod, NULL);
	vkdev_buffer_destroy(dev, &buf);
	free(spv);
	free(src);
	return rc;
}
