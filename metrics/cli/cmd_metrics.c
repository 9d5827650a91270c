/* cmd_metrics.c — `taslab metrics diff|runs|jnd`: frame-sequence comparison, run statistics (Table 1,
 * Fig. 12) and JND maths (metrics/). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "taslab/colour.h"
#include "taslab/metrics.h"
#include "taslab/metrics_diff.h"
#include "taslab/metrics_flip.h"
#include "taslab/metrics_runs.h"
#include "taslab/tl_fs.h"

/* ---- diff ---- */

/* metrics_diff_opts (commands.h) plus the metric selection and options. Kept here until commands.h carries the
 * two fields (the parser tests reach the base struct at offset 0 as before). */
typedef struct diff_cli_opts {
	metrics_diff_opts base;
	const char *metrics;
	double ppd;
} diff_cli_opts;

#define DIFF_OFF(f) (offsetof(diff_cli_opts, base) + offsetof(metrics_diff_opts, f))

static const cli_opt diff_options[] = {
	{.name = "ref", .arg = "A",
	 .help = "reference frames: a run folder or a folder of images",
	 .type = CLI_STRING, .offset = DIFF_OFF(ref)},
	{.name = "test", .arg = "B",
	 .help = "test frames (same frame names and sizes)",
	 .type = CLI_STRING, .offset = DIFF_OFF(test)},
	{.name = "out", .arg = "DIR",
	 .help = "output folder",
	 .type = CLI_STRING, .offset = DIFF_OFF(out)},
	{.name = "format", .arg = "png|exr",
	 .help = "compare the display PNGs (default) or the EXRs through the display transform",
	 .type = CLI_STRING, .offset = DIFF_OFF(format)},
	{.name = "heatmaps", .arg = NULL,
	 .help = "DIR/heatmaps/NNNNNN.png: max-RGB difference maps with a legend; with flip also heatmaps/flip/",
	 .type = CLI_FLAG, .offset = DIFF_OFF(heatmaps)},
	{.name = "heatmap-max", .arg = "V",
	 .help = "colour scale maximum in code values (default 64)",
	 .type = CLI_DOUBLE, .offset = DIFF_OFF(heatmap_max), .lo = 1e-6, .hi = 1e6},
	{.name = "plots", .arg = NULL,
	 .help = "DIR/plots/frames.png, exceed.png, distribution.png (gnuplot)",
	 .type = CLI_FLAG, .offset = DIFF_OFF(plots)},
	{.name = "threads", .arg = "N",
	 .help = "worker threads (default: all cores)",
	 .type = CLI_UINT, .offset = DIFF_OFF(threads), .lo = 1, .hi = 64},
	{.name = "metrics", .arg = "LIST",
	 .help = "metrics to compute, comma-separated: maxrgb,psnr,ssim,flicker,flip or all (default); the "
		 "others' columns stay, empty / null",
	 .type = CLI_STRING, .offset = offsetof(diff_cli_opts, metrics)},
	{.name = "ppd", .arg = "F",
	 .help = "FLIP: pixels per degree (default 67.0206: 0.7 m from a 0.7 m wide 3840-pixel monitor)",
	 .type = CLI_DOUBLE, .offset = offsetof(diff_cli_opts, ppd), .lo = 1e-3, .hi = 1000},
	{0},
};

static void diff_defaults(void *opts, cli_setup_opts *setup)
{
	(void)setup;
	diff_cli_opts *o = opts;
	o->base.format = "png";
	o->metrics = "all";
	o->ppd = MTR_FLIP_PPD_DEFAULT;
}

/* A run folder (manifest.json or frames/ in it) must hold exactly its run: no command's --out goes inside one. */
static int out_outside_runs(const char *out, const char *const *inputs, size_t n, cli_ctx *ctx)
{
	for (size_t i = 0; i < n; i++) {
		char m[4200], f[4200];
		snprintf(m, sizeof m, "%s/manifest.json", inputs[i]);
		snprintf(f, sizeof f, "%s/frames", inputs[i]);
		if ((tl_is_file(m) || tl_is_dir(f)) && tl_path_inside(out, inputs[i]))
			return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG,
					"--out %s lies inside the run folder %s, which must hold only its run (write elsewhere)", out,
					inputs[i]);
	}
	return TL_OK;
}

static int diff_validate(void *opts, cli_ctx *ctx)
{
	diff_cli_opts *x = opts;
	metrics_diff_opts *o = &x->base;
	uint32_t mask;
	if (mtr_metric_parse(x->metrics, &mask, ctx->err, sizeof ctx->err))
		return TL_ERR_ARG; /* "--metrics: unknown metric 'X' (known: maxrgb,psnr,ssim,flicker,flip, or all)" */
	if (!o->ref || !o->test || !o->out)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG,
				"--ref, --test and --out are required (see 'taslab metrics diff --help')");
	if (strcmp(o->format, "png") && strcmp(o->format, "exr"))
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--format is png or exr, not '%s'", o->format);
	const char *inputs[2] = {o->ref, o->test};
	return out_outside_runs(o->out, inputs, 2, ctx);
}

static int diff_main(void *opts, cli_ctx *ctx)
{
	diff_cli_opts *x = opts;
	metrics_diff_opts *o = &x->base;
	const mtr_option_value options[] = {{"ppd", x->ppd}};
	mtr_diff_desc d = {.ref = o->ref, .test = o->test, .out = o->out, .heatmaps = o->heatmaps, .plots = o->plots,
			   .heatmap_max = o->heatmap_max, .threads = (int)o->threads,
			   .format = !strcmp(o->format, "exr") ? MTR_FORMAT_EXR : MTR_FORMAT_PNG, .colour = ctx->setup.colour,
			   .metrics = x->metrics, .options = options, .option_count = 1};
	mtr_diff_result r;
	int rc = mtr_diff_run(&d, &r, ctx->err, sizeof ctx->err);
	if (rc)
		return rc;
	/* One line: the pooled values of the metrics that were computed (the files hold everything). */
	char line[512] = "";
	size_t n = 0;
	const mtr_frame_stats *p = &r.pooled;
	if (!isnan(p->mean))
		n += (size_t)snprintf(line + n, sizeof line - n, "; max-RGB mean %.3f, p99 %.3f, max %.0f, exceed_8 %.5f",
				      p->mean, p->p99, p->max, p->exceed[2]);
	if (n < sizeof line && !isnan(p->psnr))
		n += (size_t)snprintf(line + n, sizeof line - n, "; PSNR %.2f dB", p->psnr);
	if (n < sizeof line && !isnan(p->ssim))
		n += (size_t)snprintf(line + n, sizeof line - n, "; SSIM %.5f", p->ssim);
	if (n < sizeof line && !isnan(p->flicker_mean))
		n += (size_t)snprintf(line + n, sizeof line - n, "; flicker %.3f", p->flicker_mean);
	if (n < sizeof line && !isnan(p->flip_mean))
		n += (size_t)snprintf(line + n, sizeof line - n, "; FLIP %.5f", p->flip_mean);
	fprintf(stderr, "taslab: %zu frame pairs%s in %.2f s (%.1f pairs/s)%s -> %s/frames.csv, summary.json%s\n",
		r.frames, r.views > 1 ? " per eye" : "", r.seconds, (double)(r.frames * r.views) / r.seconds,
		line, o->out, r.views > 1 ? " (both eyes pooled; each eye in L/ and R/)" : "");
	return TL_OK;
}

static const cli_command metrics_diff = {
	.name = "metrics diff",
	.summary = "compare two frame sequences: max-RGB, exceedance, PSNR, SSIM, flicker, FLIP",
	.synopsis = "taslab metrics diff --ref A --test B --out DIR [options]",
	.description = "Compares two frame sequences (run folders or folders of images, same frame names and sizes) and\n"
		       "writes DIR/frames.csv (frame,maxrgb_mean,maxrgb_p50,maxrgb_p95,maxrgb_p99,maxrgb_max,\n"
		       "exceed_2..exceed_64,psnr,ssim,flicker_mean,flip_mean), DIR/summary.json (the same, pooled over\n"
		       "frames, plus FLIP's weighted median and quartiles, min and max over all pixels) and\n"
		       "DIR/distribution.csv (the pooled distribution of d in 1-code-value bins). --metrics picks the\n"
		       "metrics (one plug-in each); the column layout never changes. Two stereo runs: each eye\n"
		       "against the same eye into DIR/L/ and DIR/R/ (every file above), both eyes pooled into DIR/\n"
		       "(frames.csv: each frame's eyes pooled); a stereo run against a mono one is refused.",
	.options = diff_options,
	.opts_size = sizeof(diff_cli_opts),
	.defaults = diff_defaults,
	.validate = diff_validate,
	.needs = CLI_NEED_COLOUR, /* --format exr compares through the display transform */
	.run = diff_main,
};

/* ---- runs ---- */

static const cli_opt runs_options[] = {
	{.name = "out", .arg = "DIR",
	 .help = "output folder",
	 .type = CLI_STRING, .offset = offsetof(metrics_runs_opts, out)},
	{.name = "baseline", .arg = "VARIANT",
	 .help = "the variant reductions are relative to, per scene, camera path, frames and size (default: sa for "
		 "sa/sau/tasa runs when an sa run is given, as the paper's Table 1; ref otherwise)",
	 .type = CLI_STRING, .offset = offsetof(metrics_runs_opts, baseline)},
	{0},
};

static int runs_validate(void *opts, cli_ctx *ctx)
{
	metrics_runs_opts *o = opts;
	if (!o->out)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--out DIR is required (see 'taslab metrics runs --help')");
	return out_outside_runs(o->out, ctx->pos, ctx->npos, ctx);
}

static int runs_main(void *opts, cli_ctx *ctx)
{
	metrics_runs_opts *o = opts;
	const char *const *runs = (const char *const *)ctx->pos;
	size_t n = ctx->npos;
	mtr_run_summary *s = calloc(n, sizeof *s);
	if (!s)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_NOMEM, "out of memory");
	int rc = mtr_runs_summarise(runs, n, o->baseline, s, ctx->err, sizeof ctx->err);
	if (!rc)
		rc = mtr_runs_write(s, n, o->out, ctx->err, sizeof ctx->err);
	if (!rc) {
		char note[512];
		if (mtr_runs_plot(s, n, o->out, note, sizeof note))
			fprintf(stderr, "taslab metrics runs: note: %s\n", note);
		for (size_t i = 0; i < n; i++) {
			char red[48] = "no baseline run", sp[32] = "no ref run";
			if (isfinite(s[i].reduction))
				snprintf(red, sizeof red, "reduction %.1f%% vs %s", 100 * s[i].reduction, s[i].baseline);
			if (isfinite(s[i].speedup_vs_ref))
				snprintf(sp, sizeof sp, "speedup %.2fx", s[i].speedup_vs_ref);
			fprintf(stderr, "%-40s %-14s reuse %6.2f%%  shaded %.0f/frame (%s)  %.1f ms  %s\n", s[i].path,
				s[i].variant, 100 * s[i].reuse_mean, s[i].shaded_samples / (double)s[i].frames, red,
				s[i].gpu_ms_median, sp);
		}
	}
	free(s);
	return rc;
}

static const cli_command metrics_runs = {
	.name = "metrics runs",
	.summary = "reuse, Table 1 reductions and speedups from runs' stats.csv",
	.synopsis = "taslab metrics runs --out DIR [--baseline VARIANT] RUN...",
	.description = "From each run's stats.csv: reuse %, shaded samples (the methods' own counters) and their reduction\n"
		       "against the baseline variant's run of the same scene, path, frames and size (paper Table 1), median\n"
		       "GPU frame time and speedup against ref, late samples (--truth) and late/early/on-time/unchanged sums\n"
		       "when present; writes DIR/runs.csv, runs.json, table1.md and per-T plots (reduction, reuse, speedup).",
	.options = runs_options,
	.opts_size = sizeof(metrics_runs_opts),
	.validate = runs_validate,
	.min_pos = 1,
	.max_pos = CLI_MAX_POS - 1,
	.pos_help = "RUN... (run folders)",
	.run = runs_main,
};

/* ---- jnd ---- */

static const cli_opt jnd_options[] = {
	{.name = "n", .arg = "N",
	 .help = "answers in all (a whole number > 0)",
	 .type = CLI_U64, .offset = offsetof(metrics_jnd_opts, n), .lo = 1, .hi = 1e12},
	{.name = "ref-preferred", .arg = "R",
	 .help = "answers preferring the reference (a whole number)",
	 .type = CLI_U64, .offset = offsetof(metrics_jnd_opts, ref_preferred), .lo = 0, .hi = 1e12},
	{.name = "ties", .arg = "K",
	 .help = "answers 'same' (a whole number)",
	 .type = CLI_U64, .offset = offsetof(metrics_jnd_opts, ties), .lo = 0, .hi = 1e12},
	{.name = "confidence", .arg = "C",
	 .help = "confidence of the interval (default 0.95)",
	 .type = CLI_DOUBLE, .offset = offsetof(metrics_jnd_opts, confidence), .lo = 1e-9, .hi = 1 - 1e-9},
	{0},
};

static void jnd_defaults(void *opts, cli_setup_opts *setup)
{
	(void)setup;
	metrics_jnd_opts *o = opts;
	o->n = 0;
	o->ref_preferred = UINT64_MAX;
	o->confidence = 0.95;
}

static int jnd_validate(void *opts, cli_ctx *ctx)
{
	metrics_jnd_opts *o = opts;
	if (o->n == 0 || o->ref_preferred == UINT64_MAX || o->ref_preferred + o->ties > o->n)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG,
				"need --n > 0 and --ref-preferred with 0 <= --ref-preferred + --ties <= --n");
	return TL_OK;
}

static int jnd_main(void *opts, cli_ctx *ctx)
{
	metrics_jnd_opts *o = opts;
	mtr_jnd j;
	if (mtr_jnd_from_counts((double)o->ref_preferred, (double)o->ties, (double)o->n, o->confidence, &j))
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "counts out of range");
	printf("{\"n\": %llu, \"p_ref\": %.6f, \"p_ref_lo\": %.6f, \"p_ref_hi\": %.6f, \"jnd\": %.6f, \"jnd_lo\": %.6f, "
	       "\"jnd_hi\": %.6f, \"clamped\": %s}\n",
	       (unsigned long long)o->n, j.p, j.p_lo, j.p_hi, j.jnd, j.jnd_lo, j.jnd_hi, j.clamped ? "true" : "false");
	return TL_OK;
}

static const cli_command metrics_jnd = {
	.name = "metrics jnd",
	.summary = "p_ref with a Wilson interval and the JND from answer counts",
	.synopsis = "taslab metrics jnd --n N --ref-preferred R [--ties K] [--confidence 0.95]",
	.description = "p_ref = (R + K/2)/N with a Wilson interval, JND = Phi^-1(p)/Phi^-1(0.75) (p clamped half an\n"
		       "observation from 0 and 1 so the JND stays finite); prints JSON.",
	.options = jnd_options,
	.opts_size = sizeof(metrics_jnd_opts),
	.defaults = jnd_defaults,
	.validate = jnd_validate,
	.run = jnd_main,
};

static const cli_command *const metrics_subs[] = {&metrics_diff, &metrics_runs, &metrics_jnd, NULL};

const cli_command cli_cmd_metrics = {
	.name = "metrics",
	.summary = "compare frame sequences (max-RGB, PSNR, SSIM, flicker, FLIP), run statistics, JND maths",
	.synopsis = "taslab metrics diff|runs|jnd [options]",
	.subcommands = metrics_subs,
};
