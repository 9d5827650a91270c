/* taslab.c — entry point: dispatch table of commands (one file per command, cmd_*.c). */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "taslab/version.h"

static const cli_command *const commands[] = {
	&cli_cmd_render,
	&cli_cmd_pair,
	&cli_cmd_metrics,
	&cli_cmd_analyze,
	&cli_cmd_study,
	&cli_cmd_clip,
	&cli_cmd_tonemap,
	&cli_cmd_scenes,
	&cli_cmd_devices,
};

static void usage(FILE *out)
{
	fprintf(out, "usage: taslab <command> [options]   (taslab <command> --help for details)\n\n"
		     "taslab %s — offline evaluation harness for temporally adaptive shading\n\ncommands:\n",
		TASLAB_VERSION_STRING);
	for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
		fprintf(out, "  %-10s %s\n", commands[i]->name, commands[i]->summary);
	fprintf(out, "\n  --version  print the version\n  --help     this text\n");
}

int main(int argc, char **argv)
{
	if (argc < 2) {
		usage(stderr);
		return CLI_EXIT_USAGE;
	}
	if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
		usage(stdout);
		return CLI_EXIT_OK;
	}
	if (!strcmp(argv[1], "--version")) {
		printf("taslab %s\n", TASLAB_VERSION_STRING);
		return CLI_EXIT_OK;
	}
	for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
		if (!strcmp(argv[1], commands[i]->name))
			return commands[i]->run(argc - 1, argv + 1);
	fprintf(stderr, "taslab: unknown command '%s' (run 'taslab --help' for the list)\n", argv[1]);
	return CLI_EXIT_USAGE;
}
