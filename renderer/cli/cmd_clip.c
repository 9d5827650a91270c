/* cmd_clip.c — `taslab clip RUN --out clip.webm`: a run's PNG frames as a bit-exact lossless clip. */
#include <string.h>

#include "cli.h"
#include "taslab/clip.h"

static void clip_usage(FILE *out)
{
	fprintf(out, "usage: taslab clip RUN --out CLIP.webm\n\n"
		     "Encodes RUN/frames/NNNNNN.png at the run's fps as lossless VP9 with RGB (gbrp) pixels in WebM:\n"
		     "decoded frames equal the PNG frames exactly (plays back bit-exact in Chromium). The clip is\n"
		     "written under a temporary name and renamed at the end; on any error no clip is left.\n");
}

static int clip_run(int argc, char **argv)
{
	const char *run = NULL, *out = NULL;
	for (int i = 1; i < argc; i++) {
		if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
			clip_usage(stdout);
			return CLI_EXIT_OK;
		} else if (!strcmp(argv[i], "--out") && i + 1 < argc) {
			out = argv[++i];
		} else if (argv[i][0] != '-' && !run) {
			run = argv[i];
		} else {
			fprintf(stderr, "taslab clip: unexpected argument '%s' (see 'taslab clip --help')\n", argv[i]);
			return CLI_EXIT_USAGE;
		}
	}
	if (!run || !out) {
		fprintf(stderr, "taslab clip: need a run folder and --out CLIP.webm (see 'taslab clip --help')\n");
		return CLI_EXIT_USAGE;
	}
	char err[1024];
	uint32_t n;
	if (clip_encode_run(run, out, &n, err, sizeof err)) {
		fprintf(stderr, "taslab clip: %s\n", err);
		return CLI_EXIT_FAILURE;
	}
	fprintf(stderr, "taslab: wrote %u frames to %s (lossless VP9, gbrp, WebM)\n", n, out);
	return CLI_EXIT_OK;
}

const cli_command cli_cmd_clip = {"clip", "encode a run's frames as a bit-exact lossless VP9/WebM clip", clip_run,
				  clip_usage};
