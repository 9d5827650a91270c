/* ts_probe.c — does a pass-boundary timestamp (render_ts) take its value when the command stream reaches it?
 * (frame_debug.h; test_stereo). The situation of the stereo atlas runs' misattributed passes, reduced: a render pass
 * leaves a framebuffer in the rasteriser, a timestamp opens a compute pass that binds none of its attachments, and the
 * compute pass is held open by the host: it raises a flag when it starts and spins until a helper thread, having seen
 * the flag, waits `hold_ms` and releases it. By causality the interval between the two timestamps around the compute
 * pass contains the hold; a timestamp taken late (at llvmpipe's next scene flush, after the compute pass) gives an
 * interval near zero. */
#include "frame_debug.h"
#include "render_internal.h"

#include "../device/shader_compile.h"

#include <pthread.h>
#include <stdatomic.h>
#include <string.h>
#include <stdlib.h>
#include <time.h>

/* llvmpipe ends any loop after 65535 iterations (nested ones together), so one dispatch cannot wait for the host:
 * GATE_DISPATCHES of them in a row (no barrier between: no flush) each spin until the release or that bound; the ones
 * after the release return at once. `saw` (word 3) records that a dispatch saw the release: the pass ended after it. */
enum { GATE_DISPATCHES = 64 };
static const char gate_glsl[] =
	"#version 450\n"
	"layout(local_size_x = 1) in;\n"
	"layout(std430, set = 0, binding = 0) coherent volatile buffer Gate { uint started; uint release; uint spins; uint saw; } g;\n"
	"void main() {\n"
	"  atomicExchange(g.started, 1u);\n"
	"  uint n = 0u;\n"
	"  while (atomicAdd(g.release, 0u) == 0u && n < 65000u) n++;\n"
	"  atomicAdd(g.spins, n);\n"
	"  if (atomicAdd(g.release, 0u) != 0u) atomicExchange(g.saw, 1u);\n"
	"}\n";

typedef struct gate {
	_Atomic uint32_t *words; /* the mapped gate buffer: started, release, spins, saw */
	uint32_t hold_ms;
	double held_ms;          /* from seeing `started` to writing `release` */
	int seen;
} gate;

static double now_ms(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec * 1e3 + (double)t.tv_nsec * 1e-6;
}

static void *gate_thread(void *arg)
{
	gate *g = arg;
	double t0 = now_ms();
	while (!atomic_load(&g->words[0]) && now_ms() - t0 < 10000.0) {
		struct timespec ns = {0, 100000};
		nanosleep(&ns, NULL);
	}
	g->seen = atomic_load(&g->words[0]) != 0;
	double a = now_ms();
	struct timespec hold = {g->hold_ms / 1000, (long)(g->hold_ms % 1000) * 1000000L};
	nanosleep(&hold, NULL);
	g->held_ms = now_ms() - a;
	atomic_store(&g->words[1], 1u);
	return NULL;
}

int render_debug_ts_probe(render *r, uint32_t hold_ms, double *interval_ms, double *held_ms, char *err, size_t err_size)
{
	*interval_ms = *held_ms = -1.0;
	if (!r->ts_pool)
		return tl_error(err, err_size, TL_ERR_UNSUPPORTED, "timestamp probe: the device has no timestamps");
	VkDevice d = r->dev->device;
	vkdev_buffer buf = {0};
	VkDescriptorSetLayout sl = VK_NULL_HANDLE;
	VkDescriptorPool pool = VK_NULL_HANDLE;
	VkPipelineLayout pl = VK_NULL_HANDLE;
	VkPipeline pipe = VK_NULL_HANDLE;
	uint32_t *spv = NULL;
	size_t spv_size = 0;
	int rc = TL_OK;
	VkResult res = vkdev_buffer_create(r->dev, 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true, "ts probe gate", &buf);
	if (res) {
		rc = render_vk_error(err, err_size, "timestamp probe buffer", res);
		goto out;
	}
	memset(buf.mapped, 0, 16);
	if (shc_compile(gate_glsl, SHC_STAGE_COMPUTE, &spv, &spv_size, err, err_size)) {
		rc = TL_ERR_INTERNAL;
		goto out;
	}
	VkDescriptorSetLayoutBinding b = {0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL};
	VkDescriptorSetLayoutCreateInfo li = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
					      .bindingCount = 1, .pBindings = &b};
	VkDescriptorPoolSize ps = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1};
	VkDescriptorPoolCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO, .maxSets = 1,
					 .poolSizeCount = 1, .pPoolSizes = &ps};
	VkDescriptorSet set = VK_NULL_HANDLE;
	if (!(res = vkCreateDescriptorSetLayout(d, &li, NULL, &sl)) && !(res = vkCreateDescriptorPool(d, &pi, NULL, &pool))) {
		VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
						  .descriptorPool = pool, .descriptorSetCount = 1, .pSetLayouts = &sl};
		res = vkAllocateDescriptorSets(d, &ai, &set);
	}
	VkPipelineLayoutCreateInfo pli = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 1,
					  .pSetLayouts = &sl};
	if (!res)
		res = vkCreatePipelineLayout(d, &pli, NULL, &pl);
	if (!res)
		res = render_make_compute(r, spv, spv_size, pl, &pipe);
	if (res) {
		rc = render_vk_error(err, err_size, "timestamp probe pipeline", res);
		goto out;
	}
	VkDescriptorBufferInfo bi = {buf.buffer, 0, VK_WHOLE_SIZE};
	VkWriteDescriptorSet w = {.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = set, .dstBinding = 0,
				  .descriptorCount = 1, .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .pBufferInfo = &bi};
	vkUpdateDescriptorSets(d, 1, &w, 0, NULL);

	/* a render pass (depth cleared): its framebuffer stays in the rasteriser's scene */
	VkCommandBuffer cmd = r->cmd;
	if ((res = render_cmd_begin(r))) {
		rc = render_vk_error(err, err_size, "timestamp probe command buffer", res);
		goto out;
	}
	vkCmdResetQueryPool(cmd, r->ts_pool, 0, FRAME_MAX_PASSES + 1);
	r->ts_count = 0;
	vkdev_barrier_image(cmd, &r->depth, VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
			    VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_NONE, 0,
			    VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
			    VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT);
	VkRenderingAttachmentInfo da = {.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO, .imageView = r->depth.view,
					.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
					.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR, .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
					.clearValue = {.depthStencil = {1.0f, 0}}};
	VkRenderingInfo ri = {.sType = VK_STRUCTURE_TYPE_RENDERING_INFO,
			      .renderArea = {{0, 0}, {r->desc.width, r->desc.height}}, .layerCount = 1,
			      .pDepthAttachment = &da, .pStencilAttachment = &da};
	vkCmdBeginRendering(cmd, &ri);
	vkCmdEndRendering(cmd);
	render_ts(r, cmd);
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe);
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pl, 0, 1, &set, 0, NULL);
	for (int k = 0; k < GATE_DISPATCHES; k++)
		vkCmdDispatch(cmd, 1, 1, 1);
	render_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
		       VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
	render_ts(r, cmd);

	gate g = {.words = buf.mapped, .hold_ms = hold_ms};
	pthread_t th;
	if (pthread_create(&th, NULL, gate_thread, &g)) {
		vkEndCommandBuffer(cmd);
		rc = tl_error(err, err_size, TL_ERR_INTERNAL, "timestamp probe: no thread");
		goto out;
	}
	res = render_cmd_submit_wait(r);
	pthread_join(th, NULL);
	uint64_t ts[2] = {0, 0};
	if (!res)
		res = vkGetQueryPoolResults(d, r->ts_pool, 0, 2, sizeof ts, ts, sizeof ts[0],
					    VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT);
	if (res) {
		rc = render_vk_error(err, err_size, "timestamp probe", res);
		goto out;
	}
	if (!g.seen || !atomic_load(&g.words[3])) {
		rc = tl_error(err, err_size, TL_ERR_INTERNAL, "timestamp probe: the compute pass %s",
			      g.seen ? "ended before the host released it" : "never started");
		goto out;
	}
	*interval_ms = vkdev_elapsed_ms(r->dev, ts[0], ts[1]);
	*held_ms = g.held_ms;
out:
	if (pipe)
		vkDestroyPipeline(d, pipe, NULL);
	if (pl)
		vkDestroyPipelineLayout(d, pl, NULL);
	if (pool)
		vkDestroyDescriptorPool(d, pool, NULL);
	if (sl)
		vkDestroyDescriptorSetLayout(d, sl, NULL);
	vkdev_buffer_destroy(r->dev, &buf);
	free(spv);
	return rc;
}
