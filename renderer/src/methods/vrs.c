/* vrs.c — the VRS rate-selection methods of the variable-rate shading thesis (BASELINES.md A7; [V] chapter 4) on the
 * compacted sample path (lavapipe has no hardware VRS, so a coarse pixel is one listed sample whose value the resolve
 * copies into all its pixels, [V] sec. 3): `casedge` (content-adaptive by edges, Alg. 4.2), `castexel` (by texel
 * density, Alg. 4.4), `mas` (motion-adaptive, Alg. 4.7), `fovea` (foveated, fixed gaze), `taas` (TAA-error-adaptive,
 * Alg. 4.10). One rate per 16x16 tile, chosen on frame t-1's outputs and stabilised over time (shaders/vbuf/rate.comp.in);
 * frame 0 (and a jump in frames) starts at index 10 (1x1). Passes added to the path: rate + finalize before the
 * select, history after the resolve (the display colour per pixel for taas, the tile centres' positions; casedge's
 * rate pass reads frame t-1's displayed image itself, the display pass's RGBA8 output, as FXAA reads an LDR frame).
 * castexel, mas and taas draw the ids pass with a second colour attachment (common/ids.frag.in IDS_VRS_AUX): the
 * per-pixel texel density or screen motion that the next frame's rate pass reads, written where the path already
 * rasterizes each pixel's triangle instead of by a per-pixel triangle fetch in the history pass; it is
 * double-buffered (haux[frame parity]), as frame t's ids pass runs before frame t's rate pass reads frame t-1's. */
#include "vbuf_family.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "method_debug.h"

typedef enum vrs_kind { VRS_CASEDGE, VRS_CASTEXEL, VRS_MAS, VRS_FOVEA, VRS_TAAS } vrs_kind;
static const char *const kind_define[] = {"CASEDGE", "CASTEXEL", "MAS", "FOVEA", "TAAS"};

typedef struct vrs_state {
	vrs_kind kind;
	bool rates_all;
	float gaze[2], inner, outer; /* fovea */
	vkdev_buffer index, dbg;
	vkdev_image hcol[2], hpos, haux[2]; /* hcol: display colours (taas: double-buffered, see set) */
	VkDescriptorSetLayout set_layout;
	/* set[c], bound in the frames whose ids pass writes haux[c]: hist_aux = haux[1 - c]; taas: hist_color =
	 * hcol[1 - c] (frame t-1), hist_color2 = hcol[c] (t-2, which the history pass then overwrites with frame t's,
	 * so no copy); casedge: hist_color = the display pass's image (frame t-1 as shown); the others: hist_color =
	 * hist_color2 = hcol[0] */
	VkDescriptorSet set[2];
	VkPipelineLayout layout;
	VkPipeline rate, finalize, history, centres; /* history: per pixel (taas); centres: per tile */
	bool aux;                                     /* castexel, mas, taas: the ids pass writes haux */
	render_pipeline ids_pipe, ids_pipe_mask;      /* ... with these pipelines */
	int64_t last_frame;
	uint32_t run;       /* frames since the (re)start */
	uint32_t cur;       /* the current half of S this frame */
} vrs_state;

/* The options of every VRS method (one struct; each method's table lists the ones it has). */
typedef struct vrs_options {
	bool force_reshade;
	float gaze_x, gaze_y, inner, outer;
	bool centroid;
	uint32_t rates;
	bool truth;
	float truth_t;
} vrs_options;

static const char *const rates_names[] = {"default", "all", NULL};

#define VRS_FORCE                                                                                                  \
	{.name = "force-reshade", .help = "debug: every tile 1x1 (the path's overhead; equals vref)",                    \
	 .type = METHOD_OPT_BOOL, .offset = offsetof(vrs_options, force_reshade)}

#define VRS_COMMON                                                                                                 \
	{.name = "centroid", .help = "shade a coarse pixel's primitive at the mean of its covered pixel centres, not at "  \
				     "the coarse pixel's centre",                                                     \
	 .type = METHOD_OPT_BOOL, .offset = offsetof(vrs_options, centroid)},                                           \
	{.name = "rates", .arg = "SET", .help = "palette: default (4x4, 2x2, 1x1) or all (4x4, 4x2, 2x4, 2x2, 2x1, 1x2, "  \
						"1x1)",                                                               \
	 .type = METHOD_OPT_CHOICE, .offset = offsetof(vrs_options, rates), .def = 0, .choices = rates_names},          \
	VBUF_TRUTH_OPTIONS(vrs_options), VRS_FORCE

static const method_option common_table[] = {VRS_COMMON};
static const method_option fovea_table[] = {
	{.name = "gaze-x", .arg = "X", .help = "gaze point, fraction of the width from the left",
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(vrs_options, gaze_x), .def = 0.5, .min = 0, .max = 1},
	{.name = "gaze-y", .arg = "Y", .help = "gaze point, fraction of the height from the top",
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(vrs_options, gaze_y), .def = 0.5, .min = 0, .max = 1},
	{.name = "inner", .arg = "DEG", .help = "eccentricity up to which tiles shade at 1x1 (degrees)",
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(vrs_options, inner), .def = 10, .min = 0, .max = 180},
	{.name = "outer", .arg = "DEG", .help = "eccentricity up to which tiles shade at 2x2, beyond at 4x4 (degrees)",
	 .type = METHOD_OPT_FLOAT, .offset = offsetof(vrs_options, outer), .def = 20, .min = 0, .max = 180},
	VRS_COMMON,
};

static int fovea_check(const void *options, char *err, size_t err_size)
{
	const vrs_options *o = options;
	if (o->outer < o->inner)
		return tl_error(err, err_size, TL_ERR_ARG, "fovea: --outer %g is below --inner %g", (double)o->outer,
				(double)o->inner);
	return TL_OK;
}

enum { VRS_BINDINGS = 6 };

/* A history image of the frame's size, or 1x1 where the method never reads it (`used` false: it is only bound). */
static int make_image(render *r, VkFormat fmt, VkImageUsageFlags usage, bool used, const char *name, vkdev_image *out,
		      char *err, size_t err_size)
{
	VkResult res = vkdev_image_create(r->dev, used ? r->desc.width : 1, used ? r->desc.height : 1, 1, 1, fmt,
					  VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | usage,
					  VK_IMAGE_ASPECT_COLOR_BIT, false, name, out);
	return res ? render_vk_error(err, err_size, name, res) : TL_OK;
}

static int make_compute(render *r, vrs_state *s, const char *path, const char *extra, VkPipeline *out, char *err,
			size_t err_size)
{
	char defs[128];
	snprintf(defs, sizeof defs, "#define %s 1\n%s%s", kind_define[s->kind], s->rates_all ? "#define VRS_RATES_ALL 1\n" : "",
		 extra);
	return render_compute_defs(r, path, defs, s->layout, out, err, err_size);
}

/* The ids pass of castexel, mas and taas: common/ids.{vert,frag}.in with IDS_VRS_AUX and the method's define, the ids
 * pass's set 1, a second colour attachment (RGBA32F, haux). */
static int make_ids_pipelines(render *r, vbuf_pass *p, vrs_state *s, char *err, size_t err_size)
{
	char defs[96];
	snprintf(defs, sizeof defs, "#define IDS_VRS_AUX 1\n#define %s 1\n", kind_define[s->kind]);
	ids_pipe_src src = {"common/ids.vert.in", defs, "common/ids.frag.in", defs, "#define IDS_ALPHA_MASK 1\n"};
	render_pipe_desc pd = {.color = 2, .depth_write = 1, .depth_op = VK_COMPARE_OP_LESS_OR_EQUAL,
			       .color_format = VK_FORMAT_R32G32B32A32_UINT, .color2_format = VK_FORMAT_R32G32B32A32_SFLOAT,
			       .method_set = p->ids.set_layout};
	return ids_make_pipelines(r, &src, pd, &s->ids_pipe, &s->ids_pipe_mask, "vrs: ids pipeline", err, err_size);
}

static int vrs_rate_init(render *r, vbuf_pass *p, void *user, char *err, size_t err_size)
{
	vrs_state *s = user;
	VkDevice d = r->dev->device;
	uint32_t tiles = p->tiles_x * p->tiles_y;
	VkResult res;
	if ((res = vkdev_buffer_create(r->dev, (VkDeviceSize)tiles * 2 * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true,
				       "vrs index", &s->index)) ||
	    (res = vkdev_buffer_create(r->dev, (VkDeviceSize)tiles * 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true,
				       "vrs tile debug", &s->dbg)))
		return render_vk_error(err, err_size, "vrs buffers", res);
	int rc;
	const VkImageUsageFlags att = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
	bool taas = s->kind == VRS_TAAS; /* the display colours of frames t-1 and t-2 (casedge reads the display image) */
	if ((rc = make_image(r, VK_FORMAT_R16G16B16A16_SFLOAT, 0, taas, "vrs history colour 0", &s->hcol[0], err,
			     err_size)) ||
	    (rc = make_image(r, VK_FORMAT_R16G16B16A16_SFLOAT, 0, taas, "vrs history colour 1", &s->hcol[1], err,
			     err_size)) ||
	    (rc = make_image(r, VK_FORMAT_R32G32B32A32_SFLOAT, 0, true, "vrs history position", &s->hpos, err, err_size)) ||
	    (rc = make_image(r, VK_FORMAT_R32G32B32A32_SFLOAT, att, true, "vrs motion / texel density 0", &s->haux[0], err,
			     err_size)) ||
	    (rc = make_image(r, VK_FORMAT_R32G32B32A32_SFLOAT, att, true, "vrs motion / texel density 1", &s->haux[1], err,
			     err_size)))
		return rc;
	VkDescriptorSetLayoutBinding b[VRS_BINDINGS];
	for (uint32_t i = 0; i < VRS_BINDINGS; i++)
		b[i] = (VkDescriptorSetLayoutBinding){i, i == 0 || i == 5 ? VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
									  : VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
						      1, VK_SHADER_STAGE_COMPUTE_BIT, NULL};
	VkDescriptorSetLayoutCreateInfo li = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
					      .bindingCount = VRS_BINDINGS, .pBindings = b};
	if ((res = vkCreateDescriptorSetLayout(d, &li, NULL, &s->set_layout)))
		return render_vk_error(err, err_size, "vrs: descriptor set layout", res);
	VkDescriptorSetLayout two[2] = {s->set_layout, s->set_layout};
	VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
					  .descriptorPool = r->pool, .descriptorSetCount = 2, .pSetLayouts = two};
	if ((res = vkAllocateDescriptorSets(d, &ai, s->set)))
		return render_vk_error(err, err_size, "vrs: descriptor set", res);
	for (int c = 0; c < 2; c++) {
		bool two_colours = s->kind == VRS_TAAS;
		/* casedge: frame t-1's displayed image (the display pass's, RGBA8), read by its rate pass */
		const vkdev_image *col = s->kind == VRS_CASEDGE ? &r->display : &s->hcol[two_colours ? 1 - c : 0];
		const vkdev_image *imgs[VRS_BINDINGS] = {NULL, col,
							 &s->hcol[two_colours ? c : 0], &s->hpos, &s->haux[1 - c], NULL};
		const vkdev_buffer *bufs[VRS_BINDINGS] = {&s->index, NULL, NULL, NULL, NULL, &s->dbg};
		vkdev_write_storage_set(d, s->set[c], VRS_BINDINGS, bufs, imgs);
	}
	VkDescriptorSetLayout sets[3] = {r->scene_set_layout, p->set_layout, s->set_layout};
	VkPushConstantRange pcr = {VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(gpu_push)};
	VkPipelineLayoutCreateInfo pli = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 3,
					  .pSetLayouts = sets, .pushConstantRangeCount = 1, .pPushConstantRanges = &pcr};
	if ((res = vkCreatePipelineLayout(d, &pli, NULL, &s->layout)))
		return render_vk_error(err, err_size, "vrs: pipeline layout", res);
	s->aux = s->kind == VRS_CASTEXEL || s->kind == VRS_MAS || s->kind == VRS_TAAS;
	if ((rc = make_compute(r, s, "vbuf/rate.comp.in", "", &s->rate, err, err_size)) ||
	    (rc = make_compute(r, s, "vbuf/finalize.comp.in", "", &s->finalize, err, err_size)) ||
	    (s->kind == VRS_TAAS && (rc = make_compute(r, s, "vbuf/history.comp.in", "", &s->history, err, err_size))) ||
	    (s->kind != VRS_FOVEA &&
	     (rc = make_compute(r, s, "vbuf/history.comp.in", "#define CENTRES 1\n", &s->centres, err, err_size))) ||
	    (s->aux && (rc = make_ids_pipelines(r, p, s, err, err_size))))
		return rc;
	VkCommandBuffer cmd;
	if ((res = vkdev_cmd_begin(r->dev, &cmd)))
		return render_vk_error(err, err_size, "command buffer", res);
	VkClearColorValue zero = {{0}};
	VkImageSubresourceRange range = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
	const vkdev_image *im[5] = {&s->hcol[0], &s->hcol[1], &s->hpos, &s->haux[0], &s->haux[1]};
	for (int i = 0; i < 5; i++) {
		vkdev_barrier_image(cmd, im[i], VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
				    VK_PIPELINE_STAGE_2_NONE, 0, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
		vkCmdClearColorImage(cmd, im[i]->image, VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &range);
	}
	/* casedge reads the display image in the layout every frame's read-back leaves (readback.c); it starts there too,
	 * so that the rate pass's barrier holds even after a frame that failed before its read-back */
	if (s->kind == VRS_CASEDGE)
		vkdev_barrier_image(cmd, &r->display, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
				    VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0,
				    VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
	vbuf_barrier(cmd);
	if ((res = vkdev_cmd_submit_wait(r->dev, cmd)))
		return render_vk_error(err, err_size, "vrs setup", res);
	s->last_frame = -1;
	return TL_OK;
}

static void vrs_rate_prepare(render *r, vbuf_pass *p, void *user, uint32_t frame)
{
	vrs_state *s = user;
	(void)r;
	if (!(s->last_frame >= 0 && (int64_t)frame == s->last_frame + 1)) {
		/* frame 0 or a jump: S = 10 (1x1 everywhere), no history */
		s->run = 0;
		uint32_t tiles = p->tiles_x * p->tiles_y;
		int32_t *S = s->index.mapped;
		uint32_t *rates = p->rates.mapped;
		for (uint32_t t = 0; t < tiles; t++) {
			S[t] = 10;
			S[tiles + t] = -1;
			rates[t] = VBUF_RATE(1, 1);
		}
	} else {
		s->run++;
	}
	s->cur = s->run % 2;
	s->last_frame = frame;
}

static void bind(render *r, vbuf_pass *p, vrs_state *s, VkCommandBuffer cmd, VkPipeline pipe, const uint32_t aux[4])
{
	VkDescriptorSet sets[3] = {r->scene_set, p->set, s->set[s->cur]};
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe);
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s->layout, 0, 3, sets, 0, NULL);
	gpu_push pc = {0, 0, (uint32_t)r->scene->object_count, 0, {aux[0], aux[1], aux[2], aux[3]}};
	vkCmdPushConstants(cmd, s->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof pc, &pc);
}

static void vrs_rate_record(render *r, vbuf_pass *p, void *user, VkCommandBuffer cmd, uint32_t frame)
{
	vrs_state *s = user;
	(void)frame;
	/* the foveated rates need no history; the others start from the previous frame's outputs */
	if (s->kind != VRS_FOVEA && s->run == 0)
		return;
	uint32_t aux[4] = {s->cur, s->run >= 1, s->run >= 2, 0};
	if (s->kind == VRS_FOVEA) {
		uint32_t gx = (uint32_t)lroundf(s->gaze[0] * (float)r->desc.width);
		uint32_t gy = (uint32_t)lroundf(s->gaze[1] * (float)r->desc.height);
		aux[1] = (uint32_t)lroundf(s->inner * 64.0f) | (uint32_t)lroundf(s->outer * 64.0f) << 16;
		aux[3] = gx | gy << 16;
	}
	if (s->kind == VRS_CASEDGE) /* frame t-1's displayed image, left by its read-back (readback.c) */
		vkdev_barrier_image(cmd, &r->display, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
				    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT,
				    VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
	bind(r, p, s, cmd, s->rate, aux);
	if (s->kind == VRS_TAAS) /* one invocation per tile, eight tiles of a row a workgroup (rate.comp.in
				  * taas_tile_sum); rows in y, so that 16384 x 16384 (1024 x 1024 tiles) stays within the
				  * 65,535 workgroups a dimension may count */
		vkCmdDispatch(cmd, (p->tiles_x + 7) / 8, p->tiles_y, 1);
	else /* one 16x16 workgroup per tile */
		vkCmdDispatch(cmd, p->tiles_x, p->tiles_y, 1);
	vbuf_barrier(cmd);
	bind(r, p, s, cmd, s->finalize, aux);
	vkCmdDispatch(cmd, (p->tiles_x * p->tiles_y + 63) / 64, 1, 1);
}

static void vrs_rate_after(render *r, vbuf_pass *p, void *user, VkCommandBuffer cmd, uint32_t frame)
{
	vrs_state *s = user;
	(void)frame;
	if (s->kind == VRS_FOVEA)
		return;
	uint32_t aux[4] = {s->cur, 0, 0, 0};
	if (s->history) {
		bind(r, p, s, cmd, s->history, aux);
		vkCmdDispatch(cmd, (r->desc.width + 7) / 8, (r->desc.height + 7) / 8, 1);
	}
	if (s->centres) { /* writes other images than the per-pixel pass: no barrier between them */
		bind(r, p, s, cmd, s->centres, aux);
		vkCmdDispatch(cmd, (p->tiles_x * p->tiles_y + 63) / 64, 1, 1);
	}
}

/* castexel, mas, taas: the ids pass with the second attachment haux[cur] (cleared to the background's (0, 0, 1/2, 0):
 * no motion, untextured density), in place of ids_pass_record; push constants' aux[2], aux[3]: the size. */
static void vrs_ids_record(render *r, vbuf_pass *p, void *user, VkCommandBuffer cmd, uint32_t frame)
{
	vrs_state *s = user;
	(void)frame;
	if (!s->aux) {
		ids_pass_record(r, &p->ids, cmd, 0);
		return;
	}
	const VkClearColorValue clear = {.float32 = {0.0f, 0.0f, 0.5f, 0.0f}};
	const uint32_t size[2] = {r->desc.width, r->desc.height};
	const VkClearColorValue clears[2] = {{{0}}, clear};
	const vkdev_image *targets[2] = {&p->ids.image, &s->haux[s->cur]};
	ids_begin(r, cmd, targets, 2, clears);
	ids_draw_objects(r, cmd, p->ids.set, &s->ids_pipe, &s->ids_pipe_mask, 0, size);
	ids_end(cmd, targets, 2);
}

static void vrs_rate_finish(render *r, vbuf_pass *p, void *user)
{
	vrs_state *s = user;
	(void)p;
	VkDevice d = r->dev->device;
	VkPipeline pp[4] = {s->rate, s->finalize, s->history, s->centres};
	for (int i = 0; i < 4; i++)
		if (pp[i])
			vkDestroyPipeline(d, pp[i], NULL);
	if (s->layout)
		vkDestroyPipelineLayout(d, s->layout, NULL);
	if (s->set_layout)
		vkDestroyDescriptorSetLayout(d, s->set_layout, NULL);
	vkdev_buffer_destroy(r->dev, &s->index);
	vkdev_buffer_destroy(r->dev, &s->dbg);
	render_pipeline_destroy(r, &s->ids_pipe);
	render_pipeline_destroy(r, &s->ids_pipe_mask);
	vkdev_image *im[5] = {&s->hcol[0], &s->hcol[1], &s->hpos, &s->haux[0], &s->haux[1]};
	for (int i = 0; i < 5; i++)
		vkdev_image_destroy(r->dev, im[i]);
	free(s);
}

static int vrs_init(render *r, vrs_kind kind, char *err, size_t err_size)
{
	const vrs_options *o = (const vrs_options *)r->config.values.bytes;
	vrs_state *s = calloc(1, sizeof *s);
	if (!s)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	s->kind = kind;
	s->rates_all = o->rates == 1;
	if (kind == VRS_FOVEA) {
		s->gaze[0] = o->gaze_x, s->gaze[1] = o->gaze_y, s->inner = o->inner, s->outer = o->outer;
	}
	vbuf_variant v = {.force = o->force_reshade, .centroid = o->centroid, .truth = o->truth, .truth_t = o->truth_t,
			  .rate_init = vrs_rate_init, .rate_prepare = vrs_rate_prepare,
			  .rate_record = vrs_rate_record, .rate_after = vrs_rate_after, .rate_finish = vrs_rate_finish,
			  .ids_record = vrs_ids_record,
			  .user = s};
	int rc = vbuf_family_init(r, &v, err, err_size);
	if (rc && !r->method_state) /* the family's state was not made, so its finish will not free ours */
		free(s);
	return rc;
}

const float *vrs_debug_tiles(render *r, const int32_t **index, uint32_t *tiles_x, uint32_t *tiles_y)
{
	vbuf_pass *p = vbuf_family_pass(r);
	vrs_state *s = vbuf_family_user(r);
	*tiles_x = p->tiles_x, *tiles_y = p->tiles_y;
	if (index)
		*index = s->index.mapped ? (const int32_t *)s->index.mapped + (size_t)s->cur * p->tiles_x * p->tiles_y : NULL;
	return s->dbg.mapped;
}

const uint32_t *vbuf_debug_rates(render *r)
{
	return vbuf_family_pass(r)->rates.mapped;
}

int vbuf_debug_ids(render *r, uint32_t *ids, char *err, size_t err_size)
{
	return ids_pass_copy(r, &vbuf_family_pass(r)->ids, ids, false, err, err_size);
}

#define VRS_METHOD(NAME, KIND, SUMMARY, TABLE, CHECK)                                                            \
	static int NAME##_init(render *r, char *err, size_t err_size) { return vrs_init(r, KIND, err, err_size); }     \
	const render_method render_method_##NAME = {                                                               \
		.info = {.name = #NAME,                                                                            \
			 .summary = SUMMARY,                                                                        \
			 .available = true,                                                                         \
			 .family = "rate",                                                                          \
			 .tile_rates = true,                                                                        \
			 .baseline = "vref",                                                                        \
			 .options = TABLE,                                                                          \
			 .option_count = sizeof TABLE / sizeof TABLE[0],                                            \
			 .options_size = sizeof(vrs_options),                                                       \
			 .check = CHECK},                                                                           \
		.pass_names = vbuf_vrs_passes,                                                                     \
		.pass_count = sizeof vbuf_vrs_passes / sizeof vbuf_vrs_passes[0],                                  \
		.state_ring = 2,                                                                                   \
		.init = NAME##_init,                                                                               \
		VBUF_FRAME_OPS,                                                                                    \
	};

VRS_METHOD(casedge, VRS_CASEDGE, "VRS, content-adaptive by edges: FXAA edge density per 16x16 tile ([V] Alg. 4.2)",
	   common_table, NULL)
VRS_METHOD(castexel, VRS_CASTEXEL, "VRS, content-adaptive by texel density per 16x16 tile ([V] Alg. 4.4)",
	   common_table, NULL)
VRS_METHOD(mas, VRS_MAS, "VRS, motion-adaptive: object and camera motion per 16x16 tile ([V] Alg. 4.7)", common_table,
	   NULL)
VRS_METHOD(fovea, VRS_FOVEA, "VRS, foveated: rate by eccentricity from a fixed gaze point ([V] sec. 4.4)", fovea_table,
	   fovea_check)
VRS_METHOD(taas, VRS_TAAS, "VRS, TAA-error-adaptive: history distance to the neighbourhood ([V] Alg. 4.10)",
	   common_table, NULL)
