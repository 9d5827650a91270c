/* test_math.c — tl_math against hand-computed values (tolerance 1e-5 unless stated). */
#include <math.h>

#include "taslab/tl_math.h"
#include "test_util.h"

#define EPS 1e-5f

static void assert_near(float a, float b, float eps)
{
	if (fabsf(a - b) > eps)
		fail_msg("%.9g != %.9g (tolerance %g)", a, b, eps);
}

static void test_inverse_roundtrip(void **state)
{
	(void)state;
	tlm_trs trs = {{1, 2, 3}, tlm_quat_axis_angle(tlm_v3(0.3f, 1, 0.2f), 1.1f), {2, 0.5f, 3}};
	tlm_mat4 m = tlm_trs_matrix(trs);
	tlm_mat4 p = tlm_mat4_mul(m, tlm_mat4_inverse(m));
	for (int i = 0; i < 16; i++)
		assert_near(p.m[i], (i % 5 == 0) ? 1.0f : 0.0f, EPS);
}

static void test_quat_rotate(void **state)
{
	(void)state;
	/* +90 degrees about +Y turns +Z into +X (right-hand rule). */
	tlm_vec3 v = tlm_quat_rotate(tlm_quat_axis_angle(tlm_v3(0, 1, 0), TLM_PI / 2), tlm_v3(0, 0, 1));
	assert_near(v.x, 1, EPS);
	assert_near(v.y, 0, EPS);
	assert_near(v.z, 0, EPS);
	/* The matrix form agrees with the quaternion form. */
	tlm_quat q = tlm_quat_euler_deg(30, 40, 50);
	tlm_vec3 a = tlm_quat_rotate(q, tlm_v3(0.2f, -0.7f, 0.4f));
	tlm_vec3 b = tlm_mat4_mul_point(tlm_mat4_from_quat(q), tlm_v3(0.2f, -0.7f, 0.4f));
	assert_near(a.x, b.x, EPS);
	assert_near(a.y, b.y, EPS);
	assert_near(a.z, b.z, EPS);
}

static void test_slerp(void **state)
{
	(void)state;
	/* Halfway between identity and 90 degrees about Z is 45 degrees: (0, 0, sin 22.5, cos 22.5). */
	tlm_quat a = tlm_quat_identity(), b = tlm_quat_axis_angle(tlm_v3(0, 0, 1), TLM_PI / 2);
	tlm_quat h = tlm_quat_slerp(a, b, 0.5f);
	assert_near(h.z, sinf(TLM_PI / 8), EPS);
	assert_near(h.w, cosf(TLM_PI / 8), EPS);
	/* Shortest path: -b is the same rotation; slerp must not take the long way round. */
	tlm_quat nb = {-b.x, -b.y, -b.z, -b.w};
	tlm_quat h2 = tlm_quat_slerp(a, nb, 0.5f);
	assert_near(fabsf(h2.z), sinf(TLM_PI / 8), EPS);
	assert_near(fabsf(h2.w), cosf(TLM_PI / 8), EPS);
	/* u = 1/3 of a 90 degree turn is 30 degrees. */
	tlm_quat t = tlm_quat_slerp(a, b, 1.0f / 3.0f);
	assert_near(t.z, sinf(TLM_PI / 12), EPS);
}

static void test_projection(void **state)
{
	(void)state;
	/* Vulkan clip space: z = -near -> depth 0, z = -far -> depth 1, view +Y -> NDC -Y. */
	tlm_mat4 p = tlm_mat4_perspective(TLM_PI / 2, 2.0f, 0.5f, 100.0f);
	tlm_vec4 n = tlm_mat4_mul_v4(p, (tlm_vec4){0, 0, -0.5f, 1});
	tlm_vec4 f = tlm_mat4_mul_v4(p, (tlm_vec4){0, 0, -100.0f, 1});
	assert_near(n.z / n.w, 0.0f, EPS);
	assert_near(f.z / f.w, 1.0f, EPS);
	/* fovy 90: a point at 45 degrees up is on the top edge (NDC y = -1); aspect 2 halves x. */
	tlm_vec4 up = tlm_mat4_mul_v4(p, (tlm_vec4){1, 1, -1, 1});
	assert_near(up.y / up.w, -1.0f, EPS);
	assert_near(up.x / up.w, 0.5f, EPS);
	tlm_mat4 o = tlm_mat4_ortho(-2, 2, -1, 1, 0, 10);
	tlm_vec4 c = tlm_mat4_mul_v4(o, (tlm_vec4){2, 1, -10, 1});
	assert_near(c.x, 1, EPS);
	assert_near(c.y, -1, EPS);
	assert_near(c.z, 1, EPS);
}

static void test_look_at(void **state)
{
	(void)state;
	tlm_mat4 v = tlm_mat4_look_at(tlm_v3(0, 0, 5), tlm_v3(0, 0, 0), tlm_v3(0, 1, 0));
	tlm_vec3 o = tlm_mat4_mul_point(v, tlm_v3(0, 0, 0));
	assert_near(o.z, -5, EPS);
	tlm_mat4 v2 = tlm_mat4_look_at(tlm_v3(3, 0, 0), tlm_v3(0, 0, 0), tlm_v3(0, 1, 0));
	tlm_vec3 r = tlm_mat4_mul_point(v2, tlm_v3(0, 0, -1)); /* -Z world is to the camera's right */
	assert_near(r.x, 1, EPS);
	assert_near(r.z, -3, EPS);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_inverse_roundtrip), cmocka_unit_test(test_quat_rotate),
		cmocka_unit_test(test_slerp),             cmocka_unit_test(test_projection),
		cmocka_unit_test(test_look_at),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
