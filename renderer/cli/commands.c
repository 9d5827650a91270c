/* commands.c — the command table: the only list of taslab's commands (one file each, cmd_<name>.c). */
#include "cli.h"

extern const cli_command cli_cmd_render, cli_cmd_pair, cli_cmd_metrics, cli_cmd_analyze, cli_cmd_study, cli_cmd_clip,
	cli_cmd_tonemap, cli_cmd_scenes, cli_cmd_devices, cli_cmd_sweep, cli_cmd_report;

const cli_command *const cli_commands[] = {
	&cli_cmd_sweep, &cli_cmd_report, &cli_cmd_render, &cli_cmd_pair, &cli_cmd_metrics, &cli_cmd_analyze, &cli_cmd_study,
	&cli_cmd_clip,	 &cli_cmd_tonemap, &cli_cmd_scenes, &cli_cmd_devices, NULL,
};
