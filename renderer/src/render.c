/* render.c — the public frame pipeline (render.h): creates a render for a method of the registry with the
 * shared passes, renders frames and collects their statistics. The composition root of the renderer: the
 * only file that knows the frame core, the passes and the method interface together. */
#include "frame/render_internal.h"
#include "passes/passes.h"

#include <stdio.h>
#include <stdlib.h>
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
	r->world = calloc(r->scene->object_count, sizeof *r->world);
	r->light_states = calloc(r->scene->light_count + 1, sizeof *r->light_states);
	if (!r->world || !r->light_states) {
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
	if (m->init && (rc = m->init(r, err, err_size)))
		goto fail;
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
	if (r->method && r->method->finish)
		r->method->finish(r);
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
	free(r->light_states);
	free(r);
	*pr = NULL;
}

int render_frame(render *r, uint32_t frame, frame_image *img, frame_stats *st, char *err, size_t err_size)
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
	st->visible_samples = render_readback_finish(r);
	img->width = r->desc.width;
	img->height = r->desc.height;
	img->hdr_rgba_half = r->hdr_packed;
	img->display_rgba = r->display_packed;
	img->decisions = r->desc.decisions ? r->method->decisions(r) : NULL;
	st->frame = frame;
	st->time_s = (double)frame / (double)r->desc.fps;
	st->shaded_samples = st->reused_samples = st->visible_units = st->shaded_units = st->new_units = -1;
	st->allocated_samples = st->late_samples = -1;
	st->fs_invocations = st->cs_invocations = -1;
	if (r->stats_pool) {
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
	double period_ms = r->dev->props.limits.timestampPeriod * 1e-6;
	for (uint32_t p = 0; p < st->pass_count; p++) {
		st->pass_names[p] = r->method->pass_names[p];
		st->gpu_ms[p] = have_ts ? (double)(ts[p + 1] - ts[p]) * period_ms : -1.0;
	}
	/* The frame's time is the method's work: a pass named "truth" (the --truth diagnostic, which shades the reused
	 * samples to count the late ones; rrc/tarc copy their --decisions maps in the same interval; empty without
	 * either) is left out, so speedups do not change with these diagnostics. Its own time stays in gpu_ms_truth. */
	st->gpu_ms_total = have_ts ? (double)(ts[st->pass_count] - ts[0]) * period_ms : -1.0;
	for (uint32_t p = 0; have_ts && p < st->pass_count; p++)
		if (!strcmp(st->pass_names[p], "truth"))
			st->gpu_ms_total -= st->gpu_ms[p];
	if (r->method->collect)
		r->method->collect(r, st);
	return TL_OK;
}
