/* tl_clock.h — the one clock of taslab: monotonic seconds for wall times and progress, and UTC time
 * stamps for manifests. */
#ifndef TASLAB_TL_CLOCK_H
#define TASLAB_TL_CLOCK_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Seconds on a monotonic clock (CLOCK_MONOTONIC); only differences are meaningful. */
double tl_clock_s(void);
/* Current UTC time as "YYYY-MM-DDTHH:MM:SSZ" into `out` (at least 21 bytes). */
void tl_clock_utc(char *out, size_t out_size);

#ifdef __cplusplus
}
#endif
#endif
