// count.glsl - the reference shading counts its own invocations (issue 24.3): one atomic add per fragment (or per
// subgroup, below) the shading pass runs for, so that ref's shaded_samples is measured where the work runs instead
// of assumed equal to the visible samples. Scene set binding 6 (frame/targets.c), cleared by ref's record, read by ref_collect.
// The shaders that include it must declare early fragment tests: a fragment shader with side effects otherwise
// runs before the depth test (Vulkan spec, "Early Fragment Tests"), and every fragment of every overdrawn
// surface would count. BLEND surfaces are not counted (TAS-METHODS section 0: excluded from all counters).
layout(std430, set = 0, binding = 6) buffer ShadeCount { uint shaded; } shade_count;
layout(early_fragment_tests) in;

// With TL_SUBGROUP (ref/shade_sg*.frag: the device has ballot subgroup operations in fragment shaders) the subgroup's
// live invocations are counted together, one atomic by the lowest of them: on lavapipe (subgroups of 8) an atomic
// per fragment cost ~54 ms of ref's ~800 ms shading pass at 960x540 (README, "TARC's overhead"), and rrc/tarc
// count per subgroup too (reproj.glsl COUNT), so the two are compared like for like. Helper invocations may be
// active in subgroup operations but their atomics have no effect: they are left out (TL_NO_HELPERS: llvmpipe
// has none and cannot compile gl_HelperInvocation).
#ifdef TL_SUBGROUP
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
void count_shading()
{
#ifdef TL_NO_HELPERS
	uvec4 live = subgroupBallot(true);
#else
	uvec4 live = subgroupBallot(!gl_HelperInvocation);
#endif
	if (gl_SubgroupInvocationID == subgroupBallotFindLSB(live))
		atomicAdd(shade_count.shaded, subgroupBallotBitCount(live));
}
#else
void count_shading() { atomicAdd(shade_count.shaded, 1u); }
#endif
