/* upload.c — the scene on the device: geometry, materials, texture arrays with mip chains (CPU mips from
 * the scene library's texture.h), and the state and object rings. */
#include "render_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/texture.h"

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
	uint32_t size = layers ? n : 1, mips = layers ? tex_mip_count(n) : 1;
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
		rc = TL_ERR_NOMEM;
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
				tex_mip_down(dst + off, e, dst + off + (size_t)e * e * 4, srgb);
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

int render_upload_rings(render *r, char *err, size_t err_size)
{
	int rc = 0;
	/* stereo: one more slot, the centre eye's (render_center_slot) */
	size_t slots = r->state_ring + (r->view_count > 1 ? 1 : 0), objects = r->scene->object_count ? r->scene->object_count : 1;
	CHECK_VK(vkdev_buffer_create(r->dev, slots * sizeof(gpu_frame_state), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
				     true, "frame states", &r->states));
	CHECK_VK(vkdev_buffer_create(r->dev, slots * objects * sizeof(gpu_object),
				     VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true, "objects", &r->objects));
	CHECK_VK(vkdev_buffer_create(r->dev, 4 * sizeof(uint32_t), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
				     VK_BUFFER_USAGE_TRANSFER_DST_BIT, true, "shade count", &r->shade_count));
fail:
	return rc;
}

int render_upload_scene(render *r, char *err, size_t err_size)
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
		rc = TL_ERR_NOMEM;
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
	rc = render_upload_rings(r, err, err_size);
fail:
	free(verts);
	free(idx);
	free(srgb_layer);
	free(data_layer);
	free(mats);
	return rc;
}

void render_upload_destroy(render *r)
{
	vkdev_image_destroy(r->dev, &r->color_tex);
	vkdev_image_destroy(r->dev, &r->data_tex);
	vkdev_buffer *bufs[] = {&r->vertices, &r->indices, &r->materials, &r->states, &r->objects, &r->shade_count};
	for (size_t i = 0; i < sizeof bufs / sizeof bufs[0]; i++)
		vkdev_buffer_destroy(r->dev, bufs[i]);
	free(r->mesh_first_index);
	free(r->mesh_vertex_offset);
	r->mesh_first_index = r->mesh_vertex_offset = NULL;
}
