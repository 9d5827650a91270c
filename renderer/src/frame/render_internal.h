/* render_internal.h (private) — the frame core: the `render` object, the method interface, and the
 * building blocks every pass and method uses (scene upload, state rings, targets, pipelines, draws,
 * command buffer and timestamps).
 *
 * Layers inside the renderer (each includes only the ones below it):
 *   render.c, run_render.c (composition: the public render.h API)
 *   methods/ (one file per method + registry.c), analysis/ (TFR analysis)
 *   passes/  (shadow, depth, shade, display, readback, tas_filter: passes.h)
 *   frame/   (this header: the core)
 *   device/  (Vulkan device, shader compilation and the generated shader library)
 */
#ifndef TASLAB_RENDER_INTERNAL_H
#define TASLAB_RENDER_INTERNAL_H

#include <stdio.h>

#include "../device/shader_compile.h"
#include "../device/shader_library.h"
#include "gpu_types.h"
#include "taslab/colour_gpu.h"
#include "taslab/method.h"
#include "taslab/render.h"

/* ---- the method interface (one implementation per file in methods/) ---- */

typedef struct render_method {
	method_info info;              /* name, summary, option table (method.h) */
	const char *const *pass_names; /* timestamp intervals recorded by `record`, in order */
	uint32_t pass_count;
	uint32_t state_ring;           /* state slots the method needs (0: 1) */
	int (*init)(render *r, char *err, size_t err_size);
	/* Before recording frame `frame`: update state slots and plan their shadow maps (may allocate and
	 * update descriptors, which is why it runs outside the command buffer). */
	int (*prepare)(render *r, uint32_t frame, char *err, size_t err_size);
	/* Methods with a CPU step inside the frame (the atlas allocation, TAS-METHODS section 8.8): record_pre
	 * records the passes before it into `cmd`, which is submitted and waited for; then cpu_step runs; then
	 * `record` records the rest into a fresh command buffer. Timestamps run on across both (render_ts before each
	 * pass, the interval spanning the CPU step being a pass of its own). NULL: one command buffer. */
	void (*record_pre)(render *r, VkCommandBuffer cmd, uint32_t frame);
	int (*cpu_step)(render *r, uint32_t frame, char *err, size_t err_size);
	/* Records the frame into `cmd`; must call render_ts() once before each pass and once at the end. */
	void (*record)(render *r, VkCommandBuffer cmd, uint32_t frame);
	/* Fills the method-specific statistics after the frame completed. */
	void (*collect)(render *r, frame_stats *st);
	/* With render_desc.decisions (method_info.decisions): one frame_decision per pixel of the last frame. */
	const uint8_t *(*decisions)(render *r);
	/* With render_desc.rate_images (method_info.tile_rates): one frame_rate per 16x16 tile of the last frame, as the
	 * frame's passes read them (tiles_x x tiles_y). */
	const uint8_t *(*tile_rates)(render *r, uint32_t *tiles_x, uint32_t *tiles_y);
	void (*finish)(render *r);
	/* Values the method derived from its options and the frame size at init (the atlas size, the density used when
	 * the option says "default"), for the manifest's inputs.method_derived; returns the count (<= max). NULL: none. */
	size_t (*derived)(const render *r, run_option *out, size_t max);
	/* Stereo (STEREO.md): false, the frame core runs the method once per eye (its own state per eye, init and
	 * finish per eye); true, the method renders every view itself in one frame (the atlas methods share their
	 * atlas) using render_use_view, leaves view 0 active, and reports each eye's shaded samples in
	 * render.view_shaded from collect. */
	bool shared_views;
} render_method;

/* The registry (methods/registry.c, the only list of methods; each method file defines its render_method_NAME):
 * the implementation of an available method, else NULL. */
const render_method *render_method_of(const method_info *info);

/* ---- the render object ---- */

/* Shadow maps: a pool of physical layers shared by the state slots (passes/shadow.c). A physical layer's
 * global index is chunk_base[c] + its layer in chunk c; every logical layer lives in its own pinned chunk. */
typedef struct render_shadow_pool {
	uint32_t layers;       /* logical layers per slot (lights: 1, point lights: 6) */
	uint32_t size;         /* shadow map size */
	uint32_t chunk_count;  /* chunk images allocated so far */
	uint32_t chunks_max;   /* chunks the layers are pinned to */
	uint32_t chunk_cap[GPU_SHADOW_CHUNKS];  /* layers of chunk c (its pinned layers' worst case) */
	uint32_t chunk_base[GPU_SHADOW_CHUNKS]; /* global index of chunk c's first layer */
	uint32_t *layer_chunk; /* per logical layer: its chunk */
	int32_t *light_code;   /* per light: LIGHT_SHADOW_i of shading.glsl (chunks and split face), -1 none */
	vkdev_image chunks[GPU_SHADOW_CHUNKS];
	vkdev_image dummy;     /* bound for chunks not allocated (yet) */
	VkImageView *views;    /* per physical layer */
	uint32_t *refs;        /* per physical layer: slots mapping to it */
	uint32_t *owner;       /* per physical layer: logical layer whose content it holds */
	uint32_t *slot_phys;   /* state_ring x layers */
	uint8_t *todo;         /* state_ring x layers: planned, not rendered yet */
	uint8_t *casters;      /* state_ring x layers x caster_bytes: casters reaching into the layer (bits) */
	size_t caster_bytes;
	uint64_t *last_key;    /* per logical layer: inputs of its last rendering */
	uint32_t *last_phys;
	uint64_t rendered, reused; /* layer renderings and shares so far */
} render_shadow_pool;

typedef struct render_pipeline {
	VkPipeline pipeline;
	VkPipelineLayout layout;
} render_pipeline;

/* Stereo (STEREO.md): what each view (eye) has of its own. The active view's values live in the render's own fields
 * (r->hdr, r->states, ...), so passes and per-eye methods run unchanged; render_use_view swaps them. The shadow pool,
 * the scene's geometry, materials and textures, the pipelines and the command buffer are shared. */
#define RENDER_MAX_VIEWS 2
/* What --multiview auto chooses (README "Multiview": measured at 960x540 per eye) */
#define RENDER_MULTIVIEW_AUTO_ON 0
typedef struct render_view_ctx {
	vkdev_buffer states, objects, shade_count;
	vkdev_image depth, hdr, display;
	vkdev_buffer readback_hdr, readback_display;
	uint16_t *hdr_packed;
	uint8_t *display_packed;
	VkDescriptorSet scene_set, display_set;
	void *method_state;
	tlm_vec3 eye;
} render_view_ctx;

struct render {
	vkdev *dev;
	const scene *scene;
	render_desc desc;
	method_config config;     /* copy of *desc.method (desc.method points here) */
	const render_method *method;
	void *method_state;

	/* views (STEREO.md): 1 mono, 2 stereo (0 left, 1 right); views[v] holds view v's fields while it is inactive */
	uint32_t view_count, view;
	bool multiview;           /* stereo: raster passes of both eyes in one viewMask 0b11 pass (render_desc.multiview) */
	render_view_ctx views[RENDER_MAX_VIEWS];
	double *slot_time;        /* stereo: per state slot, the time last evaluated into every view (NAN: none) */
	int64_t view_shaded[RENDER_MAX_VIEWS]; /* shared_views methods: each eye's shaded samples of the frame (-1: n/a) */

	uint32_t state_ring;      /* slots in the state and object rings */
	uint32_t push_aux[4];     /* copied into gpu_push.aux of every draw */

	/* scene on the GPU (frame/upload.c) */
	vkdev_buffer vertices, indices;
	uint32_t *mesh_first_index, *mesh_vertex_offset;
	vkdev_buffer materials;
	vkdev_buffer states;      /* FrameState x state_ring, host visible */
	vkdev_buffer shade_count; /* uint: fragments the reference shading ran for (scene set binding 6), host visible */
	vkdev_buffer objects;     /* GpuObject x object_count x state_ring, host visible */
	vkdev_image color_tex, data_tex;
	VkSampler tex_sampler, shadow_sampler;
	render_shadow_pool shadow; /* D32 layers, one per light (point lights: 6) per slot */
	int *light_shadow_layer;  /* first shadow layer per light, -1 none */

	/* targets (frame/targets.c) */
	vkdev_image depth, hdr, display;
	vkdev_buffer readback_hdr, readback_display;
	uint32_t row_pitch_hdr_B, row_pitch_display_B;
	uint16_t *hdr_packed;
	uint8_t *display_packed;

	/* descriptors and pipelines */
	VkDescriptorSetLayout scene_set_layout, display_set_layout;
	VkDescriptorPool pool;
	VkDescriptorSet scene_set, display_set;
	render_pipeline shadow_pipe, depth_pipe, shade_pipe, display_pipe;
	render_pipeline shadow_mask_pipe, depth_mask_pipe, shade_blend_pipe; /* glTF alphaMode MASK / BLEND */
	tlm_vec3 eye;             /* camera position of the last render_update_state (blend sorting) */
	uint32_t *blend_order;    /* BLEND objects, sorted back to front each frame */
	uint32_t blend_count;

	/* queries and submission */
	VkQueryPool ts_pool, stats_pool;
	/* the pipeline-statistics query was begun in this frame's command buffer (render_stats_begin): only then are its
	 * results waited for. A query never written since its reset never becomes available, and waiting on it hangs on
	 * NVIDIA's driver (the vbuf methods have no shading pass that records it); lavapipe returned at once. */
	bool stats_recorded;
	uint32_t ts_count;
	VkCommandBuffer cmd;
	VkFence fence;

	colour *own_colour;       /* created when desc.colour is NULL */
	const colour *colour;
	colour_device *colour_dev; /* its GLSL for this device (the LUTs of a view in a device buffer) */

	/* scratch */
	tlm_mat4 *world;
	uint8_t *mirrored; /* scene_mirrors of `world` (GpuObject.material.y of the slot last evaluated) */
	scene_light_state *light_states;
};

/* ---- frame/upload.c: the scene on the device ---- */
int render_upload_scene(render *r, char *err, size_t err_size);
/* The active view's state and object rings and shading counter (render_upload_scene calls it for view 0). */
int render_upload_rings(render *r, char *err, size_t err_size);
void render_upload_destroy(render *r);

/* ---- frame/state.c: state rings ---- */
/* Evaluates the scene and camera at `time_s` into state slot `slot` (FrameState + object ring). In stereo it
 * writes the slot of every view at once (the scene evaluated once, each view with its eye: STEREO.md
 * e_{L,R} = eye -/+ (ipd/2) r, targets shifted alike); a view > 0 asking again for the same slot and time finds it
 * written and evaluates nothing. */
void render_update_state(render *r, uint32_t slot, double time_s);
/* Stereo: the centre-eye state slot (index state_ring of the active view's rings, allocated in stereo only): a copy
 * of slot `slot` (objects, lights and shadow layers included, so call it after render_shadow_plan) with the centre
 * camera, from which the atlas methods shade the texels both eyes share. Returns its index. */
uint32_t render_center_slot(render *r, uint32_t slot, double time_s);
/* Stereo, for methods that record every eye in one frame: the other views' slot `slot` maps the shadow layers the
 * active view's planned (render_shadow_plan once, the layers rendered once). */
void render_share_shadows(render *r, uint32_t slot);

/* ---- frame/view.c: views ---- */
/* Makes view v the active one (its targets, state rings, descriptor sets and method state in the render's fields). */
void render_use_view(render *r, uint32_t v);
/* Creates the active view's own resources (state rings, targets, readback, scene and display sets) after view 0's
 * were created by render_upload_scene, render_targets_create and render_descriptors_create. */
int render_view_create(render *r, char *err, size_t err_size);
/* Destroys the active view's own resources (not view 0's: render_destroy does those). */
void render_view_destroy(render *r);

/* ---- frame/targets.c: render targets, samplers, readback buffers, the scene descriptor set ---- */
int render_targets_create(render *r, char *err, size_t err_size);
int render_descriptors_create(render *r, char *err, size_t err_size);
/* The active view's depth, HDR and display targets and readback buffers (render_targets_create: view 0's), and its
 * scene and display descriptor sets (render_descriptors_create: view 0's; the shadow maps' binding 5 is shadow.c's). */
int render_targets_view_create(render *r, char *err, size_t err_size);
int render_descriptors_view_create(render *r, char *err, size_t err_size);
void render_targets_destroy(render *r);

/* ---- frame/pipeline.c: pipelines ---- */
/* A graphics pipeline of the frame pipeline; zero-initialised fields mean "off". */
/* The scene's depth target: 32-bit float depth (the pre-pass) with 8-bit stencil (the reuse decisions of rrc
 * and tarc mask their shading passes). Shadow layers are plain D32. */
#define RENDER_DEPTH_FORMAT VK_FORMAT_D32_SFLOAT_S8_UINT

enum {
	RENDER_STENCIL_NONE = 0,  /* no stencil attachment */
	RENDER_STENCIL_ATTACHED,  /* attached, not tested */
	RENDER_STENCIL_WRITE_ONE, /* always passes, writes 1 (a decision pass marking pixels to shade) */
	RENDER_STENCIL_EQUAL_ONE, /* passes where the stencil is 1 (shade the marked pixels) */
	RENDER_STENCIL_EQUAL_ZERO, /* passes where the stencil is 0 (the unmarked, reused pixels) */
};

typedef struct render_pipe_desc {
	const uint32_t *vs, *fs; /* vs NULL: common/scene.vert, the one vertex shader of all scene passes */
	size_t vs_size, fs_size;
	unsigned attributes;   /* bit i: vertex attribute location i (0 position, 1 normal, 2 uv, 3 tangent) */
	int depth_write, color, bias, blend; /* color: the number of colour attachments (0-4; formats below) */
	VkCompareOp depth_op;
	int no_depth_test;     /* depth test off (full-screen passes) */
	int stencil;           /* RENDER_STENCIL_* */
	int fullscreen;        /* common/fullscreen.vert, no vertex input, no culling state */
	VkFormat depth_format; /* 0: RENDER_DEPTH_FORMAT */
	VkFormat color_format; /* 0: the HDR target's RGBA16F */
	VkFormat color2_format; /* the second attachment's (location 1) format; 0: color_format's (the others') */
	int fs_alpha_blend;    /* value of shade.frag's ALPHA_BLEND specialisation constant */
	uint32_t view_mask;    /* multiview (render.multiview): the render pass's viewMask; 0: one view */
	VkDescriptorSetLayout method_set; /* optional set 1 */
} render_pipe_desc;

#define RENDER_ATTR_POSITION 1u
#define RENDER_ATTR_UV 4u
#define RENDER_ATTR_ALL 15u

VkResult render_make_graphics(render *r, const render_pipe_desc *pd, render_pipeline *out);
/* How the shading passes count their own fragments (ref/count.glsl, reproj/reproj.glsl COUNT): one atomic per
 * subgroup where the device has ballot subgroup operations in fragment shaders (lavapipe: subgroups of 8), with
 * or without leaving helper invocations out (llvmpipe has none and cannot compile gl_HelperInvocation); one per
 * fragment otherwise, or with TASLAB_COUNT_ATOMICS=1 in the environment (test_reuse compares the two). */
typedef enum { RENDER_COUNT_ATOMIC = 0, RENDER_COUNT_SUBGROUP, RENDER_COUNT_SUBGROUP_NO_HELPERS } render_count_mode;
render_count_mode render_count_mode_of(VkPhysicalDevice pd);
/* Whether the device has the subgroup operations ops in every stage of stage. */
bool render_subgroup_has(VkPhysicalDevice pd, VkShaderStageFlags stage, VkSubgroupFeatureFlags ops);
/* Whether compute shaders may count with ballot subgroup operations (TL_SUBGROUP: one atomic per subgroup; compute
 * has no helper invocations); false also with TASLAB_COUNT_ATOMICS=1. */
bool render_compute_ballot(VkPhysicalDevice pd);
/* Specialisation constants of every pipeline (entries for constants a shader does not declare are ignored):
 * 0 ALPHA_BLEND (shade.frag), 2 LIGHT_COUNT and 3 + i LIGHT_SHADOW_i (shading.glsl: the light loop unrolled,
 * each light's shadow chunk a constant). */
#define RENDER_SPEC_COUNT (3 + SCENE_MAX_LIGHTS)
typedef struct render_spec {
	int32_t values[RENDER_SPEC_COUNT];
	VkSpecializationMapEntry entries[RENDER_SPEC_COUNT];
} render_spec;
void render_specialization(const render *r, int alpha_blend, render_spec *data, VkSpecializationInfo *out);
/* Shading pipeline like the reference one (common/scene.vert, depth EQUAL) with fragment shader `fs` and an
 * optional descriptor set 1. */
VkResult render_make_shade_pipeline(render *r, const uint32_t *fs, size_t fs_size, VkDescriptorSetLayout method_set,
				    render_pipeline *out);
/* The same for a run-time template (render_compile_defs) with stencil mode `stencil`, colour output on or off,
 * and full-screen (one triangle, no depth test) or scene geometry (depth EQUAL). */
int render_make_template_pipeline(render *r, const char *template_path, const char *defines,
				  VkDescriptorSetLayout method_set, int stencil, int color, int fullscreen, render_pipeline *out,
				  char *err, size_t err_size);
/* Compute pipeline from SPIR-V with the given layout. */
VkResult render_make_compute(render *r, const uint32_t *spv, size_t spv_size, VkPipelineLayout layout, VkPipeline *out);
void render_pipeline_destroy(render *r, render_pipeline *p);
/* Compiles a run-time shader template (includes and the OCIO display function resolved, see
 * device/shader_library.h). */
int render_compile(const render *r, const char *template_path, shc_stage stage, uint32_t **spv, size_t *spv_size,
		   char *err, size_t err_size);
/* The same with `defines` inserted after #version (template variants without run-time branches). */
int render_compile_defs(const render *r, const char *template_path, const char *defines, shc_stage stage,
			uint32_t **spv, size_t *spv_size, char *err, size_t err_size);
/* A compute pipeline from a template with `defines` and `layout` (render_compile_defs + render_make_compute). */
int render_compute_defs(render *r, const char *template_path, const char *defines, VkPipelineLayout layout,
			VkPipeline *out, char *err, size_t err_size);

/* ---- frame/draw.c: drawing the scene, timestamps, the command buffer ---- */
#define RENDER_ALPHA_BIT(m) (1u << (m))
#define RENDER_OPAQUE_BIT RENDER_ALPHA_BIT(SCENE_ALPHA_OPAQUE)
#define RENDER_MASK_BIT RENDER_ALPHA_BIT(SCENE_ALPHA_MASK)
#define RENDER_BLEND_BIT RENDER_ALPHA_BIT(SCENE_ALPHA_BLEND)

void render_bind_scene(render *r, VkCommandBuffer cmd, const render_pipeline *p);
void render_set_viewport(VkCommandBuffer cmd, uint32_t w, uint32_t h);
void render_draw_object(render *r, VkCommandBuffer cmd, const render_pipeline *p, uint32_t slot, uint32_t layer,
			size_t i, int set_cull);
/* Draws the objects whose material alpha mode is in `modes` (RENDER_ALPHA_BIT set), in scene order; with
 * `only` (object_count bits, may be NULL) just the objects whose bit is set. */
void render_draw_objects(render *r, VkCommandBuffer cmd, const render_pipeline *p, uint32_t slot, uint32_t layer,
			 unsigned modes, const uint8_t *only, int set_cull);
int render_has_alpha_mode(const render *r, scene_alpha_mode mode);
/* Whether object i is mirrored at state slot `slot` of the active view (its GpuObject.material.y, scene_mirrors):
 * glTF 2.0 §3.7.2.1, its front faces are clockwise. */
bool render_object_mirrored(const render *r, uint32_t slot, size_t i);
/* Sets the cull mode (back faces for single-sided materials) and the front face (clockwise for a mirrored object
 * at `slot`) of object i's draw: the pipelines with a dynamic cull mode (render_make_graphics) take both. */
void render_set_facing(const render *r, VkCommandBuffer cmd, uint32_t slot, size_t i);
/* Writes the next timestamp (call before each pass and once at the end of the frame). */
void render_ts(render *r, VkCommandBuffer cmd);
/* The render's command buffer: reset + begin; end + submit + wait on its fence (render_frame, analysis). */
VkResult render_cmd_begin(render *r);
VkResult render_cmd_submit_wait(render *r);
/* A global memory barrier between two stage/access sets. */
/* Resets and begins / ends the pipeline-statistics query around a shading pass (no-ops without the pool). */
void render_stats_begin(render *r, VkCommandBuffer cmd);
void render_stats_end(render *r, VkCommandBuffer cmd);
void render_barrier(VkCommandBuffer cmd, VkPipelineStageFlags2 src_stage, VkAccessFlags2 src_access,
		    VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access);

/* Formats "what failed: VkResult" into err and returns TL_ERR_VULKAN (for `return render_vk_error(...)`). */
int render_vk_error(char *err, size_t err_size, const char *what, VkResult res);
/* A storage buffer bound whole (vkdev_buffer_create with STORAGE_BUFFER usage | extra): fails with one line naming
 * the size when it exceeds the device's maxStorageBufferRange (128 MiB at least; a shader may read no further). */
int render_storage_buffer(render *r, VkDeviceSize size, VkBufferUsageFlags extra, bool host, const char *name,
			  vkdev_buffer *out, char *err, size_t err_size);
/* In functions with `int rc`, `err`, `err_size` and a `fail:` label: checks a VkResult, records file:line
 * and the call (Mesa's vk_error habit), sets rc = TL_ERR_VULKAN and jumps to fail. */
#define CHECK_VK(call)                                                                                     \
	do {                                                                                               \
		VkResult vr_ = (call);                                                                     \
		if (vr_ != VK_SUCCESS) {                                                                   \
			char what_[256];                                                                   \
			snprintf(what_, sizeof what_, "%s:%d: %s", __FILE__, __LINE__, #call);               \
			rc = render_vk_error(err, err_size, what_, vr_);                                   \
			goto fail;                                                                         \
		}                                                                                          \
	} while (0)

/* render_create with a method that is not in the registry (analysis passes). */
int render_create_ops(vkdev *dev, const render_desc *desc, const render_method *m, render **out, char *err,
		      size_t err_size);

#endif
