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
