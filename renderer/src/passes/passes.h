/* passes.h (private) — the passes methods compose their frames from (frame pipeline, README "Frame
 * pipeline"). Each pass records into a command buffer; its pipelines are created with the render
 * (render.c) and, where they sample shadow maps, re-created when the shadow pool grows. */
#ifndef TASLAB_PASSES_H
#define TASLAB_PASSES_H

#include "../frame/render_internal.h"

/* ---- shadow.c: shadow maps as a pool of physical layers shared by the state slots ---- */
int render_shadow_init(render *r, char *err, size_t err_size);
void render_shadow_destroy(render *r);
/* Plans a slot's shadow layers before recording (reuses layers whose inputs are unchanged). */
int render_shadow_plan(render *r, uint32_t slot, char *err, size_t err_size);
void render_pass_shadows(render *r, VkCommandBuffer cmd, uint32_t slot);
/* Writes the shadow pool into binding 5 of every view's scene set (a view created after the pool). */
void render_shadow_write_sets(render *r);

/* ---- depth.c: depth-only rendering (shadow layers, depth pre-pass) ---- */
/* Depth-only rendering of opaque + masked objects into `view` (cleared to 1). Shadow layers pass
 * `casters` (object_count bits: the casters reaching into the layer; drawn without culling); the depth
 * pre-pass passes NULL (every object, culled per material). */
void render_depth_only_pass(render *r, VkCommandBuffer cmd, VkImageView view, VkImageLayout layout, uint32_t w,
			    uint32_t h, const render_pipeline *pipe, const render_pipeline *mask_pipe, uint32_t slot,
			    uint32_t layer, const uint8_t *casters);
/* Its draws, inside a rendering the caller began: the opaque objects with `pipe`, then the masked ones with
 * `mask_pipe` (when it exists), each bound with the scene set; also rrc/tarc's pre-pass (methods/reproj_cache.c),
 * so that both leave the same depths and the same last-drawn fragment among equal depths. */
void render_draw_depth_objects(render *r, VkCommandBuffer cmd, const render_pipeline *pipe,
			       const render_pipeline *mask_pipe, uint32_t slot, uint32_t layer, const uint8_t *casters);
int render_depth_init(render *r, char *err, size_t err_size);
/* The depth target, its contents discarded, ready as the depth attachment of a pass that clears it (after the
 * previous frame's depth tests; the depth pre-pass and the ids pass). */
void render_depth_discard(render *r, VkCommandBuffer cmd);
void render_pass_depth(render *r, VkCommandBuffer cmd, uint32_t slot);

/* ---- shade.c: forward shading (depth EQUAL after the pre-pass) and BLEND compositing ---- */
int render_shade_init(render *r, char *err, size_t err_size);
/* Forward shading of every visible sample with depth EQUAL, inside a pipeline-statistics query. */
void render_pass_shade(render *r, VkCommandBuffer cmd, uint32_t slot);
/* The same with a method's pipeline for opaque/masked surfaces (and its descriptor set 1); BLEND
 * surfaces keep the reference shading. */
void render_pass_shade_with(render *r, VkCommandBuffer cmd, uint32_t slot, const render_pipeline *opaque,
			    VkDescriptorSet method_set);

/* One rendering over the scene's targets, for methods that build their frame from several passes (rrc, tarc):
 * the HDR target cleared to the sky, loaded, or not attached; the stencil attached (cleared or loaded) or not;
 * the opaque and masked objects drawn with `pipe` (or one full-screen triangle); optionally the BLEND objects
 * composited on top with the reference shading (only in passes without stencil). The caller orders its own
 * storage-image accesses between passes. */
enum { RENDER_HDR_NONE = 0, RENDER_HDR_CLEAR, RENDER_HDR_LOAD };
enum { RENDER_STENCIL_PASS_NONE = 0, RENDER_STENCIL_PASS_CLEAR, RENDER_STENCIL_PASS_LOAD };
typedef struct render_scene_pass {
	const render_pipeline *pipe;
	VkDescriptorSet set;   /* optional set 1 */
	int hdr;               /* RENDER_HDR_* */
	int stencil;           /* RENDER_STENCIL_PASS_* */
	int fullscreen;        /* one full-screen triangle instead of the objects */
	int blend;             /* then the BLEND objects */
	int query;             /* inside the pipeline-statistics query (the method's shading passes) */
} render_scene_pass;
void render_pass_scene(render *r, VkCommandBuffer cmd, uint32_t slot, const render_scene_pass *p);

/* ---- display.c: the OpenColorIO display transform, HDR -> RGBA8 ---- */
int render_display_init(render *r, char *err, size_t err_size);
void render_pass_display(render *r, VkCommandBuffer cmd);

/* ---- readback.c: HDR and display targets to host memory ---- */
void render_pass_readback(render *r, VkCommandBuffer cmd);
/* After the frame completed: repacks the rows (padded pitch) into r->hdr_packed / r->display_packed and
 * returns the number of covered pixels (coverage alpha != 0). */
int64_t render_readback_finish(render *r);

/* ---- tas_filter.c: the spatial max filter of the TAS framework (paper secs. 5.3, 6.1) ----
 * 8x8 max downsample, then a 9x9 max kernel on the downsampled image (72x72 pixels in all), clipped at
 * the borders, component-wise over RGBA32F 2D-array images, layer by layer. Shared by the TFR analysis
 * (Figs. 8, 9) and tarc, so both use one definition. */
typedef struct tas_filter {
	VkDescriptorSetLayout set_layout;
	VkPipelineLayout layout;
	VkPipeline down, kernel;
} tas_filter;

int tas_filter_init(render *r, tas_filter *f, char *err, size_t err_size);
/* The same with another first step `down_spv` (same bindings and push constant; tarc's reads its cache state,
 * reproj/max_down_state.comp). */
int tas_filter_init_down(render *r, tas_filter *f, const uint32_t *down_spv, size_t down_size, char *err,
			 size_t err_size);
void tas_filter_finish(render *r, tas_filter *f);
/* A descriptor set binding the filter's input `src` (w x h x layers), the 8x8 level `mid` and the result
 * `dst` (both ceil(w/8) x ceil(h/8) x layers); all RGBA32F in GENERAL layout, storage usage. */
int tas_filter_bind(render *r, tas_filter *f, const vkdev_image *src, const vkdev_image *mid, const vkdev_image *dst,
		    VkDescriptorSet *out, char *err, size_t err_size);
/* Records both steps (with the barrier between them); the caller orders `src` writes before and `dst`
 * reads after. */
void tas_filter_record(const tas_filter *f, VkCommandBuffer cmd, VkDescriptorSet set, uint32_t w, uint32_t h,
		       uint32_t layers);

#endif
