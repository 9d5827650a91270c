/* cmd_clip.c — `taslab clip RUN --out clip.webm`: a run's PNG frames as a bit-exact lossless clip. */
#include <string.h>
#include <strings.h>

#include "commands.h"
#include "taslab/clip.h"
#include "taslab/tl_fs.h"

static const cli_opt clip_options[] = {
	{.name = "out", .arg = "CLIP.webm",
	 .help = "the clip to write (a temporary name until it is complete)",
	 .type = CLI_STRING, .offset = offsetof(clip_opts, out)},
	{.name = "eye", .arg = "E",
	 .help = "stereo runs: L, R or sbs (default: sbs, the eyes side by side)",
	 .type = CLI_STRING, .offset = offsetof(clip_opts, eye)},
	{0},
};

static int clip_validate(void *opts, cli_ctx *ctx)
{
	clip_opts *o = opts;
	if (!o->out)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--out CLIP.webm is required (see 'taslab clip --help')");
	/* A WebM under another name (a frame's .png of another run, a manifest) is a careless --out, not a clip. */
	size_t n = strlen(o->out);
	if (n < 6 || strcasecmp(o->out + n - 5, ".webm"))
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--out %s: the clip is a WebM file; give a name ending in "
				".webm", o->out);
	return TL_OK;
}

static int clip_main(void *opts, cli_ctx *ctx)
{
	clip_opts *o = opts;
	const char *run = ctx->pos[0];
	/* Never write into the run itself: the clip would replace a frame or the run's files. */
	if (tl_path_inside(o->out, run))
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG,
				"--out %s lies inside the run folder %s, whose files it could replace (write the clip elsewhere)",
				o->out, run);
	uint32_t n;
	int rc = clip_encode_run_view(run, o->eye, o->out, &n, ctx->err, sizeof ctx->err);
	if (!rc)
		fprintf(stderr, "taslab: wrote %u frames to %s (lossless VP9, gbrp, WebM)\n", n, o->out);
	return rc;
}

const cli_command cli_cmd_clip = {
	.name = "clip",
	.summary = "encode a run's frames as a bit-exact lossless VP9/WebM clip",
	.synopsis = "taslab clip RUN --out CLIP.webm",
	.description = "Encodes RUN/frames/NNNNNN.png (stereo runs: RUN/sbs/, or one eye with --eye) at the run's fps as lossless VP9 with RGB (gbrp) pixels in WebM:\n"
		       "decoded frames equal the PNG frames exactly (plays back bit-exact in Chromium). The frames must be\n"
		       "exactly those of the run's manifest. The clip is written under a temporary name and renamed at the\n"
		       "end; on any error no clip is left.",
	.options = clip_options,
	.opts_size = sizeof(clip_opts),
	.validate = clip_validate,
	.min_pos = 1,
	.max_pos = 1,
	.pos_help = "RUN (a run folder)",
	.run = clip_main,
};
