/*
 * test_json_strict.c - RFC 8259 numbers and strings (server/json_strict.c): the numbers of the
 * grammar's every branch pass, each lenient form cJSON takes is refused at its first byte with its
 * reason, strings hold no control character and no \u0000, and what looks like a number inside a
 * string is not one. The oracle for "passes" is the RFC's grammar written as a POSIX extended
 * regular expression (regcomp), independent of the scanner.
 */
#include <criterion/criterion.h>
#include <regex.h>
#include <stdio.h>
#include <string.h>

#include "json_strict.h"

static void expect_ok(const char *text)
{
    size_t pos = 12345;
    const char *why = NULL;
    cr_assert_eq(json_strict_check(text, strlen(text), &pos, &why), 0, "%s: refused: %s", text,
                 why ? why : "");
}

static void expect_bad(const char *text, size_t at, const char *reason)
{
    size_t pos = 12345;
    const char *why = NULL;
    cr_assert_eq(json_strict_check(text, strlen(text), &pos, &why), -1, "%s: passed", text);
    cr_assert_eq(pos, at, "%s: at %zu, not %zu", text, pos, at);
    cr_assert_str_eq(why, reason, "%s", text);
}

#define LEADING_ZERO "a number must not have a leading zero"
#define POINT "a decimal point must be followed by a digit"
#define EXPONENT "an exponent must have a digit"
#define MINUS "a minus sign must be followed by a digit"
#define GRAMMAR "a number must be -?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)?"
#define CONTROL "a string must not hold a control character (escape it)"
#define NUL "a string must not hold \\u0000"

Test(json_strict, rfc8259_numbers_pass)
{
    const char *ok[] = {"0",
                        "-0",
                        "7",
                        "-12",
                        "10",
                        "0.5",
                        "-0.125",
                        "1e5",
                        "1E5",
                        "1e+5",
                        "1e-5",
                        "2.5e-07",
                        "0e0",
                        "1e007",
                        "123456789012345678901234567890",
                        "[1,-2.5,3e3]",
                        "{\"a\":0,\"b\":[0.0,-0.0e-0]}"};
    for (size_t i = 0; i < sizeof ok / sizeof ok[0]; i++) expect_ok(ok[i]);
}

Test(json_strict, lenient_numbers_are_refused_at_their_first_byte)
{
    expect_bad("01", 0, LEADING_ZERO);
    expect_bad("-01", 0, LEADING_ZERO);
    expect_bad("{\"duration\":01}", 12, LEADING_ZERO);
    expect_bad("00", 0, LEADING_ZERO);
    expect_bad("1.", 0, POINT);
    expect_bad("[1.e5]", 1, POINT);
    expect_bad("-1.]", 0, POINT);
    expect_bad("1e", 0, EXPONENT);
    expect_bad("1e+", 0, EXPONENT);
    expect_bad("2E-,", 0, EXPONENT);
    expect_bad("-", 0, MINUS);
    expect_bad("[-.5]", 1, MINUS);
    expect_bad("--1", 0, MINUS);
    expect_bad("1.2.3", 0, GRAMMAR);
    expect_bad("1e5e5", 0, GRAMMAR);
    expect_bad("1-2", 0, GRAMMAR);
    expect_bad("[0, 1, 2, 3.]", 10, POINT);
}

Test(json_strict, strings_hold_no_control_character_and_no_u0000)
{
    expect_ok("\"tab\\t newline\\n \\u0001 \\u0020 \\\\u0000\"");
    expect_ok("\"\\\"\"");
    expect_ok("\"caf\xc3\xa9 \x7f\"");
    expect_bad("{\"name\":\"a\\u0000b\"}", 10, NUL);
    expect_bad("\"\\u0000\"", 1, NUL);
    expect_bad("\"a\tb\"", 2, CONTROL);
    expect_bad("\"line\nbreak\"", 5, CONTROL);
    expect_bad("[\"\x01\"]", 2, CONTROL);
}

Test(json_strict, numbers_inside_strings_and_keys_are_text)
{
    expect_ok("{\"01\":\"1.\",\"x\":\"1e\"}");
    expect_ok("\"-\"");
    expect_ok("{\"a\\\"01\":1}");
}

Test(json_strict, the_first_error_wins_and_the_rest_is_left_to_cjson)
{
    expect_bad("[01, \"\\u0000\"]", 1, LEADING_ZERO);
    expect_bad("[\"\\u0000\", 01]", 2, NUL);
    /* not JSON in other ways, but nothing this check owns */
    expect_ok("{\"a\": NaN, \"b\": [1,}");
    expect_ok("\"unterminated");
    expect_ok("\"ends in a backslash\\");
    expect_ok("");
    size_t pos;
    const char *why;
    cr_assert_eq(json_strict_check(NULL, 0, &pos, &why), 0);
}

Test(json_strict, agrees_with_the_rfc_grammar_on_every_short_number_text)
{
    /* every string of up to 4 characters over the number alphabet: the scanner passes exactly
       those that match the RFC's grammar */
    regex_t rfc;
    cr_assert_eq(regcomp(&rfc, "^-?(0|[1-9][0-9]*)(\\.[0-9]+)?([eE][+-]?[0-9]+)?$",
                         REG_EXTENDED | REG_NOSUB),
                 0);
    const char alphabet[] = "01-+.e";
    const int k = (int)sizeof alphabet - 1;
    int checked = 0;
    for (int n = 1; n <= 4; n++) {
        int total = 1;
        for (int i = 0; i < n; i++) total *= k;
        for (int code = 0; code < total; code++) {
            char s[8];
            int c = code;
            for (int i = 0; i < n; i++, c /= k) s[i] = alphabet[c % k];
            s[n] = '\0';
            if (s[0] != '-' && (s[0] < '0' || s[0] > '9')) continue; /* not a number's start */
            size_t pos;
            const char *why;
            int ours = json_strict_check(s, (size_t)n, &pos, &why) == 0;
            int theirs = regexec(&rfc, s, 0, NULL, 0) == 0;
            cr_assert_eq(ours, theirs, "\"%s\": scanner %d, grammar %d", s, ours, theirs);
            checked++;
        }
    }
    cr_assert_gt(checked, 500);
    regfree(&rfc);
}
