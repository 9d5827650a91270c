/* metric_flicker.c — the `flicker` metric (DESIGN section 6, the temporal difference static metrics miss): for frame
 * t > 0, flicker_mean = mean over pixels of max_c |(a_t - a_t-1) - (b_t - b_t-1)|, the difference of the two
 * sequences' frame-to-frame changes; empty for frame 0. Pooled over the frames that have it. The per-pixel term
 * comes from the shared pass (pixel.c). */
#include <math.h>

#include "metric.h"

static int flicker_compute(void *state, const mtr_pair *p, mtr_frame_stats *out, char *err, size_t err_size)
{
	(void)state, (void)err, (void)err_size;
	out->flicker_mean = p->a_prev ? p->px->sum_flicker / ((double)p->a->width * (double)p->a->height) : NAN;
	return TL_OK;
}

static void flicker_pool(void *state, const mtr_frame_stats *f, size_t n, mtr_frame_stats *p)
{
	(void)state;
	double s = 0;
	size_t k = 0;
	for (size_t i = 0; i < n; i++)
		if (!isnan(f[i].flicker_mean))
			s += f[i].flicker_mean, k++;
	p->flicker_mean = k ? s / (double)k : NAN;
}

static const mtr_column flicker_columns[] = {
	{"flicker_mean", offsetof(mtr_frame_stats, flicker_mean), MTR_COL_BOTH},
	{0},
};

const mtr_metric mtr_metric_flicker = {
	.name = "flicker",
	.help = "temporal difference: mean of max_c |(a_t - a_t-1) - (b_t - b_t-1)| (empty for frame 0)",
	.pixel_pass = MTR_PASS_FLICKER,
	.columns = flicker_columns,
	.compute = flicker_compute,
	.pool = flicker_pool,
};
