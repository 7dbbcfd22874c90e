/*
 * http.c - the service's HTTP layer on libmicrohttpd (http.h): one daemon with an internal thread
 * pool, body collection under a size limit, the route table, bearer tokens, replies and static
 * files.
 *
 * A request lives in one http_exchange, made by the first call of the access handler and freed by
 * the completion callback, whatever happened in between (libmicrohttpd calls the completion
 * callback for every request that reached the access handler, and only for those). The URI
 * callback before it only looks at the raw, still percent-encoded path for "%00". The first call
 * decides everything the headers can decide - the body's framing (400 BAD_FRAMING for two
 * lengths or codings, 501 for a coding other than chunked; these close the connection), the Host
 * (400 without one in HTTP/1.1, 421 for a host not allowed), the route (404, 405 with Allow), the
 * token (401) and a declared Content-Length over the limit (413) - and answers at once without
 * reading the body. Otherwise the body is collected into one growing buffer; a chunked body that
 * passes the limit is read on and dropped (libmicrohttpd 0.9.75 refuses a response queued half-way
 * through an upload), then answered 413, and a client that keeps sending far beyond the limit is
 * disconnected. The last call runs the handler, which fills an http_reply; the reply becomes a
 * libmicrohttpd response from its buffer, its file descriptor or its stream function (a response
 * from a callback, of unknown size, sent chunked; libmicrohttpd frees it, and with it the
 * stream's argument, once done with it), with the headers every reply carries. A text reply
 * (JSON, CSV, YAML) goes in gzip to a client that accepts it: a streamed one always, one from a
 * buffer when it is HTTP_GZIP_MIN bytes or more (http_gzip.h); every text reply says "Vary:
 * Accept-Encoding". http_stop stops accepting, then gives the requests being answered a few
 * seconds to finish.
 *
 * Paths are matched segment by segment; "{...}" in a pattern captures one non-empty segment.
 * HEAD is answered as GET (libmicrohttpd sends no body). Paths that no route matches go to the
 * static files below the web root, except under /api, which answers 404 or 405. Static files are
 * served by a whitelist: the decoded path must not contain "..", a backslash, an encoded NUL or a
 * segment starting with "."; it is resolved with realpath and must stay below realpath(web root),
 * so a symlink that leads out is refused; directories serve their index.html; only known file
 * extensions are served. Every refusal is a plain 404, so probing learns nothing.
 *
 * Connections are bounded (http_config): libmicrohttpd closes one silent for idle_timeout s, and
 * closes at accept a connection past max_connections in all or past max_per_ip from one address
 * (its per-address count is the daemon's, across the pool's threads). A client trickling header
 * bytes is not silent: the per-address limit is what bounds it.
 *
 * Handlers run on libmicrohttpd's pool threads, each of which serves many connections, so a
 * handler must not block. One that must wait (POST /api/jobs?wait) defers its reply (http_defer):
 * the connection is suspended, a detached thread of ours runs the waiting part and resumes it,
 * and the access handler, called again, sends the reply. At most max_deferred such replies
 * (http_config, default HTTP_MAX_DEFERRED) wait at once: http_defer reserves a place under
 * defer_lock and refuses past the limit, so the handler answers at once and no HTTP thread ever
 * blocks. http_stop waits for the deferring threads before libmicrohttpd stops.
 */
/* realpath is an X/Open function */
#define _XOPEN_SOURCE 700

#include "http.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <microhttpd.h>

#include "client_count.h"
#include "http_gzip.h"

#define HTTP_MAX_PARAMS 4
/* bytes per connection for headers and the read buffer */
#define HTTP_MEMORY_LIMIT (128 * 1024)
/* the defaults of http_config's connection limits (http.h) */
#define HTTP_IDLE_TIMEOUT 30
#define HTTP_MAX_CONNECTIONS 1000
#define HTTP_MAX_PER_IP 64
/* bytes of an over-long chunked body read and dropped beyond the limit before the connection is
   closed */
#define HTTP_DROP_MARGIN (1024 * 1024)
/* s http_stop waits for the requests in flight */
#define HTTP_STOP_GRACE 5.0
/* deferred replies (http_defer) waiting at once at most, by default; past them it refuses */
#define HTTP_MAX_DEFERRED 256

struct http_server {
    struct MHD_Daemon *daemon;
    const http_route *routes;
    void *ctx;
    size_t max_body;
    char *web_root; /* copies, owned */
    char *token;    /* NULL = none */
    char *hosts;    /* the allowed Host names, each followed by a NUL, then an empty one */
    int any_host;   /* no Host check (bound to every address, or "*" allowed) */
    pthread_mutex_t log_lock;
    char last_log[256];   /* libmicrohttpd's last message (start-up errors), under log_lock */
    atomic_int in_flight; /* requests being answered (http_exchange.answering) */
    pthread_mutex_t defer_lock;
    pthread_cond_t defer_done;        /* signalled when deferred falls */
    unsigned deferred;                /* deferred replies under way or reserved, under defer_lock */
    unsigned max_deferred;            /* the most at once (http_config.max_deferred) */
    client_count *deferred_by_client; /* deferred replies per client address */
    unsigned max_deferred_per_client; /* the most per client (0 = no limit) */
    int stopping;                     /* http_stop has begun, under defer_lock */
};

/* One request, from its first callback to its completion. */
typedef struct http_exchange {
    int encoded_nul;         /* the raw path has "%00" */
    const http_route *route; /* the matched route, NULL = static file */
    const char *params[HTTP_MAX_PARAMS];
    char *captures; /* storage of params */
    char *body;     /* NUL-terminated */
    size_t body_len, body_cap;
    int too_large;  /* the body passed max_body: answer 413 */
    int no_memory;  /* the body could not be stored: answer 503 */
    int answering;  /* counted in in_flight: its reply is being made or sent */
    size_t dropped; /* bytes read and dropped since either */

    /* a deferred reply (http_defer) */
    void (*defer_fn)(http_reply *rep, void *arg);
    void *defer_arg;
    http_reply rep;              /* filled by defer_fn on the deferring thread */
    int resumed;                 /* defer_fn is done, under defer_lock */
    int client_counted;          /* holds a place in deferred_by_client */
    char client[CLIENT_KEY_MAX]; /* the peer's numeric address */
    struct MHD_Connection *conn; /* suspended */
    http_server *server;
} http_exchange;

/* the exchange whose handler runs on this thread, for http_defer */
static _Thread_local http_exchange *running_exchange;

/* the bodies of replies that could not be built */
static const char no_memory_body[] =
    "{\"error\":{\"code\":\"NO_MEMORY\",\"message\":\"out of memory\",\"field\":\"\"}}\n";
static const char no_reply_body[] = "{\"error\":{\"code\":\"INTERNAL_ERROR\",\"message\":\"the "
                                    "handler gave no reply\",\"field\":\"\"}}\n";

/* ---- replies ---- */

static void reply_reset_body(http_reply *rep)
{
    free(rep->body);
    rep->body = NULL;
    rep->body_len = 0;
    if (rep->fd >= 0) close(rep->fd);
    rep->fd = -1;
    rep->fd_size = 0;
    if (rep->stream && rep->stream_free) rep->stream_free(rep->stream_arg);
    rep->stream = NULL;
    rep->stream_free = NULL;
    rep->stream_arg = NULL;
}

void http_reply_stream(http_reply *rep, int status, const char *content_type, http_stream_fn fn,
                       void (*free_fn)(void *arg), void *arg)
{
    reply_reset_body(rep);
    rep->status = status;
    rep->content_type = content_type;
    rep->stream = fn;
    rep->stream_free = free_fn;
    rep->stream_arg = arg;
}

/* a streamed body as libmicrohttpd holds it: made by send_reply, freed by stream_done */
typedef struct http_stream {
    http_stream_fn fn;
    void (*free_fn)(void *arg);
    void *arg;
} http_stream;

static ssize_t stream_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    http_stream *h = cls;
    (void)pos;
    ptrdiff_t n = h->fn(h->arg, buf, max < HTTP_STREAM_BLOCK ? max : HTTP_STREAM_BLOCK);
    return n > 0    ? (ssize_t)n
           : n == 0 ? MHD_CONTENT_READER_END_OF_STREAM
                    : MHD_CONTENT_READER_END_WITH_ERROR;
}

static void stream_done(void *cls)
{
    http_stream *h = cls;
    if (h->free_fn) h->free_fn(h->arg);
    free(h);
}

void http_reply_buffer(http_reply *rep, int status, const char *content_type, char *buf, size_t len)
{
    reply_reset_body(rep);
    rep->status = status;
    rep->content_type = content_type;
    rep->body = buf;
    rep->body_len = buf ? len : 0;
}

void http_reply_text(http_reply *rep, int status, const char *content_type, const char *text,
                     size_t len)
{
    char *copy = malloc(len + 1);
    if (!copy) {
        /* the fallback body of send_reply says "out of memory" */
        http_reply_buffer(rep, 503, "application/json", NULL, 0);
        return;
    }
    memcpy(copy, text, len);
    copy[len] = 0;
    http_reply_buffer(rep, status, content_type, copy, len);
}

void http_reply_json(http_reply *rep, int status, cJSON *json)
{
    char *text = json ? cJSON_PrintUnformatted(json) : NULL;
    cJSON_Delete(json);
    if (!text) {
        http_reply_buffer(rep, 503, "application/json", NULL, 0);
        return;
    }
    /* a final newline, for people reading replies in a terminal */
    size_t len = strlen(text);
    char *body = realloc(text, len + 2);
    if (!body) {
        free(text);
        http_reply_buffer(rep, 503, "application/json", NULL, 0);
        return;
    }
    body[len] = '\n';
    body[len + 1] = 0;
    http_reply_buffer(rep, status, "application/json", body, len + 1);
}

void http_reply_error(http_reply *rep, int status, const char *code, const char *field,
                      const char *fmt, ...)
{
    char message[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(message, sizeof message, fmt, ap);
    va_end(ap);
    cJSON *doc = cJSON_CreateObject();
    cJSON *error = cJSON_AddObjectToObject(doc, "error");
    int ok = error && cJSON_AddStringToObject(error, "code", code) &&
             cJSON_AddStringToObject(error, "message", message) &&
             cJSON_AddStringToObject(error, "field", field ? field : "");
    if (!ok) {
        cJSON_Delete(doc);
        doc = NULL;
    }
    http_reply_json(rep, status, doc);
}

/* ---- requests ---- */

const char *http_query(const http_request *req, const char *key)
{
    return MHD_lookup_connection_value(req->conn, MHD_GET_ARGUMENT_KIND, key);
}

const char *http_header(const http_request *req, const char *name)
{
    return MHD_lookup_connection_value(req->conn, MHD_HEADER_KIND, name);
}

/* The connection's peer as a numeric address, "unknown" when libmicrohttpd cannot say. */
static void client_address(struct MHD_Connection *conn, char *buf, size_t len)
{
    const union MHD_ConnectionInfo *info =
        MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
    const struct sockaddr *sa = info ? info->client_addr : NULL;
    const void *addr = NULL;
    if (sa && sa->sa_family == AF_INET)
        addr = &((const struct sockaddr_in *)(const void *)sa)->sin_addr;
    if (sa && sa->sa_family == AF_INET6)
        addr = &((const struct sockaddr_in6 *)(const void *)sa)->sin6_addr;
    if (!addr || !inet_ntop(sa->sa_family, addr, buf, (socklen_t)len))
        snprintf(buf, len, "unknown");
}

void http_client(const http_request *req, char *buf, size_t len)
{
    client_address(req->conn, buf, len);
}

/* Whether path matches pattern; the "{...}" segments are copied into buf (at least
 * strlen(path) + HTTP_MAX_PARAMS bytes) and pointed to by params. */
static int route_match(const char *pattern, const char *path, char *buf,
                       const char *params[HTTP_MAX_PARAMS])
{
    const char *p = pattern, *s = path;
    int k = 0;
    while (*p && *s) {
        if (*p == '{') {
            const char *close = strchr(p, '}');
            size_t n = strcspn(s, "/");
            if (!close || n == 0 || k == HTTP_MAX_PARAMS) return 0;
            memcpy(buf, s, n);
            buf[n] = 0;
            params[k++] = buf;
            buf += n + 1;
            p = close + 1;
            s += n;
        } else if (*p++ != *s++) {
            return 0;
        }
    }
    return *p == 0 && *s == 0;
}

static int is_api_path(const char *path)
{
    return strncmp(path, "/api", 4) == 0 && (path[4] == 0 || path[4] == '/');
}

/* Appends method to the Allow list unless it is there already. */
static void allow_add(char *allow, size_t len, const char *method)
{
    for (const char *at = strstr(allow, method); at; at = strstr(at + 1, method)) {
        size_t n = strlen(method);
        if ((at == allow || at[-1] == ' ') && (at[n] == 0 || at[n] == ',')) return;
    }
    size_t used = strlen(allow);
    snprintf(allow + used, len - used, "%s%s", used ? ", " : "", method);
}

/* Compares the Authorization header with "Bearer TOKEN" in time independent of where they
 * differ. */
static int token_ok(const char *header, const char *token)
{
    if (!header || strncasecmp(header, "Bearer ", 7) != 0) return 0;
    const char *given = header + 7;
    while (*given == ' ') given++;
    size_t n = strlen(given), m = strlen(token);
    unsigned diff = n != m;
    for (size_t i = 0; i < m; i++) {
        unsigned char g = i < n ? (unsigned char)given[i] : 0;
        diff |= (unsigned char)token[i] ^ g;
    }
    return diff == 0;
}

/* Fills s->hosts from the comma-separated list (NULL or "": the default for the bind address,
 * http.h). Names are kept as given, an IPv6 literal in brackets. Returns 0, or -1 out of memory. */
static int hosts_init(http_server *s, const char *list, const char *bind)
{
    char dflt[INET6_ADDRSTRLEN + 64];
    if (!list || !*list) {
        if (strcmp(bind, "0.0.0.0") == 0 || strcmp(bind, "::") == 0) s->any_host = 1;
        int v6 = strchr(bind, ':') != NULL;
        snprintf(dflt, sizeof dflt, "%s%s%s,localhost,127.0.0.1,[::1]", v6 ? "[" : "", bind,
                 v6 ? "]" : "");
        list = dflt;
    }
    size_t n = strlen(list);
    s->hosts = malloc(2 * n + 4); /* brackets may be added around each name */
    if (!s->hosts) return -1;
    char *out = s->hosts;
    for (const char *p = list; *p;) {
        size_t len = strcspn(p, ",");
        const char *name = p;
        p += len + (p[len] == ',');
        while (len > 0 && (*name == ' ' || *name == '\t')) name++, len--;
        while (len > 0 && (name[len - 1] == ' ' || name[len - 1] == '\t')) len--;
        if (len == 0) continue;
        if (len == 1 && name[0] == '*') s->any_host = 1;
        int bracket = name[0] != '[' && memchr(name, ':', len) != NULL; /* a bare IPv6 literal */
        if (bracket) *out++ = '[';
        memcpy(out, name, len);
        out += len;
        if (bracket) *out++ = ']';
        *out++ = 0;
    }
    *out = 0;
    return 0;
}

/* Whether the Host header names an allowed host: its name, the port stripped ("[::1]:8080" is
 * "[::1]"), compared without regard to case with each allowed name. */
static int host_ok(const http_server *s, const char *host)
{
    if (s->any_host) return 1;
    size_t len =
        host[0] == '[' ? strcspn(host, "]") + (strchr(host, ']') != NULL) : strcspn(host, ":");
    if (len > 0 && host[len - 1] == '.' && host[0] != '[') len--; /* "localhost." */
    for (const char *h = s->hosts; *h; h += strlen(h) + 1) {
        if (strlen(h) == len && strncasecmp(h, host, len) == 0) return 1;
    }
    return 0;
}

/* ---- static files ---- */

typedef struct content_type {
    const char *ext;
    const char *type;
} content_type;

static const content_type content_types[] = {
    {"html", "text/html; charset=utf-8"},
    {"js", "text/javascript; charset=utf-8"},
    {"mjs", "text/javascript; charset=utf-8"},
    {"css", "text/css; charset=utf-8"},
    {"json", "application/json"},
    {"map", "application/json"},
    {"svg", "image/svg+xml"},
    {"png", "image/png"},
    {"ico", "image/x-icon"},
    {"txt", "text/plain; charset=utf-8"},
    {"yaml", "application/yaml"},
    {"csv", "text/csv; charset=utf-8"},
    {"woff2", "font/woff2"},
};

static const char *content_type_of(const char *file)
{
    const char *slash = strrchr(file, '/');
    const char *dot = strrchr(slash ? slash : file, '.');
    if (!dot) return NULL;
    for (size_t i = 0; i < sizeof content_types / sizeof content_types[0]; i++)
        if (strcasecmp(dot + 1, content_types[i].ext) == 0) return content_types[i].type;
    return NULL;
}

/* A path the static files never serve: "..", a backslash, a hidden segment. */
static int static_path_refused(const char *path)
{
    if (path[0] != '/' || strstr(path, "..") || strchr(path, '\\')) return 1;
    for (const char *s = path; (s = strchr(s, '/')) != NULL; s++)
        if (s[1] == '.') return 1;
    return 0;
}

/* realpath(path) if it lies at or below root (itself resolved), else NULL. */
static char *resolve_below(const char *path, const char *root)
{
    char *real = realpath(path, NULL);
    if (!real) return NULL;
    size_t n = strlen(root);
    int inside = strncmp(real, root, n) == 0 && (real[n] == 0 || real[n] == '/' || n == 1);
    if (!inside) {
        free(real);
        return NULL;
    }
    return real;
}

void http_serve_static(const http_request *req, http_reply *rep, const char *web_root)
{
    char *root = NULL, *file = NULL, *joined = NULL;
    int fd = -1;
    if (static_path_refused(req->path)) goto not_found;
    root = realpath(web_root, NULL);
    if (!root) goto not_found;

    /* the file, or a directory's index.html */
    size_t len = strlen(root) + strlen(req->path) + sizeof "/index.html";
    joined = malloc(len);
    if (!joined) goto no_memory;
    snprintf(joined, len, "%s%s", root, req->path);
    file = resolve_below(joined, root);
    if (!file) goto not_found;
    struct stat st;
    if (stat(file, &st) != 0) goto not_found;
    if (S_ISDIR(st.st_mode)) {
        snprintf(joined, len, "%s%s%sindex.html", root, req->path,
                 req->path[strlen(req->path) - 1] == '/' ? "" : "/");
        free(file);
        file = resolve_below(joined, root);
        if (!file) goto not_found;
    }

    const char *type = content_type_of(file);
    if (!type) goto not_found;
    fd = open(file, O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
    if (fd < 0 || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) goto not_found;
    reply_reset_body(rep);
    rep->status = 200;
    rep->content_type = type;
    rep->fd = fd;
    rep->fd_size = (uint64_t)st.st_size;
    free(root);
    free(joined);
    free(file);
    return;

not_found:
    http_reply_error(rep, 404, "NOT_FOUND", "", "no such file: %s", req->path);
    goto done;
no_memory:
    http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
done:
    if (fd >= 0) close(fd);
    free(root);
    free(joined);
    free(file);
}

/* ---- libmicrohttpd callbacks ---- */

static void on_log(void *cls, const char *fmt, va_list ap)
{
    http_server *s = cls;
    char line[sizeof s->last_log];
    vsnprintf(line, sizeof line, fmt, ap);
    size_t n = strlen(line);
    while (n > 0 && (line[n - 1] == '\n' || line[n - 1] == ' ')) line[--n] = 0;
    pthread_mutex_lock(&s->log_lock);
    memcpy(s->last_log, line, n + 1);
    pthread_mutex_unlock(&s->log_lock);
    fprintf(stderr, "ctcsim-server: http: %s\n", line);
}

/* What the URI callback leaves in *con_cls for a path with "%00" (NULL otherwise). It allocates
 * nothing: libmicrohttpd calls the completion callback only for requests that reached the access
 * handler, and a request it refuses first (a bad version, headers too large) would leak. */
static char encoded_nul_mark;

/* Sees the raw URI before libmicrohttpd decodes it: a NUL would cut the decoded path short. */
static void *on_uri(void *cls, const char *uri, struct MHD_Connection *conn)
{
    (void)cls;
    (void)conn;
    size_t path_len = strcspn(uri, "?");
    for (size_t i = 0; i + 2 < path_len; i++)
        if (uri[i] == '%' && uri[i + 1] == '0' && uri[i + 2] == '0') return &encoded_nul_mark;
    return NULL;
}

static void on_completed(void *cls, struct MHD_Connection *conn, void **con_cls,
                         enum MHD_RequestTerminationCode why)
{
    http_server *s = cls;
    (void)conn;
    (void)why;
    http_exchange *x = *con_cls;
    if (!x || (void *)x == &encoded_nul_mark) return;
    if (x->answering) atomic_fetch_sub(&s->in_flight, 1);
    reply_reset_body(&x->rep); /* a deferred reply that was never sent */
    free(x->captures);
    free(x->body);
    free(x);
    *con_cls = NULL;
}

/* 1 if the request's Accept-Encoding admits gzip */
static int client_accepts_gzip(struct MHD_Connection *conn)
{
    return http_accepts_gzip(MHD_lookup_connection_value(conn, MHD_HEADER_KIND, "Accept-Encoding"));
}

/* Turns the reply into a response and queues it. */
static enum MHD_Result send_reply(struct MHD_Connection *conn, const char *path, http_reply *rep)
{
    struct MHD_Response *res;
    int status = rep->status, vary = 0;
    const char *type = rep->content_type, *encoding = NULL;
    if (rep->fd >= 0) {
        res = MHD_create_response_from_fd((size_t)rep->fd_size, rep->fd);
        if (res) rep->fd = -1; /* the response closes it */
    } else if (rep->stream) {
        /* a text stream in gzip when the client accepts it: the gzip stream takes the body */
        http_gzip_stream *g = NULL;
        if (http_gzip_type(type)) {
            vary = 1;
            if (client_accepts_gzip(conn))
                g = http_gzip_stream_new(rep->stream, rep->stream_free, rep->stream_arg);
        }
        if (g) {
            rep->stream = http_gzip_stream_read;
            rep->stream_free = http_gzip_stream_free;
            rep->stream_arg = g;
            encoding = "gzip";
        }
        http_stream *h = malloc(sizeof *h);
        res = NULL;
        if (h) {
            *h = (http_stream){rep->stream, rep->stream_free, rep->stream_arg};
            res = MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, HTTP_STREAM_BLOCK,
                                                    stream_read, h, stream_done);
            if (res)
                rep->stream = NULL; /* the response frees it */
            else
                free(h);
        }
        if (!res) {
            /* out of memory: the error reply instead (reply_reset_body frees the stream) */
            reply_reset_body(rep);
            status = 503;
            res = MHD_create_response_from_buffer(sizeof no_memory_body - 1, (void *)no_memory_body,
                                                  MHD_RESPMEM_PERSISTENT);
            type = "application/json";
            encoding = NULL;
            vary = 0;
        }
    } else if (rep->body) {
        /* a large text body in gzip when the client accepts it; every text body says that it
           may vary */
        char *gz;
        size_t gz_len;
        vary = http_gzip_type(type);
        if (vary && rep->body_len >= HTTP_GZIP_MIN && client_accepts_gzip(conn) &&
            http_gzip(rep->body, rep->body_len, &gz, &gz_len) == 0) {
            free(rep->body);
            rep->body = gz;
            rep->body_len = gz_len;
            encoding = "gzip";
        }
        res = MHD_create_response_from_buffer(rep->body_len, rep->body, MHD_RESPMEM_MUST_FREE);
        if (res) rep->body = NULL; /* the response frees it */
    } else if (status == 204 || (status >= 300 && status < 400)) {
        res = MHD_create_response_from_buffer(0, (void *)"", MHD_RESPMEM_PERSISTENT);
        type = NULL;
    } else if (status == 0) {
        /* a handler that forgot to reply: a bug, said as such */
        status = 500;
        res = MHD_create_response_from_buffer(sizeof no_reply_body - 1, (void *)no_reply_body,
                                              MHD_RESPMEM_PERSISTENT);
        type = "application/json";
    } else {
        /* a reply helper ran out of memory */
        status = 503;
        res = MHD_create_response_from_buffer(sizeof no_memory_body - 1, (void *)no_memory_body,
                                              MHD_RESPMEM_PERSISTENT);
        type = "application/json";
    }
    reply_reset_body(rep);
    if (!res) return MHD_NO;

    int ok = 1;
    if (type) ok &= MHD_add_response_header(res, MHD_HTTP_HEADER_CONTENT_TYPE, type) == MHD_YES;
    if (encoding)
        ok &= MHD_add_response_header(res, MHD_HTTP_HEADER_CONTENT_ENCODING, encoding) == MHD_YES;
    if (vary)
        ok &= MHD_add_response_header(res, MHD_HTTP_HEADER_VARY, "Accept-Encoding") == MHD_YES;
    ok &= MHD_add_response_header(res, "X-Content-Type-Options", "nosniff") == MHD_YES;
    if (is_api_path(path))
        ok &= MHD_add_response_header(res, MHD_HTTP_HEADER_CACHE_CONTROL, "no-cache") == MHD_YES;
    if (rep->location[0])
        ok &= MHD_add_response_header(res, MHD_HTTP_HEADER_LOCATION, rep->location) == MHD_YES;
    if (rep->allow[0])
        ok &= MHD_add_response_header(res, MHD_HTTP_HEADER_ALLOW, rep->allow) == MHD_YES;
    if (rep->retry_after > 0) {
        char secs[24];
        snprintf(secs, sizeof secs, "%d", rep->retry_after);
        ok &= MHD_add_response_header(res, MHD_HTTP_HEADER_RETRY_AFTER, secs) == MHD_YES;
    }
    if (rep->close)
        ok &= MHD_add_response_header(res, MHD_HTTP_HEADER_CONNECTION, "close") == MHD_YES;
    if (status == 401)
        ok &= MHD_add_response_header(res, MHD_HTTP_HEADER_WWW_AUTHENTICATE,
                                      "Bearer realm=\"ctcsim\"") == MHD_YES;
    enum MHD_Result queued = ok ? MHD_queue_response(conn, (unsigned)status, res) : MHD_NO;
    MHD_destroy_response(res);
    return queued;
}

/* The headers that frame a request's body, as the client sent them. */
typedef struct framing {
    int lengths;          /* Content-Length headers */
    int encodings;        /* Transfer-Encoding headers */
    const char *length;   /* the first Content-Length's value */
    const char *encoding; /* the first Transfer-Encoding's value */
} framing;

static enum MHD_Result count_framing(void *cls, enum MHD_ValueKind kind, const char *key,
                                     const char *value)
{
    (void)kind;
    framing *f = cls;
    if (strcasecmp(key, MHD_HTTP_HEADER_CONTENT_LENGTH) == 0 && f->lengths++ == 0)
        f->length = value ? value : "";
    if (strcasecmp(key, MHD_HTTP_HEADER_TRANSFER_ENCODING) == 0 && f->encodings++ == 0)
        f->encoding = value ? value : "";
    return MHD_YES;
}

/* Refuses a request whose body framing is ambiguous or unsupported (RFC 9112 sections 6.1-6.3):
 * more than one Content-Length, more than one Transfer-Encoding, both together, a
 * Content-Length that is not all digits (400 BAD_FRAMING), or a transfer coding other than
 * "chunked" (501 UNSUPPORTED_TRANSFER_ENCODING). The reply closes the connection: the bytes
 * after such headers cannot be trusted to start the next request (request smuggling).
 *
 * What libmicrohttpd 0.9.75 does itself, measured on the wire: it keeps every header line and
 * reads the body by the first Content-Length, so duplicates and Content-Length with chunked
 * reach this check; it answers a Content-Length that is not a plain decimal number (a sign,
 * a letter, trailing blanks) 400, and one past 2^64 413, before the access handler runs, with a
 * body of HTML and its status line and headers written twice - the access handler never sees
 * such a request, so only libmicrohttpd (or a proxy in front) can mend that; a Transfer-Encoding
 * other than chunked it takes as a body of unknown length that never ends, so without this check
 * the request waits for the idle timeout; it passes an HTTP/1.1 request without Host to the
 * handler (first_call answers it 400 MISSING_HOST). Returns 1 after filling rep, else 0. */
static int framing_refused(struct MHD_Connection *conn, http_reply *rep)
{
    framing f = {0};
    MHD_get_connection_values(conn, MHD_HEADER_KIND, count_framing, &f);
    char why[128] = "";
    const char *field = MHD_HTTP_HEADER_CONTENT_LENGTH;
    if (f.lengths > 1) {
        snprintf(why, sizeof why, "the request has %d Content-Length headers; one is allowed",
                 f.lengths);
    } else if (f.encodings > 1) {
        field = MHD_HTTP_HEADER_TRANSFER_ENCODING;
        snprintf(why, sizeof why, "the request has %d Transfer-Encoding headers; one is allowed",
                 f.encodings);
    } else if (f.lengths && f.encodings) {
        field = MHD_HTTP_HEADER_TRANSFER_ENCODING;
        snprintf(why, sizeof why,
                 "the request has both Content-Length and Transfer-Encoding; send one of them");
    } else if (f.lengths && (!f.length[0] || strspn(f.length, "0123456789") != strlen(f.length))) {
        snprintf(why, sizeof why, "Content-Length must be a decimal number of bytes");
    }
    if (why[0]) {
        http_reply_error(rep, 400, "BAD_FRAMING", field, "%s", why);
        rep->close = 1;
        return 1;
    }
    if (f.encodings && strcasecmp(f.encoding, "chunked") != 0) {
        http_reply_error(
            rep, 501, "UNSUPPORTED_TRANSFER_ENCODING", MHD_HTTP_HEADER_TRANSFER_ENCODING,
            "Transfer-Encoding \"%.100s\" is not supported (only chunked is)", f.encoding);
        rep->close = 1;
        return 1;
    }
    return 0;
}

/* What the headers decide on the first call: a route and its captures, or an early reply
 * (status != 0 in rep). */
static void first_call(http_server *s, http_exchange *x, struct MHD_Connection *conn,
                       const char *path, const char *method, const char *version, http_reply *rep)
{
    /* the body's framing, before anything else is believed */
    if (framing_refused(conn, rep)) return;

    /* the Host: HTTP/1.1 needs one (RFC 9112 section 3.2); it must be ours, or a page of
       another site whose name resolves here (DNS rebinding) could drive the service */
    const char *host = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_HOST);
    if (!host && strcmp(version, MHD_HTTP_VERSION_1_0) != 0) {
        http_reply_error(rep, 400, "MISSING_HOST", "", "an %s request needs a Host header",
                         version);
        return;
    }
    if (host && !host_ok(s, host)) {
        http_reply_error(rep, 421, "HOST_NOT_ALLOWED", "",
                         "this server does not answer for host \"%.100s\" (--allowed-hosts)", host);
        return;
    }
    if (x->encoded_nul) {
        http_reply_error(rep, 404, "NOT_FOUND", "", "no such path (it holds an encoded NUL)");
        return;
    }

    /* the route; HEAD is looked up as GET */
    const char *wanted = strcmp(method, "HEAD") == 0 ? "GET" : method;
    x->captures = malloc(strlen(path) + HTTP_MAX_PARAMS + 1);
    if (!x->captures) {
        http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
        return;
    }
    for (const http_route *r = s->routes; r->method; r++) {
        const char *params[HTTP_MAX_PARAMS] = {0};
        if (!route_match(r->pattern, path, x->captures, params)) continue;
        if (strcmp(r->method, wanted) == 0) {
            x->route = r;
            memcpy(x->params, params, sizeof params);
            break;
        }
        allow_add(rep->allow, sizeof rep->allow, r->method);
    }
    if (!x->route) {
        if (rep->allow[0]) {
            http_reply_error(rep, 405, "METHOD_NOT_ALLOWED", "",
                             "%s is not allowed on %s (allowed: %s)", method, path, rep->allow);
        } else if (is_api_path(path)) {
            http_reply_error(rep, 404, "NOT_FOUND", "", "no such endpoint: %s %s", method, path);
        } else if (strcmp(wanted, "GET") != 0) {
            snprintf(rep->allow, sizeof rep->allow, "GET, HEAD");
            http_reply_error(rep, 405, "METHOD_NOT_ALLOWED", "",
                             "%s is not allowed on %s (allowed: GET, HEAD)", method, path);
        }
        if (rep->status) return;
    } else {
        rep->allow[0] = 0;
    }

    /* the token, for requests that change something */
    int changes = strcmp(method, "POST") == 0 || strcmp(method, "DELETE") == 0;
    if (changes && s->token) {
        const char *auth =
            MHD_lookup_connection_value(conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_AUTHORIZATION);
        if (!token_ok(auth, s->token)) {
            if (auth)
                http_reply_error(rep, 401, "UNAUTHORIZED", "", "the bearer token is not valid");
            else
                http_reply_error(rep, 401, "UNAUTHORIZED", "",
                                 "%s %s needs \"Authorization: Bearer TOKEN\"", method, path);
            return;
        }
    }

    /* a declared length over the limit: refused before anything is read */
    const char *length =
        MHD_lookup_connection_value(conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH);
    if (length) {
        errno = 0;
        char *end;
        unsigned long long n = strtoull(length, &end, 10);
        if (errno == ERANGE || n > s->max_body)
            http_reply_error(rep, 413, "BODY_TOO_LARGE", "",
                             "the request body (%s bytes) is larger than the limit of %zu bytes",
                             length, s->max_body);
    }
}

/* Frees the body collected so far; the rest of the upload is dropped. */
static void drop_body(http_exchange *x)
{
    free(x->body);
    x->body = NULL;
    x->body_len = x->body_cap = 0;
}

/* Appends an upload chunk to the body, or drops it past the limit or out of memory. Returns 0,
 * or -1 to close the connection (far too much sent after that). */
static int collect(http_server *s, http_exchange *x, const char *data, size_t n)
{
    if (!x->too_large && !x->no_memory && n > s->max_body - x->body_len) {
        x->too_large = 1;
        drop_body(x);
    }
    if (!x->too_large && !x->no_memory && x->body_len + n + 1 > x->body_cap) {
        size_t cap = x->body_cap ? x->body_cap : 4096;
        while (cap < x->body_len + n + 1) cap *= 2;
        char *bigger = realloc(x->body, cap);
        if (bigger) {
            x->body = bigger;
            x->body_cap = cap;
        } else {
            x->no_memory = 1;
            drop_body(x);
        }
    }
    if (x->too_large || x->no_memory) {
        x->dropped += n;
        return x->dropped > HTTP_DROP_MARGIN ? -1 : 0;
    }
    memcpy(x->body + x->body_len, data, n);
    x->body_len += n;
    x->body[x->body_len] = 0;
    return 0;
}

/* ---- deferred replies ---- */

int http_defer(http_reply *rep, void (*fn)(http_reply *rep, void *arg), void *arg)
{
    (void)rep;
    http_exchange *x = running_exchange;
    if (!x || x->defer_fn) return -1; /* not inside a handler, or twice */
    http_server *s = x->server;
    int rc = -1;
    pthread_mutex_lock(&s->defer_lock);
    if (!s->stopping && s->deferred < s->max_deferred) {
        /* the places are held from here; defer_release gives them back */
        int taken = client_count_take(s->deferred_by_client, x->client, s->max_deferred_per_client);
        if (taken == 0) {
            s->deferred++;
            x->client_counted = 1;
            rc = 0;
        } else if (taken == 1) {
            rc = -2;
        }
    }
    pthread_mutex_unlock(&s->defer_lock);
    if (rc != 0) return rc;
    x->defer_fn = fn;
    x->defer_arg = arg;
    return 0;
}

/* Gives back the places http_defer took for x; under defer_lock. */
static void defer_release(http_server *s, http_exchange *x)
{
    s->deferred--;
    if (x->client_counted) client_count_give(s->deferred_by_client, x->client);
    x->client_counted = 0;
    pthread_cond_broadcast(&s->defer_done);
}

/* The deferring thread: runs defer_fn, then resumes the connection, whose next call to the
 * access handler sends x->rep. */
static void *run_deferred(void *arg)
{
    http_exchange *x = arg;
    http_server *s = x->server;
    x->defer_fn(&x->rep, x->defer_arg);
    pthread_mutex_lock(&s->defer_lock);
    x->resumed = 1;
    defer_release(s, x);
    MHD_resume_connection(x->conn); /* x may be gone once the lock is released */
    pthread_mutex_unlock(&s->defer_lock);
    return NULL;
}

/* Suspends the connection and starts the deferring thread, in the place http_defer reserved; 0,
 * or -1 when it cannot (then the caller runs defer_fn itself and gives the place back). rep
 * moves into the exchange. */
static int start_deferred(http_server *s, http_exchange *x, struct MHD_Connection *conn,
                          http_reply *rep)
{
    pthread_mutex_lock(&s->defer_lock);
    int rc = -1;
    if (!s->stopping) {
        x->rep = *rep;
        x->conn = conn;
        x->server = s;
        pthread_attr_t attr;
        pthread_t thread;
        if (pthread_attr_init(&attr) == 0) {
            pthread_attr_setdetachstate(&attr, PTHREAD_CREATE_DETACHED);
            /* the thread resumes the connection only after this lock is released: the
               suspension comes first */
            if (pthread_create(&thread, &attr, run_deferred, x) == 0) {
                MHD_suspend_connection(conn);
                rc = 0;
            } else {
                x->rep = (http_reply){.fd = -1}; /* rep stays the caller's */
            }
            pthread_attr_destroy(&attr);
        }
    }
    pthread_mutex_unlock(&s->defer_lock);
    return rc;
}

/* From here on the request is answered: http_stop gives it time to finish (a request still
 * sending its body is not waited for). */
static void begin_answer(http_server *s, http_exchange *x)
{
    if (x->answering) return;
    x->answering = 1;
    atomic_fetch_add(&s->in_flight, 1);
}

static enum MHD_Result on_request(void *cls, struct MHD_Connection *conn, const char *url,
                                  const char *method, const char *version, const char *upload_data,
                                  size_t *upload_data_size, void **con_cls)
{
    http_server *s = cls;
    http_exchange *x = *con_cls;
    http_reply rep = {.fd = -1};

    /* the first call: the exchange, freed by on_completed from now on */
    if (!x || (void *)x == &encoded_nul_mark) {
        int encoded_nul = x != NULL;
        *con_cls = x = calloc(1, sizeof *x);
        if (!x) {
            http_reply_error(&rep, 503, "NO_MEMORY", "", "out of memory");
            return send_reply(conn, url, &rep);
        }
        x->encoded_nul = encoded_nul;
        x->rep.fd = -1;
        client_address(conn, x->client, sizeof x->client);
        first_call(s, x, conn, url, method, version, &rep);
        if (!rep.status && !rep.body) return MHD_YES;
        begin_answer(s, x);
        return send_reply(conn, url, &rep);
    }
    if (*upload_data_size > 0) {
        int rc = collect(s, x, upload_data, *upload_data_size);
        *upload_data_size = 0;
        return rc == 0 ? MHD_YES : MHD_NO;
    }

    /* back from a deferred reply */
    if (x->defer_fn) {
        pthread_mutex_lock(&s->defer_lock);
        int resumed = x->resumed;
        pthread_mutex_unlock(&s->defer_lock);
        if (!resumed) return MHD_YES;
        rep = x->rep;
        x->rep = (http_reply){.fd = -1};
        return send_reply(conn, url, &rep);
    }

    /* the whole request is here */
    begin_answer(s, x);
    if (x->too_large || x->no_memory) {
        if (x->too_large)
            http_reply_error(&rep, 413, "BODY_TOO_LARGE", "",
                             "the request body is larger than the limit of %zu bytes", s->max_body);
        else
            http_reply_error(&rep, 503, "NO_MEMORY", "", "out of memory for the request body");
        return send_reply(conn, url, &rep);
    }
    http_request req = {
        .method = method,
        .path = url,
        .body = x->body ? x->body : "",
        .body_len = x->body_len,
        .conn = conn,
    };
    memcpy(req.params, x->params, sizeof req.params);
    if (x->route) {
        x->server = s;
        running_exchange = x;
        x->route->handler(&req, &rep, s->ctx);
        running_exchange = NULL;
    } else {
        http_serve_static(&req, &rep, s->web_root);
    }
    if (x->defer_fn) {
        if (start_deferred(s, x, conn, &rep) == 0) return MHD_YES;
        x->defer_fn(&rep, x->defer_arg); /* no thread for it: here, then */
        x->defer_fn = NULL;
        pthread_mutex_lock(&s->defer_lock);
        defer_release(s, x);
        pthread_mutex_unlock(&s->defer_lock);
    }
    return send_reply(conn, url, &rep);
}

/* ---- the daemon ---- */

int http_start(const http_config *config, http_server **out, char *err, size_t errlen)
{
    *out = NULL;
    if (!config->routes || config->threads < 1 || config->port < 0 || config->port > 65535 ||
        config->max_body < 1) {
        snprintf(err, errlen,
                 "bad configuration (routes, threads >= 1, port 0..65535, "
                 "max_body >= 1)");
        return -1;
    }

    /* the address: a numeric IPv4 or IPv6 address */
    const char *bind = config->bind ? config->bind : "127.0.0.1";
    struct sockaddr_in v4 = {.sin_family = AF_INET, .sin_port = htons((uint16_t)config->port)};
    struct sockaddr_in6 v6 = {.sin6_family = AF_INET6, .sin6_port = htons((uint16_t)config->port)};
    const struct sockaddr *addr = (const struct sockaddr *)&v4;
    /* suspend and resume for http_defer; ITC (which that implies) for MHD_quiesce_daemon */
    unsigned flags = MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_AUTO | MHD_USE_ERROR_LOG |
                     MHD_USE_ITC | MHD_ALLOW_SUSPEND_RESUME;
    if (inet_pton(AF_INET, bind, &v4.sin_addr) != 1) {
        if (inet_pton(AF_INET6, bind, &v6.sin6_addr) != 1) {
            snprintf(err, errlen, "cannot listen on \"%s\": not a numeric IPv4 or IPv6 address",
                     bind);
            return -1;
        }
        addr = (const struct sockaddr *)&v6;
        flags |= MHD_USE_IPv6;
    }

    http_server *s = calloc(1, sizeof *s);
    if (!s) goto no_memory;
    atomic_init(&s->in_flight, 0);
    pthread_mutex_init(&s->log_lock, NULL);
    pthread_mutex_init(&s->defer_lock, NULL);
    pthread_cond_init(&s->defer_done, NULL);
    s->routes = config->routes;
    s->ctx = config->ctx;
    s->max_body = config->max_body;
    s->web_root = strdup(config->web_root ? config->web_root : "web");
    if (!s->web_root) goto no_memory;
    if (config->token && config->token[0] && !(s->token = strdup(config->token))) goto no_memory;
    if (hosts_init(s, config->allowed_hosts, bind) != 0) goto no_memory;

    unsigned idle_timeout = config->idle_timeout ? config->idle_timeout : HTTP_IDLE_TIMEOUT;
    unsigned max_connections =
        config->max_connections ? config->max_connections : HTTP_MAX_CONNECTIONS;
    unsigned max_per_ip = config->max_per_ip ? config->max_per_ip : HTTP_MAX_PER_IP;
    s->max_deferred = config->max_deferred ? config->max_deferred : HTTP_MAX_DEFERRED;
    s->max_deferred_per_client = config->max_deferred_per_client;
    if (!(s->deferred_by_client = client_count_new())) goto no_memory;

    /* the logger first, so that libmicrohttpd's checks of the other options use it too */
    // clang-format off
    s->daemon = MHD_start_daemon(
        flags, (uint16_t)config->port, NULL, NULL, on_request, s,
        MHD_OPTION_EXTERNAL_LOGGER, on_log, s,
        MHD_OPTION_SOCK_ADDR, addr,
        MHD_OPTION_THREAD_POOL_SIZE, (unsigned)(config->threads > 1 ? config->threads : 0),
        MHD_OPTION_CONNECTION_MEMORY_LIMIT, (size_t)HTTP_MEMORY_LIMIT,
        MHD_OPTION_CONNECTION_TIMEOUT, idle_timeout,
        MHD_OPTION_CONNECTION_LIMIT, max_connections,
        MHD_OPTION_PER_IP_CONNECTION_LIMIT, max_per_ip,
        MHD_OPTION_URI_LOG_CALLBACK, on_uri, s,
        MHD_OPTION_NOTIFY_COMPLETED, on_completed, s,
        MHD_OPTION_END);
    // clang-format on
    if (!s->daemon) {
        snprintf(err, errlen, "cannot listen on %s port %d: %s", bind, config->port,
                 s->last_log[0] ? s->last_log : "libmicrohttpd could not start");
        http_stop(s);
        return -1;
    }
    *out = s;
    return 0;

no_memory:
    snprintf(err, errlen, "out of memory");
    http_stop(s);
    return -1;
}

int http_port(const http_server *s)
{
    const union MHD_DaemonInfo *info = MHD_get_daemon_info(s->daemon, MHD_DAEMON_INFO_BIND_PORT);
    return info ? info->port : -1;
}

static double monotonic_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void http_stop(http_server *s)
{
    if (!s) return;
    if (s->daemon) {
        /* no new connections; deferred replies end (libmicrohttpd must not stop with a
           connection suspended); the other replies under way get HTTP_STOP_GRACE s */
        MHD_socket listener = MHD_quiesce_daemon(s->daemon);
        pthread_mutex_lock(&s->defer_lock);
        s->stopping = 1;
        while (s->deferred > 0) pthread_cond_wait(&s->defer_done, &s->defer_lock);
        pthread_mutex_unlock(&s->defer_lock);
        double deadline = monotonic_now() + HTTP_STOP_GRACE;
        struct timespec pause = {.tv_nsec = 10 * 1000 * 1000};
        while (atomic_load(&s->in_flight) > 0 && monotonic_now() < deadline)
            nanosleep(&pause, NULL);
        MHD_stop_daemon(s->daemon);
        if (listener != MHD_INVALID_SOCKET) close(listener);
    }
    pthread_mutex_destroy(&s->log_lock);
    pthread_mutex_destroy(&s->defer_lock);
    pthread_cond_destroy(&s->defer_done);
    free(s->web_root);
    free(s->token);
    free(s->hosts);
    client_count_free(s->deferred_by_client);
    free(s);
}
