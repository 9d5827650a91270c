/* cmd_metrics.c — `taslab metrics diff|jnd`: frame-sequence comparison and JND maths (metrics/). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "taslab/colour.h"
#include "taslab/metrics.h"
#include "taslab/metrics_diff.h"
#include "taslab/metrics_runs.h"

static void metrics_usage(FILE *out)
{
	fprintf(out,
		"usage: taslab metrics diff --ref A --test B --out DIR [options]\n"
		"       taslab metrics runs --out DIR [--baseline RUN] RUN...\n"
		"       taslab metrics jnd --n N --ref-preferred R [--ties K] [--confidence 0.95]\n\n"
		"diff: compares two frame sequences (run folders or folders of images, same frame names and sizes)\n"
		"  and writes DIR/frames.csv (frame,maxrgb_mean,maxrgb_p50,maxrgb_p95,maxrgb_p99,maxrgb_max,\n"
		"  exceed_2..exceed_64,psnr,ssim,flicker_mean) and DIR/summary.json (the same, pooled over frames).\n"
		"  --format png|exr    compare the display PNGs (default) or the EXRs through the display transform\n"
		"  --ocio-config F, --display D, --view V   display transform for --format exr\n"
		"  --heatmaps          DIR/heatmaps/NNNNNN.png: max-RGB difference maps with a legend\n"
		"  --heatmap-max V     colour scale maximum in code values (default 64)\n"
		"  --plots             DIR/plots/frames.png, exceed.png, distribution.png (gnuplot)\n"
		"  DIR/distribution.csv: the pooled distribution of d in 1-code-value bins (always written)\n"
		"  --threads N         worker threads (default: all cores)\n"
		"runs: from each run's stats.csv: reuse %%, shader invocations and their reduction against the\n"
		"  baseline (default: the first ref run) in the paper's Table 1 layout, median GPU frame time and\n"
		"  speedup against ref (same scene and camera), late/early/on-time/unchanged sums when present;\n"
		"  writes DIR/runs.csv, runs.json, table1.md and per-T plots (reduction, reuse, speedup .png).\n"
		"jnd: p_ref = (R + K/2)/N with a Wilson interval, JND = Phi^-1(p)/Phi^-1(0.75) (p clamped half an\n"
		"  observation from 0 and 1 so the JND stays finite); prints JSON.\n");
}

static int diff_cmd(int argc, char **argv)
{
	mtr_diff_desc d = {0};
	colour_desc cd = {0};
	char err[1024];
	for (int i = 2; i < argc; i++) {
		const char *a = argv[i];
		const char *v = i + 1 < argc ? argv[i + 1] : NULL;
		if (!strcmp(a, "--heatmaps"))
			d.heatmaps = true;
		else if (!strcmp(a, "--plots"))
			d.plots = true;
		else if (v && !strcmp(a, "--ref"))
			d.ref = v, i++;
		else if (v && !strcmp(a, "--test"))
			d.test = v, i++;
		else if (v && !strcmp(a, "--out"))
			d.out = v, i++;
		else if (v && !strcmp(a, "--ocio-config"))
			cd.config_path = v, i++;
		else if (v && !strcmp(a, "--display"))
			cd.display = v, i++;
		else if (v && !strcmp(a, "--view"))
			cd.view = v, i++;
		else if (v && !strcmp(a, "--format")) {
			if (strcmp(v, "png") && strcmp(v, "exr")) {
				fprintf(stderr, "taslab metrics: --format is png or exr, not '%s'\n", v);
				return CLI_EXIT_USAGE;
			}
			d.format = !strcmp(v, "exr") ? MTR_FORMAT_EXR : MTR_FORMAT_PNG;
			i++;
		} else if (v && (!strcmp(a, "--heatmap-max") || !strcmp(a, "--threads"))) {
			double x;
			if (cli_parse_float(v, a, !strcmp(a, "--threads") ? 1 : 1e-6, !strcmp(a, "--threads") ? 64 : 1e6, &x, err,
					    sizeof err)) {
				fprintf(stderr, "taslab metrics: %s\n", err);
				return CLI_EXIT_USAGE;
			}
			if (!strcmp(a, "--threads"))
				d.threads = (int)x;
			else
				d.heatmap_max = x;
			i++;
		} else {
			fprintf(stderr, "taslab metrics diff: unexpected argument '%s' (see 'taslab metrics --help')\n", a);
			return CLI_EXIT_USAGE;
		}
	}
	if (!d.ref || !d.test || !d.out) {
		fprintf(stderr, "taslab metrics diff: --ref, --test and --out are required (see 'taslab metrics --help')\n");
		return CLI_EXIT_USAGE;
	}
	colour *c = NULL;
	if (d.format == MTR_FORMAT_EXR) {
		if (colour_create(&cd, &c, err, sizeof err)) {
			fprintf(stderr, "taslab metrics: %s\n", err);
			return CLI_EXIT_USAGE;
		}
		d.colour = c;
	}
	mtr_diff_result r;
	int rc = mtr_diff_run(&d, &r, err, sizeof err);
	colour_destroy(&c);
	if (rc) {
		fprintf(stderr, "taslab metrics: %s\n", err);
		return CLI_EXIT_FAILURE;
	}
	fprintf(stderr,
		"taslab: %zu frame pairs in %.2f s (%.1f pairs/s): max-RGB mean %.3f, p99 %.3f, max %.0f; exceed_8 %.5f; "
		"PSNR %.2f dB, SSIM %.5f -> %s/frames.csv, summary.json\n",
		r.frames, r.seconds, r.frames / r.seconds, r.pooled.mean, r.pooled.p99, r.pooled.max, r.pooled.exceed[2],
		r.pooled.psnr, r.pooled.ssim, d.out);
	return CLI_EXIT_OK;
}

static int jnd_cmd(int argc, char **argv)
{
	double n = -1, r = -1, k = 0, conf = 0.95;
	char err[256];
	for (int i = 2; i < argc; i++) {
		double *dst = !strcmp(argv[i], "--n") ? &n : !strcmp(argv[i], "--ref-preferred") ? &r
						: !strcmp(argv[i], "--ties") ? &k : !strcmp(argv[i], "--confidence") ? &conf : NULL;
		if (!dst || i + 1 >= argc || cli_parse_float(argv[i + 1], argv[i], 0, 1e12, dst, err, sizeof err)) {
			fprintf(stderr, "taslab metrics jnd: bad argument '%s' (see 'taslab metrics --help')\n", argv[i]);
			return CLI_EXIT_USAGE;
		}
		i++;
	}
	mtr_jnd j;
	if (n <= 0 || r < 0 || mtr_jnd_from_counts(r, k, n, conf, &j)) {
		fprintf(stderr, "taslab metrics jnd: need --n > 0, 0 <= --ref-preferred + --ties <= --n, 0 < --confidence < 1\n");
		return CLI_EXIT_USAGE;
	}
	printf("{\"n\": %g, \"p_ref\": %.6f, \"p_ref_lo\": %.6f, \"p_ref_hi\": %.6f, \"jnd\": %.6f, \"jnd_lo\": %.6f, "
	       "\"jnd_hi\": %.6f, \"clamped\": %s}\n",
	       n, j.p, j.p_lo, j.p_hi, j.jnd, j.jnd_lo, j.jnd_hi, j.clamped ? "true" : "false");
	return CLI_EXIT_OK;
}

static int runs_cmd(int argc, char **argv)
{
	const char *out = NULL, *baseline = NULL;
	const char *runs[256];
	size_t n = 0;
	char err[1024];
	for (int i = 2; i < argc; i++) {
		if (!strcmp(argv[i], "--out") && i + 1 < argc)
			out = argv[++i];
		else if (!strcmp(argv[i], "--baseline") && i + 1 < argc)
			baseline = argv[++i];
		else if (argv[i][0] != '-' && n < 256)
			runs[n++] = argv[i];
		else {
			fprintf(stderr, "taslab metrics runs: unexpected argument '%s' (see 'taslab metrics --help')\n", argv[i]);
			return CLI_EXIT_USAGE;
		}
	}
	int base = -1;
	if (baseline) {
		runs[n] = baseline;
		base = (int)n++;
	}
	if (!out || n == 0) {
		fprintf(stderr, "taslab metrics runs: need --out DIR and at least one run folder\n");
		return CLI_EXIT_USAGE;
	}
	mtr_run_summary *s = calloc(n, sizeof *s);
	if (!s || mtr_runs_summarise(runs, n, base, s, err, sizeof err) || mtr_runs_write(s, n, out, err, sizeof err)) {
		fprintf(stderr, "taslab metrics runs: %s\n", s ? err : "out of memory");
		free(s);
		return CLI_EXIT_FAILURE;
	}
	if (mtr_runs_plot(s, n, out, err, sizeof err))
		fprintf(stderr, "taslab metrics runs: note: %s\n", err);
	for (size_t i = 0; i < n; i++)
		fprintf(stderr, "%-40s %-5s T=%-3g reuse %6.2f%%  invocations %.0f (reduction %.1f%%)  %.1f ms  speedup %.2fx\n",
			s[i].path, s[i].method, s[i].threshold, 100 * s[i].reuse_mean, s[i].invocations,
			100 * s[i].invocation_reduction, s[i].gpu_ms_median, s[i].speedup_vs_ref);
	free(s);
	return CLI_EXIT_OK;
}

static int metrics_run(int argc, char **argv)
{
	if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
		metrics_usage(argc < 2 ? stderr : stdout);
		return argc < 2 ? CLI_EXIT_USAGE : CLI_EXIT_OK;
	}
	if (!strcmp(argv[1], "diff"))
		return diff_cmd(argc, argv);
	if (!strcmp(argv[1], "jnd"))
		return jnd_cmd(argc, argv);
	if (!strcmp(argv[1], "runs"))
		return runs_cmd(argc, argv);
	fprintf(stderr, "taslab metrics: unknown subcommand '%s' (diff, runs or jnd; see 'taslab metrics --help')\n", argv[1]);
	return CLI_EXIT_USAGE;
}

const cli_command cli_cmd_metrics = {"metrics", "compare frame sequences (max-RGB, PSNR, SSIM, flicker), JND maths",
				     metrics_run, metrics_usage};
