/* render_internal.h (private) — shared state of the frame pipeline and the method interface.
 *
 * Passes shared by all methods live in render.c (scene upload, state rings, shadow maps, depth
 * pre-pass, forward shading, display encoding, readback); a method is a `render_method_ops` entry
 * that records its frame from those building blocks and adds its own passes/buffers. */
#ifndef TASLAB_RENDER_INTERNAL_H
#define TASLAB_RENDER_INTERNAL_H

#include "gpu_types.h"
#include "shader_compile.h"
#include "taslab/render.h"

typedef struct render_method_ops {
	render_method_info info;
	const char *const *pass_names; /* timestamp intervals recorded by `record`, in order */
	uint32_t pass_count;
	uint32_t state_ring; /* state slots the method needs (0: 1) */
	int (*init)(render *r, char *err, size_t err_size);
	/* Before recording frame `frame`: update state slots and plan their shadow maps (may allocate and
	 * update descriptors, which is why it runs outside the command buffer). */
	int (*prepare)(render *r, uint32_t frame, char *err, size_t err_size);
	/* Records the frame into `cmd`; must call render_ts() once before each pass and once at the end. */
	void (*record)(render *r, VkCommandBuffer cmd, uint32_t frame);
	/* Fills the method-specific statistics after the frame completed. */
	void (*collect)(render *r, render_stats *st);
	void (*finish)(render *r);
	/* Re-creates the method's shading pipelines (after the shadow pool grew; see render_frame). */
	int (*rebuild)(render *r, char *err, size_t err_size);
} render_method_ops;

extern const render_method_ops render_method_ref;
extern const render_method_ops render_method_tfr;

/* Shadow maps: a pool of physical layers shared by the state slots (render_shadow.c). */
typedef struct render_shadow_pool {
	uint32_t layers;       /* logical layers per slot (lights: 1, point lights: 6) */
	uint32_t size;         /* shadow map size */
	uint32_t chunk_layers; /* physical layers per chunk image */
	uint32_t chunk_count;
	uint32_t chunks_max;   /* chunks the pool may need */
	uint32_t chunks_compiled; /* chunks the shading pipelines are specialised for (SHADOW_CHUNKS_USED) */
	vkdev_image chunks[GPU_SHADOW_CHUNKS];
	vkdev_image dummy;     /* bound while there are no chunks */
	VkImageView *views;    /* per physical layer */
	uint32_t *refs;        /* per physical layer: slots mapping to it */
	uint32_t *owner;       /* per physical layer: logical layer whose content it holds */
	uint32_t *slot_phys;   /* state_ring x layers */
	uint8_t *todo;         /* state_ring x layers: planned, not rendered yet */
	uint64_t *last_key;    /* per logical layer: inputs of its last rendering */
	uint32_t *last_phys;
	uint64_t rendered, reused; /* layer renderings and shares so far */
} render_shadow_pool;

typedef struct render_pipeline {
	VkPipeline pipeline;
	VkPipelineLayout layout;
} render_pipeline;

struct render {
	vkdev *dev;
	const scene *scene;
	render_desc desc;
	const render_method_ops *method;
	void *method_state;

	uint32_t state_ring;      /* slots in the state and object rings */
	uint32_t push_aux[4];     /* copied into gpu_push.aux of every draw */
	uint32_t current_slot;

	/* scene on the GPU */
	vkdev_buffer vertices, indices;
	uint32_t *mesh_first_index, *mesh_vertex_offset;
	vkdev_buffer materials;
	vkdev_buffer states;      /* FrameState x state_ring, host visible */
	vkdev_buffer objects;     /* GpuObject x object_count x state_ring, host visible */
	vkdev_image color_tex, data_tex;
	VkSampler tex_sampler, shadow_sampler;
	render_shadow_pool shadow; /* D32 layers, one per light (point lights: 6) per slot */
	int *light_shadow_layer;  /* first shadow layer per light, -1 none */

	/* targets */
	vkdev_image depth, hdr, display;
	vkdev_buffer readback_hdr, readback_display;
	uint32_t row_pitch_hdr_B, row_pitch_display_B;
	uint16_t *hdr_packed;
	uint8_t *display_packed;

	/* pipelines */
	VkDescriptorSetLayout scene_set_layout, display_set_layout;
	VkDescriptorPool pool;
	VkDescriptorSet scene_set, display_set;
	render_pipeline shadow_pipe, depth_pipe, shade_pipe, display_pipe;
	render_pipeline shadow_mask_pipe, depth_mask_pipe, shade_blend_pipe; /* glTF alphaMode MASK / BLEND */
	tlm_vec3 eye;             /* camera position of the last render_update_state (blend sorting) */
	uint32_t *blend_order;    /* BLEND objects, sorted back to front each frame */
	uint32_t blend_count;

	/* queries */
	VkQueryPool ts_pool, stats_pool;
	uint32_t ts_count;
	VkCommandBuffer cmd;
	VkFence fence;

	colour *own_colour;       /* created when desc.colour is NULL */
	const colour *colour;

	/* scratch */
	tlm_mat4 *world;
	scene_light_state *light_states;
};

/* The render's command buffer: reset + begin; end + submit + wait on its fence (render_frame, analysis). */
VkResult render_cmd_begin(render *r);
VkResult render_cmd_submit_wait(render *r);

/* Building blocks for methods. */
void render_ts(render *r, VkCommandBuffer cmd);
void render_update_state(render *r, uint32_t slot, double time_s);
/* Shadow maps of a slot: plan (before recording; reuses unchanged layers) then render the planned layers. */
int render_shadow_init(render *r, char *err, size_t err_size);
void render_shadow_destroy(render *r);
int render_shadow_plan(render *r, uint32_t slot, char *err, size_t err_size);
void render_pass_shadows(render *r, VkCommandBuffer cmd, uint32_t slot);
/* Depth-only rendering of opaque + masked objects into `view` (shadow layers and depth pre-passes). */
void render_depth_only_pass(render *r, VkCommandBuffer cmd, VkImageView view, uint32_t w, uint32_t h,
			    const render_pipeline *pipe, const render_pipeline *mask_pipe, uint32_t slot, uint32_t layer,
			    int shadow_pass);
void render_pass_depth(render *r, VkCommandBuffer cmd, uint32_t slot);
/* Forward shading of every visible sample with depth EQUAL, inside a pipeline-statistics query. */
void render_pass_shade(render *r, VkCommandBuffer cmd, uint32_t slot);
/* The same with a method's pipeline for opaque/masked surfaces (and its descriptor set 1); BLEND
 * surfaces keep the reference shading. */
void render_pass_shade_with(render *r, VkCommandBuffer cmd, uint32_t slot, const render_pipeline *opaque,
			    VkDescriptorSet method_set);
void render_pass_display(render *r, VkCommandBuffer cmd);
void render_pass_readback(render *r, VkCommandBuffer cmd);

/* render_create with a method that is not in the public table (analysis passes). */
int render_create_ops(vkdev *dev, const render_desc *desc, const render_method_ops *m, render **out, char *err,
		      size_t err_size);
/* Compiles a run-time shader template (includes and the OCIO display function resolved, see render.c). */
int render_compile(const render *r, const char *template_src, shc_stage stage, uint32_t **spv, size_t *spv_size,
		   char *err, size_t err_size);
/* Shading pipeline like the reference one (scene.vert, depth EQUAL) with fragment shader `fs` and an
 * optional descriptor set 1. */
VkResult render_make_shade_pipeline(render *r, const uint32_t *fs, size_t fs_size, VkDescriptorSetLayout method_set,
				    render_pipeline *out);
void render_pipeline_destroy(render *r, render_pipeline *p);

#endif
