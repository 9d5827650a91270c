/* render.c — the public frame pipeline (render.h): creates a render for a method of the registry with the
 * shared passes, renders frames and collects their statistics. The composition root of the renderer: the
 * only file that knows the frame core, the passes and the method interface together. */
#include "frame/render_internal.h"
#include "passes/passes.h"

#include <stdio.h>
#include <stdlib.h>
#include <math.h>
#include <string.h>

int render_create(vkdev *dev, const render_desc *desc, render **out, char *err, size_t err_size)
{
	*out = NULL;
	method_config ref;
	const method_config *mc = desc->method;
	if (!mc) {
		int rc = method_config_init(&ref, "ref", err, err_size);
		if (rc)
			return rc;
		mc = &ref;
	}
	int rc = method_config_check(mc, err, err_size);
	if (rc)
		return rc;
	const render_method *m = render_method_of(mc->method);
	if (!m)
		return tl_error(err, err_size, TL_ERR_UNSUPPORTED, "method '%s' is not implemented yet", mc->method->name);
	render_desc d = *desc;
	d.method = mc;
	return render_create_ops(dev, &d, m, out, err, err_size);
}

/* Timestamp and pipeline-statistics queries, the command buffer and its fence. */
static int create_submission(render *r, char *err, size_t err_size)
{
	VkResult res = VK_SUCCESS;
	VkDevice d = r->dev->device;
	if (r->dev->has_timestamps) {
		VkQueryPoolCreateInfo qi = {
			.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO,
			.queryType = VK_QUERY_TYPE_TIMESTAMP,
			.queryCount = FRAME_MAX_PASSES + 1,
		};
		res = vkCreateQueryPool(d, &qi, NULL, &r->ts_pool);
	}
	if (!res && r->dev->has_pipeline_stats) {
		VkQueryPoolCreateInfo qi = {
			.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO,
			.queryType = VK_QUERY_TYPE_PIPELINE_STATISTICS,
			.queryCount = 1,
			.pipelineStatistics = VK_QUERY_PIPELINE_STATISTIC_FRAGMENT_SHADER_INVOCATIONS_BIT |
					      VK_QUERY_PIPELINE_STATISTIC_COMPUTE_SHADER_INVOCATIONS_BIT,
		};
		res = vkCreateQueryPool(d, &qi, NULL, &r->stats_pool);
	}
	VkCommandBufferAllocateInfo ai = {
		.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
		.commandPool = r->dev->cmd_pool,
		.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
		.commandBufferCount = 1,
	};
	if (!res)
		res = vkAllocateCommandBuffers(d, &ai, &r->cmd);
	VkFenceCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
	if (!res)
		res = vkCreateFence(d, &fi, NULL, &r->fence);
	return res ? render_vk_error(err, err_size, "queries and command buffer", res) : TL_OK;
}

int render_create_ops(vkdev *dev, const render_desc *desc, const render_method *m, render **out, char *err,
		      size_t err_size)
{
	int rc = 0;
	*out = NULL;
	if (!desc->scene || desc->camera < 0 || (size_t)desc->camera >= desc->scene->camera_count)
		return tl_error(err, err_size, TL_ERR_ARG, "no such camera path");
	if (desc->width < 1 || desc->height < 1 || desc->width > 16384 || desc->height > 16384)
		return tl_error(err, err_size, TL_ERR_ARG, "frame size %ux%u out of range (1..16384)", desc->width, desc->height);
	if (desc->decisions && !m->decisions)
		return tl_error(err, err_size, TL_ERR_ARG, "decision maps: method %s makes no reuse decisions", m->info.name);
	if (desc->views > RENDER_MAX_VIEWS)
		return tl_error(err, err_size, TL_ERR_ARG, "%u views: at most %u (mono or stereo)", desc->views, RENDER_MAX_VIEWS);
	if (desc->views > 1 && !(desc->ipd >= 0.0f && desc->ipd <= RENDER_IPD_MAX))
		return tl_error(err, err_size, TL_ERR_ARG, "--ipd %g: the distance between the eyes in metres, 0..%g (human: about 0.063)",
				(double)desc->ipd, (double)RENDER_IPD_MAX);
	if (desc->views > 1 && desc->eye_shift != 0.0f)
		return tl_error(err, err_size, TL_ERR_ARG, "an eye shift is for mono renders; stereo places both eyes itself");
	if (desc->rate_images && !m->tile_rates)
		return tl_error(err, err_size, TL_ERR_ARG, "rate images: method %s chooses no tile rates", m->info.name);
	if (desc->views > 1 && desc->rate_images)
		return tl_error(err, err_size, TL_ERR_ARG, "--rate-images with --stereo: rate images are written for mono runs only");
	if (desc->views > 1 && desc->decisions)
		return tl_error(err, err_size, TL_ERR_ARG, "--decisions with --stereo: decision maps are written for mono runs only");
	if (desc->multiview != RENDER_MULTIVIEW_AUTO && desc->views < 2)
		return tl_error(err, err_size, TL_ERR_ARG, "--multiview: for stereo renders (--stereo) only");
	if (desc->multiview > RENDER_MULTIVIEW_OFF)
		return tl_error(err, err_size, TL_ERR_ARG, "multiview mode %d: auto, on or off", (int)desc->multiview);
	if (desc->multiview == RENDER_MULTIVIEW_ON && !dev->has_multiview)
		return tl_error(err, err_size, TL_ERR_UNSUPPORTED,
				"--multiview on: device '%s' has no multiview feature with 2 views (VK_KHR_multiview); use off",
				dev->props.deviceName);
	if (!(fabsf(desc->eye_shift) <= RENDER_IPD_MAX))
		return tl_error(err, err_size, TL_ERR_ARG, "eye shift %g m out of range (|shift| <= %g)", (double)desc->eye_shift,
				(double)RENDER_IPD_MAX);
	render *r = calloc(1, sizeof *r);
	if (!r)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	r->dev = dev;
	r->scene = desc->scene;
	r->desc = *desc;
	if (desc->method)
		r->config = *desc->method;
	r->desc.method = desc->method ? &r->config : NULL;
	r->method = m;
	if (!(r->desc.fps > 0.0f))
		r->desc.fps = r->scene->fps;
	r->state_ring = m->state_ring ? m->state_ring : 1;
	r->view_count = desc->views > 1 ? desc->views : 1;
	/* AUTO: the measured choice (README "Multiview") */
	r->multiview = r->view_count > 1 && dev->has_multiview &&
		       (desc->multiview == RENDER_MULTIVIEW_ON || (desc->multiview == RENDER_MULTIVIEW_AUTO && RENDER_MULTIVIEW_AUTO_ON));
	r->slot_time = malloc(r->state_ring * sizeof *r->slot_time);
	if (!r->slot_time) {
		rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		goto fail;
	}
	for (uint32_t i = 0; i < r->state_ring; i++)
		r->slot_time[i] = NAN;
	r->world = calloc(r->scene->object_count, sizeof *r->world);
	r->mirrored = calloc(r->scene->object_count + 1, 1);
	r->light_states = calloc(r->scene->light_count + 1, sizeof *r->light_states);
	if (!r->world || !r->mirrored || !r->light_states) {
		rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		goto fail;
	}
	r->colour = desc->colour;
	if (!r->colour) {
		colour_desc cd = {0};
		if ((rc = colour_create(&cd, &r->own_colour, err, err_size)))
			goto fail;
		r->colour = r->own_colour;
	}
	if ((rc = colour_device_create(r->dev, r->colour, &r->colour_dev, err, err_size)))
		goto fail;
	/* A user's view transform is checked GPU against CPU before anything is rendered with it (issue 31.7); the
	 * built-in one is checked by test_colour. */
	if (colour_config_path(r->colour) && (rc = colour_check_gpu(r->dev, r->colour, NULL, err, err_size)))
		goto fail;
	if ((rc = render_upload_scene(r, err, err_size)) || (rc = render_targets_create(r, err, err_size)) ||
	    (rc = render_descriptors_create(r, err, err_size)) || (rc = render_shadow_init(r, err, err_size)))
		goto fail;
	if ((rc = render_depth_init(r, err, err_size)) || (rc = render_shade_init(r, err, err_size)) ||
	    (rc = render_display_init(r, err, err_size)) || (rc = create_submission(r, err, err_size)))
		goto fail;
	/* stereo: the other eyes' targets, rings and sets; then the method: a per-eye method gets a state per eye */
	for (uint32_t v = 1; v < r->view_count; v++) {
		render_use_view(r, v);
		if ((rc = render_view_create(r, err, err_size)))
			goto fail;
		render_shadow_write_sets(r);
	}
	for (uint32_t v = 0; v < (m->shared_views ? 1 : r->view_count); v++) {
		render_use_view(r, v);
		if (m->init && (rc = m->init(r, err, err_size)))
			goto fail;
	}
	render_use_view(r, 0);
	*out = r;
	return TL_OK;
fail:
	render_destroy(&r);
	return rc;
}

size_t render_derived(const render *r, run_option *out, size_t max)
{
	return r->method->derived ? r->method->derived(r, out, max) : 0;
}

void render_destroy(render **pr)
{
	if (!pr || !*pr)
		return;
	render *r = *pr;
	VkDevice d = r->dev->device;
	vkDeviceWaitIdle(d);
	for (uint32_t v = r->view_count; v-- > 0;) {
		render_use_view(r, v);
		if (r->method && r->method->finish && (v == 0 || !r->method->shared_views))
			r->method->finish(r);
		if (v > 0)
			render_view_destroy(r);
	}
	render_pipeline *pipes[] = {&r->shadow_pipe,	  &r->depth_pipe,      &r->shade_pipe,	    &r->display_pipe,
				    &r->shadow_mask_pipe, &r->depth_mask_pipe, &r->shade_blend_pipe};
	for (size_t i = 0; i < sizeof pipes / sizeof pipes[0]; i++)
		render_pipeline_destroy(r, pipes[i]);
	if (r->fence)
		vkDestroyFence(d, r->fence, NULL);
	if (r->cmd)
		vkFreeCommandBuffers(d, r->dev->cmd_pool, 1, &r->cmd);
	if (r->ts_pool)
		vkDestroyQueryPool(d, r->ts_pool, NULL);
	if (r->stats_pool)
		vkDestroyQueryPool(d, r->stats_pool, NULL);
	if (r->scene_set && getenv("TASLAB_DEBUG_SHADOWS")) /* shadow pool report (README "Renderer decisions") */
		fprintf(stderr, "shadow pool: %llu layer renderings, %llu shared, %u of %u chunks\n",
			(unsigned long long)r->shadow.rendered, (unsigned long long)r->shadow.reused, r->shadow.chunk_count,
			r->shadow.chunks_max);
	if (r->scene_set)
		render_shadow_destroy(r);
	render_targets_destroy(r);
	render_upload_destroy(r);
	colour_device_destroy(r->dev, &r->colour_dev);
	colour_destroy(&r->own_colour);
	free(r->blend_order);
	free(r->world);
	free(r->mirrored);
	free(r->light_states);
	free(r->slot_time);
	free(r);
	*pr = NULL;
}

/* One frame of the active view (mono, one eye of a per-eye method, or every eye of a shared_views method). */
static int frame_view(render *r, uint32_t frame, frame_stats *st, int64_t *visible, char *err, size_t err_size)
{
	int rc = 0;
	VkResult res;
	VkCommandBuffer cmd = r->cmd;
	if (r->method->prepare && (rc = r->method->prepare(r, frame, err, err_size)))
		return rc;
	if ((res = render_cmd_begin(r)))
		return render_vk_error(err, err_size, "command buffer", res);
	if (r->ts_pool)
		vkCmdResetQueryPool(cmd, r->ts_pool, 0, FRAME_MAX_PASSES + 1);
	r->ts_count = 0;
	r->stats_recorded = false;
	if (r->method->record_pre) {
		r->method->record_pre(r, cmd, frame);
		if ((res = render_cmd_submit_wait(r)))
			return render_vk_error(err, err_size, "frame submission (before the CPU step)", res);
		if ((rc = r->method->cpu_step(r, frame, err, err_size)))
			return rc;
		if ((res = render_cmd_begin(r)))
			return render_vk_error(err, err_size, "command buffer", res);
	}
	r->method->record(r, cmd, frame);
	if ((res = render_cmd_submit_wait(r)))
		return render_vk_error(err, err_size, "frame submission", res);

	memset(st, 0, sizeof *st);
	if (r->method->shared_views && r->view_count > 1) {
		for (uint32_t v = 0; v < r->view_count; v++) {
			render_use_view(r, v);
			visible[v] = render_readback_finish(r);
		}
		render_use_view(r, 0);
	} else {
		visible[r->view] = render_readback_finish(r);
	}
	st->visible_samples = visible[r->view];
	st->frame = frame;
	st->time_s = (double)frame / (double)r->desc.fps;
	st->shaded_samples = st->reused_samples = st->visible_units = st->shaded_units = st->new_units = -1;
	st->allocated_samples = st->late_samples = -1;
	st->fs_invocations = st->cs_invocations = -1;
	if (r->stats_pool && r->stats_recorded) {
		uint64_t v[2];
		if (vkGetQueryPoolResults(r->dev->device, r->stats_pool, 0, 1, sizeof v, v, sizeof v,
					  VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) == VK_SUCCESS) {
			st->fs_invocations = (int64_t)v[0];
			st->cs_invocations = (int64_t)v[1];
		}
	}
	st->pass_count = r->method->pass_count;
	uint64_t ts[FRAME_MAX_PASSES + 1] = {0};
	int have_ts = r->ts_pool && r->ts_count == r->method->pass_count + 1 &&
		      vkGetQueryPoolResults(r->dev->device, r->ts_pool, 0, r->ts_count, sizeof ts, ts, sizeof ts[0],
					    VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) == VK_SUCCESS;
	for (uint32_t p = 0; p < st->pass_count; p++) {
		st->pass_names[p] = r->method->pass_names[p];
		st->gpu_ms[p] = have_ts ? vkdev_elapsed_ms(r->dev, ts[p], ts[p + 1]) : -1.0;
	}
	/* The frame's time is the method's work: a pass named "truth" (the --truth diagnostic, which shades the reused
	 * samples to count the late ones; rrc/tarc copy their --decisions maps in the same interval; empty without
	 * either) is left out, so speedups do not change with these diagnostics. Its own time stays in gpu_ms_truth. */
	st->gpu_ms_total = have_ts ? vkdev_elapsed_ms(r->dev, ts[0], ts[st->pass_count]) : -1.0;
	for (uint32_t p = 0; have_ts && p < st->pass_count; p++)
		if (!strcmp(st->pass_names[p], "truth"))
			st->gpu_ms_total -= st->gpu_ms[p];
	for (uint32_t v = 0; v < RENDER_MAX_VIEWS; v++)
		r->view_shaded[v] = -1;
	if (r->method->collect)
		r->method->collect(r, st);
	return TL_OK;
}

static void sum_count(int64_t *a, int64_t b) { *a = *a >= 0 && b >= 0 ? *a + b : -1; }
static void sum_ms(double *a, double b) { *a = *a >= 0.0 && b >= 0.0 ? *a + b : -1.0; }

static void add_extra(frame_stats *st, const char *name, double v)
{
	if (st->extra_count < FRAME_MAX_EXTRA) {
		st->extra_names[st->extra_count] = name;
		st->extra[st->extra_count++] = v;
	}
}

int render_frame(render *r, uint32_t frame, frame_image *img, frame_stats *st, char *err, size_t err_size)
{
	int rc;
	int64_t visible[RENDER_MAX_VIEWS] = {-1, -1}, shaded[RENDER_MAX_VIEWS] = {-1, -1};
	if (r->view_count < 2 || r->method->shared_views) {
		render_use_view(r, 0);
		if ((rc = frame_view(r, frame, st, visible, err, err_size)))
			return rc;
		if (r->view_count > 1) {
			st->visible_samples = 0;
			for (uint32_t v = 0; v < r->view_count; v++) {
				sum_count(&st->visible_samples, visible[v]);
				shaded[v] = r->view_shaded[v];
			}
		}
	} else {
		/* per-eye methods: each eye a frame of its own (the scene state and the shadow maps of the frame are
		 * made once: render_update_state and the shadow pool find the second eye's already done); totals summed */
		frame_stats sv;
		for (uint32_t v = 0; v < r->view_count; v++) {
			render_use_view(r, v);
			rc = frame_view(r, frame, v ? &sv : st, visible, err, err_size);
			render_use_view(r, 0);
			if (rc)
				return rc;
			shaded[v] = (v ? &sv : st)->shaded_samples;
			if (!v)
				continue;
			sum_count(&st->visible_samples, sv.visible_samples);
			sum_count(&st->shaded_samples, sv.shaded_samples);
			sum_count(&st->reused_samples, sv.reused_samples);
			sum_count(&st->allocated_samples, sv.allocated_samples);
			sum_count(&st->late_samples, sv.late_samples);
			sum_count(&st->visible_units, sv.visible_units);
			sum_count(&st->shaded_units, sv.shaded_units);
			sum_count(&st->new_units, sv.new_units);
			sum_count(&st->fs_invocations, sv.fs_invocations);
			sum_count(&st->cs_invocations, sv.cs_invocations);
			sum_ms(&st->gpu_ms_total, sv.gpu_ms_total);
			for (uint32_t p = 0; p < st->pass_count; p++)
				sum_ms(&st->gpu_ms[p], sv.gpu_ms[p]);
			for (uint32_t e = 0; e < st->extra_count && e < sv.extra_count; e++)
				st->extra[e] += sv.extra[e];
		}
	}
	if (r->view_count > 1) {
		add_extra(st, "visible_samples_l", (double)visible[0]);
		add_extra(st, "visible_samples_r", (double)visible[1]);
		add_extra(st, "shaded_samples_l", shaded[0] >= 0 ? (double)shaded[0] : NAN);
		add_extra(st, "shaded_samples_r", shaded[1] >= 0 ? (double)shaded[1] : NAN);
	}
	return render_view_image(r, 0, img);
}

uint32_t render_view_count(const render *r) { return r->view_count; }

int render_view_image(render *r, uint32_t v, frame_image *img)
{
	if (v >= r->view_count)
		return TL_ERR_ARG;
	render_use_view(r, v);
	img->width = r->desc.width;
	img->height = r->desc.height;
	img->hdr_rgba_half = r->hdr_packed;
	img->display_rgba = r->display_packed;
	img->decisions = r->desc.decisions && r->view_count < 2 ? r->method->decisions(r) : NULL;
	img->tile_rates = NULL;
	img->tiles_x = img->tiles_y = 0;
	if (r->desc.rate_images && r->view_count < 2)
		img->tile_rates = r->method->tile_rates(r, &img->tiles_x, &img->tiles_y);
	render_use_view(r, 0);
	return TL_OK;
}
