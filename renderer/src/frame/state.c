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

/* The camera of view v of `views` at time t (STEREO.md: parallel axes, e = eye -/+ (ipd/2) r with
 * r = normalize((target - eye) x (0, 1, 0)), the target shifted alike; view -1: the centre eye). */
static scene_camera_state view_camera(const render *r, double t, int v)
{
	scene_camera_state cam = scene_camera_eval(r->scene, r->desc.camera, (float)t);
	/* mono: render_desc.eye_shift (a mono run from one eye's camera, STEREO.md X3); stereo: -/+ ipd/2 */
	float shift = r->view_count < 2 ? r->desc.eye_shift : v < 0 ? 0.0f : 0.5f * r->desc.ipd * (v == 0 ? -1.0f : 1.0f);
	if (shift == 0.0f)
		return cam;
	tlm_vec3 right = tlm_v3_cross(tlm_v3_sub(cam.target, cam.eye), tlm_v3(0, 1, 0));
	float len = tlm_v3_length(right);
	if (!(len > 0.0f))
		return cam; /* looking straight up or down: no horizon to separate the eyes along */
	float half = shift / len;
	cam.eye = tlm_v3_add(cam.eye, tlm_v3_scale(right, half));
	cam.target = tlm_v3_add(cam.target, tlm_v3_scale(right, half));
	return cam;
}

static void write_camera(const render *r, gpu_frame_state *st, const scene_camera_state *cam, float t)
{
	tlm_mat4 view = tlm_mat4_look_at(cam->eye, cam->target, tlm_v3(0, 1, 0));
	tlm_mat4 proj = tlm_mat4_perspective(cam->fov_deg * TLM_PI / 180.0f,
					     (float)r->desc.width / (float)r->desc.height, cam->znear, cam->zfar);
	mat_copy(st->view, view);
	mat_copy(st->proj, proj);
	mat_copy(st->view_proj, tlm_mat4_mul(proj, view));
	st->camera_time[0] = cam->eye.x;
	st->camera_time[1] = cam->eye.y;
	st->camera_time[2] = cam->eye.z;
	st->camera_time[3] = t;
}

static void update_state_view(render *r, uint32_t slot, double time_s);

void render_update_state(render *r, uint32_t slot, double time_s)
{
	if (r->view_count < 2) {
		update_state_view(r, slot, time_s);
		return;
	}
	if (r->view > 0 && r->slot_time[slot] == time_s)
		return; /* written for every view when view 0 asked (the scene is evaluated once per frame) */
	/* view 0's rings hold the full state; the other views get a copy with their own camera */
	uint32_t active = r->view;
	render_use_view(r, 0);
	update_state_view(r, slot, time_s);
	const gpu_frame_state *st0 = (const gpu_frame_state *)r->states.mapped + slot;
	size_t n = r->scene->object_count;
	for (uint32_t v = 1; v < r->view_count; v++) {
		render_view_ctx *c = &r->views[v];
		gpu_frame_state *st = (gpu_frame_state *)c->states.mapped + slot;
		memcpy(st, st0, sizeof *st);
		memcpy((gpu_object *)c->objects.mapped + slot * n, (const gpu_object *)r->objects.mapped + slot * n,
		       n * sizeof(gpu_object));
		scene_camera_state cam = view_camera(r, time_s, (int)v);
		write_camera(r, st, &cam, (float)time_s);
		c->eye = cam.eye;
	}
	r->slot_time[slot] = time_s;
	render_use_view(r, active);
}

uint32_t render_center_slot(render *r, uint32_t slot, double time_s)
{
	uint32_t c = r->state_ring;
	size_t n = r->scene->object_count;
	gpu_frame_state *st = (gpu_frame_state *)r->states.mapped;
	memcpy(st + c, st + slot, sizeof *st);
	memcpy((gpu_object *)r->objects.mapped + c * n, (const gpu_object *)r->objects.mapped + slot * n,
	       n * sizeof(gpu_object));
	scene_camera_state cam = view_camera(r, time_s, -1);
	write_camera(r, st + c, &cam, (float)time_s);
	return c;
}

void render_share_shadows(render *r, uint32_t slot)
{
	const gpu_frame_state *st = (const gpu_frame_state *)r->states.mapped + slot;
	for (uint32_t v = 0; v < r->view_count; v++)
		if (v != r->view)
			memcpy(((gpu_frame_state *)r->views[v].states.mapped + slot)->shadow_phys, st->shadow_phys,
			       sizeof st->shadow_phys);
}

static void update_state_view(render *r, uint32_t slot, double time_s)
{
	const scene *s = r->scene;
	gpu_frame_state *st = (gpu_frame_state *)r->states.mapped + slot;
	gpu_object *ob = (gpu_object *)r->objects.mapped + (size_t)slot * s->object_count;
	float t = (float)time_s;
	memset(st, 0, sizeof *st);
	scene_eval(s, t, r->world, r->light_states);
	scene_mirrors(s, r->world, r->mirrored); /* per slot, so a scale animated through zero flips at its frame */
	for (size_t i = 0; i < s->object_count; i++) {
		mat_copy(ob[i].world, r->world[i]);
		mat_copy(ob[i].normal_matrix, tlm_mat4_transpose(tlm_mat4_inverse(r->world[i])));
		ob[i].material[0] = s->objects[i].material >= 0 ? (uint32_t)s->objects[i].material : 0u;
		ob[i].material[1] = r->mirrored[i];
	}
	scene_camera_state cam = view_camera(r, time_s, (int)r->view);
	r->eye = cam.eye;
	write_camera(r, st, &cam, t);
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
