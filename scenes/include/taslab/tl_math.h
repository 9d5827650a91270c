/* tl_math.h — small vector / quaternion / matrix library used by scene evaluation and the renderer.
 *
 * Conventions (fixed here, relied on by the shaders):
 *  - right-handed world space, +Y up; cameras look down -Z in view space;
 *  - matrices are column-major (m[col*4+row]), as GLSL expects, and act on column vectors;
 *  - projection matrices map to Vulkan clip space: depth 0..1, +Y pointing down in NDC;
 *  - quaternions are (x, y, z, w) as in glTF 2.0.
 * All functions are pure and take/return values; nothing allocates.
 */
#ifndef TASLAB_TL_MATH_H
#define TASLAB_TL_MATH_H

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tlm_vec3 { float x, y, z; } tlm_vec3;
typedef struct tlm_vec4 { float x, y, z, w; } tlm_vec4;
typedef struct tlm_quat { float x, y, z, w; } tlm_quat;
typedef struct tlm_mat4 { float m[16]; } tlm_mat4;

/* Translation / rotation / scale, composed as T * R * S (glTF node order). */
typedef struct tlm_trs {
	tlm_vec3 t;
	tlm_quat r;
	tlm_vec3 s;
} tlm_trs;

#define TLM_PI 3.14159265358979323846f

tlm_vec3 tlm_v3(float x, float y, float z);
tlm_vec3 tlm_v3_add(tlm_vec3 a, tlm_vec3 b);
tlm_vec3 tlm_v3_sub(tlm_vec3 a, tlm_vec3 b);
tlm_vec3 tlm_v3_scale(tlm_vec3 a, float s);
tlm_vec3 tlm_v3_mul(tlm_vec3 a, tlm_vec3 b);
tlm_vec3 tlm_v3_lerp(tlm_vec3 a, tlm_vec3 b, float u);
float tlm_v3_dot(tlm_vec3 a, tlm_vec3 b);
tlm_vec3 tlm_v3_cross(tlm_vec3 a, tlm_vec3 b);
float tlm_v3_length(tlm_vec3 a);
/* Returns a unit vector, or `fallback` when |a| is (nearly) zero. */
tlm_vec3 tlm_v3_normalize_or(tlm_vec3 a, tlm_vec3 fallback);

tlm_quat tlm_quat_identity(void);
tlm_quat tlm_quat_axis_angle(tlm_vec3 axis, float angle_rad);
/* Intrinsic Y (yaw), then X (pitch), then Z (roll), angles in degrees. */
tlm_quat tlm_quat_euler_deg(float pitch_x, float yaw_y, float roll_z);
tlm_quat tlm_quat_mul(tlm_quat a, tlm_quat b);
tlm_quat tlm_quat_normalize(tlm_quat q);
tlm_vec3 tlm_quat_rotate(tlm_quat q, tlm_vec3 v);
/* Spherical linear interpolation along the shortest arc (glTF 2.0 spec, Appendix C). */
tlm_quat tlm_quat_slerp(tlm_quat a, tlm_quat b, float u);

tlm_trs tlm_trs_identity(void);
tlm_mat4 tlm_trs_matrix(tlm_trs trs);

tlm_mat4 tlm_mat4_identity(void);
tlm_mat4 tlm_mat4_mul(tlm_mat4 a, tlm_mat4 b);
tlm_vec4 tlm_mat4_mul_v4(tlm_mat4 a, tlm_vec4 v);
tlm_vec3 tlm_mat4_mul_point(tlm_mat4 a, tlm_vec3 p);
tlm_mat4 tlm_mat4_translate(tlm_vec3 t);
tlm_mat4 tlm_mat4_scale(tlm_vec3 s);
tlm_mat4 tlm_mat4_from_quat(tlm_quat q);
tlm_mat4 tlm_mat4_transpose(tlm_mat4 a);
/* Determinant of the upper-left 3x3 (the linear part of an affine transform): negative for a mirroring one. */
float tlm_mat4_det3(tlm_mat4 a);
/* General inverse; returns identity when the matrix is singular (|det| < 1e-20). */
tlm_mat4 tlm_mat4_inverse(tlm_mat4 a);
/* View matrix for an eye at `eye` looking at `target`; `up` must not be parallel to the view direction. */
tlm_mat4 tlm_mat4_look_at(tlm_vec3 eye, tlm_vec3 target, tlm_vec3 up);
/* Perspective projection, vertical field of view in radians, Vulkan clip space (depth 0..1, y down). */
tlm_mat4 tlm_mat4_perspective(float fovy_rad, float aspect, float znear, float zfar);
/* Orthographic projection of the view-space box [l,r]x[b,t]x[-n,-f], Vulkan clip space. */
tlm_mat4 tlm_mat4_ortho(float l, float r, float b, float t, float n, float f);

float tlm_clampf(float x, float lo, float hi);
float tlm_smoothstep(float e0, float e1, float x);

#ifdef __cplusplus
}
#endif
#endif
