/* atlas.h (private) — the shading atlas shared by sa, sau and tasa (TAS-METHODS sections 4-6; [TAS] secs. 4.3,
 * 5.1, 6.2): patches of two triangles shaded into blocks of an atlas by a compute pass over a compacted work list,
 * resolved per pixel from a visibility pass. The method files (sa.c, sau.c, tasa.c) declare the options and
 * choose the variant. */
#ifndef TASLAB_ATLAS_H
#define TASLAB_ATLAS_H

#include "../passes/ids.h"
#include "../passes/passes.h"

enum { ATLAS_SA = 0, ATLAS_SAU, ATLAS_TASA };

typedef struct atlas_variant {
	int kind;          /* ATLAS_* */
	bool oracle;       /* tasa's ideal variant */
	bool truth;        /* --truth: count late texels among the reused blocks */
	bool force;        /* tasa --force-reshade: every block shaded through the TAS pipeline (overhead) */
	uint32_t period;   /* sau N */
	float threshold;   /* tasa T; sau: the T late texels are counted against with --truth */
	float scale;       /* atlas texels = scale x output pixels */
	float density;     /* texels per pixel per axis before the round-up; 0: sqrt(scale / 8) */
	uint32_t lmax;     /* largest block side, log2 */
	bool lod0;         /* ablation: textures sampled at mip 0 instead of with explicit gradients */
} atlas_variant;

int atlas_init(render *r, const atlas_variant *v, char *err, size_t err_size);
int atlas_prepare(render *r, uint32_t frame, char *err, size_t err_size);
void atlas_record_pre(render *r, VkCommandBuffer cmd, uint32_t frame);
int atlas_cpu_step(render *r, uint32_t frame, char *err, size_t err_size);
void atlas_record(render *r, VkCommandBuffer cmd, uint32_t frame);
void atlas_collect(render *r, frame_stats *st);
void atlas_finish(render *r);
size_t atlas_derived(const render *r, run_option *out, size_t max);

#define ATLAS_PASS_COUNT 10
extern const char *const atlas_pass_names[ATLAS_PASS_COUNT];

/* The frame operations of every atlas method (render_method fields after .info and .init). */
#define ATLAS_FRAME_OPS                                                                                            \
	.pass_names = atlas_pass_names, .pass_count = ATLAS_PASS_COUNT, .state_ring = 1, .prepare = atlas_prepare,      \
	.record_pre = atlas_record_pre, .cpu_step = atlas_cpu_step, .record = atlas_record, .collect = atlas_collect,   \
	.finish = atlas_finish, .derived = atlas_derived, .shared_views = true

/* The options every atlas method has (method_option entries for an options struct T with fields scale, density,
 * lmax, lod0; DESIGN section 4 --atlas-scale). */
#define ATLAS_OPTIONS(T)                                                                                           \
	{.name = "atlas-scale", .arg = "S", .help = "atlas texels = S x output pixels (4: the paper's 8 MPx at 1080p)",  \
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(T, scale), .def = 4, .min = 0.25, .max = 64},                   \
	{.name = "atlas-density", .arg = "RHO", .help = "texels per pixel per axis before the power-of-two round-up (0: sqrt(S / 8))", \
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(T, density), .def = 0, .min = 0, .max = 4},                     \
	{.name = "max-block", .arg = "L", .help = "largest block side 2^L texels (larger patches are clamped)",       \
	 .type = METHOD_OPT_UINT, .offset = offsetof(T, lmax), .def = 8, .min = 1, .max = 12},                       \
	{.name = "texture-lod0", .help = "ablation: sample textures at mip 0, as texture() does in a compute shader",   \
	 .type = METHOD_OPT_BOOL, .offset = offsetof(T, lod0)}

#endif
