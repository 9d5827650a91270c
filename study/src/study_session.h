/* study_session.h (private) — what keeps a participant's session honest (issue 27): one browser session per link
 * (a newer one takes over; answers from the older are refused, never dropped in silence), answers that are stored or
 * refused but never "acknowledged and lost", and clips padded so that no byte length tells the reference from a test
 * clip (blinding). The server (study_serve.c) is built on these calls; they take s->lock like study_select.c's.
 * Errors: a tl_err code, one line in `err`. */
#ifndef TASLAB_STUDY_SESSION_H
#define TASLAB_STUDY_SESSION_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "study_internal.h"

/* What a session call did, for the server's log line and the page's reply. */
typedef struct sty_session_info {
	char label[64];           /* the participant's label (P001) */
	uint32_t answered, total; /* after the call */
	bool restart;             /* sty_session_start: the link had a session already (a reload or another browser) */
	bool repeat;              /* sty_session_answer: this session had stored this very answer already (a retry) */
	bool superseded;          /* sty_session_answer: TL_ERR_CONFLICT because a newer session took the link over */
	char broken[48];          /* sty_session_answer with telemetry: why the playback was broken ("": it was not) */
} sty_session_info;

/* Starts a new session for the participant behind `code` (a random 128-bit id in `session`, stored in the sessions
 * table, which is made when missing); the link's earlier session, if any, is superseded. TL_ERR_NOTFOUND for an
 * unknown code. */
int sty_session_start(sty *s, const char *code, char session[33], sty_session_info *info, char *err, size_t err_size);

/* Stores an answer as sty_answer does (study.h), for session `session` (NULL: no session check, the API without one).
 * With a session: TL_ERR_CONFLICT with info->superseded when it is not the link's current session; TL_OK with
 * info->repeat when this session stored exactly this answer to this trial already (a retried request whose reply
 * was lost); TL_ERR_CONFLICT for any other answered trial. `tm` (NULL: none) is the page's playback telemetry, stored
 * with the answer; a broken playback is stored, not counted, and retaken (study_telemetry.h; info->broken). Progress
 * (info->answered, total) counts planned trials: a broken trial retaken is not one more. */
struct sty_telemetry;
int sty_session_answer(sty *s, const char *code, const char *session, uint32_t trial, int64_t answer, int64_t rt_ms,
		       const struct sty_telemetry *tm, sty_session_info *info, char *err, size_t err_size);

/* Blinding by size: every clip of a scene x camera path (the clips of the conditions sharing a reference clip) is
 * served at one byte length, that of the largest plus STY_PAD_MIN_B, the difference filled by the container's own
 * padding (an EBML Void element for WebM/Matroska, a 'free' box for MP4) after the file's last byte. *padded = that
 * length for the clip behind opaque name `name`, whose file is `rel` (from sty_clip_file) under `root`; 0 when the
 * container has no padding we know (the file is then served as it is). */
#define STY_PAD_MIN_B 16
int sty_clip_padded_size(sty *s, const char *root, const char *name, const char *rel, uint64_t *padded, char *err,
			 size_t err_size);

/* `len` bytes from `offset` into the padding of `pad_total` bytes (>= STY_PAD_MIN_B) that follows a clip of
 * container `ext` (".webm" or ".mp4"). */
void sty_pad_bytes(const char *ext, uint64_t pad_total, uint64_t offset, uint8_t *buf, size_t len);

#endif
