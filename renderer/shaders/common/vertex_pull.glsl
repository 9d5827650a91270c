// vertex_pull.glsl - vertices read from the scene's vertex buffer by index (vertex pulling), for the passes that
// draw or shade without vertex input: the ids pass (common/ids.vert.in) and the atlas methods (atlas/atlas.glsl),
// next the compacted sample path (BASELINES.md section 0). The includer declares the buffer first, in its own
// set and binding: `readonly buffer Vertices { float vtx[]; }`, the scene's vertices (scene_vertex, GPU_VERTEX_FLOATS
// floats each: position, normal, uv, tangent; common/gpu_layout.h).
#ifndef TASLAB_VERTEX_PULL_GLSL
#define TASLAB_VERTEX_PULL_GLSL

struct Vertex {
	vec3 p, n;
	vec2 uv;
	vec4 t;
};

Vertex vertex_at(uint i)
{
	uint b = i * GPU_VERTEX_FLOATS;
	Vertex v;
	v.p = vec3(vtx[b], vtx[b + 1u], vtx[b + 2u]);
	v.n = vec3(vtx[b + 3u], vtx[b + 4u], vtx[b + 5u]);
	v.uv = vec2(vtx[b + 6u], vtx[b + 7u]);
	v.t = vec4(vtx[b + 8u], vtx[b + 9u], vtx[b + 10u], vtx[b + 11u]);
	return v;
}

Vertex vertex_mix(Vertex a, Vertex b, Vertex c, vec3 w)
{
	Vertex v;
	v.p = a.p * w.x + b.p * w.y + c.p * w.z;
	v.n = a.n * w.x + b.n * w.y + c.n * w.z;
	v.uv = a.uv * w.x + b.uv * w.y + c.uv * w.z;
	v.t = a.t * w.x + b.t * w.y + c.t * w.z;
	return v;
}

#endif
