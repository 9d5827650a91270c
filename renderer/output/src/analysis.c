/* analysis.c — names and lifecycle of TFR analysis results (analysis.h). */
#include "taslab/analysis.h"

#include <stdlib.h>

static const char *const predictor_names[ANALYZE_PREDICTORS] = {"single",	   "long",	    "inst",
								  "single_filtered", "long_filtered", "inst_filtered"};
static const char *const class_names[ANALYZE_CLASSES] = {"late", "early", "on_time", "unchanged"};

const char *analyze_predictor_name(int p) { return p >= 0 && p < ANALYZE_PREDICTORS ? predictor_names[p] : "?"; }
const char *analyze_class_name(int c) { return c >= 0 && c < ANALYZE_CLASSES ? class_names[c] : "?"; }

void analyze_result_free(analyze_result *r)
{
	if (!r)
		return;
	free(r->gradients);
	free(r->gradients_filtered);
	r->gradients = r->gradients_filtered = NULL;
}
