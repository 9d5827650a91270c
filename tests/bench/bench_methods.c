/* bench_methods.c — the reuse methods side by side in one process (scripts/bench-methods; not a test).
 * One renderer per variant over the same scene, camera path and size; frame f is rendered by every variant in
 * turn before frame f + 1, so machine noise at any moment hits all variants alike, and each renderer still sees
 * consecutive frames (its cache stays valid). Writes one CSV row per variant and frame:
 *   variant,frame,visible,shaded,reused,new,late,gpu_ms_total,allocated,q_mean=M,q_p99=P,q_e8=E,<pass>=MS...
 * q_mean / q_p99: mean and 99th percentile of the max-RGB difference of the display frame against the first
 * variant's (the reference) in the same frame; q_e8 the fraction of pixels more than 8 code values from it. When a variant is labelled "sa", every row also has sa_e4, sa_e8,
 * sa_e16, sa_e32, sa_e64: the fraction of pixels whose max-RGB difference to sa's frame exceeds T (TAS-METHODS A5:
 * at matched budgets tasa should exceed less often than sau against sa).
 *
 * FLIP (--flip before SCENE): every row also has flip=F, the mean LDR-FLIP error (taslab's metrics module,
 * metrics_flip.h, the `flip` metric of `taslab metrics diff` at its default 67.02 pixels per degree) of the display frame
 * against the first variant's; computed between renders, outside the GPU timings.
 *
 * OPTION "count=atomic" makes that variant's shading passes count with one atomic per fragment (TASLAB_COUNT_ATOMICS
 * while it is created) instead of one per subgroup, to measure the counting beside the default in one process.
 * OPTION "stereo" renders that variant's both eyes (WxH per eye; the counts and times are totals over both eyes,
 * the quality columns the left eye's), "ipd=M" its eye distance (default 0.063), "multiview=on|off" how its
 * eyes' visibility pass is recorded (render_desc.multiview; default auto).
 *
 *   bench_methods [--flip] SCENE.json CAMERA WxH FIRST:END OUT.csv LABEL=VARIANT[,OPTION[=VALUE]]...
 * e.g. bench_methods scenes/calm.json fan_shadow 960x540 0:120 out.csv ref=ref tarc8=tarc@8 \
 *        force=tarc@8,force-reshade */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "taslab/metrics_flip.h"
#include "taslab/render.h"
#include "taslab/scene.h"
#include "taslab/vkdev.h"

#define MAX_VARIANTS 16

typedef struct bench_variant {
	char label[64];
	method_config mc;
	render *r;
	uint32_t views; /* 2: ",stereo" (both eyes, the size per eye; STEREO.md) */
	float ipd;      /* ",ipd=M" with stereo (default RENDER_STEREO_IPD_DEFAULT) */
	render_multiview multiview; /* ",multiview=on|off" with stereo */
	bool count_atomic; /* ",count=atomic": its shading passes count one atomic per fragment (TASLAB_COUNT_ATOMICS) */
} bench_variant;

static int parse_variant(const char *arg, bench_variant *v)
{
	char err[512], buf[512];
	snprintf(buf, sizeof buf, "%s", arg);
	char *eq = strchr(buf, '=');
	if (!eq) {
		fprintf(stderr, "bench_methods: '%s': expected LABEL=VARIANT[,OPTION[=VALUE]]...\n", arg);
		return 1;
	}
	*eq = 0;
	snprintf(v->label, sizeof v->label, "%s", buf);
	char *save = NULL, *tok = strtok_r(eq + 1, ",", &save);
	if (!tok || method_config_parse_variant(&v->mc, tok, err, sizeof err)) {
		fprintf(stderr, "bench_methods: %s: %s\n", arg, tok ? err : "no variant");
		return 1;
	}
	v->views = 1;
	v->ipd = RENDER_STEREO_IPD_DEFAULT;
	while ((tok = strtok_r(NULL, ",", &save))) {
		char *ov = strchr(tok, '=');
		if (ov)
			*ov++ = 0;
		if (!strcmp(tok, "count")) { /* a bench option: the counting cost measured beside the default, issue 32.1 */
			if (!ov || strcmp(ov, "atomic")) {
				fprintf(stderr, "bench_methods: %s: count takes 'atomic'\n", arg);
				return 1;
			}
			v->count_atomic = true;
			continue;
		}
		if (!strcmp(tok, "stereo") || !strcmp(tok, "ipd") || !strcmp(tok, "multiview")) { /* render options */
			if (!strcmp(tok, "stereo"))
				v->views = 2;
			else if (!strcmp(tok, "multiview"))
				v->multiview = ov && !strcmp(ov, "on") ? RENDER_MULTIVIEW_ON
					       : ov && !strcmp(ov, "off") ? RENDER_MULTIVIEW_OFF : (render_multiview)99;
			else
				v->ipd = ov ? strtof(ov, NULL) : -1.0f;
			continue;
		}
		if (method_config_set(&v->mc, tok, ov ? ov : "true", err, sizeof err)) {
			fprintf(stderr, "bench_methods: %s: %s\n", arg, err);
			return 1;
		}
	}
	if (method_config_check(&v->mc, err, sizeof err)) {
		fprintf(stderr, "bench_methods: %s: %s\n", arg, err);
		return 1;
	}
	return 0;
}

/* Display RGBA8 to the packed 0..255 RGB floats FLIP reads. */
static void to_rgb(const uint8_t *rgba, size_t px, float *rgb)
{
	for (size_t k = 0; k < px; k++)
		for (int c = 0; c < 3; c++)
			rgb[3 * k + c] = rgba[4 * k + c];
}

int main(int argc, char **argv)
{
	bool flip = argc > 1 && !strcmp(argv[1], "--flip");
	if (flip)
		argc--, argv++;
	if (argc < 7) {
		fprintf(stderr, "usage: bench_methods [--flip] SCENE.json CAMERA WxH FIRST:END OUT.csv LABEL=VARIANT[,OPT[=V]]...\n");
		return 2;
	}
	char err[1024];
	unsigned w, h, first, end;
	if (sscanf(argv[3], "%ux%u", &w, &h) != 2 || sscanf(argv[4], "%u:%u", &first, &end) != 2 || end <= first) {
		fprintf(stderr, "bench_methods: bad size '%s' or frames '%s'\n", argv[3], argv[4]);
		return 2;
	}
	int nv = argc - 6;
	if (nv > MAX_VARIANTS) {
		fprintf(stderr, "bench_methods: at most %d variants\n", MAX_VARIANTS);
		return 2;
	}
	bench_variant v[MAX_VARIANTS];
	memset(v, 0, sizeof v);
	for (int i = 0; i < nv; i++)
		if (parse_variant(argv[6 + i], &v[i]))
			return 2;
	scene *s = NULL;
	if (scene_load(argv[1], &s, err, sizeof err)) {
		fprintf(stderr, "bench_methods: %s\n", err);
		return 1;
	}
	int cam = -1;
	for (size_t i = 0; i < s->camera_count; i++)
		if (!strcmp(s->cameras[i].name, argv[2]))
			cam = (int)i;
	if (cam < 0) {
		fprintf(stderr, "bench_methods: %s has no camera path '%s'\n", argv[1], argv[2]);
		return 1;
	}
	vkdev *dev = NULL;
	vkdev_desc dd = {.device = getenv("TASLAB_DEVICE") ? getenv("TASLAB_DEVICE") : "lavapipe"};
	if (vkdev_create(&dd, &dev, err, sizeof err)) {
		fprintf(stderr, "bench_methods: %s\n", err);
		return 1;
	}
	for (int i = 0; i < nv; i++) {
		render_desc rd = {.scene = s, .camera = cam, .width = w, .height = h, .method = &v[i].mc, .views = v[i].views,
				  .ipd = v[i].views > 1 ? v[i].ipd : 0.0f, .multiview = v[i].multiview};
		if (v[i].count_atomic)
			setenv("TASLAB_COUNT_ATOMICS", "1", 1); /* read when the pipelines are made */
		int rc = render_create(dev, &rd, &v[i].r, err, sizeof err);
		if (v[i].count_atomic)
			unsetenv("TASLAB_COUNT_ATOMICS");
		if (rc) {
			fprintf(stderr, "bench_methods: %s: %s\n", v[i].label, err);
			return 1;
		}
	}
	FILE *out = fopen(argv[5], "w");
	if (!out) {
		perror(argv[5]);
		return 1;
	}
	int rc = 0;
	size_t px = (size_t)w * h;
	mtr_flip *fl = NULL;
	float *flip_ref = NULL, *flip_test = NULL;
	if (flip) {
		if (mtr_flip_create(MTR_FLIP_PPD_DEFAULT, &fl, err, sizeof err)) {
			fprintf(stderr, "bench_methods: flip: %s\n", err);
			return 1;
		}
		flip_ref = malloc(px * 3 * sizeof(float));
		flip_test = malloc(px * 3 * sizeof(float));
		if (!flip_ref || !flip_test) {
			fprintf(stderr, "bench_methods: out of memory\n");
			return 1;
		}
	}
	uint8_t *first_disp = malloc(px * 4), *sa_disp = NULL;
	int sa_index = -1;
	for (int i = 0; i < nv; i++)
		if (!strcmp(v[i].label, "sa"))
			sa_index = i;
	/* sa's frame is compared with every variant, those before it too: render it first within each frame */
	if (sa_index > 0) {
		bench_variant t = v[sa_index];
		memmove(&v[2], &v[1], (size_t)(sa_index - 1) * sizeof v[0]);
		v[1] = t;
		sa_index = 1;
	}
	if (sa_index >= 0)
		sa_disp = malloc(px * 4);
	for (unsigned f = first; f < end && !rc && first_disp; f++) {
		for (int i = 0; i < nv; i++) {
			frame_image img;
			frame_stats st;
			if (render_frame(v[i].r, f, &img, &st, err, sizeof err)) {
				fprintf(stderr, "bench_methods: %s frame %u: %s\n", v[i].label, f, err);
				rc = 1;
				break;
			}
			size_t hist[256] = {0};
			double sum = 0;
			if (i == 0) {
				memcpy(first_disp, img.display_rgba, px * 4);
				if (fl)
					to_rgb(first_disp, px, flip_ref);
			}
			if (i == sa_index && sa_disp)
				memcpy(sa_disp, img.display_rgba, px * 4);
			for (size_t k = 0; k < px; k++) {
				int m = 0;
				for (int c = 0; c < 3; c++) {
					int d = abs((int)img.display_rgba[k * 4 + c] - (int)first_disp[k * 4 + c]);
					m = d > m ? d : m;
				}
				hist[m]++, sum += m;
			}
			int p99 = 0;
			for (size_t acc = 0; p99 < 255 && (acc += hist[p99]) * 100 < px * 99;)
				p99++;
			size_t e8 = 0; /* exceed_8: pixels more than 8 code values from the reference */
			for (int k = 9; k < 256; k++)
				e8 += hist[k];
			fprintf(out, "%s,%u,%lld,%lld,%lld,%lld,%lld,%.4f,%lld,q_mean=%.4f,q_p99=%d,q_e8=%.6f", v[i].label, f,
				(long long)st.visible_samples, (long long)st.shaded_samples, (long long)st.reused_samples,
				(long long)st.new_units, (long long)st.late_samples, st.gpu_ms_total,
				(long long)st.allocated_samples, sum / (double)px, p99, (double)e8 / (double)px);
			if (fl) {
				double fm = 0;
				to_rgb(img.display_rgba, px, flip_test);
				if (mtr_flip_compute(fl, w, h, flip_ref, flip_test, NULL, 2, &fm, err, sizeof err)) {
					fprintf(stderr, "bench_methods: flip: %s\n", err);
					rc = 1;
					break;
				}
				fprintf(out, ",flip=%.6f", fm);
			}
			if (sa_disp) {
				static const int T[5] = {4, 8, 16, 32, 64};
				size_t over[5] = {0};
				for (size_t k = 0; k < px; k++) {
					int m = 0;
					for (int c = 0; c < 3; c++) {
						int d = abs((int)img.display_rgba[k * 4 + c] - (int)sa_disp[k * 4 + c]);
						m = d > m ? d : m;
					}
					for (int t = 0; t < 5; t++)
						over[t] += m > T[t];
				}
				for (int t = 0; t < 5; t++)
					fprintf(out, ",sa_e%d=%.6f", T[t], (double)over[t] / (double)px);
			}
			for (uint32_t e = 0; e < st.extra_count; e++)
				if (!strcmp(st.extra_names[e], "cpu_ms_alloc"))
					fprintf(out, ",cpu_ms_alloc=%.4f", st.extra[e]);
			for (uint32_t p = 0; p < st.pass_count; p++)
				fprintf(out, ",%s=%.4f", st.pass_names[p], st.gpu_ms[p]);
			fputc('\n', out);
		}
		fflush(out);
		if ((f - first + 1) % 10 == 0)
			fprintf(stderr, "bench_methods: %s %s: %u/%u frames\n", s->name, argv[2], f - first + 1, end - first);
	}
	fclose(out);
	free(first_disp);
	free(sa_disp);
	free(flip_ref);
	free(flip_test);
	mtr_flip_destroy(&fl);
	for (int i = 0; i < nv; i++)
		render_destroy(&v[i].r);
	vkdev_destroy(&dev);
	scene_destroy(&s);
	return rc;
}
