/* toml_json.cpp — sweep files in TOML (DESIGN section 9: "the same from a JSON/TOML sweep file"). toml++ (Debian's
 * libtomlplusplus) parses the file; the document becomes the jansson value the same file written as JSON would give,
 * so sweep.c checks one set of keys and values for both formats and every refusal reads the same. TOML's dates and
 * times have no meaning in a sweep file and are refused; integers stay integers (jobs, periods), floats floats. */
#include "toml_json.h"

#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <new>
#include <string>
#include <string_view>
#include <vector>

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

/* Bounds the nesting of a document before toml++ sees it (issue 31.1): toml++ builds (and destroys) nested tables
 * recursively, so `a.a.a…` or `[a.a.a…]` tens of thousands of parts deep — a 100 KB file — overflowed the stack.
 * Counts, outside strings and comments, the parts of the current table header, of a dotted key and of open inline
 * arrays and tables: an over-estimate of the depth toml++ would build (a float's '.' counts too), so a document that
 * passes nests at most `max` levels. Returns the 1-based line where the bound is crossed, 0 when it holds. */
size_t toml_too_deep(std::string_view s, int max)
{
	std::vector<int> base; /* depth at each open '[' / '{' of a value */
	size_t line = 1;
	int header = 0, dots = 0, key_dots = 0;
	bool line_start = true, in_header = false;
	for (size_t i = 0; i < s.size(); i++) {
		const char c = s[i];
		const int depth = (base.empty() ? (in_header ? 0 : header) : base.back()) + key_dots + dots + 1;
		if (depth > max)
			return line;
		if (c == '\n') {
			line++;
			dots = 0;
			if (base.empty())
				key_dots = 0, in_header = false;
			line_start = true;
			continue;
		}
		if (c == ' ' || c == '\t' || c == '\r')
			continue;
		const bool first = line_start;
		line_start = false;
		if (c == '#') { /* a comment: to the end of the line */
			while (i + 1 < s.size() && s[i + 1] != '\n')
				i++;
		} else if (c == '"' || c == '\'') {
			const bool triple = s.substr(i, 3) == std::string_view(c == '"' ? "\"\"\"" : "'''", 3);
			i += triple ? 3 : 1;
			for (; i < s.size(); i++) {
				if (c == '"' && s[i] == '\\') {
					i++;
					continue;
				}
				if (s[i] == '\n') {
					line++;
					if (!triple)
						break; /* unterminated: toml++ says so */
				}
				if (s[i] == c && (!triple || s.substr(i, 3) == std::string_view(c == '"' ? "\"\"\"" : "'''", 3))) {
					i += triple ? 2 : 0;
					break;
				}
			}
		} else if (c == '.') {
			dots++;
		} else if (c == '[' && first && base.empty()) { /* [table] or [[array of tables]] */
			in_header = true;
			header = 0;
			dots = key_dots = 0;
		} else if (c == ']' && in_header && base.empty()) {
			header = dots + 1;
			in_header = false;
			while (i + 1 < s.size() && s[i + 1] == ']')
				i++;
		} else if (c == '[' || c == '{') {
			base.push_back(depth);
			dots = key_dots = 0;
		} else if (c == ']' || c == '}') {
			if (!base.empty())
				base.pop_back();
			dots = key_dots = 0;
		} else if (c == '=') {
			key_dots += dots;
			dots = 0;
		} else if (c == ',') {
			dots = key_dots = 0;
		}
	}
	return 0;
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
	else if (auto f = n.as_floating_point()) {
		/* jansson has no inf or nan (json_real gives NULL): say so, not "out of memory" (issue 31.5) */
		if (!std::isfinite(f->get())) {
			why = at(n.source()) + "inf and nan are not sweep values (give a finite number)";
			return nullptr;
		}
		o = json_real(f->get());
	}
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
			if (size_t line = toml_too_deep(std::string_view(text, len), TOML_MAX_DEPTH)) {
				why = std::to_string(line) + ":1: nested deeper than " + std::to_string(TOML_MAX_DEPTH) +
				      " levels (dotted keys, table headers or inline arrays and tables; a sweep file needs two)";
			} else {
				toml::table doc = toml::parse(std::string_view(text, len), std::string_view(path));
				*out = convert_table(doc, 0, why).release();
			}
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
