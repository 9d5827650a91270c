/* sweep_keys.c — the one table of sweep settings (sweep_keys.h, issue 30.2). A new key is one line here plus its
 * fields in sweep_request (and sweep_spec, for a SWEEP_KEY_SPEC key) and its use: the file reader, the command line,
 * the help and sweep.json follow from the line. */
#include "taslab/sweep_keys.h"

#include <stdio.h>
#include <string.h>

#define FIELD(type, f) (((type *)0)->f)
#define REQ(f) .offset = offsetof(sweep_request, f)
/* a string field: its size */
#define STR(f) REQ(f), .size = sizeof FIELD(sweep_request, f)
/* a list: one entry's size, the most entries, the count field */
#define LIST(f, n)                                                                                                     \
	REQ(f), .size = sizeof FIELD(sweep_request, f)[0],                                                             \
		.max = sizeof FIELD(sweep_request, f) / sizeof FIELD(sweep_request, f)[0],                             \
		.count_offset = offsetof(sweep_request, n)
/* the field in sweep_spec: it must have the size of the request's, which a negative array size refuses to compile
 * otherwise (the copy and sweep.json's write and read take the request's size) */
#define SPEC(f)                                                                                                        \
	.spec_offset = offsetof(sweep_spec, f) +                                                                       \
		       0 * sizeof(char[sizeof FIELD(sweep_spec, f) == sizeof FIELD(sweep_request, f) ? 1 : -1])

/* The order is the help's and the "known keys" message's. Ranges are those the resolver and the runs accept (T and
 * the period as the method tables', ppd as FLIP's, metrics/src/metric_flip.c). */
static const sweep_key table[] = {
	{.name = "scenes", .arg = "LIST", .type = SWEEP_KEY_NAMES, LIST(scenes, scene_count), .flags = SWEEP_KEY_RELATIVE,
	 .help = "built-in scene names or scene files, comma-separated (e.g. calm,moderate,dynamic)"},
	{.name = "cameras", .arg = "LIST", .type = SWEEP_KEY_NAMES, LIST(cameras, camera_count), .all = "all",
	 .all_offset = offsetof(sweep_request, cameras_all),
	 .help = "camera paths: all (default), or names (each in every scene) and SCENE/CAMERA entries"},
	{.name = "variants", .arg = "LIST", .type = SWEEP_KEY_NAMES, LIST(variants, variant_count),
	 .help = "variants, comma-separated, ref among them (e.g. ref,tfr@2,tfr@8,tarc@8,rrc/4; see 'taslab render --help')"},
	{.name = "methods", .arg = "LIST", .type = SWEEP_KEY_NAMES, LIST(methods, method_count), .all = "all",
	 .all_offset = offsetof(sweep_request, methods_all),
	 .help = "also every variant of these methods (or all available ones) at --thresholds and --periods, plus ref"},
	{.name = "thresholds", .arg = "LIST", .type = SWEEP_KEY_NUMBERS, LIST(thresholds, threshold_count), .lo = 1e-6,
	 .hi = 255, .help = "T values for --methods (e.g. 2,4,8,16,32,64)"},
	{.name = "periods", .arg = "LIST", .type = SWEEP_KEY_WHOLES, LIST(periods, period_count), .lo = 1, .hi = 1024,
	 .help = "period values for --methods (e.g. 2,4,8)"},
	{.name = "frames", .arg = "A:B", .type = SWEEP_KEY_FRAMES, STR(frames),
	 .help = "frames A..B-1 of every scene; also A, :B, A: (default: each scene's whole clip)"},
	{.name = "size", .arg = "WxH", .type = SWEEP_KEY_SIZE, REQ(width), .flags = SWEEP_KEY_SPEC, SPEC(width),
	 .help = "frame size (default 960x540)"},
	{.name = "fps", .arg = "F", .type = SWEEP_KEY_NUMBER, REQ(fps), .lo = 1, .hi = 1000,
	 .help = "frame rate (default: each scene's)"},
	{.name = "out", .arg = "SWEEP", .type = SWEEP_KEY_STRING, STR(out), .flags = SWEEP_KEY_RELATIVE,
	 .help = "the sweep folder (runs/, clips/, metrics/, summary.csv, table1.md, report/)"},
	{.name = "baseline", .arg = "VARIANT", .type = SWEEP_KEY_STRING, STR(baseline), .flags = SWEEP_KEY_SPEC,
	 SPEC(baseline),
	 .help = "variant the shaded-sample reductions are relative to, or auto (default: sa for sa/sau/tasa when sa "
		 "is swept, as the paper's Table 1; ref otherwise)"},
	{.name = "metrics", .arg = "LIST", .type = SWEEP_KEY_STRING, STR(metrics), .flags = SWEEP_KEY_SPEC, SPEC(metrics),
	 .help = "metrics against ref: maxrgb,psnr,ssim,flicker,flip or all (default)"},
	{.name = "ppd", .arg = "F", .type = SWEEP_KEY_NUMBER, REQ(ppd), .lo = 1e-3, .hi = 1000, .flags = SWEEP_KEY_SPEC,
	 SPEC(ppd), .help = "FLIP pixels per degree (default 67.0206)"},
	{.name = "device", .arg = "D", .type = SWEEP_KEY_STRING, STR(device), .flags = SWEEP_KEY_SPEC | SWEEP_KEY_EMPTY_OK,
	 SPEC(device),
	 .help = "Vulkan device for every run: index, name substring, or 'lavapipe' (default: a GPU if present)"},
	{.name = "ocio_config", .arg = "F", .type = SWEEP_KEY_STRING, STR(ocio_config),
	 .flags = SWEEP_KEY_SPEC | SWEEP_KEY_EMPTY_OK | SWEEP_KEY_RELATIVE, SPEC(ocio_config),
	 .help = "OpenColorIO config for the display transform (default: $OCIO, else the built-in ACES 1.0 SDR-video)"},
	{.name = "display", .arg = "D", .type = SWEEP_KEY_STRING, STR(display),
	 .flags = SWEEP_KEY_SPEC | SWEEP_KEY_EMPTY_OK, SPEC(display), .help = "display of that config"},
	{.name = "view", .arg = "V", .type = SWEEP_KEY_STRING, STR(view), .flags = SWEEP_KEY_SPEC | SWEEP_KEY_EMPTY_OK,
	 SPEC(view), .help = "view of that display"},
	{.name = "validation", .type = SWEEP_KEY_BOOL, REQ(validation), .flags = SWEEP_KEY_SPEC, SPEC(validation),
	 .help = "every run with the Khronos validation layer; any message fails the run"},
	/* "truth" came after the first sweeps: a sweep.json without it was made without --truth */
	{.name = "truth", .type = SWEEP_KEY_BOOL, REQ(truth), .flags = SWEEP_KEY_SPEC | SWEEP_KEY_OPTIONAL, SPEC(truth),
	 .help = "render every variant whose method has --truth with it: late_samples and late_percent in summary.csv "
		 "(reused samples more than T from their true shading; costs shading them too)"},
	/* stereo (issue 25) came after the first sweeps: a sweep.json without it is mono */
	{.name = "stereo", .type = SWEEP_KEY_BOOL, REQ(stereo), .flags = SWEEP_KEY_SPEC | SWEEP_KEY_OPTIONAL, SPEC(stereo),
	 .help = "every run renders both eyes (--size per eye; STEREO.md): frames/L, frames/R, side-by-side clips, metrics "
		 "per eye then pooled; part of the sweep's identity"},
	{.name = "ipd", .arg = "M", .type = SWEEP_KEY_NUMBER, REQ(ipd), .lo = 1e-4, .hi = 1.0,
	 .flags = SWEEP_KEY_SPEC | SWEEP_KEY_OPTIONAL, SPEC(ipd),
	 .help = "with --stereo: distance between the eyes in metres (default 0.063)"},
	{.name = "jobs", .arg = "N", .type = SWEEP_KEY_WHOLE, REQ(jobs), .lo = 1, .hi = 256, .flags = SWEEP_KEY_RESUME_OK,
	 .help = "runs at a time on this machine, each in its own process (default 1)"},
};

#define COUNT (sizeof table / sizeof table[0])
_Static_assert(COUNT <= 32, "sweep_request.set has one bit per key");

const sweep_key *sweep_keys(size_t *count)
{
	*count = COUNT;
	return table;
}

const sweep_key *sweep_key_find(const char *name)
{
	for (size_t i = 0; name && i < COUNT; i++)
		if (!strcmp(table[i].name, name))
			return &table[i];
	return NULL;
}

uint32_t sweep_key_bit(const sweep_key *k) { return 1u << (k - table); }

size_t sweep_key_value_size(const sweep_key *k)
{
	switch (k->type) {
	case SWEEP_KEY_STRING:
	case SWEEP_KEY_FRAMES: return k->size;
	case SWEEP_KEY_SIZE: return 2 * sizeof(uint32_t);
	case SWEEP_KEY_NUMBER: return sizeof(double);
	case SWEEP_KEY_WHOLE: return sizeof(uint32_t);
	case SWEEP_KEY_BOOL: return sizeof(bool);
	default: return 0;
	}
}

bool sweep_request_has(const sweep_request *r, const char *name)
{
	const sweep_key *k = sweep_key_find(name);
	return k && (r->set & sweep_key_bit(k));
}

void sweep_spec_copy_keys(sweep_spec *s, const sweep_request *r)
{
	for (size_t i = 0; i < COUNT; i++)
		if (table[i].flags & SWEEP_KEY_SPEC)
			memcpy((char *)s + table[i].spec_offset, (const char *)r + table[i].offset,
			       sweep_key_value_size(&table[i]));
}

const char *sweep_key_list(const char *sep, char *out, size_t out_size)
{
	size_t len = 0;
	if (out_size)
		out[0] = 0;
	for (size_t i = 0; i < COUNT && len < out_size; i++) {
		int n = snprintf(out + len, out_size - len, "%s%s", i ? sep : "", table[i].name);
		len += n > 0 ? (size_t)n : 0;
	}
	return out;
}
