/* vkdev.h — headless Vulkan device: instance, device choice, queue, memory helpers, validation.
 *
 * Device choice (`vkdev_desc.device`): NULL/"" picks a real GPU when one is present (discrete, then
 * integrated, then virtual), else the CPU device (Mesa lavapipe); "lavapipe" or "cpu" forces the CPU
 * device; a number picks that index of vkEnumeratePhysicalDevices; any other string picks the first
 * device whose name contains it.
 *
 * Validation: with `validation` set, VK_LAYER_KHRONOS_validation is enabled together with a debug
 * messenger that prints every warning/error message to stderr and counts it; tests fail when
 * vkdev_validation_messages() is non-zero. TASLAB_VALIDATION=1 in the environment turns it on too.
 *
 * Errors: functions return VK_SUCCESS or a VkResult error; messages go to the `err` buffer.
 */
#ifndef TASLAB_VKDEV_H
#define TASLAB_VKDEV_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <vulkan/vulkan.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct vkdev_desc {
	const char *device; /* see above */
	bool validation;
} vkdev_desc;

typedef struct vkdev {
	VkInstance instance;
	VkDebugUtilsMessengerEXT messenger;
	VkPhysicalDevice physical;
	VkDevice device;
	VkQueue queue;
	uint32_t queue_family;
	VkCommandPool cmd_pool;
	VkPhysicalDeviceProperties props;
	VkPhysicalDeviceMemoryProperties mem_props;
	VkDriverId driver_id;
	char driver_info[256];
	bool has_pipeline_stats;
	bool has_timestamps;
	uint32_t timestamp_valid_bits; /* of the queue family: 36 on some GPUs, 64 on lavapipe (vkdev_elapsed_ms) */
	uint32_t subgroup_size;        /* 8 on lavapipe, 32 on NVIDIA, 32 or 64 on AMD: shaders must not assume one */
	bool has_buffer_device_address; /* bufferDeviceAddress enabled (LUTs of a view transform) */
	bool has_multiview;             /* the multiview feature enabled, maxMultiviewViewCount >= 2 (stereo raster passes) */
	bool validation;
	bool has_debug_utils;
	uint32_t validation_messages; /* counted by the debug messenger */
} vkdev;

/* A buffer or image with its own dedicated memory (a research renderer has few resources). */
typedef struct vkdev_buffer {
	VkBuffer buffer;
	VkDeviceMemory memory;
	VkDeviceSize size;
	void *mapped; /* host-visible buffers stay mapped */
} vkdev_buffer;

typedef struct vkdev_image {
	VkImage image;
	VkDeviceMemory memory;
	VkImageView view;
	VkFormat format;
	uint32_t width, height, layers, mips;
} vkdev_image;

VkResult vkdev_create(const vkdev_desc *desc, vkdev **out, char *err, size_t err_size);
void vkdev_destroy(vkdev **dev);
uint32_t vkdev_validation_messages(const vkdev *dev);
/* True when the selected device is Mesa's lavapipe (llvmpipe) CPU driver. */
bool vkdev_is_lavapipe(const vkdev *dev);
/* Milliseconds between two timestamps of the device's queue: the difference is taken modulo 2^timestamp_valid_bits
 * (a counter narrower than 64 bits wraps) and scaled by limits.timestampPeriod (ns per tick; 1 on lavapipe). */
double vkdev_elapsed_ms(const vkdev *dev, uint64_t begin, uint64_t end);
/* The same with the two properties given (unit-tested against values lavapipe does not have). */
double vkdev_ticks_ms(uint64_t begin, uint64_t end, uint32_t valid_bits, float period_ns);
/* Lists the physical devices, one line each ("index: name (type) ..." with the properties taslab depends on: Vulkan
 * version, subgroup size, timestamp period and bits, largest device-local heap), into `out`. */
VkResult vkdev_list(char *out, size_t out_size);

/* Attaches a debug name to an object (no-op without VK_EXT_debug_utils). */
void vkdev_name(vkdev *dev, VkObjectType type, uint64_t handle, const char *name);

VkResult vkdev_buffer_create(vkdev *dev, VkDeviceSize size, VkBufferUsageFlags usage, bool host_visible,
			     const char *name, vkdev_buffer *out);
void vkdev_buffer_destroy(vkdev *dev, vkdev_buffer *b);
/* 2D image with a view of all layers/mips: a 2D_ARRAY view when `array_view` (as sampler2DArray
 * needs, even for one layer), else a 2D view. */
VkResult vkdev_image_create(vkdev *dev, uint32_t w, uint32_t h, uint32_t layers, uint32_t mips, VkFormat fmt,
			    VkImageUsageFlags usage, VkImageAspectFlags aspect, bool array_view, const char *name,
			    vkdev_image *out);
void vkdev_image_destroy(vkdev *dev, vkdev_image *img);

/* One-shot command buffer: begin, record, then submit and wait. */
VkResult vkdev_cmd_begin(vkdev *dev, VkCommandBuffer *cmd);
VkResult vkdev_cmd_submit_wait(vkdev *dev, VkCommandBuffer cmd);

/* Uploads `size` bytes into a device-local buffer through a staging buffer. */
VkResult vkdev_upload_buffer(vkdev *dev, vkdev_buffer *dst, const void *data, VkDeviceSize size);

/* Writes bindings 0..n-1 (n <= 32) of a descriptor set of storage images and buffers: binding i is the storage image
 * imgs[i] (GENERAL layout) when it is not NULL, else the whole storage buffer bufs[i]. */
void vkdev_write_storage_set(VkDevice d, VkDescriptorSet set, uint32_t n, const vkdev_buffer *const *bufs,
			     const vkdev_image *const *imgs);

/* Image layout transition over all mips/layers (synchronization2). */
void vkdev_barrier_image(VkCommandBuffer cmd, const vkdev_image *img, VkImageAspectFlags aspect,
			 VkImageLayout from, VkImageLayout to, VkPipelineStageFlags2 src_stage,
			 VkAccessFlags2 src_access, VkPipelineStageFlags2 dst_stage, VkAccessFlags2 dst_access);

VkResult vkdev_shader_module(vkdev *dev, const uint32_t *code, size_t size_bytes, VkShaderModule *out);

const char *vkdev_result_string(VkResult r);

#ifdef __cplusplus
}
#endif
#endif
