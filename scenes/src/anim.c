/* anim.c — keyframe and scripted animation (see anim.h; glTF 2.0 spec Appendix C). */
#include "taslab/anim.h"
#include "taslab/tl_error.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int anim_path_components(anim_path path) { return path == ANIM_PATH_ROTATION ? 4 : 3; }

anim_interp anim_interp_from_string(const char *s)
{
	if (!s)
		return ANIM_INTERP_INVALID;
	if (!strcmp(s, "STEP"))
		return ANIM_INTERP_STEP;
	if (!strcmp(s, "LINEAR"))
		return ANIM_INTERP_LINEAR;
	if (!strcmp(s, "CUBICSPLINE"))
		return ANIM_INTERP_CUBICSPLINE;
	return ANIM_INTERP_INVALID;
}

const char *anim_interp_name(anim_interp interp)
{
	switch (interp) {
	case ANIM_INTERP_STEP: return "STEP";
	case ANIM_INTERP_LINEAR: return "LINEAR";
	case ANIM_INTERP_CUBICSPLINE: return "CUBICSPLINE";
	default: return "invalid";
	}
}

int anim_track_validate(const anim_track *track, char *why, size_t why_size)
{
	if (track->path <= ANIM_PATH_INVALID || track->path >= ANIM_PATH_COUNT) {
		snprintf(why, why_size, "unknown animation path");
		return TL_ERR_INPUT;
	}
	if (track->interp <= ANIM_INTERP_INVALID || track->interp >= ANIM_INTERP_COUNT) {
		snprintf(why, why_size, "unknown interpolation (use STEP, LINEAR or CUBICSPLINE)");
		return TL_ERR_INPUT;
	}
	if (track->key_count < 1 || !track->times || !track->values) {
		snprintf(why, why_size, "a track needs at least one key");
		return TL_ERR_INPUT;
	}
	for (size_t i = 0; i < track->key_count; i++) {
		if (!isfinite(track->times[i]) || (i > 0 && !(track->times[i] > track->times[i - 1]))) {
			snprintf(why, why_size, "key times must be finite and strictly increasing (key %zu)", i);
			return TL_ERR_INPUT;
		}
	}
	size_t n = track->key_count * (size_t)anim_path_components(track->path) *
		   (track->interp == ANIM_INTERP_CUBICSPLINE ? 3u : 1u);
	for (size_t i = 0; i < n; i++) {
		if (!isfinite(track->values[i])) {
			snprintf(why, why_size, "key values must be finite (value %zu)", i);
			return TL_ERR_INPUT;
		}
	}
	/* Rotation keys are unit quaternions (glTF 2.0 §3.11); a zero one has no direction to normalise to
	 * (CUBICSPLINE tangents, the first and third of each triple, may be zero). */
	if (track->path == ANIM_PATH_ROTATION) {
		const int cubic = track->interp == ANIM_INTERP_CUBICSPLINE;
		for (size_t i = 0; i < track->key_count; i++) {
			const float *q = track->values + (cubic ? i * 3 + 1 : i) * 4;
			if (!(sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]) >= 1e-6f)) {
				snprintf(why, why_size, "rotation key %zu is a zero quaternion (rotations are unit quaternions)", i);
				return TL_ERR_INPUT;
			}
		}
	}
	return 0;
}

/* Index i of the key interval [times[i], times[i+1]] containing t; t inside the range. */
static size_t find_interval(const float *times, size_t n, float t)
{
	size_t lo = 0, hi = n - 1;
	while (hi - lo > 1) {
		size_t mid = (lo + hi) / 2;
		if (times[mid] <= t)
			lo = mid;
		else
			hi = mid;
	}
	return lo;
}

void anim_track_sample(const anim_track *track, float t, float out[4])
{
	const int c = anim_path_components(track->path);
	const size_t n = track->key_count;
	const int cubic = track->interp == ANIM_INTERP_CUBICSPLINE;
	/* Element k of key i: plain layout values[i*c+k]; cubic layout (a, v, b) per key. */
#define VAL(i, k) (cubic ? track->values[((i) * 3 + 1) * c + (k)] : track->values[(i) * c + (k)])
	out[3] = 1.0f;
	if (n == 1 || t <= track->times[0] || t >= track->times[n - 1]) {
		size_t i = (n == 1 || t <= track->times[0]) ? 0 : n - 1;
		for (int k = 0; k < c; k++)
			out[k] = VAL(i, k);
	} else {
		size_t i = find_interval(track->times, n, t);
		float t0 = track->times[i], t1 = track->times[i + 1];
		float td = t1 - t0;
		float u = (t - t0) / td;
		switch (track->interp) {
		case ANIM_INTERP_STEP:
			for (int k = 0; k < c; k++)
				out[k] = VAL(i, k);
			break;
		case ANIM_INTERP_LINEAR:
			if (track->path == ANIM_PATH_ROTATION) {
				tlm_quat a = {VAL(i, 0), VAL(i, 1), VAL(i, 2), VAL(i, 3)};
				tlm_quat b = {VAL(i + 1, 0), VAL(i + 1, 1), VAL(i + 1, 2), VAL(i + 1, 3)};
				tlm_quat q = tlm_quat_slerp(a, b, u);
				out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
				return;
			}
			for (int k = 0; k < c; k++)
				out[k] = VAL(i, k) + (VAL(i + 1, k) - VAL(i, k)) * u;
			break;
		default: { /* CUBICSPLINE: p(u) = (2u³-3u²+1)v0 + (u³-2u²+u)td·b0 + (-2u³+3u²)v1 + (u³-u²)td·a1 */
			float u2 = u * u, u3 = u2 * u;
			float h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u;
			float h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
			for (int k = 0; k < c; k++) {
				float v0 = track->values[(i * 3 + 1) * c + k];
				float b0 = track->values[(i * 3 + 2) * c + k];
				float a1 = track->values[((i + 1) * 3 + 0) * c + k];
				float v1 = track->values[((i + 1) * 3 + 1) * c + k];
				out[k] = h00 * v0 + h10 * td * b0 + h01 * v1 + h11 * td * a1;
			}
			break;
		}
		}
	}
#undef VAL
	if (track->path == ANIM_PATH_ROTATION) {
		tlm_quat q = tlm_quat_normalize((tlm_quat){out[0], out[1], out[2], out[3]});
		out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
	}
}

void anim_track_apply(const anim_track *track, float t, tlm_trs *trs)
{
	float v[4];
	anim_track_sample(track, t, v);
	switch (track->path) {
	case ANIM_PATH_TRANSLATION: trs->t = tlm_v3(v[0], v[1], v[2]); break;
	case ANIM_PATH_ROTATION: trs->r = (tlm_quat){v[0], v[1], v[2], v[3]}; break;
	case ANIM_PATH_SCALE: trs->s = tlm_v3(v[0], v[1], v[2]); break;
	default: break;
	}
}

void anim_track_finish(anim_track *track)
{
	if (!track)
		return;
	free(track->times);
	free(track->values);
	track->times = NULL;
	track->values = NULL;
	track->key_count = 0;
}

const char *anim_motion_kind_name(anim_motion_kind kind)
{
	switch (kind) {
	case ANIM_MOTION_SPIN: return "spin";
	case ANIM_MOTION_ORBIT: return "orbit";
	case ANIM_MOTION_BOB: return "bob";
	case ANIM_MOTION_TRACKS: return "keyframes";
	case ANIM_MOTION_FALL: return "fall";
	default: return "invalid";
	}
}

/* Orthonormal basis (u, v) of the plane normal to n; u is the projection of +X (or +Z when n ~ X). */
static void plane_basis(tlm_vec3 n, tlm_vec3 *u, tlm_vec3 *v)
{
	tlm_vec3 ref = fabsf(n.x) < 0.9f ? tlm_v3(1, 0, 0) : tlm_v3(0, 0, 1);
	*u = tlm_v3_normalize_or(tlm_v3_sub(ref, tlm_v3_scale(n, tlm_v3_dot(ref, n))), tlm_v3(1, 0, 0));
	*v = tlm_v3_cross(n, *u);
}

/* Ballistic fall with bounces, in closed form (no integration, so any time can be evaluated).
 * Segment 0: from height y0 with vertical speed vy until y = floor: y(s) = y0 + vy s - g s^2 / 2,
 * impact after s1 = (vy + sqrt(vy^2 + 2 g (y0 - floor))) / g with speed v = g s1 - vy.
 * Segment k >= 1: leaves the floor upwards at u_k = e^k v, lasts 2 u_k / g. Horizontal speed is
 * multiplied by e at each impact. Bounces below 1 mm/s end the motion: the object rests. */
static void fall_apply(const anim_motion *m, double tau, tlm_trs *trs)
{
	double g = m->gravity > 0.0f ? m->gravity : 9.81;
	double e = m->restitution;
	double x = trs->t.x, z = trs->t.z, y0 = trs->t.y, fl = m->floor_y;
	double vx = m->velocity.x, vz = m->velocity.z, vy = m->velocity.y;
	double h = y0 > fl ? y0 - fl : 0.0;
	double s1 = (vy + sqrt(vy * vy + 2.0 * g * h)) / g;
	if (tau <= s1) {
		trs->t = tlm_v3((float)(x + vx * tau), (float)(y0 + vy * tau - 0.5 * g * tau * tau), (float)(z + vz * tau));
		return;
	}
	x += vx * s1;
	z += vz * s1;
	tau -= s1;
	double u = e * (g * s1 - vy);
	for (int k = 0; k < 200 && u > 1e-3; k++) {
		double d = 2.0 * u / g;
		vx *= e;
		vz *= e;
		if (tau <= d) {
			trs->t = tlm_v3((float)(x + vx * tau), (float)(fl + u * tau - 0.5 * g * tau * tau), (float)(z + vz * tau));
			return;
		}
		x += vx * d;
		z += vz * d;
		tau -= d;
		u *= e;
	}
	trs->t = tlm_v3((float)x, (float)fl, (float)z);
}

void anim_motion_apply(const anim_motion *m, float t, tlm_trs *trs)
{
	const float d2r = TLM_PI / 180.0f;
	float tt = t < m->start_s ? 0.0f : t - m->start_s;
	switch (m->kind) {
	case ANIM_MOTION_SPIN: {
		/* Angles are reduced modulo 360 in double so long clips keep full float precision. */
		double deg = fmod((double)m->phase_deg + (double)m->rate_deg_s * tt, 360.0);
		tlm_quat q = tlm_quat_axis_angle(m->axis, (float)deg * d2r);
		trs->r = tlm_quat_normalize(tlm_quat_mul(q, trs->r));
		break;
	}
	case ANIM_MOTION_ORBIT: {
		tlm_vec3 n = tlm_v3_normalize_or(m->axis, tlm_v3(0, 1, 0)), u, v;
		plane_basis(n, &u, &v);
		float a = (float)fmod((double)m->phase_deg + (double)m->rate_deg_s * tt, 360.0) * d2r;
		/* u rotated by angle a about the axis (right-hand rule, as SPIN): counter-clockwise seen from +axis. */
		tlm_vec3 off = tlm_v3_add(tlm_v3_scale(u, m->radius * cosf(a)), tlm_v3_scale(v, m->radius * sinf(a)));
		trs->t = tlm_v3_add(m->center, off);
		break;
	}
	case ANIM_MOTION_BOB: {
		double ph = fmod((double)m->frequency_hz * tt, 1.0) * 2.0 * TLM_PI + (double)m->phase_deg * d2r;
		trs->t = tlm_v3_add(trs->t, tlm_v3_scale(m->amplitude, (float)sin(ph)));
		break;
	}
	case ANIM_MOTION_TRACKS:
		for (size_t i = 0; i < m->track_count; i++)
			anim_track_apply(&m->tracks[i], tt, trs);
		break;
	case ANIM_MOTION_FALL:
		fall_apply(m, tt, trs);
		break;
	default: break;
	}
}

void anim_motion_finish(anim_motion *m)
{
	if (!m)
		return;
	for (size_t i = 0; i < m->track_count; i++)
		anim_track_finish(&m->tracks[i]);
	free(m->tracks);
	m->tracks = NULL;
	m->track_count = 0;
}
