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

void mtr_plot_svg_preamble(FILE *f, size_t entries)
{
	/* Tableau 10 and six darker tones: distinguishable on white, in print and for the common colour deficiencies
	 * together with the solid (over T) / dashed (fixed variant) line styles the report uses */
	static const char *const colour[16] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
					       "#e377c2", "#7f7f7f", "#bcbd22", "#17becf", "#393b79", "#637939",
					       "#8c6d31", "#843c39", "#7b4173", "#000000"};
	size_t rows = (entries + 2) / 3;
	fprintf(f, "set terminal svg size 460,%zu dynamic font 'sans,10' background rgb 'white'\n"
		   "set key outside bottom center horizontal maxcols 3 font ',9' samplen 2 spacing 1.1 noenhanced\n",
		(size_t)250 + 15 * rows);
	for (int k = 0; k < 32; k++) /* from the 17th line on the colours again, dash-dotted with open points */
		fprintf(f, "set linetype %d lc rgb '%s' lw 2 %s ps 0.8\n", k + 1, colour[k % 16],
			k < 16 ? "dt 1 pt 7" : "dt 4 pt 6");
	fputs("set linetype cycle 32\n", f);
}
