/* view.c — the views of a stereo render (STEREO.md): each eye's own targets, state rings and descriptor sets, swapped
 * into the render's fields when the eye becomes the active one, so that every pass and per-eye method records an eye
 * the way it records a mono frame. */
#include "render_internal.h"

#include <stdlib.h>

#define VIEW_FIELDS(X)                                                                                             \
	X(states) X(objects) X(shade_count) X(depth) X(hdr) X(display) X(readback_hdr) X(readback_display)           \
	X(hdr_packed) X(display_packed) X(scene_set) X(display_set) X(method_state) X(eye)

void render_use_view(render *r, uint32_t v)
{
	if (v == r->view || v >= r->view_count)
		return;
	render_view_ctx *out = &r->views[r->view], *in = &r->views[v];
#define SWAP(f) out->f = r->f, r->f = in->f;
	VIEW_FIELDS(SWAP)
#undef SWAP
	r->view = v;
}

int render_view_create(render *r, char *err, size_t err_size)
{
	int rc = render_upload_rings(r, err, err_size);
	if (!rc)
		rc = render_targets_view_create(r, err, err_size);
	if (!rc)
		rc = render_descriptors_view_create(r, err, err_size);
	return rc;
}

void render_view_destroy(render *r)
{
	vkdev_buffer *bufs[] = {&r->states, &r->objects, &r->shade_count, &r->readback_hdr, &r->readback_display};
	for (size_t i = 0; i < sizeof bufs / sizeof bufs[0]; i++)
		vkdev_buffer_destroy(r->dev, bufs[i]);
	vkdev_image_destroy(r->dev, &r->depth);
	vkdev_image_destroy(r->dev, &r->hdr);
	vkdev_image_destroy(r->dev, &r->display);
	free(r->hdr_packed);
	free(r->display_packed);
	r->hdr_packed = NULL;
	r->display_packed = NULL;
	r->scene_set = r->display_set = VK_NULL_HANDLE; /* freed with the pool */
}
