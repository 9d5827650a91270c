/* method_debug.h (private) — diagnostics of the methods for the acceptance tests (tests/test_atlas_checks.c,
 * tests/test_reuse_checks.c): read back, or for a unit test replace, a method's internal state between frames.
 * Not part of the command line; call them on a render of the right method after render_frame. */
#ifndef TASLAB_METHOD_DEBUG_H
#define TASLAB_METHOD_DEBUG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "taslab/render.h"

/* Atlas methods (atlas.c). atlas_debug_ids copies the visibility pass's image (width x height x (object + 1,
 * mesh triangle, barycentrics 1 and 2 as float bits)) out, or in with `upload`. atlas_debug_visible runs the visible
 * pass (tasa: with the 2x2 image-space max filter) on the ids image with gradients G (one per global patch) and
 * returns visible[] and F[] (per global patch). atlas_debug_blocks: the last frame's block table, 4 words per global
 * patch (x | y << 16, lw | lh << 8 | age << 16, mesh patch, object). */
int atlas_debug_ids(render *r, uint32_t *ids, bool upload, char *err, size_t err_size);
int atlas_debug_visible(render *r, const float *G, uint32_t *visible, float *F, char *err, size_t err_size);
/* Stereo: atlas_debug_ids for eye `view`; atlas_debug_visible runs every eye's pass into the shared visible[] (bit v:
 * seen by eye v) and F[] (the max over both eyes' 2x2 windows). */
int atlas_debug_ids_view(render *r, uint32_t view, uint32_t *ids, bool upload, char *err, size_t err_size);
const uint32_t *atlas_debug_blocks(render *r, uint32_t *patch_count);
/* Stereo: true when the eyes' visibility pass is recorded as one multiview render pass (render_desc.multiview). */
bool atlas_debug_multiview(render *r);
/* The facing the CPU decided for a global patch this frame (triangle A's winding seen from the eye, the rule that
 * replaces gl_FrontFacing; 1 front, 0 back), -1 when the patch has no block. */
int atlas_debug_facing(render *r, uint32_t pid);

/* rrc / tarc (reproj_cache.c): the cache state the last frame wrote, width x height x 4 words (object + 1, view
 * distance bits, age | flags | decision << 24, tarc: the stored gradient g as float bits); read back only with
 * render_desc.decisions, else NULL. */
const uint32_t *reproj_debug_state(render *r);

/* The compacted sample path (vbuf_family.c, vrs.c): the tile rates the last frame's select read (w | h << 8 per 16x16
 * tile, row-major). VRS methods: per tile (P', r, sr, target tile) of the last rate pass (fovea: eccentricity, index,
 * index, tile; -1 as target when the tile centre left the image), and the palette indices S of the last frame. */
const uint32_t *vbuf_debug_rates(render *r);
/* The last frame's ids image (passes/ids.h: width x height x 4 words) copied out. */
int vbuf_debug_ids(render *r, uint32_t *ids, char *err, size_t err_size);
/* stu (vreuse.c): the last frame's ids (as vbuf_debug_ids) and the surface its visibility pass wrote beside them,
 * width x height x 4 words each: pos the world position (float bits) and g (float bits: STU_G's at the phase
 * pixels, else 0), nrm the unit normal (float bits) and object + 1; all 0 on the background. */
int vreuse_debug_surface(render *r, uint32_t *ids, uint32_t *pos, uint32_t *nrm, char *err, size_t err_size);
const float *vrs_debug_tiles(render *r, const int32_t **index, uint32_t *tiles_x, uint32_t *tiles_y);

#endif
