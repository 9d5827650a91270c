/* colour_gpu.c — the OpenColorIO view transform on the Vulkan device (colour_gpu.h): its GLSL as the frame's shaders
 * include it, with the view's LUTs in a buffer read through buffer references, and a probe that applies it to pixels.
 *
 * LUTs without descriptors: OCIO's GLSL samples each LUT with texture() on a sampler it declares. Binding those
 * samplers would add a descriptor to every pipeline that shades (display, tfr, the reprojection passes, the atlas
 * shading, the analyses). Instead all LUT values go into one device buffer whose device address is compiled into the
 * GLSL as a constant (the shaders are compiled at run time anyway), the sampler declarations are removed, and each
 * texture(NAME, p) becomes NAME_sample(p): a function that reads the texels with the filtering the sampler would
 * have — clamp to edge, texel centres at (i + 0.5) / n, linear (bi-/trilinear in float, like OCIO's CPU path) or
 * nearest — and returns what texture() returns for the format ((v, 0, 0, 1) for one channel, (r, g, b, 1) for three).
 * Indices are clamped after the float-to-int conversion, so no input (NaN included) reads outside the buffer. */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shader_compile.h"
#include "taslab/colour_gpu.h"
#include "taslab/tl_buf.h"
#include "taslab/vkdev.h"

#define LUT_EXTENSIONS                                                                                                 \
	"#extension GL_EXT_buffer_reference : require\n#extension GL_EXT_buffer_reference_uvec2 : require\n"

struct colour_device {
	vkdev_buffer luts; /* every LUT's values, one after the other (floats) */
	char *glsl;
	const char *extensions;
};

/* NAME_texel(p): the texel at integer position p (in range) as a vec3; NAME_sample(c): texture(NAME, c). */
static void lut_functions(tl_buf *b, const colour_lut *l, uint64_t offset)
{
	static const char *const ivec[4] = {"", "int", "ivec2", "ivec3"}, *const vec[4] = {"", "float", "vec2", "vec3"};
	static const char *const comp[3] = {".x", ".y", ".z"};
	const char *iv = ivec[l->dims], *fv = vec[l->dims], *name = l->sampler;
	/* linear index of texel p */
	tl_buf_printf(b, "vec3 %s_texel(%s p)\n{\n\tuint i = %" PRIu64 "u + %du * uint(", name, iv, offset, l->channels);
	if (l->dims == 1)
		tl_buf_printf(b, "p");
	else if (l->dims == 2)
		tl_buf_printf(b, "p.x + %u * p.y", l->width);
	else
		tl_buf_printf(b, "p.x + %u * (p.y + %u * p.z)", l->width, l->height);
	tl_buf_printf(b, ");\n");
	if (l->channels == 1)
		tl_buf_printf(b, "\treturn vec3(taslab_lut_value(i), 0.0, 0.0);\n}\n");
	else
		tl_buf_printf(b, "\treturn vec3(taslab_lut_value(i), taslab_lut_value(i + 1u), taslab_lut_value(i + 2u));\n}\n");
	const unsigned n[3] = {l->width, l->height, l->depth};
	tl_buf_printf(b, "vec4 %s_sample(%s c)\n{\n\tconst %s n = %s(", name, fv, iv, iv);
	for (int k = 0; k < l->dims; k++)
		tl_buf_printf(b, "%s%u", k ? ", " : "", n[k]);
	tl_buf_printf(b, ");\n");
	if (!l->linear) {
		tl_buf_printf(b, "\t%s a = clamp(%s(floor(c * %s(n))), %s(0), n - 1);\n\treturn vec4(%s_texel(a), 1.0);\n}\n", iv, iv, fv, iv,
		    name);
		return;
	}
	tl_buf_printf(b, "\t%s p = clamp(c * %s(n) - 0.5, %s(0.0), %s(n - 1));\n", fv, fv, fv, fv);
	tl_buf_printf(b, "\t%s a = clamp(%s(p), %s(0), n - 1), e = min(a + 1, n - 1);\n", iv, iv, iv);
	tl_buf_printf(b, "\t%s f = clamp(p - %s(a), 0.0, 1.0);\n", fv, fv);
	if (l->dims == 1) {
		tl_buf_printf(b, "\treturn vec4(mix(%s_texel(a), %s_texel(e), f), 1.0);\n}\n", name, name);
		return;
	}
	/* corners: bit k of j set = take e in component k */
	for (int j = 0; j < (1 << l->dims); j++) {
		tl_buf_printf(b, "\tvec3 t%d = %s_texel(%s(", j, name, iv);
		for (int k = 0; k < l->dims; k++)
			tl_buf_printf(b, "%s%s%s", k ? ", " : "", (j >> k) & 1 ? "e" : "a", comp[k]);
		tl_buf_printf(b, "));\n");
	}
	if (l->dims == 2)
		tl_buf_printf(b, "\treturn vec4(mix(mix(t0, t1, f.x), mix(t2, t3, f.x), f.y), 1.0);\n}\n");
	else
		tl_buf_printf(b, "\treturn vec4(mix(mix(mix(t0, t1, f.x), mix(t2, t3, f.x), f.y), mix(mix(t4, t5, f.x), mix(t6, t7, f.x), "
		       "f.y), f.z), 1.0);\n}\n");
}

/* OCIO's GLSL with the sampler declarations removed and texture(NAME, ...) turned into NAME_sample(...). */
static int rewrite_lookups(const char *src, const colour *c, tl_buf *b, char *err, size_t err_size)
{
	for (const char *p = src; *p;) {
		size_t n = strcspn(p, "\n");
		int skip = 0;
		const char *text = p + strspn(p, " \t"); /* OCIO declares one sampler per line */
		for (size_t i = 0; i < colour_lut_count(c) && !skip; i++) {
			char decl[256];
			const colour_lut *l = colour_lut_get(c, i);
			int m = snprintf(decl, sizeof decl, "uniform sampler%dD %s;", l->dims, l->sampler);
			skip = m > 0 && text < p + n && !strncmp(text, decl, (size_t)m);
		}
		for (const char *q = p; !skip && q < p + n;) {
			size_t i = 0, m = 0;
			for (; i < colour_lut_count(c); i++) {
				char call[256];
				m = (size_t)snprintf(call, sizeof call, "texture(%s,", colour_lut_get(c, i)->sampler);
				if (!strncmp(q, call, m))
					break;
			}
			if (i < colour_lut_count(c)) {
				tl_buf_printf(b, "%s_sample(", colour_lut_get(c, i)->sampler);
				q += m;
			} else { /* up to the next possible call */
				const char *t = q + 1;
				while (t < p + n && *t != 't')
					t++;
				tl_buf_printf(b, "%.*s", (int)(t - q), q);
				q = t;
			}
		}
		if (!skip)
			tl_buf_printf(b, "\n");
		p += n;
		if (*p == '\n')
			p++;
	}
	if (!b->failed && strstr(b->s ? b->s : "", "Sampler"))
		for (size_t i = 0; i < colour_lut_count(c); i++) {
			char call[256];
			snprintf(call, sizeof call, "texture(%s", colour_lut_get(c, i)->sampler);
			if (strstr(b->s, call))
				return tl_error(err, err_size, TL_ERR_UNSUPPORTED,
						"the view's GLSL samples %s in a form taslab does not rewrite", colour_lut_get(c, i)->sampler);
		}
	return b->failed ? tl_error(err, err_size, TL_ERR_NOMEM, "out of memory") : TL_OK;
}

int colour_device_create(vkdev *dev, const colour *c, colour_device **out, char *err, size_t err_size)
{
	*out = NULL;
	colour_device *cd = calloc(1, sizeof *cd);
	if (!cd)
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	cd->extensions = "";
	const size_t nl = colour_lut_count(c);
	if (!nl) {
		cd->glsl = strdup(colour_glsl(c));
		if (!cd->glsl) {
			free(cd);
			return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
		}
		*out = cd;
		return TL_OK;
	}
	if (!dev->has_buffer_device_address) {
		free(cd);
		return tl_error(err, err_size, TL_ERR_UNSUPPORTED,
				"device '%s' has no bufferDeviceAddress, which a view transform with LUTs needs; choose an "
				"analytic view (the built-in ACES one is)", dev->props.deviceName);
	}
	/* one buffer for all LUTs */
	uint64_t total = 0;
	for (size_t i = 0; i < nl; i++) {
		const colour_lut *l = colour_lut_get(c, i);
		total += (uint64_t)l->width * l->height * l->depth * (uint64_t)l->channels;
	}
	float *values = malloc(total * sizeof *values);
	int rc = TL_OK;
	VkResult vr = VK_SUCCESS;
	if (!values)
		rc = tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	uint64_t off = 0;
	tl_buf b = {0};
	tl_buf_printf(&b, "// taslab: the view's LUTs, read from one buffer (renderer/src/device/colour_gpu.c)\n"
		"layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer TaslabLut { float v[]; };\n");
	if (!rc && !(vr = vkdev_buffer_create(dev, total * sizeof(float),
					      VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
					      false, "view transform LUTs", &cd->luts))) {
		VkBufferDeviceAddressInfo ai = {.sType = VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO, .buffer = cd->luts.buffer};
		const uint64_t addr = vkGetBufferDeviceAddress(dev->device, &ai);
		/* (the reference in a variable: glslang 11 crashes or refuses on indexing the constructor's result) */
		tl_buf_printf(&b, "float taslab_lut_value(uint i)\n{\n\tTaslabLut lut = TaslabLut(uvec2(%uu, %uu));\n\treturn lut.v[i];\n}\n",
		    (unsigned)(addr & 0xffffffffu), (unsigned)(addr >> 32));
		for (size_t i = 0; i < nl; i++) {
			const colour_lut *l = colour_lut_get(c, i);
			const uint64_t n = (uint64_t)l->width * l->height * l->depth * (uint64_t)l->channels;
			memcpy(values + off, l->values, n * sizeof(float));
			lut_functions(&b, l, off);
			off += n;
		}
		vr = vkdev_upload_buffer(dev, &cd->luts, values, total * sizeof(float));
	}
	if (!rc && vr)
		rc = tl_error(err, err_size, TL_ERR_VULKAN, "view transform LUTs: Vulkan error %s", vkdev_result_string(vr));
	free(values);
	if (!rc)
		rc = rewrite_lookups(colour_glsl(c), c, &b, err, err_size);
	if (rc) {
		free(b.s);
		colour_device_destroy(dev, &cd);
		return rc;
	}
	cd->glsl = b.s;
	cd->extensions = LUT_EXTENSIONS;
	*out = cd;
	return TL_OK;
}

void colour_device_destroy(vkdev *dev, colour_device **pcd)
{
	if (!pcd || !*pcd)
		return;
	vkdev_buffer_destroy(dev, &(*pcd)->luts);
	free((*pcd)->glsl);
	free(*pcd);
	*pcd = NULL;
}

const char *colour_device_glsl(const colour_device *cd) { return cd->glsl; }
const char *colour_device_extensions(const colour_device *cd) { return cd->extensions; }

static const char *const SRC_HEAD = "#version 460\n";
static const char *const SRC_MAIN =
	"layout(local_size_x = 64) in;\n"
	"layout(std430, set = 0, binding = 0) buffer Pixels { vec4 px[]; };\n"
	"layout(push_constant) uniform P { uint n; } pc;\n"
	"void main() {\n"
	"  uint i = gl_GlobalInvocationID.x;\n"
	"  if (i < pc.n) px[i] = vec4(ocio_display(vec4(px[i].rgb, 1.0)).rgb, px[i].a);\n"
	"}\n";

int colour_apply_gpu(vkdev *dev, const colour *c, float *rgba, size_t n, char *err, size_t err_size)
{
	VkResult vr;
	colour_device *cd = NULL;
	int rc = colour_device_create(dev, c, &cd, err, err_size);
	if (rc)
		return rc;
	rc = TL_ERR_INTERNAL; /* until a step says otherwise: our own shader that does not compile is a bug */
	const char *fn = colour_device_glsl(cd), *ext = colour_device_extensions(cd);
	size_t len = strlen(SRC_HEAD) + strlen(ext) + strlen(fn) + strlen(SRC_MAIN) + 1;
	char *src = malloc(len);
	uint32_t *spv = NULL;
	size_t spv_size = 0;
	vkdev_buffer buf = {0};
	VkShaderModule mod = VK_NULL_HANDLE;
	VkDescriptorSetLayout dsl = VK_NULL_HANDLE;
	VkPipelineLayout pl = VK_NULL_HANDLE;
	VkPipeline pipe = VK_NULL_HANDLE;
	VkDescriptorPool pool = VK_NULL_HANDLE;
	if (!src || n == 0 || n > (1u << 26)) {
		snprintf(err, err_size, n ? "out of memory" : "no pixels");
		rc = n ? TL_ERR_NOMEM : TL_ERR_ARG;
		goto done;
	}
	snprintf(src, len, "%s%s%s%s", SRC_HEAD, ext, fn, SRC_MAIN);
	if (shc_compile(src, SHC_STAGE_COMPUTE, &spv, &spv_size, err, err_size))
		goto done;
	VkDevice d = dev->device;
	VkDescriptorSetLayoutBinding b = {0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, NULL};
	VkDescriptorSetLayoutCreateInfo dli = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
					       .bindingCount = 1, .pBindings = &b};
	VkPushConstantRange pcr = {VK_SHADER_STAGE_COMPUTE_BIT, 0, 4};
	VkDescriptorPoolSize ps = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1};
	VkDescriptorPoolCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO, .maxSets = 1,
					 .poolSizeCount = 1, .pPoolSizes = &ps};
	if ((vr = vkdev_buffer_create(dev, n * 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true, "colour probe", &buf)) ||
	    (vr = vkdev_shader_module(dev, spv, spv_size, &mod)) ||
	    (vr = vkCreateDescriptorSetLayout(d, &dli, NULL, &dsl)))
		goto vkfail;
	VkPipelineLayoutCreateInfo pli = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO, .setLayoutCount = 1,
					  .pSetLayouts = &dsl, .pushConstantRangeCount = 1, .pPushConstantRanges = &pcr};
	if ((vr = vkCreatePipelineLayout(d, &pli, NULL, &pl)))
		goto vkfail;
	VkComputePipelineCreateInfo ci = {
		.sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
		.stage = {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_COMPUTE_BIT,
			  .module = mod, .pName = "main"},
		.layout = pl,
	};
	if ((vr = vkCreateComputePipelines(d, VK_NULL_HANDLE, 1, &ci, NULL, &pipe)) ||
	    (vr = vkCreateDescriptorPool(d, &pi, NULL, &pool)))
		goto vkfail;
	VkDescriptorSet set;
	VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO, .descriptorPool = pool,
					  .descriptorSetCount = 1, .pSetLayouts = &dsl};
	if ((vr = vkAllocateDescriptorSets(d, &ai, &set)))
		goto vkfail;
	VkDescriptorBufferInfo bi = {buf.buffer, 0, VK_WHOLE_SIZE};
	VkWriteDescriptorSet w = {.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = set, .dstBinding = 0,
				  .descriptorCount = 1, .descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, .pBufferInfo = &bi};
	vkUpdateDescriptorSets(d, 1, &w, 0, NULL);
	memcpy(buf.mapped, rgba, n * 16);
	VkCommandBuffer cmd;
	if ((vr = vkdev_cmd_begin(dev, &cmd)))
		goto vkfail;
	uint32_t count = (uint32_t)n;
	vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipe);
	vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pl, 0, 1, &set, 0, NULL);
	vkCmdPushConstants(cmd, pl, VK_SHADER_STAGE_COMPUTE_BIT, 0, 4, &count);
	vkCmdDispatch(cmd, (count + 63) / 64, 1, 1);
	VkMemoryBarrier2 mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER_2,
			       .srcStageMask = VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
			       .srcAccessMask = VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
			       .dstStageMask = VK_PIPELINE_STAGE_2_HOST_BIT, .dstAccessMask = VK_ACCESS_2_HOST_READ_BIT};
	VkDependencyInfo di = {.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO, .memoryBarrierCount = 1, .pMemoryBarriers = &mb};
	vkCmdPipelineBarrier2(cmd, &di);
	if ((vr = vkdev_cmd_submit_wait(dev, cmd)))
		goto vkfail;
	memcpy(rgba, buf.mapped, n * 16);
	rc = TL_OK;
	goto done;
vkfail:
	rc = tl_error(err, err_size, TL_ERR_VULKAN, "colour_apply_gpu: Vulkan error %s", vkdev_result_string(vr));
done:
	if (pool)
		vkDestroyDescriptorPool(dev->device, pool, NULL);
	if (pipe)
		vkDestroyPipeline(dev->device, pipe, NULL);
	if (pl)
		vkDestroyPipelineLayout(dev->device, pl, NULL);
	if (dsl)
		vkDestroyDescriptorSetLayout(dev->device, dsl, NULL);
	if (mod)
		vkDestroyShaderModule(dev->device, mod, NULL);
	vkdev_buffer_destroy(dev, &buf);
	colour_device_destroy(dev, &cd);
	free(spv);
	free(src);
	return rc;
}

int colour_check_gpu(vkdev *dev, const colour *c, double *worst, char *err, size_t err_size)
{
	enum { L = COLOUR_CHECK_LEVELS };
	const size_t n = (size_t)L * L * L;
	float lv[L], *in = malloc(n * 16), *cpu = malloc(n * 16), *gpu = malloc(n * 16);
	if (worst)
		*worst = 0;
	if (!in || !cpu || !gpu) {
		free(in), free(cpu), free(gpu);
		return tl_error(err, err_size, TL_ERR_NOMEM, "out of memory");
	}
	lv[0] = 0.0f;
	for (int i = 1; i < L; i++)
		lv[i] = 1e-4f * powf(64.0f / 1e-4f, (float)(i - 1) / (L - 2));
	for (size_t k = 0; k < n; k++) {
		in[k * 4 + 0] = lv[k / (L * L)], in[k * 4 + 1] = lv[k / L % L], in[k * 4 + 2] = lv[k % L], in[k * 4 + 3] = 1.0f;
	}
	memcpy(cpu, in, n * 16);
	memcpy(gpu, in, n * 16);
	colour_apply(c, cpu, n, 4);
	int rc = colour_apply_gpu(dev, c, gpu, n, err, err_size); /* its code, not always TL_ERR_VULKAN */
	double most = 0;
	size_t at = 0;
	for (size_t i = 0; !rc && i < n * 4; i++) {
		if (i % 4 == 3)
			continue;
		/* what reaches the display; a NaN on one side only counts as the whole range */
		double a = isnan(cpu[i]) ? -1 : fmin(fmax(cpu[i], 0.0), 1.0) * 255.0;
		double b = isnan(gpu[i]) ? -1 : fmin(fmax(gpu[i], 0.0), 1.0) * 255.0;
		double d = (a < 0) != (b < 0) ? 255.0 : fabs(a - b);
		if (d > most)
			most = d, at = i / 4;
	}
	if (worst)
		*worst = most;
	if (!rc && most > COLOUR_CHECK_TOLERANCE)
		rc = tl_error(err, err_size, TL_ERR_INPUT,
			      "%s: the GPU and CPU versions of this view transform differ by %.1f code values (linear input %g %g "
			      "%g; at most %.1f allowed), so rendered frames and CPU metrics would disagree; check the config's "
			      "transforms and LUTs",
			      colour_name(c), most, (double)in[at * 4], (double)in[at * 4 + 1], (double)in[at * 4 + 2],
			      COLOUR_CHECK_TOLERANCE);
	free(in), free(cpu), free(gpu);
	return rc;
}
