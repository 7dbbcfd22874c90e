/*
 * json_strict.c - RFC 8259 numbers and strings over raw text (json_strict.h).
 *
 * One loop over the bytes with two states: outside a string, where '"' opens one and a run of
 * number characters starting with '-' or a digit is matched against the number grammar
 * (number_end); inside one, where a backslash takes the next byte with it, "\u0000" and bytes
 * below 0x20 are refused, and '"' closes it. An unterminated string or number at the end passes:
 * cJSON reports the cut.
 */
#include "json_strict.h"

static int is_digit(char c)
{
    return c >= '0' && c <= '9';
}

static int is_number_char(char c)
{
    return is_digit(c) || c == '-' || c == '+' || c == '.' || c == 'e' || c == 'E';
}

/* Matches -?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)? at s[0..n) whole; NULL when it does,
 * else why not. */
static const char *number_error(const char *s, size_t n)
{
    size_t i = 0;
    if (s[i] == '-') i++;
    if (i == n || !is_digit(s[i])) return "a minus sign must be followed by a digit";
    if (s[i] == '0') {
        i++;
        if (i < n && is_digit(s[i])) return "a number must not have a leading zero";
    } else {
        while (i < n && is_digit(s[i])) i++;
    }
    if (i < n && s[i] == '.') {
        i++;
        if (i == n || !is_digit(s[i])) return "a decimal point must be followed by a digit";
        while (i < n && is_digit(s[i])) i++;
    }
    if (i < n && (s[i] == 'e' || s[i] == 'E')) {
        i++;
        if (i < n && (s[i] == '+' || s[i] == '-')) i++;
        if (i == n || !is_digit(s[i])) return "an exponent must have a digit";
        while (i < n && is_digit(s[i])) i++;
    }
    if (i < n) return "a number must be -?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)?";
    return NULL;
}

int json_strict_check(const char *text, size_t len, size_t *pos, const char **why)
{
    size_t i = 0;
    while (i < len) {
        char c = text[i];
        if (c == '"') {
            /* a string: up to the closing quote */
            for (i++; i < len && text[i] != '"'; i++) {
                unsigned char b = (unsigned char)text[i];
                if (b < 0x20) {
                    *pos = i;
                    *why = "a string must not hold a control character (escape it)";
                    return -1;
                }
                if (b != '\\') continue;
                if (i + 5 < len && text[i + 1] == 'u' && text[i + 2] == '0' && text[i + 3] == '0' &&
                    text[i + 4] == '0' && text[i + 5] == '0') {
                    *pos = i;
                    *why = "a string must not hold \\u0000";
                    return -1;
                }
                if (i + 1 < len) i++; /* the escaped byte ('"', '\\', ...) */
            }
            i++; /* past the closing quote */
        } else if (c == '-' || is_digit(c)) {
            size_t start = i;
            while (i < len && is_number_char(text[i])) i++;
            const char *e = number_error(text + start, i - start);
            if (e != NULL) {
                *pos = start;
                *why = e;
                return -1;
            }
        } else {
            i++;
        }
    }
    return 0;
}
