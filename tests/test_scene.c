/* test_scene.c — scene files: the built-in scene loads; bad files give one-line errors naming the
 * file and the JSON path; evaluation is a pure function of time. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "taslab/scene.h"
#include "test_util.h"

static const char *MINI =
	"{\"taslab_scene\": 1, \"name\": \"mini\", \"materials\": {\"m\": {}}, \"meshes\": {\"b\": {\"type\": \"box\"}},"
	" \"objects\": [{\"name\": \"o\", \"mesh\": \"b\", \"material\": \"m\","
	"   \"animation\": [{\"type\": \"spin\", \"rate_deg_s\": 90}]}],"
	" \"cameras\": [{\"name\": \"c\", \"motion\": \"moving\", \"keys\": ["
	"   {\"t\": 0, \"position\": [0, 0, 5], \"target\": [0, 0, 0]},"
	"   {\"t\": 1, \"position\": [5, 0, 5], \"target\": [0, 0, 0]},"
	"   {\"t\": 2, \"position\": [5, 0, 0], \"target\": [0, 0, 0]}]}]}";

static void expect_error(const char *json, const char *needle1, const char *needle2)
{
	scene *s = NULL;
	char err[512] = "";
	int rc = scene_load_from_memory(json, strlen(json), "bad.json", &s, err, sizeof err);
	assert_int_not_equal(rc, 0);
	assert_null(s);
	if (!strstr(err, "bad.json") || !strstr(err, needle1) || (needle2 && !strstr(err, needle2)))
		fail_msg("error message '%s' lacks '%s' / '%s'", err, needle1, needle2 ? needle2 : "");
	assert_null(strchr(err, '\n')); /* one line */
}

static void test_builtin_loads(void **state)
{
	(void)state;
	scene *s = NULL;
	char err[512];
	int rc = scene_load(TASLAB_SOURCE_DIR "/scenes/turntable.json", &s, err, sizeof err);
	if (rc)
		fail_msg("%s", err);
	assert_true(s->light_count >= 8); /* issue 2: at least 8 lights */
	int kinds[SCENE_LIGHT_COUNT] = {0};
	for (size_t i = 0; i < s->light_count; i++)
		kinds[s->lights[i].kind]++;
	assert_true(kinds[SCENE_LIGHT_DIRECTIONAL] && kinds[SCENE_LIGHT_POINT] && kinds[SCENE_LIGHT_SPOT]);
	int moving = 0, stationary = 0;
	for (size_t i = 0; i < s->camera_count; i++)
		s->cameras[i].motion == SCENE_CAMERA_MOVING ? moving++ : stationary++;
	assert_true(moving >= 1 && stationary >= 1);
	assert_true(scene_shadow_layer_count(s) <= SCENE_MAX_SHADOW_LAYERS);
	scene_destroy(&s);
	assert_null(s);
}

static void test_eval_is_pure(void **state)
{
	(void)state;
	scene *s = NULL;
	char err[512];
	if (scene_load(TASLAB_SOURCE_DIR "/scenes/turntable.json", &s, err, sizeof err))
		fail_msg("%s", err);
	tlm_mat4 a[64], b[64];
	scene_light_state la[16], lb[16];
	assert_true(s->object_count <= 64);
	scene_eval(s, 2.5f, a, la);
	scene_eval(s, 0.7f, b, lb); /* an unrelated evaluation in between must not matter */
	scene_eval(s, 2.5f, b, lb);
	assert_memory_equal(a, b, s->object_count * sizeof a[0]);
	assert_memory_equal(la, lb, s->light_count * sizeof la[0]);
	/* Animated things do move: the ring (spinning) differs between t = 0 and t = 1. */
	scene_eval(s, 0.0f, a, la);
	scene_eval(s, 1.0f, b, lb);
	assert_memory_not_equal(a, b, s->object_count * sizeof a[0]);
	scene_destroy(&s);
}

static void test_camera_path(void **state)
{
	(void)state;
	scene *s = NULL;
	char err[512];
	if (scene_load_from_memory(MINI, strlen(MINI), "mini.json", &s, err, sizeof err))
		fail_msg("%s", err);
	/* The Hermite path passes through its keys. */
	scene_camera_state c = scene_camera_eval(s, 0, 1.0f);
	assert_float_equal(c.eye.x, 5, 1e-5);
	assert_float_equal(c.eye.z, 5, 1e-5);
	c = scene_camera_eval(s, 0, 2.0f);
	assert_float_equal(c.eye.x, 5, 1e-5);
	assert_float_equal(c.eye.z, 0, 1e-5);
	/* Continuity at a key: positions just before and after key 1 agree within 1e-3. */
	scene_camera_state b = scene_camera_eval(s, 0, 0.9999f), a = scene_camera_eval(s, 0, 1.0001f);
	assert_float_equal(a.eye.x, b.eye.x, 1e-3);
	assert_int_equal(scene_find_camera(s, "c"), 0);
	assert_int_equal(scene_find_camera(s, "nope"), -1);
	scene_destroy(&s);
}

static void test_errors(void **state)
{
	(void)state;
	scene *s = NULL;
	char err[512];
	assert_int_equal(scene_load("/nonexistent/x.json", &s, err, sizeof err), TL_ERR_INPUT);
	assert_non_null(strstr(err, "/nonexistent/x.json"));
	expect_error("{\"taslab_scene\": 1, ", "not valid JSON", NULL);
	expect_error("[1, 2]", "$", "object");
	expect_error("{\"name\": \"x\"}", "$.taslab_scene", NULL);
	char buf[4096];
	/* Unknown key, with the path and the allowed keys. */
	snprintf(buf, sizeof buf, "%.*s, \"colour\": 1}", (int)strlen(MINI) - 1, MINI);
	expect_error(buf, "$.colour", "unknown key");
	/* A reference to a material that does not exist. */
	const char *p = strstr(MINI, "\"material\": \"m\"");
	snprintf(buf, sizeof buf, "%.*s\"material\": \"zz\"%s", (int)(p - MINI), MINI, p + strlen("\"material\": \"m\""));
	expect_error(buf, "$.objects[0].material", "zz");
	/* Wrong type deep inside. */
	p = strstr(MINI, "\"rate_deg_s\": 90");
	snprintf(buf, sizeof buf, "%.*s\"rate_deg_s\": \"fast\"%s", (int)(p - MINI), MINI, p + strlen("\"rate_deg_s\": 90"));
	expect_error(buf, "$.objects[0].animation[0].rate_deg_s", "number");
	/* Non-increasing camera key times. */
	p = strstr(MINI, "{\"t\": 1,");
	snprintf(buf, sizeof buf, "%.*s{\"t\": 0,%s", (int)(p - MINI), MINI, p + strlen("{\"t\": 1,"));
	expect_error(buf, "$.cameras[0].keys[1]", "increasing");
	/* Unknown mesh type. */
	p = strstr(MINI, "\"type\": \"box\"");
	snprintf(buf, sizeof buf, "%.*s\"type\": \"teapot\"%s", (int)(p - MINI), MINI, p + strlen("\"type\": \"box\""));
	expect_error(buf, "$.meshes.b", "teapot");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_builtin_loads), cmocka_unit_test(test_eval_is_pure),
		cmocka_unit_test(test_camera_path),   cmocka_unit_test(test_errors),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
