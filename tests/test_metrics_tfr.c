/* test_metrics_tfr.c — the TFR analysis writers (metrics_tfr.h) on synthetic analysis results: the pooled fractions
 * in coherence.csv and coherence.json are the counts' ratios, and a full disk is an output error (issue 30.5: it
 * was a bare -1, which `taslab analyze` reported as a bad argument with "fix your command line"), leaving no JSON
 * summary that would mark the folder complete. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "taslab/metrics_tfr.h"
#include "taslab/tl_error.h"
#include "test_util.h"

static const float thresholds[2] = {4.0f, 16.0f};

/* Two frames of 100 and 60 visible samples; for T_i a fraction (i + 1) / 4 of them stays unchanged at every k. */
static analyze_result *fake_frames(void)
{
	analyze_result *fr = calloc(2, sizeof *fr);
	for (int f = 0; f < 2; f++) {
		fr[f].frame = (uint32_t)(10 * f);
		fr[f].width = 10;
		fr[f].height = 10;
		fr[f].threshold_count = 2;
		fr[f].visible = f ? 60 : 100;
		fr[f].visible_prev = f ? 30 : 90;
		for (int i = 0; i < 2; i++)
			for (int k = 0; k <= ANALYZE_HISTORY; k++)
				fr[f].unchanged[i][k] = k ? fr[f].visible * (uint64_t)(i + 1) / 4 : fr[f].visible;
	}
	return fr;
}

static const mtr_tfr_meta meta = {.scene = "s", .camera = "c", .device = "dev", .thresholds = thresholds,
				  .threshold_count = 2, .seconds_per_frame = 0.5};

static void test_coherence_values(void **state)
{
	(void)state;
	char err[512], p[4200];
	analyze_result *fr = fake_frames();
	const char *d = tu_tmpdir("metrics_tfr");
	assert_int_equal(mtr_tfr_write_coherence(fr, 2, &meta, d, false, err, sizeof err), TL_OK);
	snprintf(p, sizeof p, "%s/coherence.csv", d);
	char *csv = tu_read_file(p, NULL);
	assert_non_null(csv);
	/* pooled over both frames: T 4 keeps 25 + 15 of 160, T 16 keeps 50 + 30 */
	assert_non_null(strstr(csv, "T,k,unchanged_samples,visible_samples,fraction_unchanged\n4,1,40,160,0.250000\n"));
	assert_non_null(strstr(csv, "\n16,120,80,160,0.500000\n"));
	free(csv);
	snprintf(p, sizeof p, "%s/coherence.json", d);
	assert_true(tu_file_exists(p));
	free(fr);
}

static void test_full_disk(void **state)
{
	(void)state;
	char err[512], cmd[4400], p[4200];
	analyze_result *fr = fake_frames();
	const char *base = getenv("TASLAB_TMP");
	snprintf(cmd, sizeof cmd, "umount '%s/metrics_tfr_full' 2>/dev/null", base ? base : "/tmp/taslab-tests");
	if (geteuid() == 0 && system(cmd)) { /* a mount left by an interrupted earlier run is gone now */
	}
	const char *d = tu_tmpdir("metrics_tfr_full");
	if (!tu_require(geteuid() == 0, "test_metrics_tfr: a full disk (needs root to mount an 8 KiB tmpfs)")) {
		free(fr);
		skip();
	}
	snprintf(cmd, sizeof cmd, "mount -t tmpfs -o size=8k tmpfs %s 2>/dev/null", d);
	if (!tu_require(system(cmd) == 0, "test_metrics_tfr: a full disk (cannot mount a tmpfs on %s)", d)) {
		free(fr);
		skip();
	}
	/* coherence.csv alone is 2 x 120 rows, about 5 KB; coherence_frames.csv twice that: the disk fills */
	int rc = mtr_tfr_write_coherence(fr, 2, &meta, d, false, err, sizeof err);
	snprintf(p, sizeof p, "%s/coherence.json", d);
	bool summary = tu_file_exists(p);
	snprintf(cmd, sizeof cmd, "umount %s", d);
	assert_int_equal(system(cmd), 0);
	if (rc != TL_ERR_OUTPUT || !strstr(err, "No space") || strchr(err, '\n'))
		fail_msg("a full disk: rc %d (%s), message '%s'", rc, tl_strerror(rc), err);
	assert_false(summary);
	free(fr);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_coherence_values),
		cmocka_unit_test(test_full_disk),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
