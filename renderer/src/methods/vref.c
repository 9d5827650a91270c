/* vref.c — `vref`: every covered pixel a 1x1 sample on the compacted sample path (BASELINES.md section 0): the
 * full-rate baseline of vbuf methods (each of them at its full setting renders exactly this). It differs from ref
 * only in its texture gradients (analytic instead of the quad's differences). */
#include "vbuf_family.h"

typedef struct vref_options {
	bool truth;
	float truth_t;
} vref_options;

static const method_option vref_option_table[] = {VBUF_TRUTH_OPTIONS(vref_options)};

static int vref_init(render *r, char *err, size_t err_size)
{
	const vref_options *o = (const vref_options *)r->config.values.bytes;
	vbuf_variant v = {.truth = o->truth, .truth_t = o->truth_t};
	return vbuf_family_init(r, &v, err, err_size);
}

const render_method render_method_vref = {
	.info = {.name = "vref",
		 .summary = "compacted sample path, every covered pixel shaded at 1x1 (the baseline of the VRS methods and ads)",
		 .available = true,
		 .family = "rate",
		 .tile_rates = true,
		 .options = vref_option_table,
		 .option_count = sizeof vref_option_table / sizeof vref_option_table[0],
		 .options_size = sizeof(vref_options)},
	.pass_names = vbuf_rate_passes,
	.pass_count = sizeof vbuf_rate_passes / sizeof vbuf_rate_passes[0],
	.init = vref_init,
	VBUF_FRAME_OPS,
};
