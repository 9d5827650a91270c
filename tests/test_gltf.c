/* test_gltf.c — glTF 2.0 loading (tinygltf) against values hand-computed from the glTF 2.0 spec
 * (Appendix C interpolation) on the Khronos sample models in ../shared/scenes; every sample model
 * renders a frame validation-clean on lavapipe; broken files give one-line errors.
 * Skips (with a message) when ../shared/scenes is absent. Tolerance 1e-4 (float keys). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"
#include "test_vk.h"

#define SHARED TASLAB_SHARED_DIR "/scenes"
#define EPS 1e-4f

static int have_shared(void)
{
	struct stat sb;
	if (stat(SHARED "/InterpolationTest/InterpolationTest.gltf", &sb) != 0) {
		fprintf(stderr, "skipping: %s not found (the shared glTF sample models)\n", SHARED);
		return 0;
	}
	return 1;
}

static scene *load(const char *model)
{
	char path[4096], err[1024];
	snprintf(path, sizeof path, "%s/%s/%s.gltf", SHARED, model, model);
	scene *s = NULL;
	if (scene_load(path, &s, err, sizeof err))
		fail_msg("%s", err);
	return s;
}

static int object(const scene *s, const char *name)
{
	for (size_t i = 0; i < s->object_count; i++)
		if (!strcmp(s->objects[i].name, name))
			return (int)i;
	fail_msg("no object %s", name);
	return -1;
}

static tlm_mat4 world_at(const scene *s, const char *name, float t)
{
	tlm_mat4 *w = calloc(s->object_count, sizeof *w);
	scene_eval(s, t, w, NULL);
	tlm_mat4 m = w[object(s, name)];
	free(w);
	return m;
}

static void near(float a, float b, const char *what)
{
	if (fabsf(a - b) > EPS)
		fail_msg("%s: %.6f != %.6f", what, a, b);
}

static float col_len(tlm_mat4 m, int c)
{
	return sqrtf(m.m[c * 4] * m.m[c * 4] + m.m[c * 4 + 1] * m.m[c * 4 + 1] + m.m[c * 4 + 2] * m.m[c * 4 + 2]);
}

static void test_interpolation_test(void **state)
{
	(void)state;
	if (!have_shared())
		skip();
	scene *s = load("InterpolationTest");
	const float k1 = 0.4166666567f, k2 = 0.875f;
	/* STEP scale keys 1, 0.5, 1, ... at 0.0417, 0.4167, 0.875: t = 0.6 holds key 1 = 0.5; before the first key 1. */
	near(col_len(world_at(s, "Cube", 0.6f), 0), 0.5f, "step scale");
	near(col_len(world_at(s, "Cube", 0.0f), 0), 1.0f, "step scale before first key");
	/* LINEAR scale halfway between 0.5 and 1 = 0.75. */
	near(col_len(world_at(s, "Cube.001", 0.5f * (k1 + k2)), 1), 0.75f, "linear scale");
	/* CUBICSPLINE scale, zero tangents, between 0.5 and 1: u = 0.5 -> 0.75; u = 0.25 -> 0.5*h00 + 1*h01
	 * with h00 = 2u^3 - 3u^2 + 1 = 0.84375, h01 = 0.15625 -> 0.578125. */
	near(col_len(world_at(s, "Cube.002", 0.5f * (k1 + k2)), 2), 0.75f, "cubic scale u=0.5");
	near(col_len(world_at(s, "Cube.002", k1 + 0.25f * (k2 - k1)), 2), 0.578125f, "cubic scale u=0.25");
	/* STEP rotation at t = 0.5 holds key 1: -45 degrees about Z: +X maps to (cos45, -sin45). */
	tlm_mat4 r = world_at(s, "Cube.003", 0.5f);
	near(r.m[0] / col_len(r, 0), cosf(TLM_PI / 4), "step rotation x");
	near(r.m[1] / col_len(r, 0), -sinf(TLM_PI / 4), "step rotation y");
	/* LINEAR rotation halfway between identity and -45 degrees about Z: slerp gives -22.5 degrees. */
	r = world_at(s, "Cube.005", 0.5f * k1);
	near(r.m[0] / col_len(r, 0), cosf(TLM_PI / 8), "slerp x");
	near(r.m[1] / col_len(r, 0), -sinf(TLM_PI / 8), "slerp y");
	/* STEP translation at t = 0.5 holds key 1 = (0, 10, 0). */
	near(world_at(s, "Cube.006", 0.5f).m[13], 10.0f, "step translation");
	/* LINEAR translation halfway between y = 10 and y = 6 (keys at 0.4167 and 0.8333) = 8. */
	near(world_at(s, "Cube.009", 0.625f).m[13], 8.0f, "linear translation");
	/* CUBICSPLINE translation, zero tangents, halfway between y = 6.640117 and 10: 8.3200585. */
	near(world_at(s, "Cube.008", 0.5f * k1).m[13], 0.5f * (6.640117168f + 10.0f), "cubic translation");
	scene_destroy(&s);
}

static void test_animated_cube(void **state)
{
	(void)state;
	if (!have_shared())
		skip();
	scene *s = load("AnimatedCube");
	/* Rotation keys (exact float values from the file): (0,0,0,1) at t=0, (0,1,0,-4.371139e-8) at t=1,
	 * (0,-8.742278e-8,0,-1) at t=2: consecutive keys are 180 degrees apart, so the sign of the tiny dot
	 * product decides the direction under the spec's shortest-path rule (negate the second key if dot < 0).
	 * t = 0.5: dot = -4.37e-8 < 0 -> slerp((0,0,0,1), (0,-1,0,0), 0.5) = (0,-.7071,0,.7071): +X -> +Z.
	 * t = 1.5: dot = -8.74e-8 + 4.37e-8 < 0 -> slerp((0,1,0,0), (0,0,0,1), 0.5) = (0,.7071,0,.7071): +X -> -Z. */
	tlm_mat4 m = world_at(s, "AnimatedCube", 0.5f);
	near(m.m[0], 0.0f, "t=0.5 x");
	near(m.m[2], 1.0f, "t=0.5 z");
	m = world_at(s, "AnimatedCube", 1.5f);
	near(m.m[0], 0.0f, "t=1.5 x");
	near(m.m[2], -1.0f, "t=1.5 z");
	scene_destroy(&s);
}

static void test_box_animated_hierarchy(void **state)
{
	(void)state;
	if (!have_shared())
		skip();
	scene *s = load("BoxAnimated");
	/* node0 translation y: 0 at t=0, 2.52 at t=1.25 -> 1.26 at t=0.625; node2 (grandchild, no translation
	 * of its own) inherits it through node1. */
	near(world_at(s, "node0", 0.625f).m[13], 1.26f, "node0 translation");
	near(world_at(s, "node2", 0.625f).m[13], 1.26f, "node2 inherits");
	/* node2 rotation: (0,0,0,-1) until 1.25, then slerp to (1,0,0,0) at 2.5: at 1.875 -> 90 degrees about X
	 * (up to sign): +Y maps to +-Z. */
	tlm_mat4 m = world_at(s, "node2", 1.875f);
	near(fabsf(m.m[4 + 2]), 1.0f, "node2 rotation");
	scene_destroy(&s);
}

static void test_broken_files(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("gltf_broken");
	char path[4096], err[1024];
	scene *s = NULL;
	snprintf(path, sizeof path, "%s/missing_buffer.gltf", dir);
	FILE *f = fopen(path, "w");
	fputs("{\"asset\": {\"version\": \"2.0\"}, \"buffers\": [{\"uri\": \"nope.bin\", \"byteLength\": 12}]}", f);
	fclose(f);
	assert_int_not_equal(scene_load(path, &s, err, sizeof err), 0);
	assert_non_null(strstr(err, "nope.bin"));
	assert_null(strchr(err, '\n'));
	snprintf(path, sizeof path, "%s/missing_texture.gltf", dir);
	f = fopen(path, "w");
	/* One triangle (positions in a data URI) whose material's base colour texture file is missing. */
	fputs("{\"asset\": {\"version\": \"2.0\"}, \"scenes\": [{\"nodes\": [0]}], \"nodes\": [{\"mesh\": 0}],"
	      " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"material\": 0}]}],"
	      " \"materials\": [{\"pbrMetallicRoughness\": {\"baseColorTexture\": {\"index\": 0}}}],"
	      " \"textures\": [{\"source\": 0}], \"images\": [{\"uri\": \"gone.png\"}],"
	      " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\","
	      " \"min\": [0, 0, 0], \"max\": [1, 1, 0]}], \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}],"
	      " \"buffers\": [{\"byteLength\": 36, \"uri\": \"data:application/octet-stream;base64,"
	      "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}]}", f);
	fclose(f);
	assert_int_not_equal(scene_load(path, &s, err, sizeof err), 0);
	assert_non_null(strstr(err, "gone.png"));
	snprintf(path, sizeof path, "%s/malformed.gltf", dir);
	f = fopen(path, "w");
	fputs("{\"asset\": {\"version\": \"2.0\"", f);
	fclose(f);
	assert_int_not_equal(scene_load(path, &s, err, sizeof err), 0);
	assert_non_null(strstr(err, "malformed.gltf"));
	assert_null(s);
	/* A valid glTF without triangle meshes has nothing to render. */
	snprintf(path, sizeof path, "%s/empty.gltf", dir);
	f = fopen(path, "w");
	fputs("{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{}], \"scenes\": [{\"nodes\": [0]}]}", f);
	fclose(f);
	assert_int_not_equal(scene_load(path, &s, err, sizeof err), 0);
	assert_non_null(strstr(err, "no triangle meshes"));
}

static void test_every_model_renders(void **state)
{
	(void)state;
	if (!have_shared())
		skip();
	static const char *models[] = {"AlphaBlendModeTest", "AnimatedCube", "BoxAnimated", "DamagedHelmet",
				       "InterpolationTest", "MetalRoughSpheresNoTextures"};
	vkdev *dev = NULL;
	char err[1024];
	vkdev_desc d = {.device = "lavapipe", .validation = true};
	if (vkdev_create(&d, &dev, err, sizeof err))
		fail_msg("%s", err);
	for (size_t i = 0; i < sizeof models / sizeof models[0]; i++) {
		scene *s = load(models[i]);
		render *r = NULL;
		render_desc rd = {.scene = s, .camera = 0, .width = 64, .height = 36};
		if (render_create(dev, &rd, &r, err, sizeof err))
			fail_msg("%s: %s", models[i], err);
		frame_image img;
		frame_stats st;
		if (render_frame(r, 30, &img, &st, err, sizeof err))
			fail_msg("%s: %s", models[i], err);
		if (st.visible_samples < 64 * 36 / 20)
			fail_msg("%s: only %lld visible samples: the default camera does not frame the model", models[i],
				 (long long)st.visible_samples);
		render_destroy(&r);
		scene_destroy(&s);
		if (vkdev_validation_messages(dev))
			fail_msg("%s: Vulkan validation messages", models[i]);
	}
	vkdev_destroy(&dev);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_interpolation_test), cmocka_unit_test(test_animated_cube),
		cmocka_unit_test(test_box_animated_hierarchy), cmocka_unit_test(test_broken_files),
		cmocka_unit_test(test_every_model_renders),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
