// gltf_internal.h — what the three parts of the glTF loader share (C++ only, scenes/src): the limits, the
// loader's state and its one-line errors, and the accessor rules and views. The parts: gltf_files.cpp (the file
// sandbox tinygltf reads through, GLB container and image header checks), gltf_accessors.cpp (accessor
// validation and reading, glTF 2.0 §3.6) and gltf.cpp (the scene built from the model: materials, meshes,
// nodes, animations, cameras). Sections cited as § are of the glTF 2.0 specification.
#pragma once

#include "gltf.h"

#include <tiny_gltf.h>

#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace gltf_in {

// Limits on what one asset may make the loader read or allocate (scene.h states them for users).
constexpr size_t MAX_JSON_BYTES = SCENE_GLTF_MAX_JSON_BYTES;
constexpr size_t MAX_FILE_BYTES = SCENE_GLTF_MAX_FILE_BYTES;
constexpr uint64_t MAX_READ_BYTES = 4ull << 30;    // all files of one asset together (a .bin named 1000 times)
constexpr uint64_t MAX_DECODED_BYTES = 4ull << 30; // meshes, keys and textures made from one asset
constexpr size_t MAX_ZERO_ELEMENTS = 1u << 24;     // accessor without a bufferView: zeros not backed by the file

// gltf_files.cpp: tinygltf's file and image callbacks (user data: fs_state and image_state) and the checks
// made before tinygltf sees the file.
struct fs_state {
	uint64_t read_total = 0;
};
struct image_state {
	const tinygltf::Model *model;
};
bool fs_exists(const std::string &path, void *);
std::string fs_expand(const std::string &path, void *);
bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &path, void *user);
bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *);
bool load_image(tinygltf::Image *image, const int index, std::string *err, std::string *warn, int req_w, int req_h,
		const unsigned char *bytes, int size, void *user);
// A regular file of at most `max` bytes into `out`; false with `why` otherwise.
bool read_regular_file(const std::string &path, size_t max, std::vector<unsigned char> &out, std::string &why);
// JSON nested deeper than SCENE_MAX_JSON_DEPTH levels (tinygltf recurses once per level).
bool json_too_deep(const unsigned char *s, size_t n);
// A GLB container checked against the file (§4.4): "" or what is wrong; the JSON chunk in json/json_len.
std::string check_glb(const std::vector<unsigned char> &f, const unsigned char **json, size_t *json_len);

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

// gltf_accessors.cpp
float normalized(const unsigned char *p, int ctype);
uint32_t read_uint(const unsigned char *p, int csize);
const char *ctype_name(int c);
int buffer_view(loader &L, int bv_index, const char *what, int acc, const tinygltf::BufferView **out,
		const unsigned char **bytes);
int accessor_check(loader &L, int index, const char *what, const accessor_rule &rule, accessor_view &v);
int sparse_target(loader &L, const accessor_view &v, size_t j, size_t prev, const char *what, size_t *out);
int read_floats(loader &L, int index, const char *what, const accessor_rule &rule, std::vector<float> &out);
int read_indices(loader &L, int index, const char *what, std::vector<uint32_t> &out);

} // namespace gltf_in
