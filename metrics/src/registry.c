/* registry.c — the only list of metric plug-ins (metric.h). Their order is the column order of frames.csv and
 * summary.json (DESIGN section 6): a new metric is one file and one line here, appended at the end. */
#include "metric.h"

extern const mtr_metric mtr_metric_maxrgb, mtr_metric_psnr, mtr_metric_ssim, mtr_metric_flicker, mtr_metric_flip;

const mtr_metric *const mtr_metric_registry[] = {
	&mtr_metric_maxrgb,
	&mtr_metric_psnr,
	&mtr_metric_ssim,
	&mtr_metric_flicker,
	&mtr_metric_flip,
	NULL,
};
