/* scene_eval.c — a scene as a pure function of time (DESIGN section 2): object transforms, light states
 * and camera paths at time t. Nothing depends on the history, which is what temporal forward rendering
 * and the TAS methods rely on (shading a point as it was k frames ago). */
#include "scene_internal.h"

#include <math.h>
#include <string.h>

static float light_intensity(const scene_light *l, float t)
{
	size_t n = l->intensity_key_count;
	if (!n)
		return l->intensity;
	if (t <= l->intensity_times[0])
		return l->intensity_values[0];
	for (size_t i = 1; i < n; i++)
		if (t < l->intensity_times[i]) {
			float u = (t - l->intensity_times[i - 1]) / (l->intensity_times[i] - l->intensity_times[i - 1]);
			return l->intensity_values[i - 1] + u * (l->intensity_values[i] - l->intensity_values[i - 1]);
		}
	return l->intensity_values[n - 1];
}

/* ------------------------------------------------------------------ evaluation */

static tlm_trs eval_trs(tlm_trs base, const anim_motion *m, size_t n, float t)
{
	tlm_trs trs = base;
	for (size_t i = 0; i < n; i++)
		anim_motion_apply(&m[i], t, &trs);
	return trs;
}

void scene_eval(const scene *s, float t, tlm_mat4 *world, scene_light_state *lights)
{
	if (world)
		for (size_t i = 0; i < s->object_count; i++) {
			const scene_object *o = &s->objects[i];
			tlm_mat4 local = tlm_trs_matrix(eval_trs(o->base, o->motions, o->motion_count, t));
			/* Parents precede children (enforced at load), so world[parent] is ready. */
			world[i] = o->parent >= 0 ? tlm_mat4_mul(world[o->parent], local) : local;
		}
	if (lights)
		for (size_t i = 0; i < s->light_count; i++) {
			const scene_light *l = &s->lights[i];
			tlm_trs trs = eval_trs(l->base, l->motions, l->motion_count, t);
			lights[i].position = trs.t;
			lights[i].direction = tlm_v3_normalize_or(tlm_quat_rotate(trs.r, tlm_v3(0, 0, -1)), tlm_v3(0, -1, 0));
			lights[i].intensity = light_intensity(l, t);
		}
}

void scene_mirrors(const scene *s, const tlm_mat4 *world, uint8_t *mirrored)
{
	for (size_t i = 0; i < s->object_count; i++)
		mirrored[i] = tlm_mat4_det3(world[i]) < 0.0f;
}

int scene_find_camera(const scene *s, const char *name)
{
	return s->camera_count ? SCENE_FIND(s->cameras, s->camera_count, name) : -1;
}

/* Cubic Hermite between keys i and i+1 with Catmull-Rom (central difference) tangents. */
static tlm_vec3 hermite_path(const scene_camera_key *k, size_t n, size_t i, float t, int target)
{
#define KP(j) (target ? k[(j)].target : k[(j)].position)
	size_t im = i > 0 ? i - 1 : i, ip = i + 2 < n ? i + 2 : i + 1;
	float t0 = k[i].t, t1 = k[i + 1].t, dt = t1 - t0;
	tlm_vec3 m0 = tlm_v3_scale(tlm_v3_sub(KP(i + 1), KP(im)), 1.0f / (k[i + 1].t - k[im].t));
	tlm_vec3 m1 = tlm_v3_scale(tlm_v3_sub(KP(ip), KP(i)), 1.0f / (k[ip].t - k[i].t));
	float u = (t - t0) / dt, u2 = u * u, u3 = u2 * u;
	tlm_vec3 r = tlm_v3_scale(KP(i), 2 * u3 - 3 * u2 + 1);
	r = tlm_v3_add(r, tlm_v3_scale(m0, (u3 - 2 * u2 + u) * dt));
	r = tlm_v3_add(r, tlm_v3_scale(KP(i + 1), -2 * u3 + 3 * u2));
	r = tlm_v3_add(r, tlm_v3_scale(m1, (u3 - u2) * dt));
	return r;
#undef KP
}

scene_camera_state scene_camera_eval(const scene *s, int camera, float t)
{
	const scene_camera *c = &s->cameras[camera];
	scene_camera_state st = {c->keys[0].position, c->keys[0].target, c->fov_deg, c->znear, c->zfar};
	size_t n = c->key_count;
	if (n == 1 || t <= c->keys[0].t)
		return st;
	if (t >= c->keys[n - 1].t) {
		st.eye = c->keys[n - 1].position;
		st.target = c->keys[n - 1].target;
		return st;
	}
	size_t i = 0;
	while (i + 2 < n && t >= c->keys[i + 1].t)
		i++;
	st.eye = hermite_path(c->keys, n, i, t, 0);
	st.target = hermite_path(c->keys, n, i, t, 1);
	return st;
}
