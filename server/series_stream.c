/*
 * series_stream.c - a series as CSV or columnar JSON, written in pieces (series_stream.h).
 *
 * The text is a sequence of small pieces - a header cell, one number with the separator before
 * it, a bracket - each made by step() into a buffer of SERIES_PIECE bytes and copied out as the
 * reader has room, so a fill of any size (down to one byte) resumes where the last one stopped.
 * The position is the state of the loops of result_out.c written out: the part (header, values,
 * closing), the channel (-1 for t), the column and the sample. Which channels, columns and
 * samples are written follows result_out.c exactly: a channel if recorded and selected; a column
 * unless the coordinate filter drops it (channels nv wide only, energy and loop never); samples
 * 0, stride, 2 stride, ... and the last. Numbers are "%.17g", non-finite ones "null" in JSON and
 * "nan" in CSV.
 *
 * Samples come through one window per channel: a copy of up to SERIES_STREAM_WINDOW bytes of the
 * channel's samples, refilled from the offset of the value that missed it.
 *
 * The binary forms (SERIES_F32, SERIES_F32_MINMAX) write the header as one piece and then one
 * float32 per piece, channel by channel and row by row, so each channel's samples are read in
 * their stored order. With min/max, the first value of a bucket's first row reads the whole
 * bucket of that channel once and keeps each kept column's minimum and maximum (two arrays as
 * wide as the widest channel, allocated with the stream); the bucket's two rows are then
 * written from them.
 */
#include "series_stream.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* the longest piece: a column name with its comma ("energy[potential]", "tau[24575]") or a
 * number ("-2.2250738585072014e-308") with its separator, or a channel's opening */
#define SERIES_PIECE 96
/* the binary header: {"rows":..,"reduce":..,"channels":[[name,width],...]} with every channel */
#define SERIES_HEADER (64 + 24 * (CTC_NCHANNELS + 1))

typedef enum part {
    PART_HEADER,     /* CSV: the column names */
    PART_ROWS,       /* CSV: the samples, a row at a time */
    PART_START,      /* JSON: {"t":[ */
    PART_VALUES,     /* JSON: the values of the current column */
    PART_COLUMN,     /* JSON: the next column of the current channel, or its closing */
    PART_CHANNEL,    /* JSON: the next channel, or the closing of the object */
    PART_BIN_HEADER, /* binary: the length and the JSON header */
    PART_BIN_VALUES, /* binary: the values, channel by channel, row by row */
    PART_DONE,
} part;

/* a copy of bytes [lo, lo + len) of one channel's samples */
typedef struct window {
    unsigned char *data; /* SERIES_STREAM_WINDOW bytes, allocated on first use */
    uint64_t lo;
    size_t len;
} window;

struct series_stream {
    series_layout lay;
    unsigned channels; /* the channels written */
    char *coords;      /* (nv) columns kept of nv-wide channels, or NULL = all */
    int csv;
    int bin;         /* SERIES_F32 or SERIES_F32_MINMAX */
    int minmax;      /* SERIES_F32_MINMAX: rows are the minima and maxima of buckets */
    int stride;      /* the sample stride, or the bucket size with minmax */
    double *lo, *hi; /* minmax: (widest channel) the current bucket's minima and maxima */
    series_stream_read_fn read;
    void *src;
    window win[CTC_NCHANNELS + 1]; /* t, then the channels */

    part at;
    int c, i, j;      /* channel (-1 = t), column, sample of the next value */
    int first;        /* the next value is its column's first */
    int first_column; /* the next column is its channel's first */
    char piece[SERIES_HEADER];
    size_t piece_len, piece_pos; /* made, and copied out */
    int failed;
};

/* values per sample of channel c (-1 = t) */
static int width_of(const series_stream *st, int c)
{
    return c < 0 ? 1 : st->lay.width[c];
}

static int column_kept(const series_stream *st, int c, int i)
{
    if (c < 0 || !st->coords || c == CTC_CH_ENERGY || c == CTC_CH_LOOP || c == CTC_CH_EE ||
        c == CTC_CH_POSE || st->lay.width[c] != st->lay.nv)
        return 1;
    return st->coords[i] != 0;
}

/* the sample after j: the next multiple of the stride, the last sample, or nsamples (the end) */
static int next_sample(const series_stream *st, int j)
{
    int last = st->lay.nsamples - 1;
    if (j >= last) return st->lay.nsamples;
    long long k = ((long long)j / st->stride + 1) * st->stride;
    return k < last ? (int)k : last;
}

/* the first kept column of channel c from column i on, or the channel's width if none */
static int kept_from(const series_stream *st, int c, int i)
{
    while (i < width_of(st, c) && !column_kept(st, c, i)) i++;
    return i;
}

/* the next written channel after c, or CTC_NCHANNELS */
static int channel_after(const series_stream *st, int c)
{
    for (c++; c < CTC_NCHANNELS; c++)
        if (st->channels & CTC_CH_BIT(c)) return c;
    return CTC_NCHANNELS;
}

/* advances (*c, *i) to the next written column of the CSV (t is column (-1, 0)); *c becomes
 * CTC_NCHANNELS after the last */
static void next_column(const series_stream *st, int *c, int *i)
{
    int k = kept_from(st, *c, *i + 1);
    while (k >= width_of(st, *c)) {
        *c = channel_after(st, *c);
        if (*c >= CTC_NCHANNELS) return;
        k = kept_from(st, *c, 0);
    }
    *i = k;
}

/* value i of sample j of channel c, through the channel's window; 0, or -1 when the read fails.
 * gap: the bytes to the next value this pass will want, which decides how much to read. */
static int value_at(series_stream *st, int c, int j, int i, uint64_t gap, double *x)
{
    window *w = &st->win[c + 1];
    uint64_t width = (uint64_t)width_of(st, c);
    uint64_t off = ((uint64_t)j * width + (uint64_t)i) * sizeof(double);
    if (off < w->lo || off + sizeof(double) > w->lo + w->len) {
        if (!w->data) {
            w->data = malloc(SERIES_STREAM_WINDOW);
            if (!w->data) return -1;
        }
        uint64_t end = (uint64_t)st->lay.nsamples * width * sizeof(double);
        size_t len = sizeof(double);
        if (gap <= SERIES_STREAM_SPARSE)
            len = end - off < SERIES_STREAM_WINDOW ? (size_t)(end - off) : SERIES_STREAM_WINDOW;
        w->len = 0;
        if (st->read(st->src, c, off, w->data, len) != 0) return -1;
        w->lo = off;
        w->len = len;
    }
    memcpy(x, w->data + (off - w->lo), sizeof(double)); /* the window need not be aligned */
    return 0;
}

/* appends text to the piece */
static void put(series_stream *st, const char *text)
{
    size_t n = strlen(text);
    memcpy(st->piece + st->piece_len, text, n);
    st->piece_len += n;
}

static void put_number(series_stream *st, double x)
{
    if (isfinite(x))
        st->piece_len +=
            (size_t)snprintf(st->piece + st->piece_len, SERIES_PIECE - st->piece_len, "%.17g", x);
    else
        put(st, st->csv ? "nan" : "null");
}

/* one CSV piece: a column name, a value or a line end */
static int step_csv(series_stream *st)
{
    if (st->at == PART_HEADER) {
        if (st->c >= CTC_NCHANNELS) {
            put(st, "\n");
            st->at = PART_ROWS;
            st->c = -1, st->i = 0, st->j = 0;
            if (st->lay.nsamples == 0) st->at = PART_DONE;
        } else if (st->c < 0) {
            put(st, "t");
            next_column(st, &st->c, &st->i);
        } else {
            char name[64];
            result_column_name(name, sizeof name, st->c, st->i);
            put(st, ",");
            put(st, name);
            next_column(st, &st->c, &st->i);
        }
        return 0;
    }
    /* PART_ROWS */
    if (st->c >= CTC_NCHANNELS) {
        put(st, "\n");
        st->c = -1, st->i = 0;
        st->j = next_sample(st, st->j);
        if (st->j >= st->lay.nsamples) st->at = PART_DONE;
        return 0;
    }
    double x;
    if (value_at(st, st->c, st->j, st->i, sizeof(double), &x) != 0) return -1;
    if (st->c >= 0) put(st, ",");
    put_number(st, x);
    next_column(st, &st->c, &st->i);
    return 0;
}

/* one JSON piece: an opening, a value with its comma, or a closing */
static int step_json(series_stream *st)
{
    switch (st->at) {
    case PART_START:
        put(st, "{\"t\":[");
        st->c = -1, st->i = 0, st->j = 0, st->first = 1;
        st->at = PART_VALUES;
        return 0;
    case PART_VALUES:
        if (st->j < st->lay.nsamples) {
            uint64_t gap = (uint64_t)st->stride * (uint64_t)width_of(st, st->c) * sizeof(double);
            double x;
            if (value_at(st, st->c, st->j, st->i, gap, &x) != 0) return -1;
            if (!st->first) put(st, ",");
            st->first = 0;
            put_number(st, x);
            st->j = next_sample(st, st->j);
            return 0;
        }
        put(st, "]");
        st->at = st->c < 0 ? PART_CHANNEL : PART_COLUMN;
        return 0;
    case PART_COLUMN:
        st->i = kept_from(st, st->c, st->i + 1);
        if (st->i < width_of(st, st->c)) {
            put(st, st->first_column ? "[" : ",[");
            st->j = 0, st->first = 1, st->first_column = 0;
            st->at = PART_VALUES;
        } else {
            put(st, "]");
            st->at = PART_CHANNEL;
        }
        return 0;
    case PART_CHANNEL:
        st->c = channel_after(st, st->c);
        if (st->c < CTC_NCHANNELS) {
            put(st, ",\"");
            put(st, ctc_channel_name((ctc_channel)st->c));
            put(st, "\":[");
            st->i = -1, st->first_column = 1;
            st->at = PART_COLUMN;
        } else {
            put(st, "}\n");
            st->at = PART_DONE;
        }
        return 0;
    default:
        return 0;
    }
}

/* the rows of the binary text: the samples the JSON keeps, or two per bucket */
static uint64_t bin_rows(const series_stream *st)
{
    int ns = st->lay.nsamples;
    if (ns <= 0) return 0;
    if (st->minmax) return 2 * (((uint64_t)ns + (uint64_t)st->stride - 1) / (uint64_t)st->stride);
    return (uint64_t)((ns - 1) / st->stride) + 1 + ((ns - 1) % st->stride != 0);
}

/* the kept columns of channel c (-1 = t) */
static int kept_columns(const series_stream *st, int c)
{
    int n = 0;
    for (int i = 0; i < width_of(st, c); i++) n += column_kept(st, c, i);
    return n;
}

/* the binary header piece: 4 bytes of length, then the JSON padded to a multiple of 4 */
static void put_bin_header(series_stream *st)
{
    char *h = st->piece + 4;
    size_t cap = SERIES_HEADER - 4, n = 0;
    n +=
        (size_t)snprintf(h + n, cap - n, "{\"rows\":%llu,\"reduce\":\"%s\",\"channels\":[[\"t\",1]",
                         (unsigned long long)bin_rows(st), st->minmax ? "minmax" : "stride");
    for (int c = channel_after(st, -1); c < CTC_NCHANNELS; c = channel_after(st, c))
        n += (size_t)snprintf(h + n, cap - n, ",[\"%s\",%d]", ctc_channel_name((ctc_channel)c),
                              kept_columns(st, c));
    n += (size_t)snprintf(h + n, cap - n, "]}");
    while ((n + 4) % 4 != 0) h[n++] = ' ';
    for (int k = 0; k < 4; k++) st->piece[k] = (char)((n >> (8 * k)) & 0xff);
    st->piece_len = n + 4;
}

/* fills st->lo, st->hi with the minima and maxima of the kept columns of channel c (-1 = t)
 * over bucket b; t's are its first and last times. 0, or -1 when a read fails. */
static int read_bucket(series_stream *st, int c, int b)
{
    int j0 = b * st->stride, j1 = j0 + st->stride;
    if (j1 > st->lay.nsamples) j1 = st->lay.nsamples;
    if (c < 0) {
        if (value_at(st, c, j0, 0, sizeof(double), &st->lo[0]) != 0) return -1;
        return value_at(st, c, j1 - 1, 0, sizeof(double), &st->hi[0]);
    }
    int w = width_of(st, c);
    for (int i = 0; i < w; i++) st->lo[i] = st->hi[i] = NAN;
    for (int j = j0; j < j1; j++)
        for (int i = kept_from(st, c, 0); i < w; i = kept_from(st, c, i + 1)) {
            double x;
            if (value_at(st, c, j, i, sizeof(double), &x) != 0) return -1;
            if (isnan(x)) continue;
            if (isnan(st->lo[i]) || x < st->lo[i]) st->lo[i] = x;
            if (isnan(st->hi[i]) || x > st->hi[i]) st->hi[i] = x;
        }
    return 0;
}

/* one binary piece: the header, or one float32 (little-endian); st->j counts rows */
static int step_bin(series_stream *st)
{
    if (st->at == PART_BIN_HEADER) {
        put_bin_header(st);
        st->c = -1, st->i = 0, st->j = 0;
        st->at = bin_rows(st) > 0 ? PART_BIN_VALUES : PART_DONE;
        return 0;
    }
    double x;
    if (st->minmax) {
        int b = st->j / 2;
        if (st->j % 2 == 0 && st->i == kept_from(st, st->c, 0) && read_bucket(st, st->c, b) != 0)
            return -1;
        x = st->j % 2 == 0 ? st->lo[st->c < 0 ? 0 : st->i] : st->hi[st->c < 0 ? 0 : st->i];
    } else {
        int sample = st->j == 0 ? 0 : (int)((long long)st->j * st->stride);
        if (sample >= st->lay.nsamples) sample = st->lay.nsamples - 1;
        if (value_at(st, st->c, sample, st->i, sizeof(double), &x) != 0) return -1;
    }
    float f = (float)x;
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    for (int k = 0; k < 4; k++) st->piece[k] = (char)((u >> (8 * k)) & 0xff);
    st->piece_len = 4;

    /* the next column, row, channel */
    st->i = kept_from(st, st->c, st->i + 1);
    if (st->i < width_of(st, st->c)) return 0;
    st->j++;
    if ((uint64_t)st->j < bin_rows(st)) {
        st->i = kept_from(st, st->c, 0);
        return 0;
    }
    do {
        st->c = channel_after(st, st->c);
    } while (st->c < CTC_NCHANNELS && kept_columns(st, st->c) == 0);
    if (st->c >= CTC_NCHANNELS) {
        st->at = PART_DONE;
        return 0;
    }
    st->j = 0;
    st->i = kept_from(st, st->c, 0);
    return 0;
}

series_stream *series_stream_new(const series_layout *lay, const result_select *sel,
                                 series_format fmt, series_stream_read_fn read, void *src)
{
    series_stream *st = calloc(1, sizeof *st);
    if (!st) return NULL;
    st->lay = *lay;
    st->csv = fmt == SERIES_CSV;
    st->bin = fmt == SERIES_F32 || fmt == SERIES_F32_MINMAX;
    st->minmax = fmt == SERIES_F32_MINMAX;
    st->stride = sel && sel->every > 1 ? sel->every : 1;
    st->read = read;
    st->src = src;
    for (int c = 0; c < CTC_NCHANNELS; c++)
        if (lay->width[c] > 0 && (!sel || sel->channels == 0 || (sel->channels & CTC_CH_BIT(c))))
            st->channels |= CTC_CH_BIT(c);
    if (sel && sel->coords && lay->nv > 0) {
        st->coords = malloc((size_t)lay->nv);
        if (!st->coords) {
            free(st);
            return NULL;
        }
        memcpy(st->coords, sel->coords, (size_t)lay->nv);
    }
    if (st->minmax) {
        int widest = 1;
        for (int c = 0; c < CTC_NCHANNELS; c++)
            if (lay->width[c] > widest) widest = lay->width[c];
        st->lo = malloc(2 * (size_t)widest * sizeof(double));
        if (!st->lo) {
            series_stream_free(st);
            return NULL;
        }
        st->hi = st->lo + widest;
    }
    st->c = -1;
    st->at = st->bin ? PART_BIN_HEADER : st->csv ? PART_HEADER : PART_START;
    return st;
}

ptrdiff_t series_stream_fill(series_stream *st, char *buf, size_t max)
{
    size_t n = 0;
    if (st->failed) return -1;
    while (n < max) {
        if (st->piece_pos == st->piece_len) {
            if (st->at == PART_DONE) break;
            st->piece_len = st->piece_pos = 0;
            int rc = st->bin ? step_bin(st) : st->csv ? step_csv(st) : step_json(st);
            if (rc != 0) {
                st->failed = 1;
                return -1;
            }
            continue;
        }
        size_t k = st->piece_len - st->piece_pos;
        if (k > max - n) k = max - n;
        memcpy(buf + n, st->piece + st->piece_pos, k);
        st->piece_pos += k;
        n += k;
    }
    return (ptrdiff_t)n;
}

uint64_t series_stream_values(const series_stream *st)
{
    uint64_t rows = bin_rows(st), columns = 1;
    for (int c = 0; c < CTC_NCHANNELS; c++)
        for (int i = 0; (st->channels & CTC_CH_BIT(c)) && i < st->lay.width[c]; i++)
            columns += (uint64_t)column_kept(st, c, i);
    return rows * columns;
}

void series_stream_free(series_stream *st)
{
    if (!st) return;
    for (int c = 0; c <= CTC_NCHANNELS; c++) free(st->win[c].data);
    free(st->coords);
    free(st->lo);
    free(st);
}

int series_stream_stride(int nsamples, long long every, long long max_points)
{
    long long stride = every > 1 ? every : 1;
    if (max_points >= 2 && nsamples > max_points) {
        /* ceil((nsamples - 1) / (max_points - 1)): samples 0, s, ..., and the last are then at
           most max_points, and one less would keep more */
        long long need = ((long long)nsamples - 2) / (max_points - 1) + 1;
        if (need > stride) stride = need;
    }
    return (int)stride;
}

int series_stream_buckets_stride(int nsamples, long long every, long long max_points)
{
    long long size = every > 1 ? every : 1;
    if (max_points >= 2 && nsamples > 0) {
        long long buckets = max_points / 2;
        long long need = ((long long)nsamples + buckets - 1) / buckets;
        if (need > size) size = need;
    }
    return (int)size;
}
