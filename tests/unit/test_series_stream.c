/*
 * test_series_stream.c - the series written in pieces (server/series_stream.c).
 *
 * Oracle: result_out.c, which writes a whole series in one pass to a FILE (the command line's
 * writer, and the service's before it streamed). For hand-made series holding every kind of
 * double (NaN, infinities, -0, subnormals, the extremes) and every selection (channels, the
 * coordinate filter, strides from 1 past the number of samples), the stream's text must equal
 * result_write_csv's, and result_write_series_json's plus a newline, byte for byte, whatever the
 * size of the pieces it is asked for (1 byte to 64 KiB). The reads it makes are checked too: in
 * bounds, at most SERIES_STREAM_WINDOW bytes each, and in total not much more than the bytes the
 * text needs. The stride for ?max_points is checked against a count of the samples it keeps.
 * The binary forms (f32, and f32 with min/max per bucket) are checked byte for byte against a
 * naive writer here, and min/max against a spike that a stride steps over.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "result_out.h"
#include "series_stream.h"

/* a hand-made result of nsamples samples: q nq wide, qdot and tau nv wide, e nind wide, energy;
 * values drawn from a fixed list of awkward doubles and a counter */
static ctc_sim_result *make_result(int nsamples, int nq, int nv, int nind)
{
    static const double odd[] = {NAN,
                                 INFINITY,
                                 -INFINITY,
                                 -0.0,
                                 5e-324,
                                 1.7976931348623157e308,
                                 -2.2250738585072014e-308,
                                 0.1,
                                 1.0 / 3.0,
                                 1e21,
                                 -123456789.0};
    ctc_sim_result *r = calloc(1, sizeof *r);
    cr_assert_not_null(r);
    r->nq = nq, r->nv = nv, r->nind = nind, r->nsamples = nsamples;
    r->width[CTC_CH_Q] = nq;
    r->width[CTC_CH_QD] = nv;
    r->width[CTC_CH_E] = nind;
    r->width[CTC_CH_TAU] = nind;
    r->width[CTC_CH_ENERGY] = 2;
    r->t = malloc(sizeof(double) * (size_t)(nsamples + 1));
    for (int j = 0; j < nsamples; j++) r->t[j] = 0.001 * j;
    unsigned k = 0;
    for (int c = 0; c < CTC_NCHANNELS; c++) {
        if (!r->width[c]) continue;
        r->channels |= CTC_CH_BIT(c);
        size_t count = (size_t)nsamples * (size_t)r->width[c];
        r->ch[c] = malloc(sizeof(double) * (count + 1));
        for (size_t m = 0; m < count; m++, k++)
            r->ch[c][m] = k % 7 == 3 ? odd[(k / 7) % (sizeof odd / sizeof odd[0])]
                                     : sin(0.37 * (double)k) * pow(10.0, (double)(k % 9) - 4);
    }
    r->metrics.nv = nv;
    return r;
}

/* the samples of a result as the store keeps them, with the reads counted */
typedef struct memory_source {
    const ctc_sim_result *r;
    uint64_t bytes_read;
    size_t largest_read;
    int fail_after; /* reads that succeed before the next one fails; < 0 = never */
} memory_source;

static int memory_read(void *arg, int channel, uint64_t offset, void *buf, size_t len)
{
    memory_source *m = arg;
    const ctc_sim_result *r = m->r;
    cr_assert(channel >= -1 && channel < CTC_NCHANNELS);
    const double *base = channel < 0 ? r->t : r->ch[channel];
    int width = channel < 0 ? 1 : r->width[channel];
    cr_assert_not_null(base, "read of channel %d, which is not recorded", channel);
    uint64_t size = (uint64_t)r->nsamples * (uint64_t)width * sizeof(double);
    cr_assert(len > 0 && offset + len <= size, "read of [%llu, %llu) past %llu bytes",
              (unsigned long long)offset, (unsigned long long)(offset + len),
              (unsigned long long)size);
    cr_assert_leq(len, SERIES_STREAM_WINDOW);
    if (m->fail_after == 0) return -1;
    if (m->fail_after > 0) m->fail_after--;
    memcpy(buf, (const char *)base + offset, len);
    m->bytes_read += len;
    if (len > m->largest_read) m->largest_read = len;
    return 0;
}

static series_layout layout_of(const ctc_sim_result *r)
{
    series_layout lay = {.nsamples = r->nsamples, .nv = r->nv};
    memcpy(lay.width, r->width, sizeof lay.width);
    return lay;
}

/* the oracle's text: result_out.c's CSV, or its series JSON and a newline */
static char *oracle(const ctc_sim_result *r, const result_select *sel, int csv, size_t *len)
{
    char *buf = NULL;
    FILE *f = open_memstream(&buf, len);
    cr_assert_not_null(f);
    int rc = csv ? result_write_csv(f, r, sel) : result_write_series_json(f, r, sel);
    cr_assert_eq(rc, 0);
    if (!csv) fputc('\n', f);
    cr_assert_eq(fclose(f), 0);
    return buf;
}

/* the stream's text in form fmt, asked for in pieces of at most piece bytes */
static char *streamed_as(const ctc_sim_result *r, const result_select *sel, series_format fmt,
                         size_t piece, memory_source *src, size_t *len)
{
    series_layout lay = layout_of(r);
    series_stream *st = series_stream_new(&lay, sel, fmt, memory_read, src);
    cr_assert_not_null(st);
    size_t cap = 1 << 16, n = 0;
    char *text = malloc(cap);
    for (;;) {
        if (cap - n < piece) text = realloc(text, cap *= 2);
        ptrdiff_t got = series_stream_fill(st, text + n, piece);
        cr_assert_geq(got, 0, "a fill failed");
        cr_assert_leq((size_t)got, piece);
        if (got == 0) break;
        n += (size_t)got;
    }
    cr_assert_eq(series_stream_fill(st, text, piece), 0, "the end is not kept");
    series_stream_free(st);
    *len = n;
    return text;
}

static char *streamed(const ctc_sim_result *r, const result_select *sel, int csv, size_t piece,
                      memory_source *src, size_t *len)
{
    return streamed_as(r, sel, csv ? SERIES_CSV : SERIES_JSON, piece, src, len);
}

static void assert_same_text(const ctc_sim_result *r, const result_select *sel, int csv,
                             size_t piece, const char *what)
{
    size_t want_len, got_len;
    memory_source src = {.r = r, .fail_after = -1};
    char *want = oracle(r, sel, csv, &want_len);
    char *got = streamed(r, sel, csv, piece, &src, &got_len);
    size_t k = 0;
    while (k < want_len && k < got_len && want[k] == got[k]) k++;
    cr_assert(k == want_len && k == got_len,
              "%s, %s, pieces of %zu: texts differ at byte %zu of %zu (stream: %zu)\n"
              "want ...%.40s\ngot  ...%.40s",
              what, csv ? "csv" : "json", piece, k, want_len, got_len, want + (k > 20 ? k - 20 : 0),
              got + (k > 20 ? k - 20 : 0));
    free(want);
    free(got);
}

Test(series_stream, equals_result_out_for_every_selection_and_piece_size)
{
    static const size_t pieces[] = {1, 7, 100, 65536};
    static const int sizes[][4] = {
        {0, 3, 3, 3}, {1, 3, 3, 3}, {2, 4, 3, 3}, {37, 3, 3, 2}, {400, 7, 6, 6}};
    for (size_t z = 0; z < sizeof sizes / sizeof sizes[0]; z++) {
        ctc_sim_result *r = make_result(sizes[z][0], sizes[z][1], sizes[z][2], sizes[z][3]);
        int nv = r->nv;
        char *odd_coords = calloc((size_t)nv, 1), *one_coord = calloc((size_t)nv, 1);
        for (int i = 0; i < nv; i += 2) odd_coords[i] = 1;
        one_coord[nv - 1] = 1;
        const int strides[] = {1, 2, 3, 36, r->nsamples > 0 ? r->nsamples - 1 : 1, r->nsamples + 5};
        for (size_t s = 0; s < sizeof strides / sizeof strides[0]; s++) {
            if (strides[s] < 1) continue;
            const result_select sels[] = {
                {.every = strides[s]},
                {.channels = CTC_CH_BIT(CTC_CH_TAU) | CTC_CH_BIT(CTC_CH_ENERGY),
                 .every = strides[s]},
                {.every = strides[s], .coords = odd_coords},
                {.channels = CTC_CH_BIT(CTC_CH_Q) | CTC_CH_BIT(CTC_CH_E),
                 .every = strides[s],
                 .coords = one_coord},
            };
            for (size_t k = 0; k < sizeof sels / sizeof sels[0]; k++)
                for (size_t p = 0; p < sizeof pieces / sizeof pieces[0]; p++)
                    for (int csv = 0; csv <= 1; csv++) {
                        char what[96];
                        snprintf(what, sizeof what, "%d samples, stride %d, selection %zu",
                                 r->nsamples, strides[s], k);
                        assert_same_text(r, &sels[k], csv, pieces[p], what);
                    }
        }
        assert_same_text(r, NULL, 0, 4096, "no selection");
        assert_same_text(r, NULL, 1, 4096, "no selection");
        free(odd_coords);
        free(one_coord);
        ctc_sim_result_free(r);
    }
}

Test(series_stream, reads_in_bounded_windows_and_little_more_than_it_writes)
{
    /* 3000 samples of 5 coordinates: 3000 x 18 values; and 40 samples of 300 coordinates */
    static const int sizes[][4] = {{3000, 5, 5, 5}, {40, 300, 300, 300}};
    for (size_t z = 0; z < 2; z++) {
        ctc_sim_result *r = make_result(sizes[z][0], sizes[z][1], sizes[z][2], sizes[z][3]);
        /* what each pass may read: CSV reads each value about once; JSON reads a column's
           values through windows of whole rows (each channel once per column) while they lie
           at most SERIES_STREAM_SPARSE bytes apart, and one by one beyond */
        uint64_t stored = (uint64_t)r->nsamples * sizeof(double), by_column = stored;
        for (int c = 0; c < CTC_NCHANNELS; c++) {
            uint64_t bytes = (uint64_t)r->nsamples * (uint64_t)r->width[c] * sizeof(double);
            uint64_t rereads = (uint64_t)r->width[c] * sizeof(double) <= SERIES_STREAM_SPARSE
                                   ? (uint64_t)r->width[c]
                                   : 1;
            stored += bytes;
            by_column += bytes * rereads;
        }
        for (int csv = 0; csv <= 1; csv++) {
            memory_source all = {.r = r, .fail_after = -1};
            size_t len;
            free(streamed(r, NULL, csv, 65536, &all, &len));
            uint64_t bound = 2 * (csv ? stored : by_column);
            cr_assert_leq(all.largest_read, SERIES_STREAM_WINDOW);
            cr_assert_leq(all.bytes_read, bound, "%s read %llu bytes of %llu stored (bound %llu)",
                          csv ? "csv" : "json", (unsigned long long)all.bytes_read,
                          (unsigned long long)stored, (unsigned long long)bound);
            /* a stride of 1000 in JSON reads the values it writes, one by one, and not the
               rows between them */
            memory_source sparse = {.r = r, .fail_after = -1};
            result_select every = {.every = 1000};
            series_layout lay = layout_of(r);
            series_stream *st = series_stream_new(&lay, &every, csv, memory_read, NULL);
            uint64_t written = series_stream_values(st) * sizeof(double);
            series_stream_free(st);
            free(streamed(r, &every, csv, 65536, &sparse, &len));
            if (!csv)
                cr_assert_eq(sparse.bytes_read, written, "read %llu bytes for %llu written",
                             (unsigned long long)sparse.bytes_read, (unsigned long long)written);
        }
        ctc_sim_result_free(r);
    }
}

Test(series_stream, a_failed_read_fails_the_stream_for_good)
{
    ctc_sim_result *r = make_result(5000, 3, 3, 3);
    series_layout lay = layout_of(r);
    memory_source src = {.r = r, .fail_after = 3};
    series_stream *st = series_stream_new(&lay, NULL, 0, memory_read, &src);
    char buf[4096];
    ptrdiff_t got;
    size_t total = 0;
    while ((got = series_stream_fill(st, buf, sizeof buf)) > 0) total += (size_t)got;
    cr_assert_eq(got, -1);
    cr_assert_gt(total, 0, "the reads before the failure gave text");
    src.fail_after = -1;
    cr_assert_eq(series_stream_fill(st, buf, sizeof buf), -1, "a failed stream went on");
    series_stream_free(st);
    series_stream_free(NULL);
    ctc_sim_result_free(r);
}

Test(series_stream, values_counts_the_samples_and_columns_written)
{
    ctc_sim_result *r = make_result(101, 3, 3, 3);
    series_layout lay = layout_of(r);
    char coords[3] = {0, 1, 0};
    /* t + q, qdot, e, tau (3 each) + energy (2) = 15 columns; 101 samples */
    const struct {
        result_select sel;
        uint64_t values;
    } cases[] = {
        {{.every = 1}, 101 * 15},
        {{.every = 10}, 11 * 15},                  /* 0, 10, ..., 100 */
        {{.every = 7}, 16 * 15},                   /* 0, 7, ..., 98 and 100 */
        {{.every = 1, .coords = coords}, 101 * 7}, /* t, one of each nv-wide, energy */
        {{.channels = CTC_CH_BIT(CTC_CH_ENERGY), .every = 200}, 2 * 3},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        series_stream *st = series_stream_new(&lay, &cases[k].sel, 1, memory_read, NULL);
        cr_assert_eq(series_stream_values(st), cases[k].values, "case %zu: %llu", k,
                     (unsigned long long)series_stream_values(st));
        series_stream_free(st);
    }
    ctc_sim_result_free(r);
}

/* the samples kept with this stride: 0, s, 2s, ... and the last */
static long long kept(int nsamples, int stride)
{
    long long n = 0;
    for (int j = 0; j < nsamples; j++) n += j % stride == 0 || j == nsamples - 1;
    return n;
}

Test(series_stream, max_points_keeps_the_most_samples_it_allows_and_no_more)
{
    static const int sizes[] = {0, 1, 2, 3, 10, 11, 999, 1000, 1001, 200000};
    static const long long limits[] = {2, 3, 4, 7, 10, 11, 100, 5000, 199999, 200000, 1000000};
    for (size_t a = 0; a < sizeof sizes / sizeof sizes[0]; a++)
        for (size_t b = 0; b < sizeof limits / sizeof limits[0]; b++) {
            int ns = sizes[a];
            long long n = limits[b];
            int s = series_stream_stride(ns, 1, n);
            cr_assert_geq(s, 1);
            cr_assert_leq(kept(ns, s), n, "%d samples, max_points %lld: stride %d keeps %lld", ns,
                          n, s, kept(ns, s));
            if (s > 1)
                cr_assert_gt(kept(ns, s - 1), n,
                             "%d samples, max_points %lld: stride %d is "
                             "more than needed",
                             ns, n, s);
            /* every only ever makes it larger */
            cr_assert_eq(series_stream_stride(ns, 3, n), s > 3 ? s : 3);
        }
    cr_assert_eq(series_stream_stride(1000, 7, 0), 7, "no max_points: the stride is every");
    cr_assert_eq(series_stream_stride(1000, 1, 0), 1);
}

/* ---- the binary forms ---- */

/* the oracle's binary text, built naively from the result: the header, then per channel (t
 * first) its rows - the samples kept with stride s, or each bucket of s samples' min and max
 * found by a plain scan - of float32 values of the kept columns */
static unsigned char *oracle_f32(const ctc_sim_result *r, const result_select *sel, int minmax,
                                 int s, size_t *len)
{
    int ns = r->nsamples;
    int rows_of[2] = {0, 0}; /* stride, minmax */
    for (int j = 0; j < ns; j++) rows_of[0] += j % s == 0 || j == ns - 1;
    rows_of[1] = 2 * ((ns + s - 1) / s);
    int rows = rows_of[minmax];
    char json[1024];
    int n = snprintf(json, sizeof json, "{\"rows\":%d,\"reduce\":\"%s\",\"channels\":[[\"t\",1]",
                     rows, minmax ? "minmax" : "stride");
    for (int c = 0; c < CTC_NCHANNELS; c++) {
        if (!r->width[c] || (sel->channels && !(sel->channels & CTC_CH_BIT(c)))) continue;
        int k = 0;
        for (int i = 0; i < r->width[c]; i++)
            k += !sel->coords || r->width[c] != r->nv || c == CTC_CH_ENERGY || sel->coords[i];
        n += snprintf(json + n, sizeof json - (size_t)n, ",[\"%s\",%d]",
                      ctc_channel_name((ctc_channel)c), k);
    }
    n += snprintf(json + n, sizeof json - (size_t)n, "]}");
    while (n % 4) json[n++] = ' ';
    size_t cap = 4 + (size_t)n + 4 * (size_t)rows * 64;
    unsigned char *out = calloc(cap, 1);
    out[0] = (unsigned char)(n & 0xff), out[1] = (unsigned char)(n >> 8);
    memcpy(out + 4, json, (size_t)n);
    size_t at = 4 + (size_t)n;
    for (int c = -1; c < CTC_NCHANNELS; c++) {
        if (c >= 0 && (!r->width[c] || (sel->channels && !(sel->channels & CTC_CH_BIT(c)))))
            continue;
        int w = c < 0 ? 1 : r->width[c];
        const double *v = c < 0 ? r->t : r->ch[c];
        for (int row = 0; row < rows; row++)
            for (int i = 0; i < w; i++) {
                if (c >= 0 && sel->coords && r->width[c] == r->nv && c != CTC_CH_ENERGY &&
                    !sel->coords[i])
                    continue;
                double x;
                if (!minmax) {
                    int j = row * s < ns - 1 ? row * s : ns - 1;
                    x = v[(size_t)j * (size_t)w + (size_t)i];
                } else {
                    int j0 = (row / 2) * s, j1 = j0 + s < ns ? j0 + s : ns;
                    if (c < 0) {
                        x = v[row % 2 ? j1 - 1 : j0];
                    } else {
                        x = NAN;
                        for (int j = j0; j < j1; j++) {
                            double y = v[(size_t)j * (size_t)w + (size_t)i];
                            if (!isnan(y) && (isnan(x) || (row % 2 ? y > x : y < x))) x = y;
                        }
                    }
                }
                float f = (float)x;
                memcpy(out + at, &f, 4); /* the test machine is little-endian (checked below) */
                at += 4;
            }
    }
    *len = at;
    return out;
}

Test(series_stream, f32_holds_the_kept_samples_and_minmax_each_buckets_extremes)
{
    const uint32_t one = 1;
    unsigned char first;
    memcpy(&first, &one, 1);
    cr_assert_eq(first, 1, "the oracle writes floats in the machine's order: little-endian");
    static const size_t pieces[] = {1, 3, 4096};
    static const int sizes[][4] = {{0, 3, 3, 3}, {1, 3, 3, 3}, {37, 3, 3, 2}, {400, 7, 6, 6}};
    for (size_t z = 0; z < sizeof sizes / sizeof sizes[0]; z++) {
        ctc_sim_result *r = make_result(sizes[z][0], sizes[z][1], sizes[z][2], sizes[z][3]);
        char *odd_coords = calloc((size_t)r->nv, 1);
        for (int i = 0; i < r->nv; i += 2) odd_coords[i] = 1;
        const int strides[] = {1, 2, 3, 36, r->nsamples + 5};
        for (size_t s = 0; s < sizeof strides / sizeof strides[0]; s++) {
            const result_select sels[] = {
                {.every = strides[s]},
                {.every = strides[s], .coords = odd_coords},
                {.channels = CTC_CH_BIT(CTC_CH_E) | CTC_CH_BIT(CTC_CH_ENERGY), .every = strides[s]},
            };
            for (size_t k = 0; k < sizeof sels / sizeof sels[0]; k++)
                for (int minmax = 0; minmax <= 1; minmax++)
                    for (size_t p = 0; p < sizeof pieces / sizeof pieces[0]; p++) {
                        size_t want_len, got_len;
                        unsigned char *want =
                            oracle_f32(r, &sels[k], minmax, strides[s], &want_len);
                        memory_source src = {.r = r, .fail_after = -1};
                        series_layout lay = layout_of(r);
                        series_stream *st = series_stream_new(
                            &lay, &sels[k], minmax ? SERIES_F32_MINMAX : SERIES_F32, memory_read,
                            &src);
                        cr_assert_eq(series_stream_values(st) * 4,
                                     want_len - 4 - (want[0] | want[1] << 8),
                                     "values counts the floats written");
                        series_stream_free(st);
                        char *got =
                            streamed_as(r, &sels[k], minmax ? SERIES_F32_MINMAX : SERIES_F32,
                                        pieces[p], &src, &got_len);
                        size_t b = 0;
                        while (b < want_len && b < got_len && want[b] == (unsigned char)got[b]) b++;
                        cr_assert(b == want_len && b == got_len,
                                  "%d samples, stride %d, selection %zu, %s, pieces of %zu: "
                                  "differ at byte %zu of %zu (stream: %zu)",
                                  r->nsamples, strides[s], k, minmax ? "minmax" : "stride",
                                  pieces[p], b, want_len, got_len);
                        free(want);
                        free(got);
                    }
        }
        free(odd_coords);
        ctc_sim_result_free(r);
    }
}

Test(series_stream, minmax_keeps_a_one_sample_spike_that_a_stride_drops)
{
    ctc_sim_result *r = make_result(1000, 2, 2, 2);
    for (int j = 0; j < 1000; j++) r->ch[CTC_CH_E][2 * j] = 0.0;
    r->ch[CTC_CH_E][2 * 501] = 7.0; /* a spike at sample 501, between strides of 100 */
    result_select sel = {.channels = CTC_CH_BIT(CTC_CH_E), .every = 100};
    for (int minmax = 0; minmax <= 1; minmax++) {
        memory_source src = {.r = r, .fail_after = -1};
        size_t len;
        char *text =
            streamed_as(r, &sel, minmax ? SERIES_F32_MINMAX : SERIES_F32, 4096, &src, &len);
        uint32_t h = (uint32_t)(unsigned char)text[0] | (uint32_t)(unsigned char)text[1] << 8;
        int rows = minmax ? 20 : 11, seen = 0;
        const char *e = text + 4 + h + 4 * rows; /* past t */
        cr_assert_eq(len, 4 + h + 4 * (size_t)rows * 3, "%s: %zu bytes",
                     minmax ? "minmax" : "stride", len);
        for (int row = 0; row < rows; row++) {
            float f;
            memcpy(&f, e + 8 * row, 4);
            seen |= f == 7.0f;
        }
        cr_assert_eq(seen, minmax, "%s: the spike is %s", minmax ? "minmax" : "stride",
                     seen ? "kept" : "lost");
        free(text);
    }
    cr_assert_eq(series_stream_buckets_stride(1000, 1, 20), 100, "10 buckets of 100 samples");
    cr_assert_eq(series_stream_buckets_stride(1001, 1, 20), 101, "1001 samples in 10 buckets");
    cr_assert_eq(series_stream_buckets_stride(1000, 300, 20), 300, "every is a lower bound");
    cr_assert_eq(series_stream_buckets_stride(5, 1, 0), 1, "no max_points: every sample");
    ctc_sim_result_free(r);
}
