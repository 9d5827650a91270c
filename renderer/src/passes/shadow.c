/* shadow.c — shadow maps as a pool of physical layers shared by the state slots.
 *
 * Temporal forward rendering (DESIGN section 4, paper sec. 3) shades a surface point with the shadow
 * maps of up to K = 119 frames ago, so every state slot of the ring keeps its own shadow maps. Most
 * shadow layers do not change every frame (static lights whose frustum no moving caster enters), so
 * a slot's logical layer maps to a *physical* layer, and a layer whose inputs are unchanged since the
 * last rendering of that logical layer shares the physical layer instead of being rendered again (for
 * every method: ref renders a layer only when its key changed). The inputs are keyed exactly: the layer's
 * light matrix plus index and world matrix of every shadow caster whose bounds reach into the light frustum
 * (bounding-box corners tested against the clip planes, conservative), so sharing never changes a pixel;
 * a rendered layer draws only those casters.
 *
 * Physical layers live in array images ("chunks", at most 15/16 of maxMemoryAllocationSize each, up to
 * GPU_SHADOW_CHUNKS). Every logical layer is pinned to one chunk that can hold its worst case (one physical
 * layer per state slot, plus one while a plan replaces a slot's layer), so the chunk a light samples is
 * known when pipelines are created: shading.glsl unrolls its light loop and samples each light's chunk with
 * a constant index (render_shadow_light_code). Chunk images are allocated when their first layer is needed. */
#include "passes.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NO_PHYS UINT32_MAX
#define CHUNK_BYTES_MAX ((VkDeviceSize)1 << 30) /* when the device does not report maxMemoryAllocationSize */

static uint64_t fnv(uint64_t h, const void *data, size_t n)
{
	const unsigned char *p = data;
	for (size_t i = 0; i < n; i++) {
		h ^= p[i];
		h *= 1099511628211ull;
	}
	return h;
}

/* True when the object's bounding box may reach into the clip volume of `m` (column-major). */
static int box_in_frustum(const float m[16], const float world[16], tlm_vec3 lo, tlm_vec3 hi)
{
	float c[8][4];
	for (int k = 0; k < 8; k++) {
		float p[3] = {k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z};
		float w[4];
		for (int r = 0; r < 4; r++)
			w[r] = world[r] * p[0] + world[4 + r] * p[1] + world[8 + r] * p[2] + world[12 + r];
		for (int r = 0; r < 4; r++)
			c[k][r] = m[r] * w[0] + m[4 + r] * w[1] + m[8 + r] * w[2] + m[12 + r] * w[3];
	}
	/* Planes: w+x, w-x, w+y, w-y, z, w-z >= 0 (Vulkan depth range). */
	for (int pl = 0; pl < 6; pl++) {
		int outside = 0;
		for (int k = 0; k < 8; k++) {
			float x = c[k][0], y = c[k][1], z = c[k][2], w = c[k][3];
			float v = pl == 0 ? w + x : pl == 1 ? w - x : pl == 2 ? w + y : pl == 3 ? w - y : pl == 4 ? z : w - z;
			outside += v < 0.0f;
		}
		if (outside == 8)
			return 0;
	}
	return 1;
}

/* The inputs of logical layer `layer` at `slot`; `casters` (object_count bits) receives the casters that
 * reach into the layer's frustum, the only ones drawn into it. */
static uint64_t layer_key(const render *r, uint32_t slot, uint32_t layer, uint8_t *casters)
{
	const scene *s = r->scene;
	const gpu_frame_state *st = (const gpu_frame_state *)r->states.mapped + slot;
	const gpu_object *ob = (const gpu_object *)r->objects.mapped + (size_t)slot * s->object_count;
	uint64_t h = fnv(1469598103934665603ull, st->shadow_matrix[layer], sizeof st->shadow_matrix[layer]);
	memset(casters, 0, (s->object_count + 7) / 8);
	for (size_t i = 0; i < s->object_count; i++) {
		const scene_object *o = &s->objects[i];
		if (o->mesh < 0 || !o->casts_shadow || s->materials[o->material].alpha_mode == SCENE_ALPHA_BLEND)
			continue;
		const scene_mesh *me = &s->meshes[o->mesh];
		if (!box_in_frustum(st->shadow_matrix[layer], ob[i].world, me->bounds_min, me->bounds_max))
			continue;
		casters[i / 8] |= (uint8_t)(1u << (i % 8));
		uint32_t idx = (uint32_t)i;
		h = fnv(h, &idx, sizeof idx);
		h = fnv(h, ob[i].world, sizeof ob[i].world);
	}
	return h;
}

/* Binding 5 of every view's scene set (stereo: both eyes sample the one pool). */
void render_shadow_write_sets(render *r)
{
	render_shadow_pool *p = &r->shadow;
	VkDescriptorImageInfo ii[GPU_SHADOW_CHUNKS];
	for (uint32_t c = 0; c < GPU_SHADOW_CHUNKS; c++)
		ii[c] = (VkDescriptorImageInfo){r->shadow_sampler,
						p->chunks[c].view ? p->chunks[c].view : p->dummy.view,
						VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
	for (uint32_t v = 0; v < (r->view_count ? r->view_count : 1); v++) {
		VkDescriptorSet set = v == r->view ? r->scene_set : r->views[v].scene_set;
		if (!set)
			continue; /* a view not created yet: written when it is */
		VkWriteDescriptorSet w = {.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = set,
					  .dstBinding = 5, .descriptorCount = GPU_SHADOW_CHUNKS,
					  .descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, .pImageInfo = ii};
		vkUpdateDescriptorSets(r->dev->device, 1, &w, 0, NULL);
	}
}

/* Depth image with all layers in SHADER_READ_ONLY (sampled layers must have a defined layout). */
static VkResult make_chunk(render *r, uint32_t size, uint32_t layers, const char *name, vkdev_image *img)
{
	VkResult res = vkdev_image_create(r->dev, size, size, layers, 1, VK_FORMAT_D32_SFLOAT,
					  VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
					  VK_IMAGE_ASPECT_DEPTH_BIT, true, name, img);
	VkCommandBuffer cmd;
	if (!res)
		res = vkdev_cmd_begin(r->dev, &cmd);
	if (res)
		return res;
	vkdev_barrier_image(cmd, img, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
			    VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0,
			    VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
	return vkdev_cmd_submit_wait(r->dev, cmd);
}

/* Allocates chunk c (its image and one view per layer) when its first layer is needed. */
static int add_chunk(render *r, uint32_t c, char *err, size_t err_size)
{
	render_shadow_pool *p = &r->shadow;
	char name[32];
	snprintf(name, sizeof name, "shadow chunk %u", c);
	VkResult res = make_chunk(r, p->size, p->chunk_cap[c], name, &p->chunks[c]);
	if (res) {
		vkdev_image_destroy(r->dev, &p->chunks[c]);
		return tl_error(err, err_size, res == VK_ERROR_OUT_OF_HOST_MEMORY || res == VK_ERROR_OUT_OF_DEVICE_MEMORY
							? TL_ERR_NOMEM : TL_ERR_VULKAN,
				"cannot allocate %u shadow-map layers of %ux%u (%s); lower shadow_map_size in the scene",
				p->chunk_cap[c], p->size, p->size, vkdev_result_string(res));
	}
	for (uint32_t l = 0; l < p->chunk_cap[c]; l++) {
		VkImageViewCreateInfo vi = {
			.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO,
			.image = p->chunks[c].image,
			.viewType = VK_IMAGE_VIEW_TYPE_2D,
			.format = VK_FORMAT_D32_SFLOAT,
			.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, l, 1},
		};
		if ((res = vkCreateImageView(r->dev->device, &vi, NULL, &p->views[p->chunk_base[c] + l])))
			return render_vk_error(err, err_size, "vkCreateImageView (shadow layer)", res);
	}
	p->chunk_count++;
	render_shadow_write_sets(r);
	return TL_OK;
}

/* Pins the logical layers to chunks: a light's layers stay together when its worst case fits one chunk
 * (a point light's six faces), else its faces fill chunks one by one; lights are packed in order. */
static int assign_chunks(render *r, uint32_t per_layer, uint32_t cap_max, char *err, size_t err_size)
{
	render_shadow_pool *p = &r->shadow;
	const scene *s = r->scene;
	uint32_t c = 0, used = 0;
	for (size_t i = 0; i < s->light_count; i++) {
		int first = r->light_shadow_layer[i];
		r->shadow.light_code[i] = -1;
		if (first < 0)
			continue;
		uint32_t faces = s->lights[i].kind == SCENE_LIGHT_POINT ? 6 : 1;
		uint32_t together = faces * per_layer <= cap_max;
		/* a light that fits starts a new chunk when this one is too full; a split one always does, so
		 * that its faces span as few chunks as possible (two when half of them fit one) */
		if (used && (!together || used + faces * per_layer > cap_max))
			c++, used = 0;
		uint32_t chunk_a = NO_PHYS, chunk_b = NO_PHYS, split = faces;
		for (uint32_t f = 0; f < faces; f++) {
			if (used + per_layer > cap_max)
				c++, used = 0;
			if (c >= GPU_SHADOW_CHUNKS)
				return tl_error(err, err_size, TL_ERR_NOMEM,
						"the shadow-map history needs more than %u array images of %u layers of %ux%u (%u "
						"layers x %u slots); lower shadow_map_size in the scene",
						GPU_SHADOW_CHUNKS, cap_max, p->size, p->size, p->layers, r->state_ring);
			p->layer_chunk[first + f] = c;
			p->chunk_cap[c] += per_layer;
			used += per_layer;
			if (chunk_a == NO_PHYS)
				chunk_a = c;
			else if (c != chunk_a && chunk_b == NO_PHYS)
				chunk_b = c, split = f;
			else if (c != chunk_a && c != chunk_b)
				return tl_error(err, err_size, TL_ERR_NOMEM, "a point light's shadow history spans more than two "
						"array images; lower shadow_map_size in the scene");
		}
		if (chunk_b == NO_PHYS)
			chunk_b = chunk_a;
		p->light_code[i] = (int32_t)(chunk_a | chunk_b << 8 | split << 16);
	}
	p->chunks_max = p->layers ? c + 1 : 0;
	for (uint32_t k = 1; k < GPU_SHADOW_CHUNKS; k++)
		p->chunk_base[k] = p->chunk_base[k - 1] + p->chunk_cap[k - 1];
	return TL_OK;
}

int render_shadow_init(render *r, char *err, size_t err_size)
{
	render_shadow_pool *p = &r->shadow;
	const scene *s = r->scene;
	p->size = s->shadow_map_size;
	uint32_t max_layers = r->dev->props.limits.maxImageArrayLayers;
	VkDeviceSize layer_B = (VkDeviceSize)p->size * p->size * 4;
	/* Worst case per logical layer: every slot's layer distinct, plus one while a plan replaces a slot's. */
	uint32_t per_layer = r->state_ring + 1;
	VkPhysicalDeviceMaintenance3Properties m3 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
	VkPhysicalDeviceProperties2 pp = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, .pNext = &m3};
	vkGetPhysicalDeviceProperties2(r->dev->physical, &pp);
	VkDeviceSize chunk_B = m3.maxMemoryAllocationSize ? m3.maxMemoryAllocationSize / 16 * 15 : CHUNK_BYTES_MAX;
	uint64_t cap_max = chunk_B / layer_B;
	if (cap_max > max_layers)
		cap_max = max_layers;
	if (cap_max < per_layer)
		return tl_error(err, err_size, TL_ERR_NOMEM,
				"one shadow layer's history (%u layers of %ux%u) exceeds an array image; lower shadow_map_size "
				"in the scene", per_layer, p->size, p->size);
	p->layer_chunk = calloc(p->layers + 1, sizeof *p->layer_chunk);
	p->light_code = calloc(s->light_count + 1, sizeof *p->light_code);
	if (!p->layer_chunk || !p->light_code)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	int rc = assign_chunks(r, per_layer, (uint32_t)cap_max, err, err_size);
	if (rc)
		return rc;
	size_t phys_max = (size_t)p->layers * per_layer, bits = (s->object_count + 7) / 8;
	p->views = calloc(phys_max + 1, sizeof *p->views);
	p->refs = calloc(phys_max + 1, sizeof *p->refs);
	p->owner = malloc((phys_max + 1) * sizeof *p->owner);
	p->slot_phys = malloc((size_t)r->state_ring * (p->layers + 1) * sizeof *p->slot_phys);
	p->todo = calloc((size_t)r->state_ring * (p->layers + 1), 1);
	p->casters = calloc((size_t)r->state_ring * (p->layers + 1) * (bits + 1), 1);
	p->caster_bytes = bits + 1;
	p->last_key = calloc(p->layers + 1, sizeof *p->last_key);
	p->last_phys = malloc((p->layers + 1) * sizeof *p->last_phys);
	if (!p->views || !p->refs || !p->owner || !p->slot_phys || !p->todo || !p->casters || !p->last_key || !p->last_phys)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	for (size_t i = 0; i < (size_t)r->state_ring * (p->layers + 1); i++)
		p->slot_phys[i] = NO_PHYS;
	for (uint32_t l = 0; l <= p->layers; l++)
		p->last_phys[l] = NO_PHYS;
	for (size_t i = 0; i <= phys_max; i++)
		p->owner[i] = NO_PHYS;
	VkResult res = make_chunk(r, 1, 1, "shadow dummy", &p->dummy);
	if (res)
		return render_vk_error(err, err_size, "creating the shadow-map placeholder", res);
	render_shadow_write_sets(r);
	return TL_OK;
}

void render_shadow_destroy(render *r)
{
	render_shadow_pool *p = &r->shadow;
	for (uint32_t c = 0; c < GPU_SHADOW_CHUNKS; c++) {
		if (!p->chunks[c].image)
			continue;
		for (uint32_t l = 0; l < p->chunk_cap[c]; l++)
			if (p->views[p->chunk_base[c] + l])
				vkDestroyImageView(r->dev->device, p->views[p->chunk_base[c] + l], NULL);
		vkdev_image_destroy(r->dev, &p->chunks[c]);
	}
	vkdev_image_destroy(r->dev, &p->dummy);
	free(p->views);
	free(p->refs);
	free(p->owner);
	free(p->slot_phys);
	free(p->todo);
	free(p->casters);
	free(p->last_key);
	free(p->last_phys);
	free(p->layer_chunk);
	free(p->light_code);
	memset(p, 0, sizeof *p);
}

int render_shadow_plan(render *r, uint32_t slot, char *err, size_t err_size)
{
	render_shadow_pool *p = &r->shadow;
	gpu_frame_state *st = (gpu_frame_state *)r->states.mapped + slot;
	uint32_t *map = p->slot_phys + (size_t)slot * p->layers;
	uint8_t *todo = p->todo + (size_t)slot * p->layers;
	uint32_t old[SCENE_MAX_SHADOW_LAYERS];
	memcpy(old, map, p->layers * sizeof *map);
	for (uint32_t l = 0; l < p->layers; l++) {
		uint8_t *casters = p->casters + ((size_t)slot * p->layers + l) * p->caster_bytes;
		uint64_t key = layer_key(r, slot, l, casters);
		uint32_t c = p->layer_chunk[l];
		todo[l] = 0;
		/* A physical layer keeps the content of the logical layer that rendered it last until it is
		 * handed to another layer (which clears last_phys), even while no slot references it. */
		if (p->last_phys[l] != NO_PHYS && p->last_key[l] == key) {
			map[l] = p->last_phys[l];
			p->refs[map[l]]++;
			p->reused++;
		} else {
			/* A free physical layer of the layer's own chunk; the chunk holds the worst case. */
			uint32_t phys = p->chunk_base[c], end = phys + p->chunk_cap[c];
			while (phys < end && p->refs[phys])
				phys++;
			if (phys == end || (!p->chunks[c].image && add_chunk(r, c, err, err_size))) {
				if (phys == end)
					tl_error(err, err_size, TL_ERR_INTERNAL, "shadow chunk %u is full (a pool invariant broke)", c);
				for (uint32_t k = 0; k < l; k++) /* undo this slot's new references */
					p->refs[map[k]]--;
				memcpy(map, old, p->layers * sizeof *map);
				return phys == end ? TL_ERR_INTERNAL : TL_ERR_NOMEM;
			}
			map[l] = phys;
			p->refs[phys] = 1;
			if (p->owner[phys] != NO_PHYS)
				p->last_phys[p->owner[phys]] = NO_PHYS;
			p->owner[phys] = l;
			p->last_key[l] = key;
			p->last_phys[l] = phys;
			todo[l] = 1;
			p->rendered++;
		}
		st->shadow_phys[l] = c << 16 | (map[l] - p->chunk_base[c]);
	}
	for (uint32_t l = 0; l < p->layers; l++)
		if (old[l] != NO_PHYS)
			p->refs[old[l]]--;
	return TL_OK;
}

void render_pass_shadows(render *r, VkCommandBuffer cmd, uint32_t slot)
{
	render_shadow_pool *p = &r->shadow;
	uint32_t n = p->size;
	uint8_t *todo = p->todo + (size_t)slot * p->layers;
	const uint32_t *map = p->slot_phys + (size_t)slot * p->layers;
	for (uint32_t l = 0; l < p->layers; l++) {
		if (!todo[l])
			continue;
		uint32_t c = p->layer_chunk[l], cl = map[l] - p->chunk_base[c];
		VkImageMemoryBarrier2 b = {
			.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2,
			.srcStageMask = VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			.dstStageMask = VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
			.dstAccessMask = VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT,
			.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED,
			.newLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
			.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
			.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
			.image = p->chunks[c].image,
			.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, cl, 1},
		};
		VkDependencyInfo di = {.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO, .imageMemoryBarrierCount = 1,
				       .pImageMemoryBarriers = &b};
		vkCmdPipelineBarrier2(cmd, &di);
		render_depth_only_pass(r, cmd, p->views[map[l]], VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, n, n, &r->shadow_pipe,
				       &r->shadow_mask_pipe, slot, l, p->casters + ((size_t)slot * p->layers + l) * p->caster_bytes);
		b.srcStageMask = VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT;
		b.srcAccessMask = VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
		b.dstStageMask = VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT;
		b.dstAccessMask = VK_ACCESS_2_SHADER_SAMPLED_READ_BIT;
		b.oldLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
		b.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
		vkCmdPipelineBarrier2(cmd, &di);
		todo[l] = 0;
	}
}
