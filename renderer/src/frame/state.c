/* state.c — state rings: the scene and camera evaluated at a time into a FrameState slot and the object
 * ring (DESIGN section 2: a pure function of time, so any slot can hold any past frame). */
#include "render_internal.h"

#include <math.h>
#include <string.h>

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
