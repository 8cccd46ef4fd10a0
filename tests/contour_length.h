/* The length of a height's contours, the closing edge of each polygon (the
   chord of an open one) included: the tests' bound on pixels a mask may
   differ by along a section's edge. */
#ifndef ADASLICE_CONTOUR_LENGTH_H
#define ADASLICE_CONTOUR_LENGTH_H
#include <math.h>
#include "../adaslice.h"

static inline double contour_length(const adaslice_contours *c, size_t height_index)
{
    double length = 0;
    size_t p, q;
    for (p = c->first_polygon[height_index]; p < c->first_polygon[height_index + 1]; p++) {
        const adaslice_polygon *poly = &c->polygons[p];
        for (q = 0; q < poly->count; q++) {
            const double *u = c->points + 2 * (poly->first + q), *v = c->points + 2 * (poly->first + (q + 1) % poly->count);
            length += hypot(v[0] - u[0], v[1] - u[1]);
        }
    }
    return length;
}
#endif
