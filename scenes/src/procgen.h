/* procgen.h (private) — procedural meshes and textures for scene files.
 * Meshes come with analytic normals, UVs and tangents (w = bitangent sign). */
#ifndef TASLAB_PROCGEN_H
#define TASLAB_PROCGEN_H

#include "taslab/scene.h"

typedef struct procgen_mesh_desc {
	const char *kind;      /* "plane", "box", "sphere", "cylinder", "torus" */
	tlm_vec3 size;         /* plane: x,z extent; box: edge lengths */
	float radius, height;  /* sphere, cylinder; torus: major radius */
	float tube_radius;     /* torus */
	int segments, rings;   /* tessellation */
	float uv_scale;        /* texture repeats per metre (plane/box) or per mesh (others) */
} procgen_mesh_desc;

/* Returns TL_OK, TL_ERR_INPUT (unknown kind / bad parameter: `why` says which) or TL_ERR_NOMEM. */
int procgen_mesh(const procgen_mesh_desc *d, scene_mesh *out, char *why, size_t why_size);
/* Kinds accepted by procgen_mesh, comma separated, for messages. */
const char *procgen_mesh_kinds(void);

typedef enum procgen_pattern {
	PROCGEN_PATTERN_INVALID = 0,
	PROCGEN_PATTERN_FLAT,
	PROCGEN_PATTERN_CHECKER,
	PROCGEN_PATTERN_BRICKS,
	PROCGEN_PATTERN_NOISE,
	PROCGEN_PATTERN_STRIPES,
	PROCGEN_PATTERN_COUNT
} procgen_pattern;

typedef enum procgen_output {
	PROCGEN_OUTPUT_INVALID = 0,
	PROCGEN_OUTPUT_COLOR,       /* sRGB: lerp(color_a, color_b, pattern) */
	PROCGEN_OUTPUT_NORMAL,      /* tangent-space normal from pattern as a height field */
	PROCGEN_OUTPUT_METAL_ROUGH, /* glTF layout: G = roughness, B = metallic, lerp a -> b */
	PROCGEN_OUTPUT_OCCLUSION,   /* R = lerp(a, b) */
	PROCGEN_OUTPUT_COUNT
} procgen_output;

typedef struct procgen_texture_desc {
	procgen_pattern pattern;
	procgen_output output;
	float scale;       /* pattern repeats across the texture (integer keeps it tileable) */
	float a[4], b[4];  /* endpoint values (colour RGB(A), or roughness/metallic, or occlusion) */
	float strength;    /* normal maps: height-to-slope factor */
	uint32_t seed;     /* noise and per-brick variation */
} procgen_texture_desc;

procgen_pattern procgen_pattern_from_string(const char *s);
procgen_output procgen_output_from_string(const char *s);
/* Fills size*size*4 bytes. Deterministic for a given description and size.
 * Returns TL_OK, or TL_ERR_NOMEM when out of memory. */
int procgen_texture(const procgen_texture_desc *d, uint32_t size, uint8_t *rgba);

#endif
