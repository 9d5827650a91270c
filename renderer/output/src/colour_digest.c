/* colour_digest.c — a content hash of a display transform (colour.h): the GLSL OpenColorIO generated for it and the
 * values of every LUT it samples, so a config edited, or a LUT file it uses rewritten, under the same path gives
 * another digest (issue 31.4). Built from the public colour API only. */
#include <stdio.h>
#include <string.h>

#include "taslab/colour.h"
#include "taslab/tl_hash.h"

void colour_digest(const colour *c, char out[COLOUR_DIGEST_HEX])
{
	uint64_t h = TL_FNV1A64_INIT;
	const char *glsl = colour_glsl(c);
	tl_fnv1a64(&h, glsl, strlen(glsl) + 1);
	for (size_t i = 0; i < colour_lut_count(c); i++) {
		const colour_lut *l = colour_lut_get(c, i);
		const unsigned dims[5] = {l->width, l->height, l->depth, (unsigned)l->channels, (unsigned)l->linear};
		tl_fnv1a64(&h, dims, sizeof dims);
		tl_fnv1a64(&h, l->values, (size_t)l->width * l->height * l->depth * (size_t)l->channels * sizeof *l->values);
	}
	snprintf(out, COLOUR_DIGEST_HEX, "%016llx", (unsigned long long)h);
}
