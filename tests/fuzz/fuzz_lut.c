/* fuzz_lut.c — libFuzzer harness for the LUT files of an OpenColorIO view (untrusted input: a config and its LUTs
 * come from users and studios; issue 31.7). Each input is one LUT file: its first byte picks the format (.spi1d,
 * .spi3d, .cube, .csp — all read by OpenColorIO's file readers), the rest is the file; a config in a private folder
 * uses it as its view, through colour_create (colour.h), which must refuse it with one line or give a transform.
 *
 * Properties checked beyond "no crash, leak or hang" (ASan + UBSan via scripts/fuzz lut):
 *   - a refusal is one line (no newline in the message);
 *   - an accepted transform has only finite LUT values for the GPU (colour_lut_get): NaN and Inf are refused;
 *   - it can be applied to finite pixels (0, mid-grey, 1, HDR and negative values) without a crash.
 * Every input gets a new file name: OpenColorIO caches LUT files by path for the life of the process. */
#define _GNU_SOURCE /* mkdtemp */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "taslab/colour.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char dir[256];
static unsigned long serial;

static void cleanup(void)
{
	if (dir[0])
		rmdir(dir);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	static const char *const ext[] = {"spi1d", "spi3d", "cube", "csp"};
	if (!dir[0]) {
		snprintf(dir, sizeof dir, "%s/taslab-fuzz-lut-XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
		if (!mkdtemp(dir))
			abort();
		atexit(cleanup);
	}
	if (size < 1)
		return 0;
	const char *e = ext[data[0] % 4];
	char lut[512], cfg[512], name[64];
	snprintf(name, sizeof name, "l%lu.%s", serial++, e);
	snprintf(lut, sizeof lut, "%s/%s", dir, name);
	snprintf(cfg, sizeof cfg, "%s/config%lu.ocio", dir, serial);
	FILE *f = fopen(lut, "wb");
	if (!f || (size > 1 && fwrite(data + 1, 1, size - 1, f) != size - 1) || fclose(f))
		abort();
	f = fopen(cfg, "w");
	if (!f)
		abort();
	fprintf(f,
		"ocio_profile_version: 1\nsearch_path: .\nstrictparsing: true\nroles:\n  default: linear\n  scene_linear: linear\n"
		"displays:\n  sRGB:\n    - !<View> {name: Fuzz, colorspace: fuzz}\n"
		"colorspaces:\n  - !<ColorSpace>\n    name: linear\n  - !<ColorSpace>\n    name: fuzz\n"
		"    from_reference: !<FileTransform> {src: %s, interpolation: %s}\n",
		name, data[0] & 4 ? "tetrahedral" : data[0] & 8 ? "nearest" : "linear");
	if (fclose(f))
		abort();
	colour *c = NULL;
	char err[1024];
	colour_desc cd = {.config_path = cfg, .display = "sRGB", .view = "Fuzz", .ignore_env = 1};
	if (colour_create(&cd, &c, err, sizeof err)) {
		if (strchr(err, '\n'))
			abort(); /* a message of more than one line */
	} else {
		for (size_t i = 0; i < colour_lut_count(c); i++) {
			const colour_lut *l = colour_lut_get(c, i);
			size_t n = (size_t)l->width * l->height * l->depth * (size_t)l->channels;
			for (size_t k = 0; k < n; k++)
				if (!isfinite(l->values[k]))
					abort(); /* a non-finite LUT value was accepted */
		}
		float px[] = {0, 0, 0, 1, 0.18f, 0.18f, 0.18f, 1, 1, 1, 1, 1, 16, 4, 0.5f, 1, -0.5f, 0.25f, 2, 1};
		colour_apply(c, px, 5, 4);
		colour_destroy(&c);
	}
	unlink(lut);
	unlink(cfg);
	return 0;
}
