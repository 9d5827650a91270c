/* render_internal.h (private) — shared state of the frame pipeline and the method interface.
 *
 * Passes shared by all methods live in render.c (scene upload, state rings, shadow maps, depth
 * pre-pass, forward shading, display encoding, readback); a method is a `render_method_ops` entry
 * that records its frame from those building blocks and adds its own passes/buffers. */
#ifndef TASLAB_RENDER_INTERNAL_H
#define TASLAB_RENDER_INTERNAL_H

#include "gpu_types.h"
#include "taslab/render.h"

typedef struct render_method_ops {
	render_method_info info;
	const char *const *pass_names; /* timestamp intervals recorded by `record`, in order */
	uint32_t pass_count;
	int (*init)(render *r, char *err, size_t err_size);
	/* Records the frame into `cmd`; must call render_ts() once before each pass and once at the end. */
	void (*record)(render *r, VkCommandBuffer cmd, uint32_t frame);
	/* Fills the method-specific statistics after the frame completed. */
	void (*collect)(render *r, render_stats *st);
	void (*finish)(render *r);
} render_method_ops;

extern const render_method_ops render_method_ref;

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
	uint32_t current_slot;

	/* scene on the GPU */
	vkdev_buffer vertices, indices;
	uint32_t *mesh_first_index, *mesh_vertex_offset;
	vkdev_buffer materials;
	vkdev_buffer states;      /* FrameState x state_ring, host visible */
	vkdev_buffer objects;     /* GpuObject x object_count x state_ring, host visible */
	vkdev_image color_tex, data_tex;
	VkSampler tex_sampler, shadow_sampler;
	vkdev_image shadow;       /* D32 array, one layer per light (point lights: 6) */
	VkImageView *shadow_layer_views;
	uint32_t shadow_layers;
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

/* Building blocks for methods. */
void render_ts(render *r, VkCommandBuffer cmd);
void render_update_state(render *r, uint32_t slot, double time_s);
void render_pass_shadows(render *r, VkCommandBuffer cmd, uint32_t slot);
void render_pass_depth(render *r, VkCommandBuffer cmd, uint32_t slot);
/* Forward shading of every visible sample with depth EQUAL, inside a pipeline-statistics query. */
void render_pass_shade(render *r, VkCommandBuffer cmd, uint32_t slot);
void render_pass_display(render *r, VkCommandBuffer cmd);
void render_pass_readback(render *r, VkCommandBuffer cmd);

#endif
