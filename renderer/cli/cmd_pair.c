/* cmd_pair.c — `taslab pair`: paired study clips for one scene and camera path (DESIGN sections 5, 7):
 * renders the reference and each variant (ref, tfr@8, rrc/4, tarc-oracle@8, ...) into run folders, encodes
 * their bit-exact clips, an inspection clip per variant (reference | variant side by side), and pairs.json
 * (output/pairs.h) tying every clip to its condition. pairs.json is written last and atomically: its
 * presence means the set is complete. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "commands.h"
#include "taslab/clip.h"
#include "taslab/colour.h"
#include "taslab/imageio.h"
#include "taslab/pairs.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/tl_fs.h"
#include "taslab/vkdev.h"

/* reference | variant, side by side with a 2-pixel grey gap; stereo runs: their side-by-side frames (sbs/, left |
 * right) stacked, the reference above the variant with a 2-row grey gap. */
static int inspect_clip(const char *ref_run, const char *var_run, bool stereo, uint32_t first, uint32_t end, float fps,
			const char *out, char *err, size_t err_size)
{
	const char *dir = stereo ? "sbs" : "frames";
	clip_writer *w = NULL;
	uint8_t *a = NULL, *b = NULL, *sbs = NULL;
	int rc = TL_ERR_INPUT;
	for (uint32_t f = first; f < end; f++) {
		char pa[TL_PATH_MAX], pb[TL_PATH_MAX];
		uint32_t wa, ha, wb, hb;
		snprintf(pa, sizeof pa, "%s/%s/%06u.png", ref_run, dir, f);
		snprintf(pb, sizeof pb, "%s/%s/%06u.png", var_run, dir, f);
		free(a);
		free(b);
		a = b = NULL;
		if ((rc = imageio_read_rgb8(pa, &wa, &ha, &a, err, err_size)) ||
		    (rc = imageio_read_rgb8(pb, &wb, &hb, &b, err, err_size)))
			goto done;
		if (wa != wb || ha != hb) {
			rc = tl_error(err, err_size, TL_ERR_INPUT, "%s and %s differ in size", pa, pb);
			goto done;
		}
		uint32_t W = stereo ? wa : 2 * wa + 2, H = stereo ? 2 * ha + 2 : ha;
		if (!w) {
			if (!(sbs = malloc((size_t)W * H * 3))) {
				rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
				goto done;
			}
			if ((rc = clip_writer_create(out, W, H, fps, &w, err, err_size)))
				goto done;
		}
		if (stereo) {
			size_t plane = (size_t)wa * ha * 3;
			memcpy(sbs, a, plane);
			memset(sbs + plane, 128, (size_t)wa * 2 * 3);
			memcpy(sbs + plane + (size_t)wa * 2 * 3, b, plane);
		}
		for (uint32_t y = 0; !stereo && y < ha; y++) {
			uint8_t *row = sbs + (size_t)y * W * 3;
			memcpy(row, a + (size_t)y * wa * 3, (size_t)wa * 3);
			memset(row + (size_t)wa * 3, 128, 6);
			memcpy(row + (size_t)(wa + 2) * 3, b + (size_t)y * wa * 3, (size_t)wa * 3);
		}
		if ((rc = clip_writer_frame(w, sbs, err, err_size)))
			goto done;
	}
	rc = w ? clip_writer_finish(w, err, err_size) : tl_error(err, err_size, TL_ERR_ARG, "no frames");
done:
	clip_writer_destroy(&w);
	free(a);
	free(b);
	free(sbs);
	return rc;
}

static const cli_opt pair_options[] = {
	{.name = "variants", .arg = "LIST",
	 .help = "comma-separated variants (e.g. tfr@2,tfr@8,rrc/4,tarc-oracle@8); default: ref (a catch "
			     "pair, reference against itself); see 'taslab render --help' for the methods",
	 .type = CLI_STRING, .offset = offsetof(pair_opts, variants)},
	{.name = "out", .arg = "DIR",
	 .help = "output folder (runs/, clips/, inspect/, pairs.json)",
	 .type = CLI_STRING, .offset = offsetof(pair_opts, out)},
	{.name = "stereo", .arg = NULL,
	 .help = "both eyes (--size per eye): every run stereo, the clips side by side (2W x H, left | right), "
			     "pairs.json \"display\": \"stereo\" for a study of side-by-side clips",
	 .type = CLI_FLAG, .offset = offsetof(pair_opts, stereo)},
	{.name = "ipd", .arg = "M",
	 .help = "with --stereo: distance between the eyes in metres (default 0.063)",
	 .type = CLI_DOUBLE, .offset = offsetof(pair_opts, ipd), .lo = 0.0, .hi = RENDER_IPD_MAX},
	{0},
};

static void pair_defaults(void *opts, cli_setup_opts *setup)
{
	(void)setup;
	((pair_opts *)opts)->variants = "ref";
	((pair_opts *)opts)->ipd = -1.0;
}

static int pair_validate(void *opts, cli_ctx *ctx)
{
	pair_opts *o = opts;
	if (!o->out)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--out DIR is required (see 'taslab pair --help')");
	if (o->ipd >= 0.0 && !o->stereo)
		return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--ipd needs --stereo");
	if (o->stereo && o->ipd < 0.0)
		o->ipd = RENDER_STEREO_IPD_DEFAULT;
	char buf[2048];
	const char *items[32];
	int rc = cli_split_list(o->variants, "--variants", buf, sizeof buf, items, 32, &o->count, ctx->err, sizeof ctx->err);
	for (size_t i = 0; !rc && i < o->count; i++) {
		char why[512], a[96], b[96];
		if (method_config_parse_variant(&o->configs[i], items[i], why, sizeof why))
			return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--variants: %s", why);
		method_config_id(&o->configs[i], a, sizeof a);
		for (size_t j = 0; j < i; j++) {
			method_config_id(&o->configs[j], b, sizeof b);
			if (!strcmp(a, b))
				return tl_error(ctx->err, sizeof ctx->err, TL_ERR_ARG, "--variants: '%s' is listed twice", items[i]);
		}
	}
	return rc;
}

static int pair_main(void *opts, cli_ctx *ctx)
{
	pair_opts *o = opts;
	cli_setup *s = &ctx->setup;
	const scene *scn = s->scene;
	char *err = ctx->err;
	size_t err_size = sizeof ctx->err;
	char path[TL_PATH_MAX], sub[TL_PATH_MAX];
	int rc;
	snprintf(path, sizeof path, "%s/pairs.json", o->out);
	if ((rc = tl_mkdirs(o->out, err, err_size)))
		return rc;
	if (unlink(path) && errno != ENOENT)
		return tl_error(err, err_size, TL_ERR_OUTPUT, "%s: cannot remove the old pairs.json: %s", path, strerror(errno));
	const char *subs[2] = {"clips", "inspect"};
	for (int i = 0; i < 2; i++) {
		snprintf(sub, sizeof sub, "%s/%s", o->out, subs[i]);
		if ((rc = tl_mkdirs(sub, err, err_size)))
			return rc;
	}
	pairs_condition conds[32];
	pairs_set set = {.fps = s->fps, .first_frame = s->first, .last_frame = s->end - 1, .width = s->width,
			 .height = s->height, .conditions = conds, .count = 0, .views = o->stereo ? 2 : 1,
			 .ipd = o->stereo ? o->ipd : 0.0};
	snprintf(set.scene, sizeof set.scene, "%s", scn->name);
	snprintf(set.scene_path, sizeof set.scene_path, "%s", s->scene_path);
	snprintf(set.camera, sizeof set.camera, "%s", scn->cameras[s->camera].name);
	snprintf(set.camera_motion, sizeof set.camera_motion, "%s", scene_camera_motion_name(scn->cameras[s->camera].motion));
	snprintf(set.display_transform, sizeof set.display_transform, "%s", colour_name(s->colour));
	snprintf(set.ref_run, sizeof set.ref_run, "runs/ref");
	snprintf(set.ref_clip, sizeof set.ref_clip, "clips/ref.webm");
	method_config ref;
	if ((rc = method_config_init(&ref, "ref", err, err_size)))
		return rc;
	snprintf(set.ref_method, sizeof set.ref_method, "%s", ref.method->name);
	/* Index -1 is the reference; then the variants. */
	for (int k = -1; k < (int)o->count; k++) {
		const method_config *mc = k < 0 ? &ref : &o->configs[k];
		char id[96], run[TL_PATH_MAX], clip[TL_PATH_MAX], inspect[TL_PATH_MAX];
		method_config_id(mc, id, sizeof id);
		/* A variant identical to the reference (a catch pair) reuses the reference's run and clip. */
		int same_as_ref = k >= 0 && !strcmp(id, "ref");
		if (!same_as_ref) {
			snprintf(run, sizeof run, "%s/runs/%s", o->out, id);
			snprintf(clip, sizeof clip, "%s/clips/%s.webm", o->out, id);
			fprintf(stderr, "taslab: pair %s/%s: rendering %s (frames %u..%u, %ux%u%s)\n", scn->name,
				scn->cameras[s->camera].name, id, s->first, s->end - 1, s->width, s->height,
				o->stereo ? " per eye, stereo" : "");
			render_run_desc rr = {.dev = s->dev, .scene = scn, .scene_path = s->scene_path, .camera = s->camera,
					      .colour = s->colour, .method = mc, .first = s->first, .end = s->end,
					      .width = s->width, .height = s->height, .fps = s->fps, .write_exr = true,
					      .write_png = true, .out = run, .command_line = ctx->command_line,
					      .views = o->stereo ? 2 : 1, .ipd = o->stereo ? (float)o->ipd : 0.0f};
			uint32_t n;
			char why[1024];
			if ((rc = render_run(&rr, why, sizeof why)) || (rc = clip_encode_run(run, clip, &n, why, sizeof why)))
				return tl_error(err, err_size, rc, "%s: %s", id, why);
		}
		if (k < 0) { /* the runs' input digests, so `report --study` can check the set against a sweep (issue 27.12) */
			run_manifest m;
			char why[1024];
			if ((rc = run_manifest_read(run, &m, why, sizeof why)))
				return tl_error(err, err_size, rc, "%s", why);
			snprintf(set.scene_digest, sizeof set.scene_digest, "%s", m.scene_digest);
			snprintf(set.colour_digest, sizeof set.colour_digest, "%s", m.colour_digest);
			continue;
		}
		pairs_condition *c = &conds[set.count++];
		memset(c, 0, sizeof *c);
		snprintf(c->id, sizeof c->id, "%s", id);
		method_config_name(mc, c->method, sizeof c->method);
		method_config_variant(mc, c->variant, sizeof c->variant);
		c->T = method_config_threshold(mc);
		c->period = method_config_period(mc);
		method_facts(mc->method, &c->facts); /* what the study needs to know of the method (issue 30.1) */
		snprintf(c->run, sizeof c->run, "runs/%s", same_as_ref ? "ref" : id);
		snprintf(c->clip, sizeof c->clip, "clips/%s.webm", same_as_ref ? "ref" : id);
		snprintf(c->inspect, sizeof c->inspect, "inspect/%s.webm", id);
		char ref_run[TL_PATH_MAX], var_run[TL_PATH_MAX], why[1024];
		snprintf(ref_run, sizeof ref_run, "%s/runs/ref", o->out);
		snprintf(var_run, sizeof var_run, "%s/%s", o->out, c->run);
		snprintf(inspect, sizeof inspect, "%s/%s", o->out, c->inspect);
		if ((rc = inspect_clip(ref_run, var_run, o->stereo, s->first, s->end, s->fps, inspect, why, sizeof why)))
			return tl_error(err, err_size, rc, "%s: %s", id, why);
	}
	if ((rc = pairs_write(path, &set, err, err_size)))
		return rc;
	fprintf(stderr, "taslab: %zu pair(s) in %s (pairs.json, clips/, inspect/)\n", set.count, o->out);
	printf("%s\n", path);
	return TL_OK;
}

const cli_command cli_cmd_pair = {
	.name = "pair",
	.summary = "render reference/variant clip pairs for a study, with pairs.json",
	.synopsis = "taslab pair --scene S --camera C --out DIR [--variants LIST] [options]",
	.description = "Renders the reference (ref) and each variant of one scene and camera path, and writes\n"
		       "  DIR/runs/ID/        run folders (frames, stats.csv, manifest.json)\n"
		       "  DIR/clips/ID.webm   bit-exact lossless clips for the study\n"
		       "  DIR/inspect/ID.webm reference | variant side by side, for looking at the differences\n"
		       "  DIR/pairs.json      the conditions (scene, camera, camera_motion, method, T, period) and clips\n"
		       "With --stereo every run renders both eyes and the clips show them side by side (left | right;\n"
		       "inspect: the reference's above the variant's); pairs.json says \"display\": \"stereo\".",
	.options = pair_options,
	.opts_size = sizeof(pair_opts),
	.defaults = pair_defaults,
	.validate = pair_validate,
	.needs = CLI_NEED_SCENE | CLI_NEED_COLOUR | CLI_NEED_DEVICE,
	.run = pair_main,
};
