/* frame_debug.h (private) — diagnostics of the frame core for the tests (tests/test_stereo.c). Not part of the
 * command line. */
#ifndef TASLAB_FRAME_DEBUG_H
#define TASLAB_FRAME_DEBUG_H

#include <stddef.h>
#include <stdint.h>

#include "taslab/render.h"

/* ts_probe.c: after a render pass, times a compute pass that binds none of its attachments and that the host holds
 * open for `hold_ms` (from seeing it start to releasing it) between two render_ts boundaries. *interval_ms: the two
 * timestamps' interval; *held_ms: the host's hold as measured. A timestamp taken when the command is reached gives
 * interval >= held; one taken at the rasteriser's next flush gives about 0. Uses the render's command buffer, query
 * pool and depth target (call between frames). */
int render_debug_ts_probe(render *r, uint32_t hold_ms, double *interval_ms, double *held_ms, char *err, size_t err_size);

#endif
