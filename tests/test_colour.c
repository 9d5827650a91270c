/* test_colour.c — the OpenColorIO view transform: GPU (OCIO-generated GLSL, run on lavapipe) and CPU
 * (OCIO processor) agree over a dense set of linear inputs (HDR values and saturated colours) within GPU_CPU_TOL
 * code values on the 0-255 scale for analytic transforms (the default ACES transform, a user config) and within
 * GPU_CPU_LUT_TOL for a config of LUT files (tolerances and measurements below);
 * reference points of the default ACES transform; bad configs. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "taslab/colour_gpu.h"
#include "taslab/imageio.h"
#include "taslab/vkdev.h"
#include "test_util.h"
#include "test_vk.h"

/* Both sides compute in 32-bit float; the difference is rounding in the two compilations of the same maths (OCIO's
 * CPU ops vs its GLSL on lavapipe's LLVM). Measured max |GPU - CPU| (lavapipe, OCIO 2.1.2): ACES 0.00046 code values,
 * the user config's gamma 1.5e-5, the LUT views 1.5e-5 .. 4.6e-5. Tolerances: 10x the worst measurement of each kind
 * (the margin absorbs another CPU's vector widths and FMA use). A GPU output off by a relative 1e-4 (0.0255 code values
 * at white) fails both; the 0.5 code values allowed before hid anything up to a relative 2e-3. */
#define GPU_CPU_TOL 0.005
#define GPU_CPU_LUT_TOL 0.0005

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

/* GPU and CPU within `tol` code values over the input grid, no validation message. */
static void check_gpu_cpu_within(const char *config, const char *display, const char *view, double tol)
{
	char err[1024];
	colour *c = NULL;
	colour_desc cd = {.config_path = config, .display = display, .view = view, .ignore_env = 1};
	if (colour_create(&cd, &c, err, sizeof err))
		fail_msg("%s", err);
	vkdev *dev = NULL;
	vkdev_desc vd = {.device = TASLAB_TEST_DEVICE, .validation = true};
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
	fprintf(stderr, "%s: max |GPU - CPU| = %.3g code values over %zu inputs (worst at linear %g %g %g)\n",
		colour_name(c), worst, n, (double)in[at * 4], (double)in[at * 4 + 1], (double)in[at * 4 + 2]);
	free(in);
	if (!(worst <= tol))
		fail_msg("max |GPU - CPU| = %.3g code values, tolerance %g", worst, tol);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	free(cpu);
	free(gpu);
	vkdev_destroy(&dev);
	colour_destroy(&c);
}

static void check_gpu_cpu(const char *config, const char *display, const char *view)
{
	check_gpu_cpu_within(config, display, view, GPU_CPU_TOL);
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
	vkdev_desc vd = {.device = TASLAB_TEST_DEVICE, .validation = true};
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
	double worst = 0.0;
	for (size_t i = 0; i < total * 4; i++) {
		differ += memcmp(&a[i], &b[i], sizeof a[i]) != 0;
		double d = fabs((double)a[i] - (double)b[i]);
		worst = d > worst ? d : worst;
	}
	fprintf(stderr, "curve rewrite: %zu of %zu GPU values differ from OCIO's GLSL (max %.3g code values)\n", differ,
		total * 4, worst * 255.0);
	/* bit-identical on lavapipe; a GPU compiles the two shaders' arithmetic differently (FMA): within 0.001 code
	 * values, far below the 0.01 of GPU vs CPU that render_create checks */
	if (TU_ON_LAVAPIPE)
		assert_int_equal(differ, 0);
	else
		assert_true(worst * 255.0 <= 0.001);
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

/* A view built from LUT files (tests/data/ocio_lut: a 1D shaper, a 17^3 grade): its LUTs are read from a device buffer
 * instead of samplers (colour_gpu.c), with the filtering the samplers would have; GPU and CPU agree as for analytic
 * views, with linear, tetrahedral (OCIO's shader math on nearest lookups) and nearest interpolation, inputs beyond the
 * shaper's range and 0 included; no validation message. */
static void test_lut_config(void **state)
{
	(void)state;
	char path[4096], err[1024];
	snprintf(path, sizeof path, "%s/tests/data/ocio_lut/config.ocio", TASLAB_SOURCE_DIR);
	colour *c = NULL;
	colour_desc cd = {.config_path = path, .display = "sRGB", .view = "Graded", .ignore_env = 1};
	if (colour_create(&cd, &c, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(colour_lut_count(c), 2);
	const colour_lut *a = colour_lut_get(c, 0), *b = colour_lut_get(c, 1);
	assert_true(a->dims == 2 && a->channels == 1 && a->linear && a->width * a->height >= 4096); /* OCIO: 4096 x 2 */
	assert_true(b->dims == 3 && b->channels == 3 && b->linear && b->width == 17 && b->depth == 17);
	assert_non_null(strstr(colour_glsl(c), b->sampler));
	assert_null(colour_lut_get(c, 2));
	colour_destroy(&c);
	/* (a filtering mistake in the 1D shaper costs ~0.35 code values) */
	check_gpu_cpu_within(path, "sRGB", "Graded", GPU_CPU_LUT_TOL);
	check_gpu_cpu_within(path, "sRGB", "Tetrahedral", GPU_CPU_LUT_TOL);
	check_gpu_cpu_within(path, "sRGB", "Nearest", GPU_CPU_LUT_TOL);
	/* a 1024-entry RGB shaper: a sampler1D of three channels */
	cd.view = "ShaperRGB";
	if (colour_create(&cd, &c, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(colour_lut_count(c), 1);
	a = colour_lut_get(c, 0);
	assert_true(a->dims == 1 && a->channels == 3 && a->width == 1024 && a->height == 1);
	colour_destroy(&c);
	check_gpu_cpu_within(path, "sRGB", "ShaperRGB", GPU_CPU_LUT_TOL);
	/* The frame pipeline with that view, validation on: every shader that includes the transform (display, the
	 * reprojection passes of tarc, the atlas shading of tasa) compiles and runs; ref's PNGs are within 1 code value
	 * of the CPU transform of its EXRs (taslab tonemap; measured: equal). */
	const char *dir = tu_tmpdir("colour_lut_render");
	const char *methods[] = {"ref", "tarc@8", "tasa@8"};
	char cmd[8192], out[16384];
	for (size_t i = 0; i < 3; i++) {
		snprintf(cmd, sizeof cmd,
			 "%s render --scene calm --camera walk --size 96x54 --frames 0:3 --method %s --ocio-config %s "
			 "--view Graded --validation --quiet --out %s/r%zu",
			 TASLAB_BINARY, methods[i], path, dir, i);
		if (tu_run(cmd, out, sizeof out))
			fail_msg("%s\n%s", cmd, out);
	}
	snprintf(cmd, sizeof cmd, "%s tonemap %s/r0 --ocio-config %s --view Graded --out %s/cpu", TASLAB_BINARY, dir, path, dir);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s\n%s", cmd, out);
	for (int f = 0; f < 3; f++) {
		char pa[4096], pb[4096];
		snprintf(pa, sizeof pa, "%s/r0/frames/%06d.png", dir, f);
		snprintf(pb, sizeof pb, "%s/cpu/%06d.png", dir, f);
		uint32_t wa, ha, wb, hb;
		uint8_t *ia = NULL, *ib = NULL;
		if (imageio_read_rgb8(pa, &wa, &ha, &ia, err, sizeof err) ||
		    imageio_read_rgb8(pb, &wb, &hb, &ib, err, sizeof err))
			fail_msg("%s", err);
		assert_true(wa == wb && ha == hb);
		int worst = 0;
		for (size_t k = 0; k < (size_t)wa * ha * 3; k++)
			worst = abs(ia[k] - ib[k]) > worst ? abs(ia[k] - ib[k]) : worst;
		free(ia);
		free(ib);
		if (worst > 1)
			fail_msg("frame %d: GPU and CPU transforms %d code values apart", f, worst);
	}
}

/* Writes `src` (a file of tests/data/ocio_lut) into `dir`, with its line `line` (1-based) replaced by `repl` when
 * repl is not NULL. */
static void copy_lut_file(const char *dir, const char *name, int line, const char *repl)
{
	char src[4096], dst[4096];
	snprintf(src, sizeof src, "%s/tests/data/ocio_lut/%s", TASLAB_SOURCE_DIR, name);
	snprintf(dst, sizeof dst, "%s/%s", dir, name);
	char *text = tu_read_file(src, NULL);
	assert_non_null(text);
	FILE *f = fopen(dst, "w");
	assert_non_null(f);
	int n = 1;
	for (char *p = text; *p;) {
		char *nl = strchr(p, '\n');
		size_t len = nl ? (size_t)(nl - p) + 1 : strlen(p);
		if (n++ == line && repl)
			fprintf(f, "%s\n", repl);
		else
			fwrite(p, 1, len, f);
		p += len;
	}
	fclose(f);
	free(text);
}

/* Issue 31.7: a LUT with a NaN or Inf entry is refused with one line naming the entry (OCIO's readers accept them,
 * and its GPU and CPU paths then differed by up to 148 code values on 41 % of the pixels); `taslab render` with such
 * a config exits 2 without a run. The message names the file. The same config with finite values passes the GPU = CPU check that render_create
 * runs on every user config (colour_check_gpu; the LUT views are within 0.01 code values, test_lut_config). */
static void test_lut_nonfinite(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("colour_nonfinite");
	char cfg[4096], err[1024], cmd[8192], out[8192], run[4200];
	snprintf(cfg, sizeof cfg, "%s/config.ocio", dir);
	/* line 6 of shaper.spi1d is its first value (after 5 lines of header); line 12 of grade.cube is its entry 7 (after
	 * 4 lines of header; red varies fastest in a .cube) */
	static const struct {
		const char *file;
		int line;
		const char *value, *want, *why;
	} cases[] = {
		{"shaper.spi1d", 6, "nan", "shaper.spi1d: a value of this LUT", "not a finite number"},
		{"shaper.spi1d", 300, "inf", "shaper.spi1d: a value of this LUT", "not a finite number"},
		{"grade.cube", 12, "0.5 nan 0.5", "grade.cube: a value of this LUT", "not a finite number"},
		{"grade.cube", 12, "0.5 0.5 -inf", "grade.cube: a value of this LUT", "not a finite number"},
		/* issue 31 (fuzz_lut): a .cube size OpenColorIO 2.1 would allocate before reading an entry (600^3: 2.6 GB),
		 * refused before OCIO reads the file: outside the Cube spec, or more entries than the file can hold */
		{"grade.cube", 2, "LUT_3D_SIZE 600", "grade.cube: LUT_3D_SIZE must be 2 to 256", "Cube LUT Specification"},
		{"grade.cube", 2, "LUT_3D_SIZE 200", "grade.cube: declares 8000000 entries", "bytes can hold"},
		/* the fuzzer's case: OCIO reads the keyword in any case */
		{"grade.cube", 2, "lut_3d_SIZe 600", "grade.cube: LUT_3D_SIZE must be 2 to 256", "Cube LUT Specification"},
		{"grade.cube", 2, "LUT_1D_SIZE 4000000000", "grade.cube: LUT_1D_SIZE must be 2 to 65536", "Cube LUT"},
	};
	for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
		/* a folder per case: OpenColorIO caches LUT files by path for the life of the process */
		char sub[4200];
		snprintf(sub, sizeof sub, "%s/%zu", dir, i);
		assert_int_equal(mkdir(sub, 0755), 0);
		snprintf(cfg, sizeof cfg, "%s/config.ocio", sub);
		copy_lut_file(sub, "config.ocio", 0, NULL);
		copy_lut_file(sub, "shaper.spi1d", cases[i].line, !strcmp(cases[i].file, "shaper.spi1d") ? cases[i].value : NULL);
		copy_lut_file(sub, "grade.cube", cases[i].line, !strcmp(cases[i].file, "grade.cube") ? cases[i].value : NULL);
		colour *c = NULL;
		colour_desc cd = {.config_path = cfg, .display = "sRGB", .view = "Graded", .ignore_env = 1};
		if (!colour_create(&cd, &c, err, sizeof err))
			fail_msg("%s line %d = '%s' was accepted", cases[i].file, cases[i].line, cases[i].value);
		if (!strstr(err, cases[i].why) || !strstr(err, cases[i].want) || strchr(err, '\n'))
			fail_msg("%s line %d = '%s': message '%s'", cases[i].file, cases[i].line, cases[i].value, err);
		assert_null(c);
	}
	/* the command line: exit 2, one line, no run folder (the last case's config) */
	snprintf(run, sizeof run, "%s/run", dir);
	snprintf(cmd, sizeof cmd,
		 "%s render --scene calm --camera walk --size 32x18 --frames 0:1 --method ref --ocio-config %s --view Graded "
		 "--quiet --out %s",
		 TASLAB_BINARY, cfg, run);
	int st = tu_run(cmd, out, sizeof out);
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, cases[sizeof cases / sizeof *cases - 1].why))
		fail_msg("%s: exit %d:\n%s", cmd, st, out);
	assert_false(tu_file_exists(run));
	/* finite values (a new folder, for the cache): the check passes, and the render runs */
	char good[4200];
	snprintf(good, sizeof good, "%s/good", dir);
	assert_int_equal(mkdir(good, 0755), 0);
	copy_lut_file(good, "config.ocio", 0, NULL);
	copy_lut_file(good, "shaper.spi1d", 0, NULL);
	copy_lut_file(good, "grade.cube", 0, NULL);
	snprintf(cfg, sizeof cfg, "%s/config.ocio", good);
	snprintf(cmd, sizeof cmd,
		 "%s render --scene calm --camera walk --size 32x18 --frames 0:1 --method ref --ocio-config %s --view Graded "
		 "--quiet --out %s",
		 TASLAB_BINARY, cfg, run);
	colour *c = NULL;
	colour_desc cd = {.config_path = cfg, .display = "sRGB", .view = "Graded", .ignore_env = 1};
	if (colour_create(&cd, &c, err, sizeof err))
		fail_msg("%s", err);
	vkdev *dev = NULL;
	vkdev_desc vd = {.device = TASLAB_TEST_DEVICE, .validation = true};
	if (vkdev_create(&vd, &dev, err, sizeof err))
		fail_msg("%s", err);
	double worst = -1;
	if (colour_check_gpu(dev, c, &worst, err, sizeof err))
		fail_msg("%s", err);
	assert_true(worst >= 0 && worst <= 0.01);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	vkdev_destroy(&dev);
	colour_destroy(&c);
	if ((st = tu_run(cmd, out, sizeof out)))
		fail_msg("%s: exit %d:\n%s", cmd, st, out);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_default_gpu_matches_cpu), cmocka_unit_test(test_glsl_rewrite_bit_identical),
		cmocka_unit_test(test_default_reference_points),
		cmocka_unit_test(test_user_config),       cmocka_unit_test(test_lut_config),
		cmocka_unit_test(test_lut_nonfinite),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
