/* shadow.c — shadow maps as a pool of physical layers shared by the state slots.
 *
 * Temporal forward rendering (DESIGN section 4, paper sec. 3) shades a surface point with the shadow
 * maps of up to K = 119 frames ago, so every state slot of the ring keeps its own shadow maps. Most
 * shadow layers do not change every frame (static lights whose frustum no moving caster enters), so
 * a slot's logical layer maps to a *physical* layer, and a layer whose inputs are unchanged since the
 * last rendering of that logical layer shares the physical layer instead of being rendered again.
 * The inputs are keyed exactly: the layer's light matrix plus index and world matrix of every shadow
 * caster whose bounds reach into the light frustum (bounding-box corners tested against the clip
 * planes, conservative), so sharing never changes a pixel.
 *
 * Physical layers live in up to GPU_SHADOW_CHUNKS array images ("chunks", at most 1 GiB each),
 * allocated when the pool runs out; the shader picks the chunk per lookup (shading.glsl). */
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

static uint64_t layer_key(const render *r, uint32_t slot, uint32_t layer)
{
	const scene *s = r->scene;
	const gpu_frame_state *st = (const gpu_frame_state *)r->states.mapped + slot;
	const gpu_object *ob = (const gpu_object *)r->objects.mapped + (size_t)slot * s->object_count;
	uint64_t h = fnv(1469598103934665603ull, st->shadow_matrix[layer], sizeof st->shadow_matrix[layer]);
	for (size_t i = 0; i < s->object_count; i++) {
		const scene_object *o = &s->objects[i];
		if (o->mesh < 0 || !o->casts_shadow || s->materials[o->material].alpha_mode == SCENE_ALPHA_BLEND)
			continue;
		const scene_mesh *me = &s->meshes[o->mesh];
		if (!box_in_frustum(st->shadow_matrix[layer], ob[i].world, me->bounds_min, me->bounds_max))
			continue;
		uint32_t idx = (uint32_t)i;
		h = fnv(h, &idx, sizeof idx);
		h = fnv(h, ob[i].world, sizeof ob[i].world);
	}
	return h;
}

static void write_descriptors(render *r)
{
	render_shadow_pool *p = &r->shadow;
	VkDescriptorImageInfo ii[GPU_SHADOW_CHUNKS];
	for (uint32_t c = 0; c < GPU_SHADOW_CHUNKS; c++)
		ii[c] = (VkDescriptorImageInfo){r->shadow_sampler,
						c < p->chunk_count ? p->chunks[c].view : p->chunk_count ? p->chunks[0].view
													: p->dummy.view,
						VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
	VkWriteDescriptorSet w = {.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = r->scene_set,
				  .dstBinding = 5, .descriptorCount = GPU_SHADOW_CHUNKS,
				  .descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, .pImageInfo = ii};
	vkUpdateDescriptorSets(r->dev->device, 1, &w, 0, NULL);
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

static int add_chunk(render *r, char *err, size_t err_size)
{
	render_shadow_pool *p = &r->shadow;
	if (p->chunk_count == p->chunks_max) { /* cannot happen: chunks_max covers the worst case */
		snprintf(err, err_size,
			 "the shadow-map history needs more than %u layers of %ux%u (%u logical layers x %u slots); "
			 "lower shadow_map_size in the scene",
			 GPU_SHADOW_CHUNKS * p->chunk_layers, p->size, p->size, p->layers, r->state_ring);
		return TL_ERR_NOMEM;
	}
	uint32_t c = p->chunk_count;
	char name[32];
	snprintf(name, sizeof name, "shadow chunk %u", c);
	VkResult res = make_chunk(r, p->size, p->chunk_layers, name, &p->chunks[c]);
	if (res) {
		snprintf(err, err_size, "cannot allocate %u more shadow-map layers of %ux%u (%s); lower shadow_map_size in the scene",
			 p->chunk_layers, p->size, p->size, vkdev_result_string(res));
		vkdev_image_destroy(r->dev, &p->chunks[c]);
		return res == VK_ERROR_OUT_OF_HOST_MEMORY || res == VK_ERROR_OUT_OF_DEVICE_MEMORY ? TL_ERR_NOMEM
												  : TL_ERR_VULKAN;
	}
	for (uint32_t l = 0; l < p->chunk_layers; l++) {
		VkImageViewCreateInfo vi = {
			.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO,
			.image = p->chunks[c].image,
			.viewType = VK_IMAGE_VIEW_TYPE_2D,
			.format = VK_FORMAT_D32_SFLOAT,
			.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, l, 1},
		};
		if ((res = vkCreateImageView(r->dev->device, &vi, NULL, &p->views[c * p->chunk_layers + l]))) {
			snprintf(err, err_size, "vkCreateImageView (shadow layer) failed: %s", vkdev_result_string(res));
			return TL_ERR_VULKAN;
		}
	}
	p->chunk_count++;
	write_descriptors(r);
	return 0;
}

int render_shadow_init(render *r, char *err, size_t err_size)
{
	render_shadow_pool *p = &r->shadow;
	const scene *s = r->scene;
	p->size = s->shadow_map_size;
	uint32_t max_layers = r->dev->props.limits.maxImageArrayLayers;
	VkDeviceSize layer_B = (VkDeviceSize)p->size * p->size * 4;
	/* Worst case: every slot's layers distinct, plus one slot's worth while a plan holds old and new. */
	uint32_t need = p->layers * (r->state_ring + 1);
	VkPhysicalDeviceMaintenance3Properties m3 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
	VkPhysicalDeviceProperties2 pp = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, .pNext = &m3};
	vkGetPhysicalDeviceProperties2(r->dev->physical, &pp);
	VkDeviceSize chunk_B = m3.maxMemoryAllocationSize ? m3.maxMemoryAllocationSize / 16 * 15 : CHUNK_BYTES_MAX;
	p->chunk_layers = (uint32_t)(chunk_B / layer_B);
	if (p->chunk_layers > max_layers)
		p->chunk_layers = max_layers;
	if (p->chunk_layers > need)
		p->chunk_layers = need;
	if (p->chunk_layers < 1)
		p->chunk_layers = 1;
	p->chunks_max = (need + p->chunk_layers - 1) / p->chunk_layers;
	if (p->chunks_max < 1)
		p->chunks_max = 1;
	if (p->chunks_max > GPU_SHADOW_CHUNKS) {
		snprintf(err, err_size,
			 "the shadow-map history would need up to %u layers of %ux%u (%u per frame x %u frames), more than %u "
			 "allocations of %u layers; lower shadow_map_size in the scene",
			 need, p->size, p->size, p->layers, r->state_ring, GPU_SHADOW_CHUNKS, p->chunk_layers);
		return TL_ERR_NOMEM;
	}
	size_t phys_max = (size_t)GPU_SHADOW_CHUNKS * p->chunk_layers;
	p->views = calloc(phys_max, sizeof *p->views);
	p->refs = calloc(phys_max, sizeof *p->refs);
	p->owner = malloc(phys_max * sizeof *p->owner);
	p->slot_phys = malloc((size_t)r->state_ring * (p->layers + 1) * sizeof *p->slot_phys);
	p->todo = calloc((size_t)r->state_ring * (p->layers + 1), 1);
	p->last_key = calloc(p->layers + 1, sizeof *p->last_key);
	p->last_phys = malloc((p->layers + 1) * sizeof *p->last_phys);
	if (!p->views || !p->refs || !p->owner || !p->slot_phys || !p->todo || !p->last_key || !p->last_phys) {
		snprintf(err, err_size, "out of memory");
		return TL_ERR_NOMEM;
	}
	for (size_t i = 0; i < (size_t)r->state_ring * (p->layers + 1); i++)
		p->slot_phys[i] = NO_PHYS;
	for (uint32_t l = 0; l <= p->layers; l++)
		p->last_phys[l] = NO_PHYS;
	for (size_t i = 0; i < phys_max; i++)
		p->owner[i] = NO_PHYS;
	VkResult res = make_chunk(r, 1, 1, "shadow dummy", &p->dummy);
	if (res) {
		snprintf(err, err_size, "creating the shadow-map placeholder failed: %s", vkdev_result_string(res));
		return TL_ERR_VULKAN;
	}
	write_descriptors(r);
	return 0;
}

void render_shadow_destroy(render *r)
{
	render_shadow_pool *p = &r->shadow;
	for (uint32_t c = 0; c < p->chunk_count; c++) {
		for (uint32_t l = 0; l < p->chunk_layers; l++)
			if (p->views[c * p->chunk_layers + l])
				vkDestroyImageView(r->dev->device, p->views[c * p->chunk_layers + l], NULL);
		vkdev_image_destroy(r->dev, &p->chunks[c]);
	}
	vkdev_image_destroy(r->dev, &p->dummy);
	free(p->views);
	free(p->refs);
	free(p->owner);
	free(p->slot_phys);
	free(p->todo);
	free(p->last_key);
	free(p->last_phys);
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
	size_t phys_n = (size_t)p->chunk_count * p->chunk_layers, next_free = 0;
	for (uint32_t l = 0; l < p->layers; l++) {
		uint64_t key = layer_key(r, slot, l);
		todo[l] = 0;
		/* A physical layer keeps the content of the logical layer that rendered it last until it is
		 * handed to another layer (which clears last_phys), even while no slot references it. */
		if (p->last_phys[l] != NO_PHYS && p->last_key[l] == key) {
			map[l] = p->last_phys[l];
			p->refs[map[l]]++;
			p->reused++;
		} else {
			while (next_free < phys_n && p->refs[next_free])
				next_free++;
			if (next_free == phys_n) {
				int rc = add_chunk(r, err, err_size);
				if (rc) {
					for (uint32_t k = 0; k < l; k++) /* undo this slot's new references */
						p->refs[map[k]]--;
					memcpy(map, old, p->layers * sizeof *map);
					return rc;
				}
				phys_n += p->chunk_layers;
			}
			map[l] = (uint32_t)next_free;
			p->refs[next_free] = 1;
			if (p->owner[next_free] != NO_PHYS)
				p->last_phys[p->owner[next_free]] = NO_PHYS;
			p->owner[next_free] = l;
			p->last_key[l] = key;
			p->last_phys[l] = (uint32_t)next_free;
			todo[l] = 1;
			p->rendered++;
		}
		st->shadow_phys[l] = (map[l] / p->chunk_layers) << 16 | (map[l] % p->chunk_layers);
	}
	for (uint32_t l = 0; l < p->layers; l++)
		if (old[l] != NO_PHYS)
			p->refs[old[l]]--;
	return 0;
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
		uint32_t c = map[l] / p->chunk_layers, cl = map[l] % p->chunk_layers;
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
		render_depth_only_pass(r, cmd, p->views[map[l]], n, n, &r->shadow_pipe, &r->shadow_mask_pipe, slot, l, 1);
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
