/* bench_scene_load.c — median wall time of scene_load (JSON parse, procedural meshes and textures,
 * glTF decoding) over N loads per file. Used by scripts/bench-scenes; not a test.
 *   bench_scene_load N FILE... */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "taslab/scene.h"

static int cmp(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
	if (argc < 3) {
		fprintf(stderr, "usage: bench_scene_load N FILE...\n");
		return 2;
	}
	int n = atoi(argv[1]);
	if (n < 1 || n > 1000) {
		fprintf(stderr, "bench_scene_load: N must be 1..1000\n");
		return 2;
	}
	double *ms = calloc((size_t)n, sizeof *ms);
	for (int f = 2; f < argc; f++) {
		size_t objects = 0;
		for (int i = 0; i < n; i++) {
			struct timespec a, b;
			char err[1024];
			scene *s = NULL;
			clock_gettime(CLOCK_MONOTONIC, &a);
			if (scene_load(argv[f], &s, err, sizeof err)) {
				fprintf(stderr, "bench_scene_load: %s\n", err);
				return 1;
			}
			clock_gettime(CLOCK_MONOTONIC, &b);
			objects = s->object_count;
			scene_destroy(&s);
			ms[i] = (double)(b.tv_sec - a.tv_sec) * 1e3 + (double)(b.tv_nsec - a.tv_nsec) * 1e-6;
		}
		qsort(ms, (size_t)n, sizeof *ms, cmp);
		printf("%s %zu %.2f\n", argv[f], objects, n % 2 ? ms[n / 2] : 0.5 * (ms[n / 2 - 1] + ms[n / 2]));
	}
	free(ms);
	return 0;
}
