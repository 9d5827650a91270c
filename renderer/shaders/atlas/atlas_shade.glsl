// atlas_shade.glsl - shading of one atlas texel (TAS-METHODS section 4 "Shading (compute)"): the surface point of
// the texel (corner-aligned layout, atlas.glsl), its texture footprint and its facing, then exactly ref's shading
// (tas/tas.glsl shade_point). Needs common/shading.glsl compiled with TL_EXPLICIT_GRADIENTS, tas/tas.glsl and
// atlas/atlas.glsl before it.
#ifndef TASLAB_ATLAS_SHADE_GLSL
#define TASLAB_ATLAS_SHADE_GLSL

// Shades texel `texel` (row-major) of the block of `pid` with the scene at `slot`. `tc`: the texel in the atlas;
// `inside`: false for the idle lanes of a chunk past the end of a small block.
//  - Texture footprint: in a compute shader texture() samples mip 0 (TAS-METHODS 8.4), so the derivatives of uv
//    per screen pixel are computed: the texel and its +i/+j neighbours (on the same triangle's plane) are
//    projected with the slot's view-projection, d(uv)/d(x, y) = d(uv)/d(i, j) * (d(x, y)/d(i, j))^-1, and passed to
//    textureGrad; behind the eye or degenerate, the texel spacing is the footprint.
//  - Facing (replaces gl_FrontFacing): the triangle's winding seen from the eye, dot(cross(b - a, c - a), eye - p) > 0
//    (the projection flips y, so a counter-clockwise triangle in view space is counter-clockwise in Vulkan's
//    framebuffer coordinates, VK_FRONT_FACE_COUNTER_CLOCKWISE); flipped for a mirrored object (clockwise front
//    faces, glTF 2.0 section 3.7.2.1): shading.glsl winding_front, the CPU's patch facing in atlas.c alike.
vec3 atlas_shade_texel(uint slot, uint pid, uint texel, out ivec2 tc, out bool inside)
{
	uvec4 b = blocks[pid];
	uint lw = b.y & 0xFFu, lh = (b.y >> 8) & 0xFFu;
	uint W = 1u << lw, H = 1u << lh;
	inside = texel < W * H;
	uint i = texel & (W - 1u), j = min(texel >> lw, H - 1u);
	tc = ivec2(uvec2(b.x & 0xFFFFu, b.x >> 16) + uvec2(i, j));
	vec2 inv = 1.0 / vec2(float(W - 1u), float(H - 1u));
	vec2 uv = vec2(float(i), float(j)) * inv;
	uvec4 c = corners[b.z];
	uint object = b.w;
	uvec3 tri;
	vec3 w;
	patch_point(c, uv, tri, w);
	Vertex A = vertex_at(tri.x), B = vertex_at(tri.y), C = vertex_at(tri.z);
	Vertex v = vertex_mix(A, B, C, w);
	// barycentric steps of one texel in i and j, with this side's formula (extrapolated past the edge)
	vec3 dwi, dwj;
	if (c.w == SINGLE || uv.x + uv.y <= 1.0) {
		dwi = vec3(-inv.x, inv.x, 0.0);
		dwj = vec3(-inv.y, 0.0, inv.y);
	} else {
		dwi = vec3(inv.x, -inv.x, 0.0);
		dwj = vec3(inv.y, 0.0, -inv.y);
	}
	GpuObject o = object_at(slot, object);
	mat4 m = states[slot].view_proj * o.world;
	vec3 pi = A.p * dwi.x + B.p * dwi.y + C.p * dwi.z, pj = A.p * dwj.x + B.p * dwj.y + C.p * dwj.z;
	vec2 duv_di = A.uv * dwi.x + B.uv * dwi.y + C.uv * dwi.z, duv_dj = A.uv * dwj.x + B.uv * dwj.y + C.uv * dwj.z;
	vec4 c0 = m * vec4(v.p, 1.0), ci = m * vec4(v.p + pi, 1.0), cj = m * vec4(v.p + pj, 1.0);
	tl_duv_dx = duv_di;
	tl_duv_dy = duv_dj;
	if (c0.w > 1e-6 && ci.w > 1e-6 && cj.w > 1e-6) {
		vec2 half_size = 0.5 * vec2(imageSize(hdr));
		vec2 s0 = c0.xy / c0.w * half_size, si = ci.xy / ci.w * half_size, sj = cj.xy / cj.w * half_size;
		mat2 J = mat2(si - s0, sj - s0); // columns: screen pixels per texel step in i and in j
		float det = determinant(J);
		if (abs(det) > 1e-12) {
			mat2 Ji = inverse(J); // columns: texel steps per screen pixel in x and in y
			tl_duv_dx = duv_di * Ji[0].x + duv_dj * Ji[0].y;
			tl_duv_dy = duv_di * Ji[1].x + duv_dj * Ji[1].y;
		}
	}
	vec3 wa = (o.world * vec4(A.p, 1.0)).xyz, wb = (o.world * vec4(B.p, 1.0)).xyz, wc = (o.world * vec4(C.p, 1.0)).xyz;
	vec3 wp = (o.world * vec4(v.p, 1.0)).xyz;
	bool front = winding_front(o, wa, wb, wc, wp, states[slot].camera_time.xyz);
#ifdef ATLAS_DEBUG_POSITIONS
	return v.p; // diagnostic (TASLAB_ATLAS_DEBUG=positions): the texel's object-space position (test S4)
#endif
	return shade_point(slot, object, v.p, v.n, v.t, v.uv, front);
}

// The chunk of 8 texels this invocation belongs to (workgroups of 64 = 8 chunks, a 2-D grid of workgroups) and
// its texel; false past the end of the list.
bool atlas_work_item(out uint pid, out uint texel)
{
	uint chunk = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 8u + gl_LocalInvocationID.x / 8u;
	pid = 0u;
	texel = 0u;
	if (chunk >= pc.aux[1])
		return false;
	uvec2 wk = work[pc.aux[0] + chunk];
	pid = wk.x;
	texel = wk.y + (gl_LocalInvocationID.x & 7u);
	return true;
}

#endif
