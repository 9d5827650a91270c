/* colour_digest.c — a content hash of a display transform (colour.h): the GLSL OpenColorIO generated for it and the
 * values of every LUT it samples, so a config edited, or a LUT file it uses rewritten, under the same path gives
 * another digest (issue 31.4). Built from the public colour API only. */
#include <stdio.h>
#include <string.h>

#include "taslab/colour.h"

/* FNV-1a 64 (IETF draft "The FNV Non-Cryptographic Hash Algorithm", section 2): a change detector. */
static void fnv(uint64_t *h, const void *data, size_t n)
{
	const unsigned char *p = data;
	for (size_t i = 0; i < n; i++) {
		*h ^= p[i];
		*h *= 0x100000001b3ull;
	}
}

void colour_digest(const colour *c, char out[COLOUR_DIGEST_HEX])
{
	uint64_t h = 0xcbf29ce484222325ull;
	const char *glsl = colour_glsl(c);
	fnv(&h, glsl, strlen(glsl) + 1);
	for (size_t i = 0; i < colour_lut_count(c); i++) {
		const colour_lut *l = colour_lut_get(c, i);
		const unsigned dims[5] = {l->width, l->height, l->depth, (unsigned)l->channels, (unsigned)l->linear};
		fnv(&h, dims, sizeof dims);
		fnv(&h, l->values, (size_t)l->width * l->height * l->depth * (size_t)l->channels * sizeof *l->values);
	}
	snprintf(out, COLOUR_DIGEST_HEX, "%016llx", (unsigned long long)h);
}
