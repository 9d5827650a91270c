/* study_telemetry.h (private) — remote participants' playback (issue 28 "Remote participants"): what the participant
 * page measured while a trial played, the server's verdict on it, and the retake of a trial whose playback was broken
 * (study_telemetry.c). The page only measures; the verdict is the server's, from these limits (README "Telemetry"):
 *   - dropped frames: more than STY_DROPPED_SHARE of the frames played, and more than STY_DROPPED_MIN (Chromium
 *     reported one dropped frame for every 6-frame clip it played in test_study_telemetry_browser: one per clip of a
 *     pair is tolerated);
 *   - the page hidden (visibilitychange) while a clip played;
 *   - a clip played longer than STY_LONG_FACTOR x its duration + STY_LONG_SLACK_MS (a stall; the duration is the
 *     design's, from pairs.json frames and fps, never the page's).
 * A broken trial's answer is stored (with the reason in answers.broken) but not counted, and the trial is appended to
 * the participant's plan again (trials.retake_of), at most STY_RETAKES_MAX times per planned trial; training trials
 * are not retaken. Answers without telemetry (API clients) are counted. */
#ifndef TASLAB_STUDY_TELEMETRY_H
#define TASLAB_STUDY_TELEMETRY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "study_internal.h"

#define STY_DROPPED_SHARE 0.01
#define STY_DROPPED_MIN 2
#define STY_LONG_FACTOR 1.5
#define STY_LONG_SLACK_MS 1000.0
#define STY_RETAKES_MAX 2

typedef struct sty_telemetry {
	int64_t play_ms[2];  /* wall time from play() to ended of clip A and clip B (the longest over the trial's playings) */
	int64_t dropped;     /* dropped video frames, summed over the trial's playings (getVideoPlaybackQuality) */
	int64_t frames;      /* total video frames, likewise */
	int64_t hidden;      /* times the page was hidden (visibilitychange) from the trial's first play to the answer */
	int64_t hidden_ms;   /* time it was hidden then */
	int64_t hidden_play; /* of those times, while a clip played */
	int fullscreen;      /* 1: the page was full screen when the answer was given */
} sty_telemetry;

/* The server's verdict: "" when the playback was sound, else the reasons ("dropped", "hidden", "long", joined by
 * ';') into `why`. clip_ms: the clip's duration (NAN or <= 0: unknown, no "long" check). Returns why. */
const char *sty_playback_verdict(const sty_telemetry *t, double clip_ms, char *why, size_t why_size);

/* Within the caller's transaction, after the answer to trial `trial` of participant `pid` was inserted: stores `t`
 * with it and, when the verdict says broken, marks the answer broken and appends the retake. *broken_out (may be
 * NULL): the verdict (""). Errors: TL_ERR_DB. */
int sty_telemetry_store(sty *s, int64_t pid, uint32_t trial, const sty_telemetry *t, char *broken_out, size_t broken_size,
			char *err, size_t err_size);

#endif
