/* tl_hash.h — FNV-1a, 64 bits (Fowler, Noll, Vo; the IETF draft "The FNV Non-Cryptographic Hash Algorithm",
 * section 2): the content digests of scenes and display transforms (issue 31.4). A change detector, not a defence
 * against someone forging inputs. */
#ifndef TASLAB_TL_HASH_H
#define TASLAB_TL_HASH_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TL_FNV1A64_INIT 0xcbf29ce484222325ull

/* Folds `n` bytes of `data` into the running hash *h (start from TL_FNV1A64_INIT). */
static inline void tl_fnv1a64(uint64_t *h, const void *data, size_t n)
{
	const unsigned char *p = (const unsigned char *)data;
	for (size_t i = 0; i < n; i++) {
		*h ^= p[i];
		*h *= 0x100000001b3ull;
	}
}

/* 16 hex digits and the terminator. */
#define TL_BUILD_DIGEST_HEX 17

/* The build's digest: FNV-1a 64 of the running executable's bytes as 16 hex digits (computed once per process), or ""
 * when /proc/self/exe cannot be read. Sweeps and run manifests record it so that a resume by another build is refused
 * (a change detector, like the input digests). */
const char *tl_build_digest(void);

#ifdef __cplusplus
}
#endif
#endif
