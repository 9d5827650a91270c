/* rrc.c — `rrc`: reverse reprojection cache with 16x16 tiles refreshed round-robin every N frames (DESIGN
 * section 4; paper sec. 5.1 "16x16 pixel tiles with a constant refresh rate"; Nehab et al. 2007 via the
 * survey, papers/002 sec. 3.4). A pixel is shaded when it misses the cache (not visible in the previous
 * frame: object or 2% view-distance mismatch), on the first frame, or when its tile is due:
 * (t + tile) mod N == 0; otherwise it shows the previous frame's value, resampled at the reprojected position
 * (bilinear by default, as the paper did; nearest for the ablation). TAS-METHODS section 2.
 * --payload shadow|diffuse (rrc-shadow/N, rrc-diffuse/N; [S] sec. 4.1 and 5.1, BASELINES A5): the cache keeps part
 * of the shading, the per-light shadow factors or the diffuse term, refreshed as above; the rest is shaded every frame
 * (reproj_cache.c, "compose"). */
#include "reproj_cache.h"

#include <stddef.h>

typedef struct rrc_options {
	uint32_t period;   /* N */
	uint32_t resample; /* 0 bilinear, 1 nearest */
	bool truth;
	float truth_threshold;
	uint32_t payload; /* REPROJ_PAYLOAD_* */
} rrc_options;

static const char *const resample_names[] = {"bilinear", "nearest", NULL};
static const char *const payload_names[] = {"colour", "shadow", "diffuse", NULL}; /* REPROJ_PAYLOAD_* */
static const uint32_t periods[] = {1, 2, 4, 8, 0};

static const method_option rrc_option_table[] = {
	{.name = "period", .arg = "N", .help = "refresh every 16x16 tile every N frames (1 equals ref)",
	 .type = METHOD_OPT_UINT, .offset = offsetof(rrc_options, period), .def = 4, .min = 1, .max = 8, .allowed = periods,
	 .variant = '/', .variant_required = true},
	{.name = "resample", .arg = "MODE", .help = "cache lookup: bilinear (per-tap validity) or nearest",
	 .type = METHOD_OPT_CHOICE, .offset = offsetof(rrc_options, resample), .def = 0, .choices = resample_names},
	{.name = "truth", .help = "also shade the reused samples and count those more than T from the truth "
				  "(late_samples; T = --truth-threshold)",
	 .type = METHOD_OPT_BOOL, .offset = offsetof(rrc_options, truth)},
	{.name = "truth-threshold", .arg = "T", .help = "with --truth: the T of late_samples, in code values",
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(rrc_options, truth_threshold), .def = 8, .min = 0, .max = 255},
	{.name = "payload", .arg = "P", .help = "what the cache keeps ([S] 4.1): colour (the shading), shadow (the shadow "
						"factors of lights 0-7) or diffuse (the diffuse term); the rest is shaded every frame",
	 .type = METHOD_OPT_CHOICE, .offset = offsetof(rrc_options, payload), .def = 0, .choices = payload_names,
	 .variant = '-'},
};

/* "shade": with --payload the payload's evaluation, "compose" the shading completed with it (empty without) */
static const char *const rrc_passes[] = {"shadow", "depth", "reproject", "filter", "mark", "shade", "compose", "truth",
					 "blend", "display", "readback"};

static int rrc_check(const void *options, char *err, size_t err_size)
{
	const rrc_options *o = options;
	if (o->truth && o->payload != REPROJ_PAYLOAD_COLOUR)
		return tl_error(err, err_size, TL_ERR_ARG,
				"rrc: --truth counts late colours, and with --payload %s the cache keeps no colour: drop one of them",
				payload_names[o->payload]);
	return TL_OK;
}

static int rrc_init(render *r, char *err, size_t err_size)
{
	const rrc_options *o = (const rrc_options *)r->config.values.bytes;
	reproj_variant v = {.nearest = o->resample == 1, .truth = o->truth, .period = o->period,
			    .threshold = o->truth_threshold, .payload = o->payload};
	return reproj_init(r, &v, err, err_size);
}

const render_method render_method_rrc = {
	.info = {.name = "rrc",
		 .summary = "reverse reprojection cache, 16x16 tiles refreshed round-robin every N frames",
		 .available = true,
		 .family = "reprojection",
		 .options = rrc_option_table,
		 .option_count = sizeof rrc_option_table / sizeof rrc_option_table[0],
		 .decisions = true,
		 .options_size = sizeof(rrc_options),
		 .check = rrc_check},
	.pass_names = rrc_passes,
	.pass_count = sizeof rrc_passes / sizeof rrc_passes[0],
	.state_ring = 2,
	.init = rrc_init,
	.prepare = reproj_prepare,
	.record = reproj_record,
	.collect = reproj_collect,
	.decisions = reproj_decisions,
	.finish = reproj_finish,
};
