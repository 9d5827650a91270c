/* tl_buf.h — a growing text buffer (generated source: shaders with the view transform inserted, the LUT lookups of
 * a view). Appends after a failed allocation do nothing; check `failed` once at the end. Zero-initialise it; free
 * `s` when done (NULL until the first append). */
#ifndef TASLAB_TL_BUF_H
#define TASLAB_TL_BUF_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tl_buf {
	char *s; /* NUL-terminated text, or NULL */
	size_t len, cap;
	int failed; /* an allocation failed: the text is incomplete */
} tl_buf;

/* Appends n bytes of s. Returns TL_OK, or TL_ERR_NOMEM once the buffer has failed. */
int tl_buf_append(tl_buf *b, const char *s, size_t n);
/* Appends printf-style text. Returns TL_OK, or TL_ERR_NOMEM once the buffer has failed (also after a format
 * vsnprintf cannot expand). */
int tl_buf_printf(tl_buf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#ifdef __cplusplus
}
#endif
#endif
