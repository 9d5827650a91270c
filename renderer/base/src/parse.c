/* parse.c — whole numbers, sizes and frame ranges (tl_parse.h): one parser for the command line and the files. */
#include "taslab/tl_parse.h"

#include <stdio.h>

#include "taslab/tl_error.h"

int tl_parse_u64_prefix(const char *s, const char **end, uint64_t *out)
{
	uint64_t v = 0;
	const char *p = s;
	if (!s || *p < '0' || *p > '9')
		return TL_ERR_ARG;
	for (; *p >= '0' && *p <= '9'; p++) {
		const uint64_t d = (uint64_t)(*p - '0');
		if (v > (UINT64_MAX - d) / 10)
			return TL_ERR_ARG; /* would wrap */
		v = v * 10 + d;
	}
	*out = v;
	*end = p;
	return TL_OK;
}

int tl_parse_uint(const char *s, uint64_t lo, uint64_t hi, uint64_t *out, char *why, size_t why_size)
{
	const char *e;
	uint64_t v;
	if (tl_parse_u64_prefix(s, &e, &v) || *e || v < lo || v > hi)
		return tl_error(why, why_size, TL_ERR_ARG, "must be a whole number in [%llu, %llu]", (unsigned long long)lo,
				(unsigned long long)hi);
	*out = v;
	return TL_OK;
}

/* A uint32 prefix bounded by `hi`. */
static int u32_prefix(const char *s, const char **end, uint32_t hi, uint32_t *out)
{
	uint64_t v;
	if (tl_parse_u64_prefix(s, end, &v) || v > hi)
		return TL_ERR_ARG;
	*out = (uint32_t)v;
	return TL_OK;
}

int tl_parse_size(const char *s, uint32_t *w, uint32_t *h, char *why, size_t why_size)
{
	const char *e;
	uint32_t a, b;
	if (u32_prefix(s, &e, TL_SIZE_MAX, &a) || (*e != 'x' && *e != 'X') || u32_prefix(e + 1, &e, TL_SIZE_MAX, &b) || *e ||
	    a < 1 || b < 1)
		return tl_error(why, why_size, TL_ERR_ARG, "is not WIDTHxHEIGHT with each 1..%u (e.g. 960x540)", TL_SIZE_MAX);
	*w = a, *h = b;
	return TL_OK;
}

int tl_parse_frames(const char *s, uint32_t *a, uint32_t *b_inout, bool *b_given, char *why, size_t why_size)
{
	const char *e = s;
	uint32_t lo = 0, hi = *b_inout;
	*b_given = false;
	if (!s || !*s)
		goto bad;
	if (*e != ':' && u32_prefix(e, &e, TL_FRAME_MAX - 1, &lo))
		goto bad;
	if (*e == 0) { /* single frame */
		if (e == s)
			goto bad;
		hi = lo + 1;
		*b_given = true;
	} else if (*e == ':') {
		e++;
		if (*e) {
			if (u32_prefix(e, &e, TL_FRAME_MAX, &hi) || *e)
				goto bad;
			*b_given = true;
		}
	} else {
		goto bad;
	}
	if (hi <= lo)
		return tl_error(why, why_size, TL_ERR_ARG, "is empty: A:B renders frames A..B-1, so B must exceed A");
	*a = lo;
	*b_inout = hi;
	return TL_OK;
bad:
	return tl_error(why, why_size, TL_ERR_ARG, "is not A:B, A, :B or A: with frames below %u (e.g. 0:60 for frames 0..59)",
			TL_FRAME_MAX);
}
