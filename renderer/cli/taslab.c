/* taslab.c — the entry point; everything else is in the command table (commands.c) and the parser. */
#include "cli.h"

int main(int argc, char **argv) { return cli_main(argc, argv); }
