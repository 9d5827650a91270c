/* cmd_devices.c — `taslab devices`: lists Vulkan devices usable with --device. */
#include <string.h>

#include "cli.h"
#include "taslab/vkdev.h"

static void devices_usage(FILE *out)
{
	fprintf(out, "usage: taslab devices\n\nLists the Vulkan devices; pass an index or a name substring to\n"
		     "'taslab render --device', or 'lavapipe' for the CPU device.\n");
}

static int devices_run(int argc, char **argv)
{
	int st = cli_no_args(argc, argv, devices_usage);
	if (st >= 0)
		return st;
	char list[2048];
	VkResult r = vkdev_list(list, sizeof list);
	if (r) {
		fprintf(stderr, "taslab devices: cannot enumerate Vulkan devices (%s); run scripts/setup\n", vkdev_result_string(r));
		return CLI_EXIT_FAILURE;
	}
	fputs(list, stdout);
	return CLI_EXIT_OK;
}

const cli_command cli_cmd_devices = {"devices", "list Vulkan devices", devices_run, devices_usage};
