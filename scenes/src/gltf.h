/* gltf.h (private) — appends a glTF 2.0 asset (.gltf or .glb) to a scene being built (gltf.cpp).
 * Adds materials, textures (resampled to scene->texture_size), meshes (one per primitive), one object
 * per node (parent = `parent`, or -1) plus one child object per primitive, node animations as
 * keyframe motions, and perspective cameras as stationary camera paths. On success *root_object is
 * the object all of the asset's root nodes hang from. Errors: TL_ERR_INPUT (a bad or hostile file: nothing
 * is read or allocated before it is checked), TL_ERR_NOMEM, TL_ERR_INTERNAL (an unexpected exception); one
 * line naming the file in err. On failure the scene holds what was added so far: destroy it. */
#ifndef TASLAB_GLTF_H
#define TASLAB_GLTF_H

#include "taslab/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

int gltf_append(scene *s, const char *path, int parent, int *root_object, char *err, size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
