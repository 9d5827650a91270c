/* pipeline.c — graphics and compute pipelines of the frame pipeline, and run-time shader compilation
 * (templates completed with the OpenColorIO display function, device/shader_library.h). */
#include "render_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shaders/common/fullscreen_vert.h"
#include "shaders/common/scene_vert.h"

void render_specialization(const render *r, int alpha_blend, render_spec *data, VkSpecializationInfo *out)
{
	memset(data, 0, sizeof *data);
	data->values[0] = alpha_blend ? VK_TRUE : VK_FALSE;
	data->values[1] = 0; /* constant_id 1: unused (was the shadow chunk count) */
	data->values[2] = (int32_t)r->scene->light_count;
	for (uint32_t i = 0; i < SCENE_MAX_LIGHTS; i++)
		data->values[3 + i] = i < r->scene->light_count ? r->shadow.light_code[i] : -1;
	for (uint32_t k = 0; k < RENDER_SPEC_COUNT; k++)
		data->entries[k] = (VkSpecializationMapEntry){k, k * (uint32_t)sizeof(int32_t), sizeof(int32_t)};
	*out = (VkSpecializationInfo){RENDER_SPEC_COUNT, data->entries, sizeof data->values, data->values};
}

/* Whether env names "1" (a test's switch to the one-atomic-per-invocation paths). */
static bool env_is_one(const char *env)
{
	const char *v = getenv(env);
	return v && strcmp(v, "1") == 0;
}

bool render_subgroup_has(VkPhysicalDevice pd, VkShaderStageFlags stage, VkSubgroupFeatureFlags ops)
{
	VkPhysicalDeviceSubgroupProperties sp = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
	VkPhysicalDeviceProperties2 p2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, .pNext = &sp};
	vkGetPhysicalDeviceProperties2(pd, &p2);
	return (sp.supportedStages & stage) == stage && (sp.supportedOperations & ops) == ops;
}

render_count_mode render_count_mode_of(VkPhysicalDevice pd)
{
	VkSubgroupFeatureFlags ballot = VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_BALLOT_BIT;
	if (env_is_one("TASLAB_COUNT_ATOMICS") || !render_subgroup_has(pd, VK_SHADER_STAGE_FRAGMENT_BIT, ballot))
		return RENDER_COUNT_ATOMIC;
	VkPhysicalDeviceDriverProperties dp = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
	VkPhysicalDeviceProperties2 p2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, .pNext = &dp};
	vkGetPhysicalDeviceProperties2(pd, &p2);
	/* llvmpipe shades whole 4x4 blocks with the uncovered lanes masked off: no helper invocations to leave out */
	return dp.driverID == VK_DRIVER_ID_MESA_LLVMPIPE ? RENDER_COUNT_SUBGROUP_NO_HELPERS : RENDER_COUNT_SUBGROUP;
}

bool render_compute_ballot(VkPhysicalDevice pd)
{
	VkSubgroupFeatureFlags ballot = VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_BALLOT_BIT;
	return !env_is_one("TASLAB_COUNT_ATOMICS") && render_subgroup_has(pd, VK_SHADER_STAGE_COMPUTE_BIT, ballot);
}

VkResult render_make_graphics(render *r, const render_pipe_desc *pd, render_pipeline *out)
{
	const uint32_t *vs = pd->vs ? pd->vs : pd->fullscreen ? fullscreen_vert : scene_vert, *fs = pd->fs;
	size_t vs_size = pd->vs ? pd->vs_size : pd->fullscreen ? sizeof fullscreen_vert : sizeof scene_vert;
	size_t fs_size = pd->fs_size;
	/* 0 to 4 colour attachments: 4 is every Vulkan device's maxColorAttachments at least; more is a caller's error,
	 * refused rather than cut to four (the shader would write attachments the pass does not have) */
	if (pd->color < 0 || pd->color > 4)
		return VK_ERROR_INITIALIZATION_FAILED;
	VkShaderModule vm = VK_NULL_HANDLE, fm = VK_NULL_HANDLE;
	VkResult res = vkdev_shader_module(r->dev, vs, vs_size, &vm);
	if (!res && fs)
		res = vkdev_shader_module(r->dev, fs, fs_size, &fm);
	if (res)
		goto done;
	VkPushConstantRange pcr = {VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(gpu_push)};
	VkDescriptorSetLayout sets[2] = {r->scene_set_layout, pd->method_set};
	VkPipelineLayoutCreateInfo li = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO,
		.setLayoutCount = pd->method_set ? 2u : 1u,
		.pSetLayouts = sets,
		.pushConstantRangeCount = 1,
		.pPushConstantRanges = &pcr,
	};
	if ((res = vkCreatePipelineLayout(r->dev->device, &li, NULL, &out->layout)))
		goto done;
	render_spec spec_data;
	VkSpecializationInfo spec;
	render_specialization(r, pd->fs_alpha_blend, &spec_data, &spec);
	VkPipelineShaderStageCreateInfo stages[2] = {
		{.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_VERTEX_BIT,
		 .module = vm, .pName = "main"},
		{.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_FRAGMENT_BIT,
		 .module = fm, .pName = "main", .pSpecializationInfo = &spec},
	};
	VkVertexInputBindingDescription bind = {0, sizeof(scene_vertex), VK_VERTEX_INPUT_RATE_VERTEX};
	const VkVertexInputAttributeDescription all_attrs[4] = {
		{0, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(scene_vertex, position)},
		{1, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(scene_vertex, normal)},
		{2, 0, VK_FORMAT_R32G32_SFLOAT, offsetof(scene_vertex, uv)},
		{3, 0, VK_FORMAT_R32G32B32A32_SFLOAT, offsetof(scene_vertex, tangent)},
	};
	VkVertexInputAttributeDescription attrs[4];
	uint32_t nattr = 0;
	for (int i = 0; i < 4; i++)
		if (pd->attributes & (1u << i))
			attrs[nattr++] = all_attrs[i];
	VkPipelineVertexInputStateCreateInfo vi = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO,
		.pVertexBindingDescriptions = &bind,
		.vertexBindingDescriptionCount = pd->fullscreen || !nattr ? 0u : 1u,
		.vertexAttributeDescriptionCount = pd->fullscreen ? 0u : nattr,
		.pVertexAttributeDescriptions = attrs,
	};
	VkPipelineInputAssemblyStateCreateInfo ia = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO,
		.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST,
	};
	VkPipelineViewportStateCreateInfo vps = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO, .viewportCount = 1, .scissorCount = 1};
	VkPipelineRasterizationStateCreateInfo rs = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO,
		.polygonMode = VK_POLYGON_MODE_FILL,
		.cullMode = VK_CULL_MODE_NONE,
		.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE,
		.depthBiasEnable = pd->bias ? VK_TRUE : VK_FALSE,
		.depthBiasConstantFactor = 1.25f,
		.depthBiasSlopeFactor = 1.75f,
		.lineWidth = 1.0f,
	};
	VkPipelineMultisampleStateCreateInfo ms = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO,
		.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT,
	};
	VkPipelineDepthStencilStateCreateInfo ds = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO,
		.depthTestEnable = pd->no_depth_test ? VK_FALSE : VK_TRUE,
		.depthWriteEnable = pd->depth_write ? VK_TRUE : VK_FALSE,
		.depthCompareOp = pd->depth_op,
		.stencilTestEnable = pd->stencil >= RENDER_STENCIL_WRITE_ONE ? VK_TRUE : VK_FALSE,
	};
	/* Stencil: a decision pass writes 1 where its fragment shader does not discard; shading passes test it. */
	VkStencilOpState so = {.failOp = VK_STENCIL_OP_KEEP, .passOp = VK_STENCIL_OP_KEEP, .depthFailOp = VK_STENCIL_OP_KEEP,
			       .compareOp = VK_COMPARE_OP_EQUAL, .compareMask = 0xFF, .writeMask = 0, .reference = 1};
	if (pd->stencil == RENDER_STENCIL_WRITE_ONE)
		so.compareOp = VK_COMPARE_OP_ALWAYS, so.passOp = VK_STENCIL_OP_REPLACE, so.writeMask = 0xFF;
	else if (pd->stencil == RENDER_STENCIL_EQUAL_ZERO)
		so.reference = 0;
	ds.front = ds.back = so;
	/* Blending: "over" for colour; coverage alpha accumulates as a + (1 - a) * dst. */
	VkPipelineColorBlendAttachmentState cba = {
		.blendEnable = pd->blend ? VK_TRUE : VK_FALSE,
		.srcColorBlendFactor = VK_BLEND_FACTOR_SRC_ALPHA,
		.dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA,
		.colorBlendOp = VK_BLEND_OP_ADD,
		.srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE,
		.dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA,
		.alphaBlendOp = VK_BLEND_OP_ADD,
		.colorWriteMask = 0xF,
	};
	/* pd->color attachments (0 to 4), one blend state; the second of color2_format where set */
	uint32_t ncolor = (uint32_t)pd->color;
	VkPipelineColorBlendAttachmentState cbas[4] = {cba, cba, cba, cba};
	VkPipelineColorBlendStateCreateInfo cb = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO,
		.attachmentCount = ncolor,
		.pAttachments = cbas,
	};
	/* cull mode and front face per draw (render_set_facing): single-sided materials cull, mirrored objects' front
	 * faces are clockwise (glTF 2.0 §3.7.2.1); both dynamic states are core in Vulkan 1.3, which vkdev requires */
	VkDynamicState dyn[4] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR, VK_DYNAMIC_STATE_CULL_MODE,
				 VK_DYNAMIC_STATE_FRONT_FACE};
	VkPipelineDynamicStateCreateInfo dy = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO,
		.dynamicStateCount = pd->bias || pd->fullscreen ? 2u : 4u,
		.pDynamicStates = dyn,
	};
	VkFormat cfmt = pd->color_format ? pd->color_format : VK_FORMAT_R16G16B16A16_SFLOAT;
	VkFormat cfmts[4] = {cfmt, pd->color2_format ? pd->color2_format : cfmt, cfmt, cfmt};
	VkPipelineRenderingCreateInfo pr = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO,
		.viewMask = pd->view_mask,
		.colorAttachmentCount = ncolor,
		.pColorAttachmentFormats = cfmts,
		.depthAttachmentFormat = pd->depth_format ? pd->depth_format : RENDER_DEPTH_FORMAT,
		.stencilAttachmentFormat = pd->stencil ? RENDER_DEPTH_FORMAT : VK_FORMAT_UNDEFINED,
	};
	VkGraphicsPipelineCreateInfo gi = {
		.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO,
		.pNext = &pr,
		.stageCount = fs ? 2u : 1u,
		.pStages = stages,
		.pVertexInputState = &vi,
		.pInputAssemblyState = &ia,
		.pViewportState = &vps,
		.pRasterizationState = &rs,
		.pMultisampleState = &ms,
		.pDepthStencilState = &ds,
		.pColorBlendState = &cb,
		.pDynamicState = &dy,
		.layout = out->layout,
	};
	res = vkCreateGraphicsPipelines(r->dev->device, VK_NULL_HANDLE, 1, &gi, NULL, &out->pipeline);
done:
	if (vm)
		vkDestroyShaderModule(r->dev->device, vm, NULL);
	if (fm)
		vkDestroyShaderModule(r->dev->device, fm, NULL);
	return res;
}

VkResult render_make_shade_pipeline(render *r, const uint32_t *fs, size_t fs_size, VkDescriptorSetLayout method_set,
				    render_pipeline *out)
{
	render_pipe_desc shade = {.attributes = RENDER_ATTR_ALL, .color = 1,
			   .depth_op = VK_COMPARE_OP_EQUAL, .fs = fs, .fs_size = fs_size, .method_set = method_set};
	return render_make_graphics(r, &shade, out);
}

void render_pipeline_destroy(render *r, render_pipeline *p)
{
	if (p->pipeline)
		vkDestroyPipeline(r->dev->device, p->pipeline, NULL);
	if (p->layout)
		vkDestroyPipelineLayout(r->dev->device, p->layout, NULL);
	p->pipeline = VK_NULL_HANDLE;
	p->layout = VK_NULL_HANDLE;
}

int render_compile(const render *r, const char *template_path, shc_stage stage, uint32_t **spv, size_t *spv_size,
		   char *err, size_t err_size)
{
	return render_compile_defs(r, template_path, NULL, stage, spv, spv_size, err, err_size);
}

int render_compile_defs(const render *r, const char *template_path, const char *defines, shc_stage stage,
			uint32_t **spv, size_t *spv_size, char *err, size_t err_size)
{
	char *src = NULL, *defs = NULL;
	/* the view's extensions (buffer references for its LUTs) go right after #version with the defines */
	const char *ext = colour_device_extensions(r->colour_dev);
	if (*ext) {
		size_t n = strlen(ext) + (defines ? strlen(defines) : 0) + 1;
		if (!(defs = malloc(n)))
			return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		snprintf(defs, n, "%s%s", ext, defines ? defines : "");
		defines = defs;
	}
	int rc = shader_assemble_defs(template_path, colour_device_glsl(r->colour_dev), defines, &src, err, err_size);
	free(defs);
	if (rc)
		return rc;
	if (shc_compile(src, stage, spv, spv_size, err, err_size))
		rc = TL_ERR_ARG; /* a view transform whose GLSL does not compile (the message says why) */
	free(src);
	return rc;
}

VkResult render_make_compute(render *r, const uint32_t *spv, size_t spv_size, VkPipelineLayout layout, VkPipeline *out)
{
	render_spec spec_data;
	VkSpecializationInfo spec;
	render_specialization(r, 0, &spec_data, &spec);
	VkShaderModule m;
	VkResult res = vkdev_shader_module(r->dev, spv, spv_size, &m);
	if (res)
		return res;
	VkComputePipelineCreateInfo ci = {
		.sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
		.stage = {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_COMPUTE_BIT,
			  .module = m, .pName = "main", .pSpecializationInfo = &spec},
		.layout = layout,
	};
	res = vkCreateComputePipelines(r->dev->device, VK_NULL_HANDLE, 1, &ci, NULL, out);
	vkDestroyShaderModule(r->dev->device, m, NULL);
	return res;
}

int render_make_template_pipeline(render *r, const char *template_path, const char *defines,
				  VkDescriptorSetLayout method_set, int stencil, int color, int fullscreen, render_pipeline *out,
				  char *err, size_t err_size)
{
	uint32_t *spv = NULL;
	size_t spv_size = 0;
	int rc = render_compile_defs(r, template_path, defines, SHC_STAGE_FRAGMENT, &spv, &spv_size, err, err_size);
	if (rc)
		return rc;
	render_pipe_desc pd = {.attributes = RENDER_ATTR_ALL, .color = color, .depth_op = VK_COMPARE_OP_EQUAL,
			       .fs = spv, .fs_size = spv_size, .method_set = method_set, .stencil = stencil,
			       .fullscreen = fullscreen, .no_depth_test = fullscreen};
	VkResult res = render_make_graphics(r, &pd, out);
	free(spv);
	return res ? render_vk_error(err, err_size, template_path, res) : TL_OK;
}

int render_compute_defs(render *r, const char *template_path, const char *defines, VkPipelineLayout layout,
			VkPipeline *out, char *err, size_t err_size)
{
	uint32_t *spv = NULL;
	size_t n = 0;
	int rc = render_compile_defs(r, template_path, defines, SHC_STAGE_COMPUTE, &spv, &n, err, err_size);
	if (rc)
		return rc;
	VkResult res = render_make_compute(r, spv, n, layout, out);
	free(spv);
	return res ? render_vk_error(err, err_size, template_path, res) : TL_OK;
}
