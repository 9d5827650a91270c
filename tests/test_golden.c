/* test_golden.c — rendered frames against golden PNGs in tests/golden/: three 96x54 ref frames of the turntable
 * rendered in-process, and frames 0..3 of every method in tests/golden/methods.txt (ref, tfr, rrc, tarc, sa, sau,
 * tasa and the oracles; turntable/orbit at 48x32) rendered by the command line.
 *
 * Tolerance: per channel |difference| <= 3 code values everywhere and mean |difference| <= 0.25.
 * On one machine the renderer is bit-exact (test_render checks that); the tolerance absorbs
 * lavapipe code generation differing between CPUs (LLVM picks other SIMD widths / FMA use), which
 * moves a few edge and highlight pixels by a code value or two. A shading change (a light, a BRDF
 * term, a shadow) moves thousands of pixels by much more.
 * The temporal methods decide reuse by thresholds, so a one-code-value shading difference on another CPU can flip a
 * decision; such a flip moves a few pixels by a few code values, within the same limits.
 * The test never writes goldens: scripts/update-goldens regenerates them (after an intended change; look at the new
 * images before committing them). A missing golden fails. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/imageio.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"
#include "test_util.h"
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

/* Max and mean |difference| per channel between two RGB8 images; fails over the limits. */
static void compare_rgb8(const char *what, const uint8_t *a, const uint8_t *b, size_t pixels)
{
	int max = 0;
	double sum = 0;
	for (size_t i = 0; i < pixels * 3; i++) {
		int dlt = abs((int)a[i] - (int)b[i]);
		max = dlt > max ? dlt : max;
		sum += dlt;
	}
	double mean = sum / ((double)pixels * 3.0);
	if (max)
		fprintf(stderr, "%s: max |diff| %d, mean %.4f\n", what, max, mean);
	if (max > MAX_ABS_DIFF || mean > MAX_MEAN_DIFF)
		fail_msg("%s: max |diff| %d (limit %d), mean |diff| %.4f (limit %.2f)", what, max, MAX_ABS_DIFF, mean,
			 MAX_MEAN_DIFF);
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
	uint32_t gw, gh;
	uint8_t *g = NULL;
	if (imageio_read_rgb8(path, &gw, &gh, &g, err, sizeof err))
		fail_msg("%s (scripts/update-goldens writes the goldens)", err);
	assert_int_equal(gw, W);
	assert_int_equal(gh, H);
	uint8_t rgb[W * H * 3];
	for (size_t i = 0; i < (size_t)W * H * 3; i++)
		rgb[i] = img.display_rgba[i / 3 * 4 + i % 3];
	render_destroy(&r);
	compare_rgb8(path, rgb, g, (size_t)W * H);
	free(g);
	assert_int_equal(vkdev_validation_messages(dev), 0);
}

/* Every method of tests/golden/methods.txt, rendered by the command line (validation on), frames 0..3 against its
 * goldens; the goldens folder holds exactly the listed methods (none left over from a removed line). Frame 3 of every
 * method differs from ref's (so its goldens tell it apart from ref) except ref's own and tarc@8's: at 48x32 tarc's
 * 72x72-pixel filter footprint covers the frame and it reshades everything (test_sweep_run says the same). */
static void test_methods(void **state)
{
	(void)state;
	char list[4096], line[512], cmd[8192], out[16384], err[1024], pa[4096], pb[4096];
	snprintf(list, sizeof list, "%s/tests/golden/methods.txt", TASLAB_SOURCE_DIR);
	FILE *f = fopen(list, "r");
	assert_non_null(f);
	const char *dir = tu_tmpdir("golden_methods");
	int methods = 0, differ_from_ref = 0;
	char folders[32][128];
	uint8_t *ref3 = NULL;
	while (fgets(line, sizeof line, f)) {
		char token[128], folder[128];
		if (line[0] == '#' || sscanf(line, "%127s %127s", token, folder) != 2)
			continue;
		assert_true(methods < 32);
		snprintf(folders[methods++], sizeof folders[0], "%s", folder);
		snprintf(cmd, sizeof cmd,
			 "%s render --scene turntable --camera orbit --size 48x32 --frames 0:4 --method %s --device " TASLAB_TEST_DEVICE " "
			 "--validation --no-exr --quiet --out %s/%s",
			 TASLAB_BINARY, token, dir, folder);
		if (tu_run(cmd, out, sizeof out))
			fail_msg("%s\n%s", cmd, out);
		for (int fr = 0; fr < 4; fr++) {
			uint32_t w, h, gw, gh;
			uint8_t *img = NULL, *g = NULL;
			snprintf(pa, sizeof pa, "%s/%s/frames/%06d.png", dir, folder, fr);
			snprintf(pb, sizeof pb, "%s/tests/golden/methods/%s/%06d.png", TASLAB_SOURCE_DIR, folder, fr);
			if (imageio_read_rgb8(pa, &w, &h, &img, err, sizeof err))
				fail_msg("%s", err);
			if (imageio_read_rgb8(pb, &gw, &gh, &g, err, sizeof err))
				fail_msg("%s (scripts/update-goldens writes the goldens)", err);
			assert_true(w == 48 && h == 32 && gw == w && gh == h);
			compare_rgb8(pb, img, g, (size_t)w * h);
			if (fr == 3 && !strcmp(token, "ref"))
				ref3 = img, img = NULL;
			else if (fr == 3 && ref3) {
				int d = memcmp(img, ref3, (size_t)w * h * 3) != 0;
				fprintf(stderr, "%s: frame 3 %s ref's\n", token, d ? "differs from" : "equals");
				differ_from_ref += d;
			}
			free(img);
			free(g);
		}
	}
	fclose(f);
	free(ref3);
	fprintf(stderr, "%d methods against their goldens; %d differ from ref at frame 3\n", methods, differ_from_ref);
	assert_true(methods >= 9);
	assert_int_equal(differ_from_ref, methods - 2);
	/* no golden folder without its line */
	snprintf(cmd, sizeof cmd, "ls %s/tests/golden/methods", TASLAB_SOURCE_DIR);
	assert_int_equal(tu_run(cmd, out, sizeof out), 0);
	for (char *save = NULL, *name = strtok_r(out, "\n", &save); name; name = strtok_r(NULL, "\n", &save)) {
		int listed = 0;
		for (int i = 0; i < methods && !listed; i++)
			listed = !strcmp(folders[i], name);
		if (!listed)
			fail_msg("tests/golden/methods/%s is not in tests/golden/methods.txt", name);
	}
}

static void test_orbit_start(void **state) { (void)state; check_golden("orbit", 0); }
static void test_orbit_mid(void **state) { (void)state; check_golden("orbit", 150); }
static void test_overview(void **state) { (void)state; check_golden("overview", 90); }

int main(void)
{
	/* The goldens are lavapipe's images: a GPU rasterizes and filters within the same rules but not bit for bit (H200:
	 * max 7 code values, one edge pixel 113, mean 0.35-0.41 against the 0.25 allowed). On another test device this
	 * test says so and is skipped (CI always renders on lavapipe). */
	if (!TU_ON_LAVAPIPE) {
		printf("SKIPPED: test_golden: the goldens are lavapipe's; the tests render on %s\n", TASLAB_TEST_DEVICE);
		return TU_SKIPPED;
	}
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_orbit_start), cmocka_unit_test(test_orbit_mid), cmocka_unit_test(test_overview),
		cmocka_unit_test(test_methods),
	};
	return cmocka_run_group_tests(tests, setup, teardown);
}
