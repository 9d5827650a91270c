/* clip.h — bit-exact study clips: lossless VP9 with RGB (gbrp) pixels in WebM, through libavcodec /
 * libavformat (DESIGN section 5). This is the format found to play back bit-exact in Chromium; decoded
 * frames equal the PNG frames exactly (tests/test_clip.c decodes with libavcodec to check).
 *
 * A clip is written under a temporary name in the destination folder and renamed into place by
 * clip_writer_finish; clip_writer_destroy on an unfinished writer deletes the temporary file, so no
 * partial clip ever stands under the final name. Errors: negative return, one line in `err`. */
#ifndef TASLAB_CLIP_H
#define TASLAB_CLIP_H

#include <stddef.h>
#include <stdint.h>

#include "taslab/tl_error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct clip_writer clip_writer;

int clip_writer_create(const char *path, uint32_t width, uint32_t height, double fps, clip_writer **out, char *err,
		       size_t err_size);
/* Appends one frame of packed 8-bit RGB (width*3 bytes per row). */
int clip_writer_frame(clip_writer *w, const uint8_t *rgb, char *err, size_t err_size);
int clip_writer_finish(clip_writer *w, char *err, size_t err_size);
void clip_writer_destroy(clip_writer **w);

/* Decodes a clip; calls `frame` with packed RGB8 for each frame in order (return non-zero to stop).
 * *fps receives the stream's frame rate. */
typedef int (*clip_frame_fn)(void *user, uint32_t index, uint32_t width, uint32_t height, const uint8_t *rgb);
int clip_decode(const char *path, clip_frame_fn frame, void *user, double *fps, char *err, size_t err_size);

/* Encodes a run folder's frames/NNNNNN.png (contiguous numbers, equal sizes) at the run's fps
 * (manifest.json) into `out`. Missing frames, size mismatches and unreadable images are errors. */
int clip_encode_run(const char *run_dir, const char *out, uint32_t *frames_written, char *err, size_t err_size);
/* The same for a stereo run (STEREO.md): `view` "sbs" or NULL encodes RUN/sbs/ (2W x H, left | right), "L" or "R" one
 * eye's frames; a mono run takes only NULL or "sbs" (its frames). */
int clip_encode_run_view(const char *run_dir, const char *view, const char *out, uint32_t *frames_written, char *err,
			 size_t err_size);

#ifdef __cplusplus
}
#endif
#endif
