/* study_serve.h — the study's web server (libmicrohttpd), bound to 127.0.0.1 by default.
 *   GET  /p/<code>               the participant page (an unguessable 128-bit link code)
 *   GET  /api/<code>/trial       the next unanswered trial (JSON), or {"done": true}
 *   POST /api/<code>/answer      {"trial": i, "answer": -2..2, "rt_ms": n}: committed to SQLite before the
 *                                200 reply; 400 malformed, 404 unknown trial, 409 answered already, 413 too large
 *   GET  /clips/<path>           files inside the stimulus folder only, with single-range Range support
 *   GET  /admin/export.csv?token=T, /admin/export-pwcmp.csv?token=T   (403 without the study's token) */
#ifndef TASLAB_STUDY_SERVE_H
#define TASLAB_STUDY_SERVE_H

#include <stddef.h>
#include <stdint.h>

#include "taslab/study.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sty_server sty_server;

/* Starts serving (own threads); port 0 picks a free port. The study must outlive the server. */
int sty_server_start(sty *s, const char *bind_addr, uint16_t port, unsigned threads, sty_server **out, char *err,
		     size_t err_size);
uint16_t sty_server_port(const sty_server *sv);
void sty_server_stop(sty_server **sv);

#ifdef __cplusplus
}
#endif
#endif
