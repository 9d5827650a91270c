/* test_study_methods.h — the methods of taslab's registry as the `taslab study` command describes them to a study
 * (cmd_study.c describe_methods; issue 30.1: the study module knows no method by name). The study tests and fuzz
 * harnesses link only the study library, so they describe the same facts from this table. Header-only. */
#ifndef TASLAB_TEST_STUDY_METHODS_H
#define TASLAB_TEST_STUDY_METHODS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "taslab/study.h"

/* Describes ref, tfr, rrc, tarc(-oracle), sa, sau, tasa(-oracle) (DESIGN section 4); 0 or a tl_err code. */
static inline int tu_describe_methods(sty *s)
{
	static const struct {
		const char *name, *family, *baseline;
		bool reference, T, N;
	} m[] = {
		{"ref", "reference", "ref", true, false, false}, {"tfr", "forward", "ref", false, true, false},
		{"rrc", "reprojection", "ref", false, false, true}, {"tarc", "reprojection", "ref", false, true, false},
		{"tarc-oracle", "reprojection", "ref", false, true, false}, {"sa", "atlas", "sa", false, false, false},
		{"sau", "atlas", "sa", false, false, true}, {"tasa", "atlas", "sa", false, true, false},
		{"tasa-oracle", "atlas", "sa", false, true, false},
	};
	char err[256];
	for (size_t i = 0; i < sizeof m / sizeof m[0]; i++) {
		run_method_facts f = {.known = true, .reference = m[i].reference, .takes_threshold = m[i].T,
				      .takes_period = m[i].N};
		snprintf(f.family, sizeof f.family, "%s", m[i].family);
		snprintf(f.baseline, sizeof f.baseline, "%s", m[i].baseline);
		int rc = sty_describe_method(s, m[i].name, &f, err, sizeof err);
		if (rc)
			return rc;
	}
	return 0;
}

#endif
