/*
 * http.h - the HTTP layer of the service on libmicrohttpd: request collection, routing and
 * replies.
 *
 * The daemon runs libmicrohttpd's internal thread pool. For each request it collects the body
 * (refusing bodies over the configured limit with 413 before reading them), then dispatches by
 * method and path to one handler of the route table (routes.c). Handlers answer through the reply
 * helpers below; every error is {"error": {"code", "message", "field"}} with its HTTP status.
 * Paths under /api/ that match no route answer 404 (or 405 with Allow when the path exists
 * for other methods); anything else is a static file from the web root (http_serve_static).
 */
#ifndef HTTP_H
#define HTTP_H

#include <stddef.h>
#include <stdint.h>

/* the most bytes one call of a streamed body's function writes */
#define HTTP_STREAM_BLOCK (64 * 1024)

#include <cjson/cJSON.h>

typedef struct http_server http_server;

/* Writes the next at most max bytes of a streamed body into buf (http_reply_stream): returns the
 * number written (>= 1), 0 at the end of the body, or -1 to stop on an error (the client then
 * sees a truncated body: the connection is closed without the chunked body's last chunk). */
typedef ptrdiff_t (*http_stream_fn)(void *arg, char *buf, size_t max);

/* What a handler sees of a request. Strings are valid for the handler's call only. */
typedef struct http_request {
    const char *method; /* "GET", "POST", ... */
    const char *path;   /* URL path, percent-decoded by libmicrohttpd, without the query */
    const char *body;   /* request body (NUL-terminated; may contain NULs), "" when none */
    size_t body_len;
    const char *params[4]; /* the path's {...} captures, in order, e.g. the job id */
    void *conn;            /* the libmicrohttpd connection (for http_query, http_header) */
} http_request;

/* A reply under construction; handlers fill it with one of the helpers below. */
typedef struct http_reply {
    int status; /* HTTP status */
    char *body; /* malloc'd, owned by the reply */
    size_t body_len;
    const char *content_type;
    char location[128]; /* Location header, "" = none */
    char allow[64];     /* Allow header (405), "" = none */
    int retry_after;    /* Retry-After seconds (503, 429), 0 = none */
    int close;          /* 1: "Connection: close", the connection ends after this reply */
    int fd;             /* static file to send instead of body (>= 0), -1 = none */
    uint64_t fd_size;
    http_stream_fn stream; /* a body made while it is sent instead of body, NULL = none */
    void (*stream_free)(void *arg);
    void *stream_arg;
} http_reply;

typedef void (*http_handler)(const http_request *req, http_reply *rep, void *ctx);

typedef struct http_route {
    const char *method;  /* "GET", "POST", "DELETE" */
    const char *pattern; /* "/api/jobs/{id}/series": each {...} captures one segment */
    http_handler handler;
} http_route;

typedef struct http_config {
    const char *bind;     /* address to listen on, e.g. "127.0.0.1" or "0.0.0.0" */
    int port;             /* 1..65535 (0 = any free port; see http_port) */
    int threads;          /* libmicrohttpd thread pool size, >= 1 */
    size_t max_body;      /* bytes; larger bodies get 413 */
    const char *web_root; /* directory of the static files (web/) */
    const char *token;    /* NULL/"" = none; else POST and DELETE need "Bearer TOKEN" */
    /* the names the Host header may give (its port stripped), comma-separated: a request naming
       another host is answered 421 HOST_NOT_ALLOWED, an HTTP/1.1 request without Host 400
       MISSING_HOST. "*" allows any. NULL or "": the bind address (an IPv6 one in brackets),
       localhost, 127.0.0.1 and [::1], or any host when bound to 0.0.0.0 or ::. Compared without
       regard to case; a bare IPv6 literal is taken as in brackets. */
    const char *allowed_hosts;
    /* connection limits against clients that hold connections open (slowloris); 0 = the
       default in brackets */
    unsigned idle_timeout;    /* s a connection may stay silent before it is closed [30] */
    unsigned max_connections; /* connections open at once; more are closed at accept [1000] */
    unsigned max_per_ip;      /* connections open at once from one address; more are closed at
                                 accept [64] */
    unsigned max_deferred;    /* replies waiting at once off the HTTP threads (http_defer);
                                 past them http_defer refuses [256] */
    unsigned max_deferred_per_client; /* of which from one client address at once; past them
                                         http_defer refuses [0: no limit of its own] */
    const http_route *routes;         /* terminated by a route with method NULL */
    void *ctx;                        /* passed to every handler */
} http_config;

/* Starts listening. Returns 0, or -1 with a message (address in use, bad bind address). */
int http_start(const http_config *config, http_server **out, char *err, size_t errlen);

/* The port actually bound (useful with port 0). */
int http_port(const http_server *s);

/* Stops accepting, finishes the requests in flight and frees s; NULL is allowed. */
void http_stop(http_server *s);

/* A query parameter of the request, or NULL. */
const char *http_query(const http_request *req, const char *key);

/* A request header, or NULL. */
const char *http_header(const http_request *req, const char *name);

/* The client's numeric address (the connection's peer, "127.0.0.1", "::1"; "unknown" when it
 * cannot be had) into buf of len bytes (INET6_ADDRSTRLEN is enough). */
void http_client(const http_request *req, char *buf, size_t len);

/* Replies: JSON (takes ownership of json and deletes it), raw text with a content type (copied),
 * and the error object {"error": {"code", "message", "field"}} (field may be NULL or ""). */
void http_reply_json(http_reply *rep, int status, cJSON *json);
void http_reply_text(http_reply *rep, int status, const char *content_type, const char *text,
                     size_t len);
void http_reply_error(http_reply *rep, int status, const char *code, const char *field,
                      const char *fmt, ...) __attribute__((format(printf, 5, 6)));

/* Takes ownership of a malloc'd buffer as the body. */
void http_reply_buffer(http_reply *rep, int status, const char *content_type, char *buf,
                       size_t len);

/* A body of unknown length made while it is sent, with chunked transfer encoding: fn(arg, buf,
 * max) is called, on the thread that serves the connection, each time the connection has room
 * for more (HTTP_STREAM_BLOCK bytes at most), until it returns 0 or -1. The reply owns arg from
 * here on: free_fn(arg) (may be NULL) is called once, when the response is done with - sent,
 * failed, the client gone, the server stopped, or the reply replaced by another helper before it
 * was sent - on whichever thread that happens, never while fn runs. HEAD sends no body and does
 * not call fn. */
void http_reply_stream(http_reply *rep, int status, const char *content_type, http_stream_fn fn,
                       void (*free_fn)(void *arg), void *arg);

/* For a handler that must wait (POST /api/jobs?wait): finishes the reply off libmicrohttpd's
 * threads, so that a waiting client holds up no other connection. Returns 0 when it took a place
 * among the config's max_deferred: the handler returns without replying; the connection is
 * suspended, and fn(rep, arg) is called once on a thread of the HTTP layer, where it may block;
 * it fills rep (which may already hold a Location) and owns arg. Then the reply is sent. (Should
 * no thread be had, fn runs in the handler's thread.) fn must return promptly once the server is
 * stopping: http_stop waits for it. Returns -1, without calling fn, when all places are taken,
 * the server is stopping, or it is called outside a handler or twice, and -2 when the request's
 * client address holds max_deferred_per_client places already: then the handler still owns arg
 * and must reply itself, at once. */
int http_defer(http_reply *rep, void (*fn)(http_reply *rep, void *arg), void *arg);

/* Serves a file below config->web_root for a GET of path ("/" -> index.html): rejects "..",
 * encoded traversal and symlinks that leave the root (404), sets the content type by extension.
 */
void http_serve_static(const http_request *req, http_reply *rep, const char *web_root);

#endif
