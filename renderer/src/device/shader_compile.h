/* shader_compile.h (private) — GLSL to SPIR-V at run time through glslang's C interface, for shaders
 * that contain code only known at run time (the OpenColorIO display function). Build-time shaders are
 * compiled by glslangValidator instead (renderer/CMakeLists.txt). */
#ifndef TASLAB_SHADER_COMPILE_H
#define TASLAB_SHADER_COMPILE_H

#include <stddef.h>
#include <stdint.h>

typedef enum shc_stage { SHC_STAGE_VERTEX, SHC_STAGE_FRAGMENT, SHC_STAGE_COMPUTE } shc_stage;

/* Compiles `source` for Vulkan 1.3; *spirv is malloc'ed (caller frees), *size_B its size in bytes.
 * Returns 0, or -1 with the compiler log's first error line in `err`. */
int shc_compile(const char *source, shc_stage stage, uint32_t **spirv, size_t *size_B, char *err, size_t err_size);

#endif
