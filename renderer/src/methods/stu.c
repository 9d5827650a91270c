/* stu.c — `stu/N`: spatio-temporal upsampling ([S] sec. 5.6, eq. 25, after Herzog et al. 2010; BASELINES.md A4): each
 * frame shades the interleaved phase pixels of rrc-interleaved/N (N = 4: one pixel of every 2x2); they show their
 * sample and keep it as L. Every other pixel blends the reprojected previous output H with a joint-bilateral
 * upsample S of the 5x5 window's phase samples (world-distance and normal weights, same object):
 * f = c H + (1 - c) S, c = [hit] clamp((8 - D) / 7.5, 0, 1), where D, the "temporal smoothing" of the gradient,
 * is 1/2 D_prev + 1/2 the 5x5 max of g_q = d(s_q, L_q). Shaded on the compacted sample path (vreuse.h). */
#include "vbuf_family.h" /* VBUF_TRUTH_OPTIONS */
#include "vreuse.h"

#include <stddef.h>

typedef struct stu_options {
	uint32_t period;
	bool truth;
	float truth_t;
} stu_options;

static const uint32_t periods[] = {2, 4, 8, 0};

static const method_option stu_option_table[] = {
	{.name = "period", .arg = "N", .help = "shade one pixel of every 2x1 (N 2), 2x2 (4) or 4x2 (8) cell per frame, "
					       "in turn",
	 .type = METHOD_OPT_UINT, .offset = offsetof(stu_options, period), .def = 4, .allowed = periods, .variant = '/',
	 .variant_required = true},
	VBUF_TRUTH_OPTIONS(stu_options),
};

static int stu_init(render *r, char *err, size_t err_size)
{
	const stu_options *o = (const stu_options *)r->config.values.bytes;
	vreuse_variant v = {.mode = VREUSE_STU, .period = o->period, .truth = o->truth, .truth_t = o->truth_t};
	return vreuse_init(r, &v, err, err_size);
}

const render_method render_method_stu = {
	.info = {.name = "stu",
		 .summary = "spatio-temporal upsampling: 1/N of the pixels shaded per frame, the rest from history and "
			    "their neighbours ([S] 5.6)",
		 .available = true,
		 .family = "upsampling",
		 .baseline = "vref",
		 .options = stu_option_table,
		 .option_count = sizeof stu_option_table / sizeof stu_option_table[0],
		 .options_size = sizeof(stu_options)},
	.pass_names = vreuse_rrc_passes,
	.pass_count = sizeof vreuse_rrc_passes / sizeof vreuse_rrc_passes[0],
	.init = stu_init,
	VREUSE_FRAME_OPS,
};
