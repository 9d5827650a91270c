/* sa.c — `sa`: the shading atlas, every visible block shaded every frame (DESIGN section 4; [TAS] sec. 4.3,
 * "combines the shading atlas [SAS] with the rendering pipeline of texel shading"; TAS-METHODS section 4). The
 * baseline of the atlas methods: Table 1 reductions are against it. */
#include "atlas.h"

#include <stddef.h>

typedef struct sa_options {
	float scale, density;
	uint32_t lmax;
	bool lod0;
} sa_options;

static const method_option sa_option_table[] = {ATLAS_OPTIONS(sa_options)};

static int sa_init(render *r, char *err, size_t err_size)
{
	const sa_options *o = (const sa_options *)r->config.values.bytes;
	atlas_variant v = {.kind = ATLAS_SA, .scale = o->scale, .density = o->density, .lmax = o->lmax, .lod0 = o->lod0};
	return atlas_init(r, &v, err, err_size);
}

const render_method render_method_sa = {
	.info = {.name = "sa",
		 .summary = "shading atlas: visible blocks shaded every frame (paper sec. 4.3)",
		 .available = true,
		 .family = "atlas",
		 .baseline = "sa", /* paper Table 1 reduces the atlas methods against SA */
		 .options = sa_option_table,
		 .option_count = sizeof sa_option_table / sizeof sa_option_table[0],
		 .options_size = sizeof(sa_options)},
	.init = sa_init,
	ATLAS_FRAME_OPS,
};
