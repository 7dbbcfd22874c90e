/*
 * http_gzip.c - gzip content coding of replies (http_gzip.h).
 *
 * Level: zlib's fastest (1). On a 2,000-member family table (GET /api/families/{id}, 638 KB of
 * JSON) it gives 126 KB in 2.6 ms, against 109 KB in 8.1 ms at zlib's default level 6: the
 * service answers such polls every 2 s per open page, on libmicrohttpd's threads, so the faster
 * level keeps a large table from holding a thread (measured with zlib 1.2.13 on the AMD EPYC
 * machine of bench/NOTEBOOK.md).
 */
#include "http_gzip.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define ZLIB_CONST /* next_in points to const bytes */
#include <zlib.h>

/* deflateInit2's windowBits for a gzip wrapper: 15 (a 32 KiB window) + 16 */
#define GZIP_WINDOW_BITS (15 + 16)
#define GZIP_MEM_LEVEL 8
/* bytes of the body read at once by a stream */
#define GZIP_STREAM_IN (64 * 1024)

struct http_gzip_stream {
    ptrdiff_t (*fn)(void *arg, char *buf, size_t max);
    void (*free_fn)(void *arg);
    void *arg;
    z_stream z;
    int in_end; /* the body's function said its end */
    int done;   /* the member's trailer is written */
    char in[GZIP_STREAM_IN];
};

/* 1 if the parameters after a coding's name (";q=0.5", ";q=0 ; x=y") give it weight 0 */
static int weight_zero(const char *p, const char *end)
{
    while (p < end) {
        while (p < end && (*p == ';' || *p == ' ' || *p == '\t')) p++;
        if (end - p >= 2 && (p[0] == 'q' || p[0] == 'Q') && p[1] == '=') {
            p += 2;
            /* a weight is 0 when written "0", "0." or "0.0" .. "0.000"; "1", "0.5" are not */
            if (p >= end || *p != '0') return 0;
            p++;
            if (p < end && *p == '.') {
                p++;
                while (p < end && *p == '0') p++;
            }
            while (p < end && (*p == ' ' || *p == '\t')) p++;
            return p >= end || *p == ';';
        }
        while (p < end && *p != ';') p++;
    }
    return 0;
}

int http_accepts_gzip(const char *accept_encoding)
{
    if (accept_encoding == NULL) return 0;
    int gzip = -1, star = -1; /* -1 not named, 0 named with weight 0, 1 admitted */
    const char *p = accept_encoding;
    while (*p) {
        while (*p == ',' || *p == ' ' || *p == '\t') p++;
        const char *item = p;
        while (*p && *p != ',') p++;
        const char *name_end = item;
        while (name_end < p && *name_end != ';' && *name_end != ' ' && *name_end != '\t')
            name_end++;
        const size_t n = (size_t)(name_end - item);
        const int ok = !weight_zero(name_end, p);
        if ((n == 4 && strncasecmp(item, "gzip", 4) == 0) ||
            (n == 6 && strncasecmp(item, "x-gzip", 6) == 0)) {
            gzip = gzip == 1 ? 1 : ok;
        } else if (n == 1 && item[0] == '*') {
            star = star == 1 ? 1 : ok;
        }
    }
    return gzip >= 0 ? gzip : star == 1;
}

int http_gzip(const char *in, size_t len, char **out, size_t *out_len)
{
    *out = NULL;
    *out_len = 0;
    if (len == 0 || len > UINT_MAX) return -1;
    z_stream z;
    memset(&z, 0, sizeof z);
    if (deflateInit2(&z, Z_BEST_SPEED, Z_DEFLATED, GZIP_WINDOW_BITS, GZIP_MEM_LEVEL,
                     Z_DEFAULT_STRATEGY) != Z_OK)
        return -1;
    /* room for one byte less than the input: a result that does not fit is no gain */
    const size_t cap = len - 1;
    char *buf = cap > 0 ? malloc(cap) : NULL;
    int rc = -1;
    if (buf != NULL) {
        z.next_in = (const Bytef *)in;
        z.avail_in = (uInt)len;
        z.next_out = (Bytef *)buf;
        z.avail_out = (uInt)cap;
        if (deflate(&z, Z_FINISH) == Z_STREAM_END) {
            *out = buf;
            *out_len = cap - z.avail_out;
            rc = 0;
        }
    }
    deflateEnd(&z);
    if (rc != 0) free(buf);
    return rc;
}

int http_gzip_type(const char *content_type)
{
    if (content_type == NULL) return 0;
    static const char *const text[] = {"application/json", "application/yaml", "text/"};
    for (size_t i = 0; i < sizeof text / sizeof text[0]; i++) {
        const size_t n = strlen(text[i]);
        if (strncasecmp(content_type, text[i], n) != 0) continue;
        const char next = content_type[n];
        if (text[i][n - 1] == '/' || next == '\0' || next == ';' || next == ' ') return 1;
    }
    return 0;
}

http_gzip_stream *http_gzip_stream_new(ptrdiff_t (*fn)(void *arg, char *buf, size_t max),
                                       void (*free_fn)(void *arg), void *arg)
{
    http_gzip_stream *g = calloc(1, sizeof *g);
    if (g == NULL) return NULL;
    if (deflateInit2(&g->z, Z_BEST_SPEED, Z_DEFLATED, GZIP_WINDOW_BITS, GZIP_MEM_LEVEL,
                     Z_DEFAULT_STRATEGY) != Z_OK) {
        free(g);
        return NULL;
    }
    g->fn = fn;
    g->free_fn = free_fn;
    g->arg = arg;
    return g;
}

ptrdiff_t http_gzip_stream_read(void *p, char *buf, size_t max)
{
    http_gzip_stream *g = p;
    if (g->done) return 0;
    if (max > UINT_MAX) max = UINT_MAX;
    g->z.next_out = (Bytef *)buf;
    g->z.avail_out = (uInt)max;
    /* until buf is full or the member ends: deflate's output lags its input by up to its window,
       so a piece of the body may give no bytes yet */
    while (g->z.avail_out > 0) {
        if (g->z.avail_in == 0 && !g->in_end) {
            const ptrdiff_t n = g->fn(g->arg, g->in, sizeof g->in);
            if (n < 0 || n > (ptrdiff_t)sizeof g->in) return -1;
            if (n == 0) {
                g->in_end = 1;
            } else {
                g->z.next_in = (const Bytef *)g->in;
                g->z.avail_in = (uInt)n;
            }
        }
        const int rc = deflate(&g->z, g->in_end ? Z_FINISH : Z_NO_FLUSH);
        if (rc == Z_STREAM_END) {
            g->done = 1;
            break;
        }
        if (rc != Z_OK && rc != Z_BUF_ERROR) return -1;
    }
    const size_t n = max - g->z.avail_out;
    return n > 0 ? (ptrdiff_t)n : 0; /* 0 only when the member ended with the last call */
}

void http_gzip_stream_free(void *p)
{
    http_gzip_stream *g = p;
    if (g == NULL) return;
    deflateEnd(&g->z);
    if (g->free_fn) g->free_fn(g->arg);
    free(g);
}
