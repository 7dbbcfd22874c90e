/*
 * status.h - the one table of result codes of the ctcsim library.
 *
 * Numeric kernels (kinematics, GDCA, oracle) return void and assume a validated model; the
 * functions at the library's boundary (build, validate, parse, run) return a ctc_status and, when
 * the caller passes a buffer, a precise message such as "joint 3: axis has zero length".
 */
#ifndef CTC_STATUS_H
#define CTC_STATUS_H

#include <stddef.h>

typedef enum ctc_status {
    CTC_OK = 0,
    CTC_EINVAL,    /* invalid input: the message names the item and the reason */
    CTC_ENOMEM,    /* an allocation failed */
    CTC_ESINGULAR, /* a matrix that must be invertible is (numerically) singular */
} ctc_status;

/* The status's name as a constant string ("ok", "invalid input", ...); never NULL. */
const char *ctc_status_name(ctc_status s);

/* Writes a printf-style message into err (errlen bytes, always terminated) and returns s.
 * err may be NULL (then nothing is written). */
ctc_status ctc_fail(ctc_status s, char *err, size_t errlen, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

#endif
