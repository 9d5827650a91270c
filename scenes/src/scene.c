/* scene.c — loading and freeing scenes (scene.h): scene files through scene_parse.c, bare glTF files
 * through scene_gltf.c; names of enums. */
#include "scene_internal.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "taslab/tl_fs.h"

int scene_find_named(const char *names, size_t stride, size_t n, const char *name)
{
	for (size_t i = 0; i < n; i++)
		if (!strcmp(names + i * stride, name))
			return (int)i;
	return -1; /* local sentinel: not found (an index, not an error) */
}

int scene_load(const char *path, scene **out, char *err, size_t err_size)
{
	return scene_load_with(path, NULL, out, err, err_size);
}

int scene_load_with(const char *path, const scene_load_desc *desc, scene **out, char *err, size_t err_size)
{
	*out = NULL;
	uint32_t ts = desc ? desc->texture_size : 0;
	if (ts && (ts < 4 || ts > 4096 || (ts & (ts - 1))))
		return tl_error(err, err_size, TL_ERR_ARG, "texture size %u: use a power of two from 4 to 4096", ts);
	size_t plen = strlen(path);
	if ((plen > 5 && !strcmp(path + plen - 5, ".gltf")) || (plen > 4 && !strcmp(path + plen - 4, ".glb"))) {
		int rc = scene_from_gltf(path, ts, out, err, err_size);
		if (rc)
			scene_err_one_line(err, err_size);
		return rc;
	}
	char *buf = NULL;
	size_t len = 0;
	int rc = tl_read_file(path, 64u << 20, &buf, &len, err, err_size);
	struct stat sb;
	if (rc == TL_ERR_INPUT && stat(path, &sb)) /* missing; a device or folder keeps tl_read_file's "not a regular file" */
		snprintf(err, err_size, "%s: cannot open scene file: %s (built-in scenes are in scenes/; see 'taslab scenes')", path,
			 strerror(errno ? errno : ENOENT));
	if (rc) {
		scene_err_one_line(err, err_size);
		return rc;
	}
	rc = scene_parse_memory(buf, len, path, ts, out, err, err_size);
	free(buf);
	return rc;
}

void scene_destroy(scene **ps)
{
	if (!ps || !*ps)
		return;
	scene *s = *ps;
	for (size_t i = 0; i < s->mesh_count; i++) {
		free(s->meshes[i].vertices);
		free(s->meshes[i].indices);
	}
	for (size_t i = 0; i < s->texture_count; i++)
		free(s->textures[i].rgba);
	for (size_t i = 0; i < s->object_count; i++) {
		for (size_t j = 0; j < s->objects[i].motion_count; j++)
			anim_motion_finish(&s->objects[i].motions[j]);
		free(s->objects[i].motions);
	}
	for (size_t i = 0; i < s->light_count; i++) {
		for (size_t j = 0; j < s->lights[i].motion_count; j++)
			anim_motion_finish(&s->lights[i].motions[j]);
		free(s->lights[i].motions);
		free(s->lights[i].intensity_times);
		free(s->lights[i].intensity_values);
	}
	for (size_t i = 0; i < s->camera_count; i++)
		free(s->cameras[i].keys);
	free(s->meshes);
	free(s->textures);
	free(s->materials);
	free(s->objects);
	free(s->lights);
	free(s->cameras);
	free(s->path);
	free(s);
	*ps = NULL;
}

const char *scene_camera_motion_name(scene_camera_motion m)
{
	return m == SCENE_CAMERA_STATIONARY ? "stationary" : m == SCENE_CAMERA_MOVING ? "moving" : "invalid";
}

const char *scene_light_kind_name(scene_light_kind k)
{
	static const char *n[] = {"invalid", "directional", "point", "spot"};
	return k > 0 && k < SCENE_LIGHT_COUNT ? n[k] : "invalid";
}

uint32_t scene_shadow_layer_count(const scene *s)
{
	uint32_t n = 0;
	for (size_t i = 0; i < s->light_count; i++)
		if (s->lights[i].casts_shadow)
			n += s->lights[i].kind == SCENE_LIGHT_POINT ? 6u : 1u;
	return n;
}
