/* The plan figure. Height runs up the page in both panels, as in the paper's
   Fig. 1b-c: left the metric profile phi(z), right the thickness of the layer at
   each height, coloured red (tmin) to blue (tmax) like the paper's colour scale.
   Both panels are reduced to at most one step per pixel row, so the file stays
   small for any number of bins or layers. */
#include "svg.h"
#include "report.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum {
    WIDTH = 760, HEIGHT = 660,
    TOP = 100, BOTTOM = 600,      /* plot area rows; z = 0 at BOTTOM */
    PROFILE_X0 = 80, PROFILE_X1 = 440,
    PLAN_X0 = 490, PLAN_X1 = 730
};

static const char *const INK = "#222", *const GRID = "#e4e4e4", *const MUTED = "#666";

typedef struct axis { double lo, hi, p0, p1; } axis; /* value lo..hi onto pixel p0..p1 */

static double px(const axis *a, double v)
{
    return a->p0 + (v - a->lo) / (a->hi - a->lo) * (a->p1 - a->p0);
}

double svg_nice_step(double range, int count)
{
    double raw = range / count, mag = pow(10, floor(log10(raw))), f = raw / mag;
    return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * mag;
}

void xml_text(FILE *f, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '&': fputs("&amp;", f); break;
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '"': fputs("&quot;", f); break;
        default:
            /* XML 1.0 forbids most control characters even as references */
            fputc((unsigned char)*s < 0x20 ? '?' : *s, f);
        }
    }
}

/* u = 0 red .. 1 blue through yellow, green and cyan (HSV hue 0..240 degrees). */
static void hue_colour(double u, char out[8])
{
    double h = 4 * (u < 0 ? 0 : u > 1 ? 1 : u), s = 0.8, v = 0.92;
    int sector = h >= 4 ? 3 : (int)h;
    double frac = h - sector, p = v * (1 - s), q = v * (1 - s * frac), t = v * (1 - s * (1 - frac));
    double r, g, b;
    switch (sector) {
    case 0: r = v; g = t; b = p; break;
    case 1: r = q; g = v; b = p; break;
    case 2: r = p; g = v; b = t; break;
    default: r = p; g = q; b = v; break;
    }
    snprintf(out, 8, "#%02x%02x%02x", (int)(r * 255 + 0.5), (int)(g * 255 + 0.5), (int)(b * 255 + 0.5));
}

static void thickness_colour(const adaslice_plan *plan, uint32_t bins, char out[8])
{
    uint32_t span = plan->bins_max - plan->bins_min;
    /* a uniform plan's top layer may be thinner than tmin */
    hue_colour(span ? ((double)bins - plan->bins_min) / span : 1, out);
}

/* Frame, grid and ticks of a panel; the value axis is horizontal. */
static void panel(FILE *f, const axis *x, double step, const char *label)
{
    int i;
    for (i = 0; i * step <= x->hi * (1 + 1e-9); i++) {
        double v = i * step, p = px(x, v);
        fprintf(f, "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"%s\"/>\n", p, TOP, p, BOTTOM, GRID);
        fprintf(f, "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"%s\"/>\n", p, BOTTOM, p, BOTTOM + 5, INK);
        fprintf(f, "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%g</text>\n", p, BOTTOM + 18, v);
    }
    fprintf(f, "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">", (x->p0 + x->p1) / 2, BOTTOM + 42);
    xml_text(f, label);
    fputs("</text>\n", f);
}

static void frame(FILE *f, const axis *x)
{
    fprintf(f, "<rect x=\"%.1f\" y=\"%d\" width=\"%.1f\" height=\"%d\" fill=\"none\" stroke=\"%s\"/>\n",
            x->p0, TOP, x->p1 - x->p0, BOTTOM - TOP, INK);
}

/* z grid across both panels, ticks and labels on the left one. */
static void z_axis(FILE *f, const axis *z)
{
    double step = svg_nice_step(z->hi, 8);
    int i;
    for (i = 0; i * step <= z->hi * (1 + 1e-9); i++) {
        double v = i * step, p = px(z, v);
        fprintf(f, "<path d=\"M%d %.1fH%dM%d %.1fH%d\" stroke=\"%s\"/>\n",
                PROFILE_X0, p, PROFILE_X1, PLAN_X0, p, PLAN_X1, GRID);
        fprintf(f, "<line x1=\"%d\" y1=\"%.1f\" x2=\"%d\" y2=\"%.1f\" stroke=\"%s\"/>\n",
                PROFILE_X0 - 5, p, PROFILE_X0, p, INK);
        fprintf(f, "<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">%g</text>\n", PROFILE_X0 - 8, p + 4, v);
    }
    fprintf(f, "<text transform=\"translate(%d %d) rotate(-90)\" text-anchor=\"middle\">z (mm)</text>\n",
            PROFILE_X0 - 52, (TOP + BOTTOM) / 2);
}

enum { ROWS = BOTTOM - TOP };

/* Bins [row_start(r), row_start(r + 1)) are drawn in pixel row r of `rows`. */
static size_t row_start(size_t r, size_t bins, size_t rows)
{
    return (size_t)((unsigned long long)r * bins / rows);
}

/* The profile reduced to at most one value per pixel row: the largest phi of
   the bins the row covers, so that no peak disappears. Returns the row count. */
static size_t row_maxima(const adaslice_profile *pr, double top[ROWS])
{
    size_t n = pr->bin_count, rows = n < ROWS ? n : ROWS, r, i;
    for (r = 0; r < rows; r++) {
        top[r] = 0;
        for (i = row_start(r, n, rows); i < row_start(r + 1, n, rows); i++)
            if (pr->phi[i] > top[r]) top[r] = pr->phi[i];
    }
    return rows;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The largest value the phi axis shows. Where A(z) -> 0 at tips the area metric
   spikes far above the rest of the profile, and an axis up to the spike would
   flatten everything else; so a few rows that tower over the 98th percentile
   are cut at the axis (*cut says how high they went; 0 if nothing is cut). */
static double phi_limit(const double *top, size_t rows, double *cut)
{
    double sorted[ROWS], q;
    memcpy(sorted, top, rows * sizeof *top);
    qsort(sorted, rows, sizeof *sorted, compare_doubles);
    q = sorted[(size_t)(0.98 * (rows - 1))];
    *cut = q > 0 && sorted[rows - 1] > 4 * q ? sorted[rows - 1] : 0;
    return *cut ? 1.5 * q : sorted[rows - 1] > 0 ? sorted[rows - 1] : 1;
}

static void profile_curve(FILE *f, const adaslice_profile *pr, const double *top, size_t rows,
                          const axis *x, const axis *z)
{
    size_t r;
    fprintf(f, "<path fill=\"#c6dbef\" stroke=\"#08519c\" d=\"M%.1f %.1f", px(x, 0), px(z, 0));
    for (r = 0; r < rows; r++)
        fprintf(f, "H%.1fV%.1f", px(x, top[r] < x->hi ? top[r] : x->hi),
                px(z, (double)row_start(r + 1, pr->bin_count, rows) * pr->bin));
    fprintf(f, "H%.1fZ\"/>\n", px(x, 0));
}

static uint32_t layer_bins(const adaslice_plan *p, size_t k)
{
    return p->planes[k + 1] - p->planes[k];
}

typedef struct run { size_t first, end; uint32_t bins; } run;

/* Layers [first, end) drawn as one step: a run grows until it is a pixel tall
   and the next layer's thickness differs, and shows its thinnest layer. */
static int next_run(const adaslice_plan *p, const axis *z, double b, run *r)
{
    size_t k = r->end;
    if (k >= p->layer_count) return 0;
    r->first = k;
    r->bins = layer_bins(p, k);
    for (k++; k < p->layer_count; k++) {
        uint32_t t = layer_bins(p, k);
        if (t != r->bins && px(z, p->planes[r->first] * b) - px(z, p->planes[k] * b) >= 1) break;
        if (t < r->bins) r->bins = t;
    }
    r->end = k;
    return 1;
}

static void plan_steps(FILE *f, const adaslice_plan *p, double b, const axis *x, const axis *z)
{
    run r;
    char colour[8];
    size_t k;
    r.end = 0;
    while (next_run(p, z, b, &r)) {
        double y0 = px(z, p->planes[r.end] * b), y1 = px(z, p->planes[r.first] * b);
        thickness_colour(p, r.bins, colour);
        fprintf(f, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"%s\"/>\n",
                px(x, 0), y0, px(x, r.bins * b) - px(x, 0), y1 - y0, colour);
    }
    /* planes between layers tall enough to tell apart show as slices */
    fputs("<path stroke=\"#fff\" stroke-width=\"0.6\" stroke-opacity=\"0.85\" d=\"", f);
    for (k = 1; k < p->layer_count; k++) {
        double below = px(z, p->planes[k - 1] * b), at = px(z, p->planes[k] * b), above = px(z, p->planes[k + 1] * b);
        uint32_t t = layer_bins(p, k - 1) > layer_bins(p, k) ? layer_bins(p, k - 1) : layer_bins(p, k);
        if (below - at >= 3 && at - above >= 3) fprintf(f, "M%.1f %.1fH%.1f", px(x, 0), at, px(x, t * b));
    }
    fputs("\"/>\n", f);
    fprintf(f, "<path fill=\"none\" stroke=\"%s\" d=\"M%.1f %.1f", INK, px(x, 0), px(z, 0));
    r.end = 0;
    while (next_run(p, z, b, &r))
        fprintf(f, "H%.1fV%.1f", px(x, r.bins * b), px(z, p->planes[r.end] * b));
    fputs("\"/>\n", f);
}

/* The colour scale sits above the plan panel, aligned with its thickness axis. */
static void colour_scale(FILE *f, const adaslice_plan *p, double b, const axis *x)
{
    double x0 = px(x, p->bins_min * b), x1 = px(x, p->bins_max * b);
    char colour[8];
    int i;
    fputs("<defs><linearGradient id=\"thickness\" x1=\"0\" x2=\"1\" y1=\"0\" y2=\"0\">", f);
    for (i = 0; i <= 4; i++) {
        hue_colour(i / 4.0, colour);
        fprintf(f, "<stop offset=\"%g\" stop-color=\"%s\"/>", i / 4.0, colour);
    }
    fputs("</linearGradient></defs>\n", f);
    fprintf(f, "<rect x=\"%.1f\" y=\"%d\" width=\"%.1f\" height=\"8\" fill=\"url(#thickness)\" stroke=\"%s\" stroke-width=\"0.5\"/>\n",
            x0, TOP - 14, x1 - x0 > 1 ? x1 - x0 : 1, INK);
    fprintf(f, "<path d=\"M%.1f %dV%dM%.1f %dV%d\" stroke=\"%s\" stroke-dasharray=\"4 3\"/>\n",
            x0, TOP - 6, BOTTOM, x1, TOP - 6, BOTTOM, MUTED);
    fprintf(f, "<text x=\"%.1f\" y=\"%d\" text-anchor=\"end\" font-size=\"10\" fill=\"%s\">t<tspan baseline-shift=\"sub\" font-size=\"8\">min</tspan></text>\n",
            x0 - 4, TOP - 7, MUTED);
    fprintf(f, "<text x=\"%.1f\" y=\"%d\" font-size=\"10\" fill=\"%s\">t<tspan baseline-shift=\"sub\" font-size=\"8\">max</tspan></text>\n",
            x1 + 4, TOP - 7, MUTED);
}

static void caption(FILE *f, int x, const char *text)
{
    fprintf(f, "<text x=\"%d\" y=\"%d\" font-weight=\"bold\">", x, TOP - 30);
    xml_text(f, text);
    fputs("</text>\n", f);
}

void svg_write_plan(FILE *f, const svg_plan_figure *fig)
{
    const adaslice_profile *pr = fig->profile;
    const adaslice_plan *p = fig->plan;
    double b = pr->bin, top[ROWS], cut, step;
    size_t rows = row_maxima(pr, top);
    double phi_max = phi_limit(top, rows, &cut);
    axis z, xphi, xt;

    z.lo = 0; z.hi = pr->bin_count * b; z.p0 = BOTTOM; z.p1 = TOP;
    step = svg_nice_step(phi_max, 4);
    xphi.lo = 0; xphi.hi = ceil(phi_max / step * (1 - 1e-9)) * step; xphi.p0 = PROFILE_X0; xphi.p1 = PROFILE_X1;
    xt.lo = 0; xt.hi = p->bins_max * b * 1.15; xt.p0 = PLAN_X0; xt.p1 = PLAN_X1;

    fputs("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n", f);
    fprintf(f, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\" "
               "font-family=\"Helvetica, Arial, sans-serif\" font-size=\"12\" fill=\"%s\">\n",
            WIDTH, HEIGHT, WIDTH, HEIGHT, INK);
    fprintf(f, "<rect width=\"%d\" height=\"%d\" fill=\"#fff\"/>\n", WIDTH, HEIGHT);

    fprintf(f, "<text x=\"%d\" y=\"26\" font-size=\"16\" font-weight=\"bold\">", PROFILE_X0 - 52);
    xml_text(f, fig->model);
    fputs(" &#8212; ", f);
    xml_text(f, fig->method);
    fprintf(f, " plan, K = %zu layer%s, &#949; = %g", p->layer_count, plural(p->layer_count), p->eps);
    if (*fig->eps_unit) fprintf(f, " %s", fig->eps_unit);
    fputs("</text>\n", f);
    fprintf(f, "<text x=\"%d\" y=\"46\" fill=\"%s\">", PROFILE_X0 - 52, MUTED);
    xml_text(f, fig->metric);
    fprintf(f, " &#183; bin %g mm, N = %zu &#183; t &#8712; [%g, %g] mm &#183; worst layer error %.4g",
            b, pr->bin_count, p->bins_min * b, p->bins_max * b, p->worst_error);
    if (*fig->eps_unit) fprintf(f, " %s", fig->eps_unit);
    fputs("</text>\n", f);

    caption(f, PROFILE_X0, "metric profile");
    caption(f, PLAN_X0, "slicing plan");
    z_axis(f, &z);
    panel(f, &xphi, step, fig->phi_axis);
    panel(f, &xt, svg_nice_step(xt.hi, 4), "layer thickness (mm)");
    profile_curve(f, pr, top, rows, &xphi, &z);
    if (cut)
        fprintf(f, "<text x=\"%d\" y=\"%d\" text-anchor=\"end\" font-size=\"10\" fill=\"%s\">"
                   "peaks up to %.4g cut at the axis</text>\n", PROFILE_X1, TOP - 8, MUTED, cut);
    plan_steps(f, p, b, &xt, &z);
    colour_scale(f, p, b, &xt);
    frame(f, &xphi);
    frame(f, &xt);
    fputs("</svg>\n", f);
}
