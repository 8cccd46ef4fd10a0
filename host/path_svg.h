/* One printed path seen from the side, Z against the distance along it, for
   `adaslice contour --svg-path` (README's picture of the contour). */
#ifndef ADASLICE_HOST_PATH_SVG_H
#define ADASLICE_HOST_PATH_SVG_H
#include <stdio.h>
#include <stddef.h>

/* A line along the path: count points (s, z), mm along the path and mm of Z;
   a point with z NAN breaks the line (the mesh where contour does not follow it). */
typedef struct path_line { const double *sz; size_t count; } path_line;

typedef struct path_figure {
    const char *title;
    size_t layer;                /* from 1, as the G-code's ;Z: lines count */
    double top;                  /* the layer's ;Z: */
    double from[2], to[2];       /* the path's ends on the plate (G-code X Y) */
    path_line mesh, before, after;
} path_figure;

/* A standalone SVG of the three lines: the mesh wide and grey, before dashed
   red, after solid blue. Every polyline has data-role "mesh", "before" or
   "after"; its points are pixels, px = data-px0 + s * data-px-per-mm and
   py = data-py0 - (z - data-z0) * data-py-per-mm (attributes of the <svg>,
   with data-layer, data-z-top, data-from and data-to), so a reader can take
   them back to millimetres. Errors show in ferror(f). */
void svg_write_path(FILE *f, const path_figure *fig);
#endif
