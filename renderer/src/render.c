/* render.c — shared frame pipeline: scene upload, state rings, shadow maps, depth pre-pass,
 * forward shading, display encoding, readback, queries; method dispatch (see render.h). */
#include "render_internal.h"

#include "shader_compile.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shaders/depth_mask_frag.h"
#include "shaders/common_glsl.h"
#include "shaders/display_comp_in.h"
#include "shaders/shading_glsl.h"
#include "shaders/tas_glsl.h"
#include "shaders/tfa_glsl.h"
#include "shaders/scene_vert.h"
#include "shaders/shade_frag.h"
#include "shaders/shadow_mask_vert.h"
#include "shaders/shadow_vert.h"
#include "shaders/trivial_frag.h"

#define CHECK_VK(call)                                                                                     \
	do {                                                                                               \
		VkResult vr_ = (call);                                                                     \
		if (vr_ != VK_SUCCESS) {                                                                   \
			snprintf(err, err_size, "%s:%d: %s failed: %s", __FILE__, __LINE__, #call,          \
				 vkdev_result_string(vr_));                                                \
			rc = RENDER_ERR_VULKAN;                                                            \
			goto fail;                                                                         \
		}                                                                                          \
	} while (0)

static const render_method_ops *const method_table[] = {&render_method_ref, &render_method_tfr};

static const render_method_info planned[] = {
	{"rrc", "reverse reprojection cache with round-robin tile refresh", false},
	{"tarc", "temporally adaptive reprojection caching (paper sec. 6.1)", false},
	{"sa", "shading atlas, visible blocks shaded every frame", false},
	{"sau", "shading atlas with uniform temporal upsampling", false},
	{"tasa", "temporally adaptive shading atlas (paper sec. 6.2)", false},
};

const render_method_info *render_methods(size_t *count)
{
	static render_method_info all[sizeof method_table / sizeof method_table[0] + sizeof planned / sizeof planned[0]];
	size_t n = 0;
	for (size_t i = 0; i < sizeof method_table / sizeof method_table[0]; i++)
		all[n++] = method_table[i]->info;
	for (size_t i = 0; i < sizeof planned / sizeof planned[0]; i++)
		all[n++] = planned[i];
	*count = n;
	return all;
}

/* ------------------------------------------------------------------ textures */

static float srgb_to_linear(float c)
{
	return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}

static float linear_to_srgb(float l)
{
	return l <= 0.0031308f ? 12.92f * l : 1.055f * powf(l, 1.0f / 2.4f) - 0.055f;
}

/* 2x2 box-filtered mip (colour channels averaged in linear light for sRGB data). */
static void downsample(const uint8_t *src, uint32_t n, uint8_t *dst, int srgb)
{
	uint32_t m = n / 2;
	for (uint32_t y = 0; y < m; y++)
		for (uint32_t x = 0; x < m; x++)
			for (int c = 0; c < 4; c++) {
				float s = 0.0f;
				for (int k = 0; k < 4; k++) {
					uint8_t v = src[(((size_t)(2 * y + (k >> 1))) * n + 2 * x + (k & 1)) * 4 + c];
					s += (srgb && c < 3) ? srgb_to_linear(v / 255.0f) : v / 255.0f;
				}
				s *= 0.25f;
				if (srgb && c < 3)
					s = linear_to_srgb(s);
				dst[((size_t)y * m + x) * 4 + c] = (uint8_t)lrintf(s * 255.0f);
			}
}

static uint32_t mip_count(uint32_t n)
{
	uint32_t m = 1;
	while (n > 1) {
		n /= 2;
		m++;
	}
	return m;
}

/* Uploads the scene's textures of one kind (sRGB or linear) into a 2D array with mips.
 * `layer_of[i]` receives texture i's layer, or stays -1 for textures of the other kind. */
static int upload_texture_array(render *r, int srgb, int *layer_of, vkdev_image *out, char *err, size_t err_size)
{
	const scene *s = r->scene;
	int rc = 0;
	uint32_t n = s->texture_size, layers = 0;
	for (size_t i = 0; i < s->texture_count; i++)
		if (s->textures[i].srgb == (bool)srgb)
			layer_of[i] = (int)layers++;
	uint32_t size = layers ? n : 1, mips = layers ? mip_count(n) : 1;
	VkFormat fmt = srgb ? VK_FORMAT_R8G8B8A8_SRGB : VK_FORMAT_R8G8B8A8_UNORM;
	vkdev_buffer staging = {0};
	VkBufferImageCopy *regions = NULL;
	CHECK_VK(vkdev_image_create(r->dev, size, size, layers ? layers : 1, mips, fmt,
				    VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
				    true, srgb ? "color_textures" : "data_textures", out));
	size_t per_layer = 0;
	for (uint32_t m = 0, e = size; m < mips; m++, e /= 2)
		per_layer += (size_t)e * e * 4;
	uint32_t nl = layers ? layers : 1;
	CHECK_VK(vkdev_buffer_create(r->dev, per_layer * nl, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true, "tex staging", &staging));
	regions = calloc((size_t)mips * nl, sizeof *regions);
	if (!regions) {
		rc = RENDER_ERR_NOMEM;
		snprintf(err, err_size, "out of memory");
		goto fail;
	}
	uint8_t *dst = staging.mapped;
	size_t off = 0;
	for (uint32_t l = 0; l < nl; l++) {
		const uint8_t *src = NULL;
		if (layers)
			for (size_t i = 0; i < s->texture_count; i++)
				if (layer_of[i] == (int)l && s->textures[i].srgb == (bool)srgb)
					src = s->textures[i].rgba;
		if (src)
			memcpy(dst + off, src, (size_t)size * size * 4);
		else
			memset(dst + off, 255, (size_t)size * size * 4);
		for (uint32_t m = 0, e = size; m < mips; m++, e /= 2) {
			regions[l * mips + m] = (VkBufferImageCopy){
				.bufferOffset = off,
				.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, m, l, 1},
				.imageExtent = {e, e, 1},
			};
			if (m + 1 < mips)
				downsample(dst + off, e, dst + off + (size_t)e * e * 4, srgb);
			off += (size_t)e * e * 4;
		}
	}
	VkCommandBuffer cmd;
	CHECK_VK(vkdev_cmd_begin(r->dev, &cmd));
	vkdev_barrier_image(cmd, out, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
			    VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0,
			    VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT);
	vkCmdCopyBufferToImage(cmd, staging.buffer, out->image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, mips * nl, regions);
	vkdev_barrier_image(cmd, out, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
			    VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_PIPELINE_STAGE_2_COPY_BIT,
			    VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT |
			    VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
	CHECK_VK(vkdev_cmd_submit_wait(r->dev, cmd));
fail:
	free(regions);
	vkdev_buffer_destroy(r->dev, &staging);
	return rc;
}

/* ------------------------------------------------------------------ scene upload */

static int upload_scene(render *r, char *err, size_t err_size)
{
	const scene *s = r->scene;
	int rc = 0;
	size_t nv = 0, ni = 0;
	int *srgb_layer = NULL, *data_layer = NULL;
	scene_vertex *verts = NULL;
	uint32_t *idx = NULL;
	gpu_material *mats = NULL;
	for (size_t i = 0; i < s->mesh_count; i++) {
		nv += s->meshes[i].vertex_count;
		ni += s->meshes[i].index_count;
	}
	r->mesh_first_index = calloc(s->mesh_count, sizeof *r->mesh_first_index);
	r->mesh_vertex_offset = calloc(s->mesh_count, sizeof *r->mesh_vertex_offset);
	verts = malloc(nv * sizeof *verts);
	idx = malloc(ni * sizeof *idx);
	srgb_layer = malloc((s->texture_count + 1) * sizeof *srgb_layer);
	data_layer = malloc((s->texture_count + 1) * sizeof *data_layer);
	mats = calloc(s->material_count, sizeof *mats);
	if (!r->mesh_first_index || !r->mesh_vertex_offset || !verts || !idx || !srgb_layer || !data_layer || !mats) {
		snprintf(err, err_size, "out of memory uploading the scene");
		rc = RENDER_ERR_NOMEM;
		goto fail;
	}
	for (size_t i = 0, ov = 0, oi = 0; i < s->mesh_count; i++) {
		const scene_mesh *m = &s->meshes[i];
		memcpy(verts + ov, m->vertices, m->vertex_count * sizeof *verts);
		memcpy(idx + oi, m->indices, m->index_count * sizeof *idx);
		r->mesh_vertex_offset[i] = (uint32_t)ov;
		r->mesh_first_index[i] = (uint32_t)oi;
		ov += m->vertex_count;
		oi += m->index_count;
	}
	CHECK_VK(vkdev_buffer_create(r->dev, nv * sizeof *verts, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT |
				     VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false,
				     "vertices", &r->vertices));
	CHECK_VK(vkdev_upload_buffer(r->dev, &r->vertices, verts, nv * sizeof *verts));
	CHECK_VK(vkdev_buffer_create(r->dev, ni * sizeof *idx, VK_BUFFER_USAGE_INDEX_BUFFER_BIT |
				     VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, false,
				     "indices", &r->indices));
	CHECK_VK(vkdev_upload_buffer(r->dev, &r->indices, idx, ni * sizeof *idx));

	for (size_t i = 0; i < s->texture_count; i++)
		srgb_layer[i] = data_layer[i] = -1;
	if ((rc = upload_texture_array(r, 1, srgb_layer, &r->color_tex, err, err_size)) ||
	    (rc = upload_texture_array(r, 0, data_layer, &r->data_tex, err, err_size)))
		goto fail;
	for (size_t i = 0; i < s->material_count; i++) {
		const scene_material *m = &s->materials[i];
		gpu_material *g = &mats[i];
		memcpy(g->base_color, m->base_color, sizeof g->base_color);
		memcpy(g->emissive_normal_scale, m->emissive, 3 * sizeof(float));
		g->emissive_normal_scale[3] = m->normal_scale;
		g->mr_occ_cutoff[0] = m->metallic;
		g->mr_occ_cutoff[1] = m->roughness;
		g->mr_occ_cutoff[2] = m->occlusion_strength;
		g->mr_occ_cutoff[3] = m->alpha_cutoff;
#define LAYER(tex, arr) ((tex) >= 0 ? (arr)[(tex)] : -1)
		/* A texture used in the "wrong" slot (e.g. a colour texture as normal map) reads as absent. */
		g->tex0[0] = LAYER(m->base_color_tex, srgb_layer);
		g->tex0[1] = LAYER(m->metal_rough_tex, data_layer);
		g->tex0[2] = LAYER(m->normal_tex, data_layer);
		g->tex0[3] = LAYER(m->emissive_tex, srgb_layer);
		g->tex1[0] = LAYER(m->occlusion_tex, data_layer);
#undef LAYER
		g->tex1[1] = (int32_t)m->alpha_mode;
		g->tex1[2] = m->double_sided;
	}
	CHECK_VK(vkdev_buffer_create(r->dev, s->material_count * sizeof *mats, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
				     VK_BUFFER_USAGE_TRANSFER_DST_BIT, false, "materials", &r->materials));
	CHECK_VK(vkdev_upload_buffer(r->dev, &r->materials, mats, s->material_count * sizeof *mats));
	CHECK_VK(vkdev_buffer_create(r->dev, r->state_ring * sizeof(gpu_frame_state), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
				     true, "frame states", &r->states));
	CHECK_VK(vkdev_buffer_create(r->dev, r->state_ring * s->object_count * sizeof(gpu_object),
				     VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true, "objects", &r->objects));
fail:
	free(verts);
	free(idx);
	free(srgb_layer);
	free(data_layer);
	free(mats);
	return rc;
}

/* ------------------------------------------------------------------ state */

static void mat_copy(float dst[16], tlm_mat4 m) { memcpy(dst, m.m, sizeof m.m); }

static tlm_vec3 safe_up(tlm_vec3 dir)
{
	return fabsf(dir.y) > 0.99f ? tlm_v3(0, 0, 1) : tlm_v3(0, 1, 0);
}

void render_update_state(render *r, uint32_t slot, double time_s)
{
	const scene *s = r->scene;
	gpu_frame_state *st = (gpu_frame_state *)r->states.mapped + slot;
	gpu_object *ob = (gpu_object *)r->objects.mapped + (size_t)slot * s->object_count;
	float t = (float)time_s;
	memset(st, 0, sizeof *st);
	scene_eval(s, t, r->world, r->light_states);
	for (size_t i = 0; i < s->object_count; i++) {
		mat_copy(ob[i].world, r->world[i]);
		mat_copy(ob[i].normal_matrix, tlm_mat4_transpose(tlm_mat4_inverse(r->world[i])));
		ob[i].material[0] = s->objects[i].material >= 0 ? (uint32_t)s->objects[i].material : 0u;
	}
	scene_camera_state cam = scene_camera_eval(s, r->desc.camera, t);
	r->eye = cam.eye;
	tlm_mat4 view = tlm_mat4_look_at(cam.eye, cam.target, tlm_v3(0, 1, 0));
	tlm_mat4 proj = tlm_mat4_perspective(cam.fov_deg * TLM_PI / 180.0f,
					     (float)r->desc.width / (float)r->desc.height, cam.znear, cam.zfar);
	mat_copy(st->view, view);
	mat_copy(st->proj, proj);
	mat_copy(st->view_proj, tlm_mat4_mul(proj, view));
	st->camera_time[0] = cam.eye.x;
	st->camera_time[1] = cam.eye.y;
	st->camera_time[2] = cam.eye.z;
	st->camera_time[3] = t;
	memcpy(st->ambient_exposure, s->ambient, 3 * sizeof(float));
	st->ambient_exposure[3] = s->exposure;
	memcpy(st->sky_lights, s->sky, 3 * sizeof(float));
	st->sky_lights[3] = (float)s->light_count;
	st->shadow_params[0] = 1.0f / (float)s->shadow_map_size;
	st->shadow_params[1] = 1.5f; /* PCF disk radius in texels */
	for (size_t i = 0; i < s->light_count; i++) {
		const scene_light *l = &s->lights[i];
		gpu_light *g = &st->lights[i];
		tlm_vec3 p = r->light_states[i].position, d = r->light_states[i].direction;
		g->position_range[0] = p.x, g->position_range[1] = p.y, g->position_range[2] = p.z;
		g->position_range[3] = l->range;
		g->direction_type[0] = d.x, g->direction_type[1] = d.y, g->direction_type[2] = d.z;
		g->direction_type[3] = (float)(l->kind == SCENE_LIGHT_DIRECTIONAL ? GPU_LIGHT_DIRECTIONAL
					       : l->kind == SCENE_LIGHT_POINT	  ? GPU_LIGHT_POINT
										  : GPU_LIGHT_SPOT);
		for (int c = 0; c < 3; c++)
			g->color[c] = l->color[c] * r->light_states[i].intensity;
		float co = cosf(l->outer_cone_deg * TLM_PI / 180.0f), ci = cosf(l->inner_cone_deg * TLM_PI / 180.0f);
		g->cone_shadow[0] = co;
		g->cone_shadow[1] = 1.0f / fmaxf(ci - co, 1e-4f);
		int layer = r->light_shadow_layer[i];
		g->cone_shadow[2] = (float)layer;
		if (layer < 0)
			continue;
		float far = l->range > 0.0f ? l->range : 100.0f;
		if (l->kind == SCENE_LIGHT_DIRECTIONAL) {
			float e = l->shadow_extent;
			tlm_vec3 eye = tlm_v3_sub(l->shadow_center, tlm_v3_scale(d, 2.0f * e));
			tlm_mat4 lv = tlm_mat4_look_at(eye, l->shadow_center, safe_up(d));
			mat_copy(st->shadow_matrix[layer], tlm_mat4_mul(tlm_mat4_ortho(-e, e, -e, e, 0.0f, 4.0f * e), lv));
			g->cone_shadow[3] = 1.5f * 2.0f * e / (float)s->shadow_map_size;
		} else if (l->kind == SCENE_LIGHT_SPOT) {
			tlm_mat4 lv = tlm_mat4_look_at(p, tlm_v3_add(p, d), safe_up(d));
			float fov = fminf(2.0f * l->outer_cone_deg + 4.0f, 170.0f) * TLM_PI / 180.0f;
			mat_copy(st->shadow_matrix[layer], tlm_mat4_mul(tlm_mat4_perspective(fov, 1.0f, 0.05f, far), lv));
			g->cone_shadow[3] = 0.02f;
		} else {
			/* Cube faces +X, -X, +Y, -Y, +Z, -Z (order matches cube_face() in shading.glsl);
			 * 95 degree frusta so PCF taps near a face edge stay inside the face. */
			static const float ax[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
			tlm_mat4 pr = tlm_mat4_perspective(95.0f * TLM_PI / 180.0f, 1.0f, 0.05f, far);
			for (int f = 0; f < 6; f++) {
				tlm_vec3 a = tlm_v3(ax[f][0], ax[f][1], ax[f][2]);
				tlm_mat4 lv = tlm_mat4_look_at(p, tlm_v3_add(p, a), safe_up(a));
				mat_copy(st->shadow_matrix[layer + f], tlm_mat4_mul(pr, lv));
			}
			g->cone_shadow[3] = 0.02f;
		}
	}
}

/* ------------------------------------------------------------------ passes */

void render_ts(render *r, VkCommandBuffer cmd)
{
	if (r->ts_pool)
		vkCmdWriteTimestamp2(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, r->ts_pool, r->ts_count);
	r->ts_count++;
}

static void bind_scene(render *r, VkCommandBuffer cmd, const render_pipeline *p)
{
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p->pipeline);
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p->layout, 0, 1, &r->scene_set, 0, NULL);
	VkDeviceSize zero = 0;
	vkCmdBindVertexBuffers(cmd, 0, 1, &r->vertices.buffer, &zero);
	vkCmdBindIndexBuffer(cmd, r->indices.buffer, 0, VK_INDEX_TYPE_UINT32);
}

static void set_viewport(VkCommandBuffer cmd, uint32_t w, uint32_t h)
{
	VkViewport vp = {0, 0, (float)w, (float)h, 0.0f, 1.0f};
	VkRect2D sc = {{0, 0}, {w, h}};
	vkCmdSetViewport(cmd, 0, 1, &vp);
	vkCmdSetScissor(cmd, 0, 1, &sc);
}

#define ALPHA_BIT(m) (1u << (m))
#define OPAQUE_BIT ALPHA_BIT(SCENE_ALPHA_OPAQUE)
#define MASK_BIT ALPHA_BIT(SCENE_ALPHA_MASK)
#define BLEND_BIT ALPHA_BIT(SCENE_ALPHA_BLEND)

static void draw_object(render *r, VkCommandBuffer cmd, const render_pipeline *p, uint32_t slot, uint32_t layer,
			size_t i, int set_cull)
{
	const scene *s = r->scene;
	const scene_object *o = &s->objects[i];
	gpu_push pc = {slot, (uint32_t)i, (uint32_t)s->object_count, layer, {r->push_aux[0], r->push_aux[1], r->push_aux[2], r->push_aux[3]}};
	vkCmdPushConstants(cmd, p->layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof pc, &pc);
	if (set_cull)
		vkCmdSetCullMode(cmd, s->materials[o->material].double_sided ? VK_CULL_MODE_NONE : VK_CULL_MODE_BACK_BIT);
	const scene_mesh *m = &s->meshes[o->mesh];
	vkCmdDrawIndexed(cmd, m->index_count, 1, r->mesh_first_index[o->mesh], (int32_t)r->mesh_vertex_offset[o->mesh], 0);
}

/* Draws the objects whose material alpha mode is in `modes` (ALPHA_BIT set), in scene order. */
static void draw_objects(render *r, VkCommandBuffer cmd, const render_pipeline *p, uint32_t slot, uint32_t layer,
			 unsigned modes, int shadow_casters_only, int set_cull)
{
	const scene *s = r->scene;
	for (size_t i = 0; i < s->object_count; i++) {
		const scene_object *o = &s->objects[i];
		if (o->mesh < 0 || (shadow_casters_only && !o->casts_shadow))
			continue; /* transform-only node */
		if (modes & ALPHA_BIT(s->materials[o->material].alpha_mode))
			draw_object(r, cmd, p, slot, layer, i, set_cull);
	}
}

static int has_alpha_mode(const render *r, scene_alpha_mode mode)
{
	for (size_t i = 0; i < r->scene->object_count; i++) {
		const scene_object *o = &r->scene->objects[i];
		if (o->mesh >= 0 && r->scene->materials[o->material].alpha_mode == mode)
			return 1;
	}
	return 0;
}

/* One depth-only rendering into `view` (cleared to 1): shadow layers and the depth pre-pass. Opaque
 * objects use `pipe`; alpha-masked ones `mask_pipe` (alpha test in the fragment shader); blended
 * objects write no depth and cast no shadow. */
void render_depth_only_pass(render *r, VkCommandBuffer cmd, VkImageView view, uint32_t w, uint32_t h,
			    const render_pipeline *pipe, const render_pipeline *mask_pipe, uint32_t slot, uint32_t layer,
			    int shadow_pass)
{
	VkRenderingAttachmentInfo da = {
		.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
		.imageView = view,
		.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
		.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR,
		.storeOp = VK_ATTACHMENT_STORE_OP_STORE,
		.clearValue = {.depthStencil = {1.0f, 0}},
	};
	VkRenderingInfo ri = {
		.sType = VK_STRUCTURE_TYPE_RENDERING_INFO,
		.renderArea = {{0, 0}, {w, h}},
		.layerCount = 1,
		.pDepthAttachment = &da,
	};
	vkCmdBeginRendering(cmd, &ri);
	bind_scene(r, cmd, pipe);
	set_viewport(cmd, w, h);
	/* Shadow passes draw shadow casters with culling off; the pre-pass culls per material. */
	draw_objects(r, cmd, pipe, slot, layer, OPAQUE_BIT, shadow_pass, !shadow_pass);
	if (mask_pipe->pipeline) {
		bind_scene(r, cmd, mask_pipe);
		draw_objects(r, cmd, mask_pipe, slot, layer, MASK_BIT, shadow_pass, !shadow_pass);
	}
	vkCmdEndRendering(cmd);
}

void render_pass_depth(render *r, VkCommandBuffer cmd, uint32_t slot)
{
	uint32_t w = r->desc.width, h = r->desc.height;
	vkdev_barrier_image(cmd, &r->depth, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
			    VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
			    VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
			    VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT,
			    VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
			    VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT);
	render_depth_only_pass(r, cmd, r->depth.view, w, h, &r->depth_pipe, &r->depth_mask_pipe, slot, 0, 0);
	VkMemoryBarrier2 mb = {
		.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER_2,
		.srcStageMask = VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
		.srcAccessMask = VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
		.dstStageMask = VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
		.dstAccessMask = VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT,
	};
	VkDependencyInfo di = {.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO, .memoryBarrierCount = 1, .pMemoryBarriers = &mb};
	vkCmdPipelineBarrier2(cmd, &di);
}

void render_pass_shade(render *r, VkCommandBuffer cmd, uint32_t slot)
{
	render_pass_shade_with(r, cmd, slot, &r->shade_pipe, VK_NULL_HANDLE);
}

void render_pass_shade_with(render *r, VkCommandBuffer cmd, uint32_t slot, const render_pipeline *opaque,
			    VkDescriptorSet method_set)
{
	uint32_t w = r->desc.width, h = r->desc.height;
	const scene *s = r->scene;
	vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
			    VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_COPY_BIT, 0,
			    VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
	/* Background: sky radiance (times exposure), coverage 0. */
	VkRenderingAttachmentInfo ca = {
		.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
		.imageView = r->hdr.view,
		.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
		.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR,
		.storeOp = VK_ATTACHMENT_STORE_OP_STORE,
		.clearValue = {.color = {{s->sky[0] * s->exposure, s->sky[1] * s->exposure, s->sky[2] * s->exposure, 0.0f}}},
	};
	VkRenderingAttachmentInfo da = {
		.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
		.imageView = r->depth.view,
		.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
		.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD,
		.storeOp = VK_ATTACHMENT_STORE_OP_STORE,
	};
	VkRenderingInfo ri = {
		.sType = VK_STRUCTURE_TYPE_RENDERING_INFO,
		.renderArea = {{0, 0}, {w, h}},
		.layerCount = 1,
		.colorAttachmentCount = 1,
		.pColorAttachments = &ca,
		.pDepthAttachment = &da,
	};
	if (r->stats_pool) { /* reset here so any number of shading passes may run per command buffer */
		vkCmdResetQueryPool(cmd, r->stats_pool, 0, 1);
		vkCmdBeginQuery(cmd, r->stats_pool, 0, 0);
	}
	vkCmdBeginRendering(cmd, &ri);
	bind_scene(r, cmd, opaque);
	if (method_set)
		vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, opaque->layout, 1, 1, &method_set, 0, NULL);
	set_viewport(cmd, w, h);
	draw_objects(r, cmd, opaque, slot, 0, OPAQUE_BIT | MASK_BIT, 0, 1);
	if (r->blend_count) {
		/* glTF BLEND: "over" compositing after the opaque surfaces, objects sorted back to front by the
		 * distance of their bounds centre from the camera (per object, not per triangle). */
		const scene *sc = r->scene;
		float *dist = malloc(r->blend_count * sizeof *dist);
		uint32_t n = 0;
		for (size_t i = 0; dist && i < sc->object_count; i++) {
			const scene_object *o = &sc->objects[i];
			if (o->mesh < 0 || sc->materials[o->material].alpha_mode != SCENE_ALPHA_BLEND)
				continue;
			const scene_mesh *m = &sc->meshes[o->mesh];
			tlm_vec3 c = tlm_mat4_mul_point(r->world[i], tlm_v3_scale(tlm_v3_add(m->bounds_min, m->bounds_max), 0.5f));
			uint32_t k = n++;
			float d = tlm_v3_length(tlm_v3_sub(c, r->eye));
			while (k > 0 && dist[k - 1] < d) { /* insertion sort, farthest first; ties keep scene order */
				dist[k] = dist[k - 1];
				r->blend_order[k] = r->blend_order[k - 1];
				k--;
			}
			dist[k] = d;
			r->blend_order[k] = (uint32_t)i;
		}
		free(dist);
		bind_scene(r, cmd, &r->shade_blend_pipe);
		for (uint32_t k = 0; k < n; k++)
			draw_object(r, cmd, &r->shade_blend_pipe, slot, 0, r->blend_order[k], 1);
	}
	vkCmdEndRendering(cmd);
	if (r->stats_pool)
		vkCmdEndQuery(cmd, r->stats_pool, 0);
}

void render_pass_display(render *r, VkCommandBuffer cmd)
{
	vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
			    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
			    VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			    VK_ACCESS_2_SHADER_STORAGE_READ_BIT);
	vkdev_barrier_image(cmd, &r->display, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
			    VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COPY_BIT, 0,
			    VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, r->display_pipe.pipeline);
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, r->display_pipe.layout, 0, 1, &r->display_set, 0, NULL);
	vkCmdDispatch(cmd, (r->desc.width + 7) / 8, (r->desc.height + 7) / 8, 1);
}

void render_pass_readback(render *r, VkCommandBuffer cmd)
{
	vkdev_barrier_image(cmd, &r->hdr, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL,
			    VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			    VK_ACCESS_2_SHADER_STORAGE_READ_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
			    VK_ACCESS_2_TRANSFER_READ_BIT);
	vkdev_barrier_image(cmd, &r->display, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL,
			    VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			    VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_COPY_BIT,
			    VK_ACCESS_2_TRANSFER_READ_BIT);
	/* Rows are copied with a padded pitch (bufferRowLength) and repacked on the CPU. */
	VkBufferImageCopy hr = {
		.bufferRowLength = r->row_pitch_hdr_B / 8,
		.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
		.imageExtent = {r->desc.width, r->desc.height, 1},
	};
	VkBufferImageCopy dr = hr;
	dr.bufferRowLength = r->row_pitch_display_B / 4;
	vkCmdCopyImageToBuffer(cmd, r->hdr.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, r->readback_hdr.buffer, 1, &hr);
	vkCmdCopyImageToBuffer(cmd, r->display.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, r->readback_display.buffer, 1, &dr);
	VkMemoryBarrier2 mb = {
		.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER_2,
		.srcStageMask = VK_PIPELINE_STAGE_2_COPY_BIT,
		.srcAccessMask = VK_ACCESS_2_TRANSFER_WRITE_BIT,
		.dstStageMask = VK_PIPELINE_STAGE_2_HOST_BIT,
		.dstAccessMask = VK_ACCESS_2_HOST_READ_BIT,
	};
	VkDependencyInfo di = {.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO, .memoryBarrierCount = 1, .pMemoryBarriers = &mb};
	vkCmdPipelineBarrier2(cmd, &di);
}

/* ------------------------------------------------------------------ pipelines */

/* A graphics pipeline of the frame pipeline; zero-initialised fields mean "off". */
typedef struct pipe_desc {
	const uint32_t *vs, *fs;
	size_t vs_size, fs_size;
	unsigned attributes;   /* bit i: vertex attribute location i (0 position, 1 normal, 2 uv, 3 tangent) */
	int depth_write, color, bias, blend;
	VkCompareOp depth_op;
	int fs_alpha_blend;    /* value of shade.frag's ALPHA_BLEND specialisation constant */
	VkDescriptorSetLayout method_set; /* optional set 1 */
} pipe_desc;

static VkResult make_graphics(render *r, const pipe_desc *pd, render_pipeline *out)
{
	const uint32_t *vs = pd->vs, *fs = pd->fs;
	size_t vs_size = pd->vs_size, fs_size = pd->fs_size;
	VkShaderModule vm = VK_NULL_HANDLE, fm = VK_NULL_HANDLE;
	VkResult res = vkdev_shader_module(r->dev, vs, vs_size, &vm);
	if (!res && fs)
		res = vkdev_shader_module(r->dev, fs, fs_size, &fm);
	if (res)
		goto done;
	VkPushConstantRange pcr = {VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(gpu_push)};
	VkDescriptorSetLayout sets[2] = {r->scene_set_layout, pd->method_set};
	VkPipelineLayoutCreateInfo li = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO,
		.setLayoutCount = pd->method_set ? 2u : 1u,
		.pSetLayouts = sets,
		.pushConstantRangeCount = 1,
		.pPushConstantRanges = &pcr,
	};
	if ((res = vkCreatePipelineLayout(r->dev->device, &li, NULL, &out->layout)))
		goto done;
	/* Specialisation: 0 = shade.frag's ALPHA_BLEND, 1 = SHADOW_CHUNKS_USED (shading.glsl); entries for
	 * constants a shader does not declare are ignored. */
	struct {
		VkBool32 blend;
		int32_t chunks;
	} spec_values = {pd->fs_alpha_blend ? VK_TRUE : VK_FALSE, (int32_t)r->shadow.chunks_compiled};
	VkSpecializationMapEntry spec_entries[2] = {{0, 0, sizeof(VkBool32)}, {1, sizeof(VkBool32), sizeof(int32_t)}};
	VkSpecializationInfo spec = {2, spec_entries, sizeof spec_values, &spec_values};
	VkPipelineShaderStageCreateInfo stages[2] = {
		{.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_VERTEX_BIT,
		 .module = vm, .pName = "main"},
		{.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_FRAGMENT_BIT,
		 .module = fm, .pName = "main", .pSpecializationInfo = &spec},
	};
	VkVertexInputBindingDescription bind = {0, sizeof(scene_vertex), VK_VERTEX_INPUT_RATE_VERTEX};
	const VkVertexInputAttributeDescription all_attrs[4] = {
		{0, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(scene_vertex, position)},
		{1, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(scene_vertex, normal)},
		{2, 0, VK_FORMAT_R32G32_SFLOAT, offsetof(scene_vertex, uv)},
		{3, 0, VK_FORMAT_R32G32B32A32_SFLOAT, offsetof(scene_vertex, tangent)},
	};
	VkVertexInputAttributeDescription attrs[4];
	uint32_t nattr = 0;
	for (int i = 0; i < 4; i++)
		if (pd->attributes & (1u << i))
			attrs[nattr++] = all_attrs[i];
	VkPipelineVertexInputStateCreateInfo vi = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO,
		.vertexBindingDescriptionCount = 1,
		.pVertexBindingDescriptions = &bind,
		.vertexAttributeDescriptionCount = nattr,
		.pVertexAttributeDescriptions = attrs,
	};
	VkPipelineInputAssemblyStateCreateInfo ia = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO,
		.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST,
	};
	VkPipelineViewportStateCreateInfo vps = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO, .viewportCount = 1, .scissorCount = 1};
	VkPipelineRasterizationStateCreateInfo rs = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO,
		.polygonMode = VK_POLYGON_MODE_FILL,
		.cullMode = VK_CULL_MODE_NONE,
		.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE,
		.depthBiasEnable = pd->bias ? VK_TRUE : VK_FALSE,
		.depthBiasConstantFactor = 1.25f,
		.depthBiasSlopeFactor = 1.75f,
		.lineWidth = 1.0f,
	};
	VkPipelineMultisampleStateCreateInfo ms = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO,
		.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT,
	};
	VkPipelineDepthStencilStateCreateInfo ds = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO,
		.depthTestEnable = VK_TRUE,
		.depthWriteEnable = pd->depth_write ? VK_TRUE : VK_FALSE,
		.depthCompareOp = pd->depth_op,
	};
	/* Blending: "over" for colour; coverage alpha accumulates as a + (1 - a) * dst. */
	VkPipelineColorBlendAttachmentState cba = {
		.blendEnable = pd->blend ? VK_TRUE : VK_FALSE,
		.srcColorBlendFactor = VK_BLEND_FACTOR_SRC_ALPHA,
		.dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA,
		.colorBlendOp = VK_BLEND_OP_ADD,
		.srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE,
		.dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA,
		.alphaBlendOp = VK_BLEND_OP_ADD,
		.colorWriteMask = 0xF,
	};
	VkPipelineColorBlendStateCreateInfo cb = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO,
		.attachmentCount = pd->color ? 1u : 0u,
		.pAttachments = &cba,
	};
	VkDynamicState dyn[3] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR, VK_DYNAMIC_STATE_CULL_MODE};
	VkPipelineDynamicStateCreateInfo dy = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO,
		.dynamicStateCount = pd->bias ? 2u : 3u,
		.pDynamicStates = dyn,
	};
	VkFormat cfmt = VK_FORMAT_R16G16B16A16_SFLOAT;
	VkPipelineRenderingCreateInfo pr = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO,
		.colorAttachmentCount = pd->color ? 1u : 0u,
		.pColorAttachmentFormats = &cfmt,
		.depthAttachmentFormat = VK_FORMAT_D32_SFLOAT,
	};
	VkGraphicsPipelineCreateInfo gi = {
		.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO,
		.pNext = &pr,
		.stageCount = fs ? 2u : 1u,
		.pStages = stages,
		.pVertexInputState = &vi,
		.pInputAssemblyState = &ia,
		.pViewportState = &vps,
		.pRasterizationState = &rs,
		.pMultisampleState = &ms,
		.pDepthStencilState = &ds,
		.pColorBlendState = &cb,
		.pDynamicState = &dy,
		.layout = out->layout,
	};
	res = vkCreateGraphicsPipelines(r->dev->device, VK_NULL_HANDLE, 1, &gi, NULL, &out->pipeline);
done:
	if (vm)
		vkDestroyShaderModule(r->dev->device, vm, NULL);
	if (fm)
		vkDestroyShaderModule(r->dev->device, fm, NULL);
	return res;
}

VkResult render_make_shade_pipeline(render *r, const uint32_t *fs, size_t fs_size, VkDescriptorSetLayout method_set,
				    render_pipeline *out)
{
	pipe_desc shade = {.vs = scene_vert, .vs_size = sizeof scene_vert, .attributes = 15u, .color = 1,
			   .depth_op = VK_COMPARE_OP_EQUAL, .fs = fs, .fs_size = fs_size, .method_set = method_set};
	return make_graphics(r, &shade, out);
}

void render_pipeline_destroy(render *r, render_pipeline *p)
{
	if (p->pipeline)
		vkDestroyPipeline(r->dev->device, p->pipeline, NULL);
	if (p->layout)
		vkDestroyPipelineLayout(r->dev->device, p->layout, NULL);
	p->pipeline = VK_NULL_HANDLE;
	p->layout = VK_NULL_HANDLE;
}

/* Run-time shader sources: `#include "common.glsl"` / `"shading.glsl"` / `"tas.glsl"` lines are replaced
 * by the embedded files (each once; they are include-guarded) and the marker `// @OCIO_DISPLAY@` by the
 * OpenColorIO function `ocio_display` of the active view transform (colour.h). */
static int append(char **buf, size_t *len, size_t *cap, const char *s, size_t n)
{
	if (*len + n + 1 > *cap) {
		size_t c = (*cap ? *cap * 2 : 65536) + n;
		char *b = realloc(*buf, c);
		if (!b)
			return -1;
		*buf = b;
		*cap = c;
	}
	memcpy(*buf + *len, s, n);
	*len += n;
	(*buf)[*len] = 0;
	return 0;
}

static int expand_source(const render *r, const char *src, char **buf, size_t *len, size_t *cap, int depth)
{
	static const struct {
		const char *name;
		const char *text;
	} files[] = {{"common.glsl", common_glsl}, {"shading.glsl", shading_glsl}, {"tas.glsl", tas_glsl}, {"tfa.glsl", tfa_glsl}};
	const char *p = src;
	while (*p) {
		size_t n = strcspn(p, "\n");
		const char *line = p, *repl = NULL;
		if (!strncmp(line, "#include \"", 10)) {
			for (size_t i = 0; i < sizeof files / sizeof files[0]; i++)
				if (!strncmp(line + 10, files[i].name, strlen(files[i].name)))
					repl = files[i].text;
			if (!repl || depth > 4)
				return -1;
			if (expand_source(r, repl, buf, len, cap, depth + 1))
				return -1;
		} else if (!strncmp(line, "#extension GL_GOOGLE_include_directive", 38)) {
			/* resolved here */
		} else if (!strncmp(line, "// @OCIO_DISPLAY@", 17)) {
			const char *fn = colour_glsl(r->colour);
			if (append(buf, len, cap, fn, strlen(fn)))
				return -1;
		} else if (append(buf, len, cap, line, n)) {
			return -1;
		}
		p += n;
		if (*p == '\n')
			p++;
		if (append(buf, len, cap, "\n", 1))
			return -1;
	}
	return 0;
}

int render_compile(const render *r, const char *template_src, shc_stage stage, uint32_t **spv, size_t *spv_size,
		   char *err, size_t err_size)
{
	char *src = NULL;
	size_t len = 0, cap = 0;
	if (expand_source(r, template_src, &src, &len, &cap, 0)) {
		free(src);
		snprintf(err, err_size, "out of memory or unknown include assembling a shader");
		return RENDER_ERR_NOMEM;
	}
	int bad = shc_compile(src, stage, spv, spv_size, err, err_size);
	free(src);
	return bad ? RENDER_ERR_ARG : 0;
}

/* Display pass: display.comp.in with the OpenColorIO function of the active view transform inserted. */
static VkResult make_display_pipeline(render *r, char *err, size_t err_size)
{
	uint32_t *spv = NULL;
	size_t spv_size = 0;
	int bad = render_compile(r, display_comp_in, SHC_STAGE_COMPUTE, &spv, &spv_size, err, err_size);
	if (bad == RENDER_ERR_NOMEM)
		return VK_ERROR_OUT_OF_HOST_MEMORY;
	if (bad)
		return VK_ERROR_INITIALIZATION_FAILED;
	VkShaderModule cm;
	VkResult res = vkdev_shader_module(r->dev, spv, spv_size, &cm);
	free(spv);
	if (res)
		return res;
	VkPipelineLayoutCreateInfo li = {
		.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO,
		.setLayoutCount = 1,
		.pSetLayouts = &r->display_set_layout,
	};
	if (!(res = vkCreatePipelineLayout(r->dev->device, &li, NULL, &r->display_pipe.layout))) {
		VkComputePipelineCreateInfo ci = {
			.sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
			.stage = {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
				  .stage = VK_SHADER_STAGE_COMPUTE_BIT, .module = cm, .pName = "main"},
			.layout = r->display_pipe.layout,
		};
		res = vkCreateComputePipelines(r->dev->device, VK_NULL_HANDLE, 1, &ci, NULL, &r->display_pipe.pipeline);
	}
	vkDestroyShaderModule(r->dev->device, cm, NULL);
	return res;
}

static int create_descriptors(render *r, char *err, size_t err_size)
{
	int rc = 0;
	VkDevice d = r->dev->device;
	VkShaderStageFlags gs = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT | VK_SHADER_STAGE_COMPUTE_BIT;
	VkDescriptorSetLayoutBinding sb[6] = {
		{0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, gs, NULL},
		{1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, gs, NULL},
		{2, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, gs, NULL},
		{3, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, gs, NULL},
		{4, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, gs, NULL},
		{5, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, GPU_SHADOW_CHUNKS, gs, NULL},
	};
	VkDescriptorSetLayoutCreateInfo sl = {
		.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO, .bindingCount = 6, .pBindings = sb};
	CHECK_VK(vkCreateDescriptorSetLayout(d, &sl, NULL, &r->scene_set_layout));
	VkDescriptorSetLayoutBinding db[2] = {
		{0, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL},
		{1, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL},
	};
	VkDescriptorSetLayoutCreateInfo dl = {
		.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO, .bindingCount = 2, .pBindings = db};
	CHECK_VK(vkCreateDescriptorSetLayout(d, &dl, NULL, &r->display_set_layout));
	VkDescriptorPoolSize ps[3] = {
		{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 32},
		{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 64},
		{VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 64},
	};
	VkDescriptorPoolCreateInfo pi = {
		.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO, .maxSets = 16, .poolSizeCount = 3, .pPoolSizes = ps};
	CHECK_VK(vkCreateDescriptorPool(d, &pi, NULL, &r->pool));
	VkDescriptorSetAllocateInfo ai = {
		.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
		.descriptorPool = r->pool,
		.descriptorSetCount = 1,
		.pSetLayouts = &r->scene_set_layout,
	};
	CHECK_VK(vkAllocateDescriptorSets(d, &ai, &r->scene_set));
	ai.pSetLayouts = &r->display_set_layout;
	CHECK_VK(vkAllocateDescriptorSets(d, &ai, &r->display_set));
	VkDescriptorBufferInfo bi[3] = {
		{r->states.buffer, 0, VK_WHOLE_SIZE},
		{r->objects.buffer, 0, VK_WHOLE_SIZE},
		{r->materials.buffer, 0, VK_WHOLE_SIZE},
	};
	VkDescriptorImageInfo ii[2] = {
		{r->tex_sampler, r->color_tex.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL},
		{r->tex_sampler, r->data_tex.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL},
	}; /* binding 5 (shadow maps): render_shadow.c */
	VkDescriptorImageInfo si[2] = {
		{VK_NULL_HANDLE, r->hdr.view, VK_IMAGE_LAYOUT_GENERAL},
		{VK_NULL_HANDLE, r->display.view, VK_IMAGE_LAYOUT_GENERAL},
	};
	VkWriteDescriptorSet w[7];
	for (uint32_t i = 0; i < 3; i++)
		w[i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = r->scene_set,
					      .dstBinding = i, .descriptorCount = 1,
					      .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .pBufferInfo = &bi[i]};
	for (uint32_t i = 0; i < 2; i++)
		w[3 + i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = r->scene_set,
						  .dstBinding = 3 + i, .descriptorCount = 1,
						  .descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
						  .pImageInfo = &ii[i]};
	for (uint32_t i = 0; i < 2; i++)
		w[5 + i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = r->display_set,
						  .dstBinding = i, .descriptorCount = 1,
						  .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, .pImageInfo = &si[i]};
	vkUpdateDescriptorSets(d, 7, w, 0, NULL);
fail:
	return rc;
}

static int create_targets(render *r, char *err, size_t err_size)
{
	int rc = 0;
	const scene *s = r->scene;
	uint32_t w = r->desc.width, h = r->desc.height;
	VkSamplerCreateInfo si = {
		.sType = VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO,
		.magFilter = VK_FILTER_LINEAR,
		.minFilter = VK_FILTER_LINEAR,
		.mipmapMode = VK_SAMPLER_MIPMAP_MODE_LINEAR,
		.addressModeU = VK_SAMPLER_ADDRESS_MODE_REPEAT,
		.addressModeV = VK_SAMPLER_ADDRESS_MODE_REPEAT,
		.addressModeW = VK_SAMPLER_ADDRESS_MODE_REPEAT,
		.maxLod = VK_LOD_CLAMP_NONE,
	};
	CHECK_VK(vkCreateSampler(r->dev->device, &si, NULL, &r->tex_sampler));
	VkSamplerCreateInfo sh = si;
	sh.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
	sh.addressModeU = sh.addressModeV = sh.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
	sh.compareEnable = VK_TRUE;
	sh.compareOp = VK_COMPARE_OP_LESS_OR_EQUAL;
	sh.maxLod = 0.0f;
	CHECK_VK(vkCreateSampler(r->dev->device, &sh, NULL, &r->shadow_sampler));

	r->light_shadow_layer = calloc(s->light_count + 1, sizeof *r->light_shadow_layer);
	if (!r->light_shadow_layer) {
		rc = RENDER_ERR_NOMEM;
		snprintf(err, err_size, "out of memory");
		goto fail;
	}
	for (size_t i = 0; i < s->light_count; i++) {
		r->light_shadow_layer[i] = s->lights[i].casts_shadow ? (int)r->shadow.layers : -1;
		if (s->lights[i].casts_shadow)
			r->shadow.layers += s->lights[i].kind == SCENE_LIGHT_POINT ? 6 : 1;
	}
	CHECK_VK(vkdev_image_create(r->dev, w, h, 1, 1, VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
				    VK_IMAGE_ASPECT_DEPTH_BIT, false, "depth", &r->depth));
	CHECK_VK(vkdev_image_create(r->dev, w, h, 1, 1, VK_FORMAT_R16G16B16A16_SFLOAT,
				    VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT |
				    VK_IMAGE_USAGE_TRANSFER_SRC_BIT, VK_IMAGE_ASPECT_COLOR_BIT, false, "hdr", &r->hdr));
	CHECK_VK(vkdev_image_create(r->dev, w, h, 1, 1, VK_FORMAT_R8G8B8A8_UNORM,
				    VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
				    false, "display", &r->display));
	r->row_pitch_hdr_B = (w * 8 + 255) & ~255u;
	r->row_pitch_display_B = (w * 4 + 255) & ~255u;
	CHECK_VK(vkdev_buffer_create(r->dev, (VkDeviceSize)r->row_pitch_hdr_B * h, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true,
				     "readback hdr", &r->readback_hdr));
	CHECK_VK(vkdev_buffer_create(r->dev, (VkDeviceSize)r->row_pitch_display_B * h, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
				     true, "readback display", &r->readback_display));
	r->hdr_packed = malloc((size_t)w * h * 8);
	r->display_packed = malloc((size_t)w * h * 4);
	if (!r->hdr_packed || !r->display_packed) {
		rc = RENDER_ERR_NOMEM;
		snprintf(err, err_size, "out of memory for %ux%u frame buffers", w, h);
	}
fail:
	return rc;
}

/* The reference shading pipelines (opaque/masked and BLEND); they sample shadow maps, so they are
 * re-created when the shadow pool outgrows the chunk count they were specialised for. */
static VkResult make_shade_pipelines(render *r)
{
	pipe_desc shade = {.vs = scene_vert, .vs_size = sizeof scene_vert, .attributes = 15u, .color = 1,
			   .depth_op = VK_COMPARE_OP_EQUAL, .fs = shade_frag, .fs_size = sizeof shade_frag};
	if (r->desc.trivial_shading) {
		shade.fs = trivial_frag;
		shade.fs_size = sizeof trivial_frag;
	}
	VkResult res = make_graphics(r, &shade, &r->shade_pipe);
	if (!res && has_alpha_mode(r, SCENE_ALPHA_BLEND)) {
		pipe_desc sb = shade;
		sb.depth_op = VK_COMPARE_OP_LESS_OR_EQUAL;
		sb.blend = 1;
		sb.fs_alpha_blend = !r->desc.trivial_shading;
		res = make_graphics(r, &sb, &r->shade_blend_pipe);
	}
	return res;
}

/* After render_shadow_plan added chunks beyond what the shading pipelines were specialised for. */
static int rebuild_shading(render *r, char *err, size_t err_size)
{
	int rc = 0;
	render_pipeline_destroy(r, &r->shade_pipe);
	render_pipeline_destroy(r, &r->shade_blend_pipe);
	r->shadow.chunks_compiled = r->shadow.chunk_count;
	CHECK_VK(make_shade_pipelines(r));
	if (r->method->rebuild)
		rc = r->method->rebuild(r, err, err_size);
fail:
	return rc;
}

static int create_pipelines(render *r, char *err, size_t err_size)
{
	int rc = 0;
	const unsigned POS = 1u, UV = 4u, ALL = 15u;
	pipe_desc shadow = {.vs = shadow_vert, .vs_size = sizeof shadow_vert, .attributes = POS, .depth_write = 1,
			    .depth_op = VK_COMPARE_OP_LESS, .bias = 1};
	pipe_desc depth = {.vs = scene_vert, .vs_size = sizeof scene_vert, .attributes = ALL, .depth_write = 1,
			   .depth_op = VK_COMPARE_OP_LESS};
	CHECK_VK(make_graphics(r, &shadow, &r->shadow_pipe));
	CHECK_VK(make_graphics(r, &depth, &r->depth_pipe));
	CHECK_VK(make_shade_pipelines(r));
	if (has_alpha_mode(r, SCENE_ALPHA_MASK)) {
		pipe_desc sm = shadow, dm = depth;
		sm.vs = shadow_mask_vert, sm.vs_size = sizeof shadow_mask_vert, sm.attributes = POS | UV;
		sm.fs = dm.fs = depth_mask_frag;
		sm.fs_size = dm.fs_size = sizeof depth_mask_frag;
		CHECK_VK(make_graphics(r, &sm, &r->shadow_mask_pipe));
		CHECK_VK(make_graphics(r, &dm, &r->depth_mask_pipe));
	}
	if (has_alpha_mode(r, SCENE_ALPHA_BLEND)) {
		for (size_t i = 0; i < r->scene->object_count; i++) {
			const scene_object *o = &r->scene->objects[i];
			r->blend_count += o->mesh >= 0 && r->scene->materials[o->material].alpha_mode == SCENE_ALPHA_BLEND;
		}
		r->blend_order = calloc(r->blend_count, sizeof *r->blend_order);
		if (!r->blend_order) {
			rc = RENDER_ERR_NOMEM;
			snprintf(err, err_size, "out of memory");
			goto fail;
		}
	}
	VkResult dr = make_display_pipeline(r, err, err_size);
	if (dr == VK_ERROR_INITIALIZATION_FAILED) { /* shader compilation: `err` holds the compiler's message */
		rc = RENDER_ERR_ARG;
		goto fail;
	}
	CHECK_VK(dr);
	r->ts_count = 0;
	if (r->dev->has_timestamps) {
		VkQueryPoolCreateInfo qi = {
			.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO,
			.queryType = VK_QUERY_TYPE_TIMESTAMP,
			.queryCount = RENDER_MAX_PASSES + 1,
		};
		CHECK_VK(vkCreateQueryPool(r->dev->device, &qi, NULL, &r->ts_pool));
	}
	if (r->dev->has_pipeline_stats) {
		VkQueryPoolCreateInfo qi = {
			.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO,
			.queryType = VK_QUERY_TYPE_PIPELINE_STATISTICS,
			.queryCount = 1,
			.pipelineStatistics = VK_QUERY_PIPELINE_STATISTIC_FRAGMENT_SHADER_INVOCATIONS_BIT |
					      VK_QUERY_PIPELINE_STATISTIC_COMPUTE_SHADER_INVOCATIONS_BIT,
		};
		CHECK_VK(vkCreateQueryPool(r->dev->device, &qi, NULL, &r->stats_pool));
	}
	VkCommandBufferAllocateInfo ai = {
		.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
		.commandPool = r->dev->cmd_pool,
		.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
		.commandBufferCount = 1,
	};
	CHECK_VK(vkAllocateCommandBuffers(r->dev->device, &ai, &r->cmd));
	VkFenceCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
	CHECK_VK(vkCreateFence(r->dev->device, &fi, NULL, &r->fence));
fail:
	return rc;
}

/* ------------------------------------------------------------------ lifecycle */

int render_create(vkdev *dev, const render_desc *desc, render **out, char *err, size_t err_size)
{
	*out = NULL;
	const render_method_ops *m = NULL;
	for (size_t i = 0; i < sizeof method_table / sizeof method_table[0]; i++)
		if (desc->method && !strcmp(method_table[i]->info.name, desc->method))
			m = method_table[i];
	if (!m) {
		size_t n;
		const render_method_info *all = render_methods(&n);
		for (size_t i = 0; i < n; i++)
			if (desc->method && !strcmp(all[i].name, desc->method)) {
				snprintf(err, err_size, "method '%s' is not implemented yet (available: ref, tfr)", desc->method);
				return RENDER_ERR_ARG;
			}
		snprintf(err, err_size, "unknown method '%s' (see 'taslab render --help' for the list)",
			 desc->method ? desc->method : "(none)");
		return RENDER_ERR_ARG;
	}
	return render_create_ops(dev, desc, m, out, err, err_size);
}

int render_create_ops(vkdev *dev, const render_desc *desc, const render_method_ops *m, render **out, char *err,
		      size_t err_size)
{
	int rc = 0;
	*out = NULL;
	if (!desc->scene || desc->camera < 0 || (size_t)desc->camera >= desc->scene->camera_count) {
		snprintf(err, err_size, "no such camera path");
		return RENDER_ERR_ARG;
	}
	if (desc->width < 1 || desc->height < 1 || desc->width > 16384 || desc->height > 16384) {
		snprintf(err, err_size, "frame size %ux%u out of range (1..16384)", desc->width, desc->height);
		return RENDER_ERR_ARG;
	}
	render *r = calloc(1, sizeof *r);
	if (!r) {
		snprintf(err, err_size, "out of memory");
		return RENDER_ERR_NOMEM;
	}
	r->dev = dev;
	r->scene = desc->scene;
	r->desc = *desc;
	r->method = m;
	if (!(r->desc.fps > 0.0f))
		r->desc.fps = r->scene->fps;
	r->state_ring = m->state_ring ? m->state_ring : 1;
	r->world = calloc(r->scene->object_count, sizeof *r->world);
	r->light_states = calloc(r->scene->light_count + 1, sizeof *r->light_states);
	if (!r->world || !r->light_states) {
		snprintf(err, err_size, "out of memory");
		rc = RENDER_ERR_NOMEM;
		goto fail;
	}
	r->colour = desc->colour;
	if (!r->colour) {
		colour_desc cd = {0};
		if (colour_create(&cd, &r->own_colour, err, err_size)) {
			rc = RENDER_ERR_ARG;
			goto fail;
		}
		r->colour = r->own_colour;
	}
	if ((rc = upload_scene(r, err, err_size)) || (rc = create_targets(r, err, err_size)) ||
	    (rc = create_descriptors(r, err, err_size)) || (rc = render_shadow_init(r, err, err_size)))
		goto fail;
	/* Shading pipelines are specialised for the shadow chunks in use: methods driven by render_frame
	 * start with one and are rebuilt when the pool grows; others get the worst case up front. */
	r->shadow.chunks_compiled = m->prepare && (m == &render_method_ref || m->rebuild) ? 1 : r->shadow.chunks_max;
	if ((rc = create_pipelines(r, err, err_size)))
		goto fail;
	if (m->init && (rc = m->init(r, err, err_size)))
		goto fail;
	*out = r;
	return 0;
fail:
	render_destroy(&r);
	return rc;
}

void render_destroy(render **pr)
{
	if (!pr || !*pr)
		return;
	render *r = *pr;
	VkDevice d = r->dev->device;
	vkDeviceWaitIdle(d);
	if (r->method && r->method->finish)
		r->method->finish(r);
	render_pipeline *pipes[] = {&r->shadow_pipe,	  &r->depth_pipe,      &r->shade_pipe,	    &r->display_pipe,
				    &r->shadow_mask_pipe, &r->depth_mask_pipe, &r->shade_blend_pipe};
	for (size_t i = 0; i < sizeof pipes / sizeof pipes[0]; i++) {
		if (pipes[i]->pipeline)
			vkDestroyPipeline(d, pipes[i]->pipeline, NULL);
		if (pipes[i]->layout)
			vkDestroyPipelineLayout(d, pipes[i]->layout, NULL);
	}
	if (r->fence)
		vkDestroyFence(d, r->fence, NULL);
	if (r->cmd)
		vkFreeCommandBuffers(d, r->dev->cmd_pool, 1, &r->cmd);
	if (r->ts_pool)
		vkDestroyQueryPool(d, r->ts_pool, NULL);
	if (r->stats_pool)
		vkDestroyQueryPool(d, r->stats_pool, NULL);
	if (r->pool)
		vkDestroyDescriptorPool(d, r->pool, NULL);
	if (r->scene_set_layout)
		vkDestroyDescriptorSetLayout(d, r->scene_set_layout, NULL);
	if (r->display_set_layout)
		vkDestroyDescriptorSetLayout(d, r->display_set_layout, NULL);
	if (r->scene_set && getenv("TASLAB_DEBUG_SHADOWS")) /* shadow pool report (README "Renderer decisions") */
		fprintf(stderr, "shadow pool: %llu layer renderings, %llu shared, %u of %u chunks of %u layers\n",
			(unsigned long long)r->shadow.rendered, (unsigned long long)r->shadow.reused, r->shadow.chunk_count,
			r->shadow.chunks_max, r->shadow.chunk_layers);
	if (r->scene_set)
		render_shadow_destroy(r);
	if (r->tex_sampler)
		vkDestroySampler(d, r->tex_sampler, NULL);
	if (r->shadow_sampler)
		vkDestroySampler(d, r->shadow_sampler, NULL);
	vkdev_image *imgs[] = {&r->color_tex, &r->data_tex, &r->depth, &r->hdr, &r->display};
	for (size_t i = 0; i < 5; i++)
		vkdev_image_destroy(r->dev, imgs[i]);
	vkdev_buffer *bufs[] = {&r->vertices, &r->indices, &r->materials, &r->states, &r->objects,
				&r->readback_hdr, &r->readback_display};
	for (size_t i = 0; i < 7; i++)
		vkdev_buffer_destroy(r->dev, bufs[i]);
	colour_destroy(&r->own_colour);
	free(r->blend_order);
	free(r->light_shadow_layer);
	free(r->mesh_first_index);
	free(r->mesh_vertex_offset);
	free(r->hdr_packed);
	free(r->display_packed);
	free(r->world);
	free(r->light_states);
	free(r);
	*pr = NULL;
}

VkResult render_cmd_begin(render *r)
{
	VkCommandBufferBeginInfo bi = {
		.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
		.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT,
	};
	VkResult res = vkResetCommandBuffer(r->cmd, 0);
	return res ? res : vkBeginCommandBuffer(r->cmd, &bi);
}

VkResult render_cmd_submit_wait(render *r)
{
	VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO, .commandBufferCount = 1, .pCommandBuffers = &r->cmd};
	VkResult res = vkEndCommandBuffer(r->cmd);
	if (!res)
		res = vkResetFences(r->dev->device, 1, &r->fence);
	if (!res)
		res = vkQueueSubmit(r->dev->queue, 1, &si, r->fence);
	return res ? res : vkWaitForFences(r->dev->device, 1, &r->fence, VK_TRUE, UINT64_MAX);
}

int render_frame(render *r, uint32_t frame, render_image *img, render_stats *st, char *err, size_t err_size)
{
	int rc = 0;
	VkCommandBuffer cmd = r->cmd;
	if (r->method->prepare && (rc = r->method->prepare(r, frame, err, err_size)))
		return rc;
	if (r->shadow.chunk_count > r->shadow.chunks_compiled && (rc = rebuild_shading(r, err, err_size)))
		return rc;
	CHECK_VK(render_cmd_begin(r));
	if (r->ts_pool)
		vkCmdResetQueryPool(cmd, r->ts_pool, 0, RENDER_MAX_PASSES + 1);
	r->ts_count = 0;
	r->method->record(r, cmd, frame);
	CHECK_VK(render_cmd_submit_wait(r));

	uint32_t w = r->desc.width, h = r->desc.height;
	for (uint32_t y = 0; y < h; y++) {
		memcpy(r->hdr_packed + (size_t)y * w * 4, (uint8_t *)r->readback_hdr.mapped + (size_t)y * r->row_pitch_hdr_B,
		       (size_t)w * 8);
		memcpy(r->display_packed + (size_t)y * w * 4,
		       (uint8_t *)r->readback_display.mapped + (size_t)y * r->row_pitch_display_B, (size_t)w * 4);
	}
	img->width = w;
	img->height = h;
	img->hdr_rgba_half = r->hdr_packed;
	img->display_rgba = r->display_packed;

	memset(st, 0, sizeof *st);
	st->frame = frame;
	st->time_s = (double)frame / (double)r->desc.fps;
	int64_t visible = 0;
	for (size_t i = 0; i < (size_t)w * h; i++)
		visible += r->hdr_packed[i * 4 + 3] != 0; /* half-float coverage: 0 or 1.0 */
	st->visible_samples = visible;
	st->shaded_samples = st->reused_samples = st->visible_units = st->shaded_units = st->new_units = -1;
	st->fs_invocations = st->cs_invocations = -1;
	if (r->stats_pool) {
		uint64_t v[2];
		if (vkGetQueryPoolResults(r->dev->device, r->stats_pool, 0, 1, sizeof v, v, sizeof v,
					  VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) == VK_SUCCESS) {
			st->fs_invocations = (int64_t)v[0];
			st->cs_invocations = (int64_t)v[1];
		}
	}
	st->pass_count = r->method->pass_count;
	uint64_t ts[RENDER_MAX_PASSES + 1] = {0};
	int have_ts = r->ts_pool && r->ts_count == r->method->pass_count + 1 &&
		      vkGetQueryPoolResults(r->dev->device, r->ts_pool, 0, r->ts_count, sizeof ts, ts, sizeof ts[0],
					    VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) == VK_SUCCESS;
	double period_ms = r->dev->props.limits.timestampPeriod * 1e-6;
	for (uint32_t p = 0; p < st->pass_count; p++) {
		st->pass_names[p] = r->method->pass_names[p];
		st->gpu_ms[p] = have_ts ? (double)(ts[p + 1] - ts[p]) * period_ms : -1.0;
	}
	st->gpu_ms_total = have_ts ? (double)(ts[st->pass_count] - ts[0]) * period_ms : -1.0;
	if (r->method->collect)
		r->method->collect(r, st);
fail:
	return rc;
}
