// gltf_accessors.cpp — glTF accessors (§3.6.2, sparse §3.6.2.3, alignment §3.6.2.4) checked against their
// buffer views with overflow-checked arithmetic before anything is allocated from them, and read as floats or
// indices. Shared declarations: gltf_internal.h.
#include "gltf_internal.h"

namespace gltf_in {

float normalized(const unsigned char *p, int ctype)
{
	switch (ctype) { // §3.6.2.2 (accessor data types): normalised integers to float
	case TINYGLTF_COMPONENT_TYPE_FLOAT: { float f; std::memcpy(&f, p, 4); return f; }
	case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return *p / 255.0f;
	case TINYGLTF_COMPONENT_TYPE_BYTE: return std::fmax(*(const int8_t *)p / 127.0f, -1.0f);
	case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t v; std::memcpy(&v, p, 2); return v / 65535.0f; }
	case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t v; std::memcpy(&v, p, 2); return std::fmax(v / 32767.0f, -1.0f); }
	default: return 0.0f;
	}
}

uint32_t read_uint(const unsigned char *p, int csize)
{
	if (csize == 1)
		return *p;
	if (csize == 2) {
		uint16_t v;
		std::memcpy(&v, p, 2);
		return v;
	}
	uint32_t v;
	std::memcpy(&v, p, 4);
	return v;
}

const char *ctype_name(int c)
{
	switch (c) {
	case TINYGLTF_COMPONENT_TYPE_BYTE: return "BYTE";
	case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return "UNSIGNED_BYTE";
	case TINYGLTF_COMPONENT_TYPE_SHORT: return "SHORT";
	case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return "UNSIGNED_SHORT";
	case TINYGLTF_COMPONENT_TYPE_INT: return "INT";
	case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return "UNSIGNED_INT";
	case TINYGLTF_COMPONENT_TYPE_FLOAT: return "FLOAT";
	default: return "an unknown component type";
	}
}


// A buffer view and its buffer, checked (§3.6.1: the view lies inside the buffer's loaded bytes).
int buffer_view(loader &L, int bv_index, const char *what, int acc, const tinygltf::BufferView **out,
		const unsigned char **bytes)
{
	if (bv_index < 0 || (size_t)bv_index >= L.m.bufferViews.size())
		return L.fail("%s: accessor %d: bufferView %d out of range (the file has %zu)", what, acc, bv_index,
			      L.m.bufferViews.size());
	const tinygltf::BufferView &bv = L.m.bufferViews[(size_t)bv_index];
	if (bv.buffer < 0 || (size_t)bv.buffer >= L.m.buffers.size())
		return L.fail("%s: bufferView %d: buffer %d out of range (the file has %zu)", what, bv_index, bv.buffer,
			      L.m.buffers.size());
	const std::vector<unsigned char> &b = L.m.buffers[(size_t)bv.buffer].data;
	size_t end;
	if (__builtin_add_overflow(bv.byteOffset, bv.byteLength, &end) || end > b.size())
		return L.fail("%s: bufferView %d (offset %zu, length %zu) lies outside buffer %d (%zu bytes)", what, bv_index,
			      bv.byteOffset, bv.byteLength, bv.buffer, b.size());
	*out = &bv;
	*bytes = b.data() + bv.byteOffset;
	return 0;
}

// Checks accessor `index` for one use (§3.6.2 accessors, §3.6.2.3 sparse, §3.6.2.4 data alignment) without
// allocating anything: every element it describes lies inside its buffer view.
int accessor_check(loader &L, int index, const char *what, const accessor_rule &rule, accessor_view &v)
{
	if (index < 0 || (size_t)index >= L.m.accessors.size())
		return L.fail("%s: accessor %d out of range (the file has %zu)", what, index, L.m.accessors.size());
	const tinygltf::Accessor &a = L.m.accessors[(size_t)index];
	v = accessor_view{};
	v.a = &a;
	static const char *const types[] = {"", "SCALAR", "VEC2", "VEC3", "VEC4"};
	if (a.type != (rule.comps == 1 ? TINYGLTF_TYPE_SCALAR : rule.comps)) // TINYGLTF_TYPE_VECn == n
		return L.fail("%s: accessor %d must be of type %s (glTF 2.0 §3.7.2.1, §3.11)", what, index, types[rule.comps]);
	const int comps = rule.comps;
	int k = 0;
	while (k < rule.n && !(rule.ctypes[k] == a.componentType && rule.norm[k] == a.normalized))
		k++;
	if (k == rule.n)
		return L.fail("%s: accessor %d: component type %s%s is not allowed here (glTF 2.0 §3.7.2.1, §3.11)", what,
			      index, ctype_name(a.componentType), a.normalized ? " (normalized)" : "");
	v.comps = comps;
	v.ctype = a.componentType;
	v.csize = tinygltf::GetComponentSizeInBytes((uint32_t)a.componentType);
	const size_t esize = (size_t)comps * (size_t)v.csize;
	if (a.count < 1 || a.count > UINT32_MAX) // schema: count >= 1; the scene stores 32-bit counts
		return L.fail("%s: accessor %d has %zu elements (1 to %u are supported)", what, index, a.count, UINT32_MAX);
	v.count = a.count;
	if (a.bufferView < 0) { // §3.6.2.1: no buffer view: zeros, which sparse substitution may override
		if (a.count > MAX_ZERO_ELEMENTS)
			return L.fail("%s: accessor %d has %zu elements but no bufferView (at most %zu are supported)", what, index,
				      a.count, MAX_ZERO_ELEMENTS);
	} else {
		const tinygltf::BufferView *bv;
		const unsigned char *bytes;
		int rc = buffer_view(L, a.bufferView, what, index, &bv, &bytes);
		if (rc)
			return rc;
		// §3.6.1 bufferView.byteStride: 4..252, a multiple of 4; §3.6.2.4: at least the element size.
		size_t stride = bv->byteStride ? bv->byteStride : esize;
		if (bv->byteStride && (bv->byteStride < 4 || bv->byteStride > 252 || bv->byteStride % 4 || bv->byteStride < esize))
			return L.fail("%s: accessor %d: bufferView %d has byteStride %zu (a multiple of 4 in 4..252, at least the "
				      "element size %zu; glTF 2.0 §3.6.2.4)", what, index, a.bufferView, bv->byteStride, esize);
		// §3.6.2.4: offsets are multiples of the component size ...
		if (a.byteOffset % (size_t)v.csize || (bv->byteOffset + a.byteOffset) % (size_t)v.csize)
			return L.fail("%s: accessor %d: byteOffset %zu is not aligned to its %d-byte components (glTF 2.0 §3.6.2.4)",
				      what, index, a.byteOffset, v.csize);
		// ... and byteOffset + stride * (count - 1) + element size <= bufferView.byteLength.
		size_t end;
		if (__builtin_mul_overflow(stride, a.count - 1, &end) || __builtin_add_overflow(end, esize, &end) ||
		    __builtin_add_overflow(end, a.byteOffset, &end) || end > bv->byteLength)
			return L.fail("%s: accessor %d (offset %zu, %zu elements, stride %zu) reads past the end of bufferView "
				      "%d (%zu bytes; glTF 2.0 §3.6.2.4)", what, index, a.byteOffset, a.count, stride,
				      a.bufferView, bv->byteLength);
		v.data = bytes + a.byteOffset;
		v.stride = stride;
	}
	if (!a.sparse.isSparse)
		return 0;
	// §3.6.2.3 sparse accessors: 1..count substitutions; indices are unsigned integers, tightly packed, strictly
	// increasing and below count; values tightly packed elements; neither buffer view has a byteStride.
	const auto &sp = a.sparse;
	if (sp.count < 1 || (size_t)sp.count > a.count)
		return L.fail("%s: accessor %d: sparse count %d (1 to the accessor's %zu; glTF 2.0 §3.6.2.3)", what, index,
			      sp.count, a.count);
	int ict = sp.indices.componentType;
	if (ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
	    ict != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
		return L.fail("%s: accessor %d: sparse indices of component type %s (UNSIGNED_BYTE, _SHORT or _INT; glTF 2.0 "
			      "§3.6.2.3)", what, index, ctype_name(ict));
	v.sparse_isize = tinygltf::GetComponentSizeInBytes((uint32_t)ict);
	struct {
		int bv, offset;
		size_t elem;
		const unsigned char **out;
		const char *name;
	} parts[2] = {{sp.indices.bufferView, sp.indices.byteOffset, (size_t)v.sparse_isize, &v.sparse_idx, "indices"},
		      {sp.values.bufferView, sp.values.byteOffset, esize, &v.sparse_val, "values"}};
	for (auto &p : parts) {
		const tinygltf::BufferView *bv;
		const unsigned char *bytes;
		int rc = buffer_view(L, p.bv, what, index, &bv, &bytes);
		if (rc)
			return rc;
		size_t end;
		if (bv->byteStride)
			return L.fail("%s: accessor %d: the bufferView of sparse %s has a byteStride (glTF 2.0 §3.6.2.3)", what,
				      index, p.name);
		if (p.offset < 0 || __builtin_mul_overflow(p.elem, (size_t)sp.count, &end) ||
		    __builtin_add_overflow(end, (size_t)p.offset, &end) || end > bv->byteLength)
			return L.fail("%s: accessor %d: sparse %s (offset %d, %d elements) lie outside bufferView %d", what, index,
				      p.name, p.offset, sp.count, p.bv);
		*p.out = bytes + p.offset;
	}
	v.sparse_count = (size_t)sp.count;
	return 0;
}

// Sparse substitution target of entry j, checked (strictly increasing, below count).
int sparse_target(loader &L, const accessor_view &v, size_t j, size_t prev, const char *what, size_t *out)
{
	size_t t = read_uint(v.sparse_idx + j * (size_t)v.sparse_isize, v.sparse_isize);
	if (t >= v.count || (j > 0 && t <= prev))
		return L.fail("%s: sparse index %zu = %zu is not strictly increasing or not below the count %zu (glTF 2.0 "
			      "§3.6.2.3)", what, j, t, v.count);
	*out = t;
	return 0;
}

// Reads accessor `index` as rule.comps floats per element (normalised integers converted per §3.6.2.2);
// every value must be finite.
int read_floats(loader &L, int index, const char *what, const accessor_rule &rule, std::vector<float> &out)
{
	accessor_view v;
	int rc = accessor_check(L, index, what, rule, v);
	if (rc)
		return rc;
	const int comps = v.comps;
	out.assign(v.count * (size_t)comps, 0.0f); // count is backed by the file (or <= MAX_ZERO_ELEMENTS)
	if (v.data)
		for (size_t i = 0; i < v.count; i++)
			for (int c = 0; c < comps; c++)
				out[i * comps + c] = normalized(v.data + i * v.stride + (size_t)c * v.csize, v.ctype);
	for (size_t j = 0, t = 0; j < v.sparse_count; j++) {
		if ((rc = sparse_target(L, v, j, t, what, &t)))
			return rc;
		for (int c = 0; c < comps; c++)
			out[t * comps + c] = normalized(v.sparse_val + (j * comps + c) * (size_t)v.csize, v.ctype);
	}
	for (size_t i = 0; i < out.size(); i++)
		if (!std::isfinite(out[i]))
			return L.fail("%s: accessor %d: element %zu is not a finite number", what, index, i / comps);
	return 0;
}

int read_indices(loader &L, int index, const char *what, std::vector<uint32_t> &out)
{
	accessor_view v;
	int rc = accessor_check(L, index, what, RULE_INDICES, v);
	if (rc)
		return rc;
	out.assign(v.count, 0);
	if (v.data)
		for (size_t i = 0; i < v.count; i++)
			out[i] = read_uint(v.data + i * v.stride, v.csize);
	for (size_t j = 0, t = 0; j < v.sparse_count; j++) {
		if ((rc = sparse_target(L, v, j, t, what, &t)))
			return rc;
		out[t] = read_uint(v.sparse_val + j * (size_t)v.csize, v.csize);
	}
	return 0;
}

} // namespace gltf_in
