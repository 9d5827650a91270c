/* shader_compile.c — run-time GLSL -> SPIR-V (see shader_compile.h). */
#include "shader_compile.h"

#include <glslang/Include/glslang_c_interface.h>
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

int shc_compile(const char *source, shc_stage stage, uint32_t **spirv, size_t *size_B, char *err, size_t err_size)
{
	static const glslang_stage_t stages[] = {GLSLANG_STAGE_VERTEX, GLSLANG_STAGE_FRAGMENT, GLSLANG_STAGE_COMPUTE};
	int rc = -1;
	*spirv = NULL;
	*size_B = 0;
	glslang_initialize_process(); /* reference counted */
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
	rc = 0;
done:
	if (prog)
		glslang_program_delete(prog);
	if (sh)
		glslang_shader_delete(sh);
	glslang_finalize_process();
	return rc;
}
