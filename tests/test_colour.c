/* test_colour.c — the OpenColorIO view transform: GPU (OCIO-generated GLSL, run on lavapipe) and CPU
 * (OCIO processor) agree within 0.5 code value on the 0-255 scale over a dense set of linear inputs
 * (HDR values and saturated colours); reference points of the default ACES transform; bad configs. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/colour_gpu.h"
#include "taslab/vkdev.h"
#include "test_vk.h"

/* 28 levels per channel: 0, then 1e-4 .. 64 log-spaced (HDR up to 6 stops over 1.0). */
#define LEVELS 28

static size_t make_inputs(float **out)
{
	size_t n = (size_t)LEVELS * LEVELS * LEVELS;
	float *px = malloc(n * 4 * sizeof *px), lv[LEVELS];
	lv[0] = 0.0f;
	for (int i = 1; i < LEVELS; i++)
		lv[i] = 1e-4f * powf(64.0f / 1e-4f, (float)(i - 1) / (LEVELS - 2));
	size_t k = 0;
	for (int r = 0; r < LEVELS; r++)
		for (int g = 0; g < LEVELS; g++)
			for (int b = 0; b < LEVELS; b++, k++) {
				px[k * 4 + 0] = lv[r];
				px[k * 4 + 1] = lv[g];
				px[k * 4 + 2] = lv[b];
				px[k * 4 + 3] = 1.0f;
			}
	*out = px;
	return n;
}

static void check_gpu_cpu(const char *config, const char *display, const char *view)
{
	char err[1024];
	colour *c = NULL;
	colour_desc cd = {.config_path = config, .display = display, .view = view, .ignore_env = 1};
	if (colour_create(&cd, &c, err, sizeof err))
		fail_msg("%s", err);
	vkdev *dev = NULL;
	vkdev_desc vd = {.device = "lavapipe", .validation = true};
	if (vkdev_create(&vd, &dev, err, sizeof err))
		fail_msg("%s", err);
	float *cpu, *gpu, *in;
	size_t n = make_inputs(&cpu);
	make_inputs(&gpu);
	make_inputs(&in);
	colour_apply(c, cpu, n, 4);
	if (colour_apply_gpu(dev, c, gpu, n, err, sizeof err))
		fail_msg("%s", err);
	double worst = 0;
	size_t at = 0;
	for (size_t i = 0; i < n * 4; i++) {
		if (i % 4 == 3)
			continue;
		/* Compare what reaches the display: both clamped to [0, 1], on the 0-255 scale. */
		double a = fmin(fmax(cpu[i], 0.0), 1.0) * 255.0, b = fmin(fmax(gpu[i], 0.0), 1.0) * 255.0;
		if (fabs(a - b) > worst) {
			worst = fabs(a - b);
			at = i / 4;
		}
	}
	fprintf(stderr, "%s: max |GPU - CPU| = %.4f code values over %zu inputs (worst at linear %g %g %g)\n",
		colour_name(c), worst, n, (double)in[at * 4], (double)in[at * 4 + 1], (double)in[at * 4 + 2]);
	free(in);
	assert_true(worst <= 0.5);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	free(cpu);
	free(gpu);
	vkdev_destroy(&dev);
	colour_destroy(&c);
}

static void test_default_gpu_matches_cpu(void **state)
{
	(void)state;
	check_gpu_cpu(NULL, NULL, NULL);
}

/* The restructured curve functions (colour.cpp) compute bit-identical values to OCIO's GLSL as emitted, on
 * the device, over the HDR/saturated grid and a dense ramp of every channel; and the rewrite happened. */
static void test_glsl_rewrite_bit_identical(void **state)
{
	(void)state;
	char err[1024];
	colour *fast = NULL, *orig = NULL;
	colour_desc cd = {.ignore_env = 1}, co = {.ignore_env = 1, .keep_ocio_glsl = 1};
	if (colour_create(&cd, &fast, err, sizeof err) || colour_create(&co, &orig, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(colour_glsl_rewritten(fast), 2); /* the ACES RRT and ODT tone scales */
	assert_int_equal(colour_glsl_rewritten(orig), 0);
	assert_string_not_equal(colour_glsl(fast), colour_glsl(orig));
	vkdev *dev = NULL;
	vkdev_desc vd = {.device = "lavapipe", .validation = true};
	if (vkdev_create(&vd, &dev, err, sizeof err))
		fail_msg("%s", err);
	float *a, *b;
	size_t n = make_inputs(&a);
	make_inputs(&b);
	/* plus a ramp 0 .. 2^10 in 1/64-stop steps on each channel, so every knot interval is crossed */
	size_t ramp = 64 * 24, total = n + ramp;
	a = realloc(a, total * 16);
	b = realloc(b, total * 16);
	for (size_t i = 0; i < ramp; i++)
		for (int c = 0; c < 4; c++)
			a[(n + i) * 4 + c] = b[(n + i) * 4 + c] = c == 3 ? 1.0f : c == (int)(i % 3) ? exp2f(-14.0f + (float)i / 64.0f) : 0.18f;
	if (colour_apply_gpu(dev, fast, a, total, err, sizeof err) || colour_apply_gpu(dev, orig, b, total, err, sizeof err))
		fail_msg("%s", err);
	size_t differ = 0;
	for (size_t i = 0; i < total * 4; i++)
		differ += memcmp(&a[i], &b[i], sizeof a[i]) != 0;
	fprintf(stderr, "curve rewrite: %zu of %zu GPU values differ from OCIO's GLSL\n", differ, total * 4);
	assert_int_equal(differ, 0);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	free(a);
	free(b);
	vkdev_destroy(&dev);
	colour_destroy(&fast);
	colour_destroy(&orig);
}

static void test_default_reference_points(void **state)
{
	(void)state;
	char err[1024];
	colour *c = NULL;
	colour_desc cd = {.ignore_env = 1};
	if (colour_create(&cd, &c, err, sizeof err))
		fail_msg("%s", err);
	/* ACES 1.0 SDR-video + sRGB: black stays black; scene grey 0.18 maps to ~0.356 (the RRT+ODT mid grey,
	 * cf. OCIO's ACES 1.0.3 config "sRGB" view: 0.18 -> 0.3559 within 1e-3); values far above white clip
	 * to ~1; the curve is monotonic along the grey axis. */
	float px[5 * 3] = {0, 0, 0, 0.18f, 0.18f, 0.18f, 1, 1, 1, 100, 100, 100, 0.5f, 0.5f, 0.5f};
	colour_apply(c, px, 5, 3);
	assert_float_equal(px[0], 0.0, 1e-4);
	assert_float_equal(px[3], 0.3559, 1e-3);
	assert_true(px[6] > px[12] && px[12] > px[3]);
	assert_true(px[9] > 0.99f);
	assert_non_null(strstr(colour_name(c), "ACES"));
	assert_non_null(strstr(colour_glsl(c), "ocio_display"));
	colour_destroy(&c);
}

static const char *CONFIG =
	"ocio_profile_version: 2\n"
	"roles:\n  scene_linear: lin\n  default: lin\n"
	"displays:\n  sRGB:\n    - !<View> {name: Gamma22, colorspace: g22}\n    - !<View> {name: Raw, colorspace: lin}\n"
	"colorspaces:\n"
	"  - !<ColorSpace> {name: lin}\n"
	"  - !<ColorSpace> {name: g22, from_scene_reference: !<ExponentTransform> {value: 2.2, direction: inverse}}\n";

static void test_user_config(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("colour_cfg");
	char path[4096], err[1024];
	snprintf(path, sizeof path, "%s/test.ocio", dir);
	FILE *f = fopen(path, "w");
	fputs(CONFIG, f);
	fclose(f);
	check_gpu_cpu(path, "sRGB", "Gamma22");
	colour *c = NULL;
	colour_desc cd = {.config_path = path, .display = "sRGB", .view = "Gamma22", .ignore_env = 1};
	assert_int_equal(colour_create(&cd, &c, err, sizeof err), 0);
	float px[3] = {0.5f, 0.25f, 1.0f};
	colour_apply(c, px, 1, 3); /* x^(1/2.2) */
	assert_float_equal(px[0], pow(0.5, 1 / 2.2), 1e-5);
	assert_float_equal(px[1], pow(0.25, 1 / 2.2), 1e-5);
	colour_destroy(&c);
	/* Unknown display / view and a missing config: clear, one-line errors listing what exists. */
	cd.display = "Projector";
	assert_int_not_equal(colour_create(&cd, &c, err, sizeof err), 0);
	assert_non_null(strstr(err, "Projector"));
	assert_non_null(strstr(err, "sRGB"));
	cd.display = "sRGB";
	cd.view = "Filmic";
	assert_int_not_equal(colour_create(&cd, &c, err, sizeof err), 0);
	assert_non_null(strstr(err, "Gamma22, Raw"));
	cd.config_path = "/nonexistent/config.ocio";
	assert_int_not_equal(colour_create(&cd, &c, err, sizeof err), 0);
	assert_null(strchr(err, '\n'));
	colour_desc nocfg = {.view = "Raw", .ignore_env = 1};
	assert_int_not_equal(colour_create(&nocfg, &c, err, sizeof err), 0);
	assert_non_null(strstr(err, "--ocio-config"));
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_default_gpu_matches_cpu), cmocka_unit_test(test_glsl_rewrite_bit_identical),
		cmocka_unit_test(test_default_reference_points),
		cmocka_unit_test(test_user_config),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
