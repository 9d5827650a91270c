/* rrc_random.c — `rrc-random/N`: the reverse reprojection cache with random refresh ([S] sec. 3.4, BASELINES.md A2):
 * each pixel (or each 2x2 / 4x2 group, `--group`; [S] recommends "the same ID to each 2 x 2 or larger quad") has an
 * id = PCG(x + W y) mod N and is refreshed at frame t iff (t + id) mod N = 0; misses are shaded too. The pattern
 * "gives high-frequency noise, which is usually less objectionable" than tiles' seams. A per-pixel pattern defeats
 * stencil rejection on lavapipe (TAS-METHODS section 8), so the marked set (refresh and misses) is compacted and
 * shaded on the sample path (vreuse.h). */
#include "vbuf_family.h" /* VBUF_TRUTH_OPTIONS */
#include "vreuse.h"

#include <stddef.h>

typedef struct rrc_random_options {
	uint32_t period;
	uint32_t group;
	bool truth;
	float truth_t;
} rrc_random_options;

static const uint32_t periods[] = {1, 2, 4, 8, 0};
static const char *const groups[] = {"1", "2x2", "4x2", NULL};

static const method_option rrc_random_option_table[] = {
	{.name = "period", .arg = "N", .help = "each pixel refreshed once every N frames, at a random phase (1 shades all)",
	 .type = METHOD_OPT_UINT, .offset = offsetof(rrc_random_options, period), .def = 4, .min = 1, .max = 8,
	 .allowed = periods, .variant = '/', .variant_required = true},
	{.name = "group", .arg = "G", .help = "pixels sharing one refresh phase: 1 (each pixel), 2x2 or 4x2 blocks",
	 .type = METHOD_OPT_CHOICE, .offset = offsetof(rrc_random_options, group), .def = 0, .choices = groups},
	VBUF_TRUTH_OPTIONS(rrc_random_options),
};

static int rrc_random_init(render *r, char *err, size_t err_size)
{
	const rrc_random_options *o = (const rrc_random_options *)r->config.values.bytes;
	vreuse_variant v = {.mode = VREUSE_RRC_RANDOM, .period = o->period, .group = o->group, .truth = o->truth,
			    .truth_t = o->truth_t};
	return vreuse_init(r, &v, err, err_size);
}

const render_method render_method_rrc_random = {
	.info = {.name = "rrc-random",
		 .summary = "reverse reprojection cache, each pixel refreshed every N frames at a random phase ([S] 3.4)",
		 .available = true,
		 .family = "reprojection",
		 .baseline = "vref",
		 .options = rrc_random_option_table,
		 .option_count = sizeof rrc_random_option_table / sizeof rrc_random_option_table[0],
		 .options_size = sizeof(rrc_random_options)},
	.pass_names = vreuse_rrc_passes,
	.pass_count = sizeof vreuse_rrc_passes / sizeof vreuse_rrc_passes[0],
	.init = rrc_random_init,
	VREUSE_FRAME_OPS,
};
