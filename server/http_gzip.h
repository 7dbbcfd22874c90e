/*
 * http_gzip.h - gzip content coding of the service's replies (RFC 9110 section 8.4.1.3): whether a
 * request's Accept-Encoding admits it, and the compression (zlib, RFC 1952 framing).
 *
 * The service compresses the text replies it builds in memory (JSON, CSV) when they are at least
 * HTTP_GZIP_MIN bytes, and its streamed text replies (a series as JSON or CSV) whatever their
 * size, when the client accepts gzip (http.c send_reply). Binary replies (a series as float32)
 * and static files are sent as they are.
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

/* 1 if a reply of this Content-Type is text that gzip shrinks: application/json, application/yaml
 * and text/..., with or without parameters; 0 for anything else (binary) and NULL. */
int http_gzip_type(const char *content_type);

/* A streamed body in gzip: reads the body from fn(arg, buf, max) (>= 1 bytes written, 0 at its
 * end, -1 on an error), as http.h's http_stream_fn, and gives its gzip member in pieces. */
typedef struct http_gzip_stream http_gzip_stream;

/* A stream over fn and arg, which it owns from then on (free_fn(arg) when it is freed; free_fn
 * may be NULL); NULL if memory runs out, and then arg is still the caller's. */
http_gzip_stream *http_gzip_stream_new(ptrdiff_t (*fn)(void *arg, char *buf, size_t max),
                                       void (*free_fn)(void *arg), void *arg);

/* Writes the next at most max (>= 1) bytes of the gzip member into buf: returns the number
 * written (>= 1), 0 at the end of the member, or -1 when the body's function failed or zlib did
 * (the client then sees a truncated member). g is an http_gzip_stream; the signature is
 * http_stream_fn's. */
ptrdiff_t http_gzip_stream_read(void *g, char *buf, size_t max);

/* Frees the stream and its body's argument; NULL is allowed. Takes void * to serve as a
 * stream's free function. */
void http_gzip_stream_free(void *g);

#endif
