/* metric_psnr.c — the `psnr` metric: PSNR = 10 log10(255^2 / MSE), MSE over all pixels and the three channels
 * (DESIGN section 6); identical images give +inf (an empty CSV cell, JSON null). Pooled from the mean MSE. The
 * squared differences come from the shared pass (pixel.c). */
#include <math.h>

#include "metric.h"

static double psnr_of(double mse)
{
	return mse > 0 ? 10.0 * log10(255.0 * 255.0 / mse) : INFINITY;
}

double mtr_psnr(const mtr_image *a, const mtr_image *b)
{
	double sq = 0;
	size_t n = (size_t)a->width * a->height * 3;
	for (size_t i = 0; i < n; i++) {
		double d = (double)a->rgb[i] - (double)b->rgb[i];
		sq += d * d;
	}
	return psnr_of(sq / (double)n);
}

static int psnr_compute(void *state, const mtr_pair *p, mtr_frame_stats *out, char *err, size_t err_size)
{
	(void)state, (void)err, (void)err_size;
	out->mse = p->px->sum_sq / (3.0 * (double)p->a->width * (double)p->a->height);
	out->psnr = psnr_of(out->mse);
	return TL_OK;
}

static void psnr_pool(void *state, const mtr_frame_stats *f, size_t n, mtr_frame_stats *p)
{
	(void)state;
	double mse = 0;
	for (size_t i = 0; i < n; i++)
		mse += f[i].mse;
	p->mse = mse / (double)n;
	p->psnr = psnr_of(p->mse);
}

static const mtr_column psnr_columns[] = {
	{"psnr", offsetof(mtr_frame_stats, psnr), MTR_COL_BOTH},
	{0},
};

const mtr_metric mtr_metric_psnr = {
	.name = "psnr",
	.help = "PSNR over RGB, peak 255 (empty for identical frames)",
	.pixel_pass = MTR_PASS_SQ,
	.columns = psnr_columns,
	.compute = psnr_compute,
	.pool = psnr_pool,
};
