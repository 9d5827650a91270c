/* test_output.c — the file formats of output/: run folder writer and reader (manifest, stats.csv, frames
 * checked against the manifest), a re-used run folder holding exactly its run, pairs.json round trip and
 * its refusals. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

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
	run_option opts[2] = {{.key = "threshold", .type = RUN_VALUE_NUMBER, .number = 8},
			      {.key = "oracle", .type = RUN_VALUE_BOOL, .boolean = true}};
	run_info info = {.scene_name = "s", .scene_path = "s.json", .camera = "c", .camera_motion = "moving",
			 .device = "dev", .driver = "drv", .method = "tarc-oracle", .variant = "tarc-oracle@8",
			 .threshold = 8, .options = opts, .option_count = 2, .first_frame = first,
			 .last_frame = first + n - 1, .width = W, .height = H, .fps = 30, .write_exr = exr, .write_png = png,
			 .write_decisions = with_decisions};
	run_writer *w = NULL;
	if (run_writer_create(dir, &info, &w, err, sizeof err))
		fail_msg("%s", err);
	for (uint32_t f = first; f < first + n; f++) {
		frame_stats st = {.frame = f, .time_s = f / 30.0, .visible_samples = 20, .shaded_samples = 5, .reused_samples = 15,
				  .allocated_samples = -1, .late_samples = -1, .visible_units = 20, .shaded_units = 5,
				  .new_units = 1, .fs_invocations = -1, .cs_invocations = -1, .gpu_ms_total = 1.5,
				  .pass_count = 1, .pass_names = {"shade"}, .gpu_ms = {1.25}, .extra_count = 1,
				  .extra_names = {"cpu_ms_alloc"}, .extra = {NAN}};
		frame_image img = {W, H, hdr, disp, with_decisions ? decisions : NULL};
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

static void test_pairs(void **state)
{
	(void)state;
	char err[1024], p[4096];
	const char *d = tu_tmpdir("output_pairs");
	pairs_condition c[2] = {{.id = "tfr-T8", .method = "tfr", .variant = "tfr@8", .T = 8, .run = "runs/tfr-T8",
				 .clip = "clips/tfr-T8.webm", .inspect = "inspect/tfr-T8.webm"},
				{.id = "rrc-N4", .method = "rrc", .variant = "rrc/4", .T = NAN, .period = 4,
				 .run = "runs/rrc-N4", .clip = "clips/rrc-N4.webm", .inspect = "inspect/rrc-N4.webm"}};
	pairs_set s = {.scene = "calm", .camera = "walk", .camera_motion = "moving", .scene_path = "scenes/calm.json",
		       .display_transform = "ACES", .fps = 60, .first_frame = 0, .last_frame = 59, .width = 96,
		       .height = 54, .ref_run = "runs/ref", .ref_clip = "clips/ref.webm", .conditions = c, .count = 2};
	snprintf(p, sizeof p, "%s/pairs.json", d);
	assert_int_equal(pairs_write(p, &s, err, sizeof err), TL_OK);
	pairs_set r;
	assert_int_equal(pairs_read(p, &r, err, sizeof err), TL_OK);
	assert_int_equal(r.count, 2);
	assert_string_equal(r.conditions[1].variant, "rrc/4");
	assert_true(isnan(r.conditions[1].T) && r.conditions[1].period == 4 && r.conditions[0].T == 8);
	assert_true(r.last_frame == 59 && r.width == 96 && r.fps == 60);
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
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
