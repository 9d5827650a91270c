/* shader_compile.c — run-time GLSL -> SPIR-V (see shader_compile.h). */
#include "shader_compile.h"

#include <glslang/Include/glslang_c_interface.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const glslang_resource_t *glslang_default_resource(void); /* libglslang-default-resource-limits */

static void first_error(const char *log, char *err, size_t err_size)
{
	const char *e = log ? strstr(log, "ERROR:") : NULL;
	const char *line = e ? e : (log ? log : "unknown error");
	size_t n = strcspn(line, "\n");
	snprintf(err, err_size, "shader compilation failed: %.*s", (int)n, line);
}

/* Compiled shaders of this process, keyed by the whole assembled source and the stage (compared in full: no hash
 * collision can return another shader's code). A render compiles 5-15 shaders; a process that renders many variants
 * (the tests, bench_methods, a sweep's jobs) compiles the same ones again and again, and glslang is most of a small
 * render's set-up time (perf: 40-50 % of a 64x48 render on lavapipe). Only successful compilations are kept. */
typedef struct shc_entry {
	struct shc_entry *next;
	shc_stage stage;
	char *source;
	uint32_t *spirv;
	size_t size_B;
} shc_entry;
static shc_entry *cache_head;
static pthread_mutex_t cache_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_once_t glslang_once = PTHREAD_ONCE_INIT;

/* glslang keeps its built-in symbol tables while the process is initialized: initialized once for the process (its
 * reference count never drops to zero), they are built once per stage instead of once per compilation. */
static void glslang_init_once(void) { glslang_initialize_process(); }

static int cache_lookup(const char *source, shc_stage stage, uint32_t **spirv, size_t *size_B)
{
	int found = 0;
	pthread_mutex_lock(&cache_lock);
	for (shc_entry *e = cache_head; e && !found; e = e->next)
		if (e->stage == stage && !strcmp(e->source, source) && (*spirv = malloc(e->size_B))) {
			memcpy(*spirv, e->spirv, e->size_B);
			*size_B = e->size_B;
			found = 1;
		}
	pthread_mutex_unlock(&cache_lock);
	return found;
}

static void cache_store(const char *source, shc_stage stage, const uint32_t *spirv, size_t size_B)
{
	shc_entry *e = calloc(1, sizeof *e);
	if (!e || !(e->source = strdup(source)) || !(e->spirv = malloc(size_B))) {
		if (e)
			free(e->source);
		free(e);
		return; /* out of memory: not cached, nothing lost */
	}
	memcpy(e->spirv, spirv, size_B);
	e->size_B = size_B;
	e->stage = stage;
	pthread_mutex_lock(&cache_lock);
	e->next = cache_head;
	cache_head = e;
	pthread_mutex_unlock(&cache_lock);
}

int shc_compile(const char *source, shc_stage stage, uint32_t **spirv, size_t *size_B, char *err, size_t err_size)
{
	static const glslang_stage_t stages[] = {GLSLANG_STAGE_VERTEX, GLSLANG_STAGE_FRAGMENT, GLSLANG_STAGE_COMPUTE};
	int rc = -1;
	*spirv = NULL;
	*size_B = 0;
	if (cache_lookup(source, stage, spirv, size_B))
		return 0;
	pthread_once(&glslang_once, glslang_init_once);
	glslang_input_t in = {
		.language = GLSLANG_SOURCE_GLSL,
		.stage = stages[stage],
		.client = GLSLANG_CLIENT_VULKAN,
		.client_version = GLSLANG_TARGET_VULKAN_1_3,
		.target_language = GLSLANG_TARGET_SPV,
		.target_language_version = GLSLANG_TARGET_SPV_1_6,
		.code = source,
		.default_version = 460,
		.default_profile = GLSLANG_NO_PROFILE,
		.messages = GLSLANG_MSG_SPV_RULES_BIT | GLSLANG_MSG_VULKAN_RULES_BIT,
		.resource = glslang_default_resource(),
	};
	glslang_shader_t *sh = glslang_shader_create(&in);
	glslang_program_t *prog = NULL;
	if (!sh) {
		snprintf(err, err_size, "shader compilation failed: out of memory");
		goto done;
	}
	if (!glslang_shader_preprocess(sh, &in) || !glslang_shader_parse(sh, &in)) {
		first_error(glslang_shader_get_info_log(sh), err, err_size);
		goto done;
	}
	prog = glslang_program_create();
	glslang_program_add_shader(prog, sh);
	if (!glslang_program_link(prog, GLSLANG_MSG_SPV_RULES_BIT | GLSLANG_MSG_VULKAN_RULES_BIT)) {
		first_error(glslang_program_get_info_log(prog), err, err_size);
		goto done;
	}
	glslang_program_SPIRV_generate(prog, stages[stage]);
	size_t words = glslang_program_SPIRV_get_size(prog);
	*spirv = malloc(words * sizeof **spirv);
	if (!*spirv) {
		snprintf(err, err_size, "shader compilation failed: out of memory");
		goto done;
	}
	glslang_program_SPIRV_get(prog, *spirv);
	*size_B = words * sizeof **spirv;
	cache_store(source, stage, *spirv, *size_B);
	rc = 0;
done:
	if (prog)
		glslang_program_delete(prog);
	if (sh)
		glslang_shader_delete(sh);
	return rc;
}
