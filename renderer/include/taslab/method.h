/* method.h — the rendering methods of DESIGN section 4 as a registry of plug-ins, their option tables,
 * and the variant syntax that names one configuration in one token.
 *
 * Every method lives in one file (renderer/src/methods/<name>.c) that exports its frame operations and a
 * table of options (name, help, type, default, range; libvmaf's feature-extractor shape). `taslab render
 * --help`, the manifest's "method_options" and variant parsing are generated from these tables, so a new
 * option is one table line and a new method one file plus one registry line (renderer/src/methods/registry.c).
 *
 * What other modules need to know of a method (its family, the baseline its reductions are against, whether it is
 * the reference, whether it takes T or a period) is in its method_info too; method_facts() turns it into the
 * run_method_facts that manifest.json and pairs.json carry, so metrics/ and study/ never name a method (issue 30.1).
 *
 * Variants (DESIGN section 4): NAME[-FLAG...][@T][/N], e.g. ref, tfr@8, tarc@8, tarc-oracle@8, rrc/4, sau/8.
 * "@" sets the method's threshold option, "/" its period option, "-FLAG" one of its boolean options
 * (the oracle variants). The variant's *method name* is NAME with its flags ("tarc-oracle"): the EXR
 * attribute taslab:method and the method column of every CSV; T and the period have their own columns.
 *
 * No Vulkan here: the CLI, sweeps and tests use this header without a device.
 */
#ifndef TASLAB_METHOD_H
#define TASLAB_METHOD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "taslab/run.h"
#include "taslab/tl_error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum method_opt_type {
	METHOD_OPT_FLOAT = 1, /* float */
	METHOD_OPT_UINT,      /* uint32_t; `allowed` may restrict it to a list */
	METHOD_OPT_BOOL,      /* bool, given as a flag (--oracle) */
	METHOD_OPT_CHOICE,    /* uint32_t index into `choices` */
} method_opt_type;

typedef struct method_option {
	const char *name;    /* "threshold": the CLI flag --threshold and the manifest key "threshold" */
	const char *arg;     /* placeholder in help texts ("T"); NULL for flags */
	const char *help;
	method_opt_type type;
	size_t offset;       /* of the value in the method's options struct */
	double def, min, max;
	const char *const *choices;  /* CHOICE: NULL-terminated names */
	const uint32_t *allowed;     /* UINT: the only values allowed, terminated by 0 (NULL: any in range) */
	char variant;        /* '@' or '/': the value's sigil in variants; '-': a -NAME suffix (a flag), -NAMEvalue
	                      * (a whole number: ref-ssaa2) or -VALUE (a choice other than the default: rrc-shadow) */
	bool variant_required; /* the variant token must carry it (tfr@8, not tfr) */
} method_option;

typedef struct method_info {
	const char *name;
	const char *summary;
	bool available;               /* false: planned, listed in help, refused with a message */
	const method_option *options; /* the method's option table */
	size_t option_count;
	size_t options_size;          /* sizeof the method's options struct (<= METHOD_OPTIONS_MAX_B) */
	bool decisions;               /* makes per-sample reuse decisions it can report (render --decisions) */
	bool tile_rates;              /* chooses a shading rate per 16x16 tile it can report (render --rate-images) */
	/* The method's family, by what it reuses (DESIGN section 4, BASELINES.md): "reference" (shades everything),
	 * "forward" (tfr: per-pixel reuse by re-evaluating old shading), "reprojection" (pixel caches: rrc, tarc and
	 * the reprojection alternatives of BASELINES.md), "atlas" (atlas blocks: sa, sau, tasa), "rate" (variable rate
	 * shading, BASELINES.md A7), "deferred" (adaptive deferred shading, A8). */
	const char *family;
	/* The method whose run this one's shaded-sample reductions are against when that run is in the same set (paper
	 * Table 1 reduces the atlas methods against sa); NULL: the reference. */
	const char *baseline;
	bool reference;               /* the reference every other method is compared with (exactly one) */
	/* Cross-option checks beyond the table's ranges (NULL: none); called by method_config_check. */
	int (*check)(const void *options, char *err, size_t err_size);
} method_info;

/* All methods in registry order (available ones first, then the planned ones). */
const method_info *const *method_list(size_t *count);
/* The method called `name`, or NULL. */
const method_info *method_find(const char *name);
/* The reference method (method_info.reference). */
const method_info *method_reference(void);
/* What manifest.json and pairs.json record of method `m` (run.h): family, baseline (the reference's name when
 * m->baseline is NULL), reference, and takes_threshold / takes_period from its option table (an option set by '@'
 * or '/' in variants). */
void method_facts(const method_info *m, run_method_facts *out);
/* The '-' suffixes a variant of m may carry, in option order: a flag's name ("oracle"), a whole-number option's name
 * with each allowed value but the default ("ssaa2"), a choice's values but the default ("shadow"). Writes at most max
 * of them into out; returns how many there are. No method has more than METHOD_DASH_FORMS_MAX (test_methods checks
 * the registry), so an array of that many holds every method's. */
enum { METHOD_DASH_FORM_B = 48, METHOD_DASH_FORMS_MAX = 16 };
size_t method_dash_forms(const method_info *m, char (*out)[METHOD_DASH_FORM_B], size_t max);

#define METHOD_OPTIONS_MAX_B 64

/* A method with values for all of its options. Zero-initialised it is invalid; fill it with
 * method_config_init or method_config_parse_variant. Plain data: copy it freely. */
typedef struct method_config {
	const method_info *method;
	union {
		double align;
		unsigned char bytes[METHOD_OPTIONS_MAX_B];
	} values;
	uint32_t given; /* bit i: option i was set explicitly */
} method_config;

/* The method `name` with default option values. TL_ERR_ARG for an unknown name, TL_ERR_UNSUPPORTED for a
 * planned method. */
int method_config_init(method_config *c, const char *name, char *err, size_t err_size);
/* Sets option `option` (its table name) from text ("8", "bilinear"; flags: NULL or "1"/"true").
 * TL_ERR_ARG when the method has no such option or the value is out of range (the message says which). */
int method_config_set(method_config *c, const char *option, const char *value, char *err, size_t err_size);
/* Checks that required options are set and values are consistent (before rendering). */
int method_config_check(const method_config *c, char *err, size_t err_size);
/* Parses a variant token (see above) into a checked configuration. */
int method_config_parse_variant(method_config *c, const char *variant, char *err, size_t err_size);

/* The canonical variant token ("tarc-oracle@8", "rrc/4", "ref") and the variant's method name ("tarc-oracle"). */
void method_config_variant(const method_config *c, char *out, size_t out_size);
void method_config_name(const method_config *c, char *out, size_t out_size);
/* A file-name-safe id of the variant ("tarc-oracle-T8", "rrc-N4", "ref"). */
void method_config_id(const method_config *c, char *out, size_t out_size);
/* Values of the variant options: T (NAN when the method has none) and period N (0 when none). */
double method_config_threshold(const method_config *c);
uint32_t method_config_period(const method_config *c);
/* Typed access by table name (for method files and tests); 0 / false / NAN when absent. */
double method_config_number(const method_config *c, const char *option);
bool method_config_flag(const method_config *c, const char *option);

/* What `render --help` says of an option beyond its help text, from its table line: how a variant sets it, its
 * default (or that the variant must carry it) and the values it takes, e.g. "as @T; default 8; 0..255",
 * "as /N; default 4; one of 1, 2, 4, 8", "default bilinear; bilinear or nearest" ("required" instead of a default
 * when the variant must carry the value). Empty for a plain flag. */
void method_option_describe(const method_option *o, char *out, size_t out_size);
/* Whether method `m` has an option called `name` (e.g. "truth"). */
bool method_has_option(const method_info *m, const char *name);

/* The option values as manifest entries (all options, defaults included); returns the count (<= max).
 * String values point into the method's tables. */
size_t method_config_run_options(const method_config *c, run_option *out, size_t max);

#ifdef __cplusplus
}
#endif
#endif
