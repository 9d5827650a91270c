/* vreuse.c — temporal reuse on the compacted sample path (vreuse.h; BASELINES.md A2, A6): the per-pixel cache, its
 * reverse reprojection, the decide / resolve / pull-push passes (shaders/vreuse/) and the frames of rrc-random,
 * rrc-interleaved and warp. */
#include "vreuse.h"

#include "method_debug.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const vreuse_rrc_passes[9] = {"shadow", "ids",   "decide",  "shade",   "resolve",
					 "truth",  "blend", "display", "readback"};
const char *const vreuse_warp_passes[10] = {"shadow", "depth", "shade", "ids",     "warp",
					    "fill",   "truth", "blend", "display", "readback"};

enum { VREUSE_BINDINGS = 13 };
/* decide's aux[1] flags */
enum { FLAG_HAVE_CACHE = 1u };

typedef struct vreuse_state {
	vreuse_variant v;
	vbuf_pass p;
	vkdev_image cache_col, cache_rec, rec_new, flag;
	vkdev_image cache_rec2; /* rrc, stu: the second cache, swapped with cache_rec per frame (1x1 for the others) */
	vkdev_buffer pyr;  /* warp: the pull-push pyramid, vec4 (rgb, weight) per node of levels 1 up; one texel for the
			    * others */
	vkdev_image spos, snrm; /* stu: each pixel's world position and g, its normal and object + 1, as float bits
				 * (RGBA32UI), written by the visibility pass (vis.frag.in VIS_SURFACE); 1x1 for the others */
	vkdev_image sub[2]; /* amss: 2x2 sub-pixel buffers, 2W x 2H (1x1 for the other methods), swapped per frame */
	vkdev_image age[2]; /* amss: frames since each subsample took its own sample (R32_UINT) */
	vkdev_image vis;    /* the reprojecting visibility pass's record (vis.frag.in) */
	render_pipeline vis_pipe, vis_pipe_mask;
	uint32_t parity;   /* amss: sub[parity] is this frame's (sub_next) */
	VkDescriptorSetLayout set_layout;
	VkDescriptorSet set[2]; /* sub_prev / sub_next swapped */
	VkPipelineLayout layout;
	VkPipeline decide, resolve, pull, push, fill_args, amss, jshade, stu_g, stu;
	VkPipeline hshade; /* rrc: the path's shade writing the HDR target (shade.comp.in VBUF_TO_HDR) */
	int64_t last_frame;
	bool have_cache;   /* rrc: the cache holds frame t-1 */
	bool key;          /* warp: this frame is shaded in full */
	uint32_t key_frame;
	bool shadows;      /* the frame renders shadow maps */
} vreuse_state;

static vreuse_state *state_of(render *r) { return r->method_state; }

/* A storage image of the frame's size (1x1 where the method does not use it: full false). */
static int make_image(render *r, VkFormat fmt, bool full, const char *name, vkdev_image *out, char *err,
		      size_t err_size)
{
	VkResult res = vkdev_image_create(r->dev, full ? r->desc.width : 1, full ? r->desc.height : 1, 1, 1, fmt,
					  VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
					  VK_IMAGE_ASPECT_COLOR_BIT, false, name, out);
	return res ? render_vk_error(err, err_size, name, res) : TL_OK;
}

static int make_compute_x(render *r, vreuse_state *s, const char *path, const char *extra, VkPipeline *out, char *err,
			  size_t err_size)
{
	static const char *const mode_define[] = {"", "RRC_RANDOM", "RRC_INTERLEAVED", "WARP", "AMSS", "STU"};
	char defs[96];
	snprintf(defs, sizeof defs, "#define %s 1\n%s", mode_define[s->v.mode], extra);
	return render_compute_defs(r, path, defs, s->layout, out, err, err_size);
}

static int make_compute(render *r, vreuse_state *s, const char *path, VkPipeline *out, char *err, size_t err_size)
{
	return make_compute_x(r, s, path, "", out, err, err_size);
}

/* The reprojecting visibility pass (vis.vert.in, vis.frag.in): the ids pass's draw with the ids pass's set 1 (the
 * scene's vertices and indices), writing what the lookup needs; MASK objects alpha-tested. warp: instead of the ids
 * (its extrapolated frames shade nothing); the rrc variants, amss and stu: beside them (VIS_IDS, two targets: the
 * ids and the record), so that one geometry pass serves the shading and the lookup. */
static bool vis_writes_ids(const vreuse_state *s) { return s->v.mode != VREUSE_WARP; }
/* its colour attachments: warp the record; rrc, amss the ids and the record; stu also the surface (position, normal) */
static uint32_t vis_targets(const vreuse_state *s) { return s->v.mode == VREUSE_STU ? 4 : vis_writes_ids(s) ? 2 : 1; }

static int make_vis_pipelines(render *r, vreuse_state *s, char *err, size_t err_size)
{
	/* rrc, amss, stu: this frame's distance too (the record), and the ids; stu: each pixel's surface too */
	const char *rec = s->v.mode == VREUSE_STU ? "#define VIS_RECORD 1\n#define VIS_IDS 1\n#define VIS_SURFACE 1\n"
			  : vis_writes_ids(s)       ? "#define VIS_RECORD 1\n#define VIS_IDS 1\n"
						    : "";
	ids_pipe_src src = {"vreuse/vis.vert.in", rec, "vreuse/vis.frag.in", rec, "#define VIS_ALPHA_MASK 1\n"};
	render_pipe_desc pd = {.color = (int)vis_targets(s), .depth_write = 1,
			       .depth_op = VK_COMPARE_OP_LESS_OR_EQUAL, .color_format = VK_FORMAT_R32G32B32A32_UINT,
			       .method_set = s->p.ids.set_layout};
	return ids_make_pipelines(r, &src, pd, &s->vis_pipe, &s->vis_pipe_mask, "vreuse: visibility pipeline", err,
				  err_size);
}

/* The reprojecting visibility pass: the ids pass's begin, draws and end (passes/ids.h) with the vis pipelines, so the
 * same surfaces win as in ids_pass_record (scene order, depth LESS_OR_EQUAL) and BLEND finds the same depth. For the
 * rrc variants, amss and stu it is the frame's ids pass too (the ids image is attachment 0, the record attachment
 * 1); for stu attachments 2 and 3 take each pixel's world position and normal, interpolated by the rasterizer, where a
 * compute pass fetched the pixel's triangle to make them. */
static void record_vis(render *r, vreuse_state *s, VkCommandBuffer cmd, uint32_t key_slot)
{
	const uint32_t aux23[2] = {key_slot, r->desc.width | r->desc.height << 16};
	const vkdev_image *targets[4] = {&s->p.ids.image, &s->vis, &s->spos, &s->snrm};
	uint32_t n = vis_targets(s);
	const vkdev_image *const *t = n == 1 ? targets + 1 : targets;
	ids_begin(r, cmd, t, n, NULL);
	ids_draw_objects(r, cmd, s->p.ids.set, &s->vis_pipe, &s->vis_pipe_mask, 0, aux23);
	ids_end(cmd, t, n);
}

int vreuse_init(render *r, const vreuse_variant *v, char *err, size_t err_size)
{
	vreuse_state *s = calloc(1, sizeof *s);
	if (!s)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	r->method_state = s;
	s->v = *v;
	s->last_frame = -1;
	s->p.truth = v->truth; /* the path's truth pass (vbuf.c), recorded after the method's resolve */
	s->p.truth_t = v->truth_t;
	int rc = vbuf_init(r, &s->p, false, err, err_size);
	if (rc)
		return rc;
	/* stu's record is (object + 1, view distance) alone: two channels (vreuse.glsl VREUSE_REC_FORMAT) */
	VkFormat rec_format = v->mode == VREUSE_STU ? VK_FORMAT_R32G32_UINT : VK_FORMAT_R32G32B32A32_UINT;
	if ((rc = make_image(r, VK_FORMAT_R16G16B16A16_SFLOAT, true, "vreuse cache colour", &s->cache_col, err,
			     err_size)) ||
	    (rc = make_image(r, rec_format, true, "vreuse cache record", &s->cache_rec, err, err_size)) ||
	    (rc = make_image(r, VK_FORMAT_R32G32B32A32_UINT, v->mode == VREUSE_AMSS, "vreuse record (amss)", &s->rec_new,
			     err, err_size)) ||
	    (rc = make_image(r, VK_FORMAT_R32_UINT, true, "vreuse flags", &s->flag, err, err_size)))
		return rc;
	uint32_t w = r->desc.width, h = r->desc.height;
	bool amss = v->mode == VREUSE_AMSS, stu = v->mode == VREUSE_STU;
	uint32_t sw = amss ? 2 * w : stu ? w : 1, sh = amss ? 2 * h : stu ? h : 1;
	for (int i = 0; i < 2; i++) {
		VkResult r2 = vkdev_image_create(r->dev, sw, sh, 1, 1, VK_FORMAT_R16G16B16A16_SFLOAT,
						 VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
						 VK_IMAGE_ASPECT_COLOR_BIT, false, "amss sub-pixel buffer", &s->sub[i]);
		if (r2)
			return render_vk_error(err, err_size, "amss sub-pixel buffer", r2);
		r2 = vkdev_image_create(r->dev, amss ? sw : 1, amss ? sh : 1, 1, 1, VK_FORMAT_R32_UINT,
					VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
					false, "amss sub-pixel age", &s->age[i]);
		if (r2)
			return render_vk_error(err, err_size, "amss sub-pixel age", r2);
	}
	bool warp = v->mode == VREUSE_WARP, rrc = v->mode == VREUSE_RRC_RANDOM || v->mode == VREUSE_RRC_INTERLEAVED;
	bool two_recs = rrc || stu; /* the cache record read (the previous frame's) and the one written, swapped */
	VkResult rc2 = vkdev_image_create(r->dev, two_recs ? r->desc.width : 1, two_recs ? r->desc.height : 1, 1, 1,
					  rec_format, VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
					  VK_IMAGE_ASPECT_COLOR_BIT, false, "vreuse cache record 2", &s->cache_rec2);
	if (rc2)
		return render_vk_error(err, err_size, "vreuse cache record 2", rc2);
	/* every method looks up through the reprojecting visibility pass (its record) */
	VkResult rv = vkdev_image_create(r->dev, r->desc.width, r->desc.height, 1, 1,
					 VK_FORMAT_R32G32B32A32_UINT, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT |
						 VK_IMAGE_USAGE_TRANSFER_DST_BIT,
					 VK_IMAGE_ASPECT_COLOR_BIT, false, "vreuse visibility record", &s->vis);
	if (rv)
		return render_vk_error(err, err_size, "vreuse visibility record", rv);
	/* stu's surface images (colour attachments of the visibility pass) */
	const char *const surf_name[2] = {"stu positions", "stu normals"};
	vkdev_image *surf[2] = {&s->spos, &s->snrm};
	for (int i = 0; i < 2; i++) {
		VkResult r3 = vkdev_image_create(r->dev, stu ? w : 1, stu ? h : 1, 1, 1, VK_FORMAT_R32G32B32A32_UINT,
						 VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT |
							 VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
						 VK_IMAGE_ASPECT_COLOR_BIT, false, surf_name[i], surf[i]);
		if (r3)
			return render_vk_error(err, err_size, surf_name[i], r3);
	}
	/* pyr: warp's pull-push pyramid, levels 1 up to 1x1 (level 0, the frame, is never stored: vreuse.glsl); one
	 * texel for the others */
	VkDeviceSize texels = 1;
	if (warp)
		for (texels = 0; w > 1 || h > 1;) {
			w = (w + 1) / 2, h = (h + 1) / 2;
			texels += (VkDeviceSize)w * h;
		}
	texels = texels ? texels : 1;
	VkDevice d = r->dev->device;
	if ((rc = render_storage_buffer(r, texels * 16, 0, false, "warp's pull-push pyramid", &s->pyr, err, err_size)))
		return rc;
	VkResult res;
	VkDescriptorSetLayoutBinding b[VREUSE_BINDINGS];
	for (uint32_t i = 0; i < VREUSE_BINDINGS; i++)
		b[i] = (VkDescriptorSetLayoutBinding){i, i == 4 ? VK_DESCRIPTOR_TYPE_STORAGE_BUFFER
							: VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
						      1, VK_SHADER_STAGE_COMPUTE_BIT, NULL};
	VkDescriptorSetLayoutCreateInfo li = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
					      .bindingCount = VREUSE_BINDINGS, .pBindings = b};
	if ((res = vkCreateDescriptorSetLayout(d, &li, NULL, &s->set_layout)))
		return render_vk_error(err, err_size, "vreuse: descriptor set layout", res);
	VkDescriptorSetLayout two[2] = {s->set_layout, s->set_layout};
	VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
					  .descriptorPool = r->pool, .descriptorSetCount = 2, .pSetLayouts = two};
	if ((res = vkAllocateDescriptorSets(d, &ai, s->set)))
		return render_vk_error(err, err_size, "vreuse: descriptor set", res);
	for (int i = 0; i < 2; i++) { /* set i: sub[i] is this frame's buffer, sub[1 - i] the previous frame's; rrc, stu:
				       * the cache recs[1 - i] is read, recs[i] written (cache_next) */
		const vkdev_image *recs[2] = {&s->cache_rec, two_recs ? &s->cache_rec2 : &s->cache_rec};
		const vkdev_image *imgs[VREUSE_BINDINGS] = {&s->cache_col, recs[1 - i], &s->rec_new, &s->flag, NULL,
							    &s->sub[1 - i], &s->sub[i], &s->vis, recs[i],
							    &s->age[1 - i], &s->age[i], &s->snrm, &s->spos};
		const vkdev_buffer *bufs[VREUSE_BINDINGS] = {NULL, NULL, NULL, NULL, &s->pyr};
		vkdev_write_storage_set(d, s->set[i], VREUSE_BINDINGS, bufs, imgs);
	}
	VkDescriptorSetLayout sets[3] = {r->scene_set_layout, s->p.set_layout, s->set_layout};
	VkPushConstantRange pcr = {VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(gpu_push)};
	VkPipelineLayoutCreateInfo pli = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 3,
					  .pSetLayouts = sets, .pushConstantRangeCount = 1, .pPushConstantRanges = &pcr};
	if ((res = vkCreatePipelineLayout(d, &pli, NULL, &s->layout)))
		return render_vk_error(err, err_size, "vreuse: pipeline layout", res);
	if ((rc = make_compute(r, s, "vreuse/decide.comp.in", &s->decide, err, err_size)) ||
	    (!stu && (rc = make_compute(r, s, "vreuse/resolve.comp.in", &s->resolve, err, err_size))) ||
	    (rc = make_compute(r, s, "vreuse/pull.comp.in", &s->pull, err, err_size)) ||
	    (rc = make_compute(r, s, "vreuse/push.comp.in", &s->push, err, err_size)) ||
	    (rc = make_compute_x(r, s, "vreuse/push.comp.in", "#define FILL_ARGS 1\n", &s->fill_args, err, err_size)))
		return rc;
	if ((rc = make_vis_pipelines(r, s, err, err_size)))
		return rc;
	if (rrc && (rc = vbuf_make_compute(r, &s->p, "vbuf/shade.comp.in", "#define VBUF_TO_HDR 1\n", &s->hshade, err,
					   err_size)))
		return rc;
	if (amss && ((rc = make_compute(r, s, "vreuse/amss.comp.in", &s->amss, err, err_size)) ||
		     (rc = vbuf_make_compute(r, &s->p, "vbuf/shade.comp.in", "#define VBUF_JITTER 1\n", &s->jshade, err,
					     err_size))))
		return rc;
	if (stu && ((rc = make_compute_x(r, s, "vreuse/stu.comp.in", "#define STU_G 1\n", &s->stu_g, err, err_size)) ||
		    (rc = make_compute_x(r, s, "vreuse/stu.comp.in",
					 render_compute_ballot(r->dev->physical) ? "#define TL_SUBGROUP 1\n" : "", &s->stu, err,
					 err_size))))
		return rc;
	/* the cache starts empty (object 0) in GENERAL layout */
	VkCommandBuffer cmd;
	if ((res = vkdev_cmd_begin(r->dev, &cmd)))
		return render_vk_error(err, err_size, "command buffer", res);
	VkClearColorValue zero = {{0}};
	VkImageSubresourceRange range = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
	const vkdev_image *im[12] = {&s->cache_col, &s->cache_rec, &s->rec_new,    &s->flag,   &s->sub[0], &s->sub[1],
				     &s->vis,       &s->cache_rec2, &s->age[0], &s->age[1], &s->spos,   &s->snrm};
	for (int i = 0; i < 12; i++) {
		vkdev_barrier_image(cmd, im[i], VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
				    VK_PIPELINE_STAGE_2_NONE, 0, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
		vkCmdClearColorImage(cmd, im[i]->image, VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &range);
	}
	vbuf_barrier(cmd);
	if ((res = vkdev_cmd_submit_wait(r->dev, cmd)))
		return render_vk_error(err, err_size, "vreuse setup", res);
	return TL_OK;
}

int vreuse_prepare(render *r, uint32_t frame, char *err, size_t err_size)
{
	vreuse_state *s = state_of(r);
	bool consecutive = s->last_frame >= 0 && (int64_t)frame == s->last_frame + 1;
	double fps = (double)r->desc.fps;
	render_update_state(r, 0, (double)frame / fps);
	if (s->v.mode == VREUSE_WARP) {
		/* [S] sec. 5.7: shade fully when t mod N = 0; the first frame of a run (or after a jump) has no keyframe
		 * to extrapolate from and is shaded too [P] */
		s->key = frame % s->v.period == 0 || !consecutive;
		if (s->key)
			s->key_frame = frame;
		render_update_state(r, 1, (double)s->key_frame / fps);
		s->shadows = s->key || r->blend_count; /* BLEND surfaces are shaded every frame */
		if (!s->shadows && s->v.truth) { /* the truth shades frame t: its shadow maps, in the truth interval */
			s->last_frame = frame;
			return render_shadow_plan(r, 0, err, err_size);
		}
	} else {
		s->have_cache = consecutive;
		s->parity ^= 1u;
		render_update_state(r, 1, (double)(frame ? frame - 1 : 0) / fps);
		s->shadows = true;
	}
	s->last_frame = frame;
	return s->shadows ? render_shadow_plan(r, 0, err, err_size) : TL_OK;
}

static void bind(render *r, vreuse_state *s, VkCommandBuffer cmd, VkPipeline pipe, const uint32_t aux[4])
{
	VkDescriptorSet sets[3] = {r->scene_set, s->p.set, s->set[s->parity]};
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe);
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s->layout, 0, 3, sets, 0, NULL);
	gpu_push pc = {0, 0, (uint32_t)r->scene->object_count, 0, {aux[0], aux[1], aux[2], aux[3]}};
	vkCmdPushConstants(cmd, s->layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof pc, &pc);
}

static void dispatch_pixels(render *r, VkCommandBuffer cmd)
{
	vkCmdDispatch(cmd, (r->desc.width + 7) / 8, (r->desc.height + 7) / 8, 1);
}

static void clear_to_sky(render *r, VkCommandBuffer cmd)
{
	const scene *sc = r->scene;
	VkClearColorValue sky = {{sc->sky[0] * sc->exposure, sc->sky[1] * sc->exposure, sc->sky[2] * sc->exposure, 0.0f}};
	VkImageSubresourceRange range = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
	vkCmdClearColorImage(cmd, r->hdr.image, VK_IMAGE_LAYOUT_GENERAL, &sky, 1, &range);
	vbuf_barrier(cmd);
}

/* The per-pixel pass over the ids: reprojection, decision, appends, the record of this frame (decide.comp.in). */
static void clear_image(VkCommandBuffer cmd, const vkdev_image *im)
{
	VkClearColorValue zero = {{0}};
	VkImageSubresourceRange range = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
	vkCmdClearColorImage(cmd, im->image, VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &range);
	vbuf_barrier(cmd);
}

static bool is_rrc(const vreuse_state *s)
{
	return s->v.mode == VREUSE_RRC_RANDOM || s->v.mode == VREUSE_RRC_INTERLEAVED;
}

static void record_decide(render *r, vreuse_state *s, VkCommandBuffer cmd, uint32_t frame, uint32_t flags)
{
	uint32_t aux[4] = {1, flags, frame, s->v.period | s->v.group << 8};
	bind(r, s, cmd, s->decide, aux);
	if (s->v.mode == VREUSE_AMSS)
		dispatch_pixels(r, cmd);
	else /* rrc variants, stu: one invocation per 4x4 pixels (decide.comp.in) */
		vkCmdDispatch(cmd, (r->desc.width + 31) / 32, (r->desc.height + 31) / 32, 1);
	vbuf_barrier(cmd);
	vbuf_bind(r, &s->p, cmd, s->p.args, 0, NULL);
	vkCmdDispatch(cmd, 1, 1, 1);
	vbuf_barrier(cmd);
}

/* The resolve: the cache := the frame's opaque values (before BLEND) and its record (resolve.comp.in); amss: the
 * shaded pixels' values into the HDR target first; rrc variants: the shaded pixels' texels only (decide stored the
 * reused ones, the shade wrote the HDR target); stu has none (stu.comp.in keeps its record). */
static void record_resolve(render *r, vreuse_state *s, VkCommandBuffer cmd)
{
	uint32_t aux[4] = {0, 0, 0, 0};
	bind(r, s, cmd, s->resolve, aux);
	if (is_rrc(s)) /* over the list of shaded samples (the shade's indirect arguments) */
		vkCmdDispatchIndirect(cmd, s->p.counters.buffer, 2 * sizeof(uint32_t));
	else
		dispatch_pixels(r, cmd);
	vbuf_barrier(cmd);
}

/* Pull-push ([S] sec. 3.3) into warp's holes, on the GPU's count of them: decide appended the holes to the list and
 * pulled levels 1 and 2; one dispatch writes the indirect arguments, the pull from level 3 up runs as one workgroup (none
 * when the frame has no hole) and the push runs over the hole list only (pull.comp.in, push.comp.in): no full-size
 * pass, and nothing launched on a frame without holes. */
static void record_fill(render *r, vreuse_state *s, VkCommandBuffer cmd)
{
	uint32_t aux[4] = {0, 0, 0, 0};
	bind(r, s, cmd, s->fill_args, aux);
	vkCmdDispatch(cmd, 1, 1, 1);
	vbuf_barrier(cmd);
	bind(r, s, cmd, s->pull, aux);
	vkCmdDispatchIndirect(cmd, s->p.counters.buffer, 11 * sizeof(uint32_t));
	vbuf_barrier(cmd);
	bind(r, s, cmd, s->push, aux);
	vkCmdDispatchIndirect(cmd, s->p.counters.buffer, 13 * sizeof(uint32_t));
	vbuf_barrier(cmd);
}

static void hdr_to_attachment(render *r, VkCommandBuffer cmd)
{
	vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL,
			    VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
			    VK_ACCESS_2_MEMORY_WRITE_BIT, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
			    VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
}

/* The "truth" interval (BASELINES.md section 0, left out of the frame time by render.c): with --truth, the path's
 * truth pass compares what the method shows (the HDR target before BLEND) with vref's shading of every covered
 * pixel of frame t. warp has no ids of frame t (its vis pass replaces them) and, on extrapolated frames, no shadow
 * maps of frame t: both are recorded here, so the frame's own intervals are those of the run without --truth. */
static void record_truth(render *r, vreuse_state *s, VkCommandBuffer cmd)
{
	render_ts(r, cmd);
	if (!s->v.truth) {
		hdr_to_attachment(r, cmd);
		return;
	}
	if (s->v.mode == VREUSE_WARP) {
		vbuf_barrier(cmd);
		if (!s->shadows)
			render_pass_shadows(r, cmd, 0);
		ids_pass_record(r, &s->p.ids, cmd, 0);
	}
	vbuf_barrier(cmd);
	vbuf_record_truth(r, &s->p, cmd);
}

static void record_rrc(render *r, vreuse_state *s, VkCommandBuffer cmd, uint32_t frame)
{
	vbuf_pass *p = &s->p;
	record_vis(r, s, cmd, 1); /* the ids (for the shading) and the lookup's record: the previous frame is slot 1 */
	vbuf_barrier(cmd);
	render_ts(r, cmd);
	clear_to_sky(r, cmd);
	/* the next cache (cache_next of set[parity]): decide writes the reused pixels' texels, resolve the shaded
	 * ones; the background stays 0 */
	clear_image(cmd, s->parity ? &s->cache_rec2 : &s->cache_rec);
	record_decide(r, s, cmd, frame, s->have_cache ? FLAG_HAVE_CACHE : 0);
	render_ts(r, cmd);
	vbuf_bind(r, p, cmd, s->hshade, 0, NULL); /* the path's indirect shade, into the HDR target */
	vkCmdDispatchIndirect(cmd, p->counters.buffer, 2 * sizeof(uint32_t));
	vbuf_barrier(cmd);
	render_ts(r, cmd);
	record_resolve(r, s, cmd);
	record_truth(r, s, cmd);
}

static void record_warp(render *r, vreuse_state *s, VkCommandBuffer cmd, uint32_t frame)
{
	if (s->key) { /* ref's shading (warp/1 is ref), its counter zeroed first, after the visibility pass */
		vkCmdFillBuffer(cmd, r->shade_count.buffer, 0, VK_WHOLE_SIZE, 0);
		vbuf_barrier(cmd);
		/* the depth pre-pass: the visibility pass leaves ref's depth (the same `precise` positions of the same
		 * triangles as common/scene.vert, the nearest surface kept; LESS_OR_EQUAL writes the values LESS does) and
		 * the keyframe's record beside it - one geometry pass for both */
		record_vis(r, s, cmd, 0);
		render_barrier(cmd, VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
			       VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
			       VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT);
	}
	render_ts(r, cmd);
	if (s->key) {
		render_pass_scene(r, cmd, 0, &(render_scene_pass){.pipe = &r->shade_pipe, .hdr = RENDER_HDR_CLEAR, .query = 1});
		vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
				    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
				    VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
				    VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
	} else { /* the frame's pipeline statistics: no shading pass, its compute passes */
		render_stats_begin(r, cmd);
	}
	render_ts(r, cmd);
	if (!s->key) /* (keyframes: above, as the depth pre-pass) */
		record_vis(r, s, cmd, 1);
	vbuf_barrier(cmd);
	render_ts(r, cmd);
	if (s->key) { /* the cache := the keyframe (the record from the vis pass) */
		record_resolve(r, s, cmd);
	} else {
		clear_to_sky(r, cmd); /* decide: one invocation per 4x4 pixels (decide.comp.in) */
		uint32_t aux[4] = {1, FLAG_HAVE_CACHE, frame, s->v.period};
		bind(r, s, cmd, s->decide, aux);
		vkCmdDispatch(cmd, (r->desc.width + 31) / 32, (r->desc.height + 31) / 32, 1);
		vbuf_barrier(cmd);
	}
	render_ts(r, cmd);
	if (!s->key) {
		record_fill(r, s, cmd);
		render_stats_end(r, cmd);
	}
	record_truth(r, s, cmd);
}

/* amss: every covered pixel shaded once at the frame's sub-pixel offset (k = t mod 4: (-1/4, -1/4), (+1/4, -1/4),
 * (-1/4, +1/4), (+1/4, +1/4)), then combined with the reprojected sub-pixel buffer (amss.comp.in), then stored. */
static void record_amss(render *r, vreuse_state *s, VkCommandBuffer cmd, uint32_t frame)
{
	vbuf_pass *p = &s->p;
	record_vis(r, s, cmd, 1); /* the ids (the jittered shading) and the record (decide, amss.comp.in) */
	vbuf_barrier(cmd);
	render_ts(r, cmd);
	clear_to_sky(r, cmd);
	record_decide(r, s, cmd, frame, s->have_cache ? FLAG_HAVE_CACHE : 0);
	render_ts(r, cmd);
	uint32_t k = frame % 4;
	float off[2] = {k & 1 ? 0.25f : -0.25f, k & 2 ? 0.25f : -0.25f};
	uint32_t jit[4] = {0, 0, 0, 0};
	memcpy(&jit[0], &off[0], 4);
	memcpy(&jit[1], &off[1], 4);
	vbuf_bind(r, p, cmd, s->jshade, 0, jit);
	vkCmdDispatchIndirect(cmd, p->counters.buffer, 2 * sizeof(uint32_t));
	vbuf_barrier(cmd);
	render_ts(r, cmd);
	uint32_t abits, ebits, bbits;
	memcpy(&abits, &s->v.alpha, 4);
	memcpy(&ebits, &s->v.bound, 4);
	memcpy(&bbits, &s->v.blur_bound, 4);
	uint32_t aux[4] = {bbits, abits, ebits, (s->have_cache ? 1u : 0u) | s->v.buffers << 1 | k << 4 | s->v.age_limit << 6};
	bind(r, s, cmd, s->amss, aux);
	dispatch_pixels(r, cmd);
	vbuf_barrier(cmd);
	record_resolve(r, s, cmd);
	record_truth(r, s, cmd);
}

/* stu: the phase pixels shaded, then the gradient at the phase pixels and the combination of the others. */
static void record_stu(render *r, vreuse_state *s, VkCommandBuffer cmd, uint32_t frame)
{
	vbuf_pass *p = &s->p;
	record_vis(r, s, cmd, 1); /* the ids (the shading, the windows) and the record (decide, the history) */
	vbuf_barrier(cmd);
	render_ts(r, cmd);
	clear_to_sky(r, cmd);
	record_decide(r, s, cmd, frame, s->have_cache ? FLAG_HAVE_CACHE : 0);
	render_ts(r, cmd);
	vbuf_record_shade(r, p, cmd, 0);
	render_ts(r, cmd);
	uint32_t aux[4] = {frame, s->v.period, 0, s->have_cache ? 1u : 0u};
	/* g at the phase pixels only: the shaded list, dispatched as the shade was (two display transforms a sample, which
	 * a branch in the per-pixel pass made every pixel pay on a SIMD CPU driver) */
	bind(r, s, cmd, s->stu_g, aux);
	vkCmdDispatchIndirect(cmd, p->counters.buffer, 2 * sizeof(uint32_t));
	vbuf_barrier(cmd);
	/* the output, the next frame's record and L (stu.comp.in): no resolve pass */
	bind(r, s, cmd, s->stu, aux);
	dispatch_pixels(r, cmd);
	vbuf_barrier(cmd);
	record_truth(r, s, cmd);
}

int vreuse_debug_surface(render *r, uint32_t *ids, uint32_t *pos, uint32_t *nrm, char *err, size_t err_size)
{
	vreuse_state *s = state_of(r);
	if (s->v.mode != VREUSE_STU)
		return tl_error(err, err_size, TL_ERR_ARG, "vreuse_debug_surface: not a stu render");
	int rc = ids_pass_copy(r, &s->p.ids, ids, false, err, err_size);
	if (!rc)
		rc = ids_image_copy(r, &s->spos, 0, pos, false, err, err_size);
	return rc ? rc : ids_image_copy(r, &s->snrm, 0, nrm, false, err, err_size);
}

void vreuse_record(render *r, VkCommandBuffer cmd, uint32_t frame)
{
	vreuse_state *s = state_of(r);
	vbuf_record_begin(r, &s->p, cmd);
	render_ts(r, cmd);
	if (s->shadows)
		render_pass_shadows(r, cmd, 0);
	render_ts(r, cmd);
	if (s->v.mode == VREUSE_WARP)
		record_warp(r, s, cmd, frame);
	else if (s->v.mode == VREUSE_AMSS)
		record_amss(r, s, cmd, frame);
	else if (s->v.mode == VREUSE_STU)
		record_stu(r, s, cmd, frame);
	else
		record_rrc(r, s, cmd, frame);
	render_ts(r, cmd);
	vbuf_record_finish(r, cmd);
}

static void put_extra(frame_stats *st, const char *name, double v)
{
	if (st->extra_count < FRAME_MAX_EXTRA) {
		st->extra_names[st->extra_count] = name;
		st->extra[st->extra_count++] = v;
	}
}

void vreuse_collect(render *r, frame_stats *st)
{
	vreuse_state *s = state_of(r);
	const uint32_t *c = s->p.counters.mapped;
	/* warp's key frames shade with ref's pass (its counter); every other shading runs on the path (its counter) */
	bool key = s->v.mode == VREUSE_WARP && s->key;
	st->shaded_samples = key ? (int64_t)*(const uint32_t *)r->shade_count.mapped : c[VBUF_C_SHADED];
	st->reused_samples = st->visible_samples >= 0 ? st->visible_samples - st->shaded_samples : -1;
	st->visible_units = st->visible_samples;
	st->shaded_units = st->shaded_samples;
	st->new_units = c[VBUF_C_METHOD]; /* cache misses (rrc: shaded; warp: holes; stu: no history) */
	st->late_samples = s->v.truth ? (int64_t)c[VBUF_C_LATE] : -1;
	put_extra(st, "filled_samples", (double)c[VBUF_C_FILLED]);
	put_extra(st, "listed_samples", (double)c[VBUF_C_LISTED]);
	put_extra(st, "key_frame", s->v.mode == VREUSE_WARP ? (double)key : NAN);
}

void vreuse_finish(render *r)
{
	vreuse_state *s = state_of(r);
	if (!s)
		return;
	VkDevice d = r->dev->device;
	VkPipeline pp[10] = {s->decide, s->resolve, s->pull, s->push, s->fill_args,
			     s->amss,   s->jshade,  s->stu_g, s->stu,  s->hshade};
	for (int i = 0; i < 10; i++)
		if (pp[i])
			vkDestroyPipeline(d, pp[i], NULL);
	if (s->layout)
		vkDestroyPipelineLayout(d, s->layout, NULL);
	if (s->set_layout)
		vkDestroyDescriptorSetLayout(d, s->set_layout, NULL);
	vkdev_image *im[12] = {&s->cache_col, &s->cache_rec, &s->rec_new,    &s->flag,   &s->sub[0], &s->sub[1],
			       &s->vis,       &s->cache_rec2, &s->age[0], &s->age[1], &s->spos,   &s->snrm};
	for (int i = 0; i < 12; i++)
		vkdev_image_destroy(r->dev, im[i]);
	render_pipeline_destroy(r, &s->vis_pipe);
	render_pipeline_destroy(r, &s->vis_pipe_mask);
	vkdev_buffer_destroy(r->dev, &s->pyr);
	vbuf_finish(r, &s->p);
	free(s);
	r->method_state = NULL;
}
