/* ads.c — `ads@S`: adaptive deferred shading (BASELINES.md A8; [A] "Adaptive Deferred Shading"): a coarse grid of
 * step s0 = 2^m (default 4, "initial grid step size of 4", [A] Fig. 1) is always shaded; the grid is refined, "scaled
 * and rotated with each subdivision" (diamond, then square steps for s = s0 .. 2), and a pixel is shaded where the
 * variance of its neighbours' display values exceeds S, else "linearly interpolated" from them. At least one pixel
 * of every s0^2 is shaded. On lavapipe each sub-step is one select and one indirect shade of the compacted sample
 * path (passes/vbuf.h), so interpolated pixels launch no shading. */
#include "vbuf_family.h"

#include <stddef.h>

typedef struct ads_options {
	float threshold;
	uint32_t step;
	bool edge_guard;
	bool force_reshade;
	bool truth;
	float truth_t;
} ads_options;

static const uint32_t ads_steps[] = {2, 4, 8, 16, 0};

static const method_option ads_option_table[] = {
	{.name = "threshold", .arg = "S", .help = "shade a pixel when the standard deviation of its neighbours' display "
						  "values exceeds S code values (max over R, G, B; < 0: shade all)",
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(ads_options, threshold), .def = 2, .min = -1, .max = 255, .variant = '@'},
	{.name = "step", .arg = "S0", .help = "initial grid step: one pixel of every S0 x S0 is always shaded",
	 .type = METHOD_OPT_UINT, .offset = offsetof(ads_options, step), .def = 4, .allowed = ads_steps},
	{.name = "edge-guard", .help = "also shade where a neighbour shows another object or the background",
	 .type = METHOD_OPT_BOOL, .offset = offsetof(ads_options, edge_guard)},
	{.name = "force-reshade", .help = "debug: shade every covered pixel (the path's overhead; equals vref)",
	 .type = METHOD_OPT_BOOL, .offset = offsetof(ads_options, force_reshade)},
	VBUF_TRUTH_OPTIONS(ads_options),
};

static int ads_init(render *r, char *err, size_t err_size)
{
	const ads_options *o = (const ads_options *)r->config.values.bytes;
	vbuf_variant v = {.ads = true, .S = o->threshold, .step = o->step, .edge_guard = o->edge_guard,
			  .force = o->force_reshade, .truth = o->truth, .truth_t = o->truth_t};
	return vbuf_family_init(r, &v, err, err_size);
}

const render_method render_method_ads = {
	.info = {.name = "ads",
		 .summary = "adaptive deferred shading: a coarse grid refined where neighbours differ by more than S, the "
			    "rest interpolated ([A])",
		 .available = true,
		 .family = "deferred",
		 .baseline = "vref",
		 .options = ads_option_table,
		 .option_count = sizeof ads_option_table / sizeof ads_option_table[0],
		 .options_size = sizeof(ads_options)},
	.pass_names = vbuf_ads_passes,
	.pass_count = sizeof vbuf_ads_passes / sizeof vbuf_ads_passes[0],
	.init = ads_init,
	VBUF_FRAME_OPS,
};
