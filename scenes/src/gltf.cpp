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
// No exception leaves this file: gltf_append catches them at the C boundary.
#include "gltf.h"
#include "taslab/texture.h"

#include <tiny_gltf.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <new>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace {

// Limits on what one asset may make the loader read or allocate (scene.h states them for users).
constexpr size_t MAX_JSON_BYTES = SCENE_GLTF_MAX_JSON_BYTES;
constexpr size_t MAX_FILE_BYTES = SCENE_GLTF_MAX_FILE_BYTES;
constexpr uint64_t MAX_READ_BYTES = 4ull << 30;    // all files of one asset together (a .bin named 1000 times)
constexpr uint64_t MAX_DECODED_BYTES = 4ull << 30; // meshes, keys and textures made from one asset
constexpr size_t MAX_ZERO_ELEMENTS = 1u << 24;     // accessor without a bufferView: zeros not backed by the file

// Files tinygltf opens (external buffers and images): regular files only (no FIFO that blocks, no /dev/zero
// that never ends), each at most MAX_FILE_BYTES, together at most MAX_READ_BYTES.
struct fs_state {
	uint64_t read_total = 0;
};

bool fs_exists(const std::string &path, void *)
{
	struct stat sb;
	return stat(path.c_str(), &sb) == 0 && S_ISREG(sb.st_mode);
}

std::string fs_expand(const std::string &path, void *) { return path; } // no ~ or $VAR expansion in URIs

// Reads a whole regular file of at most `max` bytes into `out`; false with a reason in `why`.
bool read_regular_file(const std::string &path, size_t max, std::vector<unsigned char> &out, std::string &why)
{
	int fd = open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
	if (fd < 0) {
		why = std::strerror(errno);
		return false;
	}
	struct stat sb;
	bool ok = false;
	if (fstat(fd, &sb) != 0)
		why = std::strerror(errno);
	else if (!S_ISREG(sb.st_mode))
		why = "not a regular file";
	else if ((uint64_t)sb.st_size > max)
		why = "larger than " + std::to_string(max) + " bytes";
	else {
		out.resize((size_t)sb.st_size);
		size_t got = 0;
		while (got < out.size()) {
			ssize_t n = read(fd, out.data() + got, out.size() - got);
			if (n < 0 && errno == EINTR)
				continue;
			if (n <= 0)
				break;
			got += (size_t)n;
		}
		ok = got == out.size();
		if (!ok)
			why = "read error";
	}
	close(fd);
	return ok;
}

bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &path, void *user)
{
	fs_state *st = static_cast<fs_state *>(user);
	std::string why;
	if (!read_regular_file(path, MAX_FILE_BYTES, *out, why)) {
		if (err)
			*err = why;
		return false;
	}
	st->read_total += out->size();
	if (st->read_total > MAX_READ_BYTES) {
		if (err)
			*err = "the asset's files together exceed " + std::to_string(MAX_READ_BYTES) + " bytes";
		out->clear();
		return false;
	}
	return true;
}

bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *)
{
	if (err)
		*err = "writing is not supported";
	return false;
}

// Width and height from a PNG (IHDR, PNG spec 11.2.2) or JPEG (first SOFn frame header, ITU T.81 B.2.2)
// header: the only image formats of core glTF (§3.8.2, §5.19 image.mimeType). false: neither format.
bool image_dimensions(const unsigned char *p, size_t n, uint32_t *w, uint32_t *h, const char **format)
{
	static const unsigned char png_sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
	if (n >= 24 && !std::memcmp(p, png_sig, 8) && !std::memcmp(p + 12, "IHDR", 4)) {
		*format = "PNG";
		*w = (uint32_t)p[16] << 24 | (uint32_t)p[17] << 16 | (uint32_t)p[18] << 8 | p[19];
		*h = (uint32_t)p[20] << 24 | (uint32_t)p[21] << 16 | (uint32_t)p[22] << 8 | p[23];
		return true;
	}
	if (n < 4 || p[0] != 0xFF || p[1] != 0xD8)
		return false;
	*format = "JPEG";
	size_t i = 2;
	while (i + 1 < n) {
		if (p[i] != 0xFF)
			return false;
		while (i + 1 < n && p[i + 1] == 0xFF) // fill bytes (T.81 B.1.1.2)
			i++;
		if (i + 1 >= n)
			return false;
		unsigned char m = p[i + 1];
		i += 2;
		if ((m >= 0xD0 && m <= 0xD7) || m == 0x01) // markers without a length
			continue;
		if (m == 0xD9 || m == 0xDA) // end of image or start of scan before any frame header
			return false;
		if (i + 2 > n)
			return false;
		size_t len = (size_t)p[i] << 8 | p[i + 1];
		if (len < 2)
			return false;
		if (m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC) { // SOF0..SOF15
			if (i + 7 > n)
				return false;
			*h = (uint32_t)p[i + 3] << 8 | p[i + 4];
			*w = (uint32_t)p[i + 5] << 8 | p[i + 6];
			return true;
		}
		i += len;
	}
	return false;
}

struct image_state {
	const tinygltf::Model *model;
};

// tinygltf's image callback: checks the encoded image before stb_image allocates for it, then decodes with
// tinygltf's own decoder (RGBA8, as before). For an image in a bufferView, tinygltf hands over
// &buffer[bufferView.byteOffset] with the bufferView's length without checking either against the buffer,
// so the bytes are located here again from the (already loaded) buffers, with checked arithmetic.
bool load_image(tinygltf::Image *image, const int index, std::string *err, std::string *warn, int req_w, int req_h,
		const unsigned char *bytes, int size, void *user)
{
	const tinygltf::Model &m = *static_cast<image_state *>(user)->model;
	auto refuse = [&](const std::string &why) {
		if (err)
			*err += "image " + std::to_string(index) + (image->uri.empty() ? "" : " (" + image->uri + ")") + ": " + why;
		return false;
	};
	size_t n = size > 0 ? (size_t)size : 0;
	if (image->bufferView >= 0) { // §3.6.1: a buffer view lies inside its buffer
		if ((size_t)image->bufferView >= m.bufferViews.size())
			return refuse("bufferView out of range");
		const tinygltf::BufferView &bv = m.bufferViews[(size_t)image->bufferView];
		if (bv.buffer < 0 || (size_t)bv.buffer >= m.buffers.size())
			return refuse("buffer out of range");
		const std::vector<unsigned char> &b = m.buffers[(size_t)bv.buffer].data;
		size_t end;
		if (__builtin_add_overflow(bv.byteOffset, bv.byteLength, &end) || end > b.size() || bv.byteLength > INT32_MAX)
			return refuse("bufferView " + std::to_string(image->bufferView) + " lies outside its buffer");
		bytes = b.data() + bv.byteOffset;
		n = bv.byteLength;
	}
	uint32_t w = 0, h = 0;
	const char *format = "";
	if (!bytes || !image_dimensions(bytes, n, &w, &h, &format))
		return refuse("not a PNG or JPEG image (glTF 2.0 §3.8.2)");
	if (w < 1 || h < 1 || w > SCENE_MAX_IMAGE_SIDE || h > SCENE_MAX_IMAGE_SIDE)
		return refuse(std::string(format) + " of " + std::to_string(w) + " x " + std::to_string(h) +
			      " pixels (1 to " + std::to_string(SCENE_MAX_IMAGE_SIDE) + " per side are supported)");
	// No option: tinygltf's default (preserve_channels false: expanded to RGBA8), as before this callback.
	return tinygltf::LoadImageData(image, index, err, warn, req_w, req_h, bytes, (int)n, nullptr);
}

// Deepest nesting of [ and { outside strings (as renderer/base/src/json.c): tinygltf's JSON parser and its
// extras/extensions conversion recurse once per level, so a file of "[[[[..." overflows the stack.
bool json_too_deep(const unsigned char *s, size_t n)
{
	int depth = 0;
	bool in_str = false;
	for (size_t i = 0; i < n; i++) {
		unsigned char c = s[i];
		if (in_str) {
			if (c == '\\')
				i++;
			else if (c == '"')
				in_str = false;
		} else if (c == '"') {
			in_str = true;
		} else if (c == '[' || c == '{') {
			if (++depth > SCENE_MAX_JSON_DEPTH)
				return true;
		} else if (c == ']' || c == '}') {
			depth--;
		}
	}
	return false;
}

uint32_t le32(const unsigned char *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }

// §4.4 (GLB file format): 12-byte header (magic, version 2, total length), a JSON chunk, optionally a BIN
// chunk; every chunk inside the file. tinygltf checks less (version not at all, the BIN chunk's length
// without its 8-byte header), so the container is checked here first. Returns "" or what is wrong; the
// JSON chunk is returned in json/json_len.
std::string check_glb(const std::vector<unsigned char> &f, const unsigned char **json, size_t *json_len)
{
	const size_t n = f.size();
	if (n < 20)
		return "GLB shorter than its 12-byte header and first chunk header";
	uint32_t version = le32(&f[4]), length = le32(&f[8]);
	if (version != 2)
		return "GLB container version " + std::to_string(version) + " (only version 2 is glTF 2.0, §4.4.2)";
	if (length != n)
		return "GLB header says " + std::to_string(length) + " bytes, the file has " + std::to_string(n);
	uint64_t json_end = 20ull + le32(&f[12]);
	if (le32(&f[16]) != 0x4E4F534Au) // "JSON"
		return "the first GLB chunk is not the JSON chunk (§4.4.3.1)";
	if (json_end > n || json_end == 20)
		return "the GLB JSON chunk (" + std::to_string(json_end - 20) + " bytes) overruns the file";
	if (json_end - 20 > MAX_JSON_BYTES)
		return "the GLB JSON chunk is larger than " + std::to_string(MAX_JSON_BYTES) + " bytes";
	*json = &f[20];
	*json_len = (size_t)(json_end - 20);
	uint64_t at = json_end;
	while (at < n) { // later chunks (BIN, then any unknown ones, which §4.4.3 says to ignore) must fit too
		if (n - at < 8)
			return "a GLB chunk header is cut off by the end of the file";
		uint64_t end = at + 8 + le32(&f[at]);
		if (end > n)
			return "a GLB chunk of " + std::to_string(le32(&f[at])) + " bytes overruns the file";
		at = end;
	}
	return "";
}

struct loader {
	const tinygltf::Model &m;
	scene *s;
	const char *path;
	char *err;
	size_t err_size;
	std::vector<int> tex_srgb, tex_linear;   // glTF image -> scene texture, per colour space (-1: not yet)
	std::map<std::pair<int, int>, int> prim; // (glTF mesh, primitive) -> scene mesh: instancing shares data
	std::string warnings;                    // tinygltf's warnings (why an external image did not load)
	uint64_t decoded = 0;                    // bytes of meshes, keys and textures made so far

#if defined(__GNUC__)
	__attribute__((format(printf, 2, 3)))
#endif
	int
	fail(const char *fmt, ...)
	{
		char msg[768];
		va_list ap;
		va_start(ap, fmt);
		std::vsnprintf(msg, sizeof msg, fmt, ap);
		va_end(ap);
		std::snprintf(err, err_size, "%s: %s", path, msg);
		return TL_ERR_INPUT;
	}

	// Counts `bytes` against MAX_DECODED_BYTES before they are allocated: instancing a mesh or re-using an
	// accessor costs nothing in the file, so the file size alone does not bound the memory.
	int charge(uint64_t bytes, const char *what)
	{
		if (bytes > MAX_DECODED_BYTES || decoded + bytes > MAX_DECODED_BYTES)
			return fail("%s: the asset would need more than %llu bytes of memory once decoded", what,
				    (unsigned long long)MAX_DECODED_BYTES);
		decoded += bytes;
		return 0;
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

// What an accessor must be for one use: number of components and the allowed component types, each with
// whether it must be normalised (the accessor tables of §3.7.2.1 meshes and §3.11 animations).
struct accessor_rule {
	int comps;
	int ctypes[5];
	bool norm[5];
	int n;
};
const accessor_rule RULE_VEC3_FLOAT = {3, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {false}, 1};
const accessor_rule RULE_VEC4_FLOAT = {4, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {false}, 1};
const accessor_rule RULE_SCALAR_FLOAT = {1, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {false}, 1};
const accessor_rule RULE_TEXCOORD = {2,
				     {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
				      TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
				     {false, true, true},
				     3};
const accessor_rule RULE_ROTATION = {4,
				     {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_BYTE,
				      TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_SHORT,
				      TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
				     {false, true, true, true, true},
				     5};
const accessor_rule RULE_INDICES = {1,
				    {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
				     TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT},
				    {false, false, false},
				    3};

// A validated accessor: `count` elements of `comps` components of `csize` bytes, element i at
// data + i * stride (data NULL: zeros), then `sparse_count` substitutions.
struct accessor_view {
	const tinygltf::Accessor *a;
	size_t count;
	int comps, ctype, csize;
	const unsigned char *data;
	size_t stride;
	size_t sparse_count;
	const unsigned char *sparse_idx, *sparse_val;
	int sparse_isize;
};

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
