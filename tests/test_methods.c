/* test_methods.c — the method registry, option tables and variant syntax (method.h, DESIGN section 4). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "taslab/method.h"
#include "test_util.h"

static void test_registry(void **state)
{
	(void)state;
	size_t n;
	const method_info *const *m = method_list(&n);
	/* The methods of DESIGN section 4, each listed once, available or planned. */
	const char *design[] = {"ref", "tfr", "rrc", "tarc", "sa", "sau", "tasa"};
	for (size_t i = 0; i < sizeof design / sizeof design[0]; i++) {
		const method_info *x = method_find(design[i]);
		assert_non_null(x);
		assert_non_null(x->summary);
	}
	for (size_t i = 0; i < n; i++) {
		for (size_t j = 0; j < i; j++)
			assert_string_not_equal(m[i]->name, m[j]->name);
		assert_true(m[i]->options_size <= METHOD_OPTIONS_MAX_B);
		for (size_t k = 0; k < m[i]->option_count; k++) { /* tables are well formed */
			const method_option *o = &m[i]->options[k];
			assert_non_null(o->help);
			assert_true(o->offset < m[i]->options_size);
			assert_true(o->type == METHOD_OPT_BOOL || o->type == METHOD_OPT_CHOICE || o->min <= o->def || isnan(o->def));
		}
	}
	for (size_t i = 0; i < sizeof design / sizeof design[0]; i++) /* every method of DESIGN section 4 is in */
		assert_true(method_find(design[i])->available);
	assert_null(method_find("magic"));
}

static void expect_variant(const char *token, const char *variant, const char *name, const char *id, double T,
			   uint32_t N)
{
	char err[256], buf[96];
	method_config c;
	if (method_config_parse_variant(&c, token, err, sizeof err))
		fail_msg("%s: %s", token, err);
	method_config_variant(&c, buf, sizeof buf);
	assert_string_equal(buf, variant);
	method_config_name(&c, buf, sizeof buf);
	assert_string_equal(buf, name);
	method_config_id(&c, buf, sizeof buf);
	assert_string_equal(buf, id);
	if (isnan(T))
		assert_true(isnan(method_config_threshold(&c)));
	else
		assert_true(method_config_threshold(&c) == T);
	assert_int_equal(method_config_period(&c), N);
}

static void test_variants(void **state)
{
	(void)state;
	expect_variant("ref", "ref", "ref", "ref", NAN, 0);
	expect_variant("tfr@8", "tfr@8", "tfr", "tfr-T8", 8, 0);
	expect_variant("tfr@2.5", "tfr@2.5", "tfr", "tfr-T2.5", 2.5, 0);
	expect_variant("rrc/4", "rrc/4", "rrc", "rrc-N4", NAN, 4);
	expect_variant("tarc@8", "tarc@8", "tarc", "tarc-T8", 8, 0);
	expect_variant("tarc-oracle@8", "tarc-oracle@8", "tarc-oracle", "tarc-oracle-T8", 8, 0);
	expect_variant("tarc-oracle@0", "tarc-oracle@0", "tarc-oracle", "tarc-oracle-T0", 0, 0);
	expect_variant("sa", "sa", "sa", "sa", NAN, 0);
	expect_variant("sau/8", "sau/8", "sau", "sau-N8", NAN, 8);
	expect_variant("tasa@16", "tasa@16", "tasa", "tasa-T16", 16, 0);
	expect_variant("tasa-oracle@8", "tasa-oracle@8", "tasa-oracle", "tasa-oracle-T8", 8, 0);
	/* the compacted sample path (BASELINES.md): ads's S with '@' (default 2), the VRS methods without variant values */
	expect_variant("vref", "vref", "vref", "vref", NAN, 0);
	expect_variant("ads", "ads", "ads", "ads", 2, 0);
	expect_variant("ads@8", "ads@8", "ads", "ads-T8", 8, 0);
	expect_variant("ads@-1", "ads@-1", "ads", "ads-T-1", -1, 0);
	expect_variant("casedge", "casedge", "casedge", "casedge", NAN, 0);
	expect_variant("taas", "taas", "taas", "taas", NAN, 0);
	/* a choice written as -VALUE (rrc --payload, BASELINES.md A5); the default is not written */
	expect_variant("rrc-shadow/4", "rrc-shadow/4", "rrc-shadow", "rrc-shadow-N4", NAN, 4);
	expect_variant("rrc-diffuse/2", "rrc-diffuse/2", "rrc-diffuse", "rrc-diffuse-N2", NAN, 2);
	expect_variant("rrc-colour/4", "rrc/4", "rrc", "rrc-N4", NAN, 4);
	char err[256];
	method_config c;
	struct {
		const char *token, *needle;
	} bad[] = {
		{"tfr", "tfr@8"},		  /* the threshold is required in a variant */
		{"ref@8", "takes no '@'"},	  /* ref has no threshold */
		{"tfr@x", "not a number"},	  {"tfr@0", "out of range"},
		{"tfr@8@9", "once"},		  {"tfr-oracle@8", "no '-oracle' form"},
		{"magic@8", "unknown method"},	  {"", "empty"},
		{"sa@8", "takes no '@'"},	  {"tfr/4", "takes no '/'"},
		{"sau", "sau/4"},		  {"tasa", "tasa@8"},
		{"tasa@0", "T > 0"},		  {"sa-oracle", "no '-oracle' form"},
		{"rrc", "rrc/4"},		  {"rrc/3", "3"},
		{"rrc/16", "one of 1, 2, 4, 8"},	  {"rrc-oracle/4", "no '-oracle' form"},
		{"tarc", "tarc@8"},		  {"tarc@0", "T > 0"},
		{"tarc@256", "out of range"},	  {"rrc@8", "takes no '@'"},
		{"ads@300", "out of range"},	  {"ads@-2", "out of range"},
		{"casedge@8", "takes no '@'"},	  {"fovea/4", "takes no '/'"},
		{"vref-oracle", "no '-oracle' form"}, {"mas-oracle", "no '-oracle' form"},
		{"rrc-random-shadow/4", "it has none"}, {"rrc-specular/4", "its '-' forms: -shadow, -diffuse"},
		{"rrc-diffuse-shadow/4", "sets --payload, which the variant sets already"},
	};
	for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
		int rc = method_config_parse_variant(&c, bad[i].token, err, sizeof err);
		if (rc != TL_ERR_ARG && rc != TL_ERR_UNSUPPORTED)
			fail_msg("'%s' parsed (%d)", bad[i].token, rc);
		if (!strstr(err, bad[i].needle))
			fail_msg("'%s': '%s' lacks '%s'", bad[i].token, err, bad[i].needle);
	}
}

/* Every '-' form of every method reads back as itself: a -VALUE choice (rrc-shadow) must not be an option name, another
 * choice's value or, joined to the method, another method's name (rrc-random), which the parser would take first. */
static void test_dash_forms_unambiguous(void **state)
{
	(void)state;
	size_t n;
	const method_info *const *m = method_list(&n);
	int choices = 0;
	for (size_t i = 0; i < n; i++)
		for (size_t k = 0; k < m[i]->option_count; k++) {
			const method_option *o = &m[i]->options[k];
			if (o->variant != '-' || o->type != METHOD_OPT_CHOICE)
				continue;
			for (size_t v = 0; o->choices[v]; v++) {
				char joined[96];
				snprintf(joined, sizeof joined, "%s-%s", m[i]->name, o->choices[v]);
				if (method_find(joined))
					fail_msg("%s: '-%s' reads as the method %s", m[i]->name, o->choices[v], joined);
				for (size_t j = 0; j < m[i]->option_count; j++) {
					const method_option *q = &m[i]->options[j];
					if (!strcmp(q->name, o->choices[v]))
						fail_msg("%s: the choice '%s' is also an option's name", m[i]->name, q->name);
					for (size_t w = 0; q->type == METHOD_OPT_CHOICE && q->variant == '-' && q->choices[w]; w++)
						if ((j != k || w != v) && !strcmp(q->choices[w], o->choices[v]))
							fail_msg("%s: '-%s' belongs to two choices", m[i]->name, o->choices[v]);
				}
				choices++;
			}
		}
	assert_true(choices >= 3); /* rrc's payloads at least */
	/* the list the parser's hint and the study's method names come from (method_dash_forms) */
	static const struct {
		const char *method, *forms;
	} want[] = {{"ref", "ssaa2 ssaa3 ssaa4"}, {"rrc", "shadow diffuse"}, {"tarc", "oracle"}, {"tasa", "oracle"},
		    {"sa", ""}};
	for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
		char forms[8][METHOD_DASH_FORM_B], joined[256] = "";
		size_t k = method_dash_forms(method_find(want[i].method), forms, 8);
		for (size_t j = 0; j < k && j < 8; j++)
			snprintf(joined + strlen(joined), sizeof joined - strlen(joined), "%s%s", j ? " " : "", forms[j]);
		if (strcmp(joined, want[i].forms))
			fail_msg("%s's '-' forms: '%s', expected '%s'", want[i].method, joined, want[i].forms);
	}
	/* every method's forms fit the arrays its callers keep (METHOD_DASH_FORMS_MAX): the study describes each one */
	size_t nm;
	const method_info *const *all = method_list(&nm);
	for (size_t i = 0; i < nm; i++) {
		char forms[METHOD_DASH_FORMS_MAX][METHOD_DASH_FORM_B];
		size_t k = method_dash_forms(all[i], forms, METHOD_DASH_FORMS_MAX);
		if (k > METHOD_DASH_FORMS_MAX)
			fail_msg("%s has %zu '-' forms, more than METHOD_DASH_FORMS_MAX (%d)", all[i]->name, k,
				 METHOD_DASH_FORMS_MAX);
	}
}

static void test_options(void **state)
{
	(void)state;
	char err[256];
	method_config c;
	/* options of the sample-path methods: ads's step from its list, fovea's radii ordered */
	assert_int_equal(method_config_init(&c, "ads", err, sizeof err), TL_OK);
	assert_int_equal(method_config_set(&c, "step", "3", err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "one of 2, 4, 8, 16"));
	assert_int_equal(method_config_init(&c, "fovea", err, sizeof err), TL_OK);
	assert_int_equal(method_config_set(&c, "inner", "30", err, sizeof err), TL_OK);
	assert_int_equal(method_config_check(&c, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "below --inner"));
	assert_int_equal(method_config_set(&c, "gaze-x", "1.5", err, sizeof err), TL_ERR_ARG);
	assert_int_equal(method_config_init(&c, "tfr", err, sizeof err), TL_OK);
	assert_true(method_config_threshold(&c) == 8);		   /* the table's default */
	assert_true(method_config_number(&c, "max-age") == 119); /* K */
	assert_int_equal(method_config_set(&c, "max-age", "3", err, sizeof err), TL_OK);
	assert_int_equal(method_config_set(&c, "max-age", "0", err, sizeof err), TL_ERR_ARG);
	assert_int_equal(method_config_set(&c, "max-age", "3.5", err, sizeof err), TL_ERR_ARG);
	/* Issue 12: whole numbers as digits only, like every count of the command line. */
	const char *not_digits[] = {"3.0", "1e1", "+3", " 3", "0x3"};
	for (size_t i = 0; i < sizeof not_digits / sizeof *not_digits; i++) {
		assert_int_equal(method_config_set(&c, "max-age", not_digits[i], err, sizeof err), TL_ERR_ARG);
		assert_non_null(strstr(err, "not a whole number") ? err : strstr(err, "not a number"));
	}
	assert_int_equal(method_config_set(&c, "period", "4", err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "not an option of tfr") ? err : strstr(err, "no option"));
	/* Manifest entries: every option, defaults included. */
	run_option o[8];
	size_t n = method_config_run_options(&c, o, 8);
	assert_int_equal(n, 3);
	assert_string_equal(o[0].key, "threshold");
	assert_true(o[2].type == RUN_VALUE_BOOL && !o[2].boolean); /* truth */
	assert_true(o[1].type == RUN_VALUE_INTEGER && o[1].number == 3); /* a uint option: a JSON integer (24.8) */
	assert_int_equal(method_config_init(&c, "ref", err, sizeof err), TL_OK);
	assert_int_equal(method_config_run_options(&c, o, 8), 1); /* --ssaa K (BASELINES.md A3), default 1 */
	assert_string_equal(o[0].key, "ssaa");
	assert_true(o[0].type == RUN_VALUE_INTEGER && o[0].number == 1);
	assert_int_equal(method_config_set(&c, "threshold", "8", err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "it applies to: tfr, tarc"));
	/* tarc: the cross-option check (method_info.check) */
	assert_int_equal(method_config_init(&c, "tarc", err, sizeof err), TL_OK);
	assert_int_equal(method_config_set(&c, "threshold", "0", err, sizeof err), TL_OK); /* in range for the oracle */
	assert_int_equal(method_config_check(&c, err, sizeof err), TL_ERR_ARG);
	assert_non_null(strstr(err, "T > 0"));
	assert_int_equal(method_config_set(&c, "oracle", "true", err, sizeof err), TL_OK);
	assert_int_equal(method_config_check(&c, err, sizeof err), TL_OK);
	assert_true(method_config_number(&c, "max-age") == 0); /* no age limit unless asked (the paper has none) */
}

int main(void)
{
	const struct CMUnitTest tests[] = {
		cmocka_unit_test(test_registry),
		cmocka_unit_test(test_variants),
		cmocka_unit_test(test_dash_forms_unambiguous),
		cmocka_unit_test(test_options),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
