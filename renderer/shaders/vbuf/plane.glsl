// plane.glsl - a triangle's plane on screen from its clip-space (x, y, w): the barycentrics of a point and the
// differences of the compacted sample path's texture gradients (vbuf.glsl's vbuf_bary; the ids pass of the VRS
// methods, common/ids.frag.in, computes castexel's texel density with the same functions). No resources.
#ifndef TASLAB_VBUF_PLANE_GLSL
#define TASLAB_VBUF_PLANE_GLSL

// Barycentrics of the point q (pixels, NDC from `size`) on the plane of the triangle whose clip-space (x, y, w) are
// va, vb, vc, from the 2-D homogeneous edge functions: lambda_i proportional to dot((x, y, 1), e_i), e_i the cross
// product of the other two vertices' (x, y, w). Perspective-correct; outside the triangle the plane is extrapolated.
vec3 vbuf_lambda(vec3 va, vec3 vb, vec3 vc, vec2 q, vec2 size)
{
	vec3 P = vec3(q / size * 2.0 - 1.0, 1.0);
	vec3 f = vec3(dot(P, cross(vb, vc)), dot(P, cross(vc, va)), dot(P, cross(va, vb)));
	return f / (f.x + f.y + f.z);
}

// The barycentrics' differences dwx, dwy of the sample at q of footprint r: between the centres of the coarse
// pixels of its 2x2 coarse quad, in x and y from the quad's first one (as the rasterizer's quad derivatives at this
// rate). VBUF_ANALYTIC_GRADIENTS (TASLAB_VBUF_GRADIENTS=analytic, a diagnostic): the analytic derivatives at q times
// the footprint instead.
void vbuf_plane_diffs(vec3 va, vec3 vb, vec3 vc, vec2 q, vec2 size, uvec2 r, out vec3 dwx, out vec3 dwy)
{
#ifdef VBUF_ANALYTIC_GRADIENTS
	vec3 ea = cross(vb, vc), eb = cross(vc, va), ec = cross(va, vb);
	vec3 P = vec3(q / size * 2.0 - 1.0, 1.0);
	vec3 f = vec3(dot(P, ea), dot(P, eb), dot(P, ec));
	float S = f.x + f.y + f.z;
	vec3 fx = vec3(ea.x, eb.x, ec.x), fy = vec3(ea.y, eb.y, ec.y);
	dwx = (fx * S - f * (fx.x + fx.y + fx.z)) / (S * S) * (2.0 / size.x * float(r.x));
	dwy = (fy * S - f * (fy.x + fy.y + fy.z)) / (S * S) * (2.0 / size.y * float(r.y));
#else
	vec2 rf = vec2(r);
	vec2 cq = floor(q / rf);                  // the coarse pixel
	vec2 c0 = (cq - mod(cq, 2.0) + 0.5) * rf; // centre of its quad's first coarse pixel
	vec3 w0 = vbuf_lambda(va, vb, vc, c0, size);
	dwx = vbuf_lambda(va, vb, vc, c0 + vec2(rf.x, 0.0), size) - w0;
	dwy = vbuf_lambda(va, vb, vc, c0 + vec2(0.0, rf.y), size) - w0;
#endif
}

#endif
