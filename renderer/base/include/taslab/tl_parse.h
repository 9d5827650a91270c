/* tl_parse.h — the one parser of whole numbers, sizes and frame ranges, shared by the command line (cli/parse.c) and
 * the files that carry the same values (sweep files, output/sweep.c), so a value means the same wherever it is given
 * and nothing wraps: "4294967297x1" is refused, not read as 1x1 (issue 31.5).
 *
 * Digits only (no sign, no spaces, no '+', no hex, no exponent); every value is range-checked before it is stored.
 * Each returns TL_OK, or TL_ERR_ARG with `why` set to the reason without the value's name ("is not WxH with each
 * 1..16384"), for the caller to prefix with the option or key ("--size '0x5' ...", "\"size\": '0x5' ..."). */
#ifndef TASLAB_TL_PARSE_H
#define TASLAB_TL_PARSE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The largest frame index + 1 anything accepts: frame numbers fit an int everywhere they are written (sweep.json,
 * manifests, CSV), and a run that long is not one anyone renders. */
#define TL_FRAME_MAX (1u << 30)
/* The largest frame width or height. */
#define TL_SIZE_MAX 16384u

/* Leading digits of `s` as a uint64 without wrapping; *end after them. TL_ERR_ARG when there are none or the value
 * exceeds UINT64_MAX. */
int tl_parse_u64_prefix(const char *s, const char **end, uint64_t *out);
/* All of `s` as a whole number in [lo, hi]. */
int tl_parse_uint(const char *s, uint64_t lo, uint64_t hi, uint64_t *out, char *why, size_t why_size);
/* "WxH" (or "WXH") with each 1..TL_SIZE_MAX. */
int tl_parse_size(const char *s, uint32_t *w, uint32_t *h, char *why, size_t why_size);
/* Frames "A:B" (A..B-1), "A" (one frame), ":B" (0..B-1) or "A:" (A..*b_inout-1, the caller's default end), each
 * bound below TL_FRAME_MAX; *b_given says whether B was given. B must exceed A. */
int tl_parse_frames(const char *s, uint32_t *a, uint32_t *b_inout, bool *b_given, char *why, size_t why_size);

#ifdef __cplusplus
}
#endif
#endif
