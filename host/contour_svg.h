/* Cross-sections as SVG, for `adaslice slice --svg`. */
#ifndef ADASLICE_HOST_CONTOUR_SVG_H
#define ADASLICE_HOST_CONTOUR_SVG_H
#include <stdio.h>
#include "../adaslice.h"

/* The layer a cross-section belongs to, in the job's terms. */
typedef struct contour_layer {
    const char *model;          /* named in the title */
    size_t number, count;       /* layer `number` (from 1) of `count` */
    double z_bottom, z_top;     /* mm above the part's bottom, as manifest.json gives them */
    double thickness;           /* mm, as manifest.json gives it */
    double cut;                 /* the contours' height, mm above the part's bottom */
} contour_layer;

/* Writes the contours of height i of `c` as one standalone SVG document of
   the layer. Units are millimetres: width and height carry "mm" (1:1 at 100 %),
   the viewBox is the polygons' bounding box plus a 1 mm margin and a caption
   band above them, and y is flipped so that +y points up the page. The caption
   (and <title>) name the layer, its heights and thickness; a legend says what
   the fill and the red strokes mean, with a scale bar. The layer's <g>
   (id "layer-N") carries data-layer, data-z-bottom, data-z-top, data-thickness
   and data-cut; it holds one path of what the layer's mask lights: every
   loop, and the open polylines of a mesh with holes closed by the chords the
   masks close them with (adaslice_polygon.next), filled with the nonzero rule
   so holes and overlaps read as the winding number says (the masks light
   where it is positive: the same wherever no shell is wound inside out), and
   a second, unfilled red path of the open polylines, if any. Errors show in
   ferror(f). */
void svg_write_contours(FILE *f, const adaslice_contours *c, size_t i, const contour_layer *layer);

#endif
