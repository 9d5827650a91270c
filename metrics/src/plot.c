/* plot.c — gnuplot scripts written atomically and run (metrics.h "plots for people"). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/metrics.h"

FILE *mtr_plot_begin(mtr_plot *p, const char *script_path, char *err, size_t err_size)
{
	return tl_atomic_open(&p->file, script_path, err, err_size) ? NULL : p->file.f;
}

int mtr_plot_end(mtr_plot *p, char *err, size_t err_size)
{
	int rc = tl_atomic_commit(&p->file, err, err_size);
	if (rc)
		return rc;
	char cmd[TL_PATH_MAX + 64];
	snprintf(cmd, sizeof cmd, "gnuplot '%s' >/dev/null 2>&1", p->file.path);
	if (strchr(p->file.path, '\'') || system(cmd) != 0)
		return tl_error(err, err_size, TL_ERR_UNSUPPORTED, "gnuplot failed or is not installed; plots skipped (script: %s)",
				p->file.path);
	return TL_OK;
}
