/* scene_digest.c — a content hash of a loaded scene (scene.h): what a sweep and a run manifest record so that a
 * run made from other inputs is told apart from one made from these (issue 31.4). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/scene.h"
#include "taslab/tl_fs.h"
#include "taslab/tl_hash.h"

#define PUT(h, v) tl_fnv1a64(h, &(v), sizeof(v))

/* The scene file's bytes, then everything loaded from it and its assets (glTF meshes, buffers, images): vertices,
 * indices, texture texels, materials, object, light and camera placement. Fields are hashed one by one (no struct
 * padding, no pointers), so the digest depends on the content only. */
void scene_digest(const scene *s, char out[SCENE_DIGEST_HEX])
{
	uint64_t h = TL_FNV1A64_INIT;
	char *text = NULL, err[256];
	size_t len = 0;
	if (s->path && !tl_read_file(s->path, 64u << 20, &text, &len, err, sizeof err))
		tl_fnv1a64(&h, text, len);
	free(text);
	PUT(&h, s->duration_s), PUT(&h, s->fps), PUT(&h, s->exposure), PUT(&h, s->ambient), PUT(&h, s->sky);
	PUT(&h, s->texture_size), PUT(&h, s->shadow_map_size);
	for (size_t i = 0; i < s->mesh_count; i++) {
		const scene_mesh *m = &s->meshes[i];
		PUT(&h, m->vertex_count), PUT(&h, m->index_count);
		tl_fnv1a64(&h, m->vertices, (size_t)m->vertex_count * sizeof *m->vertices); /* 12 floats each: no padding */
		tl_fnv1a64(&h, m->indices, (size_t)m->index_count * sizeof *m->indices);
	}
	for (size_t i = 0; i < s->texture_count; i++) {
		PUT(&h, s->textures[i].srgb);
		tl_fnv1a64(&h, s->textures[i].rgba, (size_t)s->texture_size * s->texture_size * 4);
	}
	for (size_t i = 0; i < s->material_count; i++) {
		const scene_material *m = &s->materials[i];
		PUT(&h, m->base_color), PUT(&h, m->metallic), PUT(&h, m->roughness), PUT(&h, m->emissive);
		PUT(&h, m->normal_scale), PUT(&h, m->occlusion_strength), PUT(&h, m->alpha_mode), PUT(&h, m->alpha_cutoff);
		PUT(&h, m->double_sided), PUT(&h, m->base_color_tex), PUT(&h, m->metal_rough_tex), PUT(&h, m->normal_tex);
		PUT(&h, m->emissive_tex), PUT(&h, m->occlusion_tex);
	}
	for (size_t i = 0; i < s->object_count; i++) {
		const scene_object *o = &s->objects[i];
		PUT(&h, o->mesh), PUT(&h, o->material), PUT(&h, o->parent), PUT(&h, o->casts_shadow), PUT(&h, o->base);
	}
	for (size_t i = 0; i < s->light_count; i++) {
		const scene_light *l = &s->lights[i];
		PUT(&h, l->kind), PUT(&h, l->color), PUT(&h, l->intensity), PUT(&h, l->range), PUT(&h, l->inner_cone_deg);
		PUT(&h, l->outer_cone_deg), PUT(&h, l->casts_shadow), PUT(&h, l->shadow_extent), PUT(&h, l->shadow_center);
		PUT(&h, l->base);
	}
	for (size_t i = 0; i < s->camera_count; i++) {
		const scene_camera *c = &s->cameras[i];
		tl_fnv1a64(&h, c->name, strlen(c->name));
		PUT(&h, c->motion), PUT(&h, c->fov_deg), PUT(&h, c->znear), PUT(&h, c->zfar);
		tl_fnv1a64(&h, c->keys, c->key_count * sizeof *c->keys); /* t + two vec3: floats only */
	}
	snprintf(out, SCENE_DIGEST_HEX, "%016llx", (unsigned long long)h);
}
