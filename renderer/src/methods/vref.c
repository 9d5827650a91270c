/* vref.c — `vref`: every covered pixel a 1x1 sample on the compacted sample path (BASELINES.md section 0): the
 * full-rate baseline of vbuf methods (each of them at its full setting renders exactly this). It differs from ref
 * only in its texture gradients (analytic instead of the quad's differences). */
#include "vbuf_family.h"

static int vref_init(render *r, char *err, size_t err_size)
{
	vbuf_variant v = {0};
	return vbuf_family_init(r, &v, err, err_size);
}

const render_method render_method_vref = {
	.info = {.name = "vref",
		 .summary = "compacted sample path, every covered pixel shaded at 1x1 (the baseline of the VRS methods and ads)",
		 .available = true,
		 .family = "rate"},
	.pass_names = vbuf_rate_passes,
	.pass_count = sizeof vbuf_rate_passes / sizeof vbuf_rate_passes[0],
	.init = vref_init,
	VBUF_FRAME_OPS,
};
