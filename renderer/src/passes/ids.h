/* ids.h (private) — the visibility (ids) pass: per pixel the exact nearest surface as (object, triangle,
 * barycentrics) ([TAS] sec. 6.2 step 1; TAS-METHODS section 4 "Visible set"). Shared by the shading-atlas methods
 * (sa, sau, tasa: methods/atlas.c) and the compacted sample path of BASELINES.md section 0, which both shade
 * surfaces found here, so it lives among the passes (issue 30.4; ARCHITECTURE.md "Where new work goes").
 *
 * The image (width x height, RGBA32UI): x object + 1 (0: background), y triangle in the object's mesh, z and w
 * the perspective-correct barycentrics of corners 1 and 2 as float bits. With patch tables (ids_patches: the
 * shading-atlas methods) y is instead the triangle's patch and its place in it, pid << 3 | side << 2 | rotation
 * (atlas.glsl's tri_info with the object's pid base added), found per vertex, so that the passes reading the image
 * per pixel need no table lookups (issue 25). Opaque and masked objects are drawn
 * (MASK alpha-tested as in the depth pre-pass); BLEND objects are not, they are composited later. The pass also
 * leaves the frame's depth in the render's depth target (for that compositing).
 *
 * Lifecycle: an ids_pass is embedded in its user's state, ids_pass_init / ids_pass_finish (finish accepts a
 * zeroed or half-initialised pass). The image is bound by the user into its own descriptor sets. */
#ifndef TASLAB_IDS_H
#define TASLAB_IDS_H

#include "passes.h"

typedef struct ids_pass {
	vkdev_image image;                /* the ids, GENERAL layout between frames */
	VkDescriptorSetLayout set_layout; /* set 1 of the pass: the scene's vertices and indices (common/ids.vert.in) */
	VkDescriptorSet set;
	render_pipeline pipe;             /* opaque objects: no discard, so the depth test runs before the fragment
					   * shader (llvmpipe tests depth after any shader that can discard) */
	render_pipeline pipe_mask;        /* glTF MASK objects: alpha-tested */
	uint32_t layer;                   /* multiview: the eye's layer of ids_multiview.ids (image is a view of it) */
	bool layer_view;                  /* image is that layer's view (ids_multiview owns the image), no pipelines */
} ids_pass;

/* Stereo with render.multiview (STEREO.md "Vulkan multiview", VK_KHR_multiview): both eyes' visibility in one render
 * pass with viewMask 0b11 into 2-layer attachments; view v (gl_ViewIndex) takes eye v's view_proj. */
typedef struct ids_multiview {
	vkdev_image ids, depth;           /* 2 layers each, 2D_ARRAY views (the attachments) */
	VkDescriptorSetLayout set_layout;
	VkDescriptorSet set;              /* vertices, indices and the right eye's state ring (common/ids.vert.in) */
	render_pipeline pipe, pipe_mask;  /* as ids_pass's, with viewMask 0b11 */
} ids_multiview;

/* The atlas methods' tables (methods/atlas.c, atlas.glsl): obj_info (uvec4 per object, two per object: x the
 * object's pid base, z its mesh's first triangle in tri_info) and tri_info (per mesh triangle, mesh pid << 3 |
 * side << 2 | rotation); with them the image's y holds the global pid << 3 | side << 2 | rotation. */
typedef struct ids_patches {
	const vkdev_buffer *obj_info, *tri_info;
} ids_patches;

/* pt: NULL for (object, triangle) ids, or the patch tables for pid ids */
int ids_pass_init(render *r, ids_pass *p, const ids_patches *pt, char *err, size_t err_size);
void ids_pass_finish(render *r, ids_pass *p);

/* Records the pass for state slot `slot`: the image cleared to 0 and the depth target to 1, then every opaque and
 * masked object in scene order with depth LESS_OR_EQUAL and write (among exactly coplanar surfaces the last drawn
 * wins, as in ref's EQUAL shading pass). Ends with the image in GENERAL layout, its writes visible to compute
 * shader reads; the caller orders earlier reads of the image (previous frame) by the pass's own barrier. */
void ids_pass_record(render *r, const ids_pass *p, VkCommandBuffer cmd, uint32_t slot);

/* The pieces of ids_pass_record for passes that draw the same way with other shaders into other images (the
 * reprojecting visibility pass of methods/vreuse.c, alone or writing the ids too as a second target, stu's surface as a
 * third and fourth; the VRS methods' ids pass with their per-pixel motion and texel density as the second target,
 * methods/vrs.c): ids_begin orders the previous frame's compute reads and writes of IMAGES[0..COUNT) (COUNT <=
 * IDS_MAX_TARGETS, colour attachments 0..COUNT-1), clears them to CLEARS[0..COUNT) (NULL: all 0) and the render's depth
 * target to 1 and begins rendering; ids_draw_objects draws every opaque and masked object in scene order with PIPE /
 * PIPE_MASK (set 1 = SET), push constants' aux = (the mesh's first index, its vertex offset, aux23[0], aux23[1]);
 * ids_end ends rendering and makes the images readable by compute shaders. */
enum { IDS_MAX_TARGETS = 4 };
void ids_begin(render *r, VkCommandBuffer cmd, const vkdev_image *const *images, uint32_t count,
	       const VkClearColorValue *clears);
void ids_draw_objects(render *r, VkCommandBuffer cmd, VkDescriptorSet set, const render_pipeline *pipe,
		      const render_pipeline *pipe_mask, uint32_t slot, const uint32_t aux23[2]);
void ids_end(VkCommandBuffer cmd, const vkdev_image *const *images, uint32_t count);

/* The opaque and MASK pipelines of a pass drawn like this one (ids_draw_objects; the ids pass itself, the VRS
 * methods' ids pass, the reprojecting visibility pass): the vertex template VS with VS_DEFS, the fragment template FS
 * with FS_DEFS and, for the alpha-tested MASK objects, with FS_DEFS and MASK_DEF; PD gives the rest (attachments,
 * depth, set 1; its shader fields are filled here). WHAT names the pipeline in the error message. */
typedef struct ids_pipe_src {
	const char *vs, *vs_defs, *fs, *fs_defs, *mask_def;
} ids_pipe_src;
int ids_make_pipelines(render *r, const ids_pipe_src *src, render_pipe_desc pd, render_pipeline *pipe,
		       render_pipeline *pipe_mask, const char *what, char *err, size_t err_size);

/* Multiview: creates the 2-layer images, the set and the pipelines, and makes eyes[v] (uninitialised) the view of
 * layer v (bound like an ids_pass's image; ids_pass_finish frees only the view, ids_multiview_finish the rest). Needs
 * the device's multiview feature and 2 views. */
int ids_multiview_init(render *r, ids_multiview *m, ids_pass eyes[2], const ids_patches *pt, char *err, size_t err_size);
void ids_multiview_finish(render *r, ids_multiview *m);
/* Records both eyes' pass for state slot `slot` (view 0 active): what ids_pass_record does for each eye, in one render
 * pass; with BLEND objects in the scene each eye's layer of the depth is then copied into the eye's depth target
 * (the compositing reads it there, as after ids_pass_record). */
void ids_multiview_record(render *r, const ids_multiview *m, VkCommandBuffer cmd, uint32_t slot);

/* Diagnostics for the tests (methods/method_debug.h): copies the image out to `ids` (width x height x 4 words), or
 * with `upload` from `ids` into the image; waits for the copy. */
int ids_pass_copy(render *r, const ids_pass *p, uint32_t *ids, bool upload, char *err, size_t err_size);
/* The same for any RGBA32UI image of the frame's size in GENERAL layout (layer `layer`), e.g. a pass's second
 * target. */
int ids_image_copy(render *r, const vkdev_image *image, uint32_t layer, uint32_t *ids, bool upload, char *err,
		   size_t err_size);

#endif
