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
 */
#include "series_stream.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* the longest piece: a column name with its comma ("energy[potential]", "tau[24575]") or a
 * number ("-2.2250738585072014e-308") with its separator, or a channel's opening */
#define SERIES_PIECE 96

typedef enum part {
    PART_HEADER,  /* CSV: the column names */
    PART_ROWS,    /* CSV: the samples, a row at a time */
    PART_START,   /* JSON: {"t":[ */
    PART_VALUES,  /* JSON: the values of the current column */
    PART_COLUMN,  /* JSON: the next column of the current channel, or its closing */
    PART_CHANNEL, /* JSON: the next channel, or the closing of the object */
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
    int stride;
    series_stream_read_fn read;
    void *src;
    window win[CTC_NCHANNELS + 1]; /* t, then the channels */

    part at;
    int c, i, j;      /* channel (-1 = t), column, sample of the next value */
    int first;        /* the next value is its column's first */
    int first_column; /* the next column is its channel's first */
    char piece[SERIES_PIECE];
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

series_stream *series_stream_new(const series_layout *lay, const result_select *sel, int csv,
                                 series_stream_read_fn read, void *src)
{
    series_stream *st = calloc(1, sizeof *st);
    if (!st) return NULL;
    st->lay = *lay;
    st->csv = csv != 0;
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
    st->c = -1;
    st->at = st->csv ? PART_HEADER : PART_START;
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
            int rc = st->csv ? step_csv(st) : step_json(st);
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
    int ns = st->lay.nsamples;
    uint64_t rows = 0, columns = 1;
    if (ns > 0) rows = (uint64_t)((ns - 1) / st->stride) + 1 + ((ns - 1) % st->stride != 0);
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
