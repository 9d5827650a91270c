/* error.c — tl_strerror, tl_exit_status, tl_error (tl_error.h). */
#include "taslab/tl_error.h"

#include <stdarg.h>
#include <stdio.h>

const char *tl_strerror(int code)
{
	switch (code) {
	case TL_OK: return "success";
	case TL_ERR_ARG: return "bad argument";
	case TL_ERR_INPUT: return "bad or missing input";
	case TL_ERR_OUTPUT: return "cannot write output";
	case TL_ERR_NOMEM: return "out of memory";
	case TL_ERR_VULKAN: return "Vulkan error";
	case TL_ERR_VALIDATION: return "Vulkan validation message";
	case TL_ERR_UNSUPPORTED: return "not supported";
	case TL_ERR_DB: return "database error";
	case TL_ERR_CONFLICT: return "conflict with existing state";
	case TL_ERR_NOTFOUND: return "not found";
	case TL_ERR_INTERRUPTED: return "interrupted";
	case TL_ERR_INTERNAL: return "internal error";
	case TL_ERR_INCOMPLETE: return "incomplete: some parts failed";
	default: return "unknown error";
	}
}

int tl_exit_status(int code)
{
	if (code == TL_OK)
		return 0;
	return code == TL_ERR_ARG || code == TL_ERR_INPUT || code == TL_ERR_UNSUPPORTED ? 2 : 1;
}

int tl_error(char *err, size_t err_size, int code, const char *fmt, ...)
{
	if (err && err_size) {
		va_list ap;
		va_start(ap, fmt);
		vsnprintf(err, err_size, fmt, ap);
		va_end(ap);
	}
	return code;
}
