/* The side view of a path (path_svg.h). Pixels rather than millimetres in
   the drawing: Z spans a tenth of a millimetre where the path spans several,
   so the two axes need their own scales, and strokes would stretch under a
   non-uniform transform. */
#include "path_svg.h"
#include "svg.h"

#include <math.h>

#define LEFT 60.0
#define RIGHT 700.0
#define TOP 30.0
#define BOTTOM 255.0

static void z_range(const path_line *l, double *lo, double *hi)
{
    size_t i;
    for (i = 0; i < l->count; i++) {
        double z = l->sz[2 * i + 1];
        if (isnan(z)) continue;
        if (z < *lo) *lo = z;
        if (z > *hi) *hi = z;
    }
}

/* The line's runs of numbers as polylines. */
static void polylines(FILE *f, const path_line *l, const char *role, const char *style, double kx, double z0, double ky)
{
    size_t i = 0;
    while (i < l->count) {
        size_t n = 0;
        while (i < l->count && isnan(l->sz[2 * i + 1])) i++;
        if (i == l->count) break;
        fprintf(f, "<polyline data-role=\"%s\" fill=\"none\" %s points=\"", role, style);
        for (; i < l->count && !isnan(l->sz[2 * i + 1]); i++, n++)
            fprintf(f, "%s%.3f,%.3f", n ? " " : "", LEFT + l->sz[2 * i] * kx, BOTTOM - (l->sz[2 * i + 1] - z0) * ky);
        fputs("\"/>\n", f);
    }
}

void svg_write_path(FILE *f, const path_figure *fig)
{
    double length = hypot(fig->to[0] - fig->from[0], fig->to[1] - fig->from[1]);
    double lo = HUGE_VAL, hi = -HUGE_VAL, kx, ky, step, v;
    z_range(&fig->mesh, &lo, &hi);
    z_range(&fig->before, &lo, &hi);
    z_range(&fig->after, &lo, &hi);
    if (!(lo < hi)) { lo = fig->top - 0.05; hi = fig->top + 0.05; }
    step = svg_nice_step(hi - lo, 6);
    lo = floor(lo / step) * step;
    hi = ceil(hi / step) * step;
    kx = (RIGHT - LEFT) / (length > 0 ? length : 1);
    ky = (BOTTOM - TOP) / (hi - lo);
    fprintf(f, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"720\" height=\"300\" viewBox=\"0 0 720 300\" "
               "font-family=\"sans-serif\" font-size=\"12\" data-layer=\"%zu\" data-z-top=\"%.9g\" "
               "data-from=\"%.9g %.9g\" data-to=\"%.9g %.9g\" data-px0=\"%g\" data-px-per-mm=\"%.9g\" data-z0=\"%.9g\" "
               "data-py0=\"%g\" data-py-per-mm=\"%.9g\">\n<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
            fig->layer, fig->top, fig->from[0], fig->from[1], fig->to[0], fig->to[1], LEFT, kx, lo, BOTTOM, ky);
    fputs("<text x=\"60\" y=\"18\">", f);
    xml_text(f, fig->title);
    fputs("</text>\n", f);
    step = svg_nice_step(length, 4);
    for (v = 0; v <= length + 1e-9; v += step)
        fprintf(f, "<line x1=\"%.1f\" y1=\"%g\" x2=\"%.1f\" y2=\"%g\" stroke=\"#ddd\"/><text x=\"%.1f\" y=\"270\" "
                   "text-anchor=\"middle\">%g</text>\n", LEFT + v * kx, TOP, LEFT + v * kx, BOTTOM, LEFT + v * kx, v);
    step = svg_nice_step(hi - lo, 6);
    for (v = lo; v <= hi + step / 2; v += step)
        fprintf(f, "<line x1=\"%g\" y1=\"%.1f\" x2=\"%g\" y2=\"%.1f\" stroke=\"#eee\"/><text x=\"56\" y=\"%.1f\" "
                   "text-anchor=\"end\">%.*f</text>\n", LEFT, BOTTOM - (v - lo) * ky, RIGHT, BOTTOM - (v - lo) * ky,
                BOTTOM - (v - lo) * ky + 4, step < 0.1 ? 2 : 1, v);
    fputs("<text x=\"390\" y=\"292\" text-anchor=\"middle\">mm along the path</text>\n"
          "<text x=\"14\" y=\"150\" transform=\"rotate(-90 14 150)\" text-anchor=\"middle\">Z (mm)</text>\n", f);
    polylines(f, &fig->mesh, "mesh", "stroke=\"#888\" stroke-width=\"6\" stroke-opacity=\"0.5\"", kx, lo, ky);
    polylines(f, &fig->before, "before", "stroke=\"#d33\" stroke-width=\"2\" stroke-dasharray=\"6 4\"", kx, lo, ky);
    polylines(f, &fig->after, "after", "stroke=\"#2362c0\" stroke-width=\"2\"", kx, lo, ky);
    fputs("<line x1=\"250\" y1=\"205\" x2=\"280\" y2=\"205\" stroke=\"#888\" stroke-width=\"6\"/>"
          "<text x=\"286\" y=\"209\">the mesh surface under the path</text>\n"
          "<line x1=\"250\" y1=\"221\" x2=\"280\" y2=\"221\" stroke=\"#d33\" stroke-width=\"2\" stroke-dasharray=\"6 4\"/>"
          "<text x=\"286\" y=\"225\">PrusaSlicer: the layer top, flat</text>\n"
          "<line x1=\"250\" y1=\"237\" x2=\"280\" y2=\"237\" stroke=\"#2362c0\" stroke-width=\"2\"/>"
          "<text x=\"286\" y=\"241\">adaslice contour: Z per piece</text>\n</svg>\n", f);
}
