/* test_stereo_all.c — the built-in scenes with every available method in stereo (issue 25: "every built-in scene
 * with every method in stereo"), on lavapipe with the validation layer (any message fails), at 32x24 per eye, 2
 * frames, a moving camera path. A render's set-up (its pipelines) costs 0.6-6 s here, so the full product (4 scenes
 * x 14 methods, ~5.5 min: measured 63 + 73 + 74 + 118 s) runs with TASLAB_STEREO_ALL=full, one scene of it with
 * TASLAB_STEREO_ALL=sceneK (K = 0..3; scene 0 adds both eyes' mono runs of the compacted-path methods); ctest runs 4 shards (argument k = 0..3, each under 30 s):
 * shard k renders scene k with the reference and every k-th method of the registry, so every method runs in stereo
 * on one scene and every scene with several methods. Checks:
 *  - each renders both eyes; each eye sees the scene (covered pixels, visible samples per eye > 0) and the eyes
 *    differ (ipd 0.063 at these sizes still moves edges by a pixel);
 *  - the per-eye counts add up: visible = l + r; a per-eye method's shaded = l + r; a shared-atlas method's shaded
 *    <= l + r (blocks both eyes see are shaded once) and >= max(l, r);
 *  - the compacted-sample-path methods (vref, ads and the VRS methods, BASELINES.md A7/A8) run per eye like ref:
 *    an eye equals a mono run from that eye's camera, frames and counts (X3 of STEREO.md for that path; in the
 *    shards one eye per method, alternating; the full run both eyes on the first scene).
 * Variants come from the method registry (the default of each option a variant must carry). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_vk.h"

#include "taslab/method.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

enum { W = 32, H = 24, NF = 2 };
static const float IPD = 0.063f;

typedef struct eyes {
	uint32_t views;
	uint8_t *disp[2][NF];
	uint16_t *hdr[2][NF];
	frame_stats st[NF];
} eyes;

static void render_eyes(vkdev *dev, const scene *s, int camera, const method_config *mc, uint32_t views, float ipd,
			float shift, eyes *out)
{
	char err[1024], id[96];
	method_config_id(mc, id, sizeof id);
	render *r = NULL;
	render_desc d = {.scene = s, .camera = camera, .width = W, .height = H, .method = mc, .views = views, .ipd = ipd,
			 .eye_shift = shift};
	if (render_create(dev, &d, &r, err, sizeof err))
		fail_msg("%s %s: %s", s->name, id, err);
	memset(out, 0, sizeof *out);
	out->views = views;
	for (uint32_t f = 0; f < NF; f++) {
		frame_image img;
		if (render_frame(r, f, &img, &out->st[f], err, sizeof err))
			fail_msg("%s %s frame %u: %s", s->name, id, f, err);
		for (uint32_t v = 0; v < views; v++) {
			frame_image e;
			assert_int_equal(render_view_image(r, v, &e), TL_OK);
			out->disp[v][f] = malloc((size_t)W * H * 4);
			out->hdr[v][f] = malloc((size_t)W * H * 8);
			memcpy(out->disp[v][f], e.display_rgba, (size_t)W * H * 4);
			memcpy(out->hdr[v][f], e.hdr_rgba_half, (size_t)W * H * 8);
		}
	}
	render_destroy(&r);
	if (vkdev_validation_messages(dev))
		fail_msg("%s %s: validation messages", s->name, id);
}

static void eyes_free(eyes *e)
{
	for (uint32_t v = 0; v < e->views; v++)
		for (uint32_t f = 0; f < NF; f++) {
			free(e->disp[v][f]);
			free(e->hdr[v][f]);
		}
}

static bool same(const eyes *a, uint32_t va, const eyes *b, uint32_t vb, uint32_t f)
{
	return !memcmp(a->disp[va][f], b->disp[vb][f], (size_t)W * H * 4) &&
	       !memcmp(a->hdr[va][f], b->hdr[vb][f], (size_t)W * H * 8);
}

static int64_t covered(const eyes *e, uint32_t v, uint32_t f)
{
	int64_t n = 0;
	for (size_t i = 0; i < (size_t)W * H; i++)
		n += e->hdr[v][f][4 * i + 3] != 0;
	return n;
}

/* The method with its defaults, plus a value for each option a variant must carry (its default, else the middle of
 * its allowed values or range). false for a planned method. */
static bool config_for(const method_info *m, method_config *mc)
{
	char err[512], val[32];
	if (!m->available)
		return false;
	if (method_config_init(mc, m->name, err, sizeof err))
		fail_msg("%s: %s", m->name, err);
	for (size_t i = 0; i < m->option_count; i++) {
		const method_option *o = &m->options[i];
		if (!o->variant_required)
			continue;
		double v = o->def > 0 ? o->def : 8.0;
		if (o->allowed) {
			size_t n = 0;
			while (o->allowed[n])
				n++;
			v = o->allowed[n / 2];
		} else if (!(v >= o->min && v <= o->max))
			v = (o->min + o->max) / 2;
		snprintf(val, sizeof val, "%g", v);
		if (method_config_set(mc, o->name, val, err, sizeof err))
			fail_msg("%s --%s %s: %s", m->name, o->name, val, err);
	}
	/* at 32x24 the default atlas (4 x the pixels) overflows on the busiest scene, mono as well */
	for (size_t i = 0; i < m->option_count; i++)
		if (!strcmp(m->options[i].name, "atlas-scale") && method_config_set(mc, "atlas-scale", "16", err, sizeof err))
			fail_msg("%s --atlas-scale 16: %s", m->name, err);
	if (method_config_check(mc, err, sizeof err))
		fail_msg("%s: %s", m->name, err);
	return true;
}

/* The first moving camera path of the scene (0 when none). */
static int moving_camera(const scene *s)
{
	for (uint32_t c = 0; c < s->camera_count; c++)
		if (s->cameras[c].motion == SCENE_CAMERA_MOVING)
			return (int)c;
	return 0;
}

static int shard = -1; /* main's argument: 0..3; -1 (TASLAB_STEREO_ALL=full): every scene with every method */
static int only_scene = -1; /* TASLAB_STEREO_ALL=sceneK: scene K with every method (the full product in parts) */

static void test_every_scene_every_method(void **state)
{
	(void)state;
	static const char *const scenes[] = {"scenes/calm.json", "scenes/dynamic.json", "scenes/moderate.json",
					     "scenes/turntable.json"};
	size_t nm = 0;
	const method_info *const *ms = method_list(&nm);
	vkdev *dev = tu_lavapipe();
	int checked = 0, x3 = 0;
	const size_t nscenes = sizeof scenes / sizeof *scenes;
	for (size_t si = 0; si < nscenes; si++) {
		if ((shard >= 0 && si != (size_t)shard) || (only_scene >= 0 && si != (size_t)only_scene))
			continue;
		scene *s = tu_load_scene(scenes[si]);
		int cam = moving_camera(s);
		for (size_t k = 0; k < nm; k++) {
			method_config mc;
			if ((shard >= 0 && k % nscenes != (size_t)shard && !ms[k]->reference) || !config_for(ms[k], &mc))
				continue;
			char id[96];
			method_config_id(&mc, id, sizeof id);
			eyes st;
			render_eyes(dev, s, cam, &mc, 2, IPD, 0.0f, &st);
			const bool shared = !strcmp(ms[k]->family, "atlas"); /* one atlas for both eyes (STEREO.md) */
			for (uint32_t f = 0; f < NF; f++) {
				const frame_stats *x = &st.st[f];
				double vl = tu_extra(x, "visible_samples_l"), vr = tu_extra(x, "visible_samples_r");
				double sl = tu_extra(x, "shaded_samples_l"), sr = tu_extra(x, "shaded_samples_r");
				if (!(covered(&st, 0, f) > 0 && covered(&st, 1, f) > 0 && vl > 0 && vr > 0))
					fail_msg("%s %s frame %u: an eye sees nothing (covered %lld, %lld; visible %g, %g)", s->name,
						 id, f, (long long)covered(&st, 0, f), (long long)covered(&st, 1, f), vl, vr);
				assert_true((double)x->visible_samples == vl + vr);
				if (shared) {
					if (!((double)x->shaded_samples <= sl + sr && (double)x->shaded_samples >= fmax(sl, sr)))
						fail_msg("%s %s frame %u: shaded %lld outside [max, sum] of the eyes' %g, %g", s->name,
							 id, f, (long long)x->shaded_samples, sl, sr);
				} else if ((double)x->shaded_samples != sl + sr) {
					fail_msg("%s %s frame %u: shaded %lld != left %g + right %g", s->name, id, f,
						 (long long)x->shaded_samples, sl, sr);
				}
				if (f == 0)
					assert_true(x->shaded_samples > 0);
			}
			if (same(&st, 0, &st, 1, 0))
				fail_msg("%s %s: the eyes are identical at ipd %g", s->name, id, (double)IPD);
			/* the compacted sample path per eye: each eye is the mono run from its camera (one scene) */
			const char *fam = ms[k]->family;
			if ((shard >= 0 || si == 0) && (!strcmp(fam, "rate") || !strcmp(fam, "deferred") ||
					(!strcmp(fam, "reference") && !ms[k]->reference))) {
				/* one eye per method (the left for even registry indices, the right for odd), to stay within
				 * the shard's time; the full run checks both */
				for (uint32_t v = shard >= 0 ? (uint32_t)(k % 2) : 0; v < (shard >= 0 ? (uint32_t)(k % 2) + 1 : 2); v++) {
					eyes mono;
					render_eyes(dev, s, cam, &mc, 1, 0.0f, v ? IPD / 2 : -IPD / 2, &mono);
					for (uint32_t f = 0; f < NF; f++) {
						if (!same(&st, v, &mono, 0, f))
							fail_msg("%s %s frame %u: eye %u differs from the mono run from its camera",
								 s->name, id, f, v);
						assert_int_equal((int64_t)tu_extra(&st.st[f], v ? "shaded_samples_r" : "shaded_samples_l"),
								 mono.st[f].shaded_samples);
					}
					eyes_free(&mono);
				}
				x3++;
			}
			eyes_free(&st);
			checked++;
		}
		scene_destroy(&s);
	}
	fprintf(stderr, "%d scene x method stereo runs checked; %d compacted-path methods equal to their eyes' mono runs\n",
		checked, x3);
	assert_true(checked >= (shard >= 0 ? 3 : only_scene >= 0 ? 14 : 4 * 14));
	vkdev_destroy(&dev);
}

int main(int argc, char **argv)
{
	const char *full = getenv("TASLAB_STEREO_ALL");
	shard = full && (!strcmp(full, "full") || !strncmp(full, "scene", 5)) ? -1 : argc > 1 ? atoi(argv[1]) : 0;
	if (full && !strncmp(full, "scene", 5))
		only_scene = atoi(full + 5);
	if (shard > 3)
		return fprintf(stderr, "shard %d: 0..3\n", shard), 2;
	const struct CMUnitTest tests[] = {cmocka_unit_test(test_every_scene_every_method)};
	return tu_finish(cmocka_run_group_tests(tests, NULL, NULL));
}
