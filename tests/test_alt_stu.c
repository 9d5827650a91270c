/* test_alt_stu.c — spatio-temporal upsampling (BASELINES.md A4; section C "stu") on lavapipe with the validation layer
 * (any message fails), tfr_static (a textured floor, a box, a shadow-casting sun) at 48 x 32 and 49 x 31:
 *  stu/2, stu/4 (BASELINES' N) and stu/8 (at 49 x 31: stu/4), static view: every frame shades exactly the covered
 *  phase pixels of the interleaved pattern (the CPU count of rrc-interleaved/N's refresh set); from frame 2N + 5 on the frames equal vref (display and HDR:
 *  D has fallen below 1/2, so c = 1, and every pixel has been reshaded once since); determinism.
 *  The first frame equal to vref is exactly 2N + 1, which checks the temporal smoothing of g: in frames 0..N-1 every
 *  phase sample is a first one (g = 8), so D = 8; from frame N on g = 0 (a static view), so D = 4, 2, 1, 1/2 in
 *  frames N..N+3 and c = clamp((8 - D) / 7.5, 0, 1) reaches 1 at N+3; a pixel equals vref from its first phase frame
 *  at or after N+2 (shows s, then keeps it), the last of which is 2N+1. With g lost (always 0) D would start at 4 and
 *  the frames would equal vref from N+1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_vk.h"

#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

/* stu/n for n in [n0, n1] (powers of two) on the static view at W x H against vref (the header's checks). */
static void stu_static(vkdev *dev, const scene *s, uint32_t W, uint32_t H, uint32_t n0, uint32_t n1)
{
	const uint32_t F = 2 * n1 + 5 + 2;
	tu_clip v = tu_render_clip(dev, s, 0, "vref", NULL, NULL, W, H, F, false);
	size_t px = (size_t)W * H;
	for (uint32_t n = n0; n <= n1; n *= 2) {
		char var[16];
		snprintf(var, sizeof var, "stu/%u", n);
		uint32_t frames = 2 * n + 5 + 2;
		tu_clip c = tu_render_clip(dev, s, 0, var, NULL, NULL, W, H, frames, false);
		uint32_t a = n == 8 ? 4 : n == 4 ? 2 : n, b = n / a;
		int first_equal = -1;
		for (uint32_t f = 0; f < frames; f++) {
			int64_t want = 0;
			uint32_t k = f % n;
			for (uint32_t y = 0; y < H; y++)
				for (uint32_t x = 0; x < W; x++)
					want += tu_half_to_float(v.hdr[f][4 * ((size_t)y * W + x) + 3]) != 0.0f && x % a == k % a &&
						y % b == k / a;
			assert_int_equal(c.st[f].shaded_samples, want);
			bool same = !memcmp(c.disp[f], v.disp[f], px * 4) && !memcmp(c.hdr[f], v.hdr[f], px * 8);
			if (same && first_equal < 0)
				first_equal = (int)f;
			if (f >= 2 * n + 5)
				assert_true(same);
		}
		assert_int_equal(first_equal, 2 * n + 1);
		printf("stu/%u at %ux%u: shaded %lld of %lld per frame, frames equal vref from frame %d (asserted from %u)\n",
		       n, W, H, (long long)c.st[1].shaded_samples, (long long)c.st[1].visible_samples, first_equal, 2 * n + 5);
		tu_clip_free(&c);
	}
	tu_clip_free(&v);
}

static void test_static(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("tfr_static");
	enum { W = 48, H = 32 };
	stu_static(dev, s, W, H, 2, 8); /* the 2x1, 2x2 and 4x2 cells */
	stu_static(dev, s, 49, 31, 4, 4); /* a size no 4x4 decide block and no 8x8 workgroup divides */
	tu_clip a1 = tu_render_clip(dev, s, 0, "stu/4", NULL, NULL, W, H, 3, false);
	tu_clip a2 = tu_render_clip(dev, s, 0, "stu/4", NULL, NULL, W, H, 3, false);
	tu_assert_same_frames(&a1, &a2, true);
	tu_clip_free(&a1);
	tu_clip_free(&a2);
	scene_destroy(&s);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	vkdev_destroy(&dev);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_static),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
