/* toml_json.cpp — sweep files in TOML (DESIGN section 9: "the same from a JSON/TOML sweep file"). toml++ (Debian's
 * libtomlplusplus) parses the file; the document becomes the jansson value the same file written as JSON would give,
 * so sweep.c checks one set of keys and values for both formats and every refusal reads the same. TOML's dates and
 * times have no meaning in a sweep file and are refused; integers stay integers (jobs, periods), floats floats. */
#include "toml_json.h"

#include "taslab/tl_error.h"
#include "taslab/tl_fs.h"

#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include <toml++/toml.h>

namespace {

/* A sweep file is a few hundred bytes; anything near this is not one. */
constexpr size_t TOML_MAX_BYTES = 1u << 20;
/* Sweep files nest two levels at most; deeper documents are refused before conversion recurses. */
constexpr int TOML_MAX_DEPTH = 64;

/* One line: control characters in a quoted key or message would break it. */
std::string printable(std::string_view s)
{
	std::string o;
	for (char c : s.substr(0, 200))
		o += (unsigned char)c < 0x20 || c == 0x7f ? '?' : c;
	return o;
}

json_t *convert(const toml::node &n, int depth, std::string &why);

json_t *convert_table(const toml::table &t, int depth, std::string &why)
{
	json_t *o = json_object();
	for (auto &&[k, v] : t) {
		json_t *jv = o ? convert(v, depth + 1, why) : nullptr;
		if (!jv || json_object_set_new(o, std::string(k.str()).c_str(), jv)) {
			if (why.empty())
				why = "key \"" + printable(k.str()) + "\" could not be read";
			json_decref(o);
			return nullptr;
		}
	}
	return o;
}

json_t *convert(const toml::node &n, int depth, std::string &why)
{
	if (depth > TOML_MAX_DEPTH) {
		why = "nested deeper than " + std::to_string(TOML_MAX_DEPTH) + " levels";
		return nullptr;
	}
	if (auto t = n.as_table())
		return convert_table(*t, depth, why);
	if (auto a = n.as_array()) {
		json_t *o = json_array();
		for (auto &&e : *a) {
			json_t *jv = o ? convert(e, depth + 1, why) : nullptr;
			if (!jv || json_array_append_new(o, jv)) {
				json_decref(o);
				return nullptr;
			}
		}
		return o;
	}
	if (auto s = n.as_string())
		return json_stringn(s->get().data(), s->get().size());
	if (auto i = n.as_integer())
		return json_integer((json_int_t)i->get());
	if (auto f = n.as_floating_point())
		return json_real(f->get());
	if (auto b = n.as_boolean())
		return json_boolean(b->get());
	const auto where = n.source().begin;
	why = std::to_string(where.line) + ":" + std::to_string(where.column) +
	      ": dates and times are not sweep values (give frames as \"A:B\")";
	return nullptr;
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
	std::string why;
	try {
		toml::table doc = toml::parse(std::string_view(text, len), std::string_view(path));
		*out = convert_table(doc, 0, why);
	} catch (const toml::parse_error &e) {
		const auto where = e.source().begin;
		why = std::to_string(where.line) + ":" + std::to_string(where.column) + ": " + printable(e.description());
	} catch (const std::exception &e) {
		why = printable(e.what());
	}
	free(text);
	if (*out)
		return TL_OK;
	if (why.empty())
		why = "not a TOML sweep file";
	const bool located = why[0] >= '0' && why[0] <= '9'; /* "line:column: ..." */
	return tl_error(err, err_size, TL_ERR_INPUT, "%s:%s%s", path, located ? "" : " ", why.c_str());
}
