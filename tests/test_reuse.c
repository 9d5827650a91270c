/* test_reuse.c — the pixel-space reuse methods rrc and tarc (with tarc-oracle) on lavapipe with the
 * validation layer (any message fails): the acceptance checks of TAS-METHODS section 9 that follow from the
 * definitions (DESIGN section 4; paper secs. 5.1, 6, 6.1, 7.1), pixel by pixel through the decision maps
 * (render_desc.decisions, frame_decision):
 *  R1  rrc/1 equals ref bit for bit (PNG and EXR), both lookups; also with a MASK object at an odd size
 *      (81x47), where tarc@8 --force-reshade equals ref too;
 *  R2  static scene: rrc/N shades exactly the covered pixels of the due 16x16 tiles, (t + i) mod N = 0,
 *      misses only in frame 0, frames equal ref (both lookups: bilinear weights snap to 0/1);
 *  R4  --resample nearest: cache misses per frame equal tfr's disoccluded samples (the same rule);
 *  T1  static scene: tarc shades everything in frames 0 (new) and 1 (second frame), nothing after, equal
 *      to ref at any T;
 *  T2  no predicted reshades where shading does not change (T = 255 on a scene whose only change is a sliding
 *      unlit-ish box): shaded = new + second-frame samples, and every second-frame sample was new one frame
 *      before within one pixel (the box moves 0.7 px per frame);
 *  T3  oracle: PNGs within T + 1 of ref every pixel and frame, late_samples 0; T = 0 equals ref;
 *  T4  a linear light ramp (raw OCIO config: display = linear): after the second frame each pixel is reshaded
 *      every floor(T/F) + 1 frames (+-1), F the filtered true per-frame change (8x8 max, 9x9 max) computed
 *      here from ref's frames;
 *  T5  filter footprint: every predicted reshade lies within 4 tiles (the 9x9 kernel) of a tile whose true
 *      shading changed at some earlier frame; far from any change nothing is reshaded;
 *  stats invariants (shaded + reused = visible, 0 <= new <= shaded <= visible, forced <= shaded), identical
 *  visible_samples across ref/tfr/rrc/tarc on a moving camera, determinism, --truth, bad input.
 * R3, T4's stored gradient and T6: test_reuse_checks.c. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_vk.h"

#include "taslab/colour.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

static int64_t count_dec(const tu_clip *c, uint32_t f, frame_decision d)
{
	int64_t k = 0;
	for (size_t i = 0; i < (size_t)c->w * c->h; i++)
		k += c->dec[f][i] == d;
	return k;
}

/* Stats invariants of every pixel method (TAS-METHODS 9 (a), (b)); no BLEND objects in the test scenes. */
static void assert_invariants(const tu_clip *c, const char *what)
{
	for (uint32_t f = 0; f < c->n; f++) {
		const frame_stats *s = &c->st[f];
		if (s->shaded_samples + s->reused_samples != s->visible_samples || s->new_units < 0 ||
		    s->new_units > s->shaded_samples || s->shaded_samples > s->visible_samples ||
		    s->visible_units != s->visible_samples || s->shaded_units != s->shaded_samples)
			fail_msg("%s frame %u: visible %lld shaded %lld reused %lld new %lld", what, f,
				 (long long)s->visible_samples, (long long)s->shaded_samples, (long long)s->reused_samples,
				 (long long)s->new_units);
		if (f == 0 && (s->shaded_samples != s->visible_samples || s->new_units != s->visible_samples))
			fail_msg("%s frame 0: not everything shaded and new", what);
		if (c->dec[f]) {
			/* the decision map agrees with the counters */
			int64_t shaded = 0;
			for (int d = FRAME_DECISION_NEW; d <= FRAME_DECISION_SCHEDULED; d++)
				shaded += count_dec(c, f, (frame_decision)d);
			assert_int_equal(shaded, s->shaded_samples);
			/* reused: shown from the cache, late (--truth) or not */
			int64_t late = count_dec(c, f, FRAME_DECISION_LATE);
			assert_int_equal(count_dec(c, f, FRAME_DECISION_REUSED) + late, s->reused_samples);
			assert_int_equal(late, s->late_samples > 0 ? s->late_samples : 0);
			assert_int_equal(count_dec(c, f, FRAME_DECISION_NEW), s->new_units);
		}
	}
}

/* ---- rrc ---- */

/* R1: N = 1 refreshes every tile every frame: ref exactly (a moving shadow and a moving box). */
static void test_rrc1_equals_ref(void **state)
{
	(void)state;
	scene *s = tu_load_scene("tfr_shadow");
	vkdev *dev = tu_lavapipe();
	enum { N = 6, W = 96, H = 64 };
	tu_clip ref = tu_render_clip(dev, s, 0, "ref", NULL, NULL, W, H, N, false);
	const char *nearest[] = {"resample=nearest", NULL};
	for (int k = 0; k < 2; k++) {
		tu_clip r1 = tu_render_clip(dev, s, 0, "rrc/1", k ? nearest : NULL, NULL, W, H, N, true);
		tu_assert_same_frames(&ref, &r1, true);
		assert_invariants(&r1, "rrc/1");
		for (uint32_t f = 0; f < N; f++)
			assert_int_equal(r1.st[f].shaded_samples, r1.st[f].visible_samples);
		tu_clip_free(&r1);
	}
	tu_clip_free(&ref);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* R1 with a glTF MASK object and an odd size: tests/data/reuse_mask.json (a fence with holes, alphaMode MASK,
 * alpha-tested in the pre-pass as in ref's depth pass: reproj/prepass.frag.in MASK with reproject_mask.vert; a
 * spinning box; a shadowing sun; stereo_multiview.json without its BLEND ball) at 81x47, which no 8x8 workgroup
 * of the reproject pass and no 16x16 tile divides: rrc/1 and tarc@8 --force-reshade (every sample reshaded every
 * frame) equal ref bit for bit (PNG and EXR); tarc@8 keeps the invariants (the decision map against the counters)
 * and reuses from frame 2 (little: the 72x72-pixel filter footprint around the spinning box and its shadow covers most of
 * an 81x47 frame). */
static void test_mask_odd_size(void **state)
{
	(void)state;
	scene *s = tu_load_scene("reuse_mask");
	vkdev *dev = tu_lavapipe();
	enum { N = 5, W = 81, H = 47 };
	tu_clip ref = tu_render_clip(dev, s, 0, "ref", NULL, NULL, W, H, N, false);
	const char *force[] = {"force-reshade", NULL};
	const char *variants[] = {"rrc/1", "tarc@8", "tarc@8"};
	for (int k = 0; k < 3; k++) {
		tu_clip c = tu_render_clip(dev, s, 0, variants[k], k == 1 ? force : NULL, NULL, W, H, N, true);
		assert_invariants(&c, variants[k]);
		if (k < 2) {
			tu_assert_same_frames(&ref, &c, true);
		} else {
			for (uint32_t f = 2; f < N; f++) {
				printf("tarc@8 81x47 frame %u: reused %lld of %lld\n", f, (long long)c.st[f].reused_samples,
				       (long long)c.st[f].visible_samples);
				if (c.st[f].reused_samples <= 0)
					fail_msg("tarc@8 frame %u: reused %lld of %lld", f, (long long)c.st[f].reused_samples,
						 (long long)c.st[f].visible_samples);
			}
		}
		tu_clip_free(&c);
	}
	tu_clip_free(&ref);
	assert_int_equal(vkdev_validation_messages(dev), 0);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* R2: static scene and camera: tile i of a covered pixel is refreshed at frame t iff (t + i) mod N = 0
 * (paper sec. 5.1, tiles aligned to the origin, i = (y >> 4) * ceil(W / 16) + (x >> 4)). The width is not a
 * multiple of 16 so that the partial tile column is in the check. */
static void test_rrc_static_schedule(void **state)
{
	(void)state;
	scene *s = tu_load_scene("tfr_static");
	vkdev *dev = tu_lavapipe();
	enum { F = 9, W = 88, H = 40 };
	tu_clip ref = tu_render_clip(dev, s, 0, "ref", NULL, NULL, W, H, F, false);
	const char *nearest[] = {"resample=nearest", NULL};
	const char *variants[] = {"rrc/2", "rrc/4", "rrc/8"};
	uint32_t tiles_x = (W + 15) / 16;
	for (int v = 0; v < 3; v++)
		for (int k = 0; k < 2; k++) {
			uint32_t period = 2u << v;
			tu_clip c = tu_render_clip(dev, s, 0, variants[v], k ? nearest : NULL, NULL, W, H, F, true);
			int64_t refreshed = 0;
			tu_assert_same_frames(&ref, &c, true);
			assert_invariants(&c, variants[v]);
			for (uint32_t f = 0; f < F; f++) {
				int64_t due = 0;
				for (uint32_t y = 0; y < H; y++)
					for (uint32_t x = 0; x < W; x++) {
						size_t i = (size_t)y * W + x;
						bool covered = c.hdr[f][i * 4 + 3] != 0;
						uint32_t tile = (y >> 4) * tiles_x + (x >> 4);
						frame_decision want = !covered ? FRAME_DECISION_NONE
								      : f == 0 ? FRAME_DECISION_NEW
								      : (f + tile) % period == 0 ? FRAME_DECISION_SCHEDULED
												 : FRAME_DECISION_REUSED;
						if (c.dec[f][i] != want)
							fail_msg("%s %s frame %u pixel (%u,%u): decision %d, expected %d",
								 variants[v], k ? "nearest" : "bilinear", f, x, y, c.dec[f][i],
								 want);
						due += covered && f > 0 && (f + tile) % period == 0;
					}
				if (f > 0) {
					assert_int_equal(c.st[f].new_units, 0);
					assert_int_equal(c.st[f].shaded_samples, due);
					refreshed += due;
				}
			}
			assert_true(refreshed > 0);
			tu_clip_free(&c);
		}
	tu_clip_free(&ref);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* ---- on a built-in scene with a moving camera: R4, invariants, visible samples, oracle bound, determinism ---- */

static void test_moving_camera(void **state)
{
	(void)state;
	scene *s = tu_load_scene("scenes/calm.json");
	vkdev *dev = tu_lavapipe();
	int cam = tu_camera_index(s, "walk");
	enum { N = 8, W = 80, H = 48 };
	size_t px = (size_t)W * H;
	tu_clip ref = tu_render_clip(dev, s, cam, "ref", NULL, NULL, W, H, N, false);
	tu_clip tfr = tu_render_clip(dev, s, cam, "tfr@8", NULL, NULL, W, H, N, false);
	const char *nearest[] = {"resample=nearest", NULL};
	tu_clip rrcn = tu_render_clip(dev, s, cam, "rrc/4", nearest, NULL, W, H, N, true);
	tu_clip rrc = tu_render_clip(dev, s, cam, "rrc/4", NULL, NULL, W, H, N, true);
	const char *truth[] = {"truth", NULL};
	tu_clip tarc = tu_render_clip(dev, s, cam, "tarc@8", truth, NULL, W, H, N, true);
	/* the reruns count with one atomic per fragment instead of one per subgroup (reproj.glsl COUNT, ref/count.glsl) */
	assert_int_equal(setenv("TASLAB_COUNT_ATOMICS", "1", 1), 0);
	tu_clip tarc2 = tu_render_clip(dev, s, cam, "tarc@8", truth, NULL, W, H, N, true);
	tu_clip ref2 = tu_render_clip(dev, s, cam, "ref", NULL, NULL, W, H, N, false);
	unsetenv("TASLAB_COUNT_ATOMICS");
	tu_clip oracle = tu_render_clip(dev, s, cam, "tarc-oracle@8", truth, NULL, W, H, N, true);
	assert_invariants(&rrcn, "rrc/4 nearest");
	assert_invariants(&rrc, "rrc/4");
	assert_invariants(&tarc, "tarc@8");
	assert_invariants(&oracle, "tarc-oracle@8");
	int64_t misses = 0, reused = 0;
	for (uint32_t f = 0; f < N; f++) {
		/* (c) the same visible samples whatever the method */
		assert_int_equal(tfr.st[f].visible_samples, ref.st[f].visible_samples);
		assert_int_equal(rrc.st[f].visible_samples, ref.st[f].visible_samples);
		assert_int_equal(rrcn.st[f].visible_samples, ref.st[f].visible_samples);
		assert_int_equal(tarc.st[f].visible_samples, ref.st[f].visible_samples);
		assert_int_equal(oracle.st[f].visible_samples, ref.st[f].visible_samples);
		/* R4: nearest lookup = tfr's visibility rule, so the same misses */
		assert_int_equal(rrcn.st[f].new_units, tfr.st[f].new_units);
		misses += f ? rrcn.st[f].new_units : 0;
		/* bilinear misses only where all four taps fail: never more than nearest */
		assert_true(rrc.st[f].new_units <= rrcn.st[f].new_units);
		/* T3 under motion: the oracle shows C' only within T of the truth */
		int d = tu_max_diff(oracle.disp[f], ref.disp[f], px);
		if (d > 9)
			fail_msg("tarc-oracle@8 frame %u: %d code values from ref (bound T + 1 = 9)", f, d);
		assert_int_equal(oracle.st[f].late_samples, 0);
		assert_true(tarc.st[f].late_samples >= 0 && tarc.st[f].late_samples <= tarc.st[f].reused_samples);
		double forced = tu_extra(&tarc.st[f], "forced_samples");
		assert_true(forced >= (double)tarc.st[f].new_units && forced <= (double)tarc.st[f].shaded_samples);
		reused += oracle.st[f].reused_samples;
		/* determinism: same inputs, same bytes and counts, whether counted per subgroup or per fragment */
		assert_memory_equal(tarc.disp[f], tarc2.disp[f], px * 4);
		assert_memory_equal(tarc.hdr[f], tarc2.hdr[f], px * 8);
		assert_memory_equal(tarc.dec[f], tarc2.dec[f], px);
		assert_int_equal(tarc.st[f].shaded_samples, tarc2.st[f].shaded_samples);
		assert_int_equal(tarc.st[f].late_samples, tarc2.st[f].late_samples);
		assert_int_equal(tarc.st[f].reused_samples, tarc2.st[f].reused_samples);
		assert_memory_equal(ref.hdr[f], ref2.hdr[f], px * 8);
		assert_int_equal(ref.st[f].shaded_samples, ref2.st[f].shaded_samples);
		/* ref shades every covered sample: its count, per subgroup or per fragment, is the visible samples */
		assert_int_equal(ref.st[f].shaded_samples, ref.st[f].visible_samples);
		assert_int_equal(tarc.st[f].new_units, tarc2.st[f].new_units);
		assert_true(forced == tu_extra(&tarc2.st[f], "forced_samples"));
	}
	assert_true(misses > 0);  /* the walk uncovers something */
	assert_true(reused > 0);  /* and the oracle reuses */
	print_message("calm/walk %ux%u, %u frames: misses after frame 0 %lld; oracle reused %lld\n", W, H, N,
		      (long long)misses, (long long)reused);
	tu_clip *all[] = {&ref, &ref2, &tfr, &rrcn, &rrc, &tarc, &tarc2, &oracle};
	for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
		tu_clip_free(all[i]);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* ---- tarc ---- */

/* T1: nothing changes: frame 0 new, frame 1 second frame, then reuse 1.0 with ref's frames, at any T. */
static void test_tarc_static(void **state)
{
	(void)state;
	scene *s = tu_load_scene("tfr_static");
	vkdev *dev = tu_lavapipe();
	enum { F = 6, W = 96, H = 64 };
	tu_clip ref = tu_render_clip(dev, s, 0, "ref", NULL, NULL, W, H, F, false);
	const char *variants[] = {"tarc@2", "tarc@8", "tarc@64", "tarc@8"};
	const char *nearest[] = {"resample=nearest", NULL};
	for (int v = 0; v < 4; v++) {
		tu_clip c = tu_render_clip(dev, s, 0, variants[v], v == 3 ? nearest : NULL, NULL, W, H, F, true);
		tu_assert_same_frames(&ref, &c, true);
		assert_invariants(&c, variants[v]);
		for (uint32_t f = 0; f < F; f++) {
			int64_t vis = c.st[f].visible_samples;
			frame_decision want = f == 0 ? FRAME_DECISION_NEW : f == 1 ? FRAME_DECISION_SECOND : FRAME_DECISION_REUSED;
			assert_int_equal(count_dec(&c, f, want), vis);
			assert_int_equal(c.st[f].shaded_samples, f < 2 ? vis : 0);
			assert_true(tu_extra(&c.st[f], "forced_samples") == (f < 2 ? (double)vis : 0.0));
		}
		tu_clip_free(&c);
	}
	/* the oracle on a static scene reuses everything after frame 0 (C' = truth exactly) */
	tu_clip o = tu_render_clip(dev, s, 0, "tarc-oracle@0", NULL, NULL, W, H, F, true);
	tu_assert_same_frames(&ref, &o, true);
	for (uint32_t f = 1; f < F; f++)
		assert_int_equal(o.st[f].reused_samples, o.st[f].visible_samples);
	tu_clip_free(&o);
	tu_clip_free(&ref);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* T2: where shading does not change nothing is predicted: only new samples and their second frame are
 * shaded. The box slides 0.7 px per frame over a static, unshadowed floor; its own shading hardly changes
 * (flat faces, a directional light), far below T = 255 within the clip. */
static void test_tarc_forced_only(void **state)
{
	(void)state;
	scene *s = tu_load_scene("reuse_slide");
	vkdev *dev = tu_lavapipe();
	enum { F = 16, W = 96, H = 64 };
	tu_clip c = tu_render_clip(dev, s, 0, "tarc@255", NULL, NULL, W, H, F, true);
	assert_invariants(&c, "tarc@255");
	int64_t second_total = 0;
	for (uint32_t f = 1; f < F; f++) {
		int64_t nw = count_dec(&c, f, FRAME_DECISION_NEW), sec = count_dec(&c, f, FRAME_DECISION_SECOND);
		assert_int_equal(count_dec(&c, f, FRAME_DECISION_PREDICTED), 0);
		assert_int_equal(count_dec(&c, f, FRAME_DECISION_SCHEDULED), 0);
		assert_int_equal(c.st[f].shaded_samples, nw + sec);
		assert_true(tu_extra(&c.st[f], "forced_samples") == (double)(nw + sec));
		second_total += sec;
		/* every second-frame sample was new a frame earlier, within a pixel */
		for (int y = 0; y < H; y++)
			for (int x = 0; x < W; x++) {
				if (c.dec[f][y * W + x] != FRAME_DECISION_SECOND)
					continue;
				bool found = false;
				for (int dy = -1; dy <= 1 && !found; dy++)
					for (int dx = -1; dx <= 1 && !found; dx++) {
						int xx = x + dx, yy = y + dy;
						found = xx >= 0 && yy >= 0 && xx < W && yy < H &&
							c.dec[f - 1][yy * W + xx] == FRAME_DECISION_NEW;
					}
				if (!found)
					fail_msg("frame %u pixel (%d,%d): second frame without a new sample next to it before", f,
						 x, y);
			}
	}
	assert_true(second_total > (int64_t)(F - 2) * 8); /* the box uncovers floor every frame */
	tu_clip_free(&c);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* The spatial filter of tarc (TAS-METHODS section 3 step 3): 8x8 max downsample, then 9x9 max kernel clipped
 * at the borders; v has one value per pixel, out one per 8x8 tile. */
static void filter_8x8_9x9(const float *v, uint32_t w, uint32_t h, float *out)
{
	uint32_t tw = (w + 7) / 8, th = (h + 7) / 8;
	float *l1 = calloc((size_t)tw * th, sizeof *l1);
	for (uint32_t y = 0; y < h; y++)
		for (uint32_t x = 0; x < w; x++) {
			float *t = &l1[(y / 8) * tw + x / 8];
			*t = fmaxf(*t, v[(size_t)y * w + x]);
		}
	for (uint32_t ty = 0; ty < th; ty++)
		for (uint32_t tx = 0; tx < tw; tx++) {
			float m = 0;
			for (int dy = -4; dy <= 4; dy++)
				for (int dx = -4; dx <= 4; dx++) {
					int x = (int)tx + dx, y = (int)ty + dy;
					if (x >= 0 && y >= 0 && x < (int)tw && y < (int)th)
						m = fmaxf(m, l1[y * tw + x]);
				}
			out[ty * tw + tx] = m;
		}
	free(l1);
}

/* disp(x) of the raw config, max over RGB of the difference of two HDR pixels (TAS-METHODS section 0) */
static float raw_maxrgb(const uint16_t *a, const uint16_t *b)
{
	float m = 0;
	for (int k = 0; k < 3; k++) {
		float x = fminf(fmaxf(tu_half_to_float(a[k]), 0), 1) * 255.0f, y = fminf(fmaxf(tu_half_to_float(b[k]), 0), 1) * 255.0f;
		m = fmaxf(m, fabsf(x - y));
	}
	return m;
}

/* T4: a light ramping linearly, raw display: every pixel's true change per frame g is constant, so after the
 * second frame (which measures g over one frame) a pixel is reshaded whenever F * age > T, i.e. every
 * floor(T / F) + 1 frames, F = the filtered g. The half-float rounding of the one-frame difference makes the
 * first interval uncertain by a few percent: +-1 frame. */
static void test_tarc_linear_ramp(void **state)
{
	(void)state;
	scene *s = tu_load_scene("tarc_ramp");
	vkdev *dev = tu_lavapipe();
	colour *col = tu_raw_colour();
	enum { F = 40, W = 128, H = 96 }; /* the floor covers the whole frame */
	size_t px = (size_t)W * H;
	uint32_t tw = (W + 7) / 8;
	tu_clip ref = tu_render_clip(dev, s, 0, "ref", NULL, col, W, H, F, false);
	/* the true per-frame change of each pixel, over the whole clip */
	float *g = calloc(px, sizeof *g), *filt = calloc(px, sizeof *filt);
	for (size_t i = 0; i < px; i++)
		g[i] = raw_maxrgb(ref.hdr[F - 1] + i * 4, ref.hdr[0] + i * 4) / (float)(F - 1);
	filter_8x8_9x9(g, W, H, filt);
	const char *variants[] = {"tarc@4", "tarc@8"};
	const float Ts[] = {4, 8};
	for (int v = 0; v < 2; v++) {
		tu_clip c = tu_render_clip(dev, s, 0, variants[v], NULL, col, W, H, F, true);
		assert_invariants(&c, variants[v]);
		int64_t intervals = 0, off = 0;
		for (uint32_t y = 0; y < H; y++)
			for (uint32_t x = 0; x < W; x++) {
				size_t i = (size_t)y * W + x;
				float Fp = filt[(y / 8) * tw + x / 8];
				int expect = (int)floorf(Ts[v] / Fp) + 1;
				assert_int_equal(c.dec[0][i], FRAME_DECISION_NEW);
				assert_int_equal(c.dec[1][i], FRAME_DECISION_SECOND);
				uint32_t last = 1;
				for (uint32_t f = 2; f < F; f++) {
					uint8_t d = c.dec[f][i];
					if (d == FRAME_DECISION_REUSED)
						continue;
					if (d != FRAME_DECISION_PREDICTED)
						fail_msg("%s frame %u pixel (%u,%u): decision %d", variants[v], f, x, y, d);
					int got = (int)(f - last);
					intervals++;
					if (abs(got - expect) > 1 && off++ < 5)
						print_message("%s pixel (%u,%u): reshaded after %d frames, expected %d (F = %.4f)\n",
							      variants[v], x, y, got, expect, (double)Fp);
					last = f;
				}
				/* no reshade overdue at the end of the clip either */
				if ((int)(F - 1 - last) > expect + 1 && off++ < 5)
					print_message("%s pixel (%u,%u): not reshaded for %u frames, expected every %d\n", variants[v],
						      x, y, F - 1 - last, expect);
			}
		print_message("%s: %lld intervals, %lld off by more than one frame\n", variants[v], (long long)intervals,
			      (long long)off);
		assert_true(intervals >= (int64_t)px * 2); /* at least two reshades per pixel after frame 1 */
		assert_int_equal(off, 0);
		tu_clip_free(&c);
	}
	free(g);
	free(filt);
	tu_clip_free(&ref);
	colour_destroy(&col);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* T5 and T3 on a moving shadow (static camera): predicted reshades only within the filter footprint of
 * something that changed; oracle within T + 1 of ref; oracle T = 0 equals ref's PNGs. */
static void test_tarc_footprint_and_oracle(void **state)
{
	(void)state;
	scene *s = tu_load_scene("tfr_shadow");
	vkdev *dev = tu_lavapipe();
	enum { F = 16, W = 256, H = 64 };
	size_t px = (size_t)W * H;
	int tw = (W + 7) / 8, th = (H + 7) / 8;
	tu_clip ref = tu_render_clip(dev, s, 0, "ref", NULL, NULL, W, H, F, false);
	const char *truth[] = {"truth", NULL};
	tu_clip c = tu_render_clip(dev, s, 0, "tarc@8", truth, NULL, W, H, F, true);
	assert_invariants(&c, "tarc@8");
	/* tiles whose true shading changed between two consecutive frames up to t */
	bool *changed = calloc((size_t)tw * th, 1);
	int64_t predicted = 0, far_reused = 0, late = 0;
	for (uint32_t f = 1; f < F; f++) {
		for (size_t i = 0; i < px; i++)
			if (memcmp(ref.hdr[f] + i * 4, ref.hdr[f - 1] + i * 4, 8))
				changed[(i / W / 8) * tw + (i % W) / 8] = true;
		for (size_t i = 0; i < px; i++) {
			int tx = (int)(i % W) / 8, ty = (int)(i / W) / 8;
			bool near = false;
			for (int dy = -4; dy <= 4 && !near; dy++)
				for (int dx = -4; dx <= 4 && !near; dx++) {
					int x = tx + dx, y = ty + dy;
					near = x >= 0 && y >= 0 && x < tw && y < th && changed[y * tw + x];
				}
			if (c.dec[f][i] == FRAME_DECISION_PREDICTED) {
				predicted++;
				if (!near)
					fail_msg("frame %u pixel (%zu,%zu): predicted reshade with no change within 4 tiles", f,
						 i % W, i / W);
			} else if (!near && f >= 2) {
				far_reused += c.dec[f][i] == FRAME_DECISION_REUSED;
			}
		}
		assert_true(c.st[f].late_samples >= 0);
		late += c.st[f].late_samples; /* each is a magenta pixel of the map (assert_invariants) */
	}
	print_message("tarc@8 on a moving shadow: %lld predicted reshades, %lld reused samples far from any change, "
		      "%lld late\n", (long long)predicted, (long long)far_reused, (long long)late);
	assert_true(predicted > 0);
	assert_true(far_reused > 0);
	free(changed);
	tu_clip_free(&c);

	tu_clip o = tu_render_clip(dev, s, 0, "tarc-oracle@8", truth, NULL, W, H, F, true);
	tu_clip o0 = tu_render_clip(dev, s, 0, "tarc-oracle@0", NULL, NULL, W, H, F, true);
	int64_t o_reused = 0;
	for (uint32_t f = 0; f < F; f++) {
		int d = tu_max_diff(o.disp[f], ref.disp[f], px);
		if (d > 9)
			fail_msg("tarc-oracle@8 frame %u: %d code values from ref (bound T + 1 = 9)", f, d);
		assert_int_equal(o.st[f].late_samples, 0);
		o_reused += o.st[f].reused_samples;
		assert_int_equal(count_dec(&o, f, FRAME_DECISION_SECOND), 0); /* no two-frame rule */
	}
	assert_true(o_reused > 0);
	tu_assert_same_frames(&ref, &o0, false);
	tu_clip_free(&o);
	tu_clip_free(&o0);
	tu_clip_free(&ref);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* --truth on the other reuse methods: tfr reuses only what is within T of the truth (0 late), rrc on a static
 * scene reuses exact values (0 late); a method without reuse has no --truth. */
static void test_truth(void **state)
{
	(void)state;
	char err[1024];
	scene *s = tu_load_scene("tfr_shadow");
	vkdev *dev = tu_lavapipe();
	enum { F = 8, W = 64, H = 48 };
	const char *truth[] = {"truth", NULL};
	tu_clip t = tu_render_clip(dev, s, 0, "tfr@8", truth, NULL, W, H, F, false);
	tu_clip r = tu_render_clip(dev, s, 0, "rrc/4", truth, NULL, W, H, F, true);
	assert_invariants(&r, "rrc/4 --truth"); /* incl. magenta (late) map pixels = late_samples, frame by frame */
	tu_clip plain = tu_render_clip(dev, s, 0, "rrc/4", NULL, NULL, W, H, F, false);
	int64_t r_late = 0, r_reused = 0;
	for (uint32_t f = 0; f < F; f++) {
		assert_int_equal(t.st[f].late_samples, 0);
		assert_true(r.st[f].late_samples >= 0 && r.st[f].late_samples <= r.st[f].reused_samples);
		r_late += r.st[f].late_samples;
		r_reused += r.st[f].reused_samples;
		assert_int_equal(plain.st[f].late_samples, -1); /* empty column without --truth */
		/* the diagnostic changes nothing it measures */
		assert_memory_equal(r.disp[f], plain.disp[f], (size_t)W * H * 4);
		/* and its pass is not the method's time: gpu_ms_total is every pass but "truth" */
		double sum = 0, truth_ms = -1;
		for (uint32_t p = 0; p < r.st[f].pass_count; p++) {
			sum += r.st[f].gpu_ms[p];
			if (!strcmp(r.st[f].pass_names[p], "truth"))
				truth_ms = r.st[f].gpu_ms[p];
		}
		assert_true(truth_ms >= 0);
		assert_float_equal(r.st[f].gpu_ms_total, sum - truth_ms, 1e-6 * (1 + sum));
	}
	print_message("rrc/4 on a moving shadow: %lld of %lld reused samples late (T = 8)\n", (long long)r_late,
		      (long long)r_reused);
	assert_true(r_late > 0); /* so the map check above compared something */
	tu_clip_free(&t);
	tu_clip_free(&r);
	tu_clip_free(&plain);
	method_config mc;
	assert_int_equal(method_config_init(&mc, "ref", err, sizeof err), TL_OK);
	assert_int_not_equal(method_config_set(&mc, "truth", "true", err, sizeof err), TL_OK);
	/* decision maps only from methods that make decisions */
	render *rr = NULL;
	render_desc d = {.scene = s, .width = 16, .height = 16, .method = &mc, .decisions = true};
	assert_int_equal(render_create(dev, &d, &rr, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "no reuse decisions"));
	assert_null(rr);
	vkdev_destroy(&dev);
	scene_destroy(&s);
}

/* ---- bad input: one line, non-zero exit, no run folder that looks complete ---- */

static void test_bad_input(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("reuse_bad");
	char base[4096], args[8192], path[4096];
	snprintf(base, sizeof base, "render --scene %s/tests/data/tfr_static.json --size 32x32 --frames 0:2 --out %s/r",
		 TASLAB_SOURCE_DIR, dir);
	static const struct {
		const char *opts, *needle;
	} cases[] = {
		{"--method rrc --period 3", "--period 3"},
		{"--method rrc/3", "rrc/3"},
		{"--method rrc --oracle", "--oracle"},
		{"--method rrc --resample cubic", "--resample"},
		{"--method tarc --threshold 0", "T > 0"},
		{"--method tarc@0", "T > 0"},
		{"--method tarc --threshold -1", "--threshold"},
		{"--method tarc@300", "255"},
		{"--method tarc-oracle@8 --force-reshade", "--force-reshade"},
		{"--method tarc --period 4", "--period"},
		{"--method ref --decisions", "no reuse decisions"},
		{"--method tfr@8 --decisions", "no reuse decisions"},
	};
	for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
		snprintf(args, sizeof args, "%s %s", base, cases[i].opts);
		tu_expect_cli_error(args, cases[i].needle);
	}
	snprintf(path, sizeof path, "%s/r/manifest.json", dir);
	assert_false(tu_file_exists(path));
	snprintf(path, sizeof path, "%s/r", dir);
	assert_false(tu_file_exists(path)); /* refused before anything was created */
}

/* The command line end to end: a run with decision maps, and `pair` building rrc/tarc stimuli with their
 * periods and thresholds in pairs.json. */
static void test_cli_runs(void **state)
{
	(void)state;
	const char *dir = tu_tmpdir("reuse_cli");
	char cmd[8192], out[16384], path[4096];
	snprintf(cmd, sizeof cmd,
		 "%s render --scene %s/tests/data/tfr_shadow.json --method tarc@8 --truth --decisions --size 48x32 "
		 "--frames 0:3 --quiet --out %s/run",
		 TASLAB_BINARY, TASLAB_SOURCE_DIR, dir);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s\n%s", cmd, out);
	for (int f = 0; f < 3; f++) {
		snprintf(path, sizeof path, "%s/run/decisions/%06d.png", dir, f);
		assert_true(tu_file_exists(path));
	}
	snprintf(path, sizeof path, "%s/run/stats.csv", dir);
	char *csv = tu_read_file(path, NULL);
	assert_non_null(strstr(csv, ",reused_samples,allocated_samples,late_samples,forced_samples\n"));
	free(csv);
	snprintf(path, sizeof path, "%s/run/manifest.json", dir);
	char *m = tu_read_file(path, NULL);
	assert_non_null(strstr(m, "\"variant\": \"tarc@8\""));
	assert_non_null(strstr(m, "\"truth\": true"));
	free(m);

	snprintf(cmd, sizeof cmd,
		 "%s pair --scene %s/tests/data/tfr_shadow.json --variants rrc/4,rrc/8,tarc@8,tarc-oracle@8 --size 32x24 "
		 "--frames 0:3 --out %s/set",
		 TASLAB_BINARY, TASLAB_SOURCE_DIR, dir);
	if (tu_run(cmd, out, sizeof out))
		fail_msg("%s\n%s", cmd, out);
	snprintf(path, sizeof path, "%s/set/pairs.json", dir);
	char *p = tu_read_file(path, NULL);
	assert_non_null(p);
	assert_non_null(strstr(p, "\"variant\": \"rrc/4\""));
	assert_non_null(strstr(p, "\"variant\": \"rrc/8\""));
	assert_non_null(strstr(p, "\"period\": 8"));
	assert_non_null(strstr(p, "\"method\": \"tarc-oracle\""));
	free(p);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_bad_input),
		cmocka_unit_test(test_rrc1_equals_ref),
		cmocka_unit_test(test_mask_odd_size),
		cmocka_unit_test(test_rrc_static_schedule),
		cmocka_unit_test(test_tarc_static),
		cmocka_unit_test(test_tarc_forced_only),
		cmocka_unit_test(test_tarc_linear_ramp),
		cmocka_unit_test(test_tarc_footprint_and_oracle),
		cmocka_unit_test(test_truth),
		cmocka_unit_test(test_moving_camera),
		cmocka_unit_test(test_cli_runs),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
