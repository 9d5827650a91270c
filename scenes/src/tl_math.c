/* tl_math.c — see tl_math.h for conventions. */
#include "taslab/tl_math.h"

#include <math.h>

tlm_vec3 tlm_v3(float x, float y, float z) { return (tlm_vec3){x, y, z}; }
tlm_vec3 tlm_v3_add(tlm_vec3 a, tlm_vec3 b) { return (tlm_vec3){a.x + b.x, a.y + b.y, a.z + b.z}; }
tlm_vec3 tlm_v3_sub(tlm_vec3 a, tlm_vec3 b) { return (tlm_vec3){a.x - b.x, a.y - b.y, a.z - b.z}; }
tlm_vec3 tlm_v3_scale(tlm_vec3 a, float s) { return (tlm_vec3){a.x * s, a.y * s, a.z * s}; }
tlm_vec3 tlm_v3_mul(tlm_vec3 a, tlm_vec3 b) { return (tlm_vec3){a.x * b.x, a.y * b.y, a.z * b.z}; }
tlm_vec3 tlm_v3_lerp(tlm_vec3 a, tlm_vec3 b, float u)
{
	return (tlm_vec3){a.x + (b.x - a.x) * u, a.y + (b.y - a.y) * u, a.z + (b.z - a.z) * u};
}
float tlm_v3_dot(tlm_vec3 a, tlm_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
tlm_vec3 tlm_v3_cross(tlm_vec3 a, tlm_vec3 b)
{
	return (tlm_vec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
float tlm_v3_length(tlm_vec3 a) { return sqrtf(tlm_v3_dot(a, a)); }
tlm_vec3 tlm_v3_normalize_or(tlm_vec3 a, tlm_vec3 fallback)
{
	float l = tlm_v3_length(a);
	return l > 1e-12f ? tlm_v3_scale(a, 1.0f / l) : fallback;
}

tlm_quat tlm_quat_identity(void) { return (tlm_quat){0, 0, 0, 1}; }

tlm_quat tlm_quat_axis_angle(tlm_vec3 axis, float angle_rad)
{
	tlm_vec3 n = tlm_v3_normalize_or(axis, tlm_v3(0, 1, 0));
	float s = sinf(0.5f * angle_rad);
	return (tlm_quat){n.x * s, n.y * s, n.z * s, cosf(0.5f * angle_rad)};
}

tlm_quat tlm_quat_mul(tlm_quat a, tlm_quat b)
{
	return (tlm_quat){
		a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
		a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
		a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w,
		a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
	};
}

tlm_quat tlm_quat_euler_deg(float pitch_x, float yaw_y, float roll_z)
{
	const float d = TLM_PI / 180.0f;
	tlm_quat qy = tlm_quat_axis_angle(tlm_v3(0, 1, 0), yaw_y * d);
	tlm_quat qx = tlm_quat_axis_angle(tlm_v3(1, 0, 0), pitch_x * d);
	tlm_quat qz = tlm_quat_axis_angle(tlm_v3(0, 0, 1), roll_z * d);
	return tlm_quat_mul(tlm_quat_mul(qy, qx), qz);
}

tlm_quat tlm_quat_normalize(tlm_quat q)
{
	float l = sqrtf(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
	if (l < 1e-20f)
		return tlm_quat_identity();
	return (tlm_quat){q.x / l, q.y / l, q.z / l, q.w / l};
}

tlm_vec3 tlm_quat_rotate(tlm_quat q, tlm_vec3 v)
{
	/* v' = v + 2w(u x v) + 2 u x (u x v), u = (x, y, z) */
	tlm_vec3 u = {q.x, q.y, q.z};
	tlm_vec3 c = tlm_v3_cross(u, v);
	tlm_vec3 cc = tlm_v3_cross(u, c);
	return tlm_v3_add(v, tlm_v3_add(tlm_v3_scale(c, 2.0f * q.w), tlm_v3_scale(cc, 2.0f)));
}

tlm_quat tlm_quat_slerp(tlm_quat a, tlm_quat b, float u)
{
	/* glTF 2.0 Appendix C: take the shortest path (negate b if dot < 0); fall back to
	 * normalised lerp when the quaternions are nearly parallel to avoid dividing by ~0. */
	float d = a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w;
	if (d < 0.0f) {
		b = (tlm_quat){-b.x, -b.y, -b.z, -b.w};
		d = -d;
	}
	float ka, kb;
	if (d > 0.9995f) {
		ka = 1.0f - u;
		kb = u;
	} else {
		float th = acosf(d);
		float s = sinf(th);
		ka = sinf((1.0f - u) * th) / s;
		kb = sinf(u * th) / s;
	}
	tlm_quat r = {ka * a.x + kb * b.x, ka * a.y + kb * b.y, ka * a.z + kb * b.z, ka * a.w + kb * b.w};
	return tlm_quat_normalize(r);
}

tlm_trs tlm_trs_identity(void) { return (tlm_trs){{0, 0, 0}, {0, 0, 0, 1}, {1, 1, 1}}; }

tlm_mat4 tlm_trs_matrix(tlm_trs trs)
{
	tlm_mat4 m = tlm_mat4_from_quat(trs.r);
	for (int r = 0; r < 3; r++) {
		m.m[0 * 4 + r] *= trs.s.x;
		m.m[1 * 4 + r] *= trs.s.y;
		m.m[2 * 4 + r] *= trs.s.z;
	}
	m.m[12] = trs.t.x;
	m.m[13] = trs.t.y;
	m.m[14] = trs.t.z;
	return m;
}

tlm_mat4 tlm_mat4_identity(void)
{
	tlm_mat4 m = {{0}};
	m.m[0] = m.m[5] = m.m[10] = m.m[15] = 1.0f;
	return m;
}

tlm_mat4 tlm_mat4_mul(tlm_mat4 a, tlm_mat4 b)
{
	tlm_mat4 r;
	for (int c = 0; c < 4; c++)
		for (int row = 0; row < 4; row++) {
			float s = 0.0f;
			for (int k = 0; k < 4; k++)
				s += a.m[k * 4 + row] * b.m[c * 4 + k];
			r.m[c * 4 + row] = s;
		}
	return r;
}

tlm_vec4 tlm_mat4_mul_v4(tlm_mat4 a, tlm_vec4 v)
{
	const float *m = a.m;
	return (tlm_vec4){
		m[0] * v.x + m[4] * v.y + m[8] * v.z + m[12] * v.w,
		m[1] * v.x + m[5] * v.y + m[9] * v.z + m[13] * v.w,
		m[2] * v.x + m[6] * v.y + m[10] * v.z + m[14] * v.w,
		m[3] * v.x + m[7] * v.y + m[11] * v.z + m[15] * v.w,
	};
}

tlm_vec3 tlm_mat4_mul_point(tlm_mat4 a, tlm_vec3 p)
{
	tlm_vec4 r = tlm_mat4_mul_v4(a, (tlm_vec4){p.x, p.y, p.z, 1.0f});
	return tlm_v3(r.x, r.y, r.z);
}

tlm_mat4 tlm_mat4_translate(tlm_vec3 t)
{
	tlm_mat4 m = tlm_mat4_identity();
	m.m[12] = t.x;
	m.m[13] = t.y;
	m.m[14] = t.z;
	return m;
}

tlm_mat4 tlm_mat4_scale(tlm_vec3 s)
{
	tlm_mat4 m = tlm_mat4_identity();
	m.m[0] = s.x;
	m.m[5] = s.y;
	m.m[10] = s.z;
	return m;
}

tlm_mat4 tlm_mat4_from_quat(tlm_quat q)
{
	q = tlm_quat_normalize(q);
	float x = q.x, y = q.y, z = q.z, w = q.w;
	tlm_mat4 m = tlm_mat4_identity();
	m.m[0] = 1 - 2 * (y * y + z * z);
	m.m[1] = 2 * (x * y + z * w);
	m.m[2] = 2 * (x * z - y * w);
	m.m[4] = 2 * (x * y - z * w);
	m.m[5] = 1 - 2 * (x * x + z * z);
	m.m[6] = 2 * (y * z + x * w);
	m.m[8] = 2 * (x * z + y * w);
	m.m[9] = 2 * (y * z - x * w);
	m.m[10] = 1 - 2 * (x * x + y * y);
	return m;
}

tlm_mat4 tlm_mat4_transpose(tlm_mat4 a)
{
	tlm_mat4 r;
	for (int c = 0; c < 4; c++)
		for (int row = 0; row < 4; row++)
			r.m[c * 4 + row] = a.m[row * 4 + c];
	return r;
}

float tlm_mat4_det3(tlm_mat4 a)
{
	/* columns c0, c1, c2 (m[col*4+row]): det = c0 . (c1 x c2), in double so that the sign of a tiny one is right */
	const float *m = a.m;
	double c1x = m[4], c1y = m[5], c1z = m[6], c2x = m[8], c2y = m[9], c2z = m[10];
	return (float)(m[0] * (c1y * c2z - c1z * c2y) + m[1] * (c1z * c2x - c1x * c2z) + m[2] * (c1x * c2y - c1y * c2x));
}

tlm_mat4 tlm_mat4_inverse(tlm_mat4 a)
{
	/* Cofactor expansion (as in MESA's gluInvertMatrix), in double for accuracy. */
	const float *m = a.m;
	double inv[16];
	inv[0] = (double)m[5] * m[10] * m[15] - (double)m[5] * m[11] * m[14] - (double)m[9] * m[6] * m[15] +
		 (double)m[9] * m[7] * m[14] + (double)m[13] * m[6] * m[11] - (double)m[13] * m[7] * m[10];
	inv[4] = -(double)m[4] * m[10] * m[15] + (double)m[4] * m[11] * m[14] + (double)m[8] * m[6] * m[15] -
		 (double)m[8] * m[7] * m[14] - (double)m[12] * m[6] * m[11] + (double)m[12] * m[7] * m[10];
	inv[8] = (double)m[4] * m[9] * m[15] - (double)m[4] * m[11] * m[13] - (double)m[8] * m[5] * m[15] +
		 (double)m[8] * m[7] * m[13] + (double)m[12] * m[5] * m[11] - (double)m[12] * m[7] * m[9];
	inv[12] = -(double)m[4] * m[9] * m[14] + (double)m[4] * m[10] * m[13] + (double)m[8] * m[5] * m[14] -
		  (double)m[8] * m[6] * m[13] - (double)m[12] * m[5] * m[10] + (double)m[12] * m[6] * m[9];
	inv[1] = -(double)m[1] * m[10] * m[15] + (double)m[1] * m[11] * m[14] + (double)m[9] * m[2] * m[15] -
		 (double)m[9] * m[3] * m[14] - (double)m[13] * m[2] * m[11] + (double)m[13] * m[3] * m[10];
	inv[5] = (double)m[0] * m[10] * m[15] - (double)m[0] * m[11] * m[14] - (double)m[8] * m[2] * m[15] +
		 (double)m[8] * m[3] * m[14] + (double)m[12] * m[2] * m[11] - (double)m[12] * m[3] * m[10];
	inv[9] = -(double)m[0] * m[9] * m[15] + (double)m[0] * m[11] * m[13] + (double)m[8] * m[1] * m[15] -
		 (double)m[8] * m[3] * m[13] - (double)m[12] * m[1] * m[11] + (double)m[12] * m[3] * m[9];
	inv[13] = (double)m[0] * m[9] * m[14] - (double)m[0] * m[10] * m[13] - (double)m[8] * m[1] * m[14] +
		  (double)m[8] * m[2] * m[13] + (double)m[12] * m[1] * m[10] - (double)m[12] * m[2] * m[9];
	inv[2] = (double)m[1] * m[6] * m[15] - (double)m[1] * m[7] * m[14] - (double)m[5] * m[2] * m[15] +
		 (double)m[5] * m[3] * m[14] + (double)m[13] * m[2] * m[7] - (double)m[13] * m[3] * m[6];
	inv[6] = -(double)m[0] * m[6] * m[15] + (double)m[0] * m[7] * m[14] + (double)m[4] * m[2] * m[15] -
		 (double)m[4] * m[3] * m[14] - (double)m[12] * m[2] * m[7] + (double)m[12] * m[3] * m[6];
	inv[10] = (double)m[0] * m[5] * m[15] - (double)m[0] * m[7] * m[13] - (double)m[4] * m[1] * m[15] +
		  (double)m[4] * m[3] * m[13] + (double)m[12] * m[1] * m[7] - (double)m[12] * m[3] * m[5];
	inv[14] = -(double)m[0] * m[5] * m[14] + (double)m[0] * m[6] * m[13] + (double)m[4] * m[1] * m[14] -
		  (double)m[4] * m[2] * m[13] - (double)m[12] * m[1] * m[6] + (double)m[12] * m[2] * m[5];
	inv[3] = -(double)m[1] * m[6] * m[11] + (double)m[1] * m[7] * m[10] + (double)m[5] * m[2] * m[11] -
		 (double)m[5] * m[3] * m[10] - (double)m[9] * m[2] * m[7] + (double)m[9] * m[3] * m[6];
	inv[7] = (double)m[0] * m[6] * m[11] - (double)m[0] * m[7] * m[10] - (double)m[4] * m[2] * m[11] +
		 (double)m[4] * m[3] * m[10] + (double)m[8] * m[2] * m[7] - (double)m[8] * m[3] * m[6];
	inv[11] = -(double)m[0] * m[5] * m[11] + (double)m[0] * m[7] * m[9] + (double)m[4] * m[1] * m[11] -
		  (double)m[4] * m[3] * m[9] - (double)m[8] * m[1] * m[7] + (double)m[8] * m[3] * m[5];
	inv[15] = (double)m[0] * m[5] * m[10] - (double)m[0] * m[6] * m[9] - (double)m[4] * m[1] * m[10] +
		  (double)m[4] * m[2] * m[9] + (double)m[8] * m[1] * m[6] - (double)m[8] * m[2] * m[5];
	double det = m[0] * inv[0] + m[1] * inv[4] + m[2] * inv[8] + m[3] * inv[12];
	if (fabs(det) < 1e-20)
		return tlm_mat4_identity();
	tlm_mat4 r;
	for (int i = 0; i < 16; i++)
		r.m[i] = (float)(inv[i] / det);
	return r;
}

tlm_mat4 tlm_mat4_look_at(tlm_vec3 eye, tlm_vec3 target, tlm_vec3 up)
{
	tlm_vec3 f = tlm_v3_normalize_or(tlm_v3_sub(target, eye), tlm_v3(0, 0, -1));
	tlm_vec3 s = tlm_v3_normalize_or(tlm_v3_cross(f, up), tlm_v3(1, 0, 0));
	tlm_vec3 u = tlm_v3_cross(s, f);
	tlm_mat4 m = tlm_mat4_identity();
	m.m[0] = s.x;
	m.m[4] = s.y;
	m.m[8] = s.z;
	m.m[1] = u.x;
	m.m[5] = u.y;
	m.m[9] = u.z;
	m.m[2] = -f.x;
	m.m[6] = -f.y;
	m.m[10] = -f.z;
	m.m[12] = -tlm_v3_dot(s, eye);
	m.m[13] = -tlm_v3_dot(u, eye);
	m.m[14] = tlm_v3_dot(f, eye);
	return m;
}

tlm_mat4 tlm_mat4_perspective(float fovy_rad, float aspect, float znear, float zfar)
{
	/* Right-handed view space (camera looks down -Z) to Vulkan clip space: z_ndc in [0,1],
	 * y flipped so that +Y in view space points up on screen. */
	float f = 1.0f / tanf(0.5f * fovy_rad);
	tlm_mat4 m = {{0}};
	m.m[0] = f / aspect;
	m.m[5] = -f;
	m.m[10] = zfar / (znear - zfar);
	m.m[11] = -1.0f;
	m.m[14] = (znear * zfar) / (znear - zfar);
	return m;
}

tlm_mat4 tlm_mat4_ortho(float l, float r, float b, float t, float n, float f)
{
	tlm_mat4 m = tlm_mat4_identity();
	m.m[0] = 2.0f / (r - l);
	m.m[5] = -2.0f / (t - b);
	m.m[10] = 1.0f / (n - f);
	m.m[12] = -(r + l) / (r - l);
	m.m[13] = (t + b) / (t - b);
	m.m[14] = n / (n - f);
	return m;
}

float tlm_clampf(float x, float lo, float hi) { return x < lo ? lo : (x > hi ? hi : x); }

float tlm_smoothstep(float e0, float e1, float x)
{
	float u = tlm_clampf((x - e0) / (e1 - e0), 0.0f, 1.0f);
	return u * u * (3.0f - 2.0f * u);
}
