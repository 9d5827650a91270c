/* scene.h — scene description, loading and evaluation as a pure function of time.
 *
 * A scene is loaded once from a JSON scene file (schema: scenes/README.md) into a `scene`
 * that owns everything it references (meshes, generated textures, animations). Rendering
 * never mutates it: `scene_eval` computes object transforms and light placements for any time
 * t, and `scene_camera_eval` a camera pose, so frame f (t = f / fps) can be rendered in any
 * order, and the past can be re-evaluated (DESIGN section 2; paper section 3, TFR).
 *
 * Ownership: `scene_load` allocates; `scene_destroy` frees everything and nulls the pointer.
 * Errors: negative return; a one-line message naming the file and JSON path of the bad value
 * is written into the caller's buffer.
 */
#ifndef TASLAB_SCENE_H
#define TASLAB_SCENE_H

#include "taslab/tl_error.h"
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "taslab/anim.h"
#include "taslab/tl_math.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SCENE_NAME_MAX 64
/* Cameras that make a meaningful image (scene files' fov_deg and glTF cameras alike): vertical field of view in
 * degrees, and the largest zfar / znear (float depth precision). */
#define SCENE_FOV_MIN_DEG 1.0
#define SCENE_FOV_MAX_DEG 179.0
#define SCENE_DEPTH_RANGE_MAX 1e7
#define SCENE_MAX_LIGHTS 16       /* shading loop bound (= GPU_MAX_LIGHTS, renderer/shaders/common/gpu_layout.h) */
#define SCENE_MAX_SHADOW_LAYERS 48 /* directional/spot: 1 layer, point: 6 (cube faces) */
#define SCENE_TEX_NONE (-1)

/* Limits on untrusted input: files beyond them are refused with TL_ERR_INPUT and a message. */
#define SCENE_MAX_JSON_DEPTH 64                /* nesting of [ and { in a glTF's JSON */
#define SCENE_GLTF_MAX_JSON_BYTES (64u << 20)  /* a .gltf file, or the JSON chunk of a .glb */
#define SCENE_GLTF_MAX_FILE_BYTES (1u << 30)   /* a .glb, and each external buffer or image file */
#define SCENE_MAX_IMAGE_SIDE 16384             /* width and height of a glTF image, in pixels */
#define SCENE_MAX_TEXTURES 256                 /* per colour space (sRGB, linear): Vulkan's guaranteed
						  maxImageArrayLayers, the renderer's texture arrays */

/* Vertex layout shared with the shaders (48 bytes). Tangent w = bitangent sign (glTF). */
typedef struct scene_vertex {
	float position[3];
	float normal[3];
	float uv[2];
	float tangent[4];
} scene_vertex;

typedef struct scene_mesh {
	char name[SCENE_NAME_MAX];
	scene_vertex *vertices;
	uint32_t vertex_count;
	uint32_t *indices;
	uint32_t index_count;
	tlm_vec3 bounds_min, bounds_max;
} scene_mesh;

/* A texture generated at load time at the scene's texture size (square, RGBA8). */
typedef struct scene_texture {
	char name[SCENE_NAME_MAX];
	bool srgb;     /* colour data (base colour, emissive) vs. linear data */
	uint8_t *rgba; /* texture_size^2 * 4 bytes, mip 0 */
} scene_texture;

typedef enum scene_alpha_mode {
	SCENE_ALPHA_OPAQUE = 0,
	SCENE_ALPHA_MASK,
	SCENE_ALPHA_BLEND,
	SCENE_ALPHA_COUNT
} scene_alpha_mode;

/* glTF 2.0 metal-roughness material. Texture fields index scene.textures or are SCENE_TEX_NONE. */
typedef struct scene_material {
	char name[SCENE_NAME_MAX];
	float base_color[4];
	float metallic, roughness;
	float emissive[3];
	float normal_scale;
	float occlusion_strength;
	scene_alpha_mode alpha_mode;
	float alpha_cutoff;
	bool double_sided;
	int base_color_tex, metal_rough_tex, normal_tex, emissive_tex, occlusion_tex;
} scene_material;

typedef struct scene_object {
	char name[SCENE_NAME_MAX];
	int mesh, material;
	int parent; /* index into scene.objects, or -1 */
	bool casts_shadow;
	tlm_trs base;
	size_t motion_count;
	anim_motion *motions;
} scene_object;

typedef enum scene_light_kind {
	SCENE_LIGHT_INVALID = 0,
	SCENE_LIGHT_DIRECTIONAL,
	SCENE_LIGHT_POINT,
	SCENE_LIGHT_SPOT,
	SCENE_LIGHT_COUNT
} scene_light_kind;

/* Punctual light as in KHR_lights_punctual: points down its local -Z; intensity in lux
 * (directional) or candela (point, spot); range 0 = infinite. */
typedef struct scene_light {
	char name[SCENE_NAME_MAX];
	scene_light_kind kind;
	float color[3];
	float intensity;
	float range;
	float inner_cone_deg, outer_cone_deg;
	bool casts_shadow;
	float shadow_extent; /* directional: half-size of the shadow box around `shadow_center` */
	tlm_vec3 shadow_center;
	tlm_trs base;
	size_t motion_count;
	anim_motion *motions;
	/* "intensity_keys": piecewise-linear intensity over time (held before the first / after the last
	 * key); none = constant `intensity`. */
	size_t intensity_key_count;
	float *intensity_times, *intensity_values;
} scene_light;

typedef enum scene_camera_motion {
	SCENE_CAMERA_INVALID = 0,
	SCENE_CAMERA_STATIONARY,
	SCENE_CAMERA_MOVING,
	SCENE_CAMERA_COUNT
} scene_camera_motion;

typedef struct scene_camera_key {
	float t;
	tlm_vec3 position, target;
} scene_camera_key;

/* Named camera path: positions and look-at targets interpolated with a C1 cubic Hermite
 * spline whose tangents are central differences over the key times (Catmull-Rom for
 * non-uniform keys); one key = stationary. */
typedef struct scene_camera {
	char name[SCENE_NAME_MAX];
	scene_camera_motion motion;
	float fov_deg;
	float znear, zfar;
	size_t key_count;
	scene_camera_key *keys;
} scene_camera;

typedef struct scene {
	char name[SCENE_NAME_MAX];
	char *path;
	float duration_s;
	float fps;
	float exposure;       /* linear multiplier applied before the display transform */
	float ambient[3];     /* constant ambient radiance (times occlusion) */
	float sky[3];         /* background radiance */
	uint32_t texture_size;/* edge of every texture layer */
	uint32_t shadow_map_size;
	size_t mesh_count, texture_count, material_count, object_count, light_count, camera_count;
	scene_mesh *meshes;
	scene_texture *textures;
	scene_material *materials;
	scene_object *objects;
	scene_light *lights;
	scene_camera *cameras;
} scene;

/* Light placement at time t. */
typedef struct scene_light_state {
	tlm_vec3 position;
	tlm_vec3 direction; /* unit, the way the light points */
	float intensity;
} scene_light_state;

typedef struct scene_camera_state {
	tlm_vec3 eye, target;
	float fov_deg, znear, zfar;
} scene_camera_state;


/* A content hash of a loaded scene: its file's bytes and everything loaded from it and its assets (meshes, texels,
 * materials, placement), as 16 hex digits (FNV-1a 64). Sweeps and run manifests record it, so a run made before the
 * scene or one of its assets changed is told apart (issue 31.4). */
#define SCENE_DIGEST_HEX 17
void scene_digest(const scene *s, char out[SCENE_DIGEST_HEX]);

/* Loads a scene file. `err` receives "FILE: $.json.path: what is wrong" on failure. */
int scene_load(const char *path, scene **out, char *err, size_t err_size);

/* Options of scene_load_with; zero-initialised = scene_load. */
typedef struct scene_load_desc {
	/* Edge of every texture layer (a power of two, 4..4096) instead of the scene file's texture_size (a bare
	 * glTF file's default: 1024); 0 keeps it. Texture memory grows with its square: small sizes make quick
	 * previews and keep fuzzing inside its memory limit. */
	uint32_t texture_size;
} scene_load_desc;
/* scene_load with options (desc may be NULL). TL_ERR_ARG for an invalid option. */
int scene_load_with(const char *path, const scene_load_desc *desc, scene **out, char *err, size_t err_size);
/* Same, from a JSON text already in memory (`origin` names it in messages; used by fuzzing). */
int scene_load_from_memory(const char *json, size_t len, const char *origin, scene **out, char *err,
			   size_t err_size);
void scene_destroy(scene **s);

/* Object world matrices (object_count entries, parents applied) and light placements
 * (light_count entries) at time t. Either output may be NULL. */
void scene_eval(const scene *s, float t, tlm_mat4 *object_world, scene_light_state *lights);
/* Mirror flags of world matrices as scene_eval writes them (object_count entries each): 1 where the determinant of
 * the upper 3x3 is negative, else 0. glTF 2.0 §3.7.2.1: "the determinant of the node's global transform defines the
 * winding order of that primitive. If the determinant is a positive value, the winding order triangle faces is
 * counterclockwise; in the opposite case, the winding order is clockwise." A mirrored object's front faces are
 * therefore clockwise: the renderer sets the rasterizer's front face per draw and flips its own winding tests
 * (README "Mirrored nodes"). The flag follows the world matrix, so an animated scale that changes sign flips it
 * at the frame it does. */
void scene_mirrors(const scene *s, const tlm_mat4 *object_world, uint8_t *mirrored);
/* Index of the named camera, or -1. */
int scene_find_camera(const scene *s, const char *name);
scene_camera_state scene_camera_eval(const scene *s, int camera, float t);
const char *scene_camera_motion_name(scene_camera_motion m);
const char *scene_light_kind_name(scene_light_kind k);
/* Number of shadow-map layers the scene's lights use (<= SCENE_MAX_SHADOW_LAYERS). */
uint32_t scene_shadow_layer_count(const scene *s);

#ifdef __cplusplus
}
#endif
#endif
