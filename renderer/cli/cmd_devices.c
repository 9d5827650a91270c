/* cmd_devices.c — `taslab devices`: lists Vulkan devices usable with --device. */
#include <string.h>

#include "cli.h"
#include "taslab/vkdev.h"

static int devices_main(void *opts, cli_ctx *ctx)
{
	(void)opts;
	char list[2048];
	VkResult r = vkdev_list(list, sizeof list);
	if (r)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_VULKAN, "cannot enumerate Vulkan devices (%s); run scripts/setup",
				vkdev_result_string(r));
	fputs(list, stdout);
	return TL_OK;
}

const cli_command cli_cmd_devices = {
	.name = "devices",
	.summary = "list Vulkan devices",
	.synopsis = "taslab devices",
	.description = "Lists the Vulkan devices; pass an index or a name substring to 'taslab render --device', or\n"
		       "'lavapipe' for the CPU device.",
	.run = devices_main,
};
