/* test_stereo_ts.c — per-pass times of stereo runs (issue 25): a pass boundary's timestamp is taken when the command
 * stream reaches it, also where llvmpipe would take it at its next rasteriser-scene flush (the cause of the stereo atlas
 * runs' gpu_ms_alloc holding the shading and gpu_ms_shade ~0.1 ms). Causal, not a speed: a compute pass the host holds
 * open must measure at least the hold. Lavapipe, validation layer on, a 24x16 stereo sa render. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_vk.h"

#include "../renderer/src/frame/frame_debug.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

/* ---- per-pass times ---- */

/* The stereo atlas frame's situation (eye 1's visibility pass the last framebuffer, a compute pass binding none of its
 * attachments) with the compute pass held open by the host: the interval of its two boundary timestamps must contain
 * the hold (causality: the pass starts after the first timestamp and the host sees it start before holding; it ends
 * after the release). Before the fix both timestamps were taken at llvmpipe's flush after the pass: interval ~0.1 ms. */
static void test_pass_timestamps(void **state)
{
	(void)state;
	scene *s = tu_load_scene("stereo_plane");
	vkdev *dev = tu_lavapipe();
	char err[1024];
	method_config mc;
	if (method_config_parse_variant(&mc, "sa", err, sizeof err))
		fail_msg("%s", err);
	render *r = NULL;
	render_desc d = {.scene = s, .camera = 0, .width = 24, .height = 16, .method = &mc, .views = 2, .ipd = 0.063f};
	if (render_create(dev, &d, &r, err, sizeof err))
		fail_msg("%s", err);
	frame_image img;
	frame_stats st;
	if (render_frame(r, 0, &img, &st, err, sizeof err))
		fail_msg("%s", err);
	double interval = -1.0, held = -1.0;
	if (render_debug_ts_probe(r, 40, &interval, &held, err, sizeof err))
		fail_msg("%s", err);
	fprintf(stderr, "timestamp probe: held %.2f ms, pass interval %.2f ms\n", held, interval);
	assert_true(held >= 40.0);
	if (!(interval >= held - 0.5))
		fail_msg("a pass held open %.2f ms by the host measured %.2f ms: its opening timestamp was taken late", held,
			 interval);
	/* the frames after the probe are still a frame's: the boundaries counted, every pass timed */
	if (render_frame(r, 1, &img, &st, err, sizeof err))
		fail_msg("%s", err);
	assert_true(st.gpu_ms_total > 0.0);
	for (uint32_t p = 0; p < st.pass_count; p++)
		assert_true(st.gpu_ms[p] >= 0.0);
	render_destroy(&r);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	scene_destroy(&s);
	vkdev_destroy(&dev);
}

int main(void)
{
	const struct CMUnitTest tests[] = {cmocka_unit_test(test_pass_timestamps)};
	return tu_finish(cmocka_run_group_tests(tests, NULL, NULL));
}
