/* fuzz_scene.c — libFuzzer harness for the scene-file parser (untrusted input: scene JSON).
 * Any input must either load or fail with a one-line message; never crash, leak or hang.
 * Build and run a bounded session with scripts/fuzz-scene. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "taslab/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	scene *s = NULL;
	char err[512];
	if (scene_load_from_memory((const char *)data, size, "fuzz.json", &s, err, sizeof err) == 0) {
		/* Exercise evaluation of whatever loaded, at a few times (including out of range ones). */
		static tlm_mat4 world[4096];
		static scene_light_state lights[SCENE_MAX_LIGHTS];
		if (s->object_count <= 4096)
			for (int i = 0; i < 4; i++)
				scene_eval(s, (float)i * 1.7f - 1.0f, world, lights);
		for (size_t c = 0; c < s->camera_count; c++)
			(void)scene_camera_eval(s, (int)c, 0.5f);
		scene_destroy(&s);
	} else if (memchr(err, '\n', strnlen(err, sizeof err))) {
		__builtin_trap(); /* messages are one line */
	}
	return 0;
}
