/* amss.c — `amss`: amortized supersampling ([S] secs. 3.5, 5.3, after Yang, Nehab, Sander 2009; BASELINES.md A3):
 * one jittered sample per pixel per frame. `--buffers 1`: f_t = a s_t + (1 - a) f_{t-1}(pi(p)) (eq. 2), a recursive
 * filter whose variance ratio is a / (2 - a) (a = 2/5: 1/4). `--buffers 4` (default): a 2x2 sub-pixel buffer updated
 * round-robin, quadrant k = t mod 4 at offset (+-1/4, +-1/4) px taking the new sample, the others reprojected (a tent
 * of one subsample's radius over the previous frame's subsamples); the output is the quadrant mean, so a static view
 * converges to `ref --ssaa 2` (75 % fewer shadings per frame). `--change-bound E`: a signal change (the smoothed
 * residual of a quadrant's sample against its own history) raises the new sample's weight as YNS09 bound alpha, in
 * every quadrant, so that moving lights and shadows on a still view do not drift from ssaa2 (amss.comp.in).
 * `--blur-bound B` (default 0.25 px): the blur that each frame's bilinear resampling adds to the history (variance
 * v (1 - v) per resampling at fractional offset v, [S] sec. 4.2) summed over eq. 2's weights is kept within B by a
 * lower bound on the updated value's alpha (YNS09's velocity bound, amss.comp.in). `--age-limit L` (default 3): a
 * quadrant not due whose value has gone more than L frames without its own sample (carried over by the tent) is
 * dropped for the new sample, as YNS09's buffers hold nothing older than 4 frames. Shaded on the compacted sample
 * path (vreuse.h). */
#include "vreuse.h"

#include <stddef.h>

typedef struct amss_options {
	uint32_t buffers;
	float alpha;
	float bound;
	float blur_bound;
	uint32_t age_limit;
} amss_options;

static const uint32_t buffer_counts[] = {1, 4, 0};

static const method_option amss_option_table[] = {
	{.name = "buffers", .arg = "B", .help = "1: one value per pixel (eq. 2); 4: a 2x2 sub-pixel buffer refreshed round-robin",
	 .type = METHOD_OPT_UINT, .offset = offsetof(amss_options, buffers), .def = 4, .allowed = buffer_counts},
	{.name = "alpha", .arg = "A", .help = "weight of the new sample in its quadrant (eq. 2; a miss or an empty "
					      "quadrant uses 1)",
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(amss_options, alpha), .def = 0.4, .min = 1e-6, .max = 1},
	{.name = "change-bound", .arg = "E", .help = "4 buffers: a signal change (the smoothed residual R of a quadrant's "
						 "sample against its own history, in x/(1+x)) above E raises the weight of "
						 "the new sample to 1 - E/R, in every quadrant (YNS09's bound on alpha; 0: off)",
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(amss_options, bound), .def = 0.01, .min = 0, .max = 1},
	{.name = "blur-bound", .arg = "B", .help = "the blur that repeated resampling of the history accumulates (its "
						   "standard deviation in pixels, from the reprojection's fractional offset) "
						   "is kept within B by raising the new sample's weight (YNS09's velocity "
						   "bound on alpha; 0: off)",
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(amss_options, blur_bound), .def = 0.25, .min = 0, .max = 4},
	{.name = "age-limit", .arg = "L", .help = "4 buffers: a quadrant not due whose value has gone more than L frames "
						  "without its own sample shows the new sample instead (YNS09's buffers "
						  "hold nothing older than 4 frames: 3; 0: no limit)",
	 .type = METHOD_OPT_UINT, .offset = offsetof(amss_options, age_limit), .def = 3, .min = 0, .max = 15},
};

static int amss_init(render *r, char *err, size_t err_size)
{
	const amss_options *o = (const amss_options *)r->config.values.bytes;
	vreuse_variant v = {.mode = VREUSE_AMSS, .buffers = o->buffers, .alpha = o->alpha,
			     .bound = o->bound, .blur_bound = o->blur_bound, .age_limit = o->age_limit};
	return vreuse_init(r, &v, err, err_size);
}

const render_method render_method_amss = {
	.info = {.name = "amss",
		 .summary = "amortized supersampling: one jittered sample per pixel per frame into a reprojected 2x2 "
			    "sub-pixel history ([S] 3.5)",
		 .available = true,
		 .family = "amortized",
		 .baseline = "vref",
		 .options = amss_option_table,
		 .option_count = sizeof amss_option_table / sizeof amss_option_table[0],
		 .options_size = sizeof(amss_options)},
	.pass_names = vreuse_rrc_passes,
	.pass_count = sizeof vreuse_rrc_passes / sizeof vreuse_rrc_passes[0],
	.init = amss_init,
	VREUSE_FRAME_OPS,
};
