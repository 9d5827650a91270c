/* registry.c — the method registry, option tables and variant syntax (method.h). The only list of methods:
 * adding a method is one file in methods/ (defining `const render_method render_method_NAME`) and one X(NAME)
 * line in METHODS below (issue 30.1: no per-method declarations in the frame core). */
#include "../frame/render_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Every method, in the order of `render --help` (the implemented ones first, then any planned ones of DESIGN
 * section 4, listed in help and refused with a message). */
#define METHODS(X)                                                                                                    \
	X(ref)                                                                                                         \
	X(tfr)                                                                                                         \
	X(rrc)                                                                                                         \
	X(tarc)                                                                                                        \
	X(sa)                                                                                                          \
	X(sau)                                                                                                         \
	X(tasa)                                                                                                        \
	X(vref)                                                                                                        \
	X(ads)                                                                                                         \
	X(casedge)                                                                                                     \
	X(castexel)                                                                                                    \
	X(mas)                                                                                                         \
	X(fovea)                                                                                                       \
	X(taas)                                                                                                        \
	X(rrc_random)                                                                                                  \
	X(rrc_interleaved)                                                                                             \
	X(warp)                                                                                                        \
	X(amss)                                                                                                        \
	X(stu)

#define DECLARE(name) extern const render_method render_method_##name;
METHODS(DECLARE)
#undef DECLARE

#define ENTRY(name) &render_method_##name,
static const render_method *const implemented[] = {METHODS(ENTRY)};
#undef ENTRY
/* The same list as method_info pointers, for method_list (derived from METHODS, not a second list). */
#define INFO(name) &render_method_##name.info,
static const method_info *const all[] = {METHODS(INFO)};
#undef INFO

const method_info *const *method_list(size_t *count)
{
	*count = sizeof all / sizeof all[0];
	return all;
}

const method_info *method_find(const char *name)
{
	for (size_t i = 0; name && i < sizeof all / sizeof all[0]; i++)
		if (!strcmp(all[i]->name, name))
			return all[i];
	return NULL;
}

const render_method *render_method_of(const method_info *info)
{
	for (size_t i = 0; info && info->available && i < sizeof implemented / sizeof implemented[0]; i++)
		if (&implemented[i]->info == info)
			return implemented[i];
	return NULL;
}

const method_info *method_reference(void)
{
	for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
		if (all[i]->reference)
			return all[i];
	return NULL;
}

static bool has_sigil(const method_info *m, char sigil)
{
	for (size_t i = 0; i < m->option_count; i++)
		if (m->options[i].variant == sigil)
			return true;
	return false;
}

void method_facts(const method_info *m, run_method_facts *out)
{
	memset(out, 0, sizeof *out);
	const method_info *ref = method_reference();
	const char *base = m->baseline ? m->baseline : ref ? ref->name : "";
	out->known = true;
	snprintf(out->family, sizeof out->family, "%s", m->family ? m->family : "");
	snprintf(out->baseline, sizeof out->baseline, "%s", base);
	out->reference = m->reference;
	/* T and the period are the options a variant sets with '@' and '/' (method_config_threshold, _period). */
	out->takes_threshold = has_sigil(m, '@');
	out->takes_period = has_sigil(m, '/');
}

/* Names of the implemented methods, for messages. */
static void available_names(char *out, size_t n)
{
	size_t len = 0;
	out[0] = 0;
	for (size_t i = 0; i < sizeof implemented / sizeof implemented[0] && len < n; i++)
		if (implemented[i]->info.available)
			len += (size_t)snprintf(out + len, n - len, "%s%s", len ? ", " : "", implemented[i]->info.name);
}

static void *value_ptr(method_config *c, const method_option *o) { return c->values.bytes + o->offset; }
static const void *cvalue_ptr(const method_config *c, const method_option *o) { return c->values.bytes + o->offset; }

static double get_number(const method_config *c, const method_option *o)
{
	const void *p = cvalue_ptr(c, o);
	switch (o->type) {
	case METHOD_OPT_FLOAT: return *(const float *)p;
	case METHOD_OPT_BOOL: return *(const bool *)p ? 1.0 : 0.0;
	default: return *(const uint32_t *)p;
	}
}

static void put_number(method_config *c, const method_option *o, double v)
{
	void *p = value_ptr(c, o);
	switch (o->type) {
	case METHOD_OPT_FLOAT: *(float *)p = (float)v; break;
	case METHOD_OPT_BOOL: *(bool *)p = v != 0.0; break;
	default: *(uint32_t *)p = (uint32_t)v; break;
	}
}

int method_config_init(method_config *c, const char *name, char *err, size_t err_size)
{
	memset(c, 0, sizeof *c);
	const method_info *m = method_find(name);
	char avail[256];
	available_names(avail, sizeof avail);
	if (!m)
		return tl_error(err, err_size, TL_ERR_ARG, "unknown method '%s' (available: %s; see 'taslab render --help')",
				name ? name : "", avail);
	if (!m->available)
		return tl_error(err, err_size, TL_ERR_UNSUPPORTED, "method '%s' is planned but not implemented yet (available: %s)",
				name, avail);
	if (m->options_size > METHOD_OPTIONS_MAX_B)
		return tl_error(err, err_size, TL_ERR_INTERNAL, "method '%s': options struct too large", name);
	c->method = m;
	for (size_t i = 0; i < m->option_count; i++)
		put_number(c, &m->options[i], m->options[i].def);
	return TL_OK;
}

static const method_option *find_option(const method_info *m, const char *name, size_t *index)
{
	for (size_t i = 0; m && i < m->option_count; i++)
		if (!strcmp(m->options[i].name, name)) {
			if (index)
				*index = i;
			return &m->options[i];
		}
	return NULL;
}

/* "--NAME applies to: a, b" for an option that belongs to other methods. */
static void owners(const char *option, char *out, size_t n)
{
	size_t len = 0;
	out[0] = 0;
	for (size_t i = 0; i < sizeof all / sizeof all[0] && len < n; i++)
		if (find_option(all[i], option, NULL))
			len += (size_t)snprintf(out + len, n - len, "%s%s", len ? ", " : "", all[i]->name);
}

int method_config_set(method_config *c, const char *option, const char *value, char *err, size_t err_size)
{
	size_t idx;
	const method_option *o = find_option(c->method, option, &idx);
	if (!o) {
		char who[256];
		owners(option, who, sizeof who);
		if (who[0])
			return tl_error(err, err_size, TL_ERR_ARG, "--%s is not an option of %s (it applies to: %s)", option,
					c->method->name, who);
		return tl_error(err, err_size, TL_ERR_ARG, "method %s has no option '%s'", c->method->name, option);
	}
	double v = 0;
	if (o->type == METHOD_OPT_BOOL) {
		if (value && strcmp(value, "1") && strcmp(value, "true") && strcmp(value, "0") && strcmp(value, "false"))
			return tl_error(err, err_size, TL_ERR_ARG, "--%s is a flag (no value, or true/false)", o->name);
		v = !value || !strcmp(value, "1") || !strcmp(value, "true");
	} else if (o->type == METHOD_OPT_CHOICE) {
		size_t k = 0;
		while (o->choices[k] && (!value || strcmp(o->choices[k], value)))
			k++;
		if (!o->choices[k]) {
			char list[256] = "";
			for (size_t j = 0, len = 0; o->choices[j] && len < sizeof list; j++)
				len += (size_t)snprintf(list + len, sizeof list - len, "%s%s", j ? ", " : "", o->choices[j]);
			return tl_error(err, err_size, TL_ERR_ARG, "--%s '%s' is not one of: %s", o->name, value ? value : "", list);
		}
		v = (double)k;
	} else {
		char *end = NULL;
		v = value && *value ? strtod(value, &end) : NAN;
		if (!value || !*value || *end || !isfinite(v))
			return tl_error(err, err_size, TL_ERR_ARG, "--%s '%s' is not a number", o->name, value ? value : "");
		/* Whole numbers are written as digits, as every other count of the command line (cli_parse_uint): "2.0"
		 * and "1e2" are not accepted as 2 and 100. */
		if (o->type == METHOD_OPT_UINT && (v != floor(v) || strspn(value, "0123456789") != strlen(value)))
			return tl_error(err, err_size, TL_ERR_ARG, "--%s '%s' is not a whole number", o->name, value);
		if (o->allowed) {
			size_t k = 0;
			while (o->allowed[k] && (double)o->allowed[k] != v)
				k++;
			if (!o->allowed[k]) {
				char list[128] = "";
				for (size_t j = 0, len = 0; o->allowed[j] && len < sizeof list; j++)
					len += (size_t)snprintf(list + len, sizeof list - len, "%s%u", j ? ", " : "", o->allowed[j]);
				return tl_error(err, err_size, TL_ERR_ARG, "--%s %s: must be one of %s", o->name, value, list);
			}
		} else if (v < o->min || v > o->max) {
			return tl_error(err, err_size, TL_ERR_ARG, "--%s %s: out of range [%g, %g]", o->name, value, o->min, o->max);
		}
	}
	put_number(c, o, v);
	c->given |= 1u << idx;
	return TL_OK;
}

int method_config_check(const method_config *c, char *err, size_t err_size)
{
	if (!c->method)
		return tl_error(err, err_size, TL_ERR_ARG, "no method chosen");
	for (size_t i = 0; i < c->method->option_count; i++) {
		const method_option *o = &c->method->options[i];
		if (o->variant_required && !(c->given & (1u << i)) && isnan(o->def))
			return tl_error(err, err_size, TL_ERR_ARG, "%s needs --%s (e.g. %s%c8)", c->method->name, o->name,
					c->method->name, o->variant);
	}
	return c->method->check ? c->method->check(c->values.bytes, err, err_size) : TL_OK;
}

size_t method_dash_forms(const method_info *m, char (*out)[METHOD_DASH_FORM_B], size_t max)
{
	size_t count = 0;
#define PUT_FORM(...)                                                                                          \
	do {                                                                                                   \
		if (count < max)                                                                               \
			snprintf(out[count], METHOD_DASH_FORM_B, __VA_ARGS__);                                 \
		count++;                                                                                       \
	} while (0)
	for (size_t i = 0; i < m->option_count; i++) {
		const method_option *o = &m->options[i];
		if (o->variant != '-')
			continue;
		if (o->type == METHOD_OPT_BOOL)
			PUT_FORM("%s", o->name);
		for (size_t k = 0; o->type == METHOD_OPT_UINT && o->allowed && o->allowed[k]; k++)
			if ((double)o->allowed[k] != o->def)
				PUT_FORM("%s%u", o->name, o->allowed[k]);
		for (size_t k = 0; o->type == METHOD_OPT_CHOICE && o->choices[k]; k++)
			if ((double)k != o->def)
				PUT_FORM("%s", o->choices[k]);
	}
#undef PUT_FORM
	return count;
}

/* "its '-' forms: -oracle, -ssaa2, -shadow, -diffuse" (method_dash_forms), or "it has none". */
static void dash_forms(const method_info *m, char *out, size_t n)
{
	char forms[METHOD_DASH_FORMS_MAX][METHOD_DASH_FORM_B];
	size_t k = method_dash_forms(m, forms, METHOD_DASH_FORMS_MAX), len = (size_t)snprintf(out, n, "its '-' forms:");
	for (size_t i = 0; i < k && i < METHOD_DASH_FORMS_MAX && len < n; i++)
		len += (size_t)snprintf(out + len, n - len, "%s -%s", i ? "," : "", forms[i]);
	if (!k)
		snprintf(out, n, "it has none");
}

int method_config_parse_variant(method_config *c, const char *variant, char *err, size_t err_size)
{
	char buf[128], *sig[2] = {NULL, NULL};
	memset(c, 0, sizeof *c);
	if (!variant || !*variant || snprintf(buf, sizeof buf, "%s", variant) >= (int)sizeof buf)
		return tl_error(err, err_size, TL_ERR_ARG, "empty or over-long variant '%s'", variant ? variant : "");
	char *at = strchr(buf, '@'), *slash = strchr(buf, '/');
	if (at)
		*at = 0, sig[0] = at + 1;
	if (slash)
		*slash = 0, sig[1] = slash + 1;
	if ((at && strchr(at + 1, '@')) || (slash && strchr(slash + 1, '/')))
		return tl_error(err, err_size, TL_ERR_ARG, "variant '%s': '@' and '/' may appear once each", variant);
	/* NAME[-FLAG...]: the longest prefix that names a method, the rest its flags. */
	char name[128];
	snprintf(name, sizeof name, "%s", buf);
	const method_info *m = NULL;
	char *flags = NULL;
	for (char *dash = NULL;;) {
		if ((m = method_find(name)))
			break;
		dash = strrchr(name, '-');
		if (!dash)
			break;
		*dash = 0;
		flags = buf + (dash - name);
	}
	int rc = method_config_init(c, m ? m->name : buf, err, err_size);
	if (rc) {
		if (rc == TL_ERR_ARG && !m)
			return tl_error(err, err_size, TL_ERR_ARG, "variant '%s': unknown method '%s' (see 'taslab render --help')",
					variant, buf);
		return rc;
	}
	for (char *f = flags; f && *f == '-';) {
		char *next = strchr(f + 1, '-');
		if (next)
			*next = 0;
		size_t oi = 0;
		const method_option *o = find_option(m, f + 1, &oi);
		/* a whole-number option written as -NAMEvalue ("ref-ssaa2"), a choice as -VALUE ("rrc-shadow") */
		char oname[64], *digits = NULL;
		const char *choice = NULL;
		for (size_t i = 0; !o && i < m->option_count; i++)
			for (size_t k = 0; m->options[i].type == METHOD_OPT_CHOICE && m->options[i].variant == '-' &&
					   m->options[i].choices[k];
			     k++)
				if (!strcmp(m->options[i].choices[k], f + 1))
					o = &m->options[i], oi = i, choice = f + 1;
		if (!o) {
			snprintf(oname, sizeof oname, "%s", f + 1);
			size_t len = strlen(oname);
			while (len > 0 && oname[len - 1] >= '0' && oname[len - 1] <= '9')
				len--;
			if (oname[len]) {
				digits = f + 1 + len;
				oname[len] = 0;
				o = find_option(m, oname, &oi);
				if (o && o->type != METHOD_OPT_UINT)
					o = NULL;
			}
		} else if (o->type != METHOD_OPT_BOOL && !choice) {
			o = NULL; /* "ref-ssaa": the value is part of the token */
		}
		if (!o || o->variant != '-') {
			char forms[160];
			dash_forms(m, forms, sizeof forms);
			return tl_error(err, err_size, TL_ERR_ARG, "variant '%s': %s has no '-%s' form (%s)", variant, m->name,
					f + 1, forms);
		}
		if (c->given & (1u << oi)) { /* "tasa-oracle-oracle": one spelling per variant (issue 31.9) */
			if (choice)
				return tl_error(err, err_size, TL_ERR_ARG, "variant '%s': '-%s' sets --%s, which the variant sets "
						"already: give one", variant, f + 1, o->name);
			return tl_error(err, err_size, TL_ERR_ARG, "variant '%s': '-%s' is given twice", variant, f + 1);
		}
		if (digits || choice) {
			char why[256];
			if (method_config_set(c, o->name, digits ? digits : choice, why, sizeof why))
				return tl_error(err, err_size, TL_ERR_ARG, "variant '%s': %s", variant, why);
		} else if ((rc = method_config_set(c, o->name, NULL, err, err_size))) {
			return rc;
		}
		if (!next)
			break;
		*next = '-';
		f = next;
	}
	const char sigils[2] = {'@', '/'};
	for (int k = 0; k < 2; k++) {
		if (!sig[k])
			continue;
		const method_option *o = NULL;
		for (size_t i = 0; i < m->option_count; i++)
			if (m->options[i].variant == sigils[k])
				o = &m->options[i];
		if (!o)
			return tl_error(err, err_size, TL_ERR_ARG, "variant '%s': %s takes no '%c' value", variant, m->name, sigils[k]);
		char why[256];
		if (method_config_set(c, o->name, sig[k], why, sizeof why))
			return tl_error(err, err_size, TL_ERR_ARG, "variant '%s': %s", variant, why);
	}
	for (size_t i = 0; i < m->option_count; i++) {
		const method_option *o = &m->options[i];
		if (o->variant_required && !(c->given & (1u << i)))
			return tl_error(err, err_size, TL_ERR_ARG, "variant '%s': %s needs its %s, e.g. %s%c%s", variant, m->name,
					o->name, buf, o->variant, o->variant == '@' ? "8" : "4");
	}
	return method_config_check(c, err, err_size);
}

void method_config_name(const method_config *c, char *out, size_t out_size)
{
	size_t len = (size_t)snprintf(out, out_size, "%s", c->method ? c->method->name : "?");
	for (size_t i = 0; c->method && i < c->method->option_count && len < out_size; i++) {
		const method_option *o = &c->method->options[i];
		if (o->variant == '-' && o->type == METHOD_OPT_BOOL && get_number(c, o) != 0.0)
			len += (size_t)snprintf(out + len, out_size - len, "-%s", o->name);
		else if (o->variant == '-' && o->type == METHOD_OPT_UINT && get_number(c, o) != o->def)
			len += (size_t)snprintf(out + len, out_size - len, "-%s%g", o->name, get_number(c, o));
		else if (o->variant == '-' && o->type == METHOD_OPT_CHOICE && get_number(c, o) != o->def)
			len += (size_t)snprintf(out + len, out_size - len, "-%s", o->choices[(size_t)get_number(c, o)]);
	}
}

/* Appends sigil+value (or, for ids, a letter+value) of the '@' and '/' options. */
static void variant_values(const method_config *c, char *out, size_t out_size, int id)
{
	size_t len = strlen(out);
	const char sig[2] = {'@', '/'}, letter[2] = {'T', 'N'};
	for (int k = 0; k < 2; k++)
		for (size_t i = 0; c->method && i < c->method->option_count && len < out_size; i++) {
			const method_option *o = &c->method->options[i];
			if (o->variant == sig[k] && (o->variant_required || (c->given & (1u << i))))
				len += (size_t)snprintf(out + len, out_size - len, id ? "-%c%g" : "%c%g", id ? letter[k] : sig[k],
							get_number(c, o));
		}
}

void method_config_variant(const method_config *c, char *out, size_t out_size)
{
	method_config_name(c, out, out_size);
	variant_values(c, out, out_size, 0);
}

void method_config_id(const method_config *c, char *out, size_t out_size)
{
	method_config_name(c, out, out_size);
	variant_values(c, out, out_size, 1);
}

static double by_sigil(const method_config *c, char sigil, double none)
{
	for (size_t i = 0; c->method && i < c->method->option_count; i++)
		if (c->method->options[i].variant == sigil)
			return get_number(c, &c->method->options[i]);
	return none;
}

double method_config_threshold(const method_config *c) { return by_sigil(c, '@', NAN); }
uint32_t method_config_period(const method_config *c) { return (uint32_t)by_sigil(c, '/', 0.0); }

double method_config_number(const method_config *c, const char *option)
{
	const method_option *o = find_option(c->method, option, NULL);
	return o ? get_number(c, o) : NAN;
}

bool method_config_flag(const method_config *c, const char *option)
{
	const method_option *o = find_option(c->method, option, NULL);
	return o && o->type == METHOD_OPT_BOOL && get_number(c, o) != 0.0;
}

bool method_has_option(const method_info *m, const char *name)
{
	return find_option(m, name, NULL) != NULL;
}

void method_option_describe(const method_option *o, char *out, size_t out_size)
{
	size_t len = 0;
	if (!out_size)
		return;
	out[0] = 0;
#define PUT(...)                                                                                                       \
	do {                                                                                                           \
		if (len < out_size)                                                                                    \
			len += (size_t)snprintf(out + len, out_size - len, __VA_ARGS__);                               \
	} while (0)
	if (o->variant == '@' || o->variant == '/')
		PUT("as %c%s", o->variant, o->arg ? o->arg : "");
	else if (o->variant == '-' && o->type == METHOD_OPT_CHOICE)
		PUT("as -VALUE");
	else if (o->variant == '-')
		PUT("as -%s%s", o->name, o->type == METHOD_OPT_BOOL ? "" : o->arg ? o->arg : "");
	if (o->type != METHOD_OPT_BOOL) { /* a flag has no default or range to tell */
		const char *sep = len ? "; " : "";
		if (isnan(o->def))
			PUT("%srequired", sep);
		else if (o->type == METHOD_OPT_CHOICE)
			PUT("%sdefault %s", sep, o->choices[(size_t)o->def]);
		else
			PUT("%sdefault %g", sep, o->def);
		if (o->type == METHOD_OPT_CHOICE) {
			PUT("; ");
			for (size_t k = 0; o->choices[k]; k++)
				PUT("%s%s", k == 0 ? "" : o->choices[k + 1] ? ", " : " or ", o->choices[k]);
		} else if (o->allowed) {
			PUT("; one of ");
			for (size_t k = 0; o->allowed[k]; k++)
				PUT("%s%u", k ? ", " : "", o->allowed[k]);
		} else if (o->min > 0.0 && o->min < 1e-3) { /* a positive lower bound that only excludes 0 */
			PUT("; above 0, at most %g", o->max);
		} else {
			PUT("; %g..%g", o->min, o->max);
		}
	}
#undef PUT
}

size_t method_config_run_options(const method_config *c, run_option *out, size_t max)
{
	size_t n = 0;
	for (size_t i = 0; c->method && i < c->method->option_count && n < max; i++) {
		const method_option *o = &c->method->options[i];
		run_option *r = &out[n++];
		memset(r, 0, sizeof *r);
		r->key = o->name;
		if (o->type == METHOD_OPT_BOOL) {
			r->type = RUN_VALUE_BOOL;
			r->boolean = get_number(c, o) != 0.0;
		} else if (o->type == METHOD_OPT_CHOICE) {
			r->type = RUN_VALUE_STRING;
			r->string = o->choices[(size_t)get_number(c, o)];
		} else {
			r->type = o->type == METHOD_OPT_UINT ? RUN_VALUE_INTEGER : RUN_VALUE_NUMBER;
			r->number = get_number(c, o);
		}
	}
	return n;
}
