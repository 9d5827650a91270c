/* flip_internal.h (private to metrics/src) — the LDR-FLIP filter object and the row kernels flip.c runs on it
 * (flip_rows.c). */
#ifndef TASLAB_FLIP_INTERNAL_H
#define TASLAB_FLIP_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "taslab/metrics_flip.h"

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

/* Colour-difference exponent and compression parameters. */
#define FLIP_QC 0.7
#define FLIP_PC 0.4
#define FLIP_PT 0.95
/* Feature pipeline: kernel width in degrees and exponent. */
#define FLIP_GW 0.082
#define FLIP_QF 0.5

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
	float log2_slope_lo; /* log2 slope_lo (flip_finalize_row's log2 of the re-mapped difference below the knee) */
	float slope_hi;    /* (1 - p_t) / (c_max - p_c c_max) */
};

/* Vertically filtered planes: CSF-filtered Y, Cx, Cz (two Gaussians), and Y/Yn filtered with the feature Gaussian,
 * its first and its second derivative. */
enum { V_Y, V_CX, V_CZ1, V_CZ2, V_G, V_DG, V_DDG, V_N };
/* Fully filtered planes: CSF-filtered Y, Cx, Cz; edge x/y and point x/y responses; Hunt-adjusted L, a', b'. */
enum { H_Y, H_CX, H_CZ, H_EX, H_EY, H_PX, H_PY, H_L, H_A, H_B, H_N };

/* Row kernels (flip_rows.c; each documented there). */
void flip_convert_row(const mtr_flip *f, const float *restrict rgb, uint32_t n, float *restrict lin,
                      float *restrict py, float *restrict pcx, float *restrict pcz);
void flip_vertical_pass(const mtr_flip *f, float *const *ry, float *const *rcx, float *const *rcz, size_t j0,
                        size_t j1, float *const *o0, float *const *o1);
void flip_horizontal_pass(const mtr_flip *f, const float *v, size_t swp, size_t n, float *h);
void flip_hunt_lab_row(const mtr_flip *f, const float *restrict py, const float *restrict pcx,
                       const float *restrict pcz, float *restrict pl, float *restrict pa, float *restrict pb,
                       size_t n);
void flip_finalize_row(const mtr_flip *f, const float *restrict hr, const float *restrict ht, size_t swp, size_t n,
                       float *restrict out);

#endif
