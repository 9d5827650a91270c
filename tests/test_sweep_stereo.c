/* test_sweep_stereo.c — `taslab sweep --stereo` and `taslab report --mono` (issue 25), on lavapipe with the
 * validation layer, at 32x24 per eye, 2 frames: a stereo sweep records stereo and ipd in sweep.json (part of its
 * identity: resuming its folder without --stereo, or a mono sweep's with it, is refused with one line), its runs are
 * stereo (frames/L, frames/R), its metrics are per eye then pooled, its report's thumbnails are side by side (2W x H);
 * `report --mono` writes stereo_vs_mono.csv beside a mono sweep of the same runs: ref shades twice its mono samples
 * (both eyes see the whole plane), the shared atlas between 1 and 2 times; the report's Stereo section is on the page;
 * bad combinations (--ipd without --stereo, --mono of a mono sweep, a stereo sweep as --mono) get one line. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

#include "taslab/imageio.h"

static char out[1 << 16];

#define COMMON "--scenes %s/tests/data/stereo_plane.json --variants ref,sa --frames 0:2 --size 32x24 --device lavapipe " \
	       "--validation --metrics maxrgb,psnr --quiet"

static int run(const char *fmt, const char *a, const char *b)
{
	char args[8192], cmd[9000];
	snprintf(args, sizeof args, fmt, a, b);
	snprintf(cmd, sizeof cmd, "%s %s", TASLAB_BINARY, args);
	return tu_run(cmd, out, sizeof out);
}

static void expect_one_line(int st, const char *needle)
{
	if (st == 0 || tu_count_lines(out) != 1 || !strstr(out, needle))
		fail_msg("exit %d, printed:\n%s\nexpected one line containing '%s'", st, out, needle);
}

/* The value of column `col` in the row of stereo_vs_mono.csv starting with "scene,camera," and ending the variant
 * field with `variant`. */
static double csv_value(const char *csv, const char *variant, int col)
{
	char key[128];
	snprintf(key, sizeof key, ",%s,", variant);
	for (const char *line = strchr(csv, '\n'); line && line[1]; line = strchr(line + 1, '\n')) {
		const char *end = strchr(line + 1, '\n');
		const char *hit = strstr(line + 1, key);
		if (!hit || (end && hit > end))
			continue;
		const char *p = line + 1;
		for (int c = 0; c < col; c++)
			p = strchr(p, ',') + 1;
		return strtod(p, NULL);
	}
	fail_msg("stereo_vs_mono.csv: no row of %s", variant);
	return 0;
}

static void test_sweep_stereo(void **state)
{
	(void)state;
	char dir[4096], st[4096], mono[4096], p[4300];
	snprintf(dir, sizeof dir, "%s", tu_tmpdir("sweep_stereo"));
	snprintf(st, sizeof st, "%s/st", dir);
	snprintf(mono, sizeof mono, "%s/mono", dir);
	char common[4096];
	snprintf(common, sizeof common, COMMON, TASLAB_SOURCE_DIR);
	/* bad input first: nothing rendered */
	expect_one_line(run("sweep %s --ipd 0.07 --out %s", common, st), "ipd needs stereo");
	snprintf(p, sizeof p, "%s/sweep.json", st);
	assert_false(tu_file_exists(p));
	if (run("sweep %s --stereo --out %s", common, st))
		fail_msg("stereo sweep:\n%s", out);
	if (run("sweep %s --out %s", common, mono))
		fail_msg("mono sweep:\n%s", out);
	char *spec = tu_read_file(p, NULL);
	assert_non_null(spec);
	assert_non_null(strstr(spec, "\"stereo\": true"));
	assert_non_null(strstr(spec, "\"ipd\": 0.063"));
	free(spec);
	/* the identity: the other kind in the same folder is another sweep */
	expect_one_line(run("sweep %s --out %s", common, st), "stereo on vs off");
	expect_one_line(run("sweep %s --stereo --out %s", common, mono), "stereo off vs on");
	/* stereo runs, metrics per eye then pooled */
	snprintf(p, sizeof p, "%s/runs/stereo_plane/front/sa/frames/R/000001.png", st);
	assert_true(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/metrics/stereo_plane/front/sa/R/summary.json", st);
	assert_true(tu_file_exists(p));
	snprintf(p, sizeof p, "%s/metrics/stereo_plane/front/sa/summary.json", st);
	char *pooled = tu_read_file(p, NULL);
	assert_non_null(pooled);
	assert_non_null(strstr(pooled, "\"stereo\": true"));
	free(pooled);
	/* report --mono */
	if (run("report %s --mono %s --quiet", st, mono))
		fail_msg("report --mono:\n%s", out);
	snprintf(p, sizeof p, "%s/stereo_vs_mono.csv", st);
	char *csv = tu_read_file(p, NULL);
	assert_non_null(csv);
	/* columns: scene,camera,camera_motion,variant,speedup_mono,speedup_stereo,speedup_ratio,shaded_per_frame_mono,
	 * shaded_per_frame_stereo,shaded_ratio,... */
	double ref_ratio = csv_value(csv, "ref", 9), sa_ratio = csv_value(csv, "sa", 9);
	fprintf(stderr, "shaded stereo / mono: ref %.4f, sa %.4f\n", ref_ratio, sa_ratio);
	assert_true(ref_ratio > 1.9 && ref_ratio < 2.1);
	assert_true(sa_ratio >= 1.0 && sa_ratio <= 2.0 && sa_ratio < ref_ratio);
	assert_true(csv_value(csv, "ref", 6) == 1.0); /* ref against itself in both */
	snprintf(p, sizeof p, "%s/report/index.html", st);
	char *page = tu_read_file(p, NULL);
	assert_non_null(page);
	assert_non_null(strstr(page, "<section id=\"stereo\">"));
	assert_non_null(strstr(page, "speedup stereo"));
	/* the Stereo table: per variant its mono and stereo speedups vs ref side by side, the CSV's numbers */
	const char *sec = strstr(page, "<section id=\"stereo\">");
	for (int k = 0; k < 2; k++) {
		const char *v = k ? "sa" : "ref";
		char row[256];
		snprintf(row, sizeof row, "<td class=\"l\">%s</td><td>%.2f×</td><td>%.2f×</td><td>%.2f</td>", v,
			 csv_value(csv, v, 4), csv_value(csv, v, 5), csv_value(csv, v, 6));
		if (!strstr(sec, row))
			fail_msg("the report's Stereo section has no row %s", row);
	}
	/* the speedup plot (gnuplot, like the report's other plots): on the page in the Stereo section, its data the CSV's
	 * speedups mono and stereo per run, its SVG drawn with both series */
	if (system("command -v gnuplot >/dev/null") == 0) {
		const char *img = strstr(sec, "<img src=\"plots/stereo--speedup.svg\"");
		assert_non_null(img);
		assert_true(img < strstr(sec, "</section>"));
		snprintf(p, sizeof p, "%s/report/data/stereo--speedup.csv", st);
		char *data = tu_read_file(p, NULL);
		assert_non_null(data);
		for (int k = 0; k < 2; k++) {
			const char *v = k ? "sa" : "ref";
			char row[256];
			snprintf(row, sizeof row, " %s\",%.4f,%.4f\n", v, csv_value(csv, v, 4), csv_value(csv, v, 5));
			if (!strstr(data, row))
				fail_msg("stereo--speedup.csv has no row ending %s:\n%s", row, data);
		}
		free(data);
		snprintf(p, sizeof p, "%s/report/plots/stereo--speedup.svg", st);
		char *svg = tu_read_file(p, NULL);
		assert_non_null(svg);
		assert_non_null(strstr(svg, "<svg"));
		assert_non_null(strstr(svg, ">mono<"));
		assert_non_null(strstr(svg, ">stereo<"));
		free(svg);
	}
	free(csv);
	free(page);
	/* the report's thumbnails of a stereo run are its side-by-side frames */
	snprintf(p, sizeof p, "find %s/report/img -name '*--ref--*.png' | head -1 > %s/thumb.txt", st, dir);
	assert_int_equal(system(p), 0);
	snprintf(p, sizeof p, "%s/thumb.txt", dir);
	char *thumb = tu_read_file(p, NULL);
	assert_non_null(thumb);
	thumb[strcspn(thumb, "\n")] = 0;
	uint32_t w = 0, h = 0;
	uint8_t *px = NULL;
	char err[512];
	if (imageio_read_rgb8(thumb, &w, &h, &px, err, sizeof err))
		fail_msg("%s", err);
	assert_int_equal(w * 24, h * 64); /* 2W x H: 64 x 24 scaled */
	free(px);
	free(thumb);
	/* --mono the wrong way round or of itself */
	expect_one_line(run("report %s --mono %s", mono, st), "this sweep is not stereo");
	expect_one_line(run("report %s --mono %s", st, st), "is a stereo sweep");
}

int main(void)
{
	const struct CMUnitTest tests[] = {cmocka_unit_test(test_sweep_stereo)};
	return tu_finish(cmocka_run_group_tests(tests, NULL, NULL));
}
