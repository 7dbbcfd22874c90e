/*
 * test_http_gzip.c - the gzip coding of replies (server/http_gzip.c).
 *
 * Accept-Encoding: a table of header values against what RFC 9110 section 12.5.3 says of them
 * (codings compared without regard to case, weights, "*", "x-gzip", weight 0 refusing). The
 * compression: what http_gzip makes is inflated by zlib's own gzip reader (a second
 * implementation of the format's reading side) back to the input, byte for byte, for JSON-like
 * text, runs of one byte and sizes from HTTP_GZIP_MIN to 4 MiB; a body that does not shrink
 * (random bytes) and an empty one are refused, leaving nothing to free. The streamed form: a
 * body given in pieces of every size from 1 byte to past the stream's read, read back in pieces
 * of every size from 1 byte, inflates to the body; an empty body is an empty member; a body whose
 * function fails fails the stream; the body's argument is freed with the stream, once.
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

Test(http_gzip, text_types_are_compressed_and_binary_ones_not)
{
    static const struct {
        const char *type;
        int text;
    } cases[] = {
        {"application/json", 1},
        {"application/json; charset=utf-8", 1},
        {"Application/JSON", 1},
        {"text/csv; charset=utf-8", 1},
        {"text/html", 1},
        {"application/yaml", 1},
        {"application/octet-stream", 0},
        {"application/jsonl", 0},
        {"image/png", 0},
        {"", 0},
        {NULL, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        cr_expect_eq(http_gzip_type(cases[i].type), cases[i].text, "\"%s\"",
                     cases[i].type ? cases[i].type : "(none)");
    }
}

/* a body given in pieces: text[0..len) in pieces of `piece` bytes at most (0: as asked), or -1
   once `fail_at` bytes have been given (fail_at < 0: never) */
typedef struct piecewise {
    const char *text;
    size_t len, pos, piece;
    long fail_at;
    int freed;
} piecewise;

static ptrdiff_t piecewise_read(void *arg, char *buf, size_t max)
{
    piecewise *p = arg;
    if (p->fail_at >= 0 && p->pos >= (size_t)p->fail_at) return -1;
    size_t n = p->len - p->pos;
    if (n > max) n = max;
    if (p->piece > 0 && n > p->piece) n = p->piece;
    memcpy(buf, p->text + p->pos, n);
    p->pos += n;
    return (ptrdiff_t)n;
}

static void piecewise_free(void *arg)
{
    ((piecewise *)arg)->freed++;
}

/* the whole member of a stream over p, read in pieces of at most `chunk` bytes (returns its
   length; -1 if a read failed) into out (cap bytes) */
static long read_all(http_gzip_stream *g, size_t chunk, char *out, size_t cap)
{
    size_t n = 0;
    for (;;) {
        cr_assert_lt(n + chunk, cap, "the member outgrew %zu bytes", cap);
        const ptrdiff_t r = http_gzip_stream_read(g, out + n, chunk);
        if (r < 0) return -1;
        if (r == 0) break;
        cr_assert_leq((size_t)r, chunk);
        n += (size_t)r;
    }
    cr_assert_eq(http_gzip_stream_read(g, out, chunk), 0, "a read after the end gives 0");
    return (long)n;
}

Test(http_gzip, a_streamed_body_read_in_any_pieces_inflates_back_to_it)
{
    const size_t lens[] = {0, 1, 5000, 300000};
    const size_t pieces[] = {0, 1, 777, 65536, 70000};
    const size_t chunks[] = {1, 10, 4096, 65536};
    for (size_t a = 0; a < sizeof lens / sizeof lens[0]; a++) {
        char *body = table_text(lens[a] + 1, 3 + a);
        for (size_t b = 0; b < sizeof pieces / sizeof pieces[0]; b++) {
            for (size_t c = 0; c < sizeof chunks / sizeof chunks[0]; c++) {
                if (pieces[b] == 1 && lens[a] > 5000) continue; /* 300000 calls of 1 byte */
                piecewise p = {body, lens[a], 0, pieces[b], -1, 0};
                http_gzip_stream *g = http_gzip_stream_new(piecewise_read, piecewise_free, &p);
                cr_assert_not_null(g);
                const size_t cap = lens[a] + chunks[c] + 4096;
                char *out = malloc(cap);
                cr_assert_not_null(out);
                const long n = read_all(g, chunks[c], out, cap);
                cr_assert_geq(n, 20, "%zu bytes in pieces of %zu, read by %zu: %ld", lens[a],
                              pieces[b], chunks[c], n);
                cr_assert_eq(p.pos, lens[a], "the whole body was read");
                char *back = gunzip(out, (size_t)n, lens[a]);
                cr_assert_not_null(back,
                                   "%zu bytes in pieces of %zu, read by %zu: not a gzip "
                                   "member of the body's size",
                                   lens[a], pieces[b], chunks[c]);
                cr_assert_arr_eq(back, body, lens[a]);
                free(back);
                free(out);
                cr_assert_eq(p.freed, 0);
                http_gzip_stream_free(g);
                cr_assert_eq(p.freed, 1, "the body's argument is freed with the stream, once");
            }
        }
        free(body);
    }
    http_gzip_stream_free(NULL);
}

Test(http_gzip, a_body_that_fails_fails_the_stream)
{
    const size_t len = 200000;
    char *body = table_text(len, 11);
    piecewise p = {body, len, 0, 1000, 150000, 0};
    http_gzip_stream *g = http_gzip_stream_new(piecewise_read, piecewise_free, &p);
    cr_assert_not_null(g);
    char *out = malloc(len + 8192);
    cr_assert_not_null(out);
    cr_assert_eq(read_all(g, 4096, out, len + 8192), -1);
    http_gzip_stream_free(g);
    cr_assert_eq(p.freed, 1);
    free(out);
    free(body);
}
