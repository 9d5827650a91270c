/* method_facts.c — run_method_facts as JSON (method_facts.h). */
#include "method_facts.h"
#include "taslab/tl_error.h"

#include <stdio.h>
#include <string.h>

json_t *method_facts_json(const run_method_facts *f)
{
	return json_pack("{s:s, s:s, s:b, s:b, s:b}", "family", f->family, "baseline", f->baseline, "reference",
			 f->reference, "takes_threshold", f->takes_threshold, "takes_period", f->takes_period);
}

int method_facts_read(const json_t *o, run_method_facts *f)
{
	memset(f, 0, sizeof *f);
	if (!o)
		return 0;
	const char *family = json_string_value(json_object_get(o, "family"));
	const char *baseline = json_string_value(json_object_get(o, "baseline"));
	const json_t *ref = json_object_get(o, "reference"), *T = json_object_get(o, "takes_threshold");
	const json_t *N = json_object_get(o, "takes_period");
	if (!json_is_object(o) || !family || !baseline || strlen(family) >= sizeof f->family ||
	    strlen(baseline) >= sizeof f->baseline || !json_is_boolean(ref) || !json_is_boolean(T) || !json_is_boolean(N))
		return TL_ERR_INPUT;
	snprintf(f->family, sizeof f->family, "%s", family);
	snprintf(f->baseline, sizeof f->baseline, "%s", baseline);
	f->reference = json_is_true(ref);
	f->takes_threshold = json_is_true(T);
	f->takes_period = json_is_true(N);
	f->known = true;
	return 0;
}
