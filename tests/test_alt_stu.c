/* test_alt_stu.c — spatio-temporal upsampling (BASELINES.md A4; section C "stu") on lavapipe with the validation layer
 * (any message fails), tfr_static (a textured floor, a box, a shadow-casting sun) at 48 x 32 and 49 x 31:
 *  stu/2, stu/4 (BASELINES' N) and stu/8 (at 49 x 31: stu/4), static view: every frame shades exactly the covered
 *  phase pixels of the interleaved pattern (the CPU count of rrc-interleaved/N's refresh set); from frame 2N + 5 on the frames equal vref (display and HDR:
 *  D has fallen below 1/2, so c = 1, and every pixel has been reshaded once since); the misses (new_units): every
 *  covered pixel in frame 0, none later; determinism. Under motion (test_slide) the misses are exactly the pixels the
 *  moving card uncovered, counted per subgroup and, with TASLAB_COUNT_ATOMICS, one atomic per pixel.
 *  The first frame equal to vref is exactly 2N + 1, which checks the temporal smoothing of g: in frames 0..N-1 every
 *  phase sample is a first one (g = 8), so D = 8; from frame N on g = 0 (a static view), so D = 4, 2, 1, 1/2 in
 *  frames N..N+3 and c = clamp((8 - D) / 7.5, 0, 1) reaches 1 at N+3; a pixel equals vref from its first phase frame
 *  at or after N+2 (shows s, then keeps it), the last of which is 2N+1. With g lost (always 0) D would start at 4 and
 *  the frames would equal vref from N+1.
 * The surface the windows weigh by (each pixel's world position and normal, written by the visibility pass beside the
 * ids): equal, within float rounding, to the surface point the ids name (object, triangle, barycentrics), computed
 * here from the scene's meshes and world matrices; the object + 1 beside the normal, 0 on the background. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_vk.h"

#include "../renderer/src/methods/method_debug.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/tl_math.h"
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
			/* the misses (new_units, counted by the stu pass): every covered pixel in frame 0 (no history), none
			 * after it (a static view: each pixel's previous record is its own) */
			assert_int_equal(c.st[f].new_units, f == 0 ? c.st[f].visible_samples : 0);
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

static float bits_f(uint32_t u)
{
	float f;
	memcpy(&f, &u, sizeof f);
	return f;
}

/* The surface of frames 0..2 of stu/4 at W x H against the CPU's surface point of each pixel's ids. */
static void test_surface(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("tfr_static");
	enum { W = 48, H = 32 };
	size_t px = (size_t)W * H;
	uint32_t *ids = malloc(px * 16), *pos = malloc(px * 16), *nrm = malloc(px * 16);
	tlm_mat4 *world = malloc(s->object_count * sizeof *world);
	assert_non_null(ids);
	assert_non_null(pos);
	assert_non_null(nrm);
	assert_non_null(world);
	render *r = tu_render_open(dev, s, 0, "stu/4", NULL, NULL, W, H, false);
	char err[1024];
	for (uint32_t f = 0; f < 3; f++) {
		frame_image img;
		frame_stats st;
		if (render_frame(r, f, &img, &st, err, sizeof err))
			fail_msg("frame %u: %s", f, err);
		assert_int_equal(vreuse_debug_surface(r, ids, pos, nrm, err, sizeof err), TL_OK);
		scene_eval(s, (float)f / (float)s->fps, world, NULL);
		size_t covered = 0;
		double worst_p = 0.0, worst_n = 0.0;
		for (size_t i = 0; i < px; i++) {
			const uint32_t *id = ids + 4 * i, *pp = pos + 4 * i, *nn = nrm + 4 * i;
			if (id[0] == 0) {
				if (pp[0] || pp[1] || pp[2] || nn[0] || nn[1] || nn[2] || nn[3])
					fail_msg("frame %u pixel %zu: background with a surface", f, i);
				continue;
			}
			covered++;
			assert_int_equal(nn[3], id[0]);
			assert_true(id[0] <= s->object_count);
			const scene_mesh *m = &s->meshes[s->objects[id[0] - 1].mesh];
			assert_true(3 * (size_t)id[1] + 2 < m->index_count);
			float b1 = bits_f(id[2]), b2 = bits_f(id[3]), b0 = 1.0f - b1 - b2, w3[3] = {b0, b1, b2};
			tlm_vec3 p = {0, 0, 0}, n = {0, 0, 0};
			for (int k = 0; k < 3; k++) {
				const scene_vertex *v = &m->vertices[m->indices[3 * id[1] + k]];
				p.x += w3[k] * v->position[0], p.y += w3[k] * v->position[1], p.z += w3[k] * v->position[2];
				n.x += w3[k] * v->normal[0], n.y += w3[k] * v->normal[1], n.z += w3[k] * v->normal[2];
			}
			const float *M = world[id[0] - 1].m; /* column-major */
			tlm_vec3 wp = tlm_mat4_mul_point(world[id[0] - 1], p);
			double wn[3] = {M[0] * n.x + M[4] * n.y + M[8] * n.z, M[1] * n.x + M[5] * n.y + M[9] * n.z,
					M[2] * n.x + M[6] * n.y + M[10] * n.z};
			double len = sqrt(wn[0] * wn[0] + wn[1] * wn[1] + wn[2] * wn[2]);
			double want_p[3] = {wp.x, wp.y, wp.z}, scale = 1.0 + fabs(wp.x) + fabs(wp.y) + fabs(wp.z);
			for (int c = 0; c < 3; c++) {
				double dp = fabs(bits_f(pp[c]) - want_p[c]) / scale, dn = fabs(bits_f(nn[c]) - wn[c] / len);
				worst_p = dp > worst_p ? dp : worst_p;
				worst_n = dn > worst_n ? dn : worst_n;
			}
		}
		printf("stu surface, frame %u: %zu covered pixels, position within %.2e (relative), normal within %.2e\n", f,
		       covered, worst_p, worst_n);
		assert_true(covered > px / 4);
		/* float rounding: the rasterizer's interpolation against the CPU's barycentric sums */
		assert_true(worst_p < 1e-5);
		assert_true(worst_n < 1e-5);
	}
	render_destroy(&r);
	free(ids);
	free(pos);
	free(nrm);
	free(world);
	scene_destroy(&s);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	vkdev_destroy(&dev);
}

/* stu/4 on tests/data/stu_slide.json, frames 10..16 at 64 x 32: a card 1 unit above a floor, the camera straight down
 * (screen x = world x, 4 px a unit at the card's depth), the card moving 0.5 units = 2 px a frame to the right, its
 * edges on pixel boundaries. The misses (new_units) of a frame after the first: the covered pixels whose previous
 * record (at the nearest pixel to where their surface point was in frame t-1) names another object - exactly the
 * floor pixels the card has just left (card at t-1, floor at t: 2 x 12 a frame; the card's pixels were card 2 px to
 * the left), counted here from the frames' ids. A pass that read the record it is writing (one image, not two
 * swapped) would find the floor's own record there, no miss; one reading the record of t-2 would count the strip the
 * card left in two frames. */
static void slide_misses(vkdev *dev, const scene *s)
{
	enum { W = 64, H = 32, F0 = 10, F1 = 17 };
	size_t px = (size_t)W * H;
	uint32_t *ids = malloc(px * 16), *pos = malloc(px * 16), *nrm = malloc(px * 16), *prev = malloc(px * 4);
	assert_non_null(ids);
	assert_non_null(pos);
	assert_non_null(nrm);
	assert_non_null(prev);
	render *r = tu_render_open(dev, s, 0, "stu/4", NULL, NULL, W, H, false);
	char err[1024];
	for (uint32_t f = F0; f < F1; f++) {
		frame_image img;
		frame_stats st;
		if (render_frame(r, f, &img, &st, err, sizeof err))
			fail_msg("frame %u: %s", f, err);
		assert_int_equal(vreuse_debug_surface(r, ids, pos, nrm, err, sizeof err), TL_OK);
		int64_t want = 0;
		size_t card = 0;
		for (size_t i = 0; i < px; i++) {
			uint32_t obj = ids[4 * i]; /* object + 1: 1 the floor, 2 the card */
			assert_true(obj == 1 || obj == 2);
			size_t x = i % W;
			card += obj == 2;
			if (f == F0)
				want++; /* no history yet */
			else if (obj == 1)
				want += prev[i] == 2;
			else
				want += x < 2 || prev[i - 2] != 2;
		}
		assert_int_equal(card, 16 * 12);
		if (f > F0)
			assert_int_equal(want, 2 * 12);
		assert_int_equal(st.new_units, want);
		for (size_t i = 0; i < px; i++)
			prev[i] = ids[4 * i];
	}
	render_destroy(&r);
	free(ids);
	free(pos);
	free(nrm);
	free(prev);
}

static void test_slide(void **state)
{
	(void)state;
	vkdev *dev = tu_lavapipe();
	scene *s = tu_load_scene("stu_slide");
	unsetenv("TASLAB_COUNT_ATOMICS");
	slide_misses(dev, s);
	setenv("TASLAB_COUNT_ATOMICS", "1", 1); /* the misses counted one atomic per pixel, not per subgroup */
	slide_misses(dev, s);
	unsetenv("TASLAB_COUNT_ATOMICS");
	scene_destroy(&s);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	vkdev_destroy(&dev);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_static),
		cmocka_unit_test(test_surface),
		cmocka_unit_test(test_slide), /* last: it sets TASLAB_COUNT_ATOMICS for a while */
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
