/* test_output.c — the file formats of output/: run folder writer and reader (manifest, stats.csv, frames
 * checked against the manifest), a re-used run folder holding exactly its run, pairs.json round trip and
 * its refusals, frame numbers >= 2^31 (test_large_frame_numbers), PNG reading and writing (colours as stored,
 * no library output, full disk; test_png_io). */
#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "taslab/imageio.h"
#include "taslab/pairs.h"
#include "taslab/run.h"
#include "taslab/tl_fs.h"
#include "test_util.h"

#define W 8
#define H 4

static uint16_t hdr[W * H * 4];
static uint8_t disp[W * H * 4];
static uint8_t decisions[W * H];
static bool with_decisions; /* write_run: also decision maps */

/* Writes a run of frames [first, first + n) with fake pixels and stats. */
static void write_run(const char *dir, uint32_t first, uint32_t n, bool png, bool exr)
{
	char err[1024];
	run_option opts[3] = {{.key = "threshold", .type = RUN_VALUE_NUMBER, .number = 8},
			      {.key = "oracle", .type = RUN_VALUE_BOOL, .boolean = true},
			      {.key = "max-age", .type = RUN_VALUE_INTEGER, .number = 7}};
	run_option derived[1] = {{.key = "atlas_width", .type = RUN_VALUE_INTEGER, .number = 256}};
	run_info info = {.scene_name = "s", .scene_path = "s.json", .camera = "c", .camera_motion = "moving",
			 .device = "dev", .driver = "drv", .method = "tarc-oracle", .variant = "tarc-oracle@8",
			 .threshold = 8, .options = opts, .option_count = 3, .derived = derived, .derived_count = 1,
			 .facts = {.known = true, .family = "reprojection", .baseline = "ref", .takes_threshold = true},
			 .ocio_version = "2.1.2", .vulkan_api = "1.3.230", .first_frame = first,
			 .last_frame = first + n - 1, .width = W, .height = H, .fps = 30, .write_exr = exr, .write_png = png,
			 .write_decisions = with_decisions};
	run_writer *w = NULL;
	if (run_writer_create(dir, &info, &w, err, sizeof err))
		fail_msg("%s", err);
	for (uint32_t k = 0; k < n; k++) {
		uint32_t f = first + k; /* first + n may wrap: the last frame number is 2^32 - 1 */
		frame_stats st = {.frame = f, .time_s = f / 30.0, .visible_samples = 20, .shaded_samples = 5, .reused_samples = 15,
				  .allocated_samples = -1, .late_samples = -1, .visible_units = 20, .shaded_units = 5,
				  .new_units = 1, .fs_invocations = -1, .cs_invocations = -1, .gpu_ms_total = 1.5,
				  .pass_count = 1, .pass_names = {"shade"}, .gpu_ms = {1.25}, .extra_count = 1,
				  .extra_names = {"cpu_ms_alloc"}, .extra = {NAN}};
		frame_image img = {W, H, hdr, disp, with_decisions ? decisions : NULL, NULL, 0, 0};
		for (int i = 0; i < W * H; i++)
			decisions[i] = (uint8_t)((i + f) % FRAME_DECISION_COUNT);
		memset(disp, (int)(f * 10), sizeof disp);
		if (run_writer_frame(w, &img, &st, err, sizeof err))
			fail_msg("%s", err);
	}
	if (run_writer_finish(w, 2.0, err, sizeof err))
		fail_msg("%s", err);
	run_writer_destroy(&w);
}

static void test_run_round_trip(void **state)
{
	(void)state;
	char err[1024];
	const char *d = tu_tmpdir("output_run");
	write_run(d, 10, 3, true, true);
	run_manifest m;
	assert_int_equal(run_manifest_read(d, &m, err, sizeof err), TL_OK);
	assert_string_equal(m.method, "tarc-oracle");
	assert_string_equal(m.variant, "tarc-oracle@8");
	assert_string_equal(m.camera_motion, "moving");
	assert_true(m.threshold == 8 && m.period == 0 && m.fps == 30);
	assert_true(m.first_frame == 10 && m.last_frame == 12 && m.width == W && m.height == H);
	assert_int_equal(m.frames, 3);
	/* what metrics and studies need to know of the method (issue 30.1) */
	assert_true(m.facts.known && m.facts.takes_threshold && !m.facts.takes_period && !m.facts.reference);
	assert_string_equal(m.facts.family, "reprojection");
	assert_string_equal(m.facts.baseline, "ref");
	assert_int_equal(run_check_frames(d, &m, "png", err, sizeof err), TL_OK);
	assert_int_equal(run_check_frames(d, &m, "exr", err, sizeof err), TL_OK);
	run_stats st;
	assert_int_equal(run_stats_read(d, &st, err, sizeof err), TL_OK);
	assert_int_equal(st.rows, 3);
	assert_true(run_stats_get(&st, 1, "frame") == 11);
	assert_true(fabs(run_stats_get(&st, 0, "reuse_fraction") - 0.75) < 1e-9); /* 1 - 5/20 */
	assert_true(run_stats_get(&st, 0, "gpu_ms_shade") == 1.25);
	assert_true(isnan(run_stats_get(&st, 0, "fs_invocations"))); /* empty cell */
	assert_true(isnan(run_stats_get(&st, 0, "cpu_ms_alloc")));
	assert_int_equal(run_stats_col(&st, "no_such_column"), -1);
	run_stats_free(&st);
	/* the method options reach the manifest */
	char p[4096];
	snprintf(p, sizeof p, "%s/manifest.json", d);
	char *text = tu_read_file(p, NULL);
	assert_non_null(strstr(text, "\"method_options\""));
	assert_non_null(strstr(text, "\"oracle\": true"));
	/* integer options and sizes are JSON integers, real-valued ones stay reals (issue 24.8) */
	assert_non_null(strstr(text, "\"max-age\": 7,\n")); /* keys sorted: max-age, oracle, threshold */
	assert_non_null(strstr(text, "\"threshold\": 8.0"));
	assert_non_null(strstr(text, "\"method_facts\": {\n      \"baseline\": \"ref\",\n      \"family\": \"reprojection\",\n"
				     "      \"reference\": false,\n      \"takes_period\": false,\n      \"takes_threshold\": true\n"));
	/* what the method derived, and the versions (DESIGN section 5) */
	assert_non_null(strstr(text, "\"method_derived\": {\n      \"atlas_width\": 256\n"));
	assert_non_null(strstr(text, "\"opencolorio\": \"2.1.2\""));
	assert_non_null(strstr(text, "\"vulkan_api\": \"1.3.230\""));
	assert_non_null(strstr(text, "\"vulkan_driver\": \"drv\""));
	free(text);
}

/* render --decisions: RUN/decisions/NNNNNN.png in the documented colours, decoded back exactly; a re-run
 * without them leaves none of the old maps. */
static void test_decision_maps(void **state)
{
	(void)state;
	char err[1024], p[4096];
	const char *d = tu_tmpdir("output_decisions");
	with_decisions = true;
	write_run(d, 3, 2, true, false);
	with_decisions = false;
	for (uint32_t f = 3; f < 5; f++) {
		snprintf(p, sizeof p, "%s/decisions/%06u.png", d, f);
		uint32_t w, h;
		uint8_t *rgb = NULL;
		if (imageio_read_rgb8(p, &w, &h, &rgb, err, sizeof err))
			fail_msg("%s", err);
		assert_true(w == W && h == H);
		for (int i = 0; i < W * H; i++)
			assert_int_equal(run_decision_code(rgb + i * 3), (int)((i + f) % FRAME_DECISION_COUNT));
		free(rgb);
	}
	const uint8_t other[3] = {1, 2, 3};
	assert_int_equal(run_decision_code(other), -1);
	snprintf(p, sizeof p, "%s/manifest.json", d);
	char *text = tu_read_file(p, NULL);
	assert_non_null(strstr(text, "\"decisions\": true"));
	free(text);
	write_run(d, 3, 1, true, false);
	snprintf(p, sizeof p, "%s/decisions/000003.png", d);
	assert_false(tu_file_exists(p));
}

static void test_run_folder_reuse(void **state)
{
	(void)state;
	char err[1024], p[4096];
	const char *d = tu_tmpdir("output_reuse");
	write_run(d, 0, 5, true, true);
	snprintf(p, sizeof p, "%s/frames/.000001.png.tmp.Zz9Yy8", d); /* left by a killed writer */
	fclose(fopen(p, "w"));
	/* A shorter re-render without PNGs: no frame of the old run may remain. */
	write_run(d, 0, 2, false, true);
	snprintf(p, sizeof p, "%s/frames/000004.exr", d);
	assert_false(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/frames/000000.png", d);
	assert_false(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/frames/.000001.png.tmp.Zz9Yy8", d);
	assert_false(tu_file_exists(p));
	run_manifest m;
	assert_int_equal(run_manifest_read(d, &m, err, sizeof err), TL_OK);
	assert_int_equal(run_check_frames(d, &m, "png", err, sizeof err), TL_ERR_INPUT);
	assert_non_null(strstr(err, "--no-png"));
	/* A frame outside the manifest's range, or a missing one, is named. */
	snprintf(p, sizeof p, "%s/frames/000007.exr", d);
	fclose(fopen(p, "w"));
	assert_int_equal(run_check_frames(d, &m, "exr", err, sizeof err), TL_ERR_INPUT);
	assert_non_null(strstr(err, "000007.exr"));
	remove(p);
	snprintf(p, sizeof p, "%s/frames/000001.exr", d);
	remove(p);
	assert_int_equal(run_check_frames(d, &m, "exr", err, sizeof err), TL_ERR_INPUT);
	assert_non_null(strstr(err, "000001.exr is missing"));
}

static void test_run_bad_input(void **state)
{
	(void)state;
	char err[1024], p[4096];
	const char *d = tu_tmpdir("output_bad");
	run_manifest m;
	assert_int_equal(run_manifest_read(d, &m, err, sizeof err), TL_ERR_INPUT);
	assert_non_null(strstr(err, "not a complete run"));
	const char *bad[] = {
		"{}",
		"{\"inputs\": {\"method\": \"ref\", \"frames\": [5, 2], \"size\": [8, 4], \"fps\": 30}}",
		"{\"inputs\": {\"method\": \"ref\", \"frames\": [0, 2], \"size\": [0, 4], \"fps\": 30}}",
		"{\"inputs\": {\"method\": \"ref\", \"frames\": [0, 4294967296], \"size\": [8, 4], \"fps\": 30}}",
		"not json",
	};
	snprintf(p, sizeof p, "%s/manifest.json", d);
	for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
		FILE *f = fopen(p, "w");
		fputs(bad[i], f);
		fclose(f);
		assert_int_equal(run_manifest_read(d, &m, err, sizeof err), TL_ERR_INPUT);
		assert_null(strchr(err, '\n'));
	}
	/* stats.csv: short rows, non-numbers, empty */
	const char *bad_stats[] = {"", "a,b\n1\n", "a,b\n1,x\n", "a,b\n1,2,3\n"};
	snprintf(p, sizeof p, "%s/stats.csv", d);
	for (size_t i = 0; i < sizeof bad_stats / sizeof bad_stats[0]; i++) {
		FILE *f = fopen(p, "w");
		fputs(bad_stats[i], f);
		fclose(f);
		run_stats st;
		assert_int_equal(run_stats_read(d, &st, err, sizeof err), TL_ERR_INPUT);
	}
}

/* Issue 12: frame numbers are uint32_t everywhere; the manifest held frames >= 2^31 as negative numbers (the
 * run then was "impossible" to clip or compare). */
static void test_large_frame_numbers(void **state)
{
	(void)state;
	char err[1024], p[4096];
	const char *d = tu_tmpdir("output_big_frames");
	write_run(d, 2147483648u + 5, 2, true, false);
	snprintf(p, sizeof p, "%s/manifest.json", d);
	char *text = tu_read_file(p, NULL);
	assert_non_null(strstr(text, "2147483653"));
	assert_null(strstr(text, "-2147"));
	free(text);
	run_manifest m;
	if (run_manifest_read(d, &m, err, sizeof err))
		fail_msg("%s", err);
	assert_true(m.first_frame == 2147483653u && m.last_frame == 2147483654u);
	assert_int_equal(run_check_frames(d, &m, "png", err, sizeof err), TL_OK);
	/* The largest frame number. */
	write_run(d, 4294967295u, 1, true, false);
	assert_int_equal(run_manifest_read(d, &m, err, sizeof err), TL_OK);
	assert_true(m.first_frame == 4294967295u && m.last_frame == 4294967295u);
	if (run_check_frames(d, &m, "png", err, sizeof err))
		fail_msg("%s", err);
}

/* A PNG written by libpng directly, in the colour type and bit depth given (the reader must not depend on our
 * writer's choices). `px` holds `channels` samples per pixel of `depth` bits (16-bit big-endian). */
static void raw_png(const char *path, int w, int h, int type, int depth, const uint8_t *px, int channels)
{
	FILE *f = fopen(path, "wb");
	png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
	png_infop info = png_create_info_struct(png);
	png_init_io(png, f);
	png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, depth, type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
		     PNG_FILTER_TYPE_DEFAULT);
	png_write_info(png, info);
	for (int y = 0; y < h; y++)
		png_write_row(png, (png_const_bytep)(px + (size_t)y * w * channels * (depth / 8)));
	png_write_end(png, info);
	png_destroy_write_struct(&png, &info);
	fclose(f);
}

/* Runs f(arg) with stderr sent to a file; returns what was printed there (caller frees). */
static char *stderr_of(void (*fn)(void *), void *arg, const char *dir)
{
	char p[4096];
	snprintf(p, sizeof p, "%s/stderr.txt", dir);
	fflush(stderr);
	int saved = dup(2), fd = open(p, O_WRONLY | O_CREAT | O_TRUNC, 0644);
	dup2(fd, 2);
	close(fd);
	fn(arg);
	fflush(stderr);
	dup2(saved, 2);
	close(saved);
	return tu_read_file(p, NULL);
}

typedef struct read_job {
	const char *path;
	int rc;
	char err[1024];
} read_job;

static void read_rgb8_job(void *arg)
{
	read_job *j = arg;
	uint32_t w, h;
	uint8_t *px = NULL;
	j->rc = imageio_read_rgb8(j->path, &w, &h, &px, j->err, sizeof j->err);
	free(px);
}

/* Issue 12, images: an RGBA PNG is read as stored (it was premultiplied by its alpha, so clip and metrics saw other
 * colours), grey + alpha is grey; a truncated PNG is one message and nothing on stderr (libpng printed "libpng
 * error" lines); a full disk is reported by the PNG writer and leaves no file (a truncated PNG was renamed into
 * place; needs root for a small tmpfs, skipped with a message otherwise). */
static void test_png_io(void **state)
{
	(void)state;
	char err[1024], p[4096], cmd[4200];
	const char *d = tu_tmpdir("output_png");
	uint32_t w, h;
	uint8_t *px = NULL;
	const uint8_t rgba[2 * 4] = {200, 100, 50, 128, 10, 20, 30, 0};
	snprintf(p, sizeof p, "%s/rgba.png", d);
	raw_png(p, 2, 1, PNG_COLOR_TYPE_RGBA, 8, rgba, 4);
	assert_int_equal(imageio_read_rgb8(p, &w, &h, &px, err, sizeof err), TL_OK);
	assert_true(w == 2 && h == 1);
	const uint8_t expect[6] = {200, 100, 50, 10, 20, 30};
	assert_memory_equal(px, expect, 6);
	free(px);
	const uint8_t ga[2 * 2] = {77, 10, 200, 255};
	snprintf(p, sizeof p, "%s/ga.png", d);
	raw_png(p, 2, 1, PNG_COLOR_TYPE_GRAY_ALPHA, 8, ga, 2);
	assert_int_equal(imageio_read_rgb8(p, &w, &h, &px, err, sizeof err), TL_OK);
	const uint8_t expect_ga[6] = {77, 77, 77, 200, 200, 200};
	assert_memory_equal(px, expect_ga, 6);
	free(px);
	const uint8_t rgb16[6] = {0xff, 0xff, 0x80, 0x00, 0x00, 0x00}; /* 65535, 32768, 0 -> 255, 128, 0 */
	snprintf(p, sizeof p, "%s/rgb16.png", d);
	raw_png(p, 1, 1, PNG_COLOR_TYPE_RGB, 16, rgb16, 3);
	assert_int_equal(imageio_read_rgb8(p, &w, &h, &px, err, sizeof err), TL_OK);
	const uint8_t expect16[3] = {255, 128, 0};
	assert_memory_equal(px, expect16, 3);
	free(px);
	/* Our writer round trip, RGBA source (alpha dropped). */
	snprintf(p, sizeof p, "%s/ours.png", d);
	assert_int_equal(imageio_write_png_rgb8(p, 2, 1, rgba, err, sizeof err), TL_OK);
	assert_int_equal(imageio_read_rgb8(p, &w, &h, &px, err, sizeof err), TL_OK);
	assert_memory_equal(px, expect, 6);
	free(px);
	/* Truncated: one message naming the file, nothing printed by libpng. */
	uint8_t big[64 * 64 * 3];
	for (size_t i = 0; i < sizeof big; i++)
		big[i] = (uint8_t)(i * 37 % 251);
	snprintf(p, sizeof p, "%s/trunc.png", d);
	assert_int_equal(imageio_write_png_rgb8_packed(p, 64, 64, big, err, sizeof err), TL_OK);
	assert_int_equal(truncate(p, 200), 0);
	read_job j = {.path = p};
	char *printed = stderr_of(read_rgb8_job, &j, d);
	assert_int_equal(j.rc, TL_ERR_INPUT);
	assert_non_null(strstr(j.err, "trunc.png"));
	assert_null(strchr(j.err, '\n'));
	if (printed[0])
		fail_msg("the decoder printed to stderr: %s", printed);
	free(printed);
	/* Full disk. */
	snprintf(p, sizeof p, "%s/full", d);
	mkdir(p, 0755);
	snprintf(cmd, sizeof cmd, "mount -t tmpfs -o size=8k tmpfs %s 2>/dev/null", p);
	if (!tu_require(geteuid() == 0 && system(cmd) == 0,
			"test_png_io: the PNG writer on a full disk (needs root to mount an 8 KiB tmpfs on %s)", p))
		return;
	uint8_t *noise = malloc(256 * 256 * 3);
	uint32_t x = 1;
	for (size_t i = 0; i < 256 * 256 * 3; i++)
		noise[i] = (uint8_t)((x = x * 1103515245u + 12345u) >> 24); /* incompressible: far more than 8 KiB */
	snprintf(p, sizeof p, "%s/full/frame.png", d);
	int rc = imageio_write_png_rgb8_packed(p, 256, 256, noise, err, sizeof err);
	free(noise);
	int exists = tu_file_exists(p);
	snprintf(p, sizeof p, "%s/full", d);
	int entries = -1;
	DIR *dir = opendir(p);
	if (dir) {
		entries = 0;
		for (struct dirent *e; (e = readdir(dir));)
			entries += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
		closedir(dir);
	}
	snprintf(cmd, sizeof cmd, "umount %s/full", d);
	assert_int_equal(system(cmd), 0);
	assert_int_equal(rc, TL_ERR_OUTPUT);
	assert_non_null(strstr(err, "No space"));
	assert_false(exists);
	assert_int_equal(entries, 0);
}

static void test_pairs(void **state)
{
	(void)state;
	char err[1024], p[4096];
	const char *d = tu_tmpdir("output_pairs");
	pairs_condition c[2] = {{.id = "tfr-T8", .method = "tfr", .variant = "tfr@8", .T = 8, .run = "runs/tfr-T8",
				 .clip = "clips/tfr-T8.webm", .inspect = "inspect/tfr-T8.webm",
				 .facts = {.known = true, .family = "forward", .baseline = "ref", .takes_threshold = true}},
				{.id = "rrc-N4", .method = "rrc", .variant = "rrc/4", .T = NAN, .period = 4,
				 .run = "runs/rrc-N4", .clip = "clips/rrc-N4.webm", .inspect = "inspect/rrc-N4.webm"}};
	pairs_set s = {.scene = "calm", .camera = "walk", .camera_motion = "moving", .scene_path = "scenes/calm.json",
		       .display_transform = "ACES", .fps = 60, .first_frame = 0, .last_frame = 59, .width = 96,
		       .height = 54, .ref_run = "runs/ref", .ref_clip = "clips/ref.webm", .ref_method = "ref",
		       .conditions = c, .count = 2};
	snprintf(p, sizeof p, "%s/pairs.json", d);
	assert_int_equal(pairs_write(p, &s, err, sizeof err), TL_OK);
	pairs_set r;
	assert_int_equal(pairs_read(p, &r, err, sizeof err), TL_OK);
	assert_int_equal(r.count, 2);
	assert_string_equal(r.conditions[1].variant, "rrc/4");
	assert_true(isnan(r.conditions[1].T) && r.conditions[1].period == 4 && r.conditions[0].T == 8);
	assert_true(r.last_frame == 59 && r.width == 96 && r.fps == 60);
	/* the method facts and the reference's method (issue 30.1); a condition written without them reads as unknown */
	assert_true(r.conditions[0].facts.known && r.conditions[0].facts.takes_threshold && !r.conditions[0].facts.takes_period);
	assert_string_equal(r.conditions[0].facts.family, "forward");
	assert_false(r.conditions[1].facts.known);
	assert_string_equal(r.ref_method, "ref");
	pairs_free(&r);
	/* Paths leading out of the set are refused. */
	const char *evil[] = {"../x.webm", "/etc/passwd", "clips/../../x.webm"};
	for (int i = 0; i < 3; i++) {
		snprintf(c[0].clip, sizeof c[0].clip, "%s", evil[i]);
		assert_int_equal(pairs_write(p, &s, err, sizeof err), TL_OK);
		assert_int_equal(pairs_read(p, &r, err, sizeof err), TL_ERR_INPUT);
		assert_non_null(strstr(err, "relative"));
	}
	/* A period must be one of 1, 2, 4, 8 (or absent): negative or huge values are not folded into "none" or
	 * truncated to 32 bits. */
	snprintf(c[0].clip, sizeof c[0].clip, "clips/tfr-T8.webm");
	const uint32_t bad_periods[] = {3, 16};
	for (int i = 0; i < 2; i++) {
		c[1].period = bad_periods[i];
		assert_int_equal(pairs_write(p, &s, err, sizeof err), TL_OK);
		assert_int_equal(pairs_read(p, &r, err, sizeof err), TL_ERR_INPUT);
		assert_non_null(strstr(err, "period"));
	}
	char *text = tu_read_file(p, NULL), *at = strstr(text, "\"period\": 16");
	assert_non_null(at);
	FILE *f = fopen(p, "w");
	fprintf(f, "%.*s\"period\": -4%s", (int)(at - text), text, at + strlen("\"period\": 16"));
	fclose(f);
	free(text);
	assert_int_equal(pairs_read(p, &r, err, sizeof err), TL_ERR_INPUT);
	assert_non_null(strstr(err, "period"));
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_run_round_trip),
		cmocka_unit_test(test_run_folder_reuse),
		cmocka_unit_test(test_decision_maps),
		cmocka_unit_test(test_run_bad_input),
		cmocka_unit_test(test_pairs),
		cmocka_unit_test(test_large_frame_numbers),
		cmocka_unit_test(test_png_io),
	};
	return tu_finish(cmocka_run_group_tests(tests, NULL, NULL));
}
