/*
 * series_stream.h - a run's series written in pieces of bounded size, from samples read in
 * pieces of bounded size: the body of GET /api/jobs/{id}/series.
 *
 * The text is byte for byte what result_out.h writes for the same series and selection: the CSV
 * of result_write_csv, or the series object of result_write_series_json followed by one newline.
 * It is made on demand, as the reader asks for it (series_stream_fill), and the samples are read
 * through a callback (series_stream_read_fn) in windows of at most SERIES_STREAM_WINDOW bytes, so
 * a stream holds O(SERIES_STREAM_WINDOW) memory whatever the size of the series. The samples
 * are laid out as the store keeps them (store.h): per channel, nsamples x width float64,
 * row-major; "t" is a channel of width 1.
 *
 * A third form, SERIES_F32, is compact binary for plotting (about 4 bytes a value instead of
 * 20): a 4-byte little-endian length H, H bytes of JSON header padded with spaces so the
 * values start at a multiple of 4,
 *     {"rows":R,"reduce":"stride"|"minmax","channels":[["t",1],["q",K],...]}
 * then, channel by channel in that order (t first), R rows of K float32 little-endian values,
 * row-major: the kept columns in index order, as the JSON has them. Non-finite values stay
 * non-finite (NaN, +-inf). "stride" keeps the rows the JSON keeps (0, stride, ..., the last).
 * SERIES_F32_MINMAX cuts the samples into consecutive buckets of `stride` samples (the last
 * may be shorter) and writes two rows per bucket: the first at the bucket's first time with
 * each column's minimum over the bucket, the second at its last time with the maximum (NaNs
 * ignored; NaN when a column has no number in the bucket). Drawn as a line this is the
 * bucket's envelope, so a spike of one sample survives any decimation.
 *
 * The CSV is written row by row and reads each channel's rows in order; the JSON is columnar and
 * reads one column at a time, every stride-th row of one channel, where a column's values are
 * width x 8 bytes apart: a window then holds the rows from the one asked for on, unless the
 * values wanted lie more than SERIES_STREAM_SPARSE bytes apart, when each value is read alone
 * (a wide channel, or a large stride, would otherwise read bytes it never writes).
 */
#ifndef SERIES_STREAM_H
#define SERIES_STREAM_H

#include <stddef.h>
#include <stdint.h>

#include "result_out.h"

#define SERIES_STREAM_WINDOW 16384 /* bytes of one channel's samples read at once, at most */
#define SERIES_STREAM_SPARSE 512   /* bytes between values read apart, each alone */

/* The forms of the text (SERIES_JSON and SERIES_CSV are 0 and 1: a csv flag reads as one). */
typedef enum series_format {
    SERIES_JSON = 0,
    SERIES_CSV = 1,
    SERIES_F32 = 2,        /* binary float32, the samples the JSON keeps */
    SERIES_F32_MINMAX = 3, /* binary float32, min and max rows per bucket of stride samples */
} series_format;

/* The shape of a stored series: what the selection is checked against. */
typedef struct series_layout {
    int nsamples;
    int nv;                   /* the coordinate filter applies to channels this wide */
    int width[CTC_NCHANNELS]; /* values per sample of each channel, 0 if not recorded */
} series_layout;

/* Reads len bytes at offset (bytes from the start of the channel's samples) of a channel (-1 =
 * t, else a ctc_channel) into buf. Returns 0, or non-zero when they cannot be read (the stream
 * then fails). The stream never asks for bytes past nsamples x width x 8. */
typedef int (*series_stream_read_fn)(void *src, int channel, uint64_t offset, void *buf,
                                     size_t len);

typedef struct series_stream series_stream;

/* A new stream of the series of layout lay, selected by sel (NULL: everything; sel->coords, when
 * given, holds lay->nv flags and is copied), in the form fmt. src is passed to read and is not
 * owned. Returns NULL when out of memory. */
series_stream *series_stream_new(const series_layout *lay, const result_select *sel,
                                 series_format fmt, series_stream_read_fn read, void *src);

/* Writes the next at most max (>= 1) bytes of the text into buf. Returns the number written
 * (>= 1), 0 once the whole text has been written, or -1 when a read failed (the stream is then
 * failed for good; the text so far is a truncated one). */
ptrdiff_t series_stream_fill(series_stream *st, char *buf, size_t max);

/* The number of values (rows x columns, t included) the text holds: a measure of its size
 * (CSV and JSON spend about 20 bytes a value, SERIES_F32 4). */
uint64_t series_stream_values(const series_stream *st);

/* Frees a stream; NULL is allowed. */
void series_stream_free(series_stream *st);

/* The sample stride for a series of nsamples samples read with ?every=every (>= 1) and
 * ?max_points=max_points (>= 2, or 0 for none): the smallest stride of at least every that
 * keeps at most max_points samples, counting samples 0, stride, 2 stride, ... and always the
 * last (result_select.every). */
int series_stream_stride(int nsamples, long long every, long long max_points);

/* The bucket size for SERIES_F32_MINMAX of nsamples samples with ?every=every (>= 1) and
 * ?max_points=max_points (>= 2, or 0 for none): the smallest of at least every whose rows, two
 * per bucket (2 ceil(nsamples / size)), are at most max_points. */
int series_stream_buckets_stride(int nsamples, long long every, long long max_points);

#endif
