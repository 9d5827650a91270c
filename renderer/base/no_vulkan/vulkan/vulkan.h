/* no_vulkan/vulkan/vulkan.h — put first on the include path of the libraries that must not see Vulkan
 * (scenes, output, base, metrics, study; ARCHITECTURE.md "Dependency rules"). Including vulkan.h there,
 * directly or through a renderer header, stops the build here. */
#error "vulkan.h is not allowed in this layer: only renderer/ (device, frame, passes, methods, analysis) and the CLI may use Vulkan"
