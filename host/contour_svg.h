/* Cross-sections as SVG, for `adaslice slice --svg`. */
#ifndef ADASLICE_HOST_CONTOUR_SVG_H
#define ADASLICE_HOST_CONTOUR_SVG_H
#include <stdio.h>
#include "../adaslice.h"

/* Writes heights [first, first + count) of `c` as one standalone SVG document
   (count is clipped to the heights there are). Units are millimetres: the
   viewBox is the polygons' bounding box plus a 1 mm margin, width and height
   carry "mm", and y is flipped so that +y points up the page. One <g> per
   height (id "z<index>", data-z the height in mm) holds one path of every loop,
   filled with the nonzero rule so holes and overlaps read as the winding number
   says, and a second, unfilled path for open polylines, if any. Layers are
   translucent so a stack of them shows through. Errors show in ferror(f). */
void svg_write_contours(FILE *f, const adaslice_contours *c, size_t first, size_t count);

#endif
