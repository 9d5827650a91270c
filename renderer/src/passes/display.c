/* display.c — the display pass: the OpenColorIO view transform (DESIGN section 3), compiled into
 * common/display.comp.in at run time, turns the HDR target into display-referred RGBA8. */
#include "passes.h"

#include <stdlib.h>

void render_pass_display(render *r, VkCommandBuffer cmd)
{
	vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
			    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
			    VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			    VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
	vkdev_barrier_image(cmd, &r->display, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
			    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COPY_BIT, 0,
			    VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, r->display_pipe.pipeline);
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, r->display_pipe.layout, 0, 1, &r->display_set, 0, NULL);
	vkCmdDispatch(cmd, (r->desc.width + 7) / 8, (r->desc.height + 7) / 8, 1);
}

/* The display pipeline: common/display.comp.in with the OpenColorIO function of the active view transform. */
int render_display_init(render *r, char *err, size_t err_size)
{
	uint32_t *spv = NULL;
	size_t spv_size = 0;
	int rc = render_compile(r, "common/display.comp.in", SHC_STAGE_COMPUTE, &spv, &spv_size, err, err_size);
	if (rc)
		return rc;
	VkPipelineLayoutCreateInfo li = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO,
		.setLayoutCount = 1,
		.pSetLayouts = &r->display_set_layout,
	};
	VkResult res = vkCreatePipelineLayout(r->dev->device, &li, NULL, &r->display_pipe.layout);
	if (!res)
		res = render_make_compute(r, spv, spv_size, r->display_pipe.layout, &r->display_pipe.pipeline);
	free(spv);
	return res ? render_vk_error(err, err_size, "display pipeline", res) : TL_OK;
}
