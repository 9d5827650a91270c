/* vkdev.c — headless Vulkan device (see vkdev.h). */
#include "taslab/vkdev.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define VK_FAIL(res, what)                                                                                  \
	do {                                                                                                \
		snprintf(err, err_size, "%s failed: %s", (what), vkdev_result_string(res));                   \
		goto fail;                                                                                  \
	} while (0)

const char *vkdev_result_string(VkResult r)
{
	switch (r) {
	case VK_SUCCESS: return "VK_SUCCESS";
	case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
	case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
	case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
	case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
	case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
	case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
	case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
	case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER";
	case VK_ERROR_FORMAT_NOT_SUPPORTED: return "VK_ERROR_FORMAT_NOT_SUPPORTED";
	case VK_ERROR_MEMORY_MAP_FAILED: return "VK_ERROR_MEMORY_MAP_FAILED";
	default: {
		static _Thread_local char buf[32];
		snprintf(buf, sizeof buf, "VkResult %d", (int)r);
		return buf;
	}
	}
}

static VKAPI_ATTR VkBool32 VKAPI_CALL debug_cb(VkDebugUtilsMessageSeverityFlagBitsEXT sev,
					       VkDebugUtilsMessageTypeFlagsEXT type,
					       const VkDebugUtilsMessengerCallbackDataEXT *data, void *user)
{
	(void)type;
	vkdev *dev = user;
	if (sev & (VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT)) {
		dev->validation_messages++;
		fprintf(stderr, "taslab: vulkan validation: %s\n", data->pMessage ? data->pMessage : "(no message)");
	}
	return VK_FALSE;
}

static const char *device_type_name(VkPhysicalDeviceType t)
{
	switch (t) {
	case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
	case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
	case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
	case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
	default: return "other";
	}
}

static int type_rank(VkPhysicalDeviceType t)
{
	switch (t) {
	case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 4;
	case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 3;
	case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
	case VK_PHYSICAL_DEVICE_TYPE_CPU: return 1;
	default: return 0;
	}
}

static VkResult make_instance(bool validation, bool *has_debug_utils, VkInstance *out)
{
	const char *layers[1] = {"VK_LAYER_KHRONOS_validation"};
	const char *exts[1] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME};
	*has_debug_utils = false;
	uint32_t n = 0;
	vkEnumerateInstanceExtensionProperties(NULL, &n, NULL);
	VkExtensionProperties *props = calloc(n ? n : 1, sizeof *props);
	if (!props)
		return VK_ERROR_OUT_OF_HOST_MEMORY;
	vkEnumerateInstanceExtensionProperties(NULL, &n, props);
	for (uint32_t i = 0; i < n; i++)
		if (!strcmp(props[i].extensionName, VK_EXT_DEBUG_UTILS_EXTENSION_NAME))
			*has_debug_utils = true;
	free(props);
	VkApplicationInfo app = {
		.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO,
		.pApplicationName = "taslab",
		.applicationVersion = 1,
		.pEngineName = "taslab",
		.apiVersion = VK_API_VERSION_1_3,
	};
	VkInstanceCreateInfo ci = {
		.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO,
		.pApplicationInfo = &app,
		.enabledLayerCount = validation ? 1u : 0u,
		.ppEnabledLayerNames = layers,
		.enabledExtensionCount = *has_debug_utils ? 1u : 0u,
		.ppEnabledExtensionNames = exts,
	};
	return vkCreateInstance(&ci, NULL, out);
}

/* The first graphics+compute queue family (the one taslab uses) and its timestamp bits; UINT32_MAX (bits 0) without
 * one. */
static uint32_t queue_family(VkPhysicalDevice pd, uint32_t *timestamp_bits)
{
	uint32_t qn = 0;
	vkGetPhysicalDeviceQueueFamilyProperties(pd, &qn, NULL);
	VkQueueFamilyProperties qp[16];
	if (qn > 16)
		qn = 16;
	vkGetPhysicalDeviceQueueFamilyProperties(pd, &qn, qp);
	*timestamp_bits = 0;
	for (uint32_t i = 0; i < qn; i++)
		if ((qp[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) && (qp[i].queueFlags & VK_QUEUE_COMPUTE_BIT)) {
			*timestamp_bits = qp[i].timestampValidBits;
			return i;
		}
	return UINT32_MAX;
}

double vkdev_ticks_ms(uint64_t begin, uint64_t end, uint32_t valid_bits, float period_ns)
{
	uint64_t mask = valid_bits >= 64 ? UINT64_MAX : (UINT64_C(1) << valid_bits) - 1;
	return (double)((end - begin) & mask) * (double)period_ns * 1e-6;
}

double vkdev_elapsed_ms(const vkdev *dev, uint64_t begin, uint64_t end)
{
	return vkdev_ticks_ms(begin, end, dev->timestamp_valid_bits, dev->props.limits.timestampPeriod);
}

VkResult vkdev_list(char *out, size_t out_size)
{
	VkInstance inst;
	bool du;
	VkResult r = make_instance(false, &du, &inst);
	if (r)
		return r;
	uint32_t n = 0;
	vkEnumeratePhysicalDevices(inst, &n, NULL);
	VkPhysicalDevice pd[16];
	if (n > 16)
		n = 16;
	vkEnumeratePhysicalDevices(inst, &n, pd);
	out[0] = 0;
	for (uint32_t i = 0; i < n; i++) {
		VkPhysicalDeviceProperties p;
		vkGetPhysicalDeviceProperties(pd[i], &p);
		VkPhysicalDeviceSubgroupProperties sg = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
		VkPhysicalDeviceProperties2 p2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, .pNext = &sg};
		vkGetPhysicalDeviceProperties2(pd[i], &p2);
		VkPhysicalDeviceMemoryProperties mp;
		vkGetPhysicalDeviceMemoryProperties(pd[i], &mp);
		VkDeviceSize local = 0;
		for (uint32_t h = 0; h < mp.memoryHeapCount; h++)
			if ((mp.memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) && mp.memoryHeaps[h].size > local)
				local = mp.memoryHeaps[h].size;
		uint32_t ts_bits;
		queue_family(pd[i], &ts_bits);
		size_t len = strlen(out);
		snprintf(out + len, out_size - len,
			 "%u: %s (%s) Vulkan %u.%u, subgroup %u, timestamps %.3g ns x %u bits, %.0f MiB device-local\n", i,
			 p.deviceName, device_type_name(p.deviceType), VK_API_VERSION_MAJOR(p.apiVersion),
			 VK_API_VERSION_MINOR(p.apiVersion), sg.subgroupSize, (double)p.limits.timestampPeriod,
			 ts_bits, (double)local / (1024.0 * 1024.0));
	}
	vkDestroyInstance(inst, NULL);
	return VK_SUCCESS;
}

static bool is_cpu_request(const char *s)
{
	return s && (!strcmp(s, "lavapipe") || !strcmp(s, "llvmpipe") || !strcmp(s, "cpu"));
}

VkResult vkdev_create(const vkdev_desc *desc, vkdev **out, char *err, size_t err_size)
{
	VkResult r;
	*out = NULL;
	vkdev *d = calloc(1, sizeof *d);
	if (!d) {
		snprintf(err, err_size, "out of memory");
		return VK_ERROR_OUT_OF_HOST_MEMORY;
	}
	const char *env = getenv("TASLAB_VALIDATION");
	d->validation = desc->validation || (env && env[0] && strcmp(env, "0"));
	r = make_instance(d->validation, &d->has_debug_utils, &d->instance);
	if (r == VK_ERROR_LAYER_NOT_PRESENT) {
		snprintf(err, err_size, "the Khronos validation layer is not installed (apt-get install vulkan-validationlayers, or run scripts/setup)");
		goto fail_quiet;
	}
	if (r) {
		snprintf(err, err_size, "cannot create a Vulkan instance (%s): is a Vulkan driver installed? "
			 "For the CPU device: apt-get install mesa-vulkan-drivers (scripts/setup does this)",
			 vkdev_result_string(r));
		goto fail_quiet;
	}
	if (d->has_debug_utils) {
		PFN_vkCreateDebugUtilsMessengerEXT create =
			(PFN_vkCreateDebugUtilsMessengerEXT)vkGetInstanceProcAddr(d->instance, "vkCreateDebugUtilsMessengerEXT");
		if (create && d->validation) {
			VkDebugUtilsMessengerCreateInfoEXT mi = {
				.sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT,
				.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
						   VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
				.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
					       VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
					       VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT,
				.pfnUserCallback = debug_cb,
				.pUserData = d,
			};
			if ((r = create(d->instance, &mi, NULL, &d->messenger)))
				VK_FAIL(r, "vkCreateDebugUtilsMessengerEXT");
		}
	}

	uint32_t n = 0;
	vkEnumeratePhysicalDevices(d->instance, &n, NULL);
	if (n == 0) {
		snprintf(err, err_size, "no Vulkan device found: install Mesa's CPU driver (apt-get install mesa-vulkan-drivers, or run scripts/setup)");
		r = VK_ERROR_INITIALIZATION_FAILED;
		goto fail;
	}
	VkPhysicalDevice pd[16];
	if (n > 16)
		n = 16;
	vkEnumeratePhysicalDevices(d->instance, &n, pd);
	int pick = -1;
	const char *want = desc->device && desc->device[0] ? desc->device : NULL;
	for (uint32_t i = 0; i < n; i++) {
		VkPhysicalDeviceProperties p;
		vkGetPhysicalDeviceProperties(pd[i], &p);
		if (!want) {
			if (pick < 0 || type_rank(p.deviceType) > type_rank(d->props.deviceType)) {
				pick = (int)i;
				d->props = p;
			}
		} else if (is_cpu_request(want)) {
			if (pick < 0 && p.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU) {
				pick = (int)i;
				d->props = p;
			}
		} else {
			char *end;
			long idx = strtol(want, &end, 10);
			if ((*end == 0 && idx == (long)i) || (*end != 0 && pick < 0 && strstr(p.deviceName, want))) {
				pick = (int)i;
				d->props = p;
			}
		}
	}
	if (pick < 0) {
		char list[1024];
		vkdev_list(list, sizeof list);
		for (char *c = list; *c; c++)
			if (*c == '\n')
				*c = ';';
		snprintf(err, err_size, "no Vulkan device matches --device '%s' (available: %s)", want, list);
		r = VK_ERROR_INITIALIZATION_FAILED;
		goto fail;
	}
	d->physical = pd[pick];
	vkGetPhysicalDeviceMemoryProperties(d->physical, &d->mem_props);
	VkPhysicalDeviceDriverProperties drv = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
	VkPhysicalDeviceProperties2 p2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, .pNext = &drv};
	vkGetPhysicalDeviceProperties2(d->physical, &p2);
	d->driver_id = drv.driverID;
	VkPhysicalDeviceSubgroupProperties sg = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
	VkPhysicalDeviceProperties2 sp2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, .pNext = &sg};
	vkGetPhysicalDeviceProperties2(d->physical, &sp2);
	d->subgroup_size = sg.subgroupSize;
	/* The compute shaders' workgroups: 16x16 (vbuf rate pass) and 64x1 are the largest; Vulkan guarantees only 128
	 * invocations and 128x128x64 sizes (every desktop driver and lavapipe give 1024). */
	const VkPhysicalDeviceLimits *lim = &d->props.limits;
	if (lim->maxComputeWorkGroupInvocations < 256 || lim->maxComputeWorkGroupSize[0] < 64 ||
	    lim->maxComputeWorkGroupSize[1] < 16) {
		snprintf(err, err_size, "device '%s' allows %u compute invocations per workgroup (%ux%u); taslab needs 256 (64x16): "
			 "choose another --device", d->props.deviceName, lim->maxComputeWorkGroupInvocations,
			 lim->maxComputeWorkGroupSize[0], lim->maxComputeWorkGroupSize[1]);
		r = VK_ERROR_FEATURE_NOT_PRESENT;
		goto fail;
	}
	snprintf(d->driver_info, sizeof d->driver_info, "%s %s", drv.driverName, drv.driverInfo);
	if (VK_API_VERSION_MINOR(d->props.apiVersion) < 3 && VK_API_VERSION_MAJOR(d->props.apiVersion) == 1) {
		snprintf(err, err_size, "device '%s' supports Vulkan %u.%u; taslab needs 1.3", d->props.deviceName,
			 VK_API_VERSION_MAJOR(d->props.apiVersion), VK_API_VERSION_MINOR(d->props.apiVersion));
		r = VK_ERROR_INCOMPATIBLE_DRIVER;
		goto fail;
	}

	d->queue_family = queue_family(d->physical, &d->timestamp_valid_bits);
	d->has_timestamps = d->timestamp_valid_bits > 0 && d->props.limits.timestampComputeAndGraphics;
	if (d->queue_family == UINT32_MAX) {
		snprintf(err, err_size, "device '%s' has no graphics+compute queue", d->props.deviceName);
		r = VK_ERROR_INITIALIZATION_FAILED;
		goto fail;
	}

	VkPhysicalDeviceFeatures have;
	vkGetPhysicalDeviceFeatures(d->physical, &have);
	d->has_pipeline_stats = have.pipelineStatisticsQuery;
	VkPhysicalDeviceVulkan13Features have13 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
	VkPhysicalDeviceVulkan12Features have12 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES,
						   .pNext = &have13};
	VkPhysicalDeviceVulkan11Features have11 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES,
						   .pNext = &have12};
	VkPhysicalDeviceFeatures2 have2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, .pNext = &have11};
	vkGetPhysicalDeviceFeatures2(d->physical, &have2);
	/* VK_KHR_multiview (core in 1.1; the feature is optional there): both eyes of a stereo raster pass in one
	 * render pass (STEREO.md "Vulkan multiview"), used only where the device has it with at least 2 views */
	VkPhysicalDeviceVulkan11Properties p11 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_PROPERTIES};
	VkPhysicalDeviceProperties2 props2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, .pNext = &p11};
	vkGetPhysicalDeviceProperties2(d->physical, &props2);
	d->has_multiview = have11.multiview && p11.maxMultiviewViewCount >= 2;
	if (!have13.dynamicRendering || !have13.synchronization2 || !have13.maintenance4) {
		snprintf(err, err_size, "device '%s' lacks dynamicRendering/synchronization2/maintenance4", d->props.deviceName);
		r = VK_ERROR_FEATURE_NOT_PRESENT;
		goto fail;
	}
	VkPhysicalDeviceVulkan13Features f13 = {
		.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES,
		.dynamicRendering = VK_TRUE,
		.synchronization2 = VK_TRUE,
		.maintenance4 = have13.maintenance4, /* glslang's Vulkan 1.3 target emits LocalSizeId */
	};
	VkPhysicalDeviceVulkan12Features f12 = {
		.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES,
		.pNext = &f13,
		.hostQueryReset = VK_TRUE,
		.scalarBlockLayout = VK_TRUE,
		/* the LUTs of a view transform are read through buffer references (colour_gpu.c) */
		.bufferDeviceAddress = have12.bufferDeviceAddress,
	};
	d->has_buffer_device_address = have12.bufferDeviceAddress;
	VkPhysicalDeviceVulkan11Features f11 = {
		.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES,
		.pNext = &f12,
		.multiview = d->has_multiview,
	};
	VkPhysicalDeviceFeatures2 f2 = {
		.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2,
		.pNext = &f11,
		.features = {
			.pipelineStatisticsQuery = d->has_pipeline_stats,
			.samplerAnisotropy = have.samplerAnisotropy,
			.depthClamp = have.depthClamp,
			.fragmentStoresAndAtomics = have.fragmentStoresAndAtomics,
			.shaderStorageImageWriteWithoutFormat = have.shaderStorageImageWriteWithoutFormat,
			/* rg32ui storage images (display values kept by tarc, tasa and ads: tas/disp.glsl) */
			.shaderStorageImageExtendedFormats = have.shaderStorageImageExtendedFormats,
		},
	};
	float prio = 1.0f;
	VkDeviceQueueCreateInfo qci = {
		.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO,
		.queueFamilyIndex = d->queue_family,
		.queueCount = 1,
		.pQueuePriorities = &prio,
	};
	VkDeviceCreateInfo dci = {
		.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO,
		.pNext = &f2,
		.queueCreateInfoCount = 1,
		.pQueueCreateInfos = &qci,
	};
	if ((r = vkCreateDevice(d->physical, &dci, NULL, &d->device)))
		VK_FAIL(r, "vkCreateDevice");
	vkGetDeviceQueue(d->device, d->queue_family, 0, &d->queue);
	VkCommandPoolCreateInfo pci = {
		.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
		.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT,
		.queueFamilyIndex = d->queue_family,
	};
	if ((r = vkCreateCommandPool(d->device, &pci, NULL, &d->cmd_pool)))
		VK_FAIL(r, "vkCreateCommandPool");
	*out = d;
	return VK_SUCCESS;
fail:
fail_quiet:
	vkdev_destroy(&d);
	return r ? r : VK_ERROR_INITIALIZATION_FAILED;
}

void vkdev_destroy(vkdev **pd)
{
	if (!pd || !*pd)
		return;
	vkdev *d = *pd;
	if (d->device) {
		vkDeviceWaitIdle(d->device);
		if (d->cmd_pool)
			vkDestroyCommandPool(d->device, d->cmd_pool, NULL);
		vkDestroyDevice(d->device, NULL);
	}
	if (d->messenger) {
		PFN_vkDestroyDebugUtilsMessengerEXT destroy =
			(PFN_vkDestroyDebugUtilsMessengerEXT)vkGetInstanceProcAddr(d->instance, "vkDestroyDebugUtilsMessengerEXT");
		if (destroy)
			destroy(d->instance, d->messenger, NULL);
	}
	if (d->instance)
		vkDestroyInstance(d->instance, NULL);
	free(d);
	*pd = NULL;
}

uint32_t vkdev_validation_messages(const vkdev *dev) { return dev->validation_messages; }

bool vkdev_is_lavapipe(const vkdev *dev) { return dev->driver_id == VK_DRIVER_ID_MESA_LLVMPIPE; }

void vkdev_name(vkdev *dev, VkObjectType type, uint64_t handle, const char *name)
{
	if (!dev->has_debug_utils || !name)
		return;
	static PFN_vkSetDebugUtilsObjectNameEXT fn; /* same for every instance of one loader */
	if (!fn)
		fn = (PFN_vkSetDebugUtilsObjectNameEXT)vkGetInstanceProcAddr(dev->instance, "vkSetDebugUtilsObjectNameEXT");
	if (!fn)
		return;
	VkDebugUtilsObjectNameInfoEXT ni = {
		.sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_OBJECT_NAME_INFO_EXT,
		.objectType = type,
		.objectHandle = handle,
		.pObjectName = name,
	};
	fn(dev->device, &ni);
}

static int find_memory(const vkdev *dev, uint32_t bits, VkMemoryPropertyFlags want)
{
	for (uint32_t i = 0; i < dev->mem_props.memoryTypeCount; i++)
		if ((bits & (1u << i)) && (dev->mem_props.memoryTypes[i].propertyFlags & want) == want)
			return (int)i;
	return -1; /* local sentinel: no such memory type (an index; allocate() makes it a VkResult) */
}

static VkResult allocate(vkdev *dev, VkMemoryRequirements req, VkMemoryPropertyFlags want, bool addressable,
			 VkDeviceMemory *mem)
{
	int type = find_memory(dev, req.memoryTypeBits, want);
	if (type < 0)
		return VK_ERROR_OUT_OF_DEVICE_MEMORY;
	VkMemoryAllocateFlagsInfo fi = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO,
					.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT};
	VkMemoryAllocateInfo ai = {
		.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO,
		.pNext = addressable ? &fi : NULL,
		.allocationSize = req.size,
		.memoryTypeIndex = (uint32_t)type,
	};
	return vkAllocateMemory(dev->device, &ai, NULL, mem);
}

VkResult vkdev_buffer_create(vkdev *dev, VkDeviceSize size, VkBufferUsageFlags usage, bool host_visible,
			     const char *name, vkdev_buffer *out)
{
	memset(out, 0, sizeof *out);
	VkBufferCreateInfo bi = {
		.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO,
		.size = size ? size : 4,
		.usage = usage,
		.sharingMode = VK_SHARING_MODE_EXCLUSIVE,
	};
	VkResult r = vkCreateBuffer(dev->device, &bi, NULL, &out->buffer);
	if (r)
		return r;
	VkMemoryRequirements req;
	vkGetBufferMemoryRequirements(dev->device, out->buffer, &req);
	VkMemoryPropertyFlags want = host_visible ? VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
						  : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
	const bool addressable = (usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT) != 0;
	if ((r = allocate(dev, req, want, addressable, &out->memory)) ||
	    (r = vkBindBufferMemory(dev->device, out->buffer, out->memory, 0)))
		goto fail;
	if (host_visible && (r = vkMapMemory(dev->device, out->memory, 0, VK_WHOLE_SIZE, 0, &out->mapped)))
		goto fail;
	out->size = bi.size;
	vkdev_name(dev, VK_OBJECT_TYPE_BUFFER, (uint64_t)out->buffer, name);
	return VK_SUCCESS;
fail:
	vkdev_buffer_destroy(dev, out);
	return r;
}

void vkdev_buffer_destroy(vkdev *dev, vkdev_buffer *b)
{
	if (b->buffer)
		vkDestroyBuffer(dev->device, b->buffer, NULL);
	if (b->memory)
		vkFreeMemory(dev->device, b->memory, NULL);
	memset(b, 0, sizeof *b);
}

VkResult vkdev_image_create(vkdev *dev, uint32_t w, uint32_t h, uint32_t layers, uint32_t mips, VkFormat fmt,
			    VkImageUsageFlags usage, VkImageAspectFlags aspect, bool array_view, const char *name,
			    vkdev_image *out)
{
	memset(out, 0, sizeof *out);
	VkImageCreateInfo ii = {
		.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO,
		.imageType = VK_IMAGE_TYPE_2D,
		.format = fmt,
		.extent = {w, h, 1},
		.mipLevels = mips,
		.arrayLayers = layers,
		.samples = VK_SAMPLE_COUNT_1_BIT,
		.tiling = VK_IMAGE_TILING_OPTIMAL,
		.usage = usage,
		.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED,
	};
	VkResult r = vkCreateImage(dev->device, &ii, NULL, &out->image);
	if (r)
		return r;
	VkMemoryRequirements req;
	vkGetImageMemoryRequirements(dev->device, out->image, &req);
	if ((r = allocate(dev, req, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, false, &out->memory)) ||
	    (r = vkBindImageMemory(dev->device, out->image, out->memory, 0)))
		goto fail;
	VkImageViewCreateInfo vi = {
		.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO,
		.image = out->image,
		.viewType = array_view ? VK_IMAGE_VIEW_TYPE_2D_ARRAY : VK_IMAGE_VIEW_TYPE_2D,
		.format = fmt,
		.subresourceRange = {aspect, 0, mips, 0, layers},
	};
	if ((r = vkCreateImageView(dev->device, &vi, NULL, &out->view)))
		goto fail;
	out->format = fmt;
	out->width = w;
	out->height = h;
	out->layers = layers;
	out->mips = mips;
	vkdev_name(dev, VK_OBJECT_TYPE_IMAGE, (uint64_t)out->image, name);
	return VK_SUCCESS;
fail:
	vkdev_image_destroy(dev, out);
	return r;
}

void vkdev_image_destroy(vkdev *dev, vkdev_image *img)
{
	if (img->view)
		vkDestroyImageView(dev->device, img->view, NULL);
	if (img->image)
		vkDestroyImage(dev->device, img->image, NULL);
	if (img->memory)
		vkFreeMemory(dev->device, img->memory, NULL);
	memset(img, 0, sizeof *img);
}

VkResult vkdev_cmd_begin(vkdev *dev, VkCommandBuffer *cmd)
{
	VkCommandBufferAllocateInfo ai = {
		.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
		.commandPool = dev->cmd_pool,
		.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
		.commandBufferCount = 1,
	};
	VkResult r = vkAllocateCommandBuffers(dev->device, &ai, cmd);
	if (r)
		return r;
	VkCommandBufferBeginInfo bi = {
		.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
		.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT,
	};
	r = vkBeginCommandBuffer(*cmd, &bi);
	if (r)
		vkFreeCommandBuffers(dev->device, dev->cmd_pool, 1, cmd);
	return r;
}

VkResult vkdev_cmd_submit_wait(vkdev *dev, VkCommandBuffer cmd)
{
	VkResult r = vkEndCommandBuffer(cmd);
	VkFence fence = VK_NULL_HANDLE;
	VkFenceCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
	if (!r)
		r = vkCreateFence(dev->device, &fi, NULL, &fence);
	if (!r) {
		VkSubmitInfo si = {
			.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO,
			.commandBufferCount = 1,
			.pCommandBuffers = &cmd,
		};
		r = vkQueueSubmit(dev->queue, 1, &si, fence);
	}
	if (!r)
		r = vkWaitForFences(dev->device, 1, &fence, VK_TRUE, UINT64_MAX);
	if (fence)
		vkDestroyFence(dev->device, fence, NULL);
	vkFreeCommandBuffers(dev->device, dev->cmd_pool, 1, &cmd);
	return r;
}

VkResult vkdev_upload_buffer(vkdev *dev, vkdev_buffer *dst, const void *data, VkDeviceSize size)
{
	vkdev_buffer staging;
	VkResult r = vkdev_buffer_create(dev, size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true, "staging", &staging);
	if (r)
		return r;
	memcpy(staging.mapped, data, size);
	VkCommandBuffer cmd;
	if (!(r = vkdev_cmd_begin(dev, &cmd))) {
		VkBufferCopy region = {0, 0, size};
		vkCmdCopyBuffer(cmd, staging.buffer, dst->buffer, 1, &region);
		r = vkdev_cmd_submit_wait(dev, cmd);
	}
	vkdev_buffer_destroy(dev, &staging);
	return r;
}

void vkdev_write_storage_set(VkDevice d, VkDescriptorSet set, uint32_t n, const vkdev_buffer *const *bufs,
			     const vkdev_image *const *imgs)
{
	VkDescriptorBufferInfo bi[32];
	VkDescriptorImageInfo ii[32];
	VkWriteDescriptorSet w[32];
	n = n < 32 ? n : 32;
	for (uint32_t i = 0; i < n; i++) {
		w[i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET, .dstSet = set, .dstBinding = i,
					      .descriptorCount = 1};
		if (imgs[i]) {
			ii[i] = (VkDescriptorImageInfo){VK_NULL_HANDLE, imgs[i]->view, VK_IMAGE_LAYOUT_GENERAL};
			w[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
			w[i].pImageInfo = &ii[i];
		} else {
			bi[i] = (VkDescriptorBufferInfo){bufs[i]->buffer, 0, VK_WHOLE_SIZE};
			w[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
			w[i].pBufferInfo = &bi[i];
		}
	}
	vkUpdateDescriptorSets(d, n, w, 0, NULL);
}

void vkdev_barrier_image(VkCommandBuffer cmd, const vkdev_image *img, VkImageAspectFlags aspect,
			 VkImageLayout from, VkImageLayout to, VkPipelineStageFlags2 src_stage,
			 VkAccessFlags2 src_access, VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access)
{
	VkImageMemoryBarrier2 b = {
		.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2,
		.srcStageMask = src_stage,
		.srcAccessMask = src_access,
		.dstStageMask = dst_stage,
		.dstAccessMask = dst_access,
		.oldLayout = from,
		.newLayout = to,
		.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
		.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
		.image = img->image,
		.subresourceRange = {aspect, 0, img->mips, 0, img->layers},
	};
	VkDependencyInfo di = {
		.sType = VK_STRUCTURE_TYPE_DEPENDENCY_INFO,
		.imageMemoryBarrierCount = 1,
		.pImageMemoryBarriers = &b,
	};
	vkCmdPipelineBarrier2(cmd, &di);
}

VkResult vkdev_shader_module(vkdev *dev, const uint32_t *code, size_t size_bytes, VkShaderModule *out)
{
	VkShaderModuleCreateInfo ci = {
		.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO,
		.codeSize = size_bytes,
		.pCode = code,
	};
	return vkCreateShaderModule(dev->device, &ci, NULL, out);
}
