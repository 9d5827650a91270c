/* method_facts.h (private) — run_method_facts (run.h) as JSON, shared by manifest.json (run_writer.c,
 * run_reader.c) and pairs.json (pairs.c) so both files spell them the same way (issue 30.1). */
#ifndef TASLAB_OUTPUT_METHOD_FACTS_H
#define TASLAB_OUTPUT_METHOD_FACTS_H

#include <jansson.h>

#include "taslab/run.h"

/* {"family", "baseline", "reference", "takes_threshold", "takes_period"} (a new reference). */
json_t *method_facts_json(const run_method_facts *f);
/* Reads the object `o` into *f. No object (a file made before the facts were recorded): 0 with f->known false.
 * TL_ERR_INPUT when `o` is there but is not such an object (a field missing or of the wrong type). */
int method_facts_read(const json_t *o, run_method_facts *f);

#endif
