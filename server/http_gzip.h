/*
 * http_gzip.h - gzip content coding of the service's replies (RFC 9110 section 8.4.1.3): whether a
 * request's Accept-Encoding admits it, and the compression (zlib, RFC 1952 framing).
 *
 * The service compresses the replies it builds in memory (JSON and CSV) when they are at least
 * HTTP_GZIP_MIN bytes and the client accepts gzip (http.c send_reply). Streamed replies and static
 * files are sent as they are.
 */
#ifndef HTTP_GZIP_H
#define HTTP_GZIP_H

#include <stddef.h>

/* Bodies shorter than this are sent as they are: an error or a small record gains a few hundred
 * bytes at most, fewer than its headers. */
#define HTTP_GZIP_MIN 1024

/* 1 if an Accept-Encoding header value admits gzip: a "gzip" or "x-gzip" coding whose weight is
 * not 0, or else "*" whose weight is not 0; 0 otherwise, and for NULL (no header: RFC 9110 allows
 * any coding then, but a client that names none is sent none). Codings are compared without
 * regard to case; "q=0", "q=0.0" .. "q=0.000" are weight 0. */
int http_accepts_gzip(const char *accept_encoding);

/* The gzip member (header, deflate data at zlib's fastest level, trailer) of in[0..len) into a
 * new malloc'd buffer: *out (the caller frees it) and *out_len. Returns 0, or -1 when the result
 * would not be shorter than len, len is over 4 GiB (zlib's counts are 32-bit), or memory ran
 * out; *out is then NULL. */
int http_gzip(const char *in, size_t len, char **out, size_t *out_len);

#endif
