/* test_cli_options.c — option parsing of the taslab CLI (no process spawned). */
#include <string.h>

#include "cli.h"
#include "test_util.h"

static void test_size(void **state)
{
	(void)state;
	char err[256];
	uint32_t w, h;
	assert_int_equal(cli_parse_size("960x540", &w, &h, err, sizeof err), 0);
	assert_int_equal(w, 960);
	assert_int_equal(h, 540);
	const char *bad[] = {"", "960", "960x", "x540", "0x10", "10x0", "96x54x2", "-5x5", "20000x10", "9a0x540", "960 x540"};
	for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
		assert_int_equal(cli_parse_size(bad[i], &w, &h, err, sizeof err), -1);
		assert_non_null(strstr(err, "--size"));
	}
}

static void test_frames(void **state)
{
	(void)state;
	char err[256];
	uint32_t a, b;
	bool given;
	b = 300;
	assert_int_equal(cli_parse_frames("10:20", &a, &b, &given, err, sizeof err), 0);
	assert_true(a == 10 && b == 20 && given);
	b = 300;
	assert_int_equal(cli_parse_frames("7", &a, &b, &given, err, sizeof err), 0);
	assert_true(a == 7 && b == 8);
	b = 300;
	assert_int_equal(cli_parse_frames(":5", &a, &b, &given, err, sizeof err), 0);
	assert_true(a == 0 && b == 5);
	b = 300;
	assert_int_equal(cli_parse_frames("290:", &a, &b, &given, err, sizeof err), 0);
	assert_true(a == 290 && b == 300 && !given);
	const char *bad[] = {"", "5:5", "9:3", "a:b", "1:2:3", "-1:4", "1-4"};
	for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
		b = 300;
		assert_int_equal(cli_parse_frames(bad[i], &a, &b, &given, err, sizeof err), -1);
		assert_non_null(strstr(err, "--frames"));
	}
}

static void test_render_options(void **state)
{
	(void)state;
	char err[256];
	cli_render_opts o;
	char *ok[] = {"render", "--scene", "turntable", "--size=96x54", "--frames", "0:3", "--validation", "--out", "x"};
	assert_int_equal(cli_render_parse(9, ok, &o, err, sizeof err), 0);
	assert_string_equal(o.scene, "turntable");
	assert_string_equal(o.method, "ref");
	assert_true(o.width == 96 && o.height == 54 && o.validation);
	char *unknown_method[] = {"render", "--scene", "s", "--method", "magic"};
	assert_int_equal(cli_render_parse(5, unknown_method, &o, err, sizeof err), -1);
	assert_non_null(strstr(err, "magic"));
	char *planned[] = {"render", "--scene", "s", "--method", "tasa"};
	assert_int_equal(cli_render_parse(5, planned, &o, err, sizeof err), -1);
	assert_non_null(strstr(err, "not implemented"));
	char *no_scene[] = {"render", "--size", "96x54"};
	assert_int_equal(cli_render_parse(3, no_scene, &o, err, sizeof err), -1);
	assert_non_null(strstr(err, "--scene"));
	char *missing_val[] = {"render", "--scene"};
	assert_int_equal(cli_render_parse(2, missing_val, &o, err, sizeof err), -1);
	char *unknown_opt[] = {"render", "--scene", "s", "--colour"};
	assert_int_equal(cli_render_parse(4, unknown_opt, &o, err, sizeof err), -1);
	assert_non_null(strstr(err, "--colour"));
	char *bad_thr[] = {"render", "--scene", "s", "--threshold", "-3"};
	assert_int_equal(cli_render_parse(5, bad_thr, &o, err, sizeof err), -1);
	char *help[] = {"render", "--help"};
	assert_int_equal(cli_render_parse(2, help, &o, err, sizeof err), 0);
	assert_true(o.help);
}

static void test_analysis_lists(void **state)
{
	(void)state;
	char err[256];
	uint32_t f[16];
	size_t n;
	assert_int_equal(cli_parse_frame_list("60,120", 300, f, 16, &n, err, sizeof err), 0);
	assert_int_equal(n, 2);
	assert_int_equal(f[1], 120);
	assert_int_equal(cli_parse_frame_list("120:300:60,7", 300, f, 16, &n, err, sizeof err), 0);
	assert_int_equal(n, 4); /* 120, 180, 240 (half-open), 7 */
	assert_int_equal(f[2], 240);
	assert_int_equal(f[3], 7);
	assert_int_equal(cli_parse_frame_list("300", 300, f, 16, &n, err, sizeof err), -1);
	assert_non_null(strstr(err, "outside the clip"));
	assert_int_equal(cli_parse_frame_list("0:20", 300, f, 16, &n, err, sizeof err), -1); /* more than 16 */
	const char *bad[] = {"", "a", "5:3", "1:9:0", "1,,2", "-3", "4x"};
	for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
		assert_int_equal(cli_parse_frame_list(bad[i], 300, f, 16, &n, err, sizeof err), -1);
	float t[8];
	assert_int_equal(cli_parse_float_list("2,4,8.5", "--thresholds: T", 1e-6, 255, t, 8, &n, err, sizeof err), 0);
	assert_int_equal(n, 3);
	assert_true(t[2] == 8.5f);
	assert_int_equal(cli_parse_float_list("8,0", "--thresholds: T", 1e-6, 255, t, 8, &n, err, sizeof err), -1);
	assert_non_null(strstr(err, "--thresholds"));
	assert_int_equal(cli_parse_float_list("1,2,3,4,5,6,7,8,9", "T", 1e-6, 255, t, 8, &n, err, sizeof err), -1);
}

static void test_resolve_scene(void **state)
{
	(void)state;
	char path[4096], err[256];
	assert_int_equal(cli_resolve_scene("turntable", path, sizeof path, err, sizeof err), 0);
	assert_non_null(strstr(path, "scenes/turntable.json"));
	assert_int_equal(cli_resolve_scene("no_such_scene", path, sizeof path, err, sizeof err), -1);
	assert_non_null(strstr(err, "no_such_scene"));
	assert_int_equal(cli_resolve_scene("dir/file.json", path, sizeof path, err, sizeof err), 0);
	assert_string_equal(path, "dir/file.json");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_size), cmocka_unit_test(test_frames),
		cmocka_unit_test(test_render_options), cmocka_unit_test(test_resolve_scene),
		cmocka_unit_test(test_analysis_lists),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
