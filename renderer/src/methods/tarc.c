/* tarc.c — `tarc`: temporally adaptive reprojection caching, the TAS framework on per-pixel reuse units
 * (DESIGN section 4; paper secs. 6 and 6.1; TAS-METHODS section 3). Per pixel a double-buffered cache holds the
 * shown value, the age a (frames since the last shading), the gradient g (code values per frame) and a phase.
 * A pixel is reshaded when it is newly visible, in its second frame after that ("shaded for two consecutive
 * frames" to get a first difference, sec. 6 step 1), or when the spatially filtered gradient predicts a change
 * beyond T: F * a' > T, F the 8x8 max downsample then 9x9 max kernel of g (72x72 pixels, secs. 5.3, 6.1).
 * On reshading g = d(s, C') / a' (the long-range difference since the last shading, sec. 5.2), compared after
 * the display transform. The oracle variant (`tarc-oracle`, sec. 7.1 "ideal") shades every sample and reuses
 * C' exactly when it is within T of the truth: the greedy bound of reuse for this cache. */
#include "reproj_cache.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>

typedef struct tarc_options {
	float threshold;
	bool oracle;
	uint32_t max_age;
	uint32_t resample;
	bool truth;
	bool force_reshade;
} tarc_options;

static const char *const resample_names[] = {"bilinear", "nearest", NULL};

static const method_option tarc_option_table[] = {
	{.name = "threshold", .arg = "T", .help = "reshade when the change predicted since the last shading exceeds T code "
						  "values (> 0; the oracle allows 0)",
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(tarc_options, threshold), .def = 8, .min = 0, .max = 255,
	 .variant = '@', .variant_required = true},
	{.name = "oracle", .help = "the ideal variant: shade everything, reuse exactly what is within T of the truth",
	 .type = METHOD_OPT_BOOL, .offset = offsetof(tarc_options, oracle), .variant = '-'},
	{.name = "max-age", .arg = "K", .help = "also reshade at age K frames (0: no limit, the paper's choice)",
	 .type = METHOD_OPT_UINT, .offset = offsetof(tarc_options, max_age), .def = 0, .min = 0, .max = 65535},
	{.name = "resample", .arg = "MODE", .help = "cache lookup: bilinear (per-tap validity) or nearest",
	 .type = METHOD_OPT_CHOICE, .offset = offsetof(tarc_options, resample), .def = 0, .choices = resample_names},
	{.name = "truth", .help = "also shade the reused samples and count those more than T from the truth (late_samples)",
	 .type = METHOD_OPT_BOOL, .offset = offsetof(tarc_options, truth)},
	{.name = "force-reshade", .help = "debug: reshade every sample (measures the method's overhead against ref)",
	 .type = METHOD_OPT_BOOL, .offset = offsetof(tarc_options, force_reshade)},
};

static int tarc_check(const void *options, char *err, size_t err_size)
{
	const tarc_options *o = options;
	if (!o->oracle && !(o->threshold > 0.0f))
		return tl_error(err, err_size, TL_ERR_ARG, "tarc needs a threshold T > 0 (only tarc-oracle allows T = 0)");
	if (o->oracle && o->force_reshade)
		return tl_error(err, err_size, TL_ERR_ARG, "--force-reshade does not apply to the oracle (it shades everything)");
	return TL_OK;
}

static const char *const tarc_passes[] = {"shadow", "depth", "reproject", "filter", "mark", "shade", "truth", "blend",
					  "display", "readback"};

static int tarc_init(render *r, char *err, size_t err_size)
{
	const tarc_options *o = (const tarc_options *)r->config.values.bytes;
	reproj_variant v = {.tarc = true, .oracle = o->oracle, .nearest = o->resample == 1, .truth = o->truth,
			    .force = o->force_reshade, .max_age = o->max_age, .threshold = o->threshold};
	return reproj_init(r, &v, err, err_size);
}

const render_method render_method_tarc = {
	.info = {.name = "tarc",
		 .summary = "temporally adaptive reprojection caching (paper sec. 6.1); tarc-oracle: its ideal variant",
		 .available = true,
		 .family = "reprojection",
		 .options = tarc_option_table,
		 .option_count = sizeof tarc_option_table / sizeof tarc_option_table[0],
		 .decisions = true,
		 .options_size = sizeof(tarc_options),
		 .check = tarc_check},
	.pass_names = tarc_passes,
	.pass_count = sizeof tarc_passes / sizeof tarc_passes[0],
	.state_ring = 2,
	.init = tarc_init,
	.prepare = reproj_prepare,
	.record = reproj_record,
	.collect = reproj_collect,
	.decisions = reproj_decisions,
	.finish = reproj_finish,
};
