// gltf.cpp — glTF 2.0 assets into a taslab scene, through tinygltf (Debian's shared libtinygltf).
//
// What is read: triangle primitives (POSITION, NORMAL, TEXCOORD_0, TANGENT, indices), metal-roughness
// materials with all five textures, alphaMode/alphaCutoff/doubleSided, the node hierarchy (TRS or matrix),
// perspective cameras, and node animations (translation / rotation / scale; STEP, LINEAR, CUBICSPLINE).
// Missing normals: area-weighted vertex normals. Missing tangents: per-triangle UV-derivative tangents
// accumulated per vertex and Gram-Schmidt orthonormalised (Lengyel 2001), bitangent sign chosen so that
// cross(N, T) * w points along decreasing v, the glTF convention for normal maps.
// Images are resampled (area average, colour in linear light) to the scene's square texture size.
//
// The file is untrusted (issue 12). Before tinygltf sees it: the size is bounded, the JSON nesting depth is
// bounded (tinygltf recurses once per level) and a GLB container's header and chunks are checked against
// the file. tinygltf reads external files and decodes images only through the callbacks below (regular files
// of bounded size, PNG/JPEG of bounded dimensions, bufferView images inside their buffer). Afterwards every
// index, count, offset and stride the loader uses is checked with overflow-checked arithmetic before
// anything is allocated from it, against the rules of the glTF 2.0 specification (sections cited as §).
// No exception leaves the loader: gltf_append catches them at the C boundary.
// The parts (issue 24.8): this file builds the scene from the model; gltf_files.cpp holds the file sandbox and the
// GLB and image-header checks, gltf_accessors.cpp accessor validation and reading; gltf_internal.h what they share.
#include "gltf_internal.h"
#include "taslab/texture.h"

#include <new>
#include <set>

namespace {

using namespace gltf_in;

int texture_for(loader &L, int gltf_texture, bool srgb, const char *what, int *out)
{
	*out = SCENE_TEX_NONE;
	if (gltf_texture < 0)
		return 0;
	if ((size_t)gltf_texture >= L.m.textures.size())
		return L.fail("%s: texture %d out of range (the file has %zu)", what, gltf_texture, L.m.textures.size());
	int src = L.m.textures[(size_t)gltf_texture].source;
	if (src < 0 || (size_t)src >= L.m.images.size())
		return L.fail("%s: texture %d has no image", what, gltf_texture);
	std::vector<int> &cache = srgb ? L.tex_srgb : L.tex_linear;
	if (cache[(size_t)src] >= 0) {
		*out = cache[(size_t)src];
		return 0;
	}
	const tinygltf::Image &img = L.m.images[(size_t)src];
	std::string name = img.uri.empty() ? std::to_string(src) : img.uri;
	size_t px = (size_t)(img.width > 0 ? img.width : 0) * (size_t)(img.height > 0 ? img.height : 0);
	if (img.width <= 0 || img.height <= 0 || img.bits != 8 || img.component < 1 || img.component > 4 ||
	    img.width > SCENE_MAX_IMAGE_SIDE || img.height > SCENE_MAX_IMAGE_SIDE ||
	    img.image.size() < px * (size_t)img.component) {
		std::string why = L.warnings.substr(0, L.warnings.find('\n'));
		return L.fail("image could not be decoded as 8-bit: %s%s%s", name.c_str(), why.empty() ? "" : ": ", why.c_str());
	}
	scene *s = L.s;
	size_t same = 0;
	for (size_t i = 0; i < s->texture_count; i++)
		same += s->textures[i].srgb == srgb;
	if (same >= SCENE_MAX_TEXTURES)
		return L.fail("more than %d %s textures (the renderer's texture array limit)", SCENE_MAX_TEXTURES,
			      srgb ? "colour" : "linear");
	const size_t bytes = (size_t)s->texture_size * s->texture_size * 4;
	int rc = L.charge(bytes, name.c_str());
	if (rc)
		return rc;
	if (!grow(s->textures, s->texture_count, 1))
		return TL_ERR_NOMEM;
	scene_texture &t = s->textures[s->texture_count];
	std::snprintf(t.name, sizeof t.name, "gltf_image%d%s", src, srgb ? "" : "_linear");
	t.srgb = srgb;
	t.rgba = static_cast<uint8_t *>(std::malloc(bytes));
	if (!t.rgba)
		return TL_ERR_NOMEM;
	tex_resample_area(img.image.data(), img.width, img.height, img.component, s->texture_size, srgb, t.rgba);
	cache[(size_t)src] = (int)s->texture_count;
	*out = (int)s->texture_count++;
	return 0;
}

// A material factor converted to float: finite and inside [lo, hi] (§3.9 and the material schema).
int factor(loader &L, size_t mat, const char *name, double v, double lo, double hi, float *out)
{
	float f = (float)v;
	if (!std::isfinite(f) || v < lo || v > hi)
		return L.fail("material %zu: %s = %g is not a finite number in [%g, %g]", mat, name, v, lo, hi);
	*out = f;
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
		if (pbr.baseColorFactor.size() != 4 || m.emissiveFactor.size() != 3)
			return L.fail("material %zu: baseColorFactor needs 4 and emissiveFactor 3 numbers", i);
		// Every number becomes a float: finite after the conversion (an emissive 1e39 is infinity). Ranges:
		// metallic, roughness, occlusion strength in [0, 1] (the schema and the shading model); colours and
		// the alpha cutoff >= 0 (the schema's upper bound 1 of base colour and emissive is not enforced:
		// exporters write HDR emissive values); the normal scale any finite number.
		static const char *const bc[] = {"baseColorFactor[0]", "baseColorFactor[1]", "baseColorFactor[2]",
						 "baseColorFactor[3]"};
		static const char *const em[] = {"emissiveFactor[0]", "emissiveFactor[1]", "emissiveFactor[2]"};
		const double inf = HUGE_VAL;
		int rc = 0;
		for (int c = 0; c < 4 && !rc; c++)
			rc = factor(L, i, bc[c], pbr.baseColorFactor[c], 0, inf, &d.base_color[c]);
		for (int c = 0; c < 3 && !rc; c++)
			rc = factor(L, i, em[c], m.emissiveFactor[c], 0, inf, &d.emissive[c]);
		if (rc || (rc = factor(L, i, "metallicFactor", pbr.metallicFactor, 0, 1, &d.metallic)) ||
		    (rc = factor(L, i, "roughnessFactor", pbr.roughnessFactor, 0, 1, &d.roughness)) ||
		    (rc = factor(L, i, "normalTexture.scale", m.normalTexture.scale, -inf, inf, &d.normal_scale)) ||
		    (rc = factor(L, i, "occlusionTexture.strength", m.occlusionTexture.strength, 0, 1, &d.occlusion_strength)) ||
		    (rc = factor(L, i, "alphaCutoff", m.alphaCutoff, 0, inf, &d.alpha_cutoff)))
			return rc;
		d.alpha_mode = m.alphaMode == "MASK" ? SCENE_ALPHA_MASK : m.alphaMode == "BLEND" ? SCENE_ALPHA_BLEND : SCENE_ALPHA_OPAQUE;
		d.double_sided = m.doubleSided;
		char what[64];
		std::snprintf(what, sizeof what, "material %zu", i);
		if ((rc = texture_for(L, pbr.baseColorTexture.index, true, what, &d.base_color_tex)) ||
		    (rc = texture_for(L, pbr.metallicRoughnessTexture.index, false, what, &d.metal_rough_tex)) ||
		    (rc = texture_for(L, m.normalTexture.index, false, what, &d.normal_tex)) ||
		    (rc = texture_for(L, m.emissiveTexture.index, true, what, &d.emissive_tex)) ||
		    (rc = texture_for(L, m.occlusionTexture.index, false, what, &d.occlusion_tex)))
			return rc;
		s->material_count++;
	}
	return 0;
}

tlm_vec3 v3(const std::vector<float> &a, size_t i) { return tlm_v3(a[i * 3], a[i * 3 + 1], a[i * 3 + 2]); }

int add_primitive(loader &L, int mesh_index, int prim_index, int *mesh_out)
{
	auto cached = L.prim.find({mesh_index, prim_index});
	if (cached != L.prim.end()) { // another node instancing the same mesh: share the scene mesh
		*mesh_out = cached->second;
		return 0;
	}
	const tinygltf::Primitive &p = L.m.meshes[(size_t)mesh_index].primitives[(size_t)prim_index];
	char what[96];
	std::snprintf(what, sizeof what, "mesh %d primitive %d", mesh_index, prim_index);
	if (p.mode != TINYGLTF_MODE_TRIANGLES && p.mode != -1)
		return L.fail("%s: only triangle primitives are supported (mode %d)", what, p.mode);
	auto pos_it = p.attributes.find("POSITION");
	if (pos_it == p.attributes.end())
		return L.fail("%s: no POSITION attribute", what);
	std::vector<float> pos, nrm, uv, tan;
	std::string aw = std::string(what) + " POSITION";
	int rc = read_floats(L, pos_it->second, aw.c_str(), RULE_VEC3_FLOAT, pos);
	if (rc)
		return rc;
	size_t nv = pos.size() / 3; // >= 1: accessors have at least one element
	// §3.7.2.1: every attribute accessor of a primitive has the same count; types per the attribute table.
	const struct {
		const char *name;
		const accessor_rule *rule;
		std::vector<float> *dst;
	} attrs[] = {{"NORMAL", &RULE_VEC3_FLOAT, &nrm}, {"TEXCOORD_0", &RULE_TEXCOORD, &uv}, {"TANGENT", &RULE_VEC4_FLOAT, &tan}};
	for (const auto &at : attrs) {
		auto it = p.attributes.find(at.name);
		if (it == p.attributes.end())
			continue;
		std::vector<float> *dst = at.dst;
		aw = std::string(what) + " " + at.name;
		if ((rc = read_floats(L, it->second, aw.c_str(), *at.rule, *dst)))
			return rc;
		if (dst->size() / (size_t)at.rule->comps != nv)
			return L.fail("%s: %s has %zu elements, POSITION %zu (glTF 2.0 §3.7.2.1: all attributes have the same count)",
				      what, at.name, dst->size() / (size_t)at.rule->comps, nv);
	}
	std::vector<uint32_t> idx;
	if (p.indices >= 0) {
		aw = std::string(what) + " indices";
		if ((rc = read_indices(L, p.indices, aw.c_str(), idx)))
			return rc;
	} else {
		idx.resize(nv);
		for (size_t i = 0; i < nv; i++)
			idx[i] = (uint32_t)i;
	}
	idx.resize(idx.size() / 3 * 3);
	if (idx.empty())
		return L.fail("%s: no complete triangle (%zu %s)", what, p.indices >= 0 ? L.m.accessors[(size_t)p.indices].count : nv,
			      p.indices >= 0 ? "indices" : "vertices");
	for (size_t i = 0; i < idx.size(); i++) // §3.7.2.1: indices address the attributes
		if (idx[i] >= nv)
			return L.fail("%s: index %zu = %u is not below the vertex count %zu", what, i, idx[i], nv);
	rc = L.charge((uint64_t)nv * sizeof(scene_vertex) + (uint64_t)idx.size() * sizeof(uint32_t), what);
	if (rc)
		return rc;
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
	bool finite = true;
	for (size_t i = 0; i < nv; i++) {
		scene_vertex &v = m.vertices[i];
		tlm_vec3 n = tlm_v3_normalize_or(v3(nrm, i), tlm_v3(0, 1, 0));
		std::memcpy(v.position, &pos[i * 3], 3 * sizeof(float));
		v.normal[0] = n.x, v.normal[1] = n.y, v.normal[2] = n.z;
		std::memcpy(v.uv, &uv[i * 2], 2 * sizeof(float));
		std::memcpy(v.tangent, &tan[i * 4], 4 * sizeof(float));
		for (int k = 0; k < 3; k++)
			finite = finite && std::isfinite(v.normal[k]) && std::isfinite(v.tangent[k]);
		lo = tlm_v3(std::fmin(lo.x, pos[i * 3]), std::fmin(lo.y, pos[i * 3 + 1]), std::fmin(lo.z, pos[i * 3 + 2]));
		hi = tlm_v3(std::fmax(hi.x, pos[i * 3]), std::fmax(hi.y, pos[i * 3 + 1]), std::fmax(hi.z, pos[i * 3 + 2]));
	}
	m.bounds_min = lo;
	m.bounds_max = hi;
	s->mesh_count++; // owned by the scene from here, also on the error below
	if (!finite) // finite positions so large that edge vectors and cross products overflow
		return L.fail("%s: vertex positions too large to compute normals and tangents in float", what);
	*mesh_out = (int)s->mesh_count - 1;
	L.prim[{mesh_index, prim_index}] = *mesh_out;
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

bool trs_finite(const tlm_trs &t)
{
	const float v[] = {t.t.x, t.t.y, t.t.z, t.r.x, t.r.y, t.r.z, t.r.w, t.s.x, t.s.y, t.s.z};
	for (float f : v)
		if (!std::isfinite(f))
			return false;
	return true;
}

// §3.5.3 (transformations): a matrix (column-major, decomposable to TRS) or translation, rotation (a unit
// quaternion) and scale. Sizes, finiteness in float and a non-zero rotation are checked.
int node_trs(loader &L, int index, const tinygltf::Node &n, tlm_trs *out)
{
	tlm_trs t = tlm_trs_identity();
	if ((!n.matrix.empty() && n.matrix.size() != 16) || (!n.translation.empty() && n.translation.size() != 3) ||
	    (!n.rotation.empty() && n.rotation.size() != 4) || (!n.scale.empty() && n.scale.size() != 3))
		return L.fail("node %d: matrix needs 16 numbers, translation 3, rotation 4 and scale 3", index);
	if (n.matrix.size() == 16) {
		const std::vector<double> &m = n.matrix; // column-major
		t.t = tlm_v3((float)m[12], (float)m[13], (float)m[14]);
		tlm_vec3 c0 = tlm_v3((float)m[0], (float)m[1], (float)m[2]), c1 = tlm_v3((float)m[4], (float)m[5], (float)m[6]),
			 c2 = tlm_v3((float)m[8], (float)m[9], (float)m[10]);
		t.s = tlm_v3(tlm_v3_length(c0), tlm_v3_length(c1), tlm_v3_length(c2));
		// A mirroring matrix (negative determinant, §3.7.2.1: clockwise front faces) is a rotation times a scale
		// with one negative factor: put the sign on x, else the lengths above lose it and the quaternion below
		// comes from a reflection, not a rotation.
		if (tlm_v3_dot(c0, tlm_v3_cross(c1, c2)) < 0.0f) {
			t.s.x = -t.s.x;
			c0 = tlm_v3_scale(c0, -1.0f);
		}
		c0 = tlm_v3_scale(c0, 1.0f / std::fmax(std::fabs(t.s.x), 1e-20f));
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
		if (!trs_finite(t)) // non-finite entries, or a skewed matrix that is not a rotation times a scale
			return L.fail("node %d: matrix is not a finite, decomposable TRS transform (glTF 2.0 §3.5.3)", index);
		*out = t;
		return 0;
	}
	if (n.translation.size() == 3)
		t.t = tlm_v3((float)n.translation[0], (float)n.translation[1], (float)n.translation[2]);
	if (n.rotation.size() == 4) {
		tlm_quat q = {(float)n.rotation[0], (float)n.rotation[1], (float)n.rotation[2], (float)n.rotation[3]};
		float len = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
		if (!(len >= 1e-6f) || !std::isfinite(len))
			return L.fail("node %d: rotation [%g, %g, %g, %g] is not a unit quaternion (glTF 2.0 §3.5.3)", index,
				      n.rotation[0], n.rotation[1], n.rotation[2], n.rotation[3]);
		t.r = tlm_quat_normalize(q);
	}
	if (n.scale.size() == 3)
		t.s = tlm_v3((float)n.scale[0], (float)n.scale[1], (float)n.scale[2]);
	if (!trs_finite(t))
		return L.fail("node %d: translation, rotation or scale is not finite in float", index);
	*out = t;
	return 0;
}

int add_node(loader &L, int node, int parent, int first_material, std::vector<int> &node_object, int depth)
{
	if (node < 0 || (size_t)node >= L.m.nodes.size())
		return L.fail("node index %d out of range (the file has %zu)", node, L.m.nodes.size());
	if (depth > 256 || node_object[(size_t)node] >= 0) // §3.5.2: the hierarchy is a set of disjoint trees
		return L.fail("node hierarchy has a cycle or shared node at node %d", node);
	const tinygltf::Node &n = L.m.nodes[(size_t)node];
	std::string name = n.name.empty() ? "node" + std::to_string(node) : n.name;
	tlm_trs trs = {};
	int obj, rc;
	if ((rc = node_trs(L, node, n, &trs)) || (rc = add_object(L.s, name.c_str(), parent, trs, -1, -1, &obj)))
		return rc;
	node_object[(size_t)node] = obj;
	if (n.mesh >= 0) {
		if ((size_t)n.mesh >= L.m.meshes.size())
			return L.fail("node %d: mesh %d out of range (the file has %zu)", node, n.mesh, L.m.meshes.size());
		const tinygltf::Mesh &mesh = L.m.meshes[(size_t)n.mesh];
		for (size_t p = 0; p < mesh.primitives.size(); p++) {
			int mi = -1, child = -1;
			if ((rc = add_primitive(L, n.mesh, (int)p, &mi)))
				return rc;
			int mat = mesh.primitives[p].material;
			if (mat >= (int)L.m.materials.size())
				return L.fail("mesh %d primitive %zu: material %d out of range (the file has %zu)", n.mesh, p, mat,
					      L.m.materials.size());
			mat = first_material + (mat >= 0 ? mat : (int)L.m.materials.size());
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
		std::set<std::pair<int, int>> targets; // (node, path) already animated by this animation
		for (size_t ci = 0; ci < an.channels.size(); ci++) {
			const tinygltf::AnimationChannel &ch = an.channels[ci];
			char what[96];
			std::snprintf(what, sizeof what, "animation %zu channel %zu", ai, ci);
			anim_path path = ch.target_path == "translation" ? ANIM_PATH_TRANSLATION
					 : ch.target_path == "rotation"  ? ANIM_PATH_ROTATION
					 : ch.target_path == "scale"     ? ANIM_PATH_SCALE
									 : ANIM_PATH_INVALID;
			if (ch.sampler < 0 || (size_t)ch.sampler >= an.samplers.size())
				return L.fail("%s: sampler %d out of range (the animation has %zu)", what, ch.sampler, an.samplers.size());
			if (ch.target_node >= (int)node_object.size())
				return L.fail("%s: target node %d out of range (the file has %zu)", what, ch.target_node,
					      node_object.size());
			if (!path || ch.target_node < 0 || node_object[(size_t)ch.target_node] < 0)
				continue; // morph weights, an extension's target, or a node outside the loaded scene
			if (!targets.insert({ch.target_node, (int)path}).second) // §3.11: a target at most once per animation
				return L.fail("%s: node %d %s is already animated by this animation (glTF 2.0 §3.11)", what,
					      ch.target_node, ch.target_path.c_str());
			const tinygltf::AnimationSampler &sm = an.samplers[(size_t)ch.sampler];
			anim_interp interp = anim_interp_from_string(sm.interpolation.c_str());
			if (!interp)
				return L.fail("%s: unknown interpolation %s", what, sm.interpolation.c_str());
			std::vector<float> times, values;
			int rc;
			std::string wi = std::string(what) + " input", wo = std::string(what) + " output";
			if ((rc = read_floats(L, sm.input, wi.c_str(), RULE_SCALAR_FLOAT, times)) ||
			    (rc = read_floats(L, sm.output, wo.c_str(),
					      path == ANIM_PATH_ROTATION ? RULE_ROTATION : RULE_VEC3_FLOAT, values)))
				return rc;
			size_t per = interp == ANIM_INTERP_CUBICSPLINE ? 3 : 1;
			int comps = anim_path_components(path);
			if (values.size() != times.size() * per * comps)
				return L.fail("animation sampler output count does not match its input in animation %zu (%zu keys, "
					      "%zu outputs; glTF 2.0 §3.11)", ai, times.size(), values.size() / (size_t)comps);
			if ((rc = L.charge((times.size() + values.size()) * sizeof(float), what)))
				return rc;
			scene_object &o = s->objects[(size_t)node_object[(size_t)ch.target_node]];
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
				return L.fail("%s: %s", what, why);
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
		if (cam >= (int)L.m.cameras.size())
			return L.fail("node %zu: camera %d out of range (the file has %zu)", ni, cam, L.m.cameras.size());
		if (cam < 0 || node_object[ni] < 0 || L.m.cameras[(size_t)cam].type != "perspective")
			continue;
		const tinygltf::PerspectiveCamera &pc = L.m.cameras[(size_t)cam].perspective;
		// §3.10.2 / camera.perspective schema: yfov > 0 (and below pi for a projection to exist), znear > 0,
		// zfar > znear or absent (tinygltf: 0; an infinite projection, rendered with a far plane at 1000). The schema's
		// limits still allow projections that make no meaningful image (yfov -> pi: everything squeezed into the
		// centre; zfar / znear ~ 1e30: no depth precision), so the bounds of a scene file's camera hold here too:
		// 1 to 179 degrees (scene_parse.c, fov_deg) and at most 1e7 between the far and the near plane (float depth).
		double zfar = pc.zfar > pc.znear ? pc.zfar : 1000.0;
		if (!(pc.yfov > 0 && pc.yfov < TLM_PI) || !(pc.znear > 0 && pc.znear < 1e30) ||
		    !(pc.zfar == 0 || (pc.zfar > pc.znear && pc.zfar < 1e30)))
			return L.fail("camera %d: yfov %g must be in (0, pi), znear %g > 0 and zfar %g > znear (glTF 2.0 §3.10)",
				      cam, pc.yfov, pc.znear, pc.zfar);
		if (!(pc.yfov >= SCENE_FOV_MIN_DEG * TLM_PI / 180.0 && pc.yfov <= SCENE_FOV_MAX_DEG * TLM_PI / 180.0))
			return L.fail("camera %d: yfov %g rad (%.2f degrees) makes no meaningful image: use %g to %g degrees",
				      cam, pc.yfov, pc.yfov * 180.0 / TLM_PI, SCENE_FOV_MIN_DEG, SCENE_FOV_MAX_DEG);
		if (!(zfar / pc.znear <= SCENE_DEPTH_RANGE_MAX))
			return L.fail("camera %d: zfar / znear = %g (znear %g, zfar %g) leaves no depth precision: keep it at "
				      "most %g",
				      cam, zfar / pc.znear, pc.znear, zfar, SCENE_DEPTH_RANGE_MAX);
		const tlm_mat4 &w = world[(size_t)node_object[ni]];
		tlm_vec3 pos = tlm_mat4_mul_point(w, tlm_v3(0, 0, 0)), target = tlm_mat4_mul_point(w, tlm_v3(0, 0, -1));
		tlm_vec3 d = tlm_v3_sub(target, pos);
		if (!std::isfinite(pos.x + pos.y + pos.z + d.x + d.y + d.z) || tlm_v3_length(d) < 1e-12f)
			return L.fail("node %zu: camera %d has a degenerate (zero-scale or non-finite) world transform", ni, cam);
		if (!grow(s->cameras, s->camera_count, 1))
			return TL_ERR_NOMEM;
		scene_camera &c = s->cameras[s->camera_count];
		std::snprintf(c.name, sizeof c.name, "gltf_camera%d", cam);
		c.motion = SCENE_CAMERA_STATIONARY;
		c.fov_deg = (float)(pc.yfov * 180.0 / TLM_PI);
		c.znear = (float)pc.znear;
		c.zfar = (float)(pc.zfar > pc.znear ? pc.zfar : 1000.0);
		c.keys = static_cast<scene_camera_key *>(std::calloc(1, sizeof(scene_camera_key)));
		if (!c.keys)
			return TL_ERR_NOMEM;
		c.keys[0].position = pos;
		c.keys[0].target = target;
		c.key_count = 1;
		s->camera_count++;
	}
	return 0;
}

// Everything after the file is in memory; may throw (std::bad_alloc), caught by gltf_append.
int append(scene *s, const char *path, int parent, int *root_object, char *err, size_t err_size)
{
	auto refuse = [&](const std::string &why) {
		std::snprintf(err, err_size, "%s: %s", path, why.c_str());
		return TL_ERR_INPUT;
	};
	std::vector<unsigned char> file;
	std::string why;
	size_t len = std::strlen(path);
	bool glb_name = len > 4 && !std::strcmp(path + len - 4, ".glb");
	if (!read_regular_file(path, glb_name ? MAX_FILE_BYTES : MAX_JSON_BYTES, file, why))
		return refuse("cannot read glTF: " + why);
	bool glb = file.size() >= 4 && !std::memcmp(file.data(), "glTF", 4); // §4.4.2: the GLB magic
	if (!glb && glb_name)
		return refuse("not a GLB file (no glTF magic)");
	const unsigned char *json = file.data();
	size_t json_len = file.size();
	if (glb) {
		std::string bad = check_glb(file, &json, &json_len);
		if (!bad.empty())
			return refuse(bad);
	}
	if (json_too_deep(json, json_len))
		return refuse("JSON nested deeper than " + std::to_string(SCENE_MAX_JSON_DEPTH) + " levels");

	tinygltf::Model model;
	tinygltf::TinyGLTF gl;
	fs_state fst;
	image_state ist{&model};
	gl.SetFsCallbacks(tinygltf::FsCallbacks{fs_exists, fs_expand, fs_read, fs_write, &fst});
	gl.SetImageLoader(load_image, &ist);
	std::string e, w;
	const char *slash = std::strrchr(path, '/');
	std::string base_dir = slash ? std::string(path, (size_t)(slash - path)) : std::string();
	bool ok = glb ? gl.LoadBinaryFromMemory(&model, &e, &w, file.data(), (unsigned int)file.size(), base_dir)
		      : gl.LoadASCIIFromString(&model, &e, &w, reinterpret_cast<const char *>(json), (unsigned int)json_len,
					       base_dir);
	std::vector<unsigned char>().swap(file);
	if (!ok) {
		while (!e.empty() && (e.back() == ' ' || e.back() == '\n'))
			e.pop_back();
		return refuse("cannot load glTF: " + (e.empty() ? std::string("unknown error") : e));
	}
	loader L{model, s, path, err, err_size, std::vector<int>(model.images.size(), -1),
		 std::vector<int>(model.images.size(), -1), {}, w, 0};
	int first_material, rc, root;
	if ((rc = add_materials(L, &first_material)) || (rc = add_object(s, "gltf_root", parent, tlm_trs_identity(), -1, -1, &root)))
		return rc;
	std::vector<int> node_object(model.nodes.size(), -1);
	if (model.defaultScene >= (int)model.scenes.size() && !model.scenes.empty())
		return L.fail("scene %d out of range (the file has %zu)", model.defaultScene, model.scenes.size());
	int sc = model.defaultScene >= 0 ? model.defaultScene : 0;
	if (sc < (int)model.scenes.size()) {
		for (int n : model.scenes[(size_t)sc].nodes)
			if ((rc = add_node(L, n, root, first_material, node_object, 0)))
				return rc;
	} else { // no scene: every node that is nobody's child is a root
		std::vector<char> child(model.nodes.size(), 0);
		for (const auto &o : model.nodes)
			for (int c : o.children)
				if (c >= 0 && (size_t)c < child.size())
					child[(size_t)c] = 1;
		for (size_t n = 0; n < model.nodes.size(); n++)
			if (!child[n] && node_object[n] < 0 && (rc = add_node(L, (int)n, root, first_material, node_object, 0)))
				return rc;
	}
	if ((rc = add_animations(L, node_object)) || (rc = add_cameras(L, node_object)))
		return rc;
	if (root_object)
		*root_object = root;
	return 0;
}

} // namespace

extern "C" int gltf_append(scene *s, const char *path, int parent, int *root_object, char *err, size_t err_size)
{
	int rc;
	try {
		rc = append(s, path, parent, root_object, err, err_size);
	} catch (const std::bad_alloc &) {
		rc = TL_ERR_NOMEM;
	} catch (const std::exception &x) { // std::length_error and the like from a library: still a bad file
		std::snprintf(err, err_size, "%s: cannot load glTF: %s", path, x.what());
		rc = TL_ERR_INPUT;
	} catch (...) {
		std::snprintf(err, err_size, "%s: cannot load glTF: unexpected exception", path);
		rc = TL_ERR_INTERNAL;
	}
	if (rc == TL_ERR_NOMEM)
		std::snprintf(err, err_size, "%s: out of memory loading glTF", path);
	return rc;
}
