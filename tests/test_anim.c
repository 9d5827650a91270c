/* test_anim.c — keyframe interpolation against values hand-computed from the glTF 2.0 spec
 * (Appendix C, interpolation), and scripted motions against their closed forms. Tolerance 1e-5. */
#include <math.h>
#include <string.h>

#include "taslab/anim.h"
#include "taslab/tl_error.h"
#include "test_util.h"

#define EPS 1e-5f

static void near(float a, float b)
{
	if (fabsf(a - b) > EPS)
		fail_msg("%.9g != %.9g", a, b);
}

static float T3[3] = {0, 1, 2};

static anim_track track(anim_path path, anim_interp in, float *times, size_t n, float *values)
{
	return (anim_track){path, in, n, times, values};
}

static void test_step(void **state)
{
	(void)state;
	float v[9] = {0, 0, 0, 10, 0, 0, 20, 0, 0};
	anim_track t = track(ANIM_PATH_TRANSLATION, ANIM_INTERP_STEP, T3, 3, v);
	float o[4];
	anim_track_sample(&t, 1.5f, o);
	near(o[0], 10); /* value of the key at or before t */
	anim_track_sample(&t, 0.999f, o);
	near(o[0], 0);
	anim_track_sample(&t, -1.0f, o);
	near(o[0], 0); /* held before the first key */
	anim_track_sample(&t, 5.0f, o);
	near(o[0], 20); /* held after the last key */
}

static void test_linear(void **state)
{
	(void)state;
	float v[9] = {0, 0, 0, 10, -2, 4, 20, 0, 0};
	anim_track t = track(ANIM_PATH_TRANSLATION, ANIM_INTERP_LINEAR, T3, 3, v);
	float o[4];
	anim_track_sample(&t, 1.25f, o);
	near(o[0], 12.5f);
	near(o[1], -1.5f);
	near(o[2], 3.0f);
}

static void test_cubicspline(void **state)
{
	(void)state;
	/* Keys t = 0, 2; per key (in-tangent a, value v, out-tangent b): v0 = 0, b0 = 1, a1 = -1, v1 = 4.
	 * At t = 1: u = 0.5, td = 2: p = h00 v0 + h10 td b0 + h01 v1 + h11 td a1
	 *   = 0.5*0 + 0.125*2*1 + 0.5*4 + (-0.125)*2*(-1) = 2.5. */
	float times[2] = {0, 2};
	float v[18] = {9, 9, 9, 0, 0, 0, 1, 0, 0, /* key 0: a (unused), v, b */
		       -1, 0, 0, 4, 0, 0, 9, 9, 9}; /* key 1: a, v, b (unused) */
	anim_track t = track(ANIM_PATH_TRANSLATION, ANIM_INTERP_CUBICSPLINE, times, 2, v);
	float o[4];
	anim_track_sample(&t, 1.0f, o);
	near(o[0], 2.5f);
	anim_track_sample(&t, 2.0f, o);
	near(o[0], 4.0f);
	anim_track_sample(&t, 0.0f, o);
	near(o[0], 0.0f);
}

static void test_rotation_slerp(void **state)
{
	(void)state;
	float s = sinf(TLM_PI / 4), c = cosf(TLM_PI / 4); /* 90 degrees about Y */
	float times[2] = {0, 1};
	float v[8] = {0, 0, 0, 1, 0, s, 0, c};
	anim_track t = track(ANIM_PATH_ROTATION, ANIM_INTERP_LINEAR, times, 2, v);
	float o[4];
	anim_track_sample(&t, 0.5f, o);
	near(o[1], sinf(TLM_PI / 8));
	near(o[3], cosf(TLM_PI / 8));
}

static void test_validate(void **state)
{
	(void)state;
	char why[128];
	float bad_times[3] = {0, 2, 1};
	float v[9] = {0};
	anim_track t = track(ANIM_PATH_TRANSLATION, ANIM_INTERP_LINEAR, bad_times, 3, v);
	assert_int_equal(anim_track_validate(&t, why, sizeof why), TL_ERR_INPUT); /* issue 30.5: was a bare -1 */
	assert_non_null(strstr(why, "increasing"));
	float nan_v[9] = {0, 0, 0, NAN, 0, 0, 0, 0, 0};
	anim_track t2 = track(ANIM_PATH_TRANSLATION, ANIM_INTERP_LINEAR, T3, 3, nan_v);
	assert_int_equal(anim_track_validate(&t2, why, sizeof why), TL_ERR_INPUT);
	anim_track t3 = track(ANIM_PATH_TRANSLATION, ANIM_INTERP_LINEAR, T3, 3, v);
	assert_int_equal(anim_track_validate(&t3, why, sizeof why), TL_OK);
	assert_int_equal(anim_interp_from_string("CUBICSPLINE"), ANIM_INTERP_CUBICSPLINE);
	assert_int_equal(anim_interp_from_string("linear"), ANIM_INTERP_INVALID); /* glTF names are upper case */
}

static void test_motions(void **state)
{
	(void)state;
	/* spin: 90 deg/s about +Y for 1 s turns +Z into +X. */
	anim_motion spin = {.kind = ANIM_MOTION_SPIN, .axis = {0, 1, 0}, .rate_deg_s = 90};
	tlm_trs trs = tlm_trs_identity();
	anim_motion_apply(&spin, 1.0f, &trs);
	tlm_vec3 z = tlm_quat_rotate(trs.r, tlm_v3(0, 0, 1));
	near(z.x, 1);
	near(z.z, 0);
	/* orbit: centre (1,0,0), radius 2, axis +Y, 90 deg/s: t = 0 at centre + 2X, t = 1 at centre - 2Z. */
	anim_motion orbit = {.kind = ANIM_MOTION_ORBIT, .axis = {0, 1, 0}, .center = {1, 0, 0}, .radius = 2, .rate_deg_s = 90};
	trs = tlm_trs_identity();
	anim_motion_apply(&orbit, 0.0f, &trs);
	near(trs.t.x, 3);
	near(trs.t.z, 0);
	anim_motion_apply(&orbit, 1.0f, &trs);
	near(trs.t.x, 1);
	near(trs.t.z, -2);
	/* bob: amplitude 1 along Y at 0.25 Hz peaks at t = 1 s. */
	anim_motion bob = {.kind = ANIM_MOTION_BOB, .amplitude = {0, 1, 0}, .frequency_hz = 0.25f};
	trs = tlm_trs_identity();
	anim_motion_apply(&bob, 1.0f, &trs);
	near(trs.t.y, 1);
	/* start_s freezes the motion at its t = 0 state before the start. */
	anim_motion late = spin;
	late.start_s = 2.0f;
	trs = tlm_trs_identity();
	anim_motion_apply(&late, 1.5f, &trs);
	near(trs.r.w, 1);
	/* Purity: evaluating twice at the same time gives the same result. */
	tlm_trs a = tlm_trs_identity(), b = tlm_trs_identity();
	anim_motion_apply(&spin, 3.7f, &a);
	anim_motion_apply(&spin, 1.0f, &b);
	b = tlm_trs_identity();
	anim_motion_apply(&spin, 3.7f, &b);
	assert_memory_equal(&a, &b, sizeof a);
}

static void test_fall(void **state)
{
	(void)state;
	/* Dropped from y = 5 onto a floor at 0, g = 10, e = 0.5 (hand-computed):
	 * impact at 1 s with 10 m/s; y(0.5) = 5 - 5*0.25 = 3.75; rebound at 5 m/s lasting 1 s, peak at 1.5 s:
	 * 5*0.5 - 5*0.25 = 1.25; second rebound at 2.5 m/s from 2 s: y(2.25) = 2.5*0.25 - 5*0.0625 = 0.3125.
	 * Horizontal 2 m/s for 1 s, then 1 m/s for 1 s, then 0.5 m/s: x(2.25) = 2 + 1 + 0.125 = 3.125. */
	anim_motion f = {.kind = ANIM_MOTION_FALL, .velocity = {2, 0, 0}, .gravity = 10, .floor_y = 0, .restitution = 0.5f};
	const float t[] = {0.5f, 1.0f, 1.5f, 2.0f, 2.25f, 60.0f};
	const float y[] = {3.75f, 0.0f, 1.25f, 0.0f, 0.3125f, 0.0f};
	for (int i = 0; i < 6; i++) {
		tlm_trs trs = tlm_trs_identity();
		trs.t.y = 5;
		anim_motion_apply(&f, t[i], &trs);
		if (fabsf(trs.t.y - y[i]) > 1e-4f)
			fail_msg("fall: y(%g) = %g, expected %g", t[i], trs.t.y, y[i]);
		if (i == 4)
			near(trs.t.x, 3.125f);
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_step),     cmocka_unit_test(test_linear),   cmocka_unit_test(test_cubicspline),
		cmocka_unit_test(test_rotation_slerp), cmocka_unit_test(test_validate), cmocka_unit_test(test_motions),
		cmocka_unit_test(test_fall),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
