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
 * Implementation notes (speed): all filters are applied separably, vertical pass first then horizontal, over
 * column strips of at most STRIP_W output pixels so the working set stays in L2. The vertical pass makes two output
 * rows at a time from their 2R+2 converted input rows in a ring buffer, each loaded once for both (each input row
 * is converted once per strip; the next row's part is prefetched, as the hardware prefetcher does not follow a
 * strip's row-to-row stride). Each
 * pass runs one loop per input plane, each as long as its own kernels (the achromatic and red-green CSFs are
 * narrow, see kernel_reach), written with GCC vector extensions so that accumulators and pointers stay in
 * registers. No per-pixel branches; the transcendental functions are division-free float approximations
 * (sRGB EOTF and cube root: a polynomial in the mantissa and an 8-entry table for the exponent; series for
 * log2/exp2; each within 1e-6 relative, measured) and sqrt is the hardware instruction (-fno-math-errno). On x86-64 the hot functions get AVX-512 and AVX2+FMA
 * clones (FLIP_TARGET_CLONES) with fused multiply-adds (-ffp-contract=fast): clones round differently in the
 * last bits (a machine always picks the same one, so results are reproducible on it); every clone stays within
 * 1e-7 of the reference means (tests/test_metrics.c; the baseline clone checked by hand).
 */
#include "taslab/metrics_flip.h"
#include "taslab/tl_error.h"

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

/* Chunk width of the vectorised loops (floats). All row buffers are padded to a multiple of it. */
#define VW 16
/* On x86-64 Linux with gcc, the hot row functions are compiled three times, for AVX-512 (x86-64-v4), AVX2 + FMA
 * (x86-64-v3) and the baseline ISA, and the variant is picked at load time (ifunc). Plain C everywhere else, with
 * -DFLIP_NO_CLONES, and under ThreadSanitizer (whose runtime is not initialised yet when ifunc resolvers run). The
 * variants differ only in rounding (FMA contraction), by ~1e-8 on the means. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) &&                           \
    !defined(FLIP_NO_CLONES) && !defined(__SANITIZE_THREAD__)
#define FLIP_TARGET_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define FLIP_TARGET_CLONES
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

/* Colour-difference exponent and compression parameters. */
#define FLIP_QC 0.7
#define FLIP_PC 0.4
#define FLIP_PT 0.95
/* Feature pipeline: kernel width in degrees and exponent. */
#define FLIP_GW 0.082
#define FLIP_QF 0.5

/* Linear sRGB -> XYZ (D65), exact rational form of the IEC 61966-2-1 matrix. */
static const double RGB2XYZ[9] = {
    10135552.0 / 24577794.0, 8788810.0 / 24577794.0, 4435075.0 / 24577794.0,
    2613072.0 / 12288897.0,  8788810.0 / 12288897.0, 887015.0 / 12288897.0,
    1425312.0 / 73733382.0,  8788810.0 / 73733382.0, 70074185.0 / 73733382.0,
};

/* ---- the filter object ---- */

struct mtr_flip {
	double ppd;
	int r;  /* CSF kernel radius (the blue-yellow kernels use all of it) */
	int ry; /* achromatic CSF taps used: the rest weigh too little to change a float sum (see kernel_reach) */
	int rx; /* red-green CSF taps used */
	int fr; /* feature kernel radius */
	int R;  /* max(r, fr): ring height is 2R+2 (two output rows at a time), horizontal halo is R */
	/* Half kernels, index k = |offset|, length R+1, zero beyond their own radius. */
	float *wy, *wcx, *wcz1, *wcz2; /* CSF: achromatic, red-green, blue-yellow (two Gaussians) */
	float *fg, *fdg, *fddg;        /* feature: Gaussian, first derivative (weight at +k; -k is its negative),
	                                  second derivative */
	/* Per-pixel constants (single precision, computed in double). */
	float lin2opp[9];  /* linear RGB -> (Y/Yn, X/Xn - Y/Yn, Y/Yn - Z/Zn) */
	float opp2rgb[9];  /* filtered (Y/Yn, X/Xn - Y/Yn, Y/Yn - Z/Zn) -> linear RGB */
	float rgb2xyzn[9]; /* linear RGB -> (X/Xn, Y/Yn, Z/Zn) */
	float cmax_lo;     /* p_c * c_max */
	float slope_lo;    /* p_t / (p_c c_max) */
	float log2_slope_lo;
	float slope_hi;    /* (1 - p_t) / (c_max - p_c c_max) */
};

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

/* Vertically filtered planes: CSF-filtered Y, Cx, Cz (two Gaussians), and Y/Yn filtered with the feature Gaussian,
 * its first and its second derivative. */
enum { V_Y, V_CX, V_CZ1, V_CZ2, V_G, V_DG, V_DDG, V_N };
/* Fully filtered planes: CSF-filtered Y, Cx, Cz; edge x/y and point x/y responses; Hunt-adjusted L, a', b'. */
enum { H_Y, H_CX, H_CZ, H_EX, H_EY, H_PX, H_PY, H_L, H_A, H_B, H_N };

static inline float *ring_plane(const scratch *s, int R, uint32_t src_row, int im, int plane)
{
	size_t slot = src_row % (uint32_t)(2 * R + 2);
	return s->ring + ((slot * 2 + (size_t)im) * 3 + (size_t)plane) * s->swp;
}

/* Colour pipeline, colour space transform: n packed sRGB pixels (0..255) -> linear RGB (sRGB EOTF) -> the three
 * opponent planes Y/Yn = (Yy + 16) / 116, X/Xn - Y/Yn = Cx / 500, Y/Yn - Z/Zn = Cz / 200 (YyCxCz up to constant
 * scale and offset, which the unit-sum CSF filters commute with). Y/Yn is also the feature pipeline's input.
 * One vectorised loop for every input (integral 8-bit values or not): the EOTF formula costs less than a table
 * lookup, which x86 can only do with gathers. */
FLIP_TARGET_CLONES static void convert_row(const mtr_flip *f, const float *restrict rgb, uint32_t n, float *restrict lin,
                                           float *restrict py, float *restrict pcx, float *restrict pcz)
{
	const float m0 = f->lin2opp[0], m1 = f->lin2opp[1], m2 = f->lin2opp[2], m3 = f->lin2opp[3], m4 = f->lin2opp[4],
	            m5 = f->lin2opp[5], m6 = f->lin2opp[6], m7 = f->lin2opp[7], m8 = f->lin2opp[8];
	/* The EOTF over the interleaved values (dense vectors), then the matrix, which de-interleaves. */
	uint32_t i = 0;
	for (; i + 8 <= 3 * n; i += 8)
		srgb_eotf8(rgb + i, 1.0f / 255.0f, lin + i);
	if (i < 3 * n) { /* the row's last values, through the same 8-value function */
		float in8[8] = {0}, out8[8];
		memcpy(in8, rgb + i, (3 * n - i) * sizeof(float));
		srgb_eotf8(in8, 1.0f / 255.0f, out8);
		memcpy(lin + i, out8, (3 * n - i) * sizeof(float));
	}
	/* Eight pixels at a time: their 24 interleaved values de-interleaved by register permutes (gcc turns the
	 * stride-3 loads of the plain loop into scalar inserts). */
	const v8i mr = {0, 3, 6, 9, 12, 15, 0, 0}, mr2 = {0, 1, 2, 3, 4, 5, 10, 13};
	const v8i mg = {1, 4, 7, 10, 13, 0, 0, 0}, mg2 = {0, 1, 2, 3, 4, 8, 11, 14};
	const v8i mb = {2, 5, 8, 11, 14, 0, 0, 0}, mb2 = {0, 1, 2, 3, 4, 9, 12, 15};
	uint32_t p = 0;
	for (; p + 8 <= n; p += 8) {
		const v8f A = LD8(lin + 3 * p), B = LD8(lin + 3 * p + 8), C = LD8(lin + 3 * p + 16);
		const v8f r = __builtin_shuffle(__builtin_shuffle(A, B, mr), C, mr2);
		const v8f g = __builtin_shuffle(__builtin_shuffle(A, B, mg), C, mg2);
		const v8f b = __builtin_shuffle(__builtin_shuffle(A, B, mb), C, mb2);
		ST8(py + p, m0 * r + m1 * g + m2 * b);
		ST8(pcx + p, m3 * r + m4 * g + m5 * b);
		ST8(pcz + p, m6 * r + m7 * g + m8 * b);
	}
	for (; p < n; p++) {
		const float r = lin[3 * p], g = lin[3 * p + 1], b = lin[3 * p + 2];
		py[p] = m0 * r + m1 * g + m2 * b;
		pcx[p] = m3 * r + m4 * g + m5 * b;
		pcz[p] = m6 * r + m7 * g + m8 * b;
	}
}

/* The filter loops are written with GCC's vector extensions (v8f, LD8, ST8 in flip_math.h: 8 floats, one AVX
 * register; two SSE registers in the baseline clone), mostly two vectors (VW = 16 floats) per accumulator so that
 * independent multiply-adds overlap. Loads and stores go through an unaligned, may-alias vector type. */

/* Vertical pass of the separable filters (colour pipeline: CSF spatial filtering; feature pipeline: edge / point
 * detection) for two output rows y and y + 1 at once (o0, o1: their V_N vertically filtered planes), buffer columns
 * [j0, j1) (multiples of VW). ry/rcx/rcz[R + k], -R <= k <= R + 1, are the opponent planes of source rows
 * clamp(y + k). Symmetric kernels fold the taps at -k and +k, the antisymmetric first derivative takes their
 * difference; one loop per input plane, each as long as its own kernels. Tap k of row y pairs source rows
 * y - k and y + k, tap k of row y + 1 pairs y + 1 - k and y + 1 + k; going outwards, each step loads the two new rows
 * y - k and y + 1 + k and reuses the two of the step before (y + k = y + 1 + (k - 1), y + 1 - k = y - (k - 1)), so
 * the 2R + 2 ring rows are read once for both outputs: half the ring traffic of two single passes (the ring is read
 * from L2, whose bandwidth bounds this pass; the same change made SSIM's vertical pass 14 % faster). */
FLIP_TARGET_CLONES static void vertical_pass(const mtr_flip *f, float *const *ry, float *const *rcx,
                                             float *const *rcz, size_t j0, size_t j1, float *const *o0,
                                             float *const *o1)
{
	const int R = f->R, kyf = f->ry > f->fr ? f->ry : f->fr;
	const float *wy = f->wy, *wcx = f->wcx, *wz1 = f->wcz1, *wz2 = f->wcz2;
	const float *fg = f->fg, *fdg = f->fdg, *fdd = f->fddg;
	/* Y/Yn: achromatic CSF and the three feature kernels, one 8-float vector per accumulator (eight of them). */
	for (size_t j = j0; j < j1; j += 8) {
		const v8f c0 = LD8(ry[R] + j), c1 = LD8(ry[R + 1] + j);
		v8f ay0 = wy[0] * c0, ag0 = fg[0] * c0, ad0 = (v8f){0}, add0 = fdd[0] * c0;
		v8f ay1 = wy[0] * c1, ag1 = fg[0] * c1, ad1 = (v8f){0}, add1 = fdd[0] * c1;
		v8f mprev = c0, pprev = c1;
		for (int k = 1; k <= kyf; k++) {
			const v8f m = LD8(ry[R - k] + j), p = LD8(ry[R + 1 + k] + j);
			const float a = wy[k], b = fg[k], d = fdg[k], e = fdd[k];
			const v8f sm0 = m + pprev, df0 = pprev - m, sm1 = mprev + p, df1 = p - mprev;
			ay0 += a * sm0;
			ag0 += b * sm0;
			ad0 += d * df0;
			add0 += e * sm0;
			ay1 += a * sm1;
			ag1 += b * sm1;
			ad1 += d * df1;
			add1 += e * sm1;
			mprev = m;
			pprev = p;
		}
		ST8(o0[V_Y] + j, ay0);
		ST8(o0[V_G] + j, ag0);
		ST8(o0[V_DG] + j, ad0);
		ST8(o0[V_DDG] + j, add0);
		ST8(o1[V_Y] + j, ay1);
		ST8(o1[V_G] + j, ag1);
		ST8(o1[V_DG] + j, ad1);
		ST8(o1[V_DDG] + j, add1);
	}
	/* Cx / 500: the red-green CSF. */
	for (size_t j = j0; j < j1; j += VW) {
		v8f a0[2], a1[2], mprev[2], pprev[2];
		for (int h = 0; h < 2; h++) {
			mprev[h] = LD8(rcx[R] + j + 8 * h);
			pprev[h] = LD8(rcx[R + 1] + j + 8 * h);
			a0[h] = wcx[0] * mprev[h];
			a1[h] = wcx[0] * pprev[h];
		}
		for (int k = 1; k <= f->rx; k++) {
			const float w = wcx[k];
			for (int h = 0; h < 2; h++) {
				const v8f m = LD8(rcx[R - k] + j + 8 * h), p = LD8(rcx[R + 1 + k] + j + 8 * h);
				a0[h] += w * (m + pprev[h]);
				a1[h] += w * (mprev[h] + p);
				mprev[h] = m;
				pprev[h] = p;
			}
		}
		for (int h = 0; h < 2; h++) {
			ST8(o0[V_CX] + j + 8 * h, a0[h]);
			ST8(o1[V_CX] + j + 8 * h, a1[h]);
		}
	}
	/* Cz / 200: the blue-yellow CSF's two Gaussians. */
	for (size_t j = j0; j < j1; j += VW) {
		v8f a0[2], b0[2], a1[2], b1[2], mprev[2], pprev[2];
		for (int h = 0; h < 2; h++) {
			mprev[h] = LD8(rcz[R] + j + 8 * h);
			pprev[h] = LD8(rcz[R + 1] + j + 8 * h);
			a0[h] = wz1[0] * mprev[h];
			b0[h] = wz2[0] * mprev[h];
			a1[h] = wz1[0] * pprev[h];
			b1[h] = wz2[0] * pprev[h];
		}
		for (int k = 1; k <= f->r; k++) {
			const float w1 = wz1[k], w2 = wz2[k];
			for (int h = 0; h < 2; h++) {
				const v8f m = LD8(rcz[R - k] + j + 8 * h), p = LD8(rcz[R + 1 + k] + j + 8 * h);
				const v8f sm0 = m + pprev[h], sm1 = mprev[h] + p;
				a0[h] += w1 * sm0;
				b0[h] += w2 * sm0;
				a1[h] += w1 * sm1;
				b1[h] += w2 * sm1;
				mprev[h] = m;
				pprev[h] = p;
			}
		}
		for (int h = 0; h < 2; h++) {
			ST8(o0[V_CZ1] + j + 8 * h, a0[h]);
			ST8(o0[V_CZ2] + j + 8 * h, b0[h]);
			ST8(o1[V_CZ1] + j + 8 * h, a1[h]);
			ST8(o1[V_CZ2] + j + 8 * h, b1[h]);
		}
	}
}

/* Two planes, each with its own symmetric kernel (half kernels w1, w2, taps 1..r): o1[i] = sum_k w1[|k|] p1[i + k],
 * likewise o2, i in [0, n) (multiple of VW); p1, p2 have r readable values either side. */
static inline void hfilter_pair(const float *p1, const float *w1, const float *p2, const float *w2, int r, size_t n,
                                float *o1, float *o2)
{
	for (size_t i = 0; i < n; i += VW) {
		v8f a1[2], a2[2];
		for (int u = 0; u < 2; u++) {
			a1[u] = w1[0] * LD8(p1 + i + 8 * u);
			a2[u] = w2[0] * LD8(p2 + i + 8 * u);
		}
		for (int k = 1; k <= r; k++) {
			const float c1 = w1[k], c2 = w2[k];
			for (int u = 0; u < 2; u++) {
				a1[u] += c1 * (LD8(p1 + i + 8 * u - k) + LD8(p1 + i + 8 * u + k));
				a2[u] += c2 * (LD8(p2 + i + 8 * u - k) + LD8(p2 + i + 8 * u + k));
			}
		}
		for (int u = 0; u < 2; u++) {
			ST8(o1 + i + 8 * u, a1[u]);
			ST8(o2 + i + 8 * u, a2[u]);
		}
	}
}

/* Horizontal pass of the separable filters: output i in [0, n) (n multiple of VW) reads the vertically filtered
 * planes at i + R + offset (the R halo columns were filled by clamp-to-edge). Produces the CSF-filtered Y, Cx,
 * Cz = (Cz Gaussian 1 + Cz Gaussian 2) and the detectors: edge x = d/dx (x) Gaussian (y), edge y = Gaussian (x)
 * d/dy (y), and likewise for the points with the second derivative. Four loops with at most four input streams
 * each, so that pointers and accumulators stay in registers. */
FLIP_TARGET_CLONES static void horizontal_pass(const mtr_flip *f, const float *v, size_t swp, size_t n, float *h)
{
	const int R = f->R, rxy = f->ry > f->rx ? f->ry : f->rx;
	const float *wy = f->wy, *wcx = f->wcx, *wz1 = f->wcz1, *wz2 = f->wcz2;
	const float *fg = f->fg, *fdg = f->fdg, *fdd = f->fddg;
	const float *iy = v + V_Y * swp + R, *ix = v + V_CX * swp + R, *iz1 = v + V_CZ1 * swp + R,
	            *iz2 = v + V_CZ2 * swp + R, *ig = v + V_G * swp + R, *id = v + V_DG * swp + R,
	            *idd = v + V_DDG * swp + R;
	/* Achromatic and red-green CSFs (wy, wcx are zero beyond their own radius). */
	hfilter_pair(iy, wy, ix, wcx, rxy, n, h + H_Y * swp, h + H_CX * swp);
	/* Blue-yellow CSF: the two Gaussians in their own accumulators, summed at the end. */
	for (size_t i = 0; i < n; i += VW) {
		v8f a1[2], a2[2];
		for (int u = 0; u < 2; u++) {
			a1[u] = wz1[0] * LD8(iz1 + i + 8 * u);
			a2[u] = wz2[0] * LD8(iz2 + i + 8 * u);
		}
		for (int k = 1; k <= f->r; k++) {
			const float c1 = wz1[k], c2 = wz2[k];
			for (int u = 0; u < 2; u++) {
				a1[u] += c1 * (LD8(iz1 + i + 8 * u - k) + LD8(iz1 + i + 8 * u + k));
				a2[u] += c2 * (LD8(iz2 + i + 8 * u - k) + LD8(iz2 + i + 8 * u + k));
			}
		}
		for (int u = 0; u < 2; u++)
			ST8(h + H_CZ * swp + i + 8 * u, a1[u] + a2[u]);
	}
	/* Feature pipeline, x derivatives of the vertically Gaussian-filtered plane: edges (first derivative,
	 * antisymmetric) and points (second derivative). */
	for (size_t i = 0; i < n; i += VW) {
		v8f ae[2], ap[2];
		for (int u = 0; u < 2; u++) {
			v8f c = LD8(ig + i + 8 * u);
			ae[u] = (v8f){0};
			ap[u] = fdd[0] * c;
		}
		for (int k = 1; k <= f->fr; k++) {
			const float d = fdg[k], dd = fdd[k];
			for (int u = 0; u < 2; u++) {
				v8f gl = LD8(ig + i + 8 * u - k), gh = LD8(ig + i + 8 * u + k);
				ae[u] += d * (gh - gl);
				ap[u] += dd * (gl + gh);
			}
		}
		for (int u = 0; u < 2; u++) {
			ST8(h + H_EX * swp + i + 8 * u, ae[u]);
			ST8(h + H_PX * swp + i + 8 * u, ap[u]);
		}
	}
	/* y derivatives: the vertical first / second derivative planes filtered with the Gaussian along x. */
	hfilter_pair(id, fg, idd, fg, f->fr, n, h + H_EY * swp, h + H_PY * swp);
}

/* Filtered opponent values -> linear RGB clamped to [0,1] -> Hunt-adjusted CIELAB (colour pipeline):
 * (py, pcx, pcz) -> (pl, pa, pb), eight pixels at a time (n is a multiple of VW). */
FLIP_TARGET_CLONES static void hunt_lab_row(const mtr_flip *f, const float *restrict py, const float *restrict pcx,
                                            const float *restrict pcz, float *restrict pl, float *restrict pa,
                                            float *restrict pb, size_t n)
{
	const float *m = f->opp2rgb, *nm = f->rgb2xyzn;
	const float m0 = m[0], m1 = m[1], m2 = m[2], m3 = m[3], m4 = m[4], m5 = m[5], m6 = m[6], m7 = m[7], m8 = m[8];
	const float n0 = nm[0], n1 = nm[1], n2 = nm[2], n3 = nm[3], n4 = nm[4], n5 = nm[5], n6 = nm[6], n7 = nm[7],
	            n8 = nm[8];
	/* Two independent 8-pixel groups per iteration: the polynomials are chains of dependent multiply-adds; two
	 * groups give the scheduler independent work (a few per cent of FLIP, within the noise of one run). */
	for (size_t i0 = 0; i0 < n; i0 += 16) {
		v8f fx[2], fy[2], fz[2];
		for (int h = 0; h < 2; h++) {
			const size_t i = i0 + 8 * (size_t)h;
			const v8f y = LD8(py + i), cx = LD8(pcx + i), cz = LD8(pcz + i);
			const v8f r = clamp01_8(m0 * y + m1 * cx + m2 * cz);
			const v8f g = clamp01_8(m3 * y + m4 * cx + m5 * cz);
			const v8f b = clamp01_8(m6 * y + m7 * cx + m8 * cz);
			fx[h] = n0 * r + n1 * g + n2 * b;
			fy[h] = n3 * r + n4 * g + n5 * b;
			fz[h] = n6 * r + n7 * g + n8 * b;
		}
		for (int h = 0; h < 2; h++) {
			fx[h] = lab_f8(fx[h]);
			fy[h] = lab_f8(fy[h]);
			fz[h] = lab_f8(fz[h]);
		}
		for (int h = 0; h < 2; h++) {
			const size_t i = i0 + 8 * (size_t)h;
			const v8f l = 116.0f * fy[h] - 16.0f;
			ST8(pl + i, l);
			ST8(pa + i, 0.01f * l * 500.0f * (fx[h] - fy[h])); /* Hunt: a' = 0.01 L a */
			ST8(pb + i, 0.01f * l * 200.0f * (fy[h] - fz[h])); /* Hunt: b' = 0.01 L b */
		}
	}
}

/* Colour difference, feature difference and final error for n (multiple of VW) pixels; hr / ht hold L, a', b' (see
 * hunt_lab_row) and the edge / point responses. */
FLIP_TARGET_CLONES static void finalize_row(const mtr_flip *f, const float *restrict hr, const float *restrict ht,
                                            size_t swp, size_t n, float *restrict out)
{
	const float cmax_lo = f->cmax_lo, slope_lo = f->slope_lo, slope_hi = f->slope_hi, log2_slope_lo = f->log2_slope_lo;
	for (size_t i = 0; i < n; i += VW) {
		for (int u = 0; u < VW; u++) {
			const size_t p = i + (size_t)u;
			/* HyAB distance, then ^q_c and the compression re-mapping into [0,1]. */
			float dl = hr[H_L * swp + p] - ht[H_L * swp + p];
			float da = hr[H_A * swp + p] - ht[H_A * swp + p], db = hr[H_B * swp + p] - ht[H_B * swp + p];
			float hy = fabsf(dl) + sqrtf(da * da + db * db);
			const float lq = (float)FLIP_QC * fast_log2(select_f(hy > 1e-30f, hy, 1e-30f)); /* log2 hy^q_c */
			const float pq = fast_exp2(lq);
			const int lower = pq < cmax_lo;
			float dc = select_f(lower, slope_lo * pq, (float)FLIP_PT + (pq - cmax_lo) * slope_hi);
			dc = select_f(hy > 0.0f, dc, 0.0f);
			/* log2 dc for the final error's power, without a second fast_log2: below the knee
			 * log2(slope_lo hy^q_c) = log2 slope_lo + q_c log2 hy; above it dc is in [p_t, 1], where
			 * log2(1 + x), x = dc - 1 in [-0.05, 0], is its series to x^6 (error < 2e-10). */
			const float x = dc - 1.0f;
			float ls = -1.0f / 6.0f;
			ls = ls * x + 0.2f;
			ls = ls * x - 0.25f;
			ls = ls * x + 1.0f / 3.0f;
			ls = ls * x - 0.5f;
			ls = ls * x + 1.0f;
			const float ldc = select_f(lower, log2_slope_lo + lq, ls * x * 1.44269504f); /* 1 / ln 2 */
			/* Feature pipeline: edge and point magnitudes, difference, / sqrt(2), ^q_f (q_f = 0.5 -> sqrt). */
			float ex1 = hr[H_EX * swp + p], ey1 = hr[H_EY * swp + p], px1 = hr[H_PX * swp + p],
			      py1 = hr[H_PY * swp + p];
			float ex2 = ht[H_EX * swp + p], ey2 = ht[H_EY * swp + p], px2 = ht[H_PX * swp + p],
			      py2 = ht[H_PY * swp + p];
			float de = fabsf(sqrtf(ex1 * ex1 + ey1 * ey1) - sqrtf(ex2 * ex2 + ey2 * ey2));
			float dp = fabsf(sqrtf(px1 * px1 + py1 * py1) - sqrtf(px2 * px2 + py2 * py2));
			float df = sqrtf(select_f(de > dp, de, dp) * 0.707106781f);
			/* Final error dE_c^(1 - dE_f); 0^0 = 1 as with pow(). */
			float ex = 1.0f - df;
			float e = fast_exp2(ex * ldc);
			out[p] = select_f(dc > 0.0f, e, select_f(ex == 0.0f, 1.0f, 0.0f));
		}
	}
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
		/* Output rows two at a time (vertical_pass). */
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
					convert_row(f, job->img[im] + ((size_t)next_src * W + cx0) * 3, cx1 - cx0, s.lin,
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
				vertical_pass(f, ry, rcx, rcz, ja, jb, vo[0], vo[1]);
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
					horizontal_pass(f, v, s.swp, swr, s.hbuf + (size_t)im * H_N * s.swp);
				}
				for (int im = 0; im < 2; im++) {
					float *h = s.hbuf + (size_t)im * H_N * s.swp;
					hunt_lab_row(f, h + H_Y * s.swp, h + H_CX * s.swp, h + H_CZ * s.swp, h + H_L * s.swp,
					             h + H_A * s.swp, h + H_B * s.swp, swr);
				}
				finalize_row(f, s.hbuf, s.hbuf + H_N * s.swp, s.swp, swr, s.err);
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
