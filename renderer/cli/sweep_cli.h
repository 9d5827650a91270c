/* sweep_cli.h (private to the CLI) — `taslab sweep` and `taslab report` (DESIGN section 9): resolving a sweep request
 * against the scene files and the method registry, running one run of the plan (render + clip + metrics), the local
 * job runner, Slurm submission, and the closing tables and report. */
#ifndef TASLAB_SWEEP_CLI_H
#define TASLAB_SWEEP_CLI_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "commands.h"
#include "taslab/sweep.h"

/* The command-line options of the sweep key table (output/sweep_keys.h): --NAME for key NAME ('_' as '-'), parsed
 * by the one option parser into sweep_opts.keys (the key's index). Built once. */
const cli_opt *cli_sweep_key_options(void);
/* Whether the command line gave the sweep key `name` ("scenes"). */
bool cli_sweep_opt_given(const sweep_opts *o, const char *name);
/* Whether it gave a setting that changes the sweep (any key but the SWEEP_KEY_RESUME_OK ones: --jobs). */
bool cli_sweep_opts_change_spec(const sweep_opts *o);
/* Lists the settings for `taslab sweep --help`: the option, its help, and the sweep file key it also is. */
void cli_sweep_keys_help(FILE *out);

/* Overlays the options given on the command line onto `r` (a request read from a sweep file, or zeroed), key by key
 * as the table says. TL_ERR_ARG for malformed lists. */
int cli_sweep_request_from_opts(const sweep_opts *o, sweep_request *r, char *err, size_t err_size);

/* Resolves a request into a spec: scenes loaded (names, paths, cameras and their motion, frame range, fps), variants
 * from the method registry (methods x thresholds x periods expanded; ref required), baseline, metric list and display
 * transform checked. Nothing is written. TL_ERR_ARG / TL_ERR_INPUT with one line naming the bad entry. */
int cli_sweep_resolve(const sweep_request *r, sweep_spec *s, char *err, size_t err_size);

/* Runs plan entry `index` of the sweep in `dir` in this process: renders the run unless it is complete, encodes its
 * clip unless present, and compares it with its ref run unless done or the ref run is not complete yet (then the
 * comparison is left for later: *deferred = true). Progress: one byte per rendered frame to `progress_fd` (-1: none). */
int cli_sweep_task(const sweep_spec *s, const char *dir, size_t index, int progress_fd, const char *command_line,
		   bool *deferred, char *err, size_t err_size);

/* The path of the running taslab binary (/proc/self/exe): what the local runner and Slurm scripts execute. */
int cli_sweep_self(char *out, size_t out_size, char *err, size_t err_size);
/* Opens `path` (creating it) and takes an exclusive flock on it without waiting: TL_OK and *fd; TL_ERR_CONFLICT with
 * *fd = -1 (and no message: the caller says what holds it) when another process holds it; TL_ERR_OUTPUT otherwise.
 * The lock goes when *fd is closed or the process ends, however it ends. */
int cli_sweep_flock(const char *path, int *fd, char *err, size_t err_size);

/* Runs every incomplete run of the plan, `jobs` at a time, each in its own process (`taslab sweep DIR/sweep.json
 * --task I`, output into its log file), with one progress line. *failed receives the number of runs that did not
 * complete. TL_ERR_INTERRUPTED after SIGINT/SIGTERM (children stopped, complete runs kept). */
int cli_sweep_local(const sweep_spec *s, const char *dir, unsigned jobs, bool quiet, size_t *failed, char *err,
		    size_t err_size);

/* Writes the Slurm batch scripts into DIR/slurm/ (a job array over the incomplete runs, one task per run, and a report
 * job depending on it) and submits them with sbatch, `slurm_opts` passed to both; `dry_run` prints the scripts and
 * the sbatch commands instead. */
int cli_sweep_slurm(const sweep_spec *s, const char *dir, const char *slurm_opts, bool dry_run, char *err,
		    size_t err_size);

/* Checks before the sweep folder is touched that nothing written into the Slurm scripts (the folder's path, the
 * current folder when that path is relative, the taslab binary's path) holds a control character. TL_ERR_ARG. */
int cli_sweep_slurm_check(const char *dir, char *err, size_t err_size);

/* The closing step (and `taslab report`): clips and comparisons still missing for complete runs are made, then
 * DIR/summary.csv, DIR/table1.md and DIR/report/index.html (with the study's tallies when `study` is given).
 * *incomplete: runs without run, clip or metrics at the end. `mono_dir` (NULL: none): a mono sweep whose speedups the
 * report of this stereo sweep shows beside its own (TL_ERR_ARG when this sweep is not stereo or that one is).
 * `model` (NULL: none): a saved metric-to-JND model whose predicted thresholds the report shows. */
int cli_sweep_finish(const sweep_spec *s, const char *dir, const char *study, const char *model, const char *jnd_metric,
		     const char *mono_dir, bool report,
		     bool quiet, size_t *incomplete, char *report_path, size_t report_path_size, char *err, size_t err_size);

#endif
