/* clock.c — monotonic seconds and UTC stamps (tl_clock.h). */
#include "taslab/tl_clock.h"

#include <time.h>

double tl_clock_s(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void tl_clock_utc(char *out, size_t out_size)
{
	time_t now = time(NULL);
	struct tm tmv;
	gmtime_r(&now, &tmv);
	strftime(out, out_size, "%Y-%m-%dT%H:%M:%SZ", &tmv);
}
