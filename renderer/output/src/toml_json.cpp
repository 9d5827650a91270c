/* toml_json.cpp — sweep files in TOML (DESIGN section 9: "the same from a JSON/TOML sweep file"). toml++ (Debian's
 * libtomlplusplus) parses the file; the document becomes the jansson value the same file written as JSON would give,
 * so sweep.c checks one set of keys and values for both formats and every refusal reads the same. TOML's dates and
 * times have no meaning in a sweep file and are refused; integers stay integers (jobs, periods), floats floats. */
#include "toml_json.h"

#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <new>
#include <string>
#include <string_view>

#include <toml++/toml.h>

namespace {

/* A sweep file is a few hundred bytes; anything near this is not one. */
constexpr size_t TOML_MAX_BYTES = 1u << 20;
/* Sweep files nest two levels at most; deeper documents are refused before conversion recurses. */
constexpr int TOML_MAX_DEPTH = 64;

/* Owns a jansson value until it is handed on (release), also when an exception unwinds. */
struct json_release {
	void operator()(json_t *j) const { json_decref(j); }
};
using json_ptr = std::unique_ptr<json_t, json_release>;

/* One line: control characters in a quoted key or message would break it. */
std::string printable(std::string_view s)
{
	std::string o;
	for (char c : s.substr(0, 200))
		o += (unsigned char)c < 0x20 || c == 0x7f ? '?' : c;
	return o;
}

std::string at(const toml::source_region &r)
{
	return std::to_string(r.begin.line) + ":" + std::to_string(r.begin.column) + ": ";
}

json_ptr convert(const toml::node &n, int depth, std::string &why);

json_ptr convert_table(const toml::table &t, int depth, std::string &why)
{
	json_ptr o(json_object());
	if (!o)
		throw std::bad_alloc();
	for (auto &&[k, v] : t) {
		/* JSON (jansson) refuses NUL in strings; a key cut at a NUL would silently replace another */
		if (k.str().find('\0') != std::string_view::npos) {
			why = at(k.source()) + "a key contains a NUL character";
			return nullptr;
		}
		json_ptr jv = convert(v, depth + 1, why);
		if (!jv)
			return nullptr;
		if (json_object_set_new(o.get(), std::string(k.str()).c_str(), jv.release())) /* takes the value */
			throw std::bad_alloc();
	}
	return o;
}

json_ptr convert(const toml::node &n, int depth, std::string &why)
{
	if (depth > TOML_MAX_DEPTH) {
		why = at(n.source()) + "nested deeper than " + std::to_string(TOML_MAX_DEPTH) + " levels";
		return nullptr;
	}
	json_t *o = nullptr;
	if (auto t = n.as_table())
		return convert_table(*t, depth, why);
	if (auto a = n.as_array()) {
		json_ptr arr(json_array());
		if (!arr)
			throw std::bad_alloc();
		for (auto &&e : *a) {
			json_ptr jv = convert(e, depth + 1, why);
			if (!jv)
				return nullptr;
			if (json_array_append_new(arr.get(), jv.release()))
				throw std::bad_alloc();
		}
		return arr;
	}
	if (auto s = n.as_string()) {
		if (s->get().find('\0') != std::string::npos) {
			why = at(n.source()) + "a string contains a NUL character";
			return nullptr;
		}
		o = json_stringn(s->get().data(), s->get().size());
		if (!o) { /* jansson also refuses invalid UTF-8, which toml++ lets through in literal strings */
			why = at(n.source()) + "a string is not valid UTF-8";
			return nullptr;
		}
		return json_ptr(o);
	}
	if (auto i = n.as_integer())
		o = json_integer((json_int_t)i->get());
	else if (auto f = n.as_floating_point())
		o = json_real(f->get());
	else if (auto b = n.as_boolean())
		o = json_boolean(b->get());
	else {
		why = at(n.source()) + "dates and times are not sweep values (give frames as \"A:B\")";
		return nullptr;
	}
	if (!o)
		throw std::bad_alloc();
	return json_ptr(o);
}

} // namespace

extern "C" int tl_toml_read(const char *path, json_t **out, char *err, size_t err_size)
{
	*out = nullptr;
	char *text = nullptr;
	size_t len = 0;
	int rc = tl_read_file(path, TOML_MAX_BYTES, &text, &len, err, err_size);
	if (rc)
		return rc;
	/* No exception leaves this function: every failure, an allocation's included, is one line. */
	try {
		std::string why;
		try {
			toml::table doc = toml::parse(std::string_view(text, len), std::string_view(path));
			*out = convert_table(doc, 0, why).release();
		} catch (const toml::parse_error &e) {
			why = at(e.source()) + printable(e.description());
		}
		free(text);
		text = nullptr;
		if (*out)
			return TL_OK;
		if (why.empty())
			why = "not a TOML sweep file";
		const bool located = why[0] >= '0' && why[0] <= '9'; /* "line:column: ..." */
		return tl_error(err, err_size, TL_ERR_INPUT, "%s:%s%s", path, located ? "" : " ", why.c_str());
	} catch (...) {
		free(text);
		return tl_error(err, err_size, TL_ERR_NOMEM, "%s: out of memory reading it", path);
	}
}
