// gltf_files.cpp — the glTF loader's file side (issue 12): tinygltf reads external files and decodes images
// only through the callbacks here (regular files of bounded size, PNG/JPEG of bounded dimensions, bufferView
// images inside their buffer), and a file is checked before tinygltf parses it (JSON nesting depth, GLB
// container against the file). Shared declarations: gltf_internal.h.
#include "gltf_internal.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace gltf_in {

namespace {


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

uint32_t le32(const unsigned char *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }

} // namespace


// Files tinygltf opens (external buffers and images): regular files only (no FIFO that blocks, no /dev/zero
// that never ends), each at most MAX_FILE_BYTES, together at most MAX_READ_BYTES.
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

} // namespace gltf_in
