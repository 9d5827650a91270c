/* test_clip.c — clips are bit-exact: a rendered run is encoded (lossless VP9, gbrp, WebM) and decoded with
 * libavcodec, and every decoded frame equals its PNG exactly; `taslab tonemap` reproduces the renderer's
 * PNGs within 1 code value (GPU vs CPU OCIO); bad runs fail with one line (nothing from the decoder library) and
 * leave no clip behind; careless inputs and outputs of tonemap and clip (test_careless_outputs); frames that are
 * devices, FIFOs, folders or another format (test_not_regular_frames). */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/clip.h"
#include "taslab/imageio.h"
#include "test_util.h"

static char out[65536];
static char run[4096];

static int setup(void **state)
{
	(void)state;
	char cmd[8192];
	snprintf(run, sizeof run, "%s/run", tu_tmpdir("clip"));
	snprintf(cmd, sizeof cmd, "%s render --scene turntable --camera orbit --size 64x36 --frames 10:14 --device " TASLAB_TEST_DEVICE " "
		 "--validation --quiet --out %s", TASLAB_BINARY, run);
	return tu_run(cmd, out, sizeof out) == 0 ? 0 : (fprintf(stderr, "%s\n", out), -1);
}

typedef struct cmp_ctx {
	const char *run;
	uint32_t first, count;
	int mismatches;
} cmp_ctx;

static int compare_frame(void *user, uint32_t index, uint32_t w, uint32_t h, const uint8_t *rgb)
{
	cmp_ctx *c = user;
	char path[4096], err[1024];
	uint32_t pw, ph;
	uint8_t *png = NULL;
	snprintf(path, sizeof path, "%s/frames/%06u.png", c->run, c->first + index);
	if (imageio_read_rgb8(path, &pw, &ph, &png, err, sizeof err) || pw != w || ph != h ||
	    memcmp(png, rgb, (size_t)w * h * 3) != 0)
		c->mismatches++;
	free(png);
	c->count++;
	return 0;
}

static void test_clip_bit_exact(void **state)
{
	(void)state;
	char clip[4096], err[1024];
	snprintf(clip, sizeof clip, "%s/../clip.webm", run);
	uint32_t n = 0;
	if (clip_encode_run(run, clip, &n, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(n, 4);
	cmp_ctx c = {run, 10, 0, 0};
	double fps = 0;
	if (clip_decode(clip, compare_frame, &c, &fps, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(c.count, 4);
	assert_int_equal(c.mismatches, 0); /* max difference 0 */
	assert_float_equal(fps, 60.0, 1e-9);
}

static void test_tonemap_matches_renderer(void **state)
{
	(void)state;
	char cmd[8192], a[4096], b[4096], err[1024];
	snprintf(cmd, sizeof cmd, "%s tonemap %s", TASLAB_BINARY, run);
	if (tu_run(cmd, out, sizeof out) != 0)
		fail_msg("%s", out);
	for (int f = 10; f < 14; f++) {
		uint32_t w, h, w2, h2;
		uint8_t *x = NULL, *y = NULL;
		snprintf(a, sizeof a, "%s/frames/%06d.png", run, f);
		snprintf(b, sizeof b, "%s/tonemapped/%06d.png", run, f);
		assert_int_equal(imageio_read_rgb8(a, &w, &h, &x, err, sizeof err), 0);
		assert_int_equal(imageio_read_rgb8(b, &w2, &h2, &y, err, sizeof err), 0);
		int max = 0;
		for (size_t i = 0; i < (size_t)w * h * 3; i++)
			max = abs(x[i] - y[i]) > max ? abs(x[i] - y[i]) : max;
		/* Same half-float input, same OCIO processor on GPU and CPU: at most a rounding step apart. */
		assert_true(max <= 1);
		free(x);
		free(y);
	}
}

static int dir_has_tmp(const char *dir)
{
	DIR *d = opendir(dir);
	struct dirent *e;
	int found = 0;
	while (d && (e = readdir(d)))
		found |= strstr(e->d_name, ".tmp") != NULL;
	if (d)
		closedir(d);
	return found;
}

/* One line on stderr from taslab and nothing else (a decoder library printing its own lines, as libpng did through
 * OpenImageIO for truncated PNGs, fails this). */
static void expect_clip_failure(const char *run_dir, const char *needle)
{
	char cmd[8192], clip[4096];
	snprintf(clip, sizeof clip, "%s.webm", run_dir); /* beside the run: never inside it */
	snprintf(cmd, sizeof cmd, "%s clip %s --out %s", TASLAB_BINARY, run_dir, clip);
	int st = tu_run(cmd, out, sizeof out);
	const char *ours = strstr(out, "taslab clip:");
	const char *nl = ours ? strchr(ours, '\n') : NULL;
	int ok = st != 0 && ours && nl && strstr(ours, needle) && strstr(ours, needle) < nl && tu_count_lines(out) == 1;
	if (!ok)
		fail_msg("'%s' gave %d:\n%s(expected one line with '%s')", cmd, st, out, needle);
	assert_false(tu_file_exists(clip));
	assert_false(dir_has_tmp(run_dir));
	char parent[4096];
	snprintf(parent, sizeof parent, "%s/..", run_dir);
	assert_false(dir_has_tmp(parent));
}

static void test_bad_runs(void **state)
{
	(void)state;
	char cmd[8192], p[4096];
	const char *dir = tu_tmpdir("clip_bad");
	/* A missing frame in the middle. */
	snprintf(cmd, sizeof cmd, "cp -r %s %s/gap && rm %s/gap/frames/000012.png", run, dir, dir);
	assert_int_equal(system(cmd), 0);
	snprintf(p, sizeof p, "%s/gap", dir);
	expect_clip_failure(p, "000012.png is missing");
	/* A frame of another size. */
	snprintf(cmd, sizeof cmd, "cp -r %s %s/size && oiiotool %s/frames/000011.png --resize 32x18 -o %s/size/frames/000012.png",
		 run, dir, run, dir);
	assert_int_equal(system(cmd), 0);
	snprintf(p, sizeof p, "%s/size", dir);
	expect_clip_failure(p, "differs from the run's");
	/* A truncated PNG. */
	snprintf(cmd, sizeof cmd, "cp -r %s %s/trunc && truncate -s 100 %s/trunc/frames/000013.png", run, dir, dir);
	assert_int_equal(system(cmd), 0);
	snprintf(p, sizeof p, "%s/trunc", dir);
	expect_clip_failure(p, "000013.png");
	/* Not a run. */
	expect_clip_failure(dir, "manifest.json");
	/* Unknown OCIO display / view and a missing config: one line, usage exit status, nothing written. */
	snprintf(p, sizeof p, "%s/cfg.ocio", dir);
	FILE *f = fopen(p, "w");
	fputs("ocio_profile_version: 2\nroles:\n  scene_linear: lin\n  default: lin\ndisplays:\n  sRGB:\n"
	      "    - !<View> {name: Raw, colorspace: lin}\ncolorspaces:\n  - !<ColorSpace> {name: lin}\n", f);
	fclose(f);
	const char *bad_cfg[][2] = {{"--display Projector", "no display 'Projector' (displays: sRGB)"},
				    {"--view Filmic", "has no view 'Filmic' (views: Raw)"}};
	for (int i = 0; i < 2; i++) {
		snprintf(cmd, sizeof cmd, "%s tonemap %s --out %s/tm%d --ocio-config %s %s", TASLAB_BINARY, run, dir, i, p,
			 bad_cfg[i][0]);
		assert_int_equal(tu_run(cmd, out, sizeof out), 2);
		if (!strstr(out, bad_cfg[i][1]) || tu_count_lines(out) != 1)
			fail_msg("%s:\n%s", cmd, out);
		snprintf(cmd, sizeof cmd, "%s/tm%d", dir, i);
		assert_false(tu_file_exists(cmd));
	}
	snprintf(cmd, sizeof cmd, "%s render --scene turntable --ocio-config %s/none.ocio --out %s/r", TASLAB_BINARY, dir, dir);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	assert_non_null(strstr(out, "none.ocio"));
	/* tonemap: a truncated EXR is a clear error. */
	snprintf(cmd, sizeof cmd, "truncate -s 200 %s/trunc/frames/000013.exr && %s tonemap %s/trunc/frames/000013.exr",
		 dir, TASLAB_BINARY, dir);
	assert_int_not_equal(tu_run(cmd, out, sizeof out), 0);
	assert_non_null(strstr(out, "000013.exr"));
}

/* Issue 12: tonemap converts scene-linear EXRs only (a display-referred PNG, also one named .exr, was tone-mapped
 * again into wrong colours that looked like a result), and its PNGs appear all together or not at all (frames
 * before a bad one stayed); clip writes only a .webm (it wrote a WebM over another run's frame PNG) and removes the
 * temporary file a killed clip left beside its --out. */
static void test_careless_outputs(void **state)
{
	(void)state;
	char cmd[8192], args[8192], p[4096];
	const char *dir = tu_tmpdir("clip_careless");
	snprintf(args, sizeof args, "tonemap %s/frames/000011.png --out %s/tm_png", run, dir);
	tu_expect_cli_error(args, "not an OpenEXR file");
	snprintf(p, sizeof p, "%s/tm_png", dir);
	assert_false(tu_file_exists(p));
	/* A run whose last EXR is a PNG under an .exr name: no PNG of the good frames appears; an old file stays. */
	snprintf(cmd, sizeof cmd, "cp -r %s %s/fake && cp %s/frames/000013.png %s/fake/frames/000013.exr && mkdir %s/tm && "
		 "echo old > %s/tm/000010.png", run, dir, run, dir, dir, dir);
	assert_int_equal(system(cmd), 0);
	snprintf(args, sizeof args, "tonemap %s/fake --out %s/tm_new", dir, dir);
	tu_expect_cli_error(args, "000013.exr: not an OpenEXR file");
	snprintf(p, sizeof p, "%s/tm_new", dir);
	assert_false(tu_file_exists(p));
	snprintf(args, sizeof args, "tonemap %s/fake --out %s/tm", dir, dir);
	tu_expect_cli_error(args, "000013.exr: not an OpenEXR file");
	snprintf(p, sizeof p, "%s/tm/000010.png", dir);
	char *old = tu_read_file(p, NULL);
	assert_string_equal(old, "old\n");
	free(old);
	snprintf(p, sizeof p, "%s/tm/000011.png", dir);
	assert_false(tu_file_exists(p));
	assert_false(dir_has_tmp(dir));
	/* tonemap into the run's own frames folder (its PNGs under another view transform): refused. */
	snprintf(p, sizeof p, "%s/frames/000010.png", run);
	size_t before_len, after_len;
	char *before = tu_read_file(p, &before_len);
	snprintf(args, sizeof args, "tonemap %s --out %s/frames", run, run);
	tu_expect_cli_error(args, "is the folder of the input frames");
	snprintf(args, sizeof args, "tonemap %s --out %s/./frames/", run, run);
	tu_expect_cli_error(args, "is the folder of the input frames");
	/* clip: a .webm only; a killed clip's temporary file (unlocked) goes, the finished clip stays. */
	snprintf(args, sizeof args, "clip %s --out %s", run, p);
	tu_expect_cli_error(args, "give a name ending in .webm");
	char *after = tu_read_file(p, &after_len);
	assert_true(before_len == after_len && !memcmp(before, after, before_len));
	free(before);
	free(after);
	snprintf(p, sizeof p, "%s/.c.webm.tmp.Ab12Cd", dir);
	FILE *f = fopen(p, "w");
	fputs("half a clip", f);
	fclose(f);
	snprintf(cmd, sizeof cmd, "%s clip %s --out %s/c.webm", TASLAB_BINARY, run, dir);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s", out);
	assert_false(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/c.webm", dir);
	assert_true(tu_file_exists(p));
}

typedef struct count_ctx {
	uint32_t frames, width, height;
} count_ctx;

static int count_frame(void *user, uint32_t index, uint32_t w, uint32_t h, const uint8_t *rgb)
{
	(void)index;
	(void)rgb;
	count_ctx *c = user;
	c->frames++;
	c->width = w;
	c->height = h;
	return 0;
}

static void test_pair(void **state)
{
	(void)state;
	char cmd[8192], p[4096], err[1024];
	const char *dir = tu_tmpdir("pair");
	snprintf(cmd, sizeof cmd, "%s pair --scene turntable --camera overview --frames 5:8 --size 48x27 --device " TASLAB_TEST_DEVICE " "
		 "--validation --variants ref --out %s/set", TASLAB_BINARY, dir);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s", out);
	snprintf(p, sizeof p, "%s/set/pairs.json", dir);
	char *js = tu_read_file(p, NULL);
	assert_non_null(js);
	assert_non_null(strstr(js, "\"camera_motion\": \"stationary\""));
	assert_non_null(strstr(js, "\"clip\": \"clips/ref.webm\""));
	assert_non_null(strstr(js, "\"inspect\": \"inspect/ref.webm\""));
	free(js);
	count_ctx c = {0};
	snprintf(p, sizeof p, "%s/set/clips/ref.webm", dir);
	assert_int_equal(clip_decode(p, count_frame, &c, NULL, err, sizeof err), 0);
	assert_int_equal(c.frames, 3);
	assert_int_equal(c.width, 48);
	memset(&c, 0, sizeof c);
	snprintf(p, sizeof p, "%s/set/inspect/ref.webm", dir);
	assert_int_equal(clip_decode(p, count_frame, &c, NULL, err, sizeof err), 0);
	assert_int_equal(c.frames, 3);
	assert_int_equal(c.width, 2 * 48 + 2); /* side by side with a 2-pixel gap */
	/* Unknown and not-yet-implemented variants are refused before anything is rendered. */
	snprintf(cmd, sizeof cmd, "%s pair --scene turntable --variants nosuch@8 --out %s/bad", TASLAB_BINARY, dir);
	assert_int_equal(tu_run(cmd, out, sizeof out), 2);
	assert_non_null(strstr(out, "nosuch"));
	snprintf(p, sizeof p, "%s/bad", dir);
	assert_false(tu_file_exists(p));
}

/* Runs `cmd` (bounded: `timeout 60`, so a hang fails the test instead of stopping it) and expects exit 2 and one line
 * containing `needle`. */
static void expect_one_line(const char *cmd, const char *needle)
{
	char c[8400];
	snprintf(c, sizeof c, "timeout 60 %s", cmd);
	int st = tu_run(c, out, sizeof out);
	if (st != 2 || tu_count_lines(out) != 1 || !strstr(out, needle))
		fail_msg("'%s' gave %d:\n%s(expected exit 2 and one line with '%s')", c, st, out, needle);
}

/* Issue 31.6: a run frame that is a symlink to /dev/zero made clip and metrics diff spin for ever in OpenImageIO's
 * format probing. Image files are read only when regular (a device, FIFO or folder is refused at once, never opened
 * for a decoder), whole and bounded, into memory, with the format the run's manifest gives its frames: a .png frame
 * that is an EXR is "not a PNG file", not decoded by whichever reader claims it. Also a scene that is /dev/zero and
 * `report --study /dev/null` say what they are. */
static void test_not_regular_frames(void **state)
{
	(void)state;
	char cmd[8192], p[4096];
	const char *dir = tu_tmpdir("clip_not_regular");
	static const struct {
		const char *name, *make, *needle;
	} cases[] = {
		{"zero", "ln -sf /dev/zero %s/frames/000012.%s", "000012.%s: not a regular file (a device)"},
		{"fifo", "rm %s/frames/000012.%s && mkfifo %s/frames/000012.%s", "000012.%s: not a regular file (a pipe)"},
		{"folder", "rm %s/frames/000012.%s && mkdir %s/frames/000012.%s", "000012.%s: not a regular file (a folder)"},
	};
	const char *exts[2] = {"png", "exr"};
	for (size_t i = 0; i < sizeof cases / sizeof *cases; i++)
		for (int e = 0; e < 2; e++) {
			char bad[4200], make[8192], needle[256];
			snprintf(bad, sizeof bad, "%s/%s_%s", dir, cases[i].name, exts[e]);
			snprintf(cmd, sizeof cmd, "cp -r %s %s", run, bad);
			assert_int_equal(system(cmd), 0);
			snprintf(make, sizeof make, cases[i].make, bad, exts[e], bad, exts[e]);
			assert_int_equal(system(make), 0);
			snprintf(needle, sizeof needle, cases[i].needle, exts[e]);
			if (e == 0) { /* clip reads the PNG frames */
				snprintf(cmd, sizeof cmd, "%s clip %s --out %s.webm", TASLAB_BINARY, bad, bad);
				expect_one_line(cmd, needle);
				snprintf(p, sizeof p, "%s.webm", bad);
				assert_false(tu_file_exists(p));
			}
			snprintf(cmd, sizeof cmd, "%s metrics diff --ref %s --test %s --format %s --out %s.diff", TASLAB_BINARY, run,
				 bad, exts[e], bad);
			expect_one_line(cmd, needle);
		}
	/* an EXR under a PNG frame's name: the manifest says PNG, so no other decoder is tried */
	snprintf(cmd, sizeof cmd, "cp -r %s %s/fmt && cp %s/frames/000012.exr %s/fmt/frames/000012.png", run, dir, run, dir);
	assert_int_equal(system(cmd), 0);
	snprintf(cmd, sizeof cmd, "%s clip %s/fmt --out %s/fmt.webm", TASLAB_BINARY, dir, dir);
	expect_one_line(cmd, "000012.png: not a PNG file");
	/* other inputs that are devices */
	snprintf(cmd, sizeof cmd, "%s render --scene /dev/zero --size 32x18 --frames 0:1 --out %s/r", TASLAB_BINARY, dir);
	expect_one_line(cmd, "/dev/zero: not a regular file (a device)");
	snprintf(cmd, sizeof cmd, "%s report %s --study /dev/null", TASLAB_BINARY, dir);
	expect_one_line(cmd, "--study /dev/null: not a regular file");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_clip_bit_exact),
		cmocka_unit_test(test_tonemap_matches_renderer),
		cmocka_unit_test(test_bad_runs),
		cmocka_unit_test(test_pair),
		cmocka_unit_test(test_careless_outputs),
		cmocka_unit_test(test_not_regular_frames),
	};
	return cmocka_run_group_tests(tests, setup, NULL);
}
