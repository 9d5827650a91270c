/* warp.c — `warp/N`: frame extrapolation ([S] sec. 5.7, BASELINES.md A6): every N-th frame (t mod N = 0, and the
 * first frame of a run) is shaded in full with ref's passes; the frames between reproject that keyframe unshaded -
 * each pixel's surface point (ids pass) looked up in the keyframe's cache (bilinear, per-tap object and 2 % depth
 * test) - and fill the disocclusion holes by pull-push ([S] sec. 3.3; `filled_samples`). No shading of opaque
 * surfaces is launched on those frames; warp/1 is ref. [S]: 40 -> 120 Hz "almost indistinguishable from an
 * actually-rendered 120 Hz sequence". vreuse.h. */
#include "vbuf_family.h" /* VBUF_TRUTH_OPTIONS */
#include "vreuse.h"

#include <stddef.h>

typedef struct warp_options {
	uint32_t period;
	bool truth;
	float truth_t;
} warp_options;

static const method_option warp_option_table[] = {
	{.name = "period", .arg = "N", .help = "shade every N-th frame, extrapolate the others from it (1 equals ref)",
	 .type = METHOD_OPT_UINT, .offset = offsetof(warp_options, period), .def = 2, .min = 1, .max = 16, .variant = '/',
	 .variant_required = true},
	VBUF_TRUTH_OPTIONS(warp_options),
};

static int warp_init(render *r, char *err, size_t err_size)
{
	const warp_options *o = (const warp_options *)r->config.values.bytes;
	vreuse_variant v = {.mode = VREUSE_WARP, .period = o->period, .truth = o->truth, .truth_t = o->truth_t};
	return vreuse_init(r, &v, err, err_size);
}

const render_method render_method_warp = {
	.info = {.name = "warp",
		 .summary = "frame extrapolation: shade every N-th frame, reproject it for the others, fill holes ([S] 5.7)",
		 .available = true,
		 .family = "extrapolation",
		 .options = warp_option_table,
		 .option_count = sizeof warp_option_table / sizeof warp_option_table[0],
		 .options_size = sizeof(warp_options)},
	.pass_names = vreuse_warp_passes,
	.pass_count = sizeof vreuse_warp_passes / sizeof vreuse_warp_passes[0],
	.init = warp_init,
	VREUSE_FRAME_OPS,
};
