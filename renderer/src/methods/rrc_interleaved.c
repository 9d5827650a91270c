/* rrc_interleaved.c — `rrc-interleaved/N`: the reverse reprojection cache with interleaved refresh ([S] sec. 3.4,
 * BASELINES.md A2): N = a b (2 = 2x1, 4 = 2x2, 8 = 4x2), k = t mod N, and the pixels with (x mod a, y mod b) =
 * (k mod a, floor(k / a)) are refreshed ("for a static scene and camera, interleaving n such images leads to an
 * accurate high resolution image"); misses are shaded too. `--group` applies the pattern to 2x2 or 4x2 blocks.
 * Shaded through the compacted sample path (vreuse.h): a per-pixel pattern defeats stencil rejection on lavapipe. */
#include "vbuf_family.h" /* VBUF_TRUTH_OPTIONS */
#include "vreuse.h"

#include <stddef.h>

typedef struct rrc_interleaved_options {
	uint32_t period;
	uint32_t group;
	bool truth;
	float truth_t;
} rrc_interleaved_options;

static const uint32_t periods[] = {1, 2, 4, 8, 0};
static const char *const groups[] = {"1", "2x2", "4x2", NULL};

static const method_option rrc_interleaved_option_table[] = {
	{.name = "period", .arg = "N", .help = "the refreshed pixel of each 2x1 (N 2), 2x2 (4) or 4x2 (8) cell cycles "
					       "every N frames (1 shades all)",
	 .type = METHOD_OPT_UINT, .offset = offsetof(rrc_interleaved_options, period), .def = 4, .min = 1, .max = 8,
	 .allowed = periods, .variant = '/', .variant_required = true},
	{.name = "group", .arg = "G", .help = "the pattern's unit: 1 (a pixel), 2x2 or 4x2 blocks",
	 .type = METHOD_OPT_CHOICE, .offset = offsetof(rrc_interleaved_options, group), .def = 0, .choices = groups},
	VBUF_TRUTH_OPTIONS(rrc_interleaved_options),
};

static int rrc_interleaved_init(render *r, char *err, size_t err_size)
{
	const rrc_interleaved_options *o = (const rrc_interleaved_options *)r->config.values.bytes;
	vreuse_variant v = {.mode = VREUSE_RRC_INTERLEAVED, .period = o->period, .group = o->group, .truth = o->truth,
			    .truth_t = o->truth_t};
	return vreuse_init(r, &v, err, err_size);
}

const render_method render_method_rrc_interleaved = {
	.info = {.name = "rrc-interleaved",
		 .summary = "reverse reprojection cache, pixels refreshed in an interleaved N-frame pattern ([S] 3.4)",
		 .available = true,
		 .family = "reprojection",
		 .baseline = "vref",
		 .options = rrc_interleaved_option_table,
		 .option_count = sizeof rrc_interleaved_option_table / sizeof rrc_interleaved_option_table[0],
		 .options_size = sizeof(rrc_interleaved_options)},
	.pass_names = vreuse_rrc_passes,
	.pass_count = sizeof vreuse_rrc_passes / sizeof vreuse_rrc_passes[0],
	.init = rrc_interleaved_init,
	VREUSE_FRAME_OPS,
};
