// count.glsl - the reference shading counts its own invocations (issue 24.3): one atomic add per fragment the
// shading pass runs for, so that ref's shaded_samples is measured where the work runs instead of assumed equal to
// the visible samples. Scene set binding 6 (frame/targets.c), cleared by ref's record, read by ref_collect.
// The shaders that include it must declare early fragment tests: a fragment shader with side effects otherwise
// runs before the depth test (Vulkan spec, "Early Fragment Tests"), and every fragment of every overdrawn
// surface would count. BLEND surfaces are not counted (TAS-METHODS section 0: excluded from all counters).
layout(std430, set = 0, binding = 6) buffer ShadeCount { uint shaded; } shade_count;
layout(early_fragment_tests) in;

void count_shading() { atomicAdd(shade_count.shaded, 1u); }
