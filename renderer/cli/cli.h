/* cli.h — the `taslab` command line: dispatch table entries and option parsing.
 * Parsing functions return 0 or -1 with a one-line message (what is wrong, what to do) in `err`;
 * nothing here exits, so every parser is unit-tested (tests/test_cli_options.c). */
#ifndef TASLAB_CLI_H
#define TASLAB_CLI_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

typedef struct cli_command {
	const char *name;
	const char *summary;
	int (*run)(int argc, char **argv); /* argv[0] is the command name; returns the exit status */
	void (*usage)(FILE *out);
} cli_command;

enum { CLI_EXIT_OK = 0, CLI_EXIT_FAILURE = 1, CLI_EXIT_USAGE = 2 };

/* "WxH", 1..16384 each. */
int cli_parse_size(const char *s, uint32_t *w, uint32_t *h, char *err, size_t err_size);
/* "A:B" = frames A..B-1 (half-open, like a slice), "A" = the single frame A, ":B" = 0..B-1,
 * "A:" = from A to the end (end = *b_inout on entry). */
int cli_parse_frames(const char *s, uint32_t *a, uint32_t *b_inout, bool *b_given, char *err, size_t err_size);
/* A finite number within [lo, hi]; `what` names the option in messages. */
int cli_parse_float(const char *s, const char *what, double lo, double hi, double *out, char *err, size_t err_size);

/* Analysis frames: comma-separated F, A:B (half-open) or A:B:STEP; every frame must be < `end` (the
 * clip's frame count). At most `max` frames into `frames`. */
int cli_parse_frame_list(const char *s, uint32_t end, uint32_t *frames, size_t max, size_t *n, char *err, size_t err_size);
/* Comma-separated numbers within [lo, hi], at most `max`. */
int cli_parse_float_list(const char *s, const char *what, double lo, double hi, float *out, size_t max, size_t *n,
			 char *err, size_t err_size);

/* For commands without options: handles --help (returns CLI_EXIT_OK after printing usage) and rejects
 * any other argument (CLI_EXIT_USAGE); returns -1 when the command should run. */
int cli_no_args(int argc, char **argv, void (*usage)(FILE *out));

typedef struct cli_render_opts {
	const char *scene, *camera, *method, *out, *device;
	const char *frames;   /* unparsed until the scene (its duration) is known */
	const char *ocio_config, *display, *view; /* display transform (colour.h) */
	uint32_t width, height;
	double fps;           /* 0 = scene */
	double threshold;
	double max_age;       /* tfr: K; 0 = 119 */
	bool validation, no_exr, no_png, trivial_shading, quiet, help;
} cli_render_opts;

/* Parses `taslab render` arguments (argv[0] = "render"). */
int cli_render_parse(int argc, char **argv, cli_render_opts *o, char *err, size_t err_size);
/* Resolves a --scene argument: an existing file path, or the name of a built-in scene
 * (scenes/NAME.json under $TASLAB_SCENES or the installed/source scenes folder). */
int cli_resolve_scene(const char *arg, char *path, size_t path_size, char *err, size_t err_size);

extern const cli_command cli_cmd_render;
extern const cli_command cli_cmd_devices;
extern const cli_command cli_cmd_scenes;
extern const cli_command cli_cmd_tonemap;
extern const cli_command cli_cmd_clip;
extern const cli_command cli_cmd_pair;
extern const cli_command cli_cmd_metrics; /* metrics/cli */
extern const cli_command cli_cmd_analyze; /* metrics/cli */
extern const cli_command cli_cmd_study;   /* study/cli */

#endif
