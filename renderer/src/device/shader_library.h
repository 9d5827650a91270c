/* shader_library.h (private) — the GLSL sources of renderer/shaders/, embedded by the build.
 *
 * Every *.glsl include file, *.h header shared with C (common/gpu_layout.h) and *.in run-time template under
 * renderer/shaders/<family>/ is listed in a table the build generates (shader_sources.c), keyed by its path below
 * shaders/ ("common/shading.glsl").
 * Shaders complete at build time (*.vert, *.frag, *.comp) are compiled by glslangValidator into SPIR-V
 * headers "shaders/<family>/<name>_<stage>.h"; templates are completed at run time: their #include lines
 * are resolved from the table and the marker line `// @OCIO_DISPLAY@` is replaced by the OpenColorIO
 * function of the active view transform (colour.h). Adding a shader folder needs no build change. */
#ifndef TASLAB_SHADER_LIBRARY_H
#define TASLAB_SHADER_LIBRARY_H

#include <stddef.h>

/* The embedded text of `path` ("tfr/tfr.frag.in"), or NULL. */
const char *shader_source(const char *path);

/* Assembles template `path` into one GLSL source: includes resolved (each file once; they are
 * include-guarded), `ocio_glsl` inserted at the marker. *out is malloc'ed (caller frees).
 * TL_ERR_INTERNAL naming an unknown template or include. */
int shader_assemble(const char *path, const char *ocio_glsl, char **out, char *err, size_t err_size);
/* The same with `defines` (e.g. "#define TARC 1\n", may be NULL) inserted after the #version line: one
 * template, several variants, no run-time branches between them (a SIMD CPU driver pays for every branch). */
int shader_assemble_defs(const char *path, const char *ocio_glsl, const char *defines, char **out, char *err,
			 size_t err_size);

#endif
