/*
 * svgplot.h - small log-log scatter and line plots as standalone SVG files, for the benchmarks'
 * figures (bench/NOTEBOOK.md). Header-only (the Makefile builds every C file in bench/ as its own
 * program): static inline functions, no state.
 *
 * A figure is a grid of panels; each panel has log10 axes with a grid line at every decade
 * (the range is the data's, widened to whole decades), a title, axis labels, a legend to its
 * right, and any number of series drawn as markers, optionally joined by a line in the order
 * given. A panel can also draw the diagonal y = x. Points whose x or y is not finite or not
 * positive are left out (a log axis cannot show them); a series keeps its legend entry even if
 * all of its points are left out.
 *
 * Nothing is allocated; the caller owns every array and string it passes.
 */
#ifndef BENCH_SVGPLOT_H
#define BENCH_SVGPLOT_H

#include <math.h>
#include <stdio.h>

typedef enum svg_marker {
    SVG_CIRCLE,
    SVG_SQUARE,
    SVG_TRIANGLE,
    SVG_DIAMOND,
} svg_marker;

typedef struct svg_series {
    const char *label;  /* legend text */
    const char *colour; /* CSS colour, e.g. "#1b6ac9" */
    svg_marker marker;
    int joined;      /* non-zero: a line through the points in order */
    int n;           /* points */
    const double *x; /* (n) > 0 */
    const double *y; /* (n) > 0 */
} svg_series;

typedef struct svg_panel {
    const char *title;
    const char *xlabel, *ylabel;
    int diagonal; /* non-zero: draw y = x over the panel's common range */
    int nseries;
    const svg_series *series; /* (nseries) */
} svg_panel;

/* panel geometry (px): plot area plus margins for tick labels, axis labels and the legend */
#define SVG_PANEL_W 500.0
#define SVG_PANEL_H 330.0
#define SVG_LEFT 64.0
#define SVG_RIGHT 180.0
#define SVG_TOP 28.0
#define SVG_BOTTOM 46.0

static inline int svg_usable(double x, double y)
{
    return isfinite(x) && isfinite(y) && x > 0 && y > 0;
}

/* one marker of the given shape centred on (cx, cy) */
static inline void svg_marker_at(FILE *f, svg_marker m, double cx, double cy, const char *colour)
{
    const double r = 3.5;
    switch (m) {
    case SVG_CIRCLE:
        fprintf(f, "<circle cx='%.1f' cy='%.1f' r='%.1f' fill='%s'/>", cx, cy, r, colour);
        break;
    case SVG_SQUARE:
        fprintf(f, "<rect x='%.1f' y='%.1f' width='%.1f' height='%.1f' fill='%s'/>", cx - r, cy - r,
                2 * r, 2 * r, colour);
        break;
    case SVG_TRIANGLE:
        fprintf(f, "<polygon points='%.1f,%.1f %.1f,%.1f %.1f,%.1f' fill='%s'/>", cx, cy - 1.2 * r,
                cx - 1.1 * r, cy + 0.8 * r, cx + 1.1 * r, cy + 0.8 * r, colour);
        break;
    case SVG_DIAMOND:
        fprintf(f,
                "<polygon points='%.1f,%.1f %.1f,%.1f %.1f,%.1f %.1f,%.1f' fill='none' "
                "stroke='%s' stroke-width='1.5'/>",
                cx, cy - 1.3 * r, cx + 1.3 * r, cy, cx, cy + 1.3 * r, cx - 1.3 * r, cy, colour);
        break;
    }
}

/* writes one panel with its top-left corner at (ox, oy) */
static inline void svg_panel_write(FILE *f, const svg_panel *p, double ox, double oy)
{
    /* the data's range in decades */
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (int s = 0; s < p->nseries; s++) {
        const svg_series *se = &p->series[s];
        for (int i = 0; i < se->n; i++) {
            if (!svg_usable(se->x[i], se->y[i])) continue;
            double lx = log10(se->x[i]), ly = log10(se->y[i]);
            x0 = fmin(x0, lx), x1 = fmax(x1, lx), y0 = fmin(y0, ly), y1 = fmax(y1, ly);
        }
    }
    if (!(x0 <= x1)) x0 = 0, x1 = 1, y0 = 0, y1 = 1; /* nothing to show */
    x0 = floor(x0), x1 = ceil(x1), y0 = floor(y0), y1 = ceil(y1);
    if (x1 == x0) x1 = x0 + 1;
    if (y1 == y0) y1 = y0 + 1;
    if (p->diagonal) { /* one range for both, so y = x is the 45-degree diagonal */
        double lo = fmin(x0, y0), hi = fmax(x1, y1);
        x0 = y0 = lo, x1 = y1 = hi;
    }
    const double pw = SVG_PANEL_W - SVG_LEFT - SVG_RIGHT, ph = SVG_PANEL_H - SVG_TOP - SVG_BOTTOM;
    const double left = ox + SVG_LEFT, top = oy + SVG_TOP;
#define SVG_PX(lx) (left + ((lx)-x0) / (x1 - x0) * pw)
#define SVG_PY(ly) (top + (y1 - (ly)) / (y1 - y0) * ph)

    /* decade grid and labels, every other label when crowded */
    int xstep = x1 - x0 > 8 ? 2 : 1, ystep = y1 - y0 > 8 ? 2 : 1;
    for (double x = x0; x <= x1; x++) {
        fprintf(f, "<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='#ddd'/>\n", SVG_PX(x),
                top, SVG_PX(x), top + ph);
        if ((int)(x - x0) % xstep == 0)
            fprintf(f, "<text x='%.1f' y='%.1f' text-anchor='middle'>1e%g</text>\n", SVG_PX(x),
                    top + ph + 15, x);
    }
    for (double y = y0; y <= y1; y++) {
        fprintf(f, "<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='#ddd'/>\n", left,
                SVG_PY(y), left + pw, SVG_PY(y));
        if ((int)(y - y0) % ystep == 0)
            fprintf(f, "<text x='%.1f' y='%.1f' text-anchor='end'>1e%g</text>\n", left - 5,
                    SVG_PY(y) + 4, y);
    }
    fprintf(f,
            "<rect x='%.1f' y='%.1f' width='%.1f' height='%.1f' fill='none' stroke='#888'/>\n"
            "<text x='%.1f' y='%.1f' text-anchor='middle' font-weight='bold'>%s</text>\n"
            "<text x='%.1f' y='%.1f' text-anchor='middle'>%s</text>\n"
            "<text transform='translate(%.1f,%.1f) rotate(-90)' text-anchor='middle'>%s</text>\n",
            left, top, pw, ph, left + pw / 2, oy + 17, p->title, left + pw / 2, top + ph + 34,
            p->xlabel, ox + 14, top + ph / 2, p->ylabel);
    if (p->diagonal) /* the line, and its legend entry below the series' */
        fprintf(f,
                "<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='#555' "
                "stroke-dasharray='5,4'/>\n"
                "<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='#555' "
                "stroke-dasharray='5,4'/><text x='%.1f' y='%.1f'>y = x</text>\n",
                SVG_PX(x0), SVG_PY(x0), SVG_PX(x1), SVG_PY(x1), left + pw + 12,
                top + 10 + 18 * p->nseries, left + pw + 34, top + 10 + 18 * p->nseries,
                left + pw + 40, top + 14 + 18 * p->nseries);

    /* the series, then the legend */
    for (int s = 0; s < p->nseries; s++) {
        const svg_series *se = &p->series[s];
        if (se->joined) {
            fprintf(f, "<polyline fill='none' stroke='%s' stroke-width='1.8' points='", se->colour);
            for (int i = 0; i < se->n; i++)
                if (svg_usable(se->x[i], se->y[i]))
                    fprintf(f, "%.1f,%.1f ", SVG_PX(log10(se->x[i])), SVG_PY(log10(se->y[i])));
            fprintf(f, "'/>\n");
        }
        for (int i = 0; i < se->n; i++)
            if (svg_usable(se->x[i], se->y[i]))
                svg_marker_at(f, se->marker, SVG_PX(log10(se->x[i])), SVG_PY(log10(se->y[i])),
                              se->colour);
        fprintf(f, "\n");
        double ly = top + 10 + 18 * s, lx = left + pw + 12;
        if (se->joined)
            fprintf(f,
                    "<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='%s' "
                    "stroke-width='1.8'/>",
                    lx, ly, lx + 22, ly, se->colour);
        svg_marker_at(f, se->marker, lx + 11, ly, se->colour);
        fprintf(f, "<text x='%.1f' y='%.1f'>%s</text>\n", lx + 28, ly + 4, se->label);
    }
#undef SVG_PX
#undef SVG_PY
}

/* Writes the panels on a grid of cols columns to path. Returns 0, or -1 (with perror) when the
 * file cannot be written. */
static inline int svg_write_figure(const char *path, int cols, int npanels, const svg_panel *p)
{
    FILE *f = fopen(path, "w");
    if (!f) {
        perror(path);
        return -1;
    }
    int rows = (npanels + cols - 1) / cols;
    fprintf(f,
            "<svg xmlns='http://www.w3.org/2000/svg' width='%g' height='%g' "
            "font-family='sans-serif' font-size='11'>\n"
            "<rect width='100%%' height='100%%' fill='white'/>\n",
            cols * SVG_PANEL_W, rows * SVG_PANEL_H);
    for (int k = 0; k < npanels; k++)
        svg_panel_write(f, &p[k], (k % cols) * SVG_PANEL_W, (k / cols) * SVG_PANEL_H);
    fprintf(f, "</svg>\n");
    if (fclose(f) != 0) {
        perror(path);
        return -1;
    }
    return 0;
}

#endif
