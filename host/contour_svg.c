/* Cross-sections as SVG. Coordinates go out with 4 decimals (0.1 um), far
   below any printer's pixel, which keeps files of many layers small. */
#include "contour_svg.h"

/* The polygons of height i that are loops (closed = 1) or polylines (0) as
   one path's data, y negated; loops end in Z. */
static void write_path(FILE *f, const adaslice_contours *c, size_t i, int closed)
{
    size_t p, k;
    for (p = c->first_polygon[i]; p < c->first_polygon[i + 1]; p++) {
        const adaslice_polygon *poly = c->polygons + p;
        const double *pt = c->points + 2 * poly->first;
        if (poly->closed != closed) continue;
        for (k = 0; k < poly->count; k++)
            fprintf(f, "%s%.4f %.4f", k ? " L" : " M", pt[2 * k], 0.0 - pt[2 * k + 1]); /* never "-0" */
        if (closed) fputs(" Z", f);
    }
}

void svg_write_contours(FILE *f, const adaslice_contours *c, size_t first, size_t count)
{
    double lo[2] = {0, 0}, hi[2] = {0, 0};
    size_t i, p, k, seen = 0, open;
    if (first > c->height_count) first = c->height_count;
    if (count > c->height_count - first) count = c->height_count - first;
    for (i = first; i < first + count; i++)
        for (p = c->first_polygon[i]; p < c->first_polygon[i + 1]; p++)
            for (k = 0; k < c->polygons[p].count; k++, seen++) {
                const double *pt = c->points + 2 * (c->polygons[p].first + k);
                int a;
                for (a = 0; a < 2; a++) {
                    if (!seen || pt[a] < lo[a]) lo[a] = pt[a];
                    if (!seen || pt[a] > hi[a]) hi[a] = pt[a];
                }
            }
    lo[0] -= 1; lo[1] -= 1; hi[0] += 1; hi[1] += 1;
    fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
               "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.4fmm\" height=\"%.4fmm\" "
               "viewBox=\"%.4f %.4f %.4f %.4f\">\n",
            hi[0] - lo[0], hi[1] - lo[1], lo[0], -hi[1], hi[0] - lo[0], hi[1] - lo[1]);
    /* a hairline at 800 pixels across (renderers disagree on non-scaling strokes) */
    fprintf(f, "<g fill=\"#3a6fb0\" fill-opacity=\"%.2f\" stroke=\"#14345c\" stroke-width=\"%.4f\">\n",
            count > 1 ? 0.35 : 1.0, (hi[0] - lo[0] > hi[1] - lo[1] ? hi[0] - lo[0] : hi[1] - lo[1]) / 800);
    for (i = first; i < first + count; i++) {
        fprintf(f, "<g id=\"z%zu\" data-z=\"%.6f\">\n<path fill-rule=\"nonzero\" d=\"", i, c->heights[i]);
        write_path(f, c, i, 1);
        fputs("\"/>\n", f);
        for (open = 0, p = c->first_polygon[i]; p < c->first_polygon[i + 1]; p++) open += !c->polygons[p].closed;
        if (open) {
            fputs("<path fill=\"none\" stroke=\"#c0392b\" d=\"", f);
            write_path(f, c, i, 0);
            fputs("\"/>\n", f);
        }
        fputs("</g>\n", f);
    }
    fputs("</g>\n</svg>\n", f);
}
