/* scene_gltf.c — a scene around a bare glTF file (`taslab render --scene model.gltf`). */
#include "scene_internal.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gltf.h"
#include "procgen.h"

/* Grows a scene array by `extra` zeroed entries (keeps one spare). */
#define GROW(arr, count, extra)                                                                                    \
	do {                                                                                                       \
		void *p_ = realloc((arr), ((count) + (extra) + 1) * sizeof *(arr));                                \
		if (!p_)                                                                                           \
			goto nomem;                                                                                \
		(arr) = p_;                                                                                        \
		memset((arr) + (count), 0, ((extra) + 1) * sizeof *(arr));                                         \
	} while (0)

/* A scene around a bare glTF file (`taslab render --scene model.gltf`): the asset on a floor, a sun, a key
 * spot and a fill light scaled to the asset's bounds at t = 0, and two camera paths framing the bounds:
 * `orbit` (moving, a 90 degree arc over 5 s) and `front` (stationary), plus the asset's own cameras. */
int scene_from_gltf(const char *path, uint32_t texture_size, scene **out, char *err, size_t err_size)
{
	scene *s = calloc(1, sizeof *s);
	tlm_mat4 *world = NULL;
	if (!s || !(s->path = strdup(path)))
		goto nomem;
	const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
	size_t n = 0;
	for (const char *q = base; *q && *q != '.' && n < SCENE_NAME_MAX - 1; q++)
		s->name[n++] = (isalnum((unsigned char)*q) || *q == '-' || *q == '_') ? *q : '_';
	if (!n)
		s->name[n++] = 'g';
	s->duration_s = 5.0f;
	s->fps = 60.0f;
	s->exposure = 1.0f;
	s->ambient[0] = s->ambient[1] = s->ambient[2] = 0.03f;
	s->sky[0] = 0.05f, s->sky[1] = 0.06f, s->sky[2] = 0.08f;
	s->texture_size = texture_size ? texture_size : 1024;
	s->shadow_map_size = 1024;
	int rc = gltf_append(s, path, -1, NULL, err, err_size);
	if (rc)
		goto fail;
	world = calloc(s->object_count + 1, sizeof *world);
	if (!world)
		goto nomem;
	scene_eval(s, 0.0f, world, NULL);
	tlm_vec3 lo = tlm_v3(1e30f, 1e30f, 1e30f), hi = tlm_v3(-1e30f, -1e30f, -1e30f);
	for (size_t i = 0; i < s->object_count; i++) {
		if (s->objects[i].mesh < 0)
			continue;
		const scene_mesh *m = &s->meshes[s->objects[i].mesh];
		for (int k = 0; k < 8; k++) {
			tlm_vec3 p = tlm_v3(k & 1 ? m->bounds_max.x : m->bounds_min.x, k & 2 ? m->bounds_max.y : m->bounds_min.y,
					    k & 4 ? m->bounds_max.z : m->bounds_min.z);
			p = tlm_mat4_mul_point(world[i], p);
			if (!isfinite(p.x) || !isfinite(p.y) || !isfinite(p.z)) {
				snprintf(err, err_size, "%s: object %s is not finite at t = 0 (transforms too large)", path,
					 s->objects[i].name);
				rc = TL_ERR_INPUT;
				goto fail;
			}
			lo = tlm_v3(fminf(lo.x, p.x), fminf(lo.y, p.y), fminf(lo.z, p.z));
			hi = tlm_v3(fmaxf(hi.x, p.x), fmaxf(hi.y, p.y), fmaxf(hi.z, p.z));
		}
	}
	if (lo.x > hi.x) {
		snprintf(err, err_size, "%s: the glTF has no triangle meshes to render", path);
		rc = TL_ERR_INPUT;
		goto fail;
	}
	tlm_vec3 c = tlm_v3_scale(tlm_v3_add(lo, hi), 0.5f);
	float r = fmaxf(0.5f * tlm_v3_length(tlm_v3_sub(hi, lo)), 1e-3f);
	/* The lights and cameras below scale with r (the key light with (3r)^2, the far plane with ~50 r). */
	if (!isfinite(c.x + c.y + c.z) || !isfinite(100.0f * r * r)) {
		snprintf(err, err_size, "%s: the asset is too large to frame in float (bounding radius %g)", path, (double)r);
		rc = TL_ERR_INPUT;
		goto fail;
	}
	/* floor */
	GROW(s->meshes, s->mesh_count, 1);
	GROW(s->materials, s->material_count, 1);
	GROW(s->objects, s->object_count, 1);
	procgen_mesh_desc fd = {.kind = "plane", .size = {6 * r, 0, 6 * r}, .segments = 8, .uv_scale = 1};
	char why[200];
	if (procgen_mesh(&fd, &s->meshes[s->mesh_count], why, sizeof why))
		goto nomem;
	snprintf(s->meshes[s->mesh_count].name, SCENE_NAME_MAX, "taslab_floor");
	scene_material *fm = &s->materials[s->material_count];
	snprintf(fm->name, SCENE_NAME_MAX, "taslab_floor");
	fm->base_color[0] = fm->base_color[1] = fm->base_color[2] = 0.35f, fm->base_color[3] = 1;
	fm->roughness = 0.8f;
	fm->normal_scale = fm->occlusion_strength = 1;
	fm->base_color_tex = fm->metal_rough_tex = fm->normal_tex = fm->emissive_tex = fm->occlusion_tex = SCENE_TEX_NONE;
	scene_object *fo = &s->objects[s->object_count];
	snprintf(fo->name, SCENE_NAME_MAX, "taslab_floor");
	fo->mesh = (int)s->mesh_count++;
	fo->material = (int)s->material_count++;
	fo->parent = -1;
	fo->casts_shadow = false;
	fo->base = tlm_trs_identity();
	fo->base.t = tlm_v3(c.x, lo.y - 1e-3f * r, c.z);
	s->object_count++;
	/* lights: intensities scale with distance^2 so the asset is lit alike at any size */
	GROW(s->lights, s->light_count, 3);
	scene_light *L = s->lights;
	float d = 3.0f * r;
	L[0] = (scene_light){.name = "sun", .kind = SCENE_LIGHT_DIRECTIONAL, .color = {1, 0.96f, 0.9f}, .intensity = 2.0f,
			     .casts_shadow = true, .shadow_extent = 2.0f * r, .shadow_center = c};
	L[1] = (scene_light){.name = "key", .kind = SCENE_LIGHT_SPOT, .color = {1, 0.9f, 0.8f}, .intensity = 2.5f * d * d,
			     .inner_cone_deg = 20, .outer_cone_deg = 32, .casts_shadow = true};
	L[2] = (scene_light){.name = "fill", .kind = SCENE_LIGHT_POINT, .color = {0.6f, 0.7f, 1.0f}, .intensity = 0.8f * d * d};
	tlm_vec3 sun_dir = tlm_v3_normalize_or(tlm_v3(-0.4f, -1.0f, -0.3f), tlm_v3(0, -1, 0));
	tlm_vec3 key_pos = tlm_v3_add(c, tlm_v3(0.6f * d, 0.8f * d, 0.6f * d));
	tlm_vec3 dirs[2] = {sun_dir, tlm_v3_normalize_or(tlm_v3_sub(c, key_pos), tlm_v3(0, -1, 0))};
	for (int i = 0; i < 3; i++) {
		L[i].base = tlm_trs_identity();
		if (i < 2) { /* orientation turning -Z onto the direction */
			tlm_vec3 from = tlm_v3(0, 0, -1), ax = tlm_v3_cross(from, dirs[i]);
			L[i].base.r = tlm_quat_normalize((tlm_quat){ax.x, ax.y, ax.z, 1.0f + tlm_v3_dot(from, dirs[i])});
		}
	}
	L[1].base.t = key_pos;
	L[2].base.t = tlm_v3_add(c, tlm_v3(-0.8f * d, 0.4f * d, 0.5f * d));
	s->light_count = 3;
	/* cameras: glTF cameras (if any) were appended by gltf_append; put ours first */
	size_t own = s->camera_count;
	GROW(s->cameras, s->camera_count, 2);
	memmove(s->cameras + 2, s->cameras, own * sizeof *s->cameras);
	memset(s->cameras, 0, 2 * sizeof *s->cameras);
	float dist = r / tanf(0.5f * 50.0f * TLM_PI / 180.0f) * 1.1f;
	for (int k = 0; k < 2; k++) {
		scene_camera *cam = &s->cameras[k];
		snprintf(cam->name, SCENE_NAME_MAX, k ? "front" : "orbit");
		cam->motion = k ? SCENE_CAMERA_STATIONARY : SCENE_CAMERA_MOVING;
		cam->fov_deg = 50.0f;
		cam->znear = fmaxf(1e-3f, 0.01f * dist);
		cam->zfar = 20.0f * dist;
		cam->key_count = k ? 1 : 5;
		cam->keys = calloc(cam->key_count, sizeof *cam->keys);
		if (!cam->keys)
			goto nomem;
		for (size_t j = 0; j < cam->key_count; j++) {
			float a = (k ? 20.0f : -45.0f + 22.5f * (float)j) * TLM_PI / 180.0f;
			cam->keys[j].t = 1.25f * (float)j;
			cam->keys[j].position = tlm_v3_add(c, tlm_v3(dist * sinf(a), 0.35f * dist, dist * cosf(a)));
			cam->keys[j].target = c;
		}
	}
	s->camera_count += 2;
	free(world);
	*out = s;
	return 0;
nomem:
	snprintf(err, err_size, "%s: out of memory", path);
	rc = TL_ERR_NOMEM;
fail:
	free(world);
	scene_destroy(&s);
	return rc;
}
