/* flip.c — LDR-FLIP image difference (metrics_flip.h; the `flip` metric plug-in is metric_flip.c), written from
 * the paper:
 *
 *   P. Andersson, J. Nilsson, T. Akenine-Möller, M. Oskarsson, K. Åström, M. D. Fairchild,
 *   "FLIP: A Difference Evaluator for Alternating Images", Proc. ACM CGIT 3(2), 2020 (HPG 2020),
 *
 * with the refinements of NVIDIA's public FLIP releases (v1.6 is the reference for the tests). Comments cite the
 * paper's pipeline stages by name: "colour pipeline" (spatial filtering, perceptual uniform colour space, Hunt
 * adjustment, HyAB, colour-difference re-mapping), "feature pipeline" (edge and point detection, feature difference)
 * and "final error" (combination of the two), plus "pooling" for the statistics.
 *
 * Pipeline per pixel (both images unless stated):
 *   1. sRGB (0..255) -> linear RGB (sRGB EOTF) -> XYZ (D65) -> YyCxCz opponent space (linearised CIELAB):
 *        Yy = 116 Y/Yn - 16, Cx = 500 (X/Xn - Y/Yn), Cz = 200 (Y/Yn - Z/Zn).
 *   2. Spatial filtering of each opponent channel with the contrast sensitivity function of that channel
 *      (colour pipeline, "spatial filtering"). The CSFs are (sums of) Gaussians in frequency,
 *        S(f) = a1 exp(-b1 f^2) + a2 exp(-b2 f^2),
 *      whose spatial-domain counterparts are Gaussians a sqrt(pi/b) exp(-pi^2 x^2 / b), x in degrees
 *      (x = pixel offset / ppd). Constants: achromatic a1=1, b1=0.0047; red-green a1=1, b1=0.0053; blue-yellow
 *      a1=34.1, b1=0.04, a2=13.5, b2=0.025. Kernel radius = ceil(3 * sqrt(max b / (2 pi^2)) * ppd) (3 standard
 *      deviations of the widest Gaussian). The 2D kernel is sum_i a_i sqrt(pi/b_i) exp(-pi^2 r^2 / b_i) normalised
 *      to unit sum (as in FLIP v1.x); each term is separable, so the blue-yellow channel is filtered as the sum of two
 *      separable passes with 1D kernels sqrt(a_i sqrt(pi/b_i)) exp(-pi^2 x^2 / b_i), normalised jointly.
 *   3. Back to linear RGB, clamp to [0,1] (colour pipeline: keeps filtered colours inside the display gamut),
 *      to CIELAB (D65), Hunt adjustment a' = 0.01 L a, b' = 0.01 L b (colour pipeline, "Hunt effect").
 *   4. HyAB distance |dL| + sqrt(da'^2 + db'^2), raised to q_c = 0.7, and re-mapped to [0,1] with the
 *      compression function of the paper (p_c = 0.4, p_t = 0.95), normalised by c_max = HyAB(Hunt(green),
 *      Hunt(blue))^q_c, the largest difference between two colours of the sRGB gamut after the Hunt adjustment.
 *   5. Feature pipeline on the achromatic channel normalised to [0,1], (Yy + 16) / 116 = Y/Yn (linear luminance):
 *      edges = first derivative of a Gaussian, points = second derivative, sigma = 0.5 * 0.082 * ppd pixels,
 *      radius ceil(3 sigma); positive weights of each derivative kernel sum to 1, negative weights to -1 (the
 *      Gaussian itself sums to 1). Edge/point magnitudes are |(d/dx, d/dy)|; the feature difference is
 *        dE_f = ( max(| |e_r| - |e_t| |, | |p_r| - |p_t| |) / sqrt(2) )^q_f,  q_f = 0.5.
 *   6. Final error dE = dE_c^(1 - dE_f).
 * Borders: clamp-to-edge (pixel indices outside the image take the nearest edge pixel), for every filter. Determined
 * empirically: with clamp-to-edge a double-precision direct-2D-convolution version matches the reference means to
 * ~1e-9, while mirror (with or without edge repeat) and zero padding are off by 3e-4..8e-3.
 *
 * Implementation: the row kernels (colour conversion, the separable filter passes, CIELAB, the final error) and
 * how they are made fast are in flip_rows.c; this file creates the filter object, runs the bands of rows on
 * threads through a ring of converted rows per column strip, and pools the statistics.
 */
#include "taslab/metrics_flip.h"
#include "taslab/tl_error.h"

#include "flip_internal.h"
#include "flip_math.h"

#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Maximum number of output columns processed per strip. */
#define STRIP_W 512
/* Largest accepted pixels-per-degree value (kernel radius ~0.135 ppd; scratch memory grows with its square). */
#define FLIP_MAX_PPD 1000.0
/* Largest accepted thread count. */
#define FLIP_MAX_THREADS 256

/* ---- constants (paper: colour pipeline) ---- */

/* CSF parameters per opponent channel (achromatic, red-green, blue-yellow). */
static const double CSF_A1[3] = {1.0, 1.0, 34.1};
static const double CSF_B1[3] = {0.0047, 0.0053, 0.04};
static const double CSF_A2[3] = {0.0, 0.0, 13.5};
static const double CSF_B2[3] = {1e-5, 1e-5, 0.025};


/* Linear sRGB -> XYZ (D65), exact rational form of the IEC 61966-2-1 matrix. */
static const double RGB2XYZ[9] = {
    10135552.0 / 24577794.0, 8788810.0 / 24577794.0, 4435075.0 / 24577794.0,
    2613072.0 / 12288897.0,  8788810.0 / 12288897.0, 887015.0 / 12288897.0,
    1425312.0 / 73733382.0,  8788810.0 / 73733382.0, 70074185.0 / 73733382.0,
};

/* (the filter object, struct mtr_flip, and the plane layout: flip_internal.h) */

static void set_err(char *err, size_t err_size, const char *fmt, ...)
{
	if (!err || err_size == 0)
		return;
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(err, err_size, fmt, ap);
	va_end(ap);
}

/* ---- double-precision helpers used only at set-up ---- */

static void mat3_inv(const double *a, double *o)
{
	double c00 = a[4] * a[8] - a[5] * a[7], c01 = a[5] * a[6] - a[3] * a[8], c02 = a[3] * a[7] - a[4] * a[6];
	double det = a[0] * c00 + a[1] * c01 + a[2] * c02;
	o[0] = c00 / det;
	o[1] = (a[2] * a[7] - a[1] * a[8]) / det;
	o[2] = (a[1] * a[5] - a[2] * a[4]) / det;
	o[3] = c01 / det;
	o[4] = (a[0] * a[8] - a[2] * a[6]) / det;
	o[5] = (a[2] * a[3] - a[0] * a[5]) / det;
	o[6] = c02 / det;
	o[7] = (a[1] * a[6] - a[0] * a[7]) / det;
	o[8] = (a[0] * a[4] - a[1] * a[3]) / det;
}

static void mat3_mul(const double *a, const double *b, double *o)
{
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			o[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

/* CIELAB companding function f(t). */
static double lab_f(double t)
{
	const double d = 6.0 / 29.0;
	return t > d * d * d ? cbrt(t) : t / (3.0 * d * d) + 4.0 / 29.0;
}

/* Linear RGB -> Hunt-adjusted CIELAB (colour pipeline, Hunt effect), double precision. */
static void rgb_to_hunt_lab(const double rgb[3], double lab[3])
{
	double white[3], xyz[3];
	for (int i = 0; i < 3; i++) {
		white[i] = RGB2XYZ[3 * i] + RGB2XYZ[3 * i + 1] + RGB2XYZ[3 * i + 2];
		xyz[i] = RGB2XYZ[3 * i] * rgb[0] + RGB2XYZ[3 * i + 1] * rgb[1] + RGB2XYZ[3 * i + 2] * rgb[2];
	}
	double fx = lab_f(xyz[0] / white[0]), fy = lab_f(xyz[1] / white[1]), fz = lab_f(xyz[2] / white[2]);
	double L = 116.0 * fy - 16.0;
	lab[0] = L;
	lab[1] = 0.01 * L * 500.0 * (fx - fy);
	lab[2] = 0.01 * L * 200.0 * (fy - fz);
}

/* ---- creation ---- */

/* Number of taps of the half kernel w[0..r] (unit sum over -r..r) that matter in single precision: the outer taps
 * are dropped while their total weight on both sides stays below 2^-27 of the kernel's (7.5e-9: less than a
 * float's rounding of any filtered value, whose magnitude is at most ~1; the 2D kernel loses at most twice that). */
static int kernel_reach(const float *w, int r)
{
	double total = w[0], tail = 0.0;
	for (int k = 1; k <= r; k++)
		total += 2.0 * w[k];
	int n = r;
	while (n > 0 && tail + 2.0 * w[n] <= 0x1p-27 * total) {
		tail += 2.0 * w[n];
		n--;
	}
	return n;
}

int mtr_flip_create(double ppd, mtr_flip **out, char *err, size_t err_size)
{
	if (!out) {
		set_err(err, err_size, "flip: NULL output pointer");
		return TL_ERR_ARG;
	}
	*out = NULL;
	if (!(ppd > 0.0) || !(ppd <= FLIP_MAX_PPD)) {
		set_err(err, err_size, "flip: pixels per degree must be in (0, %g], got %g", FLIP_MAX_PPD, ppd);
		return TL_ERR_ARG;
	}
	/* Colour pipeline, spatial filtering: radius = 3 standard deviations of the widest spatial Gaussian; the
	 * Gaussian exp(-pi^2 x^2 / b) has variance b / (2 pi^2). */
	double bmax = 0.0;
	for (int c = 0; c < 3; c++) {
		bmax = fmax(bmax, CSF_B1[c]);
		bmax = fmax(bmax, CSF_B2[c]);
	}
	int r = (int)ceil(3.0 * sqrt(bmax / (2.0 * M_PI * M_PI)) * ppd);
	/* Feature pipeline: sigma = 0.5 * 0.082 degrees, in pixels; radius 3 sigma. */
	double sd = 0.5 * FLIP_GW * ppd;
	int fr = (int)ceil(3.0 * sd);
	int R = r > fr ? r : fr;

	mtr_flip *f = calloc(1, sizeof *f);
	float *kern = f ? calloc(7 * (size_t)(R + 1), sizeof(float)) : NULL;
	if (!kern) {
		free(f);
		set_err(err, err_size, "flip: out of memory");
		return TL_ERR_NOMEM;
	}
	f->ppd = ppd;
	f->r = r;
	f->fr = fr;
	f->R = R;
	f->wy = kern;
	f->wcx = kern + (R + 1);
	f->wcz1 = kern + 2 * (R + 1);
	f->wcz2 = kern + 3 * (R + 1);
	f->fg = kern + 4 * (R + 1);
	f->fdg = kern + 5 * (R + 1);
	f->fddg = kern + 6 * (R + 1);

	/* CSF kernels. For each channel the 2D kernel sum_i a_i sqrt(pi/b_i) exp(-pi^2 |x|^2 / b_i) is normalised to
	 * unit sum; with the separable 1D factors g_i(x) = sqrt(a_i sqrt(pi/b_i)) exp(-pi^2 x^2 / b_i) the 2D sum is
	 * sum_i (sum_x g_i(x))^2, so each 1D factor is divided by the square root of that. */
	double *g1 = malloc(3 * (size_t)(R + 1) * sizeof(double));
	if (!g1) {
		free(kern);
		free(f);
		set_err(err, err_size, "flip: out of memory");
		return TL_ERR_NOMEM;
	}
	double *g2 = g1 + (R + 1), *g = g2 + (R + 1);
	float *w1[3] = {f->wy, f->wcx, f->wcz1};
	for (int c = 0; c < 3; c++) {
		double s1 = 0.0, s2 = 0.0;
		for (int k = 0; k <= R; k++) {
			double x = k / ppd, x2 = x * x;
			g1[k] = k <= r ? sqrt(CSF_A1[c] * sqrt(M_PI / CSF_B1[c])) * exp(-M_PI * M_PI * x2 / CSF_B1[c]) : 0.0;
			g2[k] = k <= r ? sqrt(CSF_A2[c] * sqrt(M_PI / CSF_B2[c])) * exp(-M_PI * M_PI * x2 / CSF_B2[c]) : 0.0;
			s1 += (k ? 2.0 : 1.0) * g1[k];
			s2 += (k ? 2.0 : 1.0) * g2[k];
		}
		double norm = 1.0 / sqrt(s1 * s1 + s2 * s2);
		for (int k = 0; k <= R; k++) {
			w1[c][k] = (float)(g1[k] * norm);
			if (c == 2)
				f->wcz2[k] = (float)(g2[k] * norm);
		}
	}

	/* The achromatic and red-green Gaussians are narrow (sigma ~1.0 and ~1.1 pixels at 67 ppd) but get the
	 * blue-yellow radius; their outer taps are cut where they can no longer change a single-precision result. */
	f->ry = kernel_reach(f->wy, r);
	f->rx = kernel_reach(f->wcx, r);
	for (int k = f->ry + 1; k <= R; k++)
		f->wy[k] = 0.0f;
	for (int k = f->rx + 1; k <= R; k++)
		f->wcx[k] = 0.0f;

	/* Feature kernels (feature pipeline): Gaussian g, -x g, (x^2/sigma^2 - 1) g. The 2D detectors are products
	 * with a Gaussian in the other direction; normalising g to unit sum and the positive / negative lobes of the
	 * derivatives to +1 / -1 in 1D gives the same 2D normalisation. */
	{
		double gs = 0.0, dpos = 0.0, ddpos = 0.0, ddneg = 0.0;
		for (int k = 0; k <= R; k++) {
			g[k] = k <= fr ? exp(-(double)k * k / (2.0 * sd * sd)) : 0.0;
			gs += (k ? 2.0 : 1.0) * g[k];
			dpos += k * g[k]; /* positive lobe of -x g lies at x = -k */
			double dd = ((double)k * k / (sd * sd) - 1.0) * g[k];
			if (dd > 0.0)
				ddpos += (k ? 2.0 : 1.0) * dd;
			else
				ddneg -= (k ? 2.0 : 1.0) * dd;
		}
		for (int k = 0; k <= R; k++) {
			double dd = ((double)k * k / (sd * sd) - 1.0) * g[k];
			f->fg[k] = (float)(g[k] / gs);
			f->fdg[k] = dpos > 0.0 ? (float)(-k * g[k] / dpos) : 0.0f;
			f->fddg[k] = (float)(dd > 0.0 ? dd / ddpos : (ddneg > 0.0 ? dd / ddneg : 0.0));
		}
	}
	free(g1);

	/* Colour transforms folded into 3x3 matrices. White point Xn, Yn, Zn = XYZ of linear RGB (1,1,1). */
	double white[3], xyz2rgb[9], m[9], opp2xyz[9], tmp[9];
	for (int i = 0; i < 3; i++)
		white[i] = RGB2XYZ[3 * i] + RGB2XYZ[3 * i + 1] + RGB2XYZ[3 * i + 2];
	mat3_inv(RGB2XYZ, xyz2rgb);
	for (int j = 0; j < 3; j++) {
		double xn = RGB2XYZ[j] / white[0], yn = RGB2XYZ[3 + j] / white[1], zn = RGB2XYZ[6 + j] / white[2];
		m[j] = yn;          /* Yy channel, stored as Y/Yn = (Yy + 16) / 116 */
		m[3 + j] = xn - yn; /* Cx / 500 */
		m[6 + j] = yn - zn; /* Cz / 200 */
		f->rgb2xyzn[j] = (float)xn;
		f->rgb2xyzn[3 + j] = (float)yn;
		f->rgb2xyzn[6 + j] = (float)zn;
	}
	for (int i = 0; i < 9; i++)
		f->lin2opp[i] = (float)m[i];
	/* (Y/Yn, X/Xn - Y/Yn, Y/Yn - Z/Zn) -> XYZ: X = Xn (cx + y), Y = Yn y, Z = Zn (y - cz). */
	const double o2x[9] = {white[0], white[0], 0.0, white[1], 0.0, 0.0, white[2], 0.0, -white[2]};
	memcpy(opp2xyz, o2x, sizeof o2x);
	mat3_mul(xyz2rgb, opp2xyz, tmp);
	for (int i = 0; i < 9; i++)
		f->opp2rgb[i] = (float)tmp[i];

	/* Colour pipeline, re-mapping: c_max = HyAB(Hunt(green), Hunt(blue))^q_c. */
	{
		const double green[3] = {0.0, 1.0, 0.0}, blue[3] = {0.0, 0.0, 1.0};
		double lg[3], lb[3];
		rgb_to_hunt_lab(green, lg);
		rgb_to_hunt_lab(blue, lb);
		double hy = fabs(lg[0] - lb[0]) + hypot(lg[1] - lb[1], lg[2] - lb[2]);
		double cmax = pow(hy, FLIP_QC);
		f->cmax_lo = (float)(FLIP_PC * cmax);
		f->slope_lo = (float)(FLIP_PT / (FLIP_PC * cmax));
		f->log2_slope_lo = (float)log2(FLIP_PT / (FLIP_PC * cmax));
		f->slope_hi = (float)((1.0 - FLIP_PT) / (cmax - FLIP_PC * cmax));
	}
	*out = f;
	return 0;
}

void mtr_flip_destroy(mtr_flip **f)
{
	if (!f || !*f)
		return;
	free((*f)->wy);
	free(*f);
	*f = NULL;
}

/* ---- per-thread work ---- */

typedef struct {
	const mtr_flip *f;
	uint32_t W, H;
	const float *img[2]; /* ref, test */
	float *map;          /* may be NULL */
	mtr_flip_row_fn row_fn; /* may be NULL */
	void *row_ctx;
	int band;
	uint32_t y0, y1;     /* band of output rows */
	double sum;          /* sum of the band's error values */
	int status;          /* 0 or negative */
} band_job;

/* Per-thread scratch. Planes are rows of `swp` floats. */
typedef struct {
	size_t swp;
	float *ring; /* (2R+2) row slots x 2 images x 3 opponent planes (Y/Yn, Cx/500, Cz/200) */
	float *vbuf; /* 2 output rows x 2 images x V_N vertically filtered planes */
	float *hbuf; /* 2 images x H_N planes: filtered Y, Cx, Cz, edge/point responses, then L, a', b' */
	float *err;  /* one row of errors */
	float *lin;  /* one row of linear RGB, interleaved (3 swp floats) */
} scratch;


static inline float *ring_plane(const scratch *s, int R, uint32_t src_row, int im, int plane)
{
	size_t slot = src_row % (uint32_t)(2 * R + 2);
	return s->ring + ((slot * 2 + (size_t)im) * 3 + (size_t)plane) * s->swp;
}


static size_t round_up(size_t v, size_t m)
{
	return (v + m - 1) / m * m;
}

/* Sum of a row of errors in double, in 8 independent partial sums (a single running sum is a chain of dependent
 * adds, 4 cycles per pixel; the lanes vectorise). A fixed order: the same row gives the same bits. */
static double row_sum(const float *e, size_t n)
{
	double acc[8] = {0};
	size_t i = 0;
	for (; i + 8 <= n; i += 8)
		for (int u = 0; u < 8; u++)
			acc[u] += (double)e[i + (size_t)u];
	double s = 0.0;
	for (; i < n; i++)
		s += (double)e[i];
	for (int u = 0; u < 8; u++)
		s += acc[u];
	return s;
}

static void *band_worker(void *arg)
{
	band_job *job = arg;
	const mtr_flip *f = job->f;
	const int R = f->R;
	const uint32_t W = job->W, H = job->H;
	const uint32_t sw_max = W < STRIP_W ? W : STRIP_W;
	scratch s;
	s.swp = round_up(round_up(sw_max, VW) + 2 * (size_t)R, VW);
	s.ring = calloc((size_t)(2 * R + 2) * 6 * s.swp, sizeof(float));
	s.vbuf = calloc(2 * 2 * V_N * s.swp, sizeof(float));
	s.hbuf = calloc(2 * H_N * s.swp, sizeof(float));
	s.err = calloc(s.swp, sizeof(float));
	s.lin = calloc(3 * s.swp, sizeof(float));
	float **rp = malloc(sizeof(float *) * 6 * (size_t)(2 * R + 2));
	job->sum = 0.0;
	if (!s.ring || !s.vbuf || !s.hbuf || !s.err || !s.lin || !rp) {
		job->status = -2;
		goto done;
	}
	for (uint32_t x0 = 0; x0 < W; x0 += sw_max) {
		const uint32_t x1 = x0 + sw_max < W ? x0 + sw_max : W;
		const size_t sw = x1 - x0;
		/* Buffer index j holds image column x0 - R + j; columns [cx0, cx1) exist in the image, at buffer
		 * indices [jv0, jv1). */
		const int64_t ox0 = (int64_t)x0 - R;
		const uint32_t cx0 = ox0 > 0 ? (uint32_t)ox0 : 0u;
		const uint32_t cx1 = (uint64_t)x1 + (uint64_t)R < W ? x1 + (uint32_t)R : W;
		const size_t jv0 = (size_t)((int64_t)cx0 - ox0), jv1 = jv0 + (cx1 - cx0);
		const size_t ja = jv0 / VW * VW, jb = round_up(jv1, VW);
		const size_t swr = round_up(sw, VW);
		uint32_t next_src = job->y0 > (uint32_t)R ? job->y0 - (uint32_t)R : 0u;
		/* Output rows two at a time (flip_vertical_pass). */
		for (uint32_t y = job->y0; y < job->y1; y += 2) {
			const uint32_t nrows = y + 1 < job->y1 ? 2u : 1u;
			/* Convert the input rows that enter the vertical windows of the rows (clamped to the image). */
			const uint64_t want = (uint64_t)y + (nrows - 1) + (uint64_t)R;
			const uint32_t last = want < H ? (uint32_t)want : H - 1;
			for (; next_src <= last; next_src++)
				for (int im = 0; im < 2; im++) {
					/* The strip's part of the row after this one is not a stream the hardware prefetcher
					 * follows (one image row apart): fetch it while this row is converted. */
					if (next_src + 1 < H) {
						const char *nx = (const char *)(job->img[im] + ((size_t)(next_src + 1) * W + cx0) * 3);
						for (size_t b = 0; b < (size_t)(cx1 - cx0) * 3 * sizeof(float); b += 64)
							__builtin_prefetch(nx + b);
					}
					flip_convert_row(f, job->img[im] + ((size_t)next_src * W + cx0) * 3, cx1 - cx0, s.lin,
					            ring_plane(&s, R, next_src, im, 0) + jv0, ring_plane(&s, R, next_src, im, 1) + jv0,
					            ring_plane(&s, R, next_src, im, 2) + jv0);
				}
			for (int im = 0; im < 2; im++) {
				float **ry = rp + (size_t)(3 * im) * (size_t)(2 * R + 2);
				float **rcx = ry + (2 * R + 2), **rcz = rcx + (2 * R + 2);
				for (int k = 0; k < 2 * R + (int)nrows; k++) {
					int64_t sy = (int64_t)y - R + k; /* clamp-to-edge rows */
					uint32_t cy = sy < 0 ? 0u : (sy >= (int64_t)H ? H - 1 : (uint32_t)sy);
					ry[k] = ring_plane(&s, R, cy, im, 0);
					rcx[k] = ring_plane(&s, R, cy, im, 1);
					rcz[k] = ring_plane(&s, R, cy, im, 2);
				}
				float *vo[2][V_N];
				for (uint32_t t = 0; t < 2; t++)
					for (int pl = 0; pl < V_N; pl++)
						vo[t][pl] = s.vbuf + ((size_t)(2 * im + (int)t) * V_N + (size_t)pl) * s.swp;
				if (nrows == 1) { /* a band's odd last row: the pair's second row is computed and not used */
					ry[2 * R + 1] = ry[2 * R];
					rcx[2 * R + 1] = rcx[2 * R];
					rcz[2 * R + 1] = rcz[2 * R];
				}
				flip_vertical_pass(f, ry, rcx, rcz, ja, jb, vo[0], vo[1]);
			}
			for (uint32_t t = 0; t < nrows; t++) {
				const uint32_t yt = y + t;
				for (int im = 0; im < 2; im++) {
					float *v = s.vbuf + (size_t)(2 * im + (int)t) * V_N * s.swp;
					/* Clamp-to-edge columns: replicate the first / last image column into the halo. */
					for (int pl = 0; pl < V_N; pl++) {
						float *row = v + (size_t)pl * s.swp;
						for (size_t j = 0; j < jv0; j++)
							row[j] = row[jv0];
						for (size_t j = jv1; j < swr + 2 * (size_t)R; j++)
							row[j] = row[jv1 - 1];
					}
					flip_horizontal_pass(f, v, s.swp, swr, s.hbuf + (size_t)im * H_N * s.swp);
				}
				for (int im = 0; im < 2; im++) {
					float *h = s.hbuf + (size_t)im * H_N * s.swp;
					flip_hunt_lab_row(f, h + H_Y * s.swp, h + H_CX * s.swp, h + H_CZ * s.swp, h + H_L * s.swp,
					             h + H_A * s.swp, h + H_B * s.swp, swr);
				}
				flip_finalize_row(f, s.hbuf, s.hbuf + H_N * s.swp, s.swp, swr, s.err);
				job->sum += row_sum(s.err, sw);
				if (job->map)
					memcpy(job->map + (size_t)yt * W + x0, s.err, sw * sizeof(float));
				if (job->row_fn)
					job->row_fn(job->row_ctx, job->band, yt, x0, s.err, sw);
			}
		}
	}
	job->status = 0;
done:
	free(s.ring);
	free(s.vbuf);
	free(s.hbuf);
	free(s.err);
	free(s.lin);
	free(rp);
	return NULL;
}

int mtr_flip_compute(const mtr_flip *f, uint32_t width, uint32_t height, const float *ref_rgb, const float *test_rgb,
                     float *map, int threads, double *mean, char *err, size_t err_size)
{
	return mtr_flip_compute_rows(f, width, height, ref_rgb, test_rgb, map, NULL, NULL, threads, mean, err, err_size);
}

int mtr_flip_compute_rows(const mtr_flip *f, uint32_t width, uint32_t height, const float *ref_rgb,
                          const float *test_rgb, float *map, mtr_flip_row_fn row_fn, void *row_ctx, int threads,
                          double *mean, char *err, size_t err_size)
{
	if (!f || !ref_rgb || !test_rgb || !mean) {
		set_err(err, err_size, "flip: NULL argument");
		return TL_ERR_ARG;
	}
	if (width == 0 || height == 0) {
		set_err(err, err_size, "flip: empty image (%ux%u)", (unsigned)width, (unsigned)height);
		return TL_ERR_ARG;
	}
	if (width > INT32_MAX || height > INT32_MAX ||
	    (uint64_t)width * height > (uint64_t)(SIZE_MAX / (3 * sizeof(float)))) {
		set_err(err, err_size, "flip: image too large (%ux%u)", (unsigned)width, (unsigned)height);
		return TL_ERR_ARG;
	}
	if (threads <= 0) {
		long nc = sysconf(_SC_NPROCESSORS_ONLN);
		threads = nc > 0 ? (int)(nc < FLIP_MAX_THREADS ? nc : FLIP_MAX_THREADS) : 1;
	}
	if (threads > FLIP_MAX_THREADS)
		threads = FLIP_MAX_THREADS;
	/* Bands of at least 16 rows; halo rows are converted twice, so tiny bands would waste work. */
	uint32_t max_bands = height / 16 > 0 ? height / 16 : 1;
	uint32_t nb = (uint32_t)threads < max_bands ? (uint32_t)threads : max_bands;
	band_job *jobs = calloc(nb, sizeof *jobs);
	pthread_t *tid = calloc(nb, sizeof *tid);
	int *started = calloc(nb, sizeof *started);
	if (!jobs || !tid || !started) {
		free(jobs);
		free(tid);
		free(started);
		set_err(err, err_size, "flip: out of memory");
		return TL_ERR_NOMEM;
	}
	for (uint32_t b = 0; b < nb; b++) {
		jobs[b].f = f;
		jobs[b].W = width;
		jobs[b].H = height;
		jobs[b].img[0] = ref_rgb;
		jobs[b].img[1] = test_rgb;
		jobs[b].map = map;
		jobs[b].row_fn = row_fn;
		jobs[b].row_ctx = row_ctx;
		jobs[b].band = (int)b;
		jobs[b].y0 = (uint32_t)((uint64_t)height * b / nb);
		jobs[b].y1 = (uint32_t)((uint64_t)height * (b + 1) / nb);
		jobs[b].status = -1;
	}
	for (uint32_t b = 1; b < nb; b++)
		started[b] = pthread_create(&tid[b], NULL, band_worker, &jobs[b]) == 0;
	band_worker(&jobs[0]);
	for (uint32_t b = 1; b < nb; b++) {
		if (started[b])
			pthread_join(tid[b], NULL);
		else
			band_worker(&jobs[b]); /* thread creation failed: do the band here */
	}
	double sum = 0.0;
	int status = 0;
	for (uint32_t b = 0; b < nb; b++) {
		sum += jobs[b].sum;
		if (jobs[b].status < 0)
			status = jobs[b].status;
	}
	free(jobs);
	free(tid);
	free(started);
	if (status < 0) {
		set_err(err, err_size, "flip: out of memory");
		return TL_ERR_NOMEM;
	}
	*mean = sum / ((double)width * (double)height);
	return 0;
}

/* ---- pooling ---- */

/* Order-preserving unsigned key of a float (negative values reversed, NaN sorts last). */
static inline uint32_t sort_key(float v)
{
	uint32_t u = float_to_bits(v);
	return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

int mtr_flip_pool_stats(const float *map, size_t n, mtr_flip_pool *out)
{
	if (!map || !out || n == 0)
		return TL_ERR_ARG;
	uint32_t *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
	if (!a || !b) {
		free(a);
		free(b);
		return TL_ERR_NOMEM;
	}
	double sum = 0.0;
	for (size_t i = 0; i < n; i++) {
		a[i] = sort_key(map[i]);
		sum += (double)map[i];
	}
	/* LSD radix sort, 3 passes of 11 bits. */
	for (int pass = 0; pass < 3; pass++) {
		const int shift = 11 * pass;
		size_t cnt[2048] = {0};
		for (size_t i = 0; i < n; i++)
			cnt[(a[i] >> shift) & 2047u]++;
		size_t acc = 0;
		for (int k = 0; k < 2048; k++) {
			size_t c = cnt[k];
			cnt[k] = acc;
			acc += c;
		}
		for (size_t i = 0; i < n; i++)
			b[cnt[(a[i] >> shift) & 2047u]++] = a[i];
		uint32_t *t = a;
		a = b;
		b = t;
	}
	free(b);
	/* Pooling: weighted percentiles, weight = value; first value whose running sum exceeds p * total. */
	const double ps[3] = {0.25, 0.5, 0.75};
	double res[3] = {0.0, 0.0, 0.0};
	int found[3] = {0, 0, 0};
	double run = 0.0;
	for (size_t i = 0, q = 0; i < n && q < 3; i++) {
		uint32_t k = a[i];
		float v = bits_to_float((k & 0x80000000u) ? (k & 0x7fffffffu) : ~k);
		run += (double)v;
		while (q < 3 && run > ps[q] * sum) {
			res[q] = v;
			found[q] = 1;
			q++;
		}
	}
	uint32_t kmin = a[0], kmax = a[n - 1];
	out->min = bits_to_float((kmin & 0x80000000u) ? (kmin & 0x7fffffffu) : ~kmin);
	out->max = bits_to_float((kmax & 0x80000000u) ? (kmax & 0x7fffffffu) : ~kmax);
	out->mean = sum / (double)n;
	out->q1_weighted = found[0] ? res[0] : 0.0;
	out->weighted_median = found[1] ? res[1] : 0.0;
	out->q3_weighted = found[2] ? res[2] : 0.0;
	free(a);
	return 0;
}
