/* test_scene.c — scene files: the built-in scene loads; bad files give one-line errors naming the
 * file and the JSON path (also for degenerate values and hostile glTF assets, issue 12); evaluation is a
 * pure function of time. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
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

/* A small scene with one material (fields `mat`), one object (extra fields `obj`), lights `lights` and extra
 * top-level keys `root`; it loads when all four are empty. */
static const char *HOSTILE =
	"{\"taslab_scene\": 1, \"name\": \"h\", \"materials\": {\"m\": {%s}}, \"meshes\": {\"b\": {\"type\": \"box\"}},"
	" \"objects\": [{\"name\": \"o\", \"mesh\": \"b\", \"material\": \"m\"%s}], \"lights\": [%s],"
	" \"cameras\": [{\"name\": \"c\", \"motion\": \"stationary\", \"keys\": [{\"t\": 0, \"position\": [0, 0, 5],"
	" \"target\": [0, 0, 0]}]}]%s}";

static char *hostile_scene(const char *mat, const char *obj, const char *lights, const char *root)
{
	size_t n = strlen(HOSTILE) + strlen(mat) + strlen(obj) + strlen(lights) + strlen(root) + 1;
	char *buf = malloc(n);
	snprintf(buf, n, HOSTILE, mat, obj, lights, root);
	return buf;
}

static void expect_hostile(const char *mat, const char *obj, const char *lights, const char *root, const char *path,
			   const char *needle)
{
	char *buf = hostile_scene(mat, obj, lights, root);
	expect_error(buf, path, needle);
	free(buf);
}

/* Degenerate values in scene files (issue 12): every number parsed into a float is finite after the
 * conversion (1e39 is valid JSON but infinity as a float); no zero rotation quaternions or rotation axes
 * (they were silently replaced by the identity and +Y). */
static void test_degenerate_values(void **state)
{
	(void)state;
	char *ok = hostile_scene("", "", "", "");
	scene *s = NULL;
	char err[512];
	if (scene_load_from_memory(ok, strlen(ok), "ok.json", &s, err, sizeof err))
		fail_msg("%s", err);
	scene_destroy(&s);
	free(ok);
	expect_hostile("\"emissive\": [1e39, 0, 0]", "", "", "", "$.materials.m.emissive", "finite");
	expect_hostile("\"base_color\": [1, 1, -1e39, 1]", "", "", "", "$.materials.m.base_color", "finite");
	expect_hostile("", ", \"scale\": 1e39", "", "", "$.objects[0].scale", "finite");
	expect_hostile("", ", \"translation\": [0, 1e39, 0]", "", "", "$.objects[0].translation", "finite");
	expect_hostile("", ", \"rotation\": [0, 0, 0, 0]", "", "", "$.objects[0].rotation", "quaternion");
	expect_hostile("", ", \"animation\": [{\"type\": \"spin\", \"axis\": [0, 0, 0]}]", "", "",
		       "$.objects[0].animation[0].axis", "zero vector");
	expect_hostile("", ", \"animation\": [{\"type\": \"keyframes\", \"times\": [0, 1], \"rotation\": [[0, 0, 0, 1],"
			   " [0, 0, 0, 0]]}]",
		       "", "", "$.objects[0].animation[0].rotation", "zero quaternion");
	expect_hostile("", "", "{\"name\": \"l\", \"type\": \"point\", \"animation\": [{\"type\": \"orbit\", \"axis\": [0, 0, 0]}]}",
		       "", "$.lights[0].animation[0].axis", "zero vector");
	expect_hostile("", "", "{\"name\": \"l\", \"type\": \"point\", \"intensity_keys\": {\"times\": [0], \"values\": [1e39]}}",
		       "", "$.lights[0].intensity_keys[0]", "finite");
	/* 257 colour textures: beyond the renderer's 256 texture layers per colour space */
	size_t n = 64 + 40 * (SCENE_MAX_TEXTURES + 1), at = 0;
	char *root = malloc(n);
	at += (size_t)snprintf(root, n, ", \"texture_size\": 4, \"textures\": {");
	for (int i = 0; i <= SCENE_MAX_TEXTURES; i++)
		at += (size_t)snprintf(root + at, n - at, "%s\"t%d\": {\"pattern\": \"flat\"}", i ? ", " : "", i);
	snprintf(root + at, n - at, "}");
	expect_hostile("", "", "", root, "$.textures.t256", "more than 256 colour textures");
	free(root);
}

/* A hostile glTF reached through "assets" is refused with the scene file's JSON path and the glTF's reason;
 * messages stay one line even when a file name holds a newline. */
static void test_hostile_assets(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("scene_hostile");
	char path[4096], err[1024];
	/* 6148914691236517206 positions * 12 bytes wraps to 8 bytes: before issue 12, a heap overflow */
	snprintf(path, sizeof path, "%s/wrap.gltf", dir);
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	fputs("{\"asset\": {\"version\": \"2.0\"}, \"scenes\": [{\"nodes\": [0]}], \"nodes\": [{\"mesh\": 0}],"
	      " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}}]}],"
	      " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 6148914691236517206, \"type\": \"VEC3\"}],"
	      " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}], \"buffers\": [{\"byteLength\": 36, \"uri\":"
	      " \"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}]}", f);
	fclose(f);
	static const char *const scenes[][3] = {
		{"wrap.json", "wrap.gltf", "elements"},
		{"newline.json", "new\\nline.gltf", "new line.gltf"},
	};
	for (size_t i = 0; i < 2; i++) {
		snprintf(path, sizeof path, "%s/%s", dir, scenes[i][0]);
		f = fopen(path, "w");
		assert_non_null(f);
		fprintf(f, "{\"taslab_scene\": 1, \"name\": \"a\", \"assets\": [{\"name\": \"x\", \"gltf\": \"%s\"}],"
			   " \"cameras\": [{\"name\": \"c\", \"motion\": \"stationary\", \"keys\": [{\"t\": 0,"
			   " \"position\": [0, 0, 5], \"target\": [0, 0, 0]}]}]}", scenes[i][1]);
		fclose(f);
		scene *s = NULL;
		int rc = scene_load(path, &s, err, sizeof err);
		if (rc != TL_ERR_INPUT || s || !strstr(err, "$.assets[0].gltf") || !strstr(err, scenes[i][2]) ||
		    strchr(err, '\n'))
			fail_msg("%s: rc %d, message '%s'", scenes[i][0], rc, err);
	}
}

/* scene_load_with: the texture size knob replaces the file's (textures are made at that size). */
static void test_load_with_texture_size(void **state)
{
	(void)state;
	scene *s = NULL;
	char err[512];
	const char *path = TASLAB_SOURCE_DIR "/scenes/turntable.json";
	if (scene_load_with(path, &(scene_load_desc){.texture_size = 8}, &s, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(s->texture_size, 8);
	assert_true(s->texture_count > 0);
	scene_destroy(&s);
	assert_int_equal(scene_load_with(path, &(scene_load_desc){.texture_size = 12}, &s, err, sizeof err), TL_ERR_ARG);
	assert_null(s);
	if (scene_load_with(path, NULL, &s, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(s->texture_size, 512); /* the file's */
	scene_destroy(&s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_builtin_loads), cmocka_unit_test(test_eval_is_pure),
		cmocka_unit_test(test_camera_path),   cmocka_unit_test(test_errors),
		cmocka_unit_test(test_degenerate_values), cmocka_unit_test(test_hostile_assets),
		cmocka_unit_test(test_load_with_texture_size),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
