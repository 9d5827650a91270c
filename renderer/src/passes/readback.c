/* readback.c — copies the HDR and display targets to host-visible buffers (padded row pitch) and repacks
 * them for the run writer. */
#include "passes.h"

#include <string.h>

void render_pass_readback(render *r, VkCommandBuffer cmd)
{
	vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL,
			    VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			    VK_ACCESS_2_SHADER_STORAGE_READ_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
			    VK_ACCESS_2_TRANSFER_READ_BIT);
	vkdev_barrier_image(cmd, &r->display, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL,
			    VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			    VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
			    VK_ACCESS_2_TRANSFER_READ_BIT);
	/* Rows are copied with a padded pitch (bufferRowLength) and repacked on the CPU. */
	VkBufferImageCopy hr = {
		.bufferRowLength = r->row_pitch_hdr_B / 8,
		.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
		.imageExtent = {r->desc.width, r->desc.height, 1},
	};
	VkBufferImageCopy dr = hr;
	dr.bufferRowLength = r->row_pitch_display_B / 4;
	vkCmdCopyImageToBuffer(cmd, r->hdr.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, r->readback_hdr.buffer, 1, &hr);
	vkCmdCopyImageToBuffer(cmd, r->display.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, r->readback_display.buffer, 1, &dr);
	render_barrier(cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
		       VK_ACCESS_2_HOST_READ_BIT);
}

int64_t render_readback_finish(render *r)
{
	uint32_t w = r->desc.width, h = r->desc.height;
	for (uint32_t y = 0; y < h; y++) {
		memcpy(r->hdr_packed + (size_t)y * w * 4, (uint8_t *)r->readback_hdr.mapped + (size_t)y * r->row_pitch_hdr_B,
		       (size_t)w * 8);
		memcpy(r->display_packed + (size_t)y * w * 4,
		       (uint8_t *)r->readback_display.mapped + (size_t)y * r->row_pitch_display_B, (size_t)w * 4);
	}
	int64_t visible = 0;
	for (size_t i = 0; i < (size_t)w * h; i++)
		visible += r->hdr_packed[i * 4 + 3] != 0; /* half-float coverage: 0 or 1.0 */
	return visible;
}
