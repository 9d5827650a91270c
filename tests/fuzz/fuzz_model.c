/* fuzz_model.c — libFuzzer harness for saved metric-to-JND models (untrusted input: a MODEL.json someone sent or edited
 * by hand; `study model --model`, `report --model`; study_model.h, issue 28). Each input is read as MODEL.json and used
 * to predict the thresholds of a fixed sweep (two series of T written once in setup).
 * Properties checked beyond "no crash, leak or hang" (ASan + UBSan via scripts/fuzz model):
 *   - every refusal is one non-empty line naming the file;
 *   - an accepted model predicts one row per series, each with 0 <= t_jnd_lo <= t_jnd <= t_jnd_hi (inf allowed) and
 *     never NaN: a threshold, its interval and the open ends as thresholds.csv writes them.
 * Temporary files live in a private folder (in /dev/shm when there is one). */
#define _GNU_SOURCE /* mkdtemp, nftw */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "taslab/study_model.h"
#include "fuzz_tmp.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);


static void setup(void)
{
	fuzz_tmp_make("model", NULL);
	char path[320];
	snprintf(path, sizeof path, "%s/summary.csv", fuzz_dir);
	FILE *f = fopen(path, "w");
	if (!f)
		abort();
	fprintf(f, "scene,camera,camera_motion,method,variant,T,period,status,flip_mean,maxrgb_p99,exceed_8\n"
		   "a,c,moving,ref,ref,,,complete,,,\n");
	static const double T[] = {2, 4, 8, 16, 32, 64};
	for (int i = 0; i < 6; i++) /* a rising series and one that is flat (0 at first) */
		fprintf(f, "a,c,moving,tfr,tfr@%g,%g,,complete,%g,%g,%g\na,c,moving,rrc,rrc/%g,%g,4,complete,%g,%g,%g\n",
			T[i], T[i], 0.004 * T[i], 0.5 * T[i], 0.01 * i, T[i], T[i], i ? 0.02 : 0.0, 3.0, 0.1);
	if (fclose(f))
		abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	if (!fuzz_dir[0])
		setup();
	char in[320], err[1024] = "";
	snprintf(in, sizeof in, "%s/model.json", fuzz_dir);
	FILE *f = fopen(in, "wb");
	if (!f || fwrite(data, 1, size, f) != size || fclose(f))
		abort();
	sty_model_pred *p = NULL;
	size_t n = 0;
	char metric[64];
	if (sty_model_predict(in, fuzz_dir, metric, sizeof metric, &p, &n, err, sizeof err)) {
		if (!err[0] || strchr(err, '\n') || !strstr(err, in))
			__builtin_trap(); /* one line, naming the file */
		free(p);
		return 0;
	}
	for (size_t i = 0; i < n; i++)
		if (isnan(p[i].t_jnd) || isnan(p[i].t_jnd_lo) || isnan(p[i].t_jnd_hi) || !(p[i].t_jnd_lo >= 0) ||
		    !(p[i].t_jnd_lo <= p[i].t_jnd) || !(p[i].t_jnd <= p[i].t_jnd_hi))
			__builtin_trap(); /* a threshold inside its interval */
	free(p);
	return 0;
}
