/* plot.h (private) — runs a gnuplot script written by the metrics module (plots for people). */
#ifndef TASLAB_METRICS_PLOT_H
#define TASLAB_METRICS_PLOT_H

#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

/* Returns 0, or -1 with "gnuplot failed or is not installed; plots skipped (script: PATH)" in err. */
static inline int mtr_gnuplot(const char *script, char *err, size_t err_size)
{
	char cmd[4200];
	snprintf(cmd, sizeof cmd, "gnuplot '%s' >/dev/null 2>&1", script);
	if (system(cmd) != 0) {
		snprintf(err, err_size, "gnuplot failed or is not installed; plots skipped (script: %s)", script);
		return -1;
	}
	return 0;
}

#endif
