/* cli.h — the taslab command line: one table-driven option parser, the command table with need-flags, and
 * the shared setup (scene, camera, frames, colour, device) done once for the commands that declare it.
 *
 * A command (one file, cmd_<name>.c) declares its options as a table (name, placeholder, help, type,
 * offset into its options struct, range) and what it needs (git's RUN_SETUP habit): CLI_NEED_SCENE adds
 * --scene/--camera/--frames/--size/--fps, CLI_NEED_COLOUR --ocio-config/--display/--view, CLI_NEED_DEVICE
 * --device/--validation, and cli_main loads the scene, builds the display transform and opens the device
 * before the command runs. --help text, `--x=v` and `--x v`, range checks and one-line errors all come
 * from the tables. Parsing never exits and has no side effects, so every command's parser is unit-tested
 * (tests/test_cli_options.c); only main() decides the exit status (tl_exit_status of the error).
 */
#ifndef TASLAB_CLI_H
#define TASLAB_CLI_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "taslab/tl_error.h"

struct scene;
struct colour;
struct vkdev;

typedef enum cli_opt_type {
	CLI_OPT_END = 0,
	CLI_FLAG,    /* bool, no value */
	CLI_STRING,  /* const char * (non-empty) */
	CLI_UINT,    /* uint32_t, a whole number in [lo, hi] */
	CLI_U64,     /* uint64_t, a whole number in [lo, hi] (seeds) */
	CLI_DOUBLE,  /* double, finite, in [lo, hi] */
	CLI_SIZE,    /* uint32_t[2] from WIDTHxHEIGHT, each 1..16384 */
	CLI_CUSTOM,  /* parse(opt, value, field) decides; value is NULL when `arg` is NULL (a flag) */
	CLI_INCLUDE, /* the options of table `include`, same struct */
} cli_opt_type;

typedef struct cli_opt cli_opt;
struct cli_opt {
	const char *name; /* "scene": --scene */
	const char *arg;  /* placeholder ("S"); NULL for flags */
	const char *help;
	cli_opt_type type;
	size_t offset;    /* of the field in the options struct */
	double lo, hi;    /* numeric range */
	int (*parse)(const cli_opt *o, const char *value, void *field, char *err, size_t err_size);
	const cli_opt *include;
};

#define CLI_MAX_POS 256

/* ---- shared setup ---- */
enum {
	CLI_NEED_SCENE = 1u,      /* --scene --camera --frames --size --fps; scene, camera and frame range loaded */
	CLI_NEED_COLOUR = 2u,     /* --ocio-config --display --view; the display transform created */
	CLI_NEED_DEVICE = 4u,     /* --device --validation; the Vulkan device opened */
	CLI_NEED_FRAME_LIST = 8u, /* with SCENE: --frames is a list of single frames, parsed by the command */
};

typedef struct cli_setup_opts {
	const char *scene, *camera, *frames;
	uint32_t size[2];
	double fps;
	const char *ocio_config, *display, *view;
	const char *device;
	bool validation;
} cli_setup_opts;

typedef struct cli_setup {
	struct scene *scene;
	char scene_path[4096];
	int camera;
	float fps;             /* the run's frame rate (option or scene) */
	uint32_t first, end;   /* frames [first, end) */
	uint32_t width, height;
	struct colour *colour;
	struct vkdev *dev;
} cli_setup;

/* ---- commands ---- */
typedef struct cli_ctx {
	const char *name;      /* "render", "metrics diff" */
	const char *pos[CLI_MAX_POS];
	size_t npos;
	bool help;
	cli_setup_opts setup_opts;
	cli_setup setup;
	char command_line[2048];
	char err[1024];
} cli_ctx;

typedef struct cli_command cli_command;
struct cli_command {
	const char *name;
	const char *summary;      /* one line for `taslab --help` */
	const char *synopsis;     /* "taslab render --scene S [options]" (lines may follow, '\n'-separated) */
	const char *description;  /* paragraphs printed after the synopsis */
	const cli_opt *options;   /* the command's own options (may be NULL) */
	const cli_opt *(*dynamic_options)(void); /* options known only at run time (method options), same struct */
	size_t opts_size;         /* sizeof its options struct (<= CLI_OPTS_MAX_B) */
	void (*defaults)(void *opts, cli_setup_opts *setup);
	/* After parsing, before any side effect: cross-option checks (TL_ERR_ARG, message in ctx->err). */
	int (*validate)(void *opts, cli_ctx *ctx);
	unsigned needs;           /* CLI_NEED_* */
	size_t min_pos, max_pos;  /* positional arguments */
	const char *pos_help;     /* what the positionals are ("RUN", "RATINGS.csv") */
	int (*run)(void *opts, cli_ctx *ctx); /* returns a tl_err with its message in ctx->err */
	void (*help_extra)(FILE *out);        /* printed after the options (e.g. the method table) */
	const cli_command *const *subcommands; /* NULL-terminated; argv[1] picks one */
};

#define CLI_OPTS_MAX_B 8192

/* The command table (cmd_*.c), NULL-terminated, and lookup by name ("metrics diff" finds a subcommand). */
extern const cli_command *const cli_commands[];
const cli_command *cli_find_command(const char *name);

/* Parses argv (argv[0] is the command's name) against the command's options and those its needs add:
 * fills `opts` (defaults first) and ctx->setup_opts, positionals and --help into ctx, then runs the
 * command's validate. No side effects. TL_ERR_ARG with the message in ctx->err. */
int cli_parse_command(const cli_command *c, int argc, char **argv, void *opts, cli_ctx *ctx);
/* Help generated from the tables. */
void cli_print_help(FILE *out, const cli_command *c);
/* One option line of a help text: "--name ARG" (left), then `help` wrapped to the text width, all indented by
 * `indent` more columns than the options list. */
void cli_print_option(FILE *out, int indent, const char *left, const char *help);

/* The whole command line: dispatch, parse, setup, run; returns the exit status. */
int cli_main(int argc, char **argv);

/* The shared setup for `needs` (after parsing): resolves and loads the scene, finds the camera path,
 * parses --frames against the clip, creates the display transform and opens the device. */
int cli_setup_run(unsigned needs, const cli_setup_opts *o, cli_setup *s, char *err, size_t err_size);
void cli_setup_free(cli_setup *s);

/* ---- value parsers, shared with commands and tests ---- */
/* "WxH", 1..16384 each. */
int cli_parse_size(const char *s, uint32_t *w, uint32_t *h, char *err, size_t err_size);
/* "A:B" = frames A..B-1 (half-open, like a slice), "A" = the single frame A, ":B" = 0..B-1,
 * "A:" = from A to the end (end = *b_inout on entry). */
int cli_parse_frames(const char *s, uint32_t *a, uint32_t *b_inout, bool *b_given, char *err, size_t err_size);
/* A finite number within [lo, hi]; `what` names the option in messages. */
int cli_parse_float(const char *s, const char *what, double lo, double hi, double *out, char *err, size_t err_size);
/* A whole number within [lo, hi] (no fraction, no sign, no exponent). */
int cli_parse_uint(const char *s, const char *what, uint64_t lo, uint64_t hi, uint64_t *out, char *err, size_t err_size);
/* Analysis frames: comma-separated F, A:B (half-open) or A:B:STEP; every frame must be < `end`. */
int cli_parse_frame_list(const char *s, uint32_t end, uint32_t *frames, size_t max, size_t *n, char *err, size_t err_size);
/* Comma-separated numbers within [lo, hi], at most `max`; empty entries are errors. */
int cli_parse_float_list(const char *s, const char *what, double lo, double hi, float *out, size_t max, size_t *n,
			 char *err, size_t err_size);
/* Comma-separated non-empty items, at most `max`, into `buf` (modified copy; items point into it). */
int cli_split_list(const char *s, const char *what, char *buf, size_t buf_size, const char **items, size_t max,
		   size_t *n, char *err, size_t err_size);
/* A --scene argument: an existing file path, or the name of a built-in scene (scenes/NAME.json under
 * $TASLAB_SCENES or the source tree's scenes folder). */
int cli_resolve_scene(const char *arg, char *path, size_t path_size, char *err, size_t err_size);
/* The scenes folder ($TASLAB_SCENES or the built-in one). */
const char *cli_scenes_dir(void);

#endif
