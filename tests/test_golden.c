/* test_golden.c — reference frames against golden PNGs in tests/golden/.
 *
 * Tolerance: per channel |difference| <= 3 code values everywhere and mean |difference| <= 0.25.
 * On one machine the renderer is bit-exact (test_render checks that); the tolerance absorbs
 * lavapipe code generation differing between CPUs (LLVM picks other SIMD widths / FMA use), which
 * moves a few edge and highlight pixels by a code value or two. A shading change (a light, a BRDF
 * term, a shadow) moves thousands of pixels by much more.
 * Regenerate after an intended change: TASLAB_REGEN_GOLDENS=1 ctest --test-dir build-test -R golden
 * (or scripts/regen-goldens), then look at the new images before committing them. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/imageio.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"
#include "test_vk.h"

#define W 96
#define H 54
#define MAX_ABS_DIFF 3
#define MAX_MEAN_DIFF 0.25

static scene *scn;
static vkdev *dev;

static int setup(void **state)
{
	(void)state;
	return tu_open_scene_and_device("turntable", &scn, &dev);
}

static int teardown(void **state)
{
	(void)state;
	return tu_close_scene_and_device(&scn, &dev);
}

static void check_golden(const char *camera, uint32_t frame)
{
	char err[1024], path[4096];
	int cam = scene_find_camera(scn, camera);
	assert_true(cam >= 0);
	render *r = NULL;
	render_desc d = {.scene = scn, .camera = cam, .width = W, .height = H};
	if (render_create(dev, &d, &r, err, sizeof err))
		fail_msg("%s", err);
	frame_image img;
	frame_stats st;
	if (render_frame(r, frame, &img, &st, err, sizeof err))
		fail_msg("%s", err);
	snprintf(path, sizeof path, "%s/tests/golden/turntable_%s_%06u_%ux%u.png", TASLAB_SOURCE_DIR, camera, frame, W, H);
	const char *regen = getenv("TASLAB_REGEN_GOLDENS");
	if (regen && *regen && strcmp(regen, "0")) {
		if (imageio_write_png_rgb8(path, W, H, img.display_rgba, err, sizeof err))
			fail_msg("%s", err);
		fprintf(stderr, "regenerated %s\n", path);
		render_destroy(&r);
		return;
	}
	uint32_t gw, gh;
	uint8_t *g = NULL;
	if (imageio_read_rgb8(path, &gw, &gh, &g, err, sizeof err))
		fail_msg("%s (regenerate with TASLAB_REGEN_GOLDENS=1)", err);
	assert_int_equal(gw, W);
	assert_int_equal(gh, H);
	int max = 0;
	double sum = 0;
	for (size_t i = 0; i < (size_t)W * H; i++)
		for (int c = 0; c < 3; c++) {
			int dlt = abs((int)img.display_rgba[i * 4 + c] - (int)g[i * 3 + c]);
			max = dlt > max ? dlt : max;
			sum += dlt;
		}
	double mean = sum / (W * H * 3.0);
	free(g);
	render_destroy(&r);
	if (max > MAX_ABS_DIFF || mean > MAX_MEAN_DIFF)
		fail_msg("%s: max |diff| %d (limit %d), mean |diff| %.4f (limit %.2f)", path, max, MAX_ABS_DIFF, mean,
			 MAX_MEAN_DIFF);
	assert_int_equal(vkdev_validation_messages(dev), 0);
}

static void test_orbit_start(void **state) { (void)state; check_golden("orbit", 0); }
static void test_orbit_mid(void **state) { (void)state; check_golden("orbit", 150); }
static void test_overview(void **state) { (void)state; check_golden("overview", 90); }

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_orbit_start), cmocka_unit_test(test_orbit_mid), cmocka_unit_test(test_overview),
	};
	return cmocka_run_group_tests(tests, setup, teardown);
}
