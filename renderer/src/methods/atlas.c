/* atlas.c — the shading atlas of sa, sau and tasa (atlas.h; TAS-METHODS sections 4-6, 8; [TAS] secs. 4.3, 5.1, 6.2).
 *
 * Frame t (state slot 0; frames in order, a jump starts over):
 *   shadow maps                                            (shared pass)
 *   ids      visibility pass (passes/ids.c, shared with the sample path): per pixel (object + 1, pid << 3 | side
 *            << 2 | rotation, barycentrics) — the exact visible set of step 1 (the pid looked up per vertex)
 *   visible  compute over pixels: visible[patch]; tasa: the 2x2 image-space max of last frame's gradients (step 2)
 *   alloc    CPU (between two submits): free the blocks of patches no longer visible or resized, allocate the new
 *            ones in ascending patch id (shelf + buddy, atlas_alloc.c), decide which blocks to shade (sa: all;
 *            sau: (t - t_alloc) mod N = 0; tasa: new, second frame, or F * age > T), build the work lists
 *   shade    compute over the selected blocks' texels (exact dispatch; reused blocks launch nothing); the oracle
 *            shades every block into a scratch atlas and commits whole blocks (commit.comp.in); --truth: the
 *            reused blocks shaded once more and compared
 *   resolve  compute over pixels: bilinear lookup in the pixel's block, into the HDR target cleared to the sky
 *   blend    glTF BLEND objects forward-shaded on top (depth from the visibility pass)
 *   display, readback
 * CPU-side state per patch: its block, level, the frame it was allocated and last shaded, its phase and gradient. */
#include "atlas.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "atlas_alloc.h"
#include "method_debug.h"
#include "taslab/tl_clock.h"

const char *const atlas_pass_names[ATLAS_PASS_COUNT] = {"shadow", "ids",     "visible", "alloc", "shade", "truth",
							 "resolve", "blend", "display", "readback"};

enum {
	B_CORNERS, B_TRIINFO, B_OBJINFO, B_BLOCKS, B_WORK, B_VISIBLE, B_G, B_F, B_GNEW, B_COUNTERS, B_DMAX, B_COUNT
};

typedef struct patch_state {
	uint32_t x, y;
	uint8_t lw, lh;      /* allocated block (log2 sides) */
	uint8_t req_lw, req_lh;   /* the levels asked for when it was allocated (lw, lh are smaller after an overflow) */
	uint8_t want_lw, want_lh;
	uint8_t allocated, facing, want_facing, phase; /* phase 0 new, 1 shaded once, 2 steady */
	uint8_t clamped, shade;
	uint32_t t_alloc, t_last;
	float G;             /* tasa: gradient of the last shading (code values per frame) */
} patch_state;

typedef struct atlas_state {
	atlas_variant v;
	atlas_patches patches;
	uint32_t patch_count;      /* global patches (per object instance) */
	uint32_t *patch_object;    /* per global patch: object */
	uint32_t *patch_mesh;      /* per global patch: mesh patch */
	patch_state *ps;
	atlas_alloc *alloc;
	uint32_t atlas_w, atlas_h;
	float rho;
	vkdev_buffer buf[B_COUNT];
	ids_pass ids[RENDER_MAX_VIEWS]; /* the visibility pass and its image, per eye (stereo: STEREO.md) */
	ids_multiview mv;          /* render.multiview: both eyes' visibility in one pass (ids[v] views of its layers) */
	vkdev_image atlas, scratch, shown; /* shown: tasa, display code values of the atlas (RG32UI, tas/disp.glsl) */
	bool subgroup;             /* tasa: per-chunk gradient maxima in the subgroup (TL_SUBGROUP) */
	size_t work_cap;           /* chunks */
	uint32_t shade_chunks, truth_chunks;
	VkDescriptorSetLayout set_layout;
	VkDescriptorSet set[RENDER_MAX_VIEWS]; /* per eye: its ids image and HDR target */
	uint32_t shade_slot;       /* the state slot the texels are shaded from (stereo: the centre eye's) */
	VkPipelineLayout comp_layout;
	VkPipeline visible_pipe, shade_pipe, commit_pipe, truth_pipe, resolve_pipe;
	int64_t last_frame;
	/* this frame's numbers */
	uint64_t allocated_blocks, allocated_texels, new_blocks, shaded_blocks, shaded_texels;
	uint64_t listed_texels;     /* texels on the shading work list (the oracle: every allocated one) */
	uint32_t overflow, clamped;
	double cpu_ms;
} atlas_state;

/* The visible pass (visible.comp.in): each invocation walks a block of VIS_W x VIS_H pixels in registers, 8x8
 * invocations a workgroup. Measured at 960x540 on calm / fan_shadow (2026-11-26, lavapipe, tasa@8's pass): 4x8
 * 3.85 ms, 8x8 3.68, 4x16 3.85, 2x8 4.70, 4x4 4.42, 8x4 4.80 (the previous 8x8 tile in shared memory: 11.1 ms);
 * 4x8 keeps 16k invocations at that size for devices that want many. */
enum { VIS_W = 4, VIS_H = 8 };

static atlas_state *state_of(render *r) { return r->method_state; }

static uint32_t log2_ceil(uint64_t v)
{
	uint32_t l = 0;
	while (((uint64_t)1 << l) < v)
		l++;
	return l;
}

/* ---- setup ---- */

static int make_patches(render *r, atlas_state *s, char *err, size_t err_size)
{
	const scene *sc = r->scene;
	int rc = atlas_patches_build(sc, &s->patches, err, err_size);
	if (rc)
		return rc;
	/* global patches: one set per opaque or masked object (BLEND objects are forward-shaded) */
	uint64_t total = 0;
	for (size_t o = 0; o < sc->object_count; o++) {
		const scene_object *ob = &sc->objects[o];
		if (ob->mesh >= 0 && sc->materials[ob->material].alpha_mode != SCENE_ALPHA_BLEND)
			total += s->patches.mesh_patch_base[ob->mesh + 1] - s->patches.mesh_patch_base[ob->mesh];
	}
	if (total >= (1u << 28))
		return tl_error(err, err_size, TL_ERR_UNSUPPORTED, "atlas: %llu patches, at most 2^28", (unsigned long long)total);
	s->patch_count = (uint32_t)total;
	size_t n = total ? total : 1;
	s->patch_object = malloc(n * sizeof *s->patch_object);
	s->patch_mesh = malloc(n * sizeof *s->patch_mesh);
	s->ps = calloc(n, sizeof *s->ps);
	if (!s->patch_object || !s->patch_mesh || !s->ps)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	uint32_t k = 0;
	for (size_t o = 0; o < sc->object_count; o++) {
		const scene_object *ob = &sc->objects[o];
		if (ob->mesh < 0 || sc->materials[ob->material].alpha_mode == SCENE_ALPHA_BLEND)
			continue;
		for (uint32_t p = s->patches.mesh_patch_base[ob->mesh]; p < s->patches.mesh_patch_base[ob->mesh + 1]; p++) {
			s->patch_object[k] = (uint32_t)o;
			s->patch_mesh[k++] = p;
		}
	}
	return TL_OK;
}

/* tasa proper (not its oracle) measures gradients while shading */
static bool tasa_gradients(const atlas_state *s) { return s->v.kind == ATLAS_TASA && !s->v.oracle; }

static int make_buffers(render *r, atlas_state *s, char *err, size_t err_size)
{
	const scene *sc = r->scene;
	size_t P = s->patch_count ? s->patch_count : 1, MP = s->patches.patch_total ? s->patches.patch_total : 1;
	size_t T = s->patches.tri_total ? s->patches.tri_total : 1;
	s->work_cap = (size_t)s->atlas_w * s->atlas_h / 8 + P + 8;
	const struct {
		VkDeviceSize size;
		const char *name;
	} spec[B_COUNT] = {
		[B_CORNERS] = {MP * 16, "atlas corners"}, [B_TRIINFO] = {T * 4, "atlas triangle info"},
		[B_OBJINFO] = {(sc->object_count ? sc->object_count : 1) * 32, "atlas object info"},
		[B_BLOCKS] = {P * 16, "atlas blocks"}, [B_WORK] = {s->work_cap * 8, "atlas work list"},
		[B_VISIBLE] = {P * 4, "atlas visible"}, [B_G] = {P * 4, "atlas G"}, [B_F] = {P * 4, "atlas F"},
		[B_GNEW] = {P * 4, "atlas G new"}, [B_COUNTERS] = {32, "atlas counters"}, [B_DMAX] = {P * 4, "atlas dmax"},
	};
	for (int i = 0; i < B_COUNT; i++) {
		int rc = render_storage_buffer(r, spec[i].size, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true, spec[i].name,
					       &s->buf[i], err, err_size);
		if (rc)
			return rc;
	}
	/* static tables: corners with the mesh's vertex offset (global vertex indices), triangle info, objects */
	uint32_t *c = s->buf[B_CORNERS].mapped;
	for (size_t m = 0; m < s->patches.mesh_count; m++)
		for (uint32_t p = s->patches.mesh_patch_base[m]; p < s->patches.mesh_patch_base[m + 1]; p++)
			for (int k = 0; k < 4; k++) {
				uint32_t v = s->patches.corners[4 * p + k];
				c[4 * p + k] = v == ATLAS_SINGLE ? v : v + r->mesh_vertex_offset[m];
			}
	if (s->patches.tri_total)
		memcpy(s->buf[B_TRIINFO].mapped, s->patches.tri_info, s->patches.tri_total * 4);
	uint32_t *oi = s->buf[B_OBJINFO].mapped, base = 0;
	for (size_t o = 0; o < sc->object_count; o++) {
		const scene_object *ob = &sc->objects[o];
		uint32_t *e = oi + 8 * o;
		memset(e, 0, 32);
		if (ob->mesh < 0)
			continue;
		bool has = sc->materials[ob->material].alpha_mode != SCENE_ALPHA_BLEND;
		e[0] = base, e[1] = s->patches.mesh_patch_base[ob->mesh], e[2] = s->patches.mesh_tri_base[ob->mesh], e[3] = has;
		if (has)
			base += s->patches.mesh_patch_base[ob->mesh + 1] - s->patches.mesh_patch_base[ob->mesh];
	}
	VkResult res;
	if ((res = vkdev_image_create(r->dev, s->atlas_w, s->atlas_h, 1, 1, VK_FORMAT_R16G16B16A16_SFLOAT,
				      VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
				      false, "atlas", &s->atlas)) ||
	    (res = vkdev_image_create(r->dev, s->v.oracle ? s->atlas_w : 1, s->v.oracle ? s->atlas_h : 1, 1, 1,
				      VK_FORMAT_R16G16B16A16_SFLOAT, VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
				      VK_IMAGE_ASPECT_COLOR_BIT, false, "atlas scratch", &s->scratch)) ||
	    (res = vkdev_image_create(r->dev, tasa_gradients(s) ? s->atlas_w : 1, tasa_gradients(s) ? s->atlas_h : 1, 1, 1,
				      VK_FORMAT_R32G32_UINT, VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
				      VK_IMAGE_ASPECT_COLOR_BIT, false, "atlas shown", &s->shown)))
		return render_vk_error(err, err_size, "atlas images", res);
	return TL_OK;
}

/* The method's descriptor set (atlas.glsl): storage buffers, and images at 12-15 and 17. */
enum { ATLAS_BINDINGS = 18 };
static bool is_image_binding(uint32_t i) { return (i >= 12 && i <= 15) || i == 17; }

static int make_set(render *r, atlas_state *s, uint32_t v, char *err, size_t err_size)
{
	VkDevice d = r->dev->device;
	VkShaderStageFlags st = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT | VK_SHADER_STAGE_COMPUTE_BIT;
	VkDescriptorSetLayoutBinding b[ATLAS_BINDINGS];
	for (uint32_t i = 0; i < ATLAS_BINDINGS; i++)
		b[i] = (VkDescriptorSetLayoutBinding){i, is_image_binding(i) ? VK_DESCRIPTOR_TYPE_STORAGE_IMAGE
								 : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
						      1, st, NULL};
	VkDescriptorSetLayoutCreateInfo li = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
					      .bindingCount = ATLAS_BINDINGS, .pBindings = b};
	VkResult res;
	if (!s->set_layout && (res = vkCreateDescriptorSetLayout(d, &li, NULL, &s->set_layout)))
		return render_vk_error(err, err_size, "atlas: descriptor set layout", res);
	VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
					  .descriptorPool = r->pool, .descriptorSetCount = 1, .pSetLayouts = &s->set_layout};
	if ((res = vkAllocateDescriptorSets(d, &ai, &s->set[v])))
		return render_vk_error(err, err_size, "atlas: descriptor set", res);
	/* bindings 0-9, 11: our buffers; 10 vertices, 16 indices (the scene's); 12-15 and 17 images */
	const vkdev_buffer *bufs[ATLAS_BINDINGS] = {&s->buf[B_CORNERS], &s->buf[B_TRIINFO], &s->buf[B_OBJINFO], &s->buf[B_BLOCKS],
					&s->buf[B_WORK],    &s->buf[B_VISIBLE], &s->buf[B_G],       &s->buf[B_F],
					&s->buf[B_GNEW],    &s->buf[B_COUNTERS], &r->vertices,      &s->buf[B_DMAX],
					NULL, NULL, NULL, NULL, &r->indices, NULL};
	const vkdev_image *imgs[ATLAS_BINDINGS] = {[12] = &s->ids[v].image, [13] = &s->atlas, [14] = &s->scratch, [15] = &r->hdr,
						   [17] = &s->shown};
	vkdev_write_storage_set(d, s->set[v], ATLAS_BINDINGS, bufs, imgs);
	return TL_OK;
}

static int make_compute(render *r, atlas_state *s, const char *path, const char *defs, VkPipeline *out, char *err,
			size_t err_size)
{
	return render_compute_defs(r, path, defs, s->comp_layout, out, err, err_size);
}

static int make_pipelines(render *r, atlas_state *s, char *err, size_t err_size)
{
	VkDescriptorSetLayout sets[2] = {r->scene_set_layout, s->set_layout};
	VkPushConstantRange pcr = {VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(gpu_push)};
	VkPipelineLayoutCreateInfo li = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 2,
					 .pSetLayouts = sets, .pushConstantRangeCount = 1, .pPushConstantRanges = &pcr};
	VkResult res = vkCreatePipelineLayout(r->dev->device, &li, NULL, &s->comp_layout);
	if (res)
		return render_vk_error(err, err_size, "atlas: pipeline layout", res);
	int rc;
	char defs[256];
	/* TASLAB_ATLAS_DEBUG=positions (diagnostic, README "Shading atlas"): texels hold their object-space position */
	const char *dbg = getenv("TASLAB_ATLAS_DEBUG");
	char vdefs[64];
	snprintf(vdefs, sizeof vdefs, "#define VIS_W %d\n#define VIS_H %d\n", VIS_W, VIS_H);
	snprintf(defs, sizeof defs, "%s%s%s%s%s%s%s", vdefs, tasa_gradients(s) ? "#define TASA 1\n" : "",
		 s->v.oracle ? "#define ORACLE 1\n" : "", s->v.truth ? "#define TRUTH 1\n" : "",
		 s->v.lod0 ? "#define TL_TEXTURE_LOD0 1\n" : "", s->subgroup ? "#define TL_SUBGROUP 1\n" : "",
		 dbg && !strcmp(dbg, "positions") ? "#define ATLAS_DEBUG_POSITIONS 1\n" : "");
	if ((rc = make_compute(r, s, "atlas/visible.comp.in", defs, &s->visible_pipe, err, err_size)) ||
	    (rc = make_compute(r, s, "atlas/shade.comp.in", defs, &s->shade_pipe, err, err_size)) ||
	    (rc = make_compute(r, s, "atlas/resolve.comp.in", defs, &s->resolve_pipe, err, err_size)))
		return rc;
	if (s->v.oracle && (rc = make_compute(r, s, "atlas/commit.comp.in", defs, &s->commit_pipe, err, err_size)))
		return rc;
	if (s->v.truth && !s->v.oracle && (rc = make_compute(r, s, "atlas/truth.comp.in", defs, &s->truth_pipe, err, err_size)))
		return rc;
	return TL_OK;
}

/* Arithmetic and vote subgroup operations in compute shaders (lavapipe: yes, subgroups of 8). Without them, or with
 * TASLAB_ATLAS_ATOMICS=1 in the environment (test_atlas compares the two), the gradients are reduced with one atomic
 * per texel: the same result, slower. */
static bool has_subgroup_reduction(VkPhysicalDevice pd)
{
	const char *force = getenv("TASLAB_ATLAS_ATOMICS");
	if (force && strcmp(force, "1") == 0)
		return false;
	VkSubgroupFeatureFlags need = VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_ARITHMETIC_BIT |
				      VK_SUBGROUP_FEATURE_VOTE_BIT;
	return render_subgroup_has(pd, VK_SHADER_STAGE_COMPUTE_BIT, need);
}

/* TAS-METHODS section 4: "record s, rho, lmax, hysteresis in the manifest" — s and lmax are options; these are what
 * they became at this frame size. */
size_t atlas_derived(const render *r, run_option *out, size_t max)
{
	const atlas_state *s = r->method_state;
	const run_option v[] = {
		{.key = "atlas_width", .type = RUN_VALUE_INTEGER, .number = s->atlas_w},
		{.key = "atlas_height", .type = RUN_VALUE_INTEGER, .number = s->atlas_h},
		{.key = "atlas_density", .type = RUN_VALUE_NUMBER, .number = s->rho},
		{.key = "hysteresis_below", .type = RUN_VALUE_NUMBER, .number = ATLAS_HYSTERESIS_BELOW},
		{.key = "hysteresis_above", .type = RUN_VALUE_NUMBER, .number = ATLAS_HYSTERESIS_ABOVE},
	};
	size_t n = sizeof v / sizeof v[0] < max ? sizeof v / sizeof v[0] : max;
	memcpy(out, v, n * sizeof *out);
	return n;
}

int atlas_init(render *r, const atlas_variant *v, char *err, size_t err_size)
{
	atlas_state *s = calloc(1, sizeof *s);
	if (!s)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	r->method_state = s;
	s->v = *v;
	s->last_frame = -1;
	/* the smallest power-of-two rectangle (w = h or 2h) of at least scale x output pixels */
	double texels = (double)v->scale * r->desc.width * r->desc.height;
	uint32_t l = log2_ceil((uint64_t)ceil(texels));
	if (l < 2)
		l = 2;
	if (l > 28)
		return tl_error(err, err_size, TL_ERR_ARG,
				"--atlas-scale %g at %ux%u needs a %.0f-texel atlas, more than 2^28: lower --atlas-scale or --size",
				(double)v->scale, r->desc.width, r->desc.height, texels);
	s->atlas_w = 1u << ((l + 1) / 2);
	s->atlas_h = 1u << (l / 2);
	if (s->atlas_w > 16384)
		return tl_error(err, err_size, TL_ERR_ARG, "--atlas-scale %g: atlas %ux%u exceeds 16384 texels per side",
				(double)v->scale, s->atlas_w, s->atlas_h);
	s->rho = v->density > 0.0f ? v->density : sqrtf(v->scale / 8.0f);
	s->subgroup = tasa_gradients(s) && has_subgroup_reduction(r->dev->physical);
	int rc = make_patches(r, s, err, err_size);
	if (!rc)
		rc = atlas_alloc_create(s->atlas_w, s->atlas_h, &s->alloc, err, err_size);
	if (!rc)
		rc = make_buffers(r, s, err, err_size);
	/* per eye (stereo): the visibility pass's image and the set binding it and the eye's HDR target */
	/* the ids pass writes each pixel's pid (ids.h ids_patches): looked up per vertex, not per pixel in the passes */
	ids_patches pt = {&s->buf[B_OBJINFO], &s->buf[B_TRIINFO]};
	if (!rc && r->multiview)
		rc = ids_multiview_init(r, &s->mv, s->ids, &pt, err, err_size);
	for (uint32_t v = 0; !rc && v < r->view_count; v++) {
		render_use_view(r, v);
		if (!r->multiview)
			rc = ids_pass_init(r, &s->ids[v], &pt, err, err_size);
		if (!rc)
			rc = make_set(r, s, v, err, err_size);
	}
	render_use_view(r, 0);
	if (!rc)
		rc = make_pipelines(r, s, err, err_size);
	if (rc)
		return rc;
	VkCommandBuffer cmd;
	VkResult res = vkdev_cmd_begin(r->dev, &cmd);
	if (res)
		return render_vk_error(err, err_size, "command buffer", res);
	VkClearColorValue zero = {{0}};
	VkImageSubresourceRange range = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
	const vkdev_image *im[3] = {&s->atlas, &s->scratch, &s->shown};
	for (int i = 0; i < 3; i++) {
		vkdev_barrier_image(cmd, im[i], VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
				    VK_PIPELINE_STAGE_2_NONE, 0, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
		vkCmdClearColorImage(cmd, im[i]->image, VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &range);
	}
	render_barrier(cmd, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
		       VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
	if ((res = vkdev_cmd_submit_wait(r->dev, cmd)))
		return render_vk_error(err, err_size, "atlas setup", res);
	return TL_OK;
}

/* ---- frame ---- */

/* Desired block levels and facing of every patch at this frame's view (the sizes of step 2 come from the
 * projected edges; patches that turn out invisible ignore them). Gradients of patches that will be (re)allocated
 * are zeroed before the 2x2 filter reads them: new blocks contribute G = 0. */
static void plan_levels(render *r, atlas_state *s)
{
	const scene *sc = r->scene;
	/* stereo (STEREO.md): one block for both eyes, its level from the larger projected edge over the eyes; the
	 * facing as the shading sees it, from the shading slot's eye (the centre eye) */
	tlm_mat4 vps[RENDER_MAX_VIEWS];
	for (uint32_t v = 0; v < r->view_count; v++) {
		render_use_view(r, v);
		memcpy(vps[v].m, ((const gpu_frame_state *)r->states.mapped)->view_proj, sizeof vps[v].m);
	}
	render_use_view(r, 0);
	const float *ce = ((const gpu_frame_state *)r->states.mapped + s->shade_slot)->camera_time;
	tlm_vec3 shade_eye = tlm_v3(ce[0], ce[1], ce[2]);
	float *G = s->buf[B_G].mapped;
	for (uint32_t p = 0; p < s->patch_count; p++) {
		patch_state *q = &s->ps[p];
		uint32_t o = s->patch_object[p], mp = s->patch_mesh[p];
		const scene_mesh *m = &sc->meshes[sc->objects[o].mesh];
		const uint32_t *c = s->patches.corners + 4 * (size_t)mp;
		bool single = c[3] == ATLAS_SINGLE;
		float lu = 0.0f, lv = 0.0f;
		tlm_vec3 w[4];
		for (uint32_t v = 0; v < r->view_count; v++) {
			tlm_mat4 mvp = tlm_mat4_mul(vps[v], r->world[o]);
			float clip[16] = {0};
			for (int k = 0; k < (single ? 3 : 4); k++) {
				const float *pos = m->vertices[c[k]].position;
				w[k] = tlm_mat4_mul_point(r->world[o], tlm_v3(pos[0], pos[1], pos[2]));
				for (int row = 0; row < 4; row++)
					clip[4 * k + row] = mvp.m[row] * pos[0] + mvp.m[4 + row] * pos[1] + mvp.m[8 + row] * pos[2] + mvp.m[12 + row];
			}
			float eu, ev;
			atlas_edge_lengths(clip, single, r->desc.width, r->desc.height, &eu, &ev);
			lu = fmaxf(lu, eu);
			lv = fmaxf(lv, ev);
		}
		bool cu, cv;
		q->want_lw = (uint8_t)atlas_level(lu, s->rho, s->v.lmax, q->allocated ? q->req_lw : 0, &cu);
		q->want_lh = (uint8_t)atlas_level(lv, s->rho, s->v.lmax, q->allocated ? q->req_lh : 0, &cv);
		q->clamped = cu || cv;
		/* facing of triangle A as seen from the eye (a double-sided patch turning around is new); a mirrored
		 * object's front faces wind clockwise (glTF 2.0 §3.7.2.1), as the rasterizer and atlas_shade.glsl take it;
		 * r->mirrored is the flag of r->world used above (state.c computes both together), read from the CPU's
		 * array rather than per patch from the mapped object ring (uncached memory on a discrete GPU) */
		tlm_vec3 n = tlm_v3_cross(tlm_v3_sub(w[1], w[0]), tlm_v3_sub(w[2], w[0]));
		q->want_facing = (tlm_v3_dot(n, tlm_v3_sub(shade_eye, w[0])) > 0.0f) != (r->mirrored[o] != 0);
		bool keeps = q->allocated && q->want_lw == q->req_lw && q->want_lh == q->req_lh && q->want_facing == q->facing;
		G[p] = keeps && q->phase == 2 ? q->G : 0.0f;
	}
}

int atlas_prepare(render *r, uint32_t frame, char *err, size_t err_size)
{
	atlas_state *s = state_of(r);
	double t = (double)frame / (double)r->desc.fps;
	render_update_state(r, 0, t);
	int rc = render_shadow_plan(r, 0, err, err_size);
	if (rc)
		return rc;
	render_share_shadows(r, 0); /* stereo: the other eye's slot maps the same shadow layers (rendered once) */
	s->shade_slot = r->view_count > 1 ? render_center_slot(r, 0, t) : 0;
	if (!(s->last_frame >= 0 && (int64_t)frame == s->last_frame + 1)) {
		/* first frame or a jump: everything starts over */
		for (uint32_t p = 0; p < s->patch_count; p++) {
			patch_state *q = &s->ps[p];
			if (q->allocated)
				atlas_alloc_free(s->alloc, q->x, q->y, q->lw, q->lh);
			memset(q, 0, sizeof *q);
		}
	}
	plan_levels(r, s);
	return TL_OK;
}

static void barrier_compute(VkCommandBuffer cmd)
{
	VkPipelineStageFlags2 st = VK_PIPELINE_STAGE_2_ALL_GRAPHICS_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT |
				   VK_PIPELINE_STAGE_2_TRANSFER_BIT | VK_PIPELINE_STAGE_2_HOST_BIT;
	render_barrier(cmd, st, VK_ACCESS_2_MEMORY_WRITE_BIT, st, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
}

static void bind_compute(render *r, atlas_state *s, VkCommandBuffer cmd, VkPipeline p, uint32_t a0, uint32_t a1, uint32_t a2,
			 uint32_t a3)
{
	/* the active eye's scene and atlas sets; the shading runs from the shading slot (stereo: the centre eye) */
	VkDescriptorSet sets[2] = {r->scene_set, s->set[r->view]};
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p);
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, s->comp_layout, 0, 2, sets, 0, NULL);
	uint32_t slot = p == s->shade_pipe || p == s->truth_pipe ? s->shade_slot : 0;
	gpu_push pc = {slot, 0, (uint32_t)r->scene->object_count, 0, {a0, a1, a2, a3}};
	vkCmdPushConstants(cmd, s->comp_layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof pc, &pc);
}

static void dispatch_visible(VkCommandBuffer cmd, uint32_t w, uint32_t h)
{
	uint32_t bx = (w + VIS_W - 1) / VIS_W, by = (h + VIS_H - 1) / VIS_H;
	vkCmdDispatch(cmd, (bx + 7) / 8, (by + 7) / 8, 1);
}

/* Work-list dispatch: workgroups of 64 invocations = 8 chunks of 8 texels, a 2-D grid within the 65 535 limit (as
 * few rows as fit, the groups spread evenly over them: at most gy - 1 empty workgroups). */
static void dispatch_chunks(VkCommandBuffer cmd, uint32_t chunks)
{
	uint32_t groups = (chunks + 7) / 8, gy = (groups + 65534) / 65535, gx = gy ? (groups + gy - 1) / gy : 0;
	if (groups)
		vkCmdDispatch(cmd, gx, gy, 1);
}

void atlas_record_pre(render *r, VkCommandBuffer cmd, uint32_t frame)
{
	(void)frame;
	atlas_state *s = state_of(r);
	uint32_t w = r->desc.width, h = r->desc.height;
	vkCmdFillBuffer(cmd, s->buf[B_VISIBLE].buffer, 0, VK_WHOLE_SIZE, 0);
	vkCmdFillBuffer(cmd, s->buf[B_F].buffer, 0, VK_WHOLE_SIZE, 0);
	/* the HDR target is bound in the method's descriptor set (resolve writes it): GENERAL from here on */
	for (uint32_t v = 0; v < r->view_count; v++) {
		render_use_view(r, v);
		vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
				    VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT, VK_PIPELINE_STAGE_2_CLEAR_BIT,
				    VK_ACCESS_2_TRANSFER_WRITE_BIT);
	}
	render_use_view(r, 0);
	barrier_compute(cmd);
	render_ts(r, cmd);
	render_pass_shadows(r, cmd, 0);
	render_ts(r, cmd);
	/* stereo: each eye's visibility pass; the visible sets and the 2x2 filter's F of both eyes go into the shared
	 * buffers (visible: bit v per eye; F: atomicMax over both eyes' windows) */
	for (uint32_t v = 0; v < r->view_count && !r->multiview; v++) {
		render_use_view(r, v);
		ids_pass_record(r, &s->ids[v], cmd, 0);
	}
	render_use_view(r, 0);
	if (r->multiview) /* both eyes in one viewMask 0b11 pass (README "Multiview") */
		ids_multiview_record(r, &s->mv, cmd, 0);
	render_ts(r, cmd);
	for (uint32_t v = 0; v < r->view_count; v++) {
		render_use_view(r, v);
		bind_compute(r, s, cmd, s->visible_pipe, v, 0, 0, 0);
		dispatch_visible(cmd, w, h);
	}
	render_use_view(r, 0);
	barrier_compute(cmd);
	render_ts(r, cmd);
}

/* Frees a patch's block; it is new when it next becomes visible. */
static void release(atlas_state *s, patch_state *q)
{
	atlas_alloc_free(s->alloc, q->x, q->y, q->lw, q->lh);
	q->allocated = 0;
	q->phase = 0;
	q->G = 0.0f;
}

int atlas_cpu_step(render *r, uint32_t frame, char *err, size_t err_size)
{
	atlas_state *s = state_of(r);
	double t0 = tl_clock_s();
	const uint32_t *vis = s->buf[B_VISIBLE].mapped;
	const float *F = s->buf[B_F].mapped;
	s->allocated_blocks = s->allocated_texels = s->new_blocks = s->shaded_blocks = s->shaded_texels = 0;
	s->listed_texels = 0;
	s->overflow = s->clamped = 0;
	/* 1-2: free the blocks of patches no longer visible, resized or turned around. "Resized" compares with the size
	 * the patch asked for: a block made smaller by an overflow (step 3) stays while that request stays the same —
	 * comparing with the block's own size would free and re-allocate it, new, in every frame. */
	for (uint32_t p = 0; p < s->patch_count; p++) {
		patch_state *q = &s->ps[p];
		if (q->allocated && (!vis[p] || q->want_lw != q->req_lw || q->want_lh != q->req_lh || q->want_facing != q->facing))
			release(s, q);
	}
	/* 3: allocate the new ones in ascending patch id; on overflow one level smaller (the longer side halved) */
	for (uint32_t p = 0; p < s->patch_count; p++) {
		patch_state *q = &s->ps[p];
		if (!vis[p] || q->allocated)
			continue;
		uint32_t lw = q->want_lw, lh = q->want_lh;
		while (!atlas_alloc_block(s->alloc, lw, lh, &q->x, &q->y)) {
			if (lw <= 1 && lh <= 1 && getenv("TASLAB_DEBUG_ATLAS")) {
				uint64_t hist[16] = {0}, nvis = 0;
				for (uint32_t k = 0; k < s->patch_count; k++)
					if (vis[k])
						nvis++, hist[(s->ps[k].want_lw + s->ps[k].want_lh) / 2]++;
				fprintf(stderr, "atlas full at patch %u of %u; visible %llu; used %llu of %u texels; levels:", p,
					s->patch_count, (unsigned long long)nvis, (unsigned long long)atlas_alloc_used(s->alloc),
					s->atlas_w * s->atlas_h);
				for (int k = 0; k < 16; k++)
					fprintf(stderr, " %llu", (unsigned long long)hist[k]);
				fprintf(stderr, "\n");
			}
			if (lw <= 1 && lh <= 1)
				return tl_error(err, err_size, TL_ERR_UNSUPPORTED,
						"the atlas (%ux%u texels) is full: raise --atlas-scale or lower --atlas-density",
						s->atlas_w, s->atlas_h);
			if (lw >= lh && lw > 1)
				lw--;
			else
				lh--;
		}
		q->lw = (uint8_t)lw, q->lh = (uint8_t)lh;
		q->req_lw = q->want_lw, q->req_lh = q->want_lh;
		q->allocated = 1;
		q->facing = q->want_facing;
		q->t_alloc = frame;
		q->phase = 0;
		q->G = 0.0f;
		s->new_blocks++;
	}
	/* decisions and work lists */
	uint32_t(*blocks)[4] = s->buf[B_BLOCKS].mapped;
	uint32_t(*work)[2] = s->buf[B_WORK].mapped;
	size_t nw = 0;
	for (int pass = 0; pass < 2; pass++) { /* 0: blocks to shade; 1: --truth, the reused ones */
		if (pass == 1)
			s->shade_chunks = (uint32_t)nw;
		for (uint32_t p = 0; p < s->patch_count; p++) {
			patch_state *q = &s->ps[p];
			if (!q->allocated)
				continue;
			uint32_t texels = 1u << (q->lw + q->lh);
			if (pass == 0) {
				bool fresh = q->phase == 0;
				uint32_t age = fresh ? 0u : frame - q->t_last;
				bool shade;
				switch (s->v.kind) {
				case ATLAS_SAU: shade = fresh || (frame - q->t_alloc) % s->v.period == 0; break;
				case ATLAS_TASA:
					shade = s->v.oracle || fresh || q->phase == 1 || s->v.force ||
						(F[p] > 0.0f && (double)F[p] * age > (double)s->v.threshold);
					break;
				default: shade = true;
				}
				q->shade = shade;
				blocks[p][0] = q->x | q->y << 16;
				blocks[p][1] = q->lw | (uint32_t)q->lh << 8 | (age < 65535 ? age : 65535u) << 16;
				blocks[p][2] = s->patch_mesh[p];
				blocks[p][3] = s->patch_object[p];
				s->allocated_blocks++;
				s->allocated_texels += texels;
				s->clamped += q->clamped;
				s->overflow += q->lw != q->req_lw || q->lh != q->req_lh;
			}
			if (pass == 0 ? !q->shade : (q->shade || !s->v.truth || s->v.oracle))
				continue;
			for (uint32_t first = 0; first < texels && nw < s->work_cap; first += 8) {
				work[nw][0] = p;
				work[nw++][1] = first;
			}
			if (pass == 0)
				s->listed_texels += texels;
			if (pass == 0 && !s->v.oracle) {
				s->shaded_blocks++;
				s->shaded_texels += texels;
			}
		}
	}
	s->truth_chunks = (uint32_t)nw - s->shade_chunks;
	/* state after this frame's shading (the oracle's phases do not matter: it decides on the truth) */
	for (uint32_t p = 0; p < s->patch_count; p++) {
		patch_state *q = &s->ps[p];
		if (q->allocated && q->shade) {
			q->t_last = frame;
			q->phase = q->phase < 2 ? q->phase + 1 : 2;
		}
	}
	memset(s->buf[B_GNEW].mapped, 0, s->buf[B_GNEW].size);
	memset(s->buf[B_COUNTERS].mapped, 0, s->buf[B_COUNTERS].size);
	if (s->v.oracle)
		memset(s->buf[B_DMAX].mapped, 0, s->buf[B_DMAX].size);
	s->cpu_ms = (tl_clock_s() - t0) * 1e3;
	return TL_OK;
}

void atlas_record(render *r, VkCommandBuffer cmd, uint32_t frame)
{
	atlas_state *s = state_of(r);
	uint32_t w = r->desc.width, h = r->desc.height;
	uint32_t tbits;
	memcpy(&tbits, &s->v.threshold, sizeof tbits);
	barrier_compute(cmd); /* host writes (blocks, work, counters) before the shaders */
	render_ts(r, cmd);
	render_stats_begin(r, cmd);
	bind_compute(r, s, cmd, s->shade_pipe, 0, s->shade_chunks, frame, tbits);
	dispatch_chunks(cmd, s->shade_chunks);
	render_stats_end(r, cmd);
	barrier_compute(cmd);
	if (s->v.oracle) {
		bind_compute(r, s, cmd, s->commit_pipe, 0, s->shade_chunks, frame, tbits);
		dispatch_chunks(cmd, s->shade_chunks);
		barrier_compute(cmd);
	}
	render_ts(r, cmd);
	if (s->truth_pipe && s->truth_chunks) {
		bind_compute(r, s, cmd, s->truth_pipe, s->shade_chunks, s->truth_chunks, frame, tbits);
		dispatch_chunks(cmd, s->truth_chunks);
		barrier_compute(cmd);
	}
	render_ts(r, cmd);
	/* resolve into the HDR target cleared to the sky (coverage 0); stereo: each eye from the shared atlas */
	const scene *sc = r->scene;
	VkClearColorValue sky = {{sc->sky[0] * sc->exposure, sc->sky[1] * sc->exposure, sc->sky[2] * sc->exposure, 0.0f}};
	VkImageSubresourceRange range = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
	for (uint32_t v = 0; v < r->view_count; v++) {
		render_use_view(r, v);
		vkCmdClearColorImage(cmd, r->hdr.image, VK_IMAGE_LAYOUT_GENERAL, &sky, 1, &range);
		render_barrier(cmd, VK_PIPELINE_STAGE_2_CLEAR_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
			       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
		bind_compute(r, s, cmd, s->resolve_pipe, 0, 0, frame, tbits);
		vkCmdDispatch(cmd, (w + 7) / 8, (h + 7) / 8, 1);
		vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL,
				    VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
				    VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
				    VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
	}
	render_ts(r, cmd);
	for (uint32_t v = 0; v < r->view_count && r->blend_count; v++) {
		render_use_view(r, v);
		render_pass_scene(r, cmd, 0, &(render_scene_pass){.hdr = RENDER_HDR_LOAD, .blend = 1});
	}
	render_ts(r, cmd);
	for (uint32_t v = 0; v < r->view_count; v++) {
		render_use_view(r, v);
		render_pass_display(r, cmd);
	}
	render_ts(r, cmd);
	for (uint32_t v = 0; v < r->view_count; v++) {
		render_use_view(r, v);
		render_pass_readback(r, cmd);
	}
	render_use_view(r, 0);
	barrier_compute(cmd);
	render_ts(r, cmd);
	s->last_frame = frame;
}

void atlas_collect(render *r, frame_stats *st)
{
	atlas_state *s = state_of(r);
	const uint32_t *c = s->buf[B_COUNTERS].mapped;
	if (s->v.oracle) {
		s->shaded_blocks = c[0];
		s->shaded_texels = c[1];
	}
	st->allocated_samples = (int64_t)s->allocated_texels;
	st->visible_units = (int64_t)s->allocated_blocks;
	st->new_units = (int64_t)s->new_blocks;
	/* shaded texels as counted by the shading itself (shade.comp.in, count[3]); the oracle's are the committed ones
	 * (commit.comp.in). listed_samples: the texels the CPU put on the shading work list — equal to the shading's own
	 * count (count[3]; the oracle shades every listed texel into its scratch atlas) unless work was lost on the way
	 * (tests assert it). */
	if (!s->v.oracle)
		s->shaded_texels = c[3];
	st->shaded_units = (int64_t)s->shaded_blocks;
	st->shaded_samples = (int64_t)s->shaded_texels;
	st->reused_samples = (int64_t)s->allocated_texels - (int64_t)s->shaded_texels;
	st->late_samples = s->v.truth ? (int64_t)c[2] : -1;
	/* stereo: the texels shaded in blocks each eye sees, counted by the shading (count[4], count[5]); a shared block
	 * counts for both eyes, once in shaded_samples */
	for (uint32_t v = 0; v < r->view_count && v < 2 && !s->v.oracle; v++)
		r->view_shaded[v] = (int64_t)c[4 + v];
	const char *names[5] = {"cpu_ms_alloc", "atlas_overflow", "clamped_units", "listed_samples", "shade_invocations"};
	double vals[5] = {s->cpu_ms, s->overflow, s->clamped, (double)s->listed_texels, (double)c[3]};
	for (int i = 0; i < 5 && st->extra_count < FRAME_MAX_EXTRA; i++) {
		st->extra_names[st->extra_count] = names[i];
		st->extra[st->extra_count++] = vals[i];
	}
	/* tasa: the gradients measured by this frame's shading (the per-block maximum) */
	if (s->v.kind == ATLAS_TASA && !s->v.oracle) {
		const uint32_t *gn = s->buf[B_GNEW].mapped;
		for (uint32_t p = 0; p < s->patch_count; p++)
			if (s->ps[p].allocated && s->ps[p].shade)
				memcpy(&s->ps[p].G, &gn[p], sizeof(float));
	}
}

void atlas_finish(render *r)
{
	atlas_state *s = state_of(r);
	if (!s)
		return;
	VkDevice d = r->dev->device;
	VkPipeline cp[5] = {s->visible_pipe, s->shade_pipe, s->commit_pipe, s->truth_pipe, s->resolve_pipe};
	for (int i = 0; i < 5; i++)
		if (cp[i])
			vkDestroyPipeline(d, cp[i], NULL);
	if (s->comp_layout)
		vkDestroyPipelineLayout(d, s->comp_layout, NULL);
	if (s->set_layout)
		vkDestroyDescriptorSetLayout(d, s->set_layout, NULL);
	for (int i = 0; i < B_COUNT; i++)
		vkdev_buffer_destroy(r->dev, &s->buf[i]);
	for (uint32_t v = 0; v < RENDER_MAX_VIEWS; v++)
		ids_pass_finish(r, &s->ids[v]);
	ids_multiview_finish(r, &s->mv);
	vkdev_image_destroy(r->dev, &s->atlas);
	vkdev_image_destroy(r->dev, &s->scratch);
	vkdev_image_destroy(r->dev, &s->shown);
	atlas_alloc_destroy(&s->alloc);
	atlas_patches_free(&s->patches);
	free(s->patch_object);
	free(s->patch_mesh);
	free(s->ps);
	free(s);
	r->method_state = NULL;
}

/* ---- diagnostics for the tests (atlas.h) ---- */

int atlas_debug_ids(render *r, uint32_t *ids, bool upload, char *err, size_t err_size)
{
	return ids_pass_copy(r, &state_of(r)->ids[r->view], ids, upload, err, err_size);
}

bool atlas_debug_multiview(render *r) { return state_of(r)->mv.ids.image != VK_NULL_HANDLE; }

int atlas_debug_ids_view(render *r, uint32_t view, uint32_t *ids, bool upload, char *err, size_t err_size)
{
	if (view >= r->view_count)
		return tl_error(err, err_size, TL_ERR_ARG, "no view %u", view);
	atlas_state *s = state_of(r); /* view 0's: a shared-views method keeps one state */
	render_use_view(r, view);
	int rc = ids_pass_copy(r, &s->ids[view], ids, upload, err, err_size);
	render_use_view(r, 0);
	return rc;
}

int atlas_debug_visible(render *r, const float *G, uint32_t *visible, float *F, char *err, size_t err_size)
{
	atlas_state *s = state_of(r);
	memcpy(s->buf[B_G].mapped, G, (size_t)s->patch_count * sizeof *G);
	VkCommandBuffer cmd;
	VkResult res = vkdev_cmd_begin(r->dev, &cmd);
	if (res)
		return render_vk_error(err, err_size, "atlas visible pass", res);
	vkCmdFillBuffer(cmd, s->buf[B_VISIBLE].buffer, 0, VK_WHOLE_SIZE, 0);
	vkCmdFillBuffer(cmd, s->buf[B_F].buffer, 0, VK_WHOLE_SIZE, 0);
	barrier_compute(cmd);
	for (uint32_t v = 0; v < r->view_count; v++) { /* stereo: both eyes into the one visible set and F */
		render_use_view(r, v);
		bind_compute(r, s, cmd, s->visible_pipe, v, 0, 0, 0);
		dispatch_visible(cmd, r->desc.width, r->desc.height);
	}
	render_use_view(r, 0);
	barrier_compute(cmd);
	if ((res = vkdev_cmd_submit_wait(r->dev, cmd)))
		return render_vk_error(err, err_size, "atlas visible pass", res);
	memcpy(visible, s->buf[B_VISIBLE].mapped, (size_t)s->patch_count * sizeof *visible);
	memcpy(F, s->buf[B_F].mapped, (size_t)s->patch_count * sizeof *F);
	return TL_OK;
}

const uint32_t *atlas_debug_blocks(render *r, uint32_t *patch_count)
{
	atlas_state *s = state_of(r);
	*patch_count = s->patch_count;
	return s->buf[B_BLOCKS].mapped;
}

int atlas_debug_facing(render *r, uint32_t pid)
{
	atlas_state *s = state_of(r);
	return pid < s->patch_count && s->ps[pid].allocated ? s->ps[pid].facing : -1;
}
