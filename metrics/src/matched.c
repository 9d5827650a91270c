/* matched.c — the matched-budget pairs of a sweep (metrics_matched.h; BASELINES.md section 0 "Comparison"). */
#include "taslab/metrics_matched.h"

#include <math.h>
#include <string.h>

bool mtr_match_is_tas(const char *family, bool takes_threshold)
{
	/* [TAS] reuses shading across frames by a threshold T: by reprojection (tarc) or in the atlas (tasa). ads also
	 * takes a threshold (@S, its refinement variance), but it is a deferred method: an alternative, not TAS. */
	return takes_threshold && family && (!strcmp(family, "reprojection") || !strcmp(family, "atlas"));
}

static bool usable(const mtr_match_item *x)
{
	return x->group && x->method && !x->reference && isfinite(x->shaded);
}

size_t mtr_match_budget(const mtr_match_item *in, size_t n, mtr_match_pair *out, size_t cap)
{
	size_t count = 0;
	for (size_t t = 0; t < n; t++) {
		if (!in[t].tas || !usable(&in[t]))
			continue;
		for (size_t m = 0; m < n; m++) {
			const mtr_match_item *o = &in[m];
			if (o->tas || !usable(o) || strcmp(o->group, in[t].group))
				continue;
			bool first = true; /* m is the method's first item in this group */
			for (size_t k = 0; k < m && first; k++)
				first = !(!in[k].tas && usable(&in[k]) && !strcmp(in[k].group, o->group) &&
					  !strcmp(in[k].method, o->method));
			if (!first)
				continue;
			size_t best = m;
			for (size_t k = m + 1; k < n; k++)
				if (!in[k].tas && usable(&in[k]) && !strcmp(in[k].group, o->group) &&
				    !strcmp(in[k].method, o->method) &&
				    fabs(in[k].shaded - in[t].shaded) < fabs(in[best].shaded - in[t].shaded))
					best = k;
			if (count < cap && out)
				out[count] = (mtr_match_pair){t, best};
			count++;
		}
	}
	return count;
}
