/* parse.c — the table-driven option parser, help from the same tables, the command dispatcher, and the
 * value parsers shared by commands (cli.h). Nothing here exits; main() returns cli_main's status. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "taslab/tl_fs.h"
#include "taslab/tl_parse.h"
#include "taslab/tl_hash.h"
#include "taslab/version.h"
#include "taslab/vkdev.h"

#ifndef TASLAB_SCENES_DIR
#define TASLAB_SCENES_DIR "scenes"
#endif

/* ------------------------------------------------------------------ value parsers */

/* Whole numbers, sizes and frame ranges come from base/tl_parse.h: the sweep file reader uses the same parser, so a
 * value means the same on the command line and in a file (issue 31.5). */
static int parse_u32(const char *s, const char **end, uint32_t *out)
{
	uint64_t v;
	if (tl_parse_u64_prefix(s, end, &v) || v > UINT32_MAX)
		return TL_ERR_ARG;
	*out = (uint32_t)v;
	return 0;
}

int cli_parse_size(const char *s, uint32_t *w, uint32_t *h, char *err, size_t err_size)
{
	char why[256];
	if (tl_parse_size(s, w, h, why, sizeof why))
		return tl_error(err, err_size, TL_ERR_ARG, "--size '%s' %s", s ? s : "", why);
	return 0;
}

int cli_parse_frames(const char *s, uint32_t *a, uint32_t *b_inout, bool *b_given, char *err, size_t err_size)
{
	char why[256];
	if (tl_parse_frames(s, a, b_inout, b_given, why, sizeof why))
		return tl_error(err, err_size, TL_ERR_ARG, "--frames '%s' %s", s ? s : "", why);
	return 0;
}

int cli_parse_float(const char *s, const char *what, double lo, double hi, double *out, char *err, size_t err_size)
{
	char *e;
	errno = 0;
	double v = s ? strtod(s, &e) : NAN;
	if (!s || !*s || *e || errno || !isfinite(v) || v < lo || v > hi) {
		snprintf(err, err_size, "%s '%s' must be a number in [%g, %g]", what, s ? s : "", lo, hi);
		return TL_ERR_ARG;
	}
	*out = v;
	return 0;
}

int cli_resolve_scene(const char *arg, char *path, size_t path_size, char *err, size_t err_size)
{
	if (!arg || !*arg) {
		snprintf(err, err_size, "--scene needs a scene file or a built-in scene name (see 'taslab render --help')");
		return TL_ERR_ARG;
	}
	if (strchr(arg, '/') || strstr(arg, ".json") || strstr(arg, ".gltf") || strstr(arg, ".glb")) {
		snprintf(path, path_size, "%s", arg); /* a path: loading reports a missing file */
		return 0;
	}
	const char *dirs[2] = {getenv("TASLAB_SCENES"), TASLAB_SCENES_DIR};
	for (int i = 0; i < 2; i++) {
		if (!dirs[i] || !*dirs[i])
			continue;
		snprintf(path, path_size, "%s/%s.json", dirs[i], arg);
		if (tl_is_file(path))
			return 0;
	}
	snprintf(err, err_size, "no built-in scene named '%s' in %s (give a path to a scene file, or see scenes/README.md)",
		 arg, TASLAB_SCENES_DIR);
	return TL_ERR_ARG;
}

int cli_parse_frame_list(const char *s, uint32_t end, uint32_t *frames, size_t max, size_t *n, char *err, size_t err_size)
{
	*n = 0;
	const char *p = s;
	while (*p) {
		uint32_t a, b, step = 1;
		const char *e;
		if (parse_u32(p, &e, &a))
			goto bad;
		b = a + 1;
		if (*e == ':') {
			if (parse_u32(e + 1, &e, &b))
				goto bad;
			if (*e == ':' && (parse_u32(e + 1, &e, &step) || step == 0))
				goto bad;
			if (b <= a)
				goto bad;
		}
		if (*e && *e != ',')
			goto bad;
		for (uint32_t f = a; f < b; f += step) {
			if (f >= end) {
				snprintf(err, err_size, "analysis frame %u is outside the clip (frames 0..%u)", f, end - 1);
				return TL_ERR_ARG;
			}
			if (*n == max) {
				snprintf(err, err_size, "at most %zu analysis frames", max);
				return TL_ERR_ARG;
			}
			frames[(*n)++] = f;
		}
		p = *e ? e + 1 : e;
	}
	if (*n)
		return 0;
bad:
	snprintf(err, err_size, "bad frame list '%s' (expected comma-separated F, A:B or A:B:STEP, e.g. 60,120 or 60:300:60)", s);
	return TL_ERR_ARG;
}

int cli_split_list(const char *s, const char *what, char *buf, size_t buf_size, const char **items, size_t max,
		   size_t *n, char *err, size_t err_size)
{
	*n = 0;
	if (!s || !*s)
		return tl_error(err, err_size, TL_ERR_ARG, "%s: empty list", what);
	if (snprintf(buf, buf_size, "%s", s) >= (int)buf_size)
		return tl_error(err, err_size, TL_ERR_ARG, "%s: list too long", what);
	for (char *p = buf;;) {
		char *c = strchr(p, ',');
		if (c)
			*c = 0;
		if (!*p)
			return tl_error(err, err_size, TL_ERR_ARG, "%s: empty entry in '%s'", what, s);
		if (*n == max)
			return tl_error(err, err_size, TL_ERR_ARG, "%s: at most %zu entries", what, max);
		items[(*n)++] = p;
		if (!c)
			break;
		p = c + 1;
	}
	return TL_OK;
}

int cli_parse_float_list(const char *s, const char *what, double lo, double hi, float *out, size_t max, size_t *n,
			 char *err, size_t err_size)
{
	char buf[512];
	const char *items[64];
	size_t k;
	*n = 0;
	int rc = cli_split_list(s, what, buf, sizeof buf, items, max < 64 ? max : 64, &k, err, err_size);
	if (rc)
		return rc;
	for (size_t i = 0; i < k; i++) {
		double v;
		if ((rc = cli_parse_float(items[i], what, lo, hi, &v, err, err_size)))
			return rc;
		out[(*n)++] = (float)v;
	}
	return TL_OK;
}

int cli_parse_uint(const char *s, const char *what, uint64_t lo, uint64_t hi, uint64_t *out, char *err, size_t err_size)
{
	char why[128];
	if (tl_parse_uint(s, lo, hi, out, why, sizeof why))
		return tl_error(err, err_size, TL_ERR_ARG, "%s '%s' %s", what, s ? s : "", why);
	return TL_OK;
}

const char *cli_scenes_dir(void)
{
	const char *d = getenv("TASLAB_SCENES");
	return d && *d ? d : TASLAB_SCENES_DIR;
}

/* ------------------------------------------------------------------ the option parser */

static const cli_opt setup_scene_common[] = {
	{.name = "scene", .arg = "S",
	 .help = "built-in scene name (see 'taslab scenes'), a scene .json file, or a .gltf/.glb",
	 .type = CLI_STRING, .offset = offsetof(cli_setup_opts, scene)},
	{.name = "camera", .arg = "C",
	 .help = "camera path name (default: the scene's first)",
	 .type = CLI_STRING, .offset = offsetof(cli_setup_opts, camera)},
	{.name = "size", .arg = "WxH",
	 .help = "frame size",
	 .type = CLI_SIZE, .offset = offsetof(cli_setup_opts, size)},
	{.name = "fps", .arg = "F",
	 .help = "frame rate; frame f is at t = f/F (default: the scene's, usually 60)",
	 .type = CLI_DOUBLE, .offset = offsetof(cli_setup_opts, fps), .lo = 1, .hi = 1000},
	{0},
};
static const cli_opt setup_scene_opts[] = {
	{.type = CLI_INCLUDE, .include = setup_scene_common},
	{.name = "frames", .arg = "A:B",
	 .help = "frames A..B-1; also A (one frame), :B, A: (default: the whole clip)",
	 .type = CLI_STRING, .offset = offsetof(cli_setup_opts, frames)},
	{0},
};
static const cli_opt setup_scene_list_opts[] = {
	{.type = CLI_INCLUDE, .include = setup_scene_common},
	{.name = "frames", .arg = "LIST",
	 .help = "single frames: F, A:B (half-open) or A:B:STEP, comma-separated, inside the clip",
	 .type = CLI_STRING, .offset = offsetof(cli_setup_opts, frames)},
	{0},
};
static const cli_opt setup_colour_opts[] = {
	{.name = "ocio-config", .arg = "F",
	 .help = "OpenColorIO config for the display transform (default: $OCIO, else the built-in ACES 1.0 "
			     "SDR-video output transform on an sRGB display)",
	 .type = CLI_STRING, .offset = offsetof(cli_setup_opts, ocio_config)},
	{.name = "display", .arg = "D",
	 .help = "display of that config (default: the config's default)",
	 .type = CLI_STRING, .offset = offsetof(cli_setup_opts, display)},
	{.name = "view", .arg = "V",
	 .help = "view of that display (default: the display's default)",
	 .type = CLI_STRING, .offset = offsetof(cli_setup_opts, view)},
	{0},
};
static const cli_opt setup_device_opts[] = {
	{.name = "device", .arg = "D",
	 .help = "Vulkan device: index, name substring, or 'lavapipe' (default: a GPU if present, else lavapipe)",
	 .type = CLI_STRING, .offset = offsetof(cli_setup_opts, device)},
	{.name = "validation", .arg = NULL,
	 .help = "enable the Khronos validation layer; any message fails the command",
	 .type = CLI_FLAG, .offset = offsetof(cli_setup_opts, validation)},
	{0},
};

typedef struct group {
	const cli_opt *opts;
	void *dst;
} group;

/* The option called `name` in a table (following includes). */
static const cli_opt *find_in(const cli_opt *t, const char *name)
{
	for (; t && t->type != CLI_OPT_END; t++) {
		if (t->type == CLI_INCLUDE) {
			const cli_opt *o = find_in(t->include, name);
			if (o)
				return o;
		} else if (!strcmp(t->name, name)) {
			return t;
		}
	}
	return NULL;
}

static size_t groups_of(const cli_command *c, void *opts, cli_ctx *ctx, group *g)
{
	size_t n = 0;
	if (c->options)
		g[n++] = (group){c->options, opts};
	if (c->dynamic_options)
		g[n++] = (group){c->dynamic_options(), opts};
	if (c->needs & CLI_NEED_SCENE)
		g[n++] = (group){c->needs & CLI_NEED_FRAME_LIST ? setup_scene_list_opts : setup_scene_opts, &ctx->setup_opts};
	if (c->needs & CLI_NEED_COLOUR)
		g[n++] = (group){setup_colour_opts, &ctx->setup_opts};
	if (c->needs & CLI_NEED_DEVICE)
		g[n++] = (group){setup_device_opts, &ctx->setup_opts};
	return n;
}

static int set_value(const cli_opt *o, const char *flag, const char *v, void *dst, char *err, size_t err_size)
{
	void *field = (char *)dst + o->offset;
	int rc = TL_OK;
	switch (o->type) {
	case CLI_FLAG: *(bool *)field = true; break;
	case CLI_STRING:
		if (!*v)
			return tl_error(err, err_size, TL_ERR_ARG, "%s needs a non-empty value", flag);
		*(const char **)field = v;
		break;
	case CLI_UINT:
	case CLI_U64: {
		uint64_t u = 0;
		if ((rc = cli_parse_uint(v, flag, (uint64_t)o->lo, (uint64_t)o->hi, &u, err, err_size)))
			return rc;
		if (o->type == CLI_UINT)
			*(uint32_t *)field = (uint32_t)u;
		else
			*(uint64_t *)field = u;
		break;
	}
	case CLI_DOUBLE: rc = cli_parse_float(v, flag, o->lo, o->hi, (double *)field, err, err_size); break;
	case CLI_SIZE: {
		uint32_t *wh = field;
		rc = cli_parse_size(v, &wh[0], &wh[1], err, err_size);
		break;
	}
	case CLI_CUSTOM: rc = o->parse(o, v, field, err, err_size); break;
	default: rc = tl_error(err, err_size, TL_ERR_INTERNAL, "%s: bad option table", flag);
	}
	return rc;
}

int cli_parse_command(const cli_command *c, int argc, char **argv, void *opts, cli_ctx *ctx)
{
	group g[5];
	ctx->name = c->name;
	ctx->npos = 0;
	ctx->help = false;
	memset(&ctx->setup_opts, 0, sizeof ctx->setup_opts);
	ctx->setup_opts.size[0] = 960;
	ctx->setup_opts.size[1] = 540;
	if (opts && c->opts_size)
		memset(opts, 0, c->opts_size);
	if (c->defaults)
		c->defaults(opts, &ctx->setup_opts);
	size_t ng = groups_of(c, opts, ctx, g);
	bool only_pos = false;
	for (int i = 1; i < argc; i++) {
		const char *a = argv[i];
		if (only_pos || a[0] != '-' || !a[1]) {
			if (ctx->npos == c->max_pos || ctx->npos == CLI_MAX_POS)
				return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "unexpected argument '%s' (see 'taslab %s --help')",
						a, c->name);
			ctx->pos[ctx->npos++] = a;
			continue;
		}
		if (!strcmp(a, "--")) {
			only_pos = true;
			continue;
		}
		if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
			ctx->help = true;
			continue;
		}
		char name[64];
		const char *eq = strchr(a, '='), *v = eq ? eq + 1 : NULL;
		size_t len = eq ? (size_t)(eq - a) : strlen(a);
		if (strncmp(a, "--", 2) || len - 2 >= sizeof name)
			return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "unknown option '%s' (see 'taslab %s --help')", a, c->name);
		memcpy(name, a + 2, len - 2);
		name[len - 2] = 0;
		const cli_opt *o = NULL;
		void *dst = NULL;
		for (size_t k = 0; k < ng && !o; k++)
			if ((o = find_in(g[k].opts, name)))
				dst = g[k].dst;
		if (!o)
			return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "unknown option '--%s' (see 'taslab %s --help')", name,
					c->name);
		bool takes_value = o->arg != NULL;
		if (!takes_value && v)
			return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--%s takes no value", name);
		if (takes_value && !v) {
			if (i + 1 >= argc)
				return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--%s needs a value %s (see 'taslab %s --help')",
						name, o->arg, c->name);
			v = argv[++i];
		}
		char flag[80];
		snprintf(flag, sizeof flag, "--%s", name);
		int rc = set_value(o, flag, v, dst, ctx->err, sizeof ctx->err);
		if (rc)
			return rc;
	}
	if (ctx->help)
		return TL_OK;
	if (ctx->npos < c->min_pos)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "%s %s required (see 'taslab %s --help')",
				c->pos_help ? c->pos_help : "an argument", c->min_pos > 1 ? "are" : "is", c->name);
	if ((c->needs & CLI_NEED_SCENE) && !ctx->setup_opts.scene)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--scene is required (e.g. --scene calm; see 'taslab scenes')");
	if (ctx->setup_opts.frames && !(c->needs & CLI_NEED_FRAME_LIST)) { /* syntax now, the range with the scene */
		uint32_t a = 0, b = 1u << 30;
		bool given;
		int rc = cli_parse_frames(ctx->setup_opts.frames, &a, &b, &given, ctx->err, sizeof ctx->err);
		if (rc)
			return rc;
	}
	return c->validate ? c->validate(opts, ctx) : TL_OK;
}

/* ------------------------------------------------------------------ help */

/* " (default V)" for an option whose default (in `defaults`, the options struct after the command's
 * defaults()) is not zero and whose help does not already say it. */
static void default_text(const cli_opt *t, const void *defaults, char *out, size_t n)
{
	out[0] = 0;
	if (!defaults || (t->help && strstr(t->help, "default")))
		return;
	const void *f = (const char *)defaults + t->offset;
	switch (t->type) {
	case CLI_STRING:
		if (*(const char *const *)f)
			snprintf(out, n, " (default %s)", *(const char *const *)f);
		break;
	/* A value outside the option's range is a "not given" marker, not a default. */
	case CLI_UINT:
		if (*(const uint32_t *)f && *(const uint32_t *)f <= t->hi)
			snprintf(out, n, " (default %u)", *(const uint32_t *)f);
		break;
	case CLI_U64:
		if (*(const uint64_t *)f && (double)*(const uint64_t *)f <= t->hi)
			snprintf(out, n, " (default %llu)", (unsigned long long)*(const uint64_t *)f);
		break;
	case CLI_DOUBLE:
		if (*(const double *)f != 0.0 && *(const double *)f >= t->lo && *(const double *)f <= t->hi)
			snprintf(out, n, " (default %g)", *(const double *)f);
		break;
	case CLI_SIZE:
		if (((const uint32_t *)f)[0])
			snprintf(out, n, " (default %ux%u)", ((const uint32_t *)f)[0], ((const uint32_t *)f)[1]);
		break;
	default: break;
	}
}

void cli_print_option(FILE *out, int indent, const char *left, const char *help)
{
	/* wrap the help text at ~100 columns, continuation lines indented */
	const int width = 76 - indent;
	const char *h = help;
	int first = 1;
	while (*h || first) {
		size_t n = strlen(h);
		if (n > (size_t)width) {
			n = (size_t)width;
			while (n > 20 && h[n] != ' ')
				n--;
		}
		fprintf(out, "  %*s%-20s %.*s\n", indent, "", first ? left : "", (int)n, h);
		h += n;
		while (*h == ' ')
			h++;
		first = 0;
	}
}

static void print_opts(FILE *out, const cli_opt *t, const void *defaults)
{
	for (; t && t->type != CLI_OPT_END; t++) {
		if (t->type == CLI_INCLUDE) {
			print_opts(out, t->include, defaults);
			continue;
		}
		char left[64], help[512], def[96];
		snprintf(left, sizeof left, "--%s%s%s", t->name, t->arg ? " " : "", t->arg ? t->arg : "");
		default_text(t, defaults, def, sizeof def);
		snprintf(help, sizeof help, "%s%s", t->help ? t->help : "", def);
		cli_print_option(out, 0, left, help);
	}
}

void cli_print_help(FILE *out, const cli_command *c)
{
	fprintf(out, "usage: %s\n", c->synopsis ? c->synopsis : c->name);
	if (c->description)
		fprintf(out, "\n%s\n", c->description);
	if (c->subcommands) {
		fprintf(out, "\nsubcommands (taslab %s SUB --help for each):\n", c->name);
		for (const cli_command *const *s = c->subcommands; *s; s++)
			fprintf(out, "  %-12s %s\n", strrchr((*s)->name, ' ') ? strrchr((*s)->name, ' ') + 1 : (*s)->name,
				(*s)->summary);
	}
	if (c->options || c->needs) {
		static _Alignas(max_align_t) unsigned char defaults[CLI_OPTS_MAX_B];
		cli_setup_opts setup = {.size = {960, 540}};
		memset(defaults, 0, sizeof defaults);
		if (c->defaults)
			c->defaults(defaults, &setup);
		fprintf(out, "\noptions:\n");
		print_opts(out, c->options, defaults);
		/* (the dynamic options, i.e. the methods' own, are listed per method by help_extra) */
		if (c->needs & CLI_NEED_SCENE)
			print_opts(out, c->needs & CLI_NEED_FRAME_LIST ? setup_scene_list_opts : setup_scene_opts, &setup);
		if (c->needs & CLI_NEED_COLOUR)
			print_opts(out, setup_colour_opts, &setup);
		if (c->needs & CLI_NEED_DEVICE)
			print_opts(out, setup_device_opts, &setup);
		fprintf(out, "  %-20s %s\n", "--help", "this text");
	}
	if (c->help_extra)
		c->help_extra(out);
}

/* ------------------------------------------------------------------ dispatch */

const cli_command *cli_find_command(const char *name)
{
	char top[64];
	const char *sp = strchr(name, ' ');
	snprintf(top, sizeof top, "%.*s", sp ? (int)(sp - name) : (int)strlen(name), name);
	for (const cli_command *const *c = cli_commands; *c; c++) {
		if (strcmp((*c)->name, top))
			continue;
		if (!sp)
			return *c;
		for (const cli_command *const *s = (*c)->subcommands; s && *s; s++)
			if (!strcmp((*s)->name, name))
				return *s;
	}
	return NULL;
}

static void usage(FILE *out)
{
	fprintf(out, "usage: taslab <command> [options]   (taslab <command> --help for details)\n\n"
		     "taslab %s — offline evaluation harness for temporally adaptive shading\n\ncommands:\n",
		TASLAB_VERSION_STRING);
	for (const cli_command *const *c = cli_commands; *c; c++)
		fprintf(out, "  %-10s %s\n", (*c)->name, (*c)->summary);
	fprintf(out, "\n  --version  print the version and the build's digest\n  --help     this text\n");
}

static int run_command(const cli_command *c, int argc, char **argv)
{
	static _Alignas(max_align_t) unsigned char opts[CLI_OPTS_MAX_B];
	cli_ctx *ctx = calloc(1, sizeof *ctx);
	if (!ctx) {
		fprintf(stderr, "taslab: out of memory\n");
		return 1;
	}
	for (int i = 0; i < argc; i++) {
		strncat(ctx->command_line, i ? " " : "taslab ", sizeof ctx->command_line - strlen(ctx->command_line) - 1);
		strncat(ctx->command_line, argv[i], sizeof ctx->command_line - strlen(ctx->command_line) - 1);
	}
	int rc = c->opts_size > sizeof opts ? TL_ERR_INTERNAL : cli_parse_command(c, argc, argv, opts, ctx);
	if (!rc && ctx->help) {
		cli_print_help(stdout, c);
	} else if (!rc) {
		rc = cli_setup_run(c->needs, &ctx->setup_opts, &ctx->setup, ctx->err, sizeof ctx->err);
		if (!rc)
			rc = c->run(opts, ctx);
		if (!rc && ctx->setup.dev && vkdev_validation_messages(ctx->setup.dev))
			rc = tl_error(ctx->err, sizeof ctx->err, TL_ERR_VALIDATION, "%u Vulkan validation message(s) (printed above)",
				      vkdev_validation_messages(ctx->setup.dev));
	}
	if (rc)
		fprintf(stderr, "taslab %s: %s\n", c->name, ctx->err[0] ? ctx->err : tl_strerror(rc));
	cli_setup_free(&ctx->setup);
	free(ctx);
	return tl_exit_status(rc);
}

int cli_main(int argc, char **argv)
{
	if (argc < 2) {
		usage(stderr);
		return 2;
	}
	if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
		usage(stdout);
		return 0;
	}
	if (!strcmp(argv[1], "--version")) {
		/* the build digest tells builds of one version apart (sweeps record it: tl_hash.h) */
		printf("taslab %s (build %s)\n", TASLAB_VERSION_STRING, tl_build_digest()[0] ? tl_build_digest() : "unknown");
		return 0;
	}
	const cli_command *c = cli_find_command(argv[1]);
	if (!c || strchr(argv[1], ' ')) {
		fprintf(stderr, "taslab: unknown command '%s' (run 'taslab --help' for the list)\n", argv[1]);
		return 2;
	}
	if (!c->subcommands)
		return run_command(c, argc - 1, argv + 1);
	if (argc < 3 || !strcmp(argv[2], "--help") || !strcmp(argv[2], "-h")) {
		cli_print_help(argc < 3 ? stderr : stdout, c);
		return argc < 3 ? 2 : 0;
	}
	for (const cli_command *const *s = c->subcommands; *s; s++) {
		const char *sub = strrchr((*s)->name, ' ');
		if (sub && !strcmp(sub + 1, argv[2]))
			return run_command(*s, argc - 2, argv + 2);
	}
	fprintf(stderr, "taslab %s: unknown subcommand '%s' (see 'taslab %s --help')\n", c->name, argv[2], c->name);
	return 2;
}
