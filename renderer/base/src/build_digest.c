/* build_digest.c — tl_build_digest (tl_hash.h): FNV-1a 64 of the running executable's bytes, so that a sweep resumed
 * by another taslab build (another commit, other flags, another compiler) is told apart from the build that made its
 * runs. The shaders are embedded in the executable (renderer/shaders.cmake), so they count too; the shared libraries
 * (Vulkan driver, OpenColorIO) do not: the manifests record their versions. */
#include <stdio.h>
#include <threads.h> /* call_once: C11, in glibc's libc */

#include "taslab/tl_hash.h"

static char digest[TL_BUILD_DIGEST_HEX];

static void compute(void)
{
	FILE *f = fopen("/proc/self/exe", "rb");
	if (!f)
		return; /* digest stays "": "unknown build" */
	uint64_t h = TL_FNV1A64_INIT;
	static unsigned char buf[1 << 16];
	size_t n;
	while ((n = fread(buf, 1, sizeof buf, f)) > 0)
		tl_fnv1a64(&h, buf, n);
	if (!ferror(f))
		snprintf(digest, sizeof digest, "%016llx", (unsigned long long)h);
	fclose(f);
}

const char *tl_build_digest(void)
{
	static once_flag once = ONCE_FLAG_INIT;
	call_once(&once, compute);
	return digest;
}
