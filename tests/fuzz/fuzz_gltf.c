/* fuzz_gltf.c — libFuzzer harness for glTF loading (untrusted input: .gltf and .glb files, issue 12).
 * Each input is written to a temporary file — NAME.glb when it starts with the GLB magic "glTF", NAME.gltf
 * otherwise — and loaded as a bare glTF scene (scene_load_with), so the whole path runs: the size, nesting and
 * container checks, tinygltf, external files and images through the loader's callbacks, accessor
 * validation, normals and tangents, texture resampling, animations, cameras and the framing of the asset.
 * Textures are made at 16 x 16 instead of the bare-glTF default 1024 x 1024: the resampling code is the same
 * for any size, and at 1024 a 50 KB file naming one tiny PNG as 256 images legitimately needs 2 GB (the
 * texture-layer limit), beyond libFuzzer's memory limit.
 * Any input must either load or fail with a one-line message naming the file; never crash, leak or hang.
 * Run a bounded session with `scripts/fuzz gltf SECONDS`.
 *
 * Seeds (tests/fuzz/seeds/gltf/): the small shared sample models with their buffers (and small images)
 * embedded as data URIs, a GLB of one of them, and the hostile files of tests/test_gltf.c. So that verbatim
 * sample .gltf files work as inputs too, the files of ../shared/scenes/<model>/ are linked into the
 * temporary folder at start-up (TASLAB_SHARED_DIR overrides where ../shared is). */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "taslab/scene.h"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char dir[256];

/* Links every file of every sample model folder into `dir` (the models' relative URIs are plain names). */
static void link_shared_models(void)
{
	char shared[4096];
	const char *env = getenv("TASLAB_SHARED_DIR");
	if (env)
		snprintf(shared, sizeof shared, "%s/scenes", env);
	else { /* this file is tests/fuzz/fuzz_gltf.c in the checkout; ../shared sits beside the checkout */
		snprintf(shared, sizeof shared, "%s", __FILE__);
		for (int up = 0; up < 3; up++) {
			char *slash = strrchr(shared, '/');
			if (slash)
				*slash = 0;
		}
		strncat(shared, "/../shared/scenes", sizeof shared - strlen(shared) - 1);
	}
	DIR *models = opendir(shared);
	if (!models) {
		fprintf(stderr, "fuzz_gltf: %s not found: seeds that reference external sample files will not load\n", shared);
		return;
	}
	struct dirent *m;
	while ((m = readdir(models))) {
		char sub[4352];
		snprintf(sub, sizeof sub, "%s/%s", shared, m->d_name);
		DIR *files = m->d_name[0] != '.' ? opendir(sub) : NULL;
		struct dirent *f;
		while (files && (f = readdir(files))) {
			char from[8192], to[512];
			snprintf(from, sizeof from, "%s/%s", sub, f->d_name);
			snprintf(to, sizeof to, "%s/%s", dir, f->d_name);
			if (f->d_name[0] != '.' && symlink(from, to) != 0) {
				/* a name two models share: the first one's file stays */
			}
		}
		if (files)
			closedir(files);
	}
	closedir(models);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
	(void)argc, (void)argv;
	const char *tmp = getenv("TMPDIR");
	snprintf(dir, sizeof dir, "%s/fuzz_gltf.XXXXXX", tmp && *tmp ? tmp : "/tmp");
	if (!mkdtemp(dir)) {
		perror("fuzz_gltf: mkdtemp");
		abort();
	}
	link_shared_models();
	return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	char path[512];
	int glb = size >= 4 && !memcmp(data, "glTF", 4);
	snprintf(path, sizeof path, "%s/input.%s", dir, glb ? "glb" : "gltf");
	FILE *f = fopen(path, "wb");
	if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0)
		abort();
	scene *s = NULL;
	char err[1024] = "";
	if (scene_load_with(path, &(scene_load_desc){.texture_size = 16}, &s, err, sizeof err) == 0) {
		/* Exercise evaluation of whatever loaded, at a few times (including out of range ones). */
		tlm_mat4 *world = malloc((s->object_count + 1) * sizeof *world);
		scene_light_state lights[SCENE_MAX_LIGHTS];
		if (!world || s->light_count > SCENE_MAX_LIGHTS)
			abort();
		for (int i = 0; i < 4; i++)
			scene_eval(s, (float)i * 1.7f - 1.0f, world, lights);
		for (size_t c = 0; c < s->camera_count; c++)
			(void)scene_camera_eval(s, (int)c, 0.5f);
		free(world);
		scene_destroy(&s);
	} else if (s || !err[0] || memchr(err, '\n', strnlen(err, sizeof err)) || !strstr(err, "input.gl")) {
		__builtin_trap(); /* failures leave no scene and say, in one line, which file is wrong */
	}
	unlink(path);
	return 0;
}
