/* test_cli_options.c — option parsing of the taslab CLI (no process spawned). */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "taslab/method.h"
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

/* Parses argv with command `name`'s table into opts (a buffer of CLI_OPTS_MAX_B) and ctx; returns the tl_err. */
static _Alignas(max_align_t) unsigned char opts_buf[CLI_OPTS_MAX_B];
static cli_ctx ctx;

static int parse(const char *name, int argc, char **argv)
{
	const cli_command *c = cli_find_command(name);
	assert_non_null(c);
	memset(&ctx, 0, sizeof ctx);
	return cli_parse_command(c, argc, argv, opts_buf, &ctx);
}

#define PARSE_OK(name, ...)                                                                                        \
	do {                                                                                                       \
		char *argv_[] = {__VA_ARGS__};                                                                     \
		int rc_ = parse(name, (int)(sizeof argv_ / sizeof argv_[0]), argv_);                               \
		if (rc_)                                                                                           \
			fail_msg("%s: %s", name, ctx.err);                                                         \
	} while (0)
/* Fails unless parsing fails with TL_ERR_ARG and a message containing `needle`. */
#define PARSE_BAD(name, needle, ...)                                                                               \
	do {                                                                                                       \
		char *argv_[] = {__VA_ARGS__};                                                                     \
		int rc_ = parse(name, (int)(sizeof argv_ / sizeof argv_[0]), argv_);                               \
		if (rc_ != TL_ERR_ARG && rc_ != TL_ERR_UNSUPPORTED)                                                \
			fail_msg("%s: expected a usage error, got %d (%s)", name, rc_, ctx.err);                   \
		if (!strstr(ctx.err, needle))                                                                      \
			fail_msg("%s: message '%s' lacks '%s'", name, ctx.err, needle);                            \
		assert_null(strchr(ctx.err, '\n'));                                                                \
	} while (0)

static void test_render_options(void **state)
{
	(void)state;
	render_opts *o = (render_opts *)opts_buf;
	PARSE_OK("render", "render", "--scene", "turntable", "--size=96x54", "--frames", "0:3", "--validation", "--out", "x");
	assert_string_equal(ctx.setup_opts.scene, "turntable");
	assert_string_equal(o->config.method->name, "ref");
	assert_true(ctx.setup_opts.size[0] == 96 && ctx.setup_opts.size[1] == 54 && ctx.setup_opts.validation);
	PARSE_OK("render", "render", "--scene=s", "--method=tfr", "--threshold=4", "--max-age", "3");
	assert_true(method_config_threshold(&o->config) == 4 && method_config_number(&o->config, "max-age") == 3);
	PARSE_OK("render", "render", "--scene", "s", "--method", "tfr@16"); /* a variant token */
	assert_true(method_config_threshold(&o->config) == 16);
	PARSE_OK("render", "render", "--scene", "s", "--method", "tfr"); /* --threshold's default */
	assert_true(method_config_threshold(&o->config) == 8);
	/* the reuse methods: variants, option tables, render-level flags */
	PARSE_OK("render", "render", "--scene", "s", "--method", "rrc/8", "--resample", "nearest", "--decisions");
	assert_true(method_config_period(&o->config) == 8 && o->decisions);
	PARSE_OK("render", "render", "--scene", "s", "--method", "tarc", "--threshold", "16", "--truth", "--max-age=30");
	assert_true(method_config_threshold(&o->config) == 16 && method_config_number(&o->config, "max-age") == 30);
	PARSE_OK("render", "render", "--scene", "s", "--method", "tarc", "--oracle", "--threshold", "0");
	PARSE_BAD("render", "T > 0", "render", "--scene", "s", "--method", "tarc", "--threshold", "0");
	PARSE_BAD("render", "one of 1, 2, 4, 8", "render", "--scene", "s", "--method", "rrc", "--period", "3");
	PARSE_BAD("render", "not an option of rrc", "render", "--scene", "s", "--method", "rrc", "--oracle");
	PARSE_BAD("render", "no reuse decisions", "render", "--scene", "s", "--method", "tfr@8", "--decisions");
	PARSE_BAD("render", "magic", "render", "--scene", "s", "--method", "magic");
	PARSE_OK("render", "render", "--scene", "s", "--method", "tasa@16", "--atlas-scale", "8", "--truth");
	assert_true(method_config_threshold(&o->config) == 16 && method_config_number(&o->config, "atlas-scale") == 8);
	PARSE_BAD("render", "--atlas-scale", "render", "--scene", "s", "--method", "sa", "--atlas-scale", "0");
	PARSE_BAD("render", "not an option of sa", "render", "--scene", "s", "--method", "sa", "--threshold", "8");
	PARSE_BAD("render", "--scene", "render", "--size", "96x54");
	PARSE_BAD("render", "needs a value", "render", "--scene");
	PARSE_BAD("render", "--colour", "render", "--scene", "s", "--colour");
	PARSE_BAD("render", "--threshold", "render", "--scene", "s", "--method", "tfr", "--threshold", "-3");
	PARSE_BAD("render", "not an option of ref", "render", "--scene", "s", "--max-age", "3");
	PARSE_BAD("render", "whole number", "render", "--scene", "s", "--method", "tfr", "--max-age", "2.5");
	PARSE_BAD("render", "takes no value", "render", "--scene", "s", "--validation=1");
	PARSE_BAD("render", "unexpected argument", "render", "--scene", "s", "stray");
	PARSE_BAD("render", "--frames", "render", "--scene", "s", "--frames", "9:3");
	PARSE_BAD("render", "--fps", "render", "--scene", "s", "--fps", "0");
	PARSE_OK("render", "render", "--help");
	assert_true(ctx.help);
}

static void test_pair_options(void **state)
{
	(void)state;
	pair_opts *o = (pair_opts *)opts_buf;
	PARSE_OK("pair", "pair", "--scene", "calm", "--out", "d", "--variants", "ref,tfr@2,tfr@8");
	assert_int_equal(o->count, 3);
	assert_true(method_config_threshold(&o->configs[2]) == 8);
	PARSE_OK("pair", "pair", "--scene", "calm", "--out", "d", "--variants", "rrc/4,rrc/8,tarc@8,tarc-oracle@8");
	assert_int_equal(o->count, 4);
	assert_true(method_config_period(&o->configs[1]) == 8 && method_config_threshold(&o->configs[3]) == 8);
	PARSE_OK("pair", "pair", "--scene", "calm", "--out", "d"); /* default: the catch pair */
	assert_int_equal(o->count, 1);
	PARSE_BAD("pair", "tfr@8", "pair", "--scene", "calm", "--out", "d", "--variants", "tfr");
	PARSE_BAD("pair", "listed twice", "pair", "--scene", "calm", "--out", "d", "--variants", "tfr@8,tfr@8");
	PARSE_BAD("pair", "empty entry", "pair", "--scene", "calm", "--out", "d", "--variants", "tfr@8,,ref");
	PARSE_BAD("pair", "takes no '@'", "pair", "--scene", "calm", "--out", "d", "--variants", "ref@8");
	PARSE_BAD("pair", "--out", "pair", "--scene", "calm");
}

static void test_tool_options(void **state)
{
	(void)state;
	PARSE_OK("tonemap", "tonemap", "run", "--out", "x", "--view", "v");
	assert_int_equal(ctx.npos, 1);
	PARSE_BAD("tonemap", "INPUT", "tonemap", "--out", "x");
	PARSE_BAD("tonemap", "unexpected argument", "tonemap", "a", "b");
	PARSE_OK("clip", "clip", "run", "--out=c.webm");
	PARSE_BAD("clip", "--out", "clip", "run");
	PARSE_BAD("scenes", "unexpected argument", "scenes", "extra");
	PARSE_BAD("devices", "unknown option", "devices", "--all");
}

static void test_metrics_options(void **state)
{
	(void)state;
	metrics_diff_opts *d = (metrics_diff_opts *)opts_buf;
	PARSE_OK("metrics diff", "diff", "--ref", "a", "--test", "b", "--out", "o", "--threads", "2", "--heatmaps");
	assert_true(d->threads == 2 && d->heatmaps && !strcmp(d->format, "png"));
	PARSE_BAD("metrics diff", "--ref", "diff", "--ref", "a", "--out", "o");
	PARSE_BAD("metrics diff", "--format", "diff", "--ref", "a", "--test", "b", "--out", "o", "--format", "jpg");
	PARSE_BAD("metrics diff", "--threads", "diff", "--ref", "a", "--test", "b", "--out", "o", "--threads", "1.5");
	/* the metric registry's selection and FLIP's viewing condition */
	PARSE_OK("metrics diff", "diff", "--ref", "a", "--test", "b", "--out", "o", "--metrics", "maxrgb,flip", "--ppd=30");
	PARSE_OK("metrics diff", "diff", "--ref", "a", "--test", "b", "--out", "o", "--metrics", "all");
	PARSE_BAD("metrics diff", "unknown metric 'vmaf'", "diff", "--ref", "a", "--test", "b", "--out", "o", "--metrics",
		  "psnr,vmaf");
	PARSE_BAD("metrics diff", "--ppd", "diff", "--ref", "a", "--test", "b", "--out", "o", "--ppd", "0");
	PARSE_BAD("metrics diff", "--ppd", "diff", "--ref", "a", "--test", "b", "--out", "o", "--ppd", "x");
	PARSE_OK("metrics runs", "runs", "--out", "o", "r1", "r2");
	assert_int_equal(ctx.npos, 2);
	PARSE_BAD("metrics runs", "RUN", "runs", "--out", "o");
	metrics_jnd_opts *j = (metrics_jnd_opts *)opts_buf;
	PARSE_OK("metrics jnd", "jnd", "--n", "40", "--ref-preferred", "22", "--ties", "6");
	assert_true(j->n == 40 && j->confidence == 0.95);
	PARSE_BAD("metrics jnd", "--n", "jnd", "--n", "10", "--ref-preferred", "12");
	/* Issue 12: answer counts are whole numbers (fractions were taken as counts). */
	PARSE_BAD("metrics jnd", "whole number", "jnd", "--n", "10.5", "--ref-preferred", "3");
	PARSE_BAD("metrics jnd", "whole number", "jnd", "--n", "10", "--ref-preferred", "3.2");
	PARSE_BAD("metrics jnd", "whole number", "jnd", "--n", "10", "--ref-preferred", "3", "--ties", "0.5");
	PARSE_BAD("metrics jnd", "--ref-preferred", "jnd", "--n", "10");
	PARSE_BAD("metrics diff", "empty entry", "diff", "--ref", "a", "--test", "b", "--out", "o", "--metrics", "maxrgb,,psnr");
	PARSE_BAD("metrics diff", "empty entry", "diff", "--ref", "a", "--test", "b", "--out", "o", "--metrics", "maxrgb,");
}

static void test_analyze_options(void **state)
{
	(void)state;
	analyze_opts *o = (analyze_opts *)opts_buf;
	PARSE_OK("analyze coherence", "coherence", "--scene", "calm", "--frames", "120:300:60", "--out", "a");
	assert_int_equal(o->nT, 6);
	assert_true(ctx.setup_opts.size[0] == 480 && ctx.setup_opts.size[1] == 270);
	PARSE_OK("analyze predictors", "predictors", "--scene", "calm", "--frames", "60,120", "--out", "a", "--thresholds",
		 "4,8", "--step", "0.25", "--images");
	assert_true(o->nT == 2 && o->step == 0.25 && o->images);
	PARSE_BAD("analyze coherence", "--frames", "coherence", "--scene", "calm", "--out", "a");
	PARSE_BAD("analyze coherence", "--thresholds", "coherence", "--scene", "calm", "--frames", "1", "--out", "a",
		  "--thresholds", "8,0");
	PARSE_BAD("analyze coherence", "empty entry", "coherence", "--scene", "calm", "--frames", "1", "--out", "a",
		  "--thresholds", "8,,16");
	PARSE_BAD("analyze predictors", "--step", "predictors", "--scene", "calm", "--frames", "1", "--out", "a", "--step",
		  "2");
}

static void test_study_options(void **state)
{
	(void)state;
	study_opts *o = (study_opts *)opts_buf;
	PARSE_OK("study design", "design", "--db", "s.db", "--stimuli", "st", "--participants", "24", "--seed", "7");
	assert_true(o->participants == 24 && o->seed == 7);
	PARSE_BAD("study design", "--participants", "design", "--db", "s.db", "--stimuli", "st", "--participants", "2.5");
	PARSE_BAD("study design", "--participants", "design", "--db", "s.db", "--stimuli", "st", "--participants", "0");
	PARSE_BAD("study design", "--training", "design", "--db", "s.db", "--stimuli", "st", "--participants", "2",
		  "--training", "1e9");
	PARSE_BAD("study design", "--db", "design", "--stimuli", "st", "--participants", "2");
	PARSE_OK("study design", "design", "--db", "s.db", "--stimuli", "st", "--participants", "2", "--seed", "4294967295");
	/* GSL's mt19937 keeps 32 bits of a seed: 2^32 would repeat seed 0 */
	PARSE_BAD("study design", "--seed", "design", "--db", "s.db", "--stimuli", "st", "--participants", "2", "--seed",
		  "4294967296");
	PARSE_OK("study serve", "serve", "--db", "s.db", "--port", "0");
	assert_int_equal(o->port, 0);
	PARSE_BAD("study serve", "--port", "serve", "--db", "s.db", "--port", "18080.7");
	PARSE_BAD("study serve", "--port", "serve", "--db", "s.db", "--port", "70000");
	PARSE_BAD("study serve", "--threads", "serve", "--db", "s.db", "--threads", "100000");
	PARSE_BAD("study tally", "--bootstrap", "tally", "--db", "s.db", "--out", "o", "--bootstrap", "1e9");
	PARSE_BAD("study tally", "--out", "tally", "--db", "s.db");
	PARSE_OK("study import", "import", "--db", "s.db", "r.csv");
	PARSE_BAD("study import", "RATINGS.csv", "import", "--db", "s.db");
	PARSE_BAD("study links", "unexpected argument", "links", "--db", "s.db", "stray");
	PARSE_BAD("study export", "unknown option", "export", "--db", "s.db", "--out", "x.csv", "--pwcmp-x", "y");
}

static void test_help_from_tables(void **state)
{
	(void)state;
	/* Every command's and subcommand's help is generated from its tables and mentions each option. */
	for (const cli_command *const *c = cli_commands; *c; c++) {
		const cli_command *const *subs = (*c)->subcommands;
		for (size_t k = 0; subs ? subs[k] != NULL : k == 0; k++) {
			const cli_command *cmd = subs ? subs[k] : *c;
			assert_true(cmd->opts_size <= CLI_OPTS_MAX_B);
			char *text = NULL;
			size_t len = 0;
			FILE *f = open_memstream(&text, &len);
			cli_print_help(f, cmd);
			fclose(f);
			assert_non_null(strstr(text, "usage: taslab"));
			for (const cli_opt *o = cmd->options; o && o->type != CLI_OPT_END; o++)
				if (o->type != CLI_INCLUDE) {
					char flag[80];
					snprintf(flag, sizeof flag, "--%s", o->name);
					if (!strstr(text, flag))
						fail_msg("%s --help lacks %s", cmd->name, flag);
				}
			free(text);
			if (!subs)
				break;
		}
	}
}

/* s with every run of white space (line breaks of wrapped help included) as one space; malloc'ed. */
static char *flatten(const char *s)
{
	char *flat = malloc(strlen(s) + 1), *w = flat;
	assert_non_null(flat);
	for (const char *r = s; *r; r++)
		if (!(isspace((unsigned char)*r) && w > flat && w[-1] == ' '))
			*w++ = isspace((unsigned char)*r) ? ' ' : *r;
	*w = 0;
	return flat;
}

/* `render --help` lists every method with its own options under it (DESIGN section 4: help from the option tables),
 * each with that method's help text, default and range: --max-age is 1..119 for tfr and 0..65535 for tarc. */
static void test_render_help_per_method(void **state)
{
	(void)state;
	char *text = NULL;
	size_t len = 0;
	FILE *f = open_memstream(&text, &len);
	cli_print_help(f, cli_find_command("render"));
	fclose(f);
	size_t n;
	const method_info *const *m = method_list(&n);
	for (size_t i = 0; i < n; i++) {
		char head[32];
		snprintf(head, sizeof head, "\n  %-6s ", m[i]->name);
		const char *sec = strstr(text, head), *end = NULL;
		if (!sec)
			fail_msg("render --help lacks method %s", m[i]->name);
		if (i + 1 < n) {
			snprintf(head, sizeof head, "\n  %-6s ", m[i + 1]->name);
			end = strstr(sec, head);
		}
		char *section = strndup(sec, end ? (size_t)(end - sec) : strlen(sec));
		char *flat = flatten(section); /* the help wraps */
		for (size_t k = 0; k < m[i]->option_count; k++) {
			const method_option *o = &m[i]->options[k];
			char want[256], desc[160];
			method_option_describe(o, desc, sizeof desc);
			snprintf(want, sizeof want, "--%s", o->name);
			if (!strstr(flat, want))
				fail_msg("render --help: %s lacks --%s", m[i]->name, o->name);
			if (*desc) {
				snprintf(want, sizeof want, "[%s]", desc);
				if (!strstr(flat, want))
					fail_msg("render --help: %s --%s lacks '%s'", m[i]->name, o->name, want);
			}
		}
		free(flat);
		free(section);
	}
	char *flat = flatten(text);
	assert_non_null(strstr(flat, "[default 119; 1..119]"));                 /* tfr --max-age */
	assert_non_null(strstr(flat, "[default 0; 0..65535]"));                 /* tarc --max-age */
	assert_non_null(strstr(flat, "[as /N; default 4; one of 1, 2, 4, 8]")); /* rrc, sau --period */
	free(flat);
	free(text);
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
		cmocka_unit_test(test_render_options), cmocka_unit_test(test_pair_options),
		cmocka_unit_test(test_tool_options), cmocka_unit_test(test_metrics_options),
		cmocka_unit_test(test_analyze_options), cmocka_unit_test(test_study_options),
		cmocka_unit_test(test_help_from_tables), cmocka_unit_test(test_render_help_per_method), cmocka_unit_test(test_resolve_scene),
		cmocka_unit_test(test_analysis_lists),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
