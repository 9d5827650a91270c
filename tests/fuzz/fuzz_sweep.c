/* fuzz_sweep.c — libFuzzer harness for sweep files (untrusted input: a sweep file someone wrote, or a SWEEP/sweep.json
 * edited by hand; DESIGN section 9, output/sweep.h). Each input is read as a request twice, as JSON and as TOML (the
 * reader picks the format by the file's extension), and as a resolved spec.
 * Properties checked beyond "no crash, leak or hang" (ASan + UBSan via scripts/fuzz sweep):
 *   - every refusal is one non-empty line naming the file;
 *   - an accepted spec round-trips: write -> read gives the same sweep (sweep_spec_compare) and the same bytes when
 *     written again; its plan enumerates runs whose ref runs are ref runs of the same scene and camera, and whose
 *     paths stay inside the sweep folder (no '..', names are single folder names).
 * Temporary files live in a private folder (in /dev/shm when there is one). */
#define _GNU_SOURCE /* mkdtemp, nftw */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "taslab/sweep.h"
#include "fuzz_tmp.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static sweep_request *req;
static sweep_spec *spec, *again;

static void setup(void)
{
	fuzz_tmp_make("sweep", NULL);
	req = malloc(sizeof *req);
	spec = malloc(sizeof *spec);
	again = malloc(sizeof *again);
	if (!req || !spec || !again)
		abort();
}

static void refused(const char *err, const char *file)
{
	if (!err[0] || strchr(err, '\n') || !strstr(err, file))
		__builtin_trap(); /* one line, naming the file */
}

static char *slurp(const char *path)
{
	FILE *f = fopen(path, "rb");
	if (!f)
		return NULL;
	fseek(f, 0, SEEK_END);
	long n = ftell(f);
	fseek(f, 0, SEEK_SET);
	char *b = malloc((size_t)n + 1);
	if (b && fread(b, 1, (size_t)n, f) != (size_t)n) {
		free(b);
		b = NULL;
	}
	if (b)
		b[n] = 0;
	fclose(f);
	return b;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	if (!fuzz_dir[0])
		setup();
	char in[300], in_toml[300], out[300], out2[300], err[1024] = "", what[512];
	snprintf(in, sizeof in, "%s/in.json", fuzz_dir);
	snprintf(in_toml, sizeof in_toml, "%s/in.toml", fuzz_dir);
	snprintf(out, sizeof out, "%s/sweep.json", fuzz_dir);
	snprintf(out2, sizeof out2, "%s/again.json", fuzz_dir);
	FILE *f = fopen(in, "wb");
	if (!f || fwrite(data, 1, size, f) != size || fclose(f))
		abort();
	if (sweep_request_read(in, req, err, sizeof err))
		refused(err, in);
	err[0] = 0;
	f = fopen(in_toml, "wb");
	if (!f || fwrite(data, 1, size, f) != size || fclose(f))
		abort();
	if (sweep_request_read(in_toml, req, err, sizeof err))
		refused(err, in_toml);
	err[0] = 0;
	if (sweep_spec_read(in, spec, err, sizeof err)) {
		refused(err, in);
		return 0;
	}
	if (sweep_spec_write(out, spec, err, sizeof err) || sweep_spec_read(out, again, err, sizeof err) ||
	    sweep_spec_compare(spec, again, what, sizeof what))
		__builtin_trap(); /* an accepted spec round-trips */
	if (sweep_spec_write(out2, again, err, sizeof err))
		__builtin_trap();
	char *a = slurp(out), *b = slurp(out2);
	if (!a || !b || strcmp(a, b))
		__builtin_trap(); /* and is a fixed point */
	free(a);
	free(b);
	size_t n = sweep_run_count(spec);
	for (size_t i = 0; i < n && i < 64; i++) {
		sweep_run r, ref;
		char p[4096];
		if (sweep_run_at(spec, i, &r) || sweep_run_at(spec, r.ref_index, &ref) || !ref.is_ref || ref.scene != r.scene ||
		    ref.camera != r.camera)
			__builtin_trap();
		for (int k = SWEEP_PATH_RUN; k <= SWEEP_PATH_LOG; k++) {
			sweep_run_path(spec, "SW", &r, (sweep_path_kind)k, p, sizeof p);
			if (strncmp(p, "SW/", 3) || strstr(p, "/..") || strstr(p, "//"))
				__builtin_trap(); /* inside the sweep folder */
		}
	}
	if (sweep_run_at(spec, n, &(sweep_run){0}) == 0)
		__builtin_trap();
	return 0;
}
