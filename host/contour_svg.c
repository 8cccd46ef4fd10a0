/* Cross-sections as SVG. Coordinates go out with 4 decimals (0.1 um), far
   below any printer's pixel, which keeps files of many layers small. Heights
   go out as the manifest's, above the part's bottom, so that a layer's SVG,
   PNG and manifest entry say the same. */
#include "contour_svg.h"
#include "svg.h"

#include <string.h>

static const char *const FILL = "#3a6fb0", *const STROKE = "#14345c", *const OPEN = "#c0392b", *const INK = "#222";

/* The polygons of height i as one path's data, y negated. With `region`,
   the area the masks light: every loop, and the polylines joined by their
   chords into the cycles the library lays out one after another (a cycle
   ends where `next` does not go on to the following polygon); else the
   polylines alone, as open lines. */
static void write_path(FILE *f, const adaslice_contours *c, size_t i, int region)
{
    size_t p, k;
    int drawing = 0; /* inside a cycle of polylines */
    for (p = c->first_polygon[i]; p < c->first_polygon[i + 1]; p++) {
        const adaslice_polygon *poly = c->polygons + p;
        const double *pt = c->points + 2 * poly->first;
        if (!region && poly->closed) continue;
        for (k = 0; k < poly->count; k++)
            fprintf(f, "%s%.4f %.4f", k || drawing ? " L" : " M", pt[2 * k], 0.0 - pt[2 * k + 1]); /* never "-0" */
        drawing = region && !poly->closed && poly->next == p + 1;
        if (region && !drawing) fputs(" Z", f);
    }
}

/* One line of text in the caption band, its baseline at y. */
static void caption_line(FILE *f, double x, double y, double em, const char *weight, const char *text)
{
    fprintf(f, "<text x=\"%.4f\" y=\"%.4f\" font-size=\"%.4f\"%s>", x, y, em, weight);
    xml_text(f, text);
    fputs("</text>\n", f);
}

void svg_write_contours(FILE *f, const adaslice_contours *c, size_t i, const contour_layer *layer)
{
    double lo[2] = {0, 0}, hi[2] = {0, 0}, em, band, width, top, x, bar, line[4], scale_row;
    size_t p, k, seen = 0, open = 0;
    char text[3][160];
    int n;
    for (p = c->first_polygon[i]; p < c->first_polygon[i + 1]; p++) {
        open += !c->polygons[p].closed;
        for (k = 0; k < c->polygons[p].count; k++, seen++) {
            const double *pt = c->points + 2 * (c->polygons[p].first + k);
            int a;
            for (a = 0; a < 2; a++) {
                if (!seen || pt[a] < lo[a]) lo[a] = pt[a];
                if (!seen || pt[a] > hi[a]) hi[a] = pt[a];
            }
        }
    }
    lo[0] -= 1; lo[1] -= 1; hi[0] += 1; hi[1] += 1;

    snprintf(text[0], sizeof text[0], "%s: layer %zu of %zu", layer->model, layer->number, layer->count);
    snprintf(text[1], sizeof text[1], "%.7g to %.7g mm above the part's bottom", layer->z_bottom, layer->z_top);
    snprintf(text[2], sizeof text[2], "%.7g mm thick, the contours cut at %.7g mm", layer->thickness, layer->cut);
    /* text stays readable when a viewer fits a big part to its window: at
       least 3 mm, else 1/40 of the part; the band is wide enough for the
       longest line at about 0.6 em a character */
    em = hi[0] - lo[0] > hi[1] - lo[1] ? hi[0] - lo[0] : hi[1] - lo[1];
    em = em / 40 > 3 ? em / 40 : 3;
    for (width = 0, n = 0; n < 3; n++)
        if (0.6 * em * (double)strlen(text[n]) > width) width = 0.6 * em * (double)strlen(text[n]);
    if (width < 24 * em) width = 24 * em;
    if (width < hi[0] - lo[0]) width = hi[0] - lo[0];
    for (n = 0; n < 4; n++) line[n] = (1.2 + 1.3 * n) * em; /* baselines below the band's top */
    scale_row = line[3] + (open ? 2 : 1) * 1.3 * em;          /* the legend's last row */
    band = scale_row + 0.6 * em;
    top = -hi[1] - band;

    fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
               "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.4fmm\" height=\"%.4fmm\" "
               "viewBox=\"%.4f %.4f %.4f %.4f\" font-family=\"Helvetica, Arial, sans-serif\" fill=\"%s\">\n",
            width, hi[1] - lo[1] + band, lo[0], top, width, hi[1] - lo[1] + band, INK);
    fputs("<title>", f);
    xml_text(f, text[0]);
    fputs(": ", f);
    xml_text(f, text[1]);
    fprintf(f, ", %.7g mm thick</title>\n", layer->thickness);

    x = lo[0];
    caption_line(f, x, top + line[0], 1.1 * em, " font-weight=\"bold\"", text[0]);
    caption_line(f, x, top + line[1], em, "", text[1]);
    caption_line(f, x, top + line[2], em, "", text[2]);
    /* the legend: the fill, the open polylines (only when there are any), the scale */
    fprintf(f, "<rect x=\"%.4f\" y=\"%.4f\" width=\"%.4f\" height=\"%.4f\" fill=\"%s\" stroke=\"%s\" "
               "stroke-width=\"%.4f\"/>\n", x, top + line[3] - 0.75 * em, 1.6 * em, 0.8 * em, FILL, STROKE, em / 20);
    caption_line(f, x + 2.1 * em, top + line[3], em, "", "inside the part: what cures");
    if (open) {
        double y = top + line[3] + 1.3 * em;
        fprintf(f, "<path d=\"M%.4f %.4fH%.4f\" stroke=\"%s\" stroke-width=\"%.4f\"/>\n", x, y - 0.35 * em,
                x + 1.6 * em, OPEN, em / 8);
        caption_line(f, x + 2.1 * em, y, em, "", "open contour: the mesh has a hole here (filled to its chord)");
    }
    {
        double y = top + scale_row - 0.35 * em;
        char label[32];
        bar = svg_nice_step(hi[0] - lo[0], 4);
        fprintf(f, "<path d=\"M%.4f %.4fv%.4fH%.4fv%.4f\" fill=\"none\" stroke=\"%s\" stroke-width=\"%.4f\"/>\n", x,
                y - 0.3 * em, 0.3 * em, x + bar, -0.3 * em, INK, em / 12);
        snprintf(label, sizeof label, "%g mm", bar);
        caption_line(f, x + bar + 0.5 * em, y + 0.35 * em, em, "", label);
    }

    /* a hairline at 800 pixels across (renderers disagree on non-scaling strokes) */
    fprintf(f, "<g id=\"layer-%zu\" data-layer=\"%zu\" data-z-bottom=\"%.9g\" data-z-top=\"%.9g\" data-thickness=\"%.9g\" "
               "data-cut=\"%.9g\" fill=\"%s\" stroke=\"%s\" stroke-width=\"%.4f\">\n<path fill-rule=\"nonzero\" d=\"",
            layer->number, layer->number, layer->z_bottom, layer->z_top, layer->thickness, layer->cut, FILL, STROKE,
            (hi[0] - lo[0] > hi[1] - lo[1] ? hi[0] - lo[0] : hi[1] - lo[1]) / 800);
    write_path(f, c, i, 1);
    fputs("\"/>\n", f);
    if (open) {
        fprintf(f, "<path fill=\"none\" stroke=\"%s\" d=\"", OPEN);
        write_path(f, c, i, 0);
        fputs("\"/>\n", f);
    }
    fputs("</g>\n</svg>\n", f);
}
