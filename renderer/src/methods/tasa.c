/* tasa.c — `tasa`: the temporally adaptive shading atlas, the TAS framework on atlas blocks (DESIGN section 4;
 * [TAS] sec. 6.2, five steps; TAS-METHODS section 6). A block is shaded when newly (re)allocated, in its second frame
 * ("shaded for two consecutive frames" to get a first difference), or when F * age > T: F the block's gradient
 * (code values per frame, the maximum over its texels of d / age at its last shading, sec. 6.2 "retaining the
 * maximum of all shading gradients across an entire RU") spread by the 2x2 image-space max over neighbouring
 * blocks. The oracle (`tasa-oracle`, sec. 7.1 and Fig. 5b) shades every block and keeps a block's old shading only
 * when all of its texels are within T of the truth. */
#include "atlas.h"

#include <stddef.h>

typedef struct tasa_options {
	float threshold;
	bool oracle;
	float scale, density;
	uint32_t lmax;
	bool lod0;
	bool truth, force_reshade;
} tasa_options;

static const method_option tasa_option_table[] = {
	{.name = "threshold", .arg = "T", .help = "reshade when the change predicted since the last shading exceeds T code "
						  "values (> 0; the oracle allows 0)",
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(tasa_options, threshold), .def = 8, .min = 0, .max = 255,
	 .variant = '@', .variant_required = true},
	{.name = "oracle", .help = "the ideal variant: shade every block, keep those whose texels are all within T of the truth",
	 .type = METHOD_OPT_BOOL, .offset = offsetof(tasa_options, oracle), .variant = '-'},
	ATLAS_OPTIONS(tasa_options),
	{.name = "truth", .help = "also shade the reused blocks and count texels more than T from the truth (late_samples)",
	 .type = METHOD_OPT_BOOL, .offset = offsetof(tasa_options, truth)},
	{.name = "force-reshade", .help = "debug: reshade every block through the TAS pipeline (overhead against sa)",
	 .type = METHOD_OPT_BOOL, .offset = offsetof(tasa_options, force_reshade)},
};

static int tasa_check(const void *options, char *err, size_t err_size)
{
	const tasa_options *o = options;
	if (!o->oracle && !(o->threshold > 0.0f))
		return tl_error(err, err_size, TL_ERR_ARG, "tasa needs a threshold T > 0 (only tasa-oracle allows T = 0)");
	if (o->oracle && o->force_reshade)
		return tl_error(err, err_size, TL_ERR_ARG, "--force-reshade does not apply to the oracle (it shades everything)");
	return TL_OK;
}

static int tasa_init(render *r, char *err, size_t err_size)
{
	const tasa_options *o = (const tasa_options *)r->config.values.bytes;
	atlas_variant v = {.kind = ATLAS_TASA, .oracle = o->oracle, .threshold = o->threshold, .scale = o->scale,
			   .density = o->density, .lmax = o->lmax, .lod0 = o->lod0, .truth = o->truth, .force = o->force_reshade};
	return atlas_init(r, &v, err, err_size);
}

const render_method render_method_tasa = {
	.info = {.name = "tasa",
		 .summary = "temporally adaptive shading atlas (paper sec. 6.2); tasa-oracle: its ideal variant",
		 .available = true,
		 .family = "atlas",
		 .baseline = "sa", /* paper Table 1 reduces the atlas methods against SA */
		 .options = tasa_option_table,
		 .option_count = sizeof tasa_option_table / sizeof tasa_option_table[0],
		 .options_size = sizeof(tasa_options),
		 .check = tasa_check},
	.init = tasa_init,
	ATLAS_FRAME_OPS,
};
