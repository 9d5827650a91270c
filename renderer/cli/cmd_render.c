/* cmd_render.c — `taslab render`: renders a clip of a scene/camera path with a method into a run folder
 * (DESIGN section 5). Every argument is checked and the scene loaded before anything is written, so bad
 * input leaves no output behind. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "commands.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/tl_clock.h"
#include "taslab/vkdev.h"

/* ---- method options on the command line (shared with `pair` and `sweep`) ---- */

static int take_method_arg(const cli_opt *o, const char *value, void *field, char *err, size_t err_size)
{
	cli_method_args *a = field;
	if (a->n == sizeof a->name / sizeof a->name[0])
		return tl_error(err, err_size, TL_ERR_ARG, "too many method options");
	a->name[a->n] = o->name;
	a->value[a->n++] = value;
	return TL_OK;
}

const cli_opt *cli_method_options(size_t offset)
{
	/* The union of the registry's option tables (an option shared by several methods appears once). */
	static cli_opt table[64];
	static size_t built_for = (size_t)-1;
	if (built_for == offset)
		return table;
	size_t n = 0, count;
	const method_info *const *m = method_list(&count);
	for (size_t i = 0; i < count; i++)
		for (size_t k = 0; k < m[i]->option_count && n + 1 < sizeof table / sizeof table[0]; k++) {
			const method_option *mo = &m[i]->options[k];
			size_t j = 0;
			while (j < n && strcmp(table[j].name, mo->name))
				j++;
			if (j < n)
				continue;
			table[n++] = (cli_opt){.name = mo->name, .arg = mo->type == METHOD_OPT_BOOL ? NULL : mo->arg,
					       .help = mo->help, .type = CLI_CUSTOM, .offset = offset, .parse = take_method_arg};
		}
	table[n] = (cli_opt){0};
	built_for = offset;
	return table;
}

int cli_method_config(const char *method, const cli_method_args *args, method_config *out, char *err, size_t err_size)
{
	int rc = method_find(method) ? method_config_init(out, method, err, err_size)
				     : method_config_parse_variant(out, method, err, err_size);
	/* What the variant sets (tarc@8's T) is not set again by an option: `--method tarc@8 --threshold 16` rendered
	 * T = 16 under the name tarc@8 (issue 31.9). */
	const uint32_t from_variant = rc ? 0 : out->given;
	for (size_t i = 0; !rc && args && i < args->n; i++) {
		for (size_t k = 0; k < out->method->option_count; k++)
			if ((from_variant & (1u << k)) && !strcmp(out->method->options[k].name, args->name[i]))
				return tl_error(err, err_size, TL_ERR_ARG,
						"--%s conflicts with --method %s, which sets it already (give one of the two)",
						args->name[i], method);
		rc = method_config_set(out, args->name[i], args->value[i], err, err_size);
	}
	return rc ? rc : method_config_check(out, err, err_size);
}

/* ---- the command ---- */

static const cli_opt render_options[] = {
	{.name = "method", .arg = "M",
	 .help = "rendering method or variant (e.g. ref, tfr, tfr@8; default ref; methods below)",
	 .type = CLI_STRING, .offset = offsetof(render_opts, method)},
	{.name = "out", .arg = "RUN",
	 .help = "output folder (default runs/SCENE-CAMERA-VARIANT)",
	 .type = CLI_STRING, .offset = offsetof(render_opts, out)},
	{.name = "no-exr", .arg = NULL,
	 .help = "do not write EXR frames",
	 .type = CLI_FLAG, .offset = offsetof(render_opts, no_exr)},
	{.name = "no-png", .arg = NULL,
	 .help = "do not write PNG frames",
	 .type = CLI_FLAG, .offset = offsetof(render_opts, no_png)},
	{.name = "decisions", .arg = NULL,
	 .help = "also write RUN/decisions/NNNNNN.png, the reuse decision of every pixel (reuse methods)",
	 .type = CLI_FLAG, .offset = offsetof(render_opts, decisions)},
	{.name = "rate-images", .arg = NULL,
	 .help = "also write RUN/rates/NNNNNN.png, the shading rate of every 16x16 tile, one pixel per tile (VRS "
		 "methods, vref)",
	 .type = CLI_FLAG, .offset = offsetof(render_opts, rate_images)},
	{.name = "trivial-shading", .arg = NULL,
	 .help = "benchmark only: replace shading with base colour output",
	 .type = CLI_FLAG, .offset = offsetof(render_opts, trivial_shading)},
	{.name = "quiet", .arg = NULL,
	 .help = "no progress output",
	 .type = CLI_FLAG, .offset = offsetof(render_opts, quiet)},
	{.name = "stereo", .arg = NULL,
	 .help = "render both eyes (--size per eye): RUN/frames/L/, RUN/frames/R/, RUN/sbs/ side by side",
	 .type = CLI_FLAG, .offset = offsetof(render_opts, stereo)},
	{.name = "ipd", .arg = "M",
	 .help = "with --stereo: distance between the eyes in metres (default 0.063)",
	 .type = CLI_DOUBLE, .offset = offsetof(render_opts, ipd), .lo = 0.0, .hi = RENDER_IPD_MAX},
	{.name = "multiview", .arg = "auto|on|off",
	 .help = "with --stereo: both eyes' visibility pass (sa, sau, tasa) in one VK_KHR_multiview render pass (on) or "
		 "one pass per eye (off); same output; default auto (the measured choice, README \"Multiview\")",
	 .type = CLI_STRING, .offset = offsetof(render_opts, multiview)},
	{0},
};

static const cli_opt *render_dynamic(void) { return cli_method_options(offsetof(render_opts, margs)); }

static void render_defaults(void *opts, cli_setup_opts *setup)
{
	(void)setup;
	((render_opts *)opts)->method = "ref";
	((render_opts *)opts)->ipd = -1.0;
}

static int render_validate(void *opts, cli_ctx *ctx)
{
	render_opts *o = opts;
	int rc = cli_method_config(o->method, &o->margs, &o->config, ctx->err, sizeof ctx->err);
	if (!rc && o->decisions && !o->config.method->decisions)
		rc = tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG,
			      "--decisions: method %s makes no reuse decisions (use rrc, tarc or their variants)",
			      o->config.method->name);
	if (!rc && o->rate_images && !o->config.method->tile_rates)
		rc = tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG,
			      "--rate-images: method %s chooses no tile rates (the VRS methods and vref do)",
			      o->config.method->name);
	if (!rc && o->stereo && o->rate_images)
		rc = tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG,
			      "--rate-images with --stereo: rate images are written for mono runs only");
	if (!rc && o->ipd >= 0.0 && !o->stereo)
		rc = tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--ipd needs --stereo");
	if (!rc && o->stereo && o->decisions)
		rc = tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG,
			      "--decisions with --stereo: decision maps are written for mono runs only");
	if (o->stereo && o->ipd < 0.0)
		o->ipd = RENDER_STEREO_IPD_DEFAULT;
	if (!rc && o->multiview) {
		static const char *const names[] = {[RENDER_MULTIVIEW_AUTO] = "auto", [RENDER_MULTIVIEW_ON] = "on",
						    [RENDER_MULTIVIEW_OFF] = "off"};
		int k = 0;
		while (k < 3 && strcmp(o->multiview, names[k]))
			k++;
		if (k == 3)
			rc = tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--multiview '%s': auto, on or off", o->multiview);
		else if (!o->stereo)
			rc = tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--multiview needs --stereo");
		else
			o->mv = k;
	}
	return rc;
}

/* The methods and each one's own options, from the registry's tables (DESIGN section 4): an option several methods
 * share (--threshold, --period, ...) is listed under each with that method's help, default and range. */
static void methods_help(FILE *out)
{
	size_t n;
	const method_info *const *m = method_list(&n);
	fprintf(out, "\nmethods and their options (--NAME VALUE after --method; a variant token sets the ones marked\n"
		     "'as': tfr@8, rrc/4, tarc-oracle@8):\n");
	for (size_t i = 0; i < n; i++) {
		fprintf(out, "  %-6s %s%s\n", m[i]->name, m[i]->summary, m[i]->available ? "" : " [planned]");
		for (size_t k = 0; k < m[i]->option_count; k++) {
			const method_option *o = &m[i]->options[k];
			char left[64], desc[160], help[640];
			snprintf(left, sizeof left, "--%s%s%s", o->name, o->type != METHOD_OPT_BOOL && o->arg ? " " : "",
				 o->type != METHOD_OPT_BOOL && o->arg ? o->arg : "");
			method_option_describe(o, desc, sizeof desc);
			snprintf(help, sizeof help, "%s%s%s%s", o->help, *desc ? " [" : "", desc, *desc ? "]" : "");
			cli_print_option(out, 5, left, help);
		}
	}
}

typedef struct progress_state {
	int tty;
	double t0;
	char banner[512]; /* printed with the first progress report, once the run folder exists */
} progress_state;

static void progress(void *user, uint32_t done, uint32_t total)
{
	progress_state *ps = user;
	double elapsed = tl_clock_s() - ps->t0;
	if (done == 1)
		fputs(ps->banner, stderr);
	if (ps->tty) {
		int width = 30, fill = (int)((double)done / total * width);
		fprintf(stderr, "\r[%.*s%*s] %u/%u frames, %.1f s", fill, "##############################", width - fill, "",
			done, total, elapsed);
		if (done == total)
			fputc('\n', stderr);
	} else if (done == total || done % 10 == 0) {
		fprintf(stderr, "taslab: rendered %u/%u frames (%.1f s)\n", done, total, elapsed);
	}
	fflush(stderr);
}

static int render_main(void *opts, cli_ctx *ctx)
{
	render_opts *o = opts;
	cli_setup *s = &ctx->setup;
	char out_default[512], variant[96];
	method_config_id(&o->config, variant, sizeof variant);
	const char *out = o->out;
	if (!out) {
		snprintf(out_default, sizeof out_default, "runs/%s-%s-%s", s->scene->name, s->scene->cameras[s->camera].name,
			 variant);
		out = out_default;
	}
	method_config_variant(&o->config, variant, sizeof variant);
	progress_state ps = {isatty(2), tl_clock_s(), ""};
	snprintf(ps.banner, sizeof ps.banner, "taslab: rendering %s/%s with %s on %s, frames %u..%u at %ux%u%s\n",
		 s->scene->name, s->scene->cameras[s->camera].name, variant, s->dev->props.deviceName, s->first, s->end - 1,
		 s->width, s->height, o->stereo ? " per eye, stereo" : "");
	render_run_desc rr = {
		.dev = s->dev,
		.scene = s->scene,
		.scene_path = s->scene_path,
		.camera = s->camera,
		.colour = s->colour,
		.method = &o->config,
		.first = s->first,
		.end = s->end,
		.width = s->width,
		.height = s->height,
		.fps = s->fps,
		.write_exr = !o->no_exr,
		.write_png = !o->no_png,
		.trivial_shading = o->trivial_shading,
		.write_decisions = o->decisions,
		.write_rates = o->rate_images,
		.views = o->stereo ? 2 : 1,
		.ipd = o->stereo ? (float)o->ipd : 0.0f,
		.multiview = (render_multiview)o->mv,
		.out = out,
		.command_line = ctx->command_line,
		.progress = o->quiet ? NULL : progress,
		.user = &ps,
	};
	int rc = render_run(&rr, ctx->err, sizeof ctx->err);
	if (rc) {
		if (ps.tty && !o->quiet)
			fputc('\n', stderr);
		return rc;
	}
	if (!o->quiet)
		fprintf(stderr, "taslab: wrote %u frames to %s/%s (stats: %s/stats.csv)\n", s->end - s->first, out,
			o->stereo ? "frames/L, frames/R and sbs" : "frames", out);
	printf("%s\n", out);
	return TL_OK;
}

const cli_command cli_cmd_render = {
	.name = "render",
	.summary = "render a clip of a scene with a method into a run folder",
	.synopsis = "taslab render --scene S [options]",
	.description = "Renders frames of a scene along a camera path into a run folder:\n"
		       "  RUN/frames/NNNNNN.exr (scene-linear, half), RUN/frames/NNNNNN.png (display 8-bit),\n"
		       "  RUN/stats.csv (per frame), RUN/manifest.json (written last: the run is complete).",
	.options = render_options,
	.dynamic_options = render_dynamic,
	.opts_size = sizeof(render_opts),
	.defaults = render_defaults,
	.validate = render_validate,
	.needs = CLI_NEED_SCENE | CLI_NEED_COLOUR | CLI_NEED_DEVICE,
	.run = render_main,
	.help_extra = methods_help,
};
