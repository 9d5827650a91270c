/* buf.c — the growing text buffer of tl_buf.h. */
#include "taslab/tl_buf.h"
#include "taslab/tl_error.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Room for n more bytes and the NUL: TL_OK or TL_ERR_NOMEM. */
static int reserve(tl_buf *b, size_t n)
{
	if (b->failed)
		return TL_ERR_NOMEM;
	if (b->len + n + 1 <= b->cap)
		return 0;
	size_t cap = b->cap ? b->cap : 4096;
	while (cap < b->len + n + 1)
		cap *= 2;
	char *t = realloc(b->s, cap);
	if (!t) {
		b->failed = 1;
		return TL_ERR_NOMEM;
	}
	b->s = t;
	b->cap = cap;
	return 0;
}

int tl_buf_append(tl_buf *b, const char *s, size_t n)
{
	if (reserve(b, n))
		return TL_ERR_NOMEM;
	memcpy(b->s + b->len, s, n);
	b->len += n;
	b->s[b->len] = 0;
	return 0;
}

int tl_buf_printf(tl_buf *b, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	int n = vsnprintf(NULL, 0, fmt, ap);
	va_end(ap);
	if (n < 0)
		b->failed = 1;
	if (n < 0 || reserve(b, (size_t)n))
		return TL_ERR_NOMEM;
	va_start(ap, fmt);
	vsnprintf(b->s + b->len, b->cap - b->len, fmt, ap);
	va_end(ap);
	b->len += (size_t)n;
	return 0;
}
