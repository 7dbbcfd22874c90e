/*
 * json_strict.h - the RFC 8259 checks cJSON 1.7 leaves out, made over the raw text before cJSON
 * parses it.
 *
 * cJSON reads a number with strtod over the characters [0-9+-.eE], so it takes "01", "1.", ".5",
 * "1e", "+1" and "1.e5" as numbers; and it decodes "\u0000" into a zero byte, which cuts the
 * C string it returns short without a word. A job is a contract: what is not JSON is refused
 * (RFC 8259 section 6: number = [ "-" ] int [ frac ] [ exp ], int = "0" / digit1-9 *DIGIT,
 * frac = "." 1*DIGIT, exp = ("e" / "E") [ "-" / "+" ] 1*DIGIT; section 7: a string holds no
 * unescaped character below U+0020).
 *
 * The check is one pass, O(length), with no allocation. It knows strings (from '"' to the next
 * unescaped '"') from the rest of the text, and outside strings takes every run of the number
 * characters [0-9+-.eE] that starts with '-' or a digit as one number, which must match the
 * grammar whole. It is not a parser: it passes text that is not JSON in other ways (a missing
 * comma, "NaN", a truncated document), which cJSON then refuses.
 */
#ifndef JSON_STRICT_H
#define JSON_STRICT_H

#include <stddef.h>

/* Checks the numbers and strings of the len bytes at text (NULL with len 0 is empty). Returns 0
 * when they are all RFC 8259's; otherwise -1, with *pos the offset of the first offending byte
 * (the first byte of a bad number, the backslash of "\u0000", the control character) and *why a
 * static English reason ("a number must not have a leading zero"). pos and why must not be NULL.
 * Thread safety: pure; any number of threads may call it. */
int json_strict_check(const char *text, size_t len, size_t *pos, const char **why);

#endif
