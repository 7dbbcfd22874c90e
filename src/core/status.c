/*
 * status.c - names of the library's result codes and the one helper that fills an error buffer.
 */
#include "status.h"

#include <stdarg.h>
#include <stdio.h>

const char *ctc_status_name(ctc_status s)
{
    switch (s) {
    case CTC_OK:
        return "ok";
    case CTC_EINVAL:
        return "invalid input";
    case CTC_ENOMEM:
        return "out of memory";
    case CTC_ESINGULAR:
        return "singular matrix";
    }
    return "unknown status";
}

ctc_status ctc_fail(ctc_status s, char *err, size_t errlen, const char *fmt, ...)
{
    if (err != NULL && errlen > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, errlen, fmt, ap);
        va_end(ap);
    }
    return s;
}
