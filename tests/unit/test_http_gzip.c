/*
 * test_http_gzip.c - the gzip coding of replies (server/http_gzip.c).
 *
 * Accept-Encoding: a table of header values against what RFC 9110 section 12.5.3 says of them
 * (codings compared without regard to case, weights, "*", "x-gzip", weight 0 refusing). The
 * compression: what http_gzip makes is inflated by zlib's own gzip reader (a second
 * implementation of the format's reading side) back to the input, byte for byte, for JSON-like
 * text, runs of one byte and sizes from HTTP_GZIP_MIN to 4 MiB; a body that does not shrink
 * (random bytes) and an empty one are refused, leaving nothing to free.
 */
#include <criterion/criterion.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define ZLIB_CONST
#include <zlib.h>

#include "http_gzip.h"

Test(http_gzip, accept_encoding_values_admit_gzip_as_rfc_9110_says)
{
    static const struct {
        const char *value;
        int gzip;
    } cases[] = {
        {NULL, 0},
        {"", 0},
        {"identity", 0},
        {"br", 0},
        {"deflate, br", 0},
        {"gzip", 1},
        {"GZip", 1},
        {"x-gzip", 1},
        {"gzip, deflate", 1},
        {"deflate, gzip", 1},
        {"gzip, deflate, br, zstd", 1},
        {"br;q=1.0, gzip;q=0.8, *;q=0.1", 1},
        {"gzip;q=0.001", 1},
        {"gzip ; q=0.5", 1},
        {"gzip;q=0", 0},
        {"gzip;q=0.0", 0},
        {"gzip;q=0.000", 0},
        {"gzip;Q=0", 0},
        {"gzip; q=0 ", 0},
        {"gzip;level=1;q=0", 0},
        {"*", 1},
        {"*;q=0", 0},
        {"br, *", 1},
        {"gzip;q=0, *", 0}, /* gzip named: its own weight decides */
        {"*;q=0, gzip", 1},
        {"gzipx", 0},
        {"xgzip", 0},
        {",, gzip ,", 1},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        cr_expect_eq(http_accepts_gzip(cases[i].value), cases[i].gzip, "\"%s\": %d, want %d",
                     cases[i].value ? cases[i].value : "(none)", http_accepts_gzip(cases[i].value),
                     cases[i].gzip);
    }
}

/* inflates a gzip member (zlib's reader, windowBits 15 + 16: gzip only) into a new buffer of
   exactly want bytes; NULL if it is not a whole gzip member of that length */
static char *gunzip(const char *in, size_t len, size_t want)
{
    char *out = malloc(want + 1);
    cr_assert_not_null(out);
    z_stream z;
    memset(&z, 0, sizeof z);
    cr_assert_eq(inflateInit2(&z, 15 + 16), Z_OK);
    z.next_in = (const Bytef *)in;
    z.avail_in = (uInt)len;
    z.next_out = (Bytef *)out;
    z.avail_out = (uInt)(want + 1);
    const int rc = inflate(&z, Z_FINISH);
    const int whole = rc == Z_STREAM_END && z.total_out == want && z.avail_in == 0;
    inflateEnd(&z);
    if (!whole) {
        free(out);
        return NULL;
    }
    return out;
}

/* JSON-like text of len bytes: a family table's shape, rows with counters and numbers */
static char *table_text(size_t len, uint64_t seed)
{
    char *s = malloc(len + 64);
    cr_assert_not_null(s);
    size_t n = 0;
    for (long row = 0; n < len; row++) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        n += (size_t)sprintf(s + n, "{\"job\":%ld,\"status\":\"done\",\"e_rms\":%.17g},", row,
                             (double)(seed >> 11) * 0x1p-53);
    }
    return s;
}

Test(http_gzip, what_it_makes_inflates_back_to_the_body)
{
    const size_t sizes[] = {HTTP_GZIP_MIN, 4096, 65536 + 17, 1u << 20, 4u << 20};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        for (int kind = 0; kind < 2; kind++) {
            const size_t len = sizes[i];
            char *body = table_text(len, 7 + i);
            if (kind == 1) memset(body, 'x', len); /* one byte repeated */
            char *gz = NULL;
            size_t gz_len = 0;
            cr_assert_eq(http_gzip(body, len, &gz, &gz_len), 0, "%zu bytes, kind %d", len, kind);
            cr_assert_lt(gz_len, len);
            cr_assert_geq(gz_len, 18, "a gzip member has a 10-byte header and an 8-byte trailer");
            cr_assert_eq((unsigned char)gz[0], 0x1f);
            cr_assert_eq((unsigned char)gz[1], 0x8b);
            char *back = gunzip(gz, gz_len, len);
            cr_assert_not_null(back, "%zu bytes, kind %d: not a gzip member of the body's size",
                               len, kind);
            cr_assert_arr_eq(back, body, len, "%zu bytes, kind %d: inflated differently", len,
                             kind);
            if (kind == 0 && len >= 65536) { /* the reply this is for: several times smaller */
                cr_expect_lt(gz_len * 3, len, "%zu bytes of a table: %zu in gzip", len, gz_len);
            }
            free(back);
            free(gz);
            free(body);
        }
    }
}

Test(http_gzip, a_body_that_does_not_shrink_is_refused)
{
    const size_t len = 8192;
    unsigned char *body = malloc(len);
    cr_assert_not_null(body);
    uint64_t x = 88172645463325252ull;
    for (size_t i = 0; i < len; i++) { /* xorshift64: bytes that deflate cannot shorten */
        x ^= x << 13, x ^= x >> 7, x ^= x << 17;
        body[i] = (unsigned char)(x >> 56);
    }
    char *gz = (char *)1;
    size_t gz_len = 1;
    cr_assert_eq(http_gzip((const char *)body, len, &gz, &gz_len), -1);
    cr_assert_null(gz);
    cr_assert_eq(gz_len, 0);
    cr_assert_eq(http_gzip("", 0, &gz, &gz_len), -1);
    cr_assert_null(gz);
    free(body);
}
