// gltf.cpp — glTF 2.0 assets into a taslab scene, through tinygltf (Debian's shared libtinygltf).
//
// What is read: triangle primitives (POSITION, NORMAL, TEXCOORD_0, TANGENT, indices), metal-roughness
// materials with all five textures, alphaMode/alphaCutoff/doubleSided, the node hierarchy (TRS or matrix),
// perspective cameras, and node animations (translation / rotation / scale; STEP, LINEAR, CUBICSPLINE).
// Missing normals: area-weighted vertex normals. Missing tangents: per-triangle UV-derivative tangents
// accumulated per vertex and Gram-Schmidt orthonormalised (Lengyel 2001), bitangent sign chosen so that
// cross(N, T) * w points along decreasing v, the glTF convention for normal maps.
// Images are resampled (area average, colour in linear light) to the scene's square texture size.
#include "gltf.h"
#include "taslab/texture.h"

#include <tiny_gltf.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

struct loader {
	const tinygltf::Model &m;
	scene *s;
	const char *path;
	char *err;
	size_t err_size;
	std::vector<int> tex_srgb, tex_linear; // glTF image -> scene texture, per colour space (-1: not yet)

	int fail(const char *fmt, const std::string &what)
	{
		std::snprintf(err, err_size, "%s: %s", path, (std::string(fmt) + what).c_str());
		return TL_ERR_INPUT;
	}
};

template <typename T> bool grow(T *&arr, size_t count, size_t extra)
{
	void *p = std::realloc(arr, (count + extra + 1) * sizeof(T));
	if (!p)
		return false;
	arr = static_cast<T *>(p);
	std::memset(static_cast<void *>(arr + count), 0, (extra + 1) * sizeof(T));
	return true;
}

float normalized(const unsigned char *p, int ctype)
{
	switch (ctype) {
	case TINYGLTF_COMPONENT_TYPE_FLOAT: { float f; std::memcpy(&f, p, 4); return f; }
	case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return *p / 255.0f;
	case TINYGLTF_COMPONENT_TYPE_BYTE: return std::fmax(*(const int8_t *)p / 127.0f, -1.0f);
	case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t v; std::memcpy(&v, p, 2); return v / 65535.0f; }
	case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t v; std::memcpy(&v, p, 2); return std::fmax(v / 32767.0f, -1.0f); }
	default: return 0.0f;
	}
}

// Reads accessor `index` as `comps` floats per element (normalised integers converted per the spec).
int read_floats(loader &L, int index, int comps, std::vector<float> &out)
{
	if (index < 0 || index >= (int)L.m.accessors.size())
		return L.fail("accessor index out of range: ", std::to_string(index));
	const tinygltf::Accessor &a = L.m.accessors[index];
	if (a.sparse.isSparse)
		return L.fail("sparse accessors are not supported: accessor ", std::to_string(index));
	int have = tinygltf::GetNumComponentsInType(a.type);
	int csize = tinygltf::GetComponentSizeInBytes(a.componentType);
	if (have != comps || csize <= 0)
		return L.fail("unexpected accessor type for accessor ", std::to_string(index));
	out.assign(a.count * (size_t)comps, 0.0f);
	if (a.bufferView < 0)
		return 0; // all zeros, as the spec says
	const tinygltf::BufferView &bv = L.m.bufferViews[a.bufferView];
	const tinygltf::Buffer &b = L.m.buffers[bv.buffer];
	int stride = a.ByteStride(bv);
	size_t start = bv.byteOffset + a.byteOffset;
	if (stride <= 0 || (a.count && start + (a.count - 1) * (size_t)stride + (size_t)(comps * csize) > b.data.size()))
		return L.fail("accessor reads past the end of its buffer: accessor ", std::to_string(index));
	for (size_t i = 0; i < a.count; i++)
		for (int c = 0; c < comps; c++)
			out[i * comps + c] = normalized(&b.data[start + i * stride + c * csize], a.componentType);
	return 0;
}

int read_indices(loader &L, int index, std::vector<uint32_t> &out)
{
	const tinygltf::Accessor &a = L.m.accessors[index];
	if (a.sparse.isSparse || a.bufferView < 0)
		return L.fail("unsupported index accessor ", std::to_string(index));
	const tinygltf::BufferView &bv = L.m.bufferViews[a.bufferView];
	const tinygltf::Buffer &b = L.m.buffers[bv.buffer];
	int csize = tinygltf::GetComponentSizeInBytes(a.componentType);
	int stride = a.ByteStride(bv);
	size_t start = bv.byteOffset + a.byteOffset;
	if (csize <= 0 || stride <= 0 || (a.count && start + (a.count - 1) * (size_t)stride + csize > b.data.size()))
		return L.fail("index accessor reads past the end of its buffer: accessor ", std::to_string(index));
	out.resize(a.count);
	for (size_t i = 0; i < a.count; i++) {
		const unsigned char *p = &b.data[start + i * stride];
		uint32_t v = 0;
		if (csize == 1)
			v = *p;
		else if (csize == 2) {
			uint16_t s;
			std::memcpy(&s, p, 2);
			v = s;
		} else
			std::memcpy(&v, p, 4);
		out[i] = v;
	}
	return 0;
}

int texture_for(loader &L, int gltf_texture, bool srgb, int *out)
{
	*out = SCENE_TEX_NONE;
	if (gltf_texture < 0)
		return 0;
	if (gltf_texture >= (int)L.m.textures.size())
		return L.fail("texture index out of range: ", std::to_string(gltf_texture));
	int src = L.m.textures[gltf_texture].source;
	if (src < 0 || src >= (int)L.m.images.size())
		return L.fail("texture without an image: ", std::to_string(gltf_texture));
	std::vector<int> &cache = srgb ? L.tex_srgb : L.tex_linear;
	if (cache[src] >= 0) {
		*out = cache[src];
		return 0;
	}
	const tinygltf::Image &img = L.m.images[src];
	if (img.width <= 0 || img.height <= 0 || img.bits != 8 || img.component < 1 || img.component > 4 ||
	    img.image.size() < (size_t)img.width * (size_t)img.height * (size_t)img.component)
		return L.fail("image could not be decoded as 8-bit: ", img.uri.empty() ? std::to_string(src) : img.uri);
	scene *s = L.s;
	if (!grow(s->textures, s->texture_count, 1))
		return TL_ERR_NOMEM;
	scene_texture &t = s->textures[s->texture_count];
	std::snprintf(t.name, sizeof t.name, "gltf_image%d%s", src, srgb ? "" : "_linear");
	t.srgb = srgb;
	t.rgba = static_cast<uint8_t *>(std::malloc((size_t)s->texture_size * s->texture_size * 4));
	if (!t.rgba)
		return TL_ERR_NOMEM;
	tex_resample_area(img.image.data(), img.width, img.height, img.component, s->texture_size, srgb, t.rgba);
	cache[src] = (int)s->texture_count;
	*out = (int)s->texture_count++;
	return 0;
}

int add_materials(loader &L, int *first)
{
	scene *s = L.s;
	*first = (int)s->material_count;
	size_t n = L.m.materials.size();
	if (!grow(s->materials, s->material_count, n + 1))
		return TL_ERR_NOMEM;
	for (size_t i = 0; i <= n; i++) {
		scene_material &d = s->materials[s->material_count];
		if (i == n) { // glTF default material, for primitives without one
			std::snprintf(d.name, sizeof d.name, "gltf_default");
			d.base_color[0] = d.base_color[1] = d.base_color[2] = d.base_color[3] = 1.0f;
			d.metallic = 1.0f;
			d.roughness = 1.0f;
			d.normal_scale = d.occlusion_strength = 1.0f;
			d.alpha_cutoff = 0.5f;
			d.base_color_tex = d.metal_rough_tex = d.normal_tex = d.emissive_tex = d.occlusion_tex = SCENE_TEX_NONE;
			s->material_count++;
			break;
		}
		const tinygltf::Material &m = L.m.materials[i];
		std::snprintf(d.name, sizeof d.name, "gltf_%zu", i);
		const auto &pbr = m.pbrMetallicRoughness;
		for (int c = 0; c < 4; c++)
			d.base_color[c] = (float)pbr.baseColorFactor[c];
		d.metallic = (float)pbr.metallicFactor;
		d.roughness = (float)pbr.roughnessFactor;
		for (int c = 0; c < 3; c++)
			d.emissive[c] = (float)m.emissiveFactor[c];
		d.normal_scale = (float)m.normalTexture.scale;
		d.occlusion_strength = (float)m.occlusionTexture.strength;
		d.alpha_mode = m.alphaMode == "MASK" ? SCENE_ALPHA_MASK : m.alphaMode == "BLEND" ? SCENE_ALPHA_BLEND : SCENE_ALPHA_OPAQUE;
		d.alpha_cutoff = (float)m.alphaCutoff;
		d.double_sided = m.doubleSided;
		int rc;
		if ((rc = texture_for(L, pbr.baseColorTexture.index, true, &d.base_color_tex)) ||
		    (rc = texture_for(L, pbr.metallicRoughnessTexture.index, false, &d.metal_rough_tex)) ||
		    (rc = texture_for(L, m.normalTexture.index, false, &d.normal_tex)) ||
		    (rc = texture_for(L, m.emissiveTexture.index, true, &d.emissive_tex)) ||
		    (rc = texture_for(L, m.occlusionTexture.index, false, &d.occlusion_tex)))
			return rc;
		s->material_count++;
	}
	return 0;
}

tlm_vec3 v3(const std::vector<float> &a, size_t i) { return tlm_v3(a[i * 3], a[i * 3 + 1], a[i * 3 + 2]); }

int add_primitive(loader &L, const tinygltf::Primitive &p, int *mesh_out)
{
	if (p.mode != TINYGLTF_MODE_TRIANGLES && p.mode != -1)
		return L.fail("only triangle primitives are supported (mode ", std::to_string(p.mode) + ")");
	auto pos_it = p.attributes.find("POSITION");
	if (pos_it == p.attributes.end())
		return L.fail("primitive without POSITION", "");
	std::vector<float> pos, nrm, uv, tan;
	int rc = read_floats(L, pos_it->second, 3, pos);
	if (rc)
		return rc;
	size_t nv = pos.size() / 3;
	auto it = p.attributes.find("NORMAL");
	if (it != p.attributes.end() && (rc = read_floats(L, it->second, 3, nrm)))
		return rc;
	it = p.attributes.find("TEXCOORD_0");
	if (it != p.attributes.end() && (rc = read_floats(L, it->second, 2, uv)))
		return rc;
	it = p.attributes.find("TANGENT");
	if (it != p.attributes.end() && (rc = read_floats(L, it->second, 4, tan)))
		return rc;
	std::vector<uint32_t> idx;
	if (p.indices >= 0) {
		if ((rc = read_indices(L, p.indices, idx)))
			return rc;
	} else {
		idx.resize(nv);
		for (size_t i = 0; i < nv; i++)
			idx[i] = (uint32_t)i;
	}
	idx.resize(idx.size() / 3 * 3);
	for (uint32_t i : idx)
		if (i >= nv)
			return L.fail("index out of range of the vertex attributes in a primitive", "");
	if (uv.size() != nv * 2)
		uv.assign(nv * 2, 0.0f);
	if (nrm.size() != nv * 3) { // area-weighted vertex normals
		nrm.assign(nv * 3, 0.0f);
		for (size_t t = 0; t < idx.size(); t += 3) {
			tlm_vec3 a = v3(pos, idx[t]), b = v3(pos, idx[t + 1]), c = v3(pos, idx[t + 2]);
			tlm_vec3 fn = tlm_v3_cross(tlm_v3_sub(b, a), tlm_v3_sub(c, a));
			for (int k = 0; k < 3; k++)
				for (int d = 0; d < 3; d++)
					nrm[idx[t + k] * 3 + d] += (&fn.x)[d];
		}
	}
	if (tan.size() != nv * 4) { // Lengyel 2001
		std::vector<float> sd(nv * 3, 0.0f), td(nv * 3, 0.0f);
		for (size_t t = 0; t < idx.size(); t += 3) {
			uint32_t i0 = idx[t], i1 = idx[t + 1], i2 = idx[t + 2];
			tlm_vec3 e1 = tlm_v3_sub(v3(pos, i1), v3(pos, i0)), e2 = tlm_v3_sub(v3(pos, i2), v3(pos, i0));
			float du1 = uv[i1 * 2] - uv[i0 * 2], dv1 = uv[i1 * 2 + 1] - uv[i0 * 2 + 1];
			float du2 = uv[i2 * 2] - uv[i0 * 2], dv2 = uv[i2 * 2 + 1] - uv[i0 * 2 + 1];
			float det = du1 * dv2 - du2 * dv1;
			if (std::fabs(det) < 1e-20f)
				continue;
			float r = 1.0f / det;
			tlm_vec3 sdir = tlm_v3_scale(tlm_v3_sub(tlm_v3_scale(e1, dv2), tlm_v3_scale(e2, dv1)), r);
			tlm_vec3 tdir = tlm_v3_scale(tlm_v3_sub(tlm_v3_scale(e2, du1), tlm_v3_scale(e1, du2)), r);
			for (uint32_t i : {i0, i1, i2})
				for (int d = 0; d < 3; d++) {
					sd[i * 3 + d] += (&sdir.x)[d];
					td[i * 3 + d] += (&tdir.x)[d];
				}
		}
		tan.assign(nv * 4, 0.0f);
		for (size_t i = 0; i < nv; i++) {
			tlm_vec3 n = tlm_v3_normalize_or(v3(nrm, i), tlm_v3(0, 1, 0)), sdir = v3(sd, i);
			tlm_vec3 t = tlm_v3_sub(sdir, tlm_v3_scale(n, tlm_v3_dot(n, sdir)));
			if (tlm_v3_length(t) < 1e-12f)
				t = tlm_v3_cross(std::fabs(n.y) < 0.9f ? tlm_v3(0, 1, 0) : tlm_v3(1, 0, 0), n);
			t = tlm_v3_normalize_or(t, tlm_v3(1, 0, 0));
			float w = tlm_v3_dot(tlm_v3_cross(n, t), v3(td, i)) > 0.0f ? -1.0f : 1.0f;
			tan[i * 4] = t.x, tan[i * 4 + 1] = t.y, tan[i * 4 + 2] = t.z, tan[i * 4 + 3] = w;
		}
	}
	scene *s = L.s;
	if (!grow(s->meshes, s->mesh_count, 1))
		return TL_ERR_NOMEM;
	scene_mesh &m = s->meshes[s->mesh_count];
	std::snprintf(m.name, sizeof m.name, "gltf_mesh%zu", s->mesh_count);
	m.vertices = static_cast<scene_vertex *>(std::malloc(nv * sizeof(scene_vertex)));
	m.indices = static_cast<uint32_t *>(std::malloc((idx.size() + 1) * sizeof(uint32_t)));
	if (!m.vertices || !m.indices) {
		std::free(m.vertices);
		std::free(m.indices);
		m.vertices = nullptr;
		m.indices = nullptr;
		return TL_ERR_NOMEM;
	}
	m.vertex_count = (uint32_t)nv;
	m.index_count = (uint32_t)idx.size();
	std::memcpy(m.indices, idx.data(), idx.size() * sizeof(uint32_t));
	tlm_vec3 lo = tlm_v3(1e30f, 1e30f, 1e30f), hi = tlm_v3(-1e30f, -1e30f, -1e30f);
	for (size_t i = 0; i < nv; i++) {
		scene_vertex &v = m.vertices[i];
		tlm_vec3 n = tlm_v3_normalize_or(v3(nrm, i), tlm_v3(0, 1, 0));
		std::memcpy(v.position, &pos[i * 3], 3 * sizeof(float));
		v.normal[0] = n.x, v.normal[1] = n.y, v.normal[2] = n.z;
		std::memcpy(v.uv, &uv[i * 2], 2 * sizeof(float));
		std::memcpy(v.tangent, &tan[i * 4], 4 * sizeof(float));
		lo = tlm_v3(std::fmin(lo.x, pos[i * 3]), std::fmin(lo.y, pos[i * 3 + 1]), std::fmin(lo.z, pos[i * 3 + 2]));
		hi = tlm_v3(std::fmax(hi.x, pos[i * 3]), std::fmax(hi.y, pos[i * 3 + 1]), std::fmax(hi.z, pos[i * 3 + 2]));
	}
	m.bounds_min = lo;
	m.bounds_max = hi;
	*mesh_out = (int)s->mesh_count++;
	return 0;
}

int add_object(scene *s, const char *name, int parent, tlm_trs trs, int mesh, int material, int *out)
{
	if (!grow(s->objects, s->object_count, 1))
		return TL_ERR_NOMEM;
	scene_object &o = s->objects[s->object_count];
	std::snprintf(o.name, sizeof o.name, "%s", name);
	o.parent = parent;
	o.base = trs;
	o.mesh = mesh;
	o.material = material;
	o.casts_shadow = true;
	*out = (int)s->object_count++;
	return 0;
}

tlm_trs node_trs(const tinygltf::Node &n)
{
	tlm_trs t = tlm_trs_identity();
	if (n.matrix.size() == 16) {
		const std::vector<double> &m = n.matrix; // column-major
		t.t = tlm_v3((float)m[12], (float)m[13], (float)m[14]);
		tlm_vec3 c0 = tlm_v3((float)m[0], (float)m[1], (float)m[2]), c1 = tlm_v3((float)m[4], (float)m[5], (float)m[6]),
			 c2 = tlm_v3((float)m[8], (float)m[9], (float)m[10]);
		t.s = tlm_v3(tlm_v3_length(c0), tlm_v3_length(c1), tlm_v3_length(c2));
		c0 = tlm_v3_scale(c0, 1.0f / std::fmax(t.s.x, 1e-20f));
		c1 = tlm_v3_scale(c1, 1.0f / std::fmax(t.s.y, 1e-20f));
		c2 = tlm_v3_scale(c2, 1.0f / std::fmax(t.s.z, 1e-20f));
		float tr = c0.x + c1.y + c2.z; // rotation matrix to quaternion (Shepperd's method)
		tlm_quat q;
		if (tr > 0) {
			float k = 0.5f / std::sqrt(tr + 1.0f);
			q = {(c1.z - c2.y) * k, (c2.x - c0.z) * k, (c0.y - c1.x) * k, 0.25f / k};
		} else if (c0.x > c1.y && c0.x > c2.z) {
			float k = 2.0f * std::sqrt(1.0f + c0.x - c1.y - c2.z);
			q = {0.25f * k, (c1.x + c0.y) / k, (c2.x + c0.z) / k, (c1.z - c2.y) / k};
		} else if (c1.y > c2.z) {
			float k = 2.0f * std::sqrt(1.0f + c1.y - c0.x - c2.z);
			q = {(c1.x + c0.y) / k, 0.25f * k, (c2.y + c1.z) / k, (c2.x - c0.z) / k};
		} else {
			float k = 2.0f * std::sqrt(1.0f + c2.z - c0.x - c1.y);
			q = {(c2.x + c0.z) / k, (c2.y + c1.z) / k, 0.25f * k, (c0.y - c1.x) / k};
		}
		t.r = tlm_quat_normalize(q);
		return t;
	}
	if (n.translation.size() == 3)
		t.t = tlm_v3((float)n.translation[0], (float)n.translation[1], (float)n.translation[2]);
	if (n.rotation.size() == 4)
		t.r = tlm_quat_normalize({(float)n.rotation[0], (float)n.rotation[1], (float)n.rotation[2], (float)n.rotation[3]});
	if (n.scale.size() == 3)
		t.s = tlm_v3((float)n.scale[0], (float)n.scale[1], (float)n.scale[2]);
	return t;
}

int add_node(loader &L, int node, int parent, int first_material, std::vector<int> &node_object, int depth)
{
	if (node < 0 || node >= (int)L.m.nodes.size())
		return L.fail("node index out of range: ", std::to_string(node));
	if (depth > 256 || node_object[node] >= 0)
		return L.fail("node hierarchy has a cycle or shared node at node ", std::to_string(node));
	const tinygltf::Node &n = L.m.nodes[node];
	std::string name = n.name.empty() ? "node" + std::to_string(node) : n.name;
	int obj, rc;
	if ((rc = add_object(L.s, name.c_str(), parent, node_trs(n), -1, -1, &obj)))
		return rc;
	node_object[node] = obj;
	if (n.mesh >= 0) {
		if (n.mesh >= (int)L.m.meshes.size())
			return L.fail("mesh index out of range: ", std::to_string(n.mesh));
		const tinygltf::Mesh &mesh = L.m.meshes[n.mesh];
		for (size_t p = 0; p < mesh.primitives.size(); p++) {
			int mi, child;
			if ((rc = add_primitive(L, mesh.primitives[p], &mi)))
				return rc;
			int mat = mesh.primitives[p].material;
			mat = first_material + (mat >= 0 && mat < (int)L.m.materials.size() ? mat : (int)L.m.materials.size());
			std::string cname = name + "#" + std::to_string(p);
			if ((rc = add_object(L.s, cname.c_str(), obj, tlm_trs_identity(), mi, mat, &child)))
				return rc;
		}
	}
	for (int c : n.children)
		if ((rc = add_node(L, c, obj, first_material, node_object, depth + 1)))
			return rc;
	return 0;
}

int add_animations(loader &L, const std::vector<int> &node_object)
{
	scene *s = L.s;
	for (size_t ai = 0; ai < L.m.animations.size(); ai++) {
		const tinygltf::Animation &an = L.m.animations[ai];
		for (const tinygltf::AnimationChannel &ch : an.channels) {
			anim_path path = ch.target_path == "translation" ? ANIM_PATH_TRANSLATION
					 : ch.target_path == "rotation"  ? ANIM_PATH_ROTATION
					 : ch.target_path == "scale"     ? ANIM_PATH_SCALE
									 : ANIM_PATH_INVALID;
			if (!path || ch.target_node < 0 || ch.target_node >= (int)node_object.size() ||
			    node_object[ch.target_node] < 0 || ch.sampler < 0 || ch.sampler >= (int)an.samplers.size())
				continue; // morph weights, or a node outside the loaded scene
			const tinygltf::AnimationSampler &sm = an.samplers[ch.sampler];
			anim_interp interp = anim_interp_from_string(sm.interpolation.c_str());
			if (!interp)
				return L.fail("unknown interpolation ", sm.interpolation);
			std::vector<float> times, values;
			int comps = anim_path_components(path), rc;
			if ((rc = read_floats(L, sm.input, 1, times)) || (rc = read_floats(L, sm.output, comps, values)))
				return rc;
			size_t per = interp == ANIM_INTERP_CUBICSPLINE ? 3 : 1;
			if (times.empty() || values.size() != times.size() * per * comps)
				return L.fail("animation sampler output count does not match its input in animation ", std::to_string(ai));
			scene_object &o = s->objects[node_object[ch.target_node]];
			if (o.motion_count == 0) {
				o.motions = static_cast<anim_motion *>(std::calloc(1, sizeof(anim_motion)));
				if (!o.motions)
					return TL_ERR_NOMEM;
				o.motion_count = 1;
				o.motions[0].kind = ANIM_MOTION_TRACKS;
			}
			anim_motion &mo = o.motions[0];
			if (!grow(mo.tracks, mo.track_count, 1))
				return TL_ERR_NOMEM;
			anim_track &tr = mo.tracks[mo.track_count++];
			tr.path = path;
			tr.interp = interp;
			tr.key_count = times.size();
			tr.times = static_cast<float *>(std::malloc(times.size() * sizeof(float)));
			tr.values = static_cast<float *>(std::malloc(values.size() * sizeof(float)));
			if (!tr.times || !tr.values)
				return TL_ERR_NOMEM;
			std::memcpy(tr.times, times.data(), times.size() * sizeof(float));
			std::memcpy(tr.values, values.data(), values.size() * sizeof(float));
			char why[200];
			if (anim_track_validate(&tr, why, sizeof why))
				return L.fail("animation: ", why);
		}
	}
	return 0;
}

int add_cameras(loader &L, const std::vector<int> &node_object)
{
	scene *s = L.s;
	std::vector<tlm_mat4> world(s->object_count);
	scene_eval(s, 0.0f, world.data(), nullptr);
	for (size_t ni = 0; ni < L.m.nodes.size(); ni++) {
		int cam = L.m.nodes[ni].camera;
		if (cam < 0 || cam >= (int)L.m.cameras.size() || node_object[ni] < 0 || L.m.cameras[cam].type != "perspective")
			continue;
		const tinygltf::PerspectiveCamera &pc = L.m.cameras[cam].perspective;
		if (!grow(s->cameras, s->camera_count, 1))
			return TL_ERR_NOMEM;
		scene_camera &c = s->cameras[s->camera_count];
		std::snprintf(c.name, sizeof c.name, "gltf_camera%d", cam);
		c.motion = SCENE_CAMERA_STATIONARY;
		c.fov_deg = (float)(pc.yfov * 180.0 / TLM_PI);
		c.znear = (float)(pc.znear > 0 ? pc.znear : 0.05);
		c.zfar = (float)(pc.zfar > pc.znear ? pc.zfar : 1000.0);
		c.keys = static_cast<scene_camera_key *>(std::calloc(1, sizeof(scene_camera_key)));
		if (!c.keys)
			return TL_ERR_NOMEM;
		const tlm_mat4 &w = world[node_object[ni]];
		c.keys[0].position = tlm_mat4_mul_point(w, tlm_v3(0, 0, 0));
		c.keys[0].target = tlm_mat4_mul_point(w, tlm_v3(0, 0, -1));
		c.key_count = 1;
		s->camera_count++;
	}
	return 0;
}

} // namespace

extern "C" int gltf_append(scene *s, const char *path, int parent, int *root_object, char *err, size_t err_size)
{
	tinygltf::Model model;
	tinygltf::TinyGLTF gl;
	std::string e, w;
	size_t len = std::strlen(path);
	bool binary = len > 4 && !std::strcmp(path + len - 4, ".glb");
	bool ok = binary ? gl.LoadBinaryFromFile(&model, &e, &w, path) : gl.LoadASCIIFromFile(&model, &e, &w, path);
	if (!ok) {
		for (char &c : e)
			if (c == '\n')
				c = ' ';
		while (!e.empty() && e.back() == ' ')
			e.pop_back();
		std::snprintf(err, err_size, "%s: cannot load glTF: %s", path, e.empty() ? "unknown error" : e.c_str());
		return TL_ERR_INPUT;
	}
	loader L{model, s, path, err, err_size, std::vector<int>(model.images.size(), -1),
		 std::vector<int>(model.images.size(), -1)};
	int first_material, rc, root;
	if ((rc = add_materials(L, &first_material)))
		goto done;
	if ((rc = add_object(s, "gltf_root", parent, tlm_trs_identity(), -1, -1, &root)))
		goto done;
	{
		std::vector<int> node_object(model.nodes.size(), -1);
		int sc = model.defaultScene >= 0 ? model.defaultScene : 0;
		if (sc < (int)model.scenes.size()) {
			for (int n : model.scenes[sc].nodes)
				if ((rc = add_node(L, n, root, first_material, node_object, 0)))
					goto done;
		} else {
			for (size_t n = 0; n < model.nodes.size(); n++) // no scene: all nodes that are nobody's child
				if (node_object[n] < 0) {
					bool child = false;
					for (const auto &o : model.nodes)
						for (int c : o.children)
							child = child || c == (int)n;
					if (!child && (rc = add_node(L, (int)n, root, first_material, node_object, 0)))
						goto done;
				}
		}
		if ((rc = add_animations(L, node_object)) || (rc = add_cameras(L, node_object)))
			goto done;
	}
	if (root_object)
		*root_object = root;
done:
	if (rc == TL_ERR_NOMEM)
		std::snprintf(err, err_size, "%s: out of memory loading glTF", path);
	return rc;
}
