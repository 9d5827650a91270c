/* sau.c — `sau`: the shading atlas with uniform temporal upsampling (DESIGN section 4; [TAS] sec. 5.1: "The lifespan
 * of cache entries is also constant, but every cache entry has an individual remaining time to live depending on
 * when it became visible"; TAS-METHODS section 5): a block is shaded when (t - t_alloc) mod N = 0, its allocation
 * frame included; a reallocation starts it over. sau/1 is sa. */
#include "atlas.h"

#include <stddef.h>

typedef struct sau_options {
	uint32_t period;
	float scale, density;
	uint32_t lmax;
	bool lod0;
	bool truth;
	float truth_threshold;
} sau_options;

static const uint32_t periods[] = {1, 2, 4, 8, 0};

static const method_option sau_option_table[] = {
	{.name = "period", .arg = "N", .help = "shade every block every N frames from its allocation (1 is sa)",
	 .type = METHOD_OPT_UINT, .offset = offsetof(sau_options, period), .def = 4, .min = 1, .max = 8, .allowed = periods,
	 .variant = '/', .variant_required = true},
	ATLAS_OPTIONS(sau_options),
	{.name = "truth", .help = "also shade the reused blocks and count texels more than T from the truth "
				  "(late_samples; T = --truth-threshold)",
	 .type = METHOD_OPT_BOOL, .offset = offsetof(sau_options, truth)},
	{.name = "truth-threshold", .arg = "T", .help = "with --truth: the T of late_samples, in code values",
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(sau_options, truth_threshold), .def = 8, .min = 0, .max = 255},
};

static int sau_init(render *r, char *err, size_t err_size)
{
	const sau_options *o = (const sau_options *)r->config.values.bytes;
	atlas_variant v = {.kind = ATLAS_SAU, .period = o->period, .scale = o->scale, .density = o->density,
			   .lmax = o->lmax, .lod0 = o->lod0, .truth = o->truth, .threshold = o->truth_threshold};
	return atlas_init(r, &v, err, err_size);
}

const render_method render_method_sau = {
	.info = {.name = "sau",
		 .summary = "shading atlas with uniform temporal upsampling: each block reshaded every N frames (sec. 5.1)",
		 .available = true,
		 .family = "atlas",
		 .baseline = "sa", /* paper Table 1 reduces the atlas methods against SA */
		 .options = sau_option_table,
		 .option_count = sizeof sau_option_table / sizeof sau_option_table[0],
		 .options_size = sizeof(sau_options)},
	.init = sau_init,
	ATLAS_FRAME_OPS,
};
