/* The FDM time model: see fdm.h. */
#include "fdm.h"
#include "report.h"

#include <math.h>
#include <stdlib.h>

/* The area of every face seen from above or below: the skins' footprints. */
static double footprints(const adaslice_mesh *m)
{
    double sum = 0;
    size_t t;
    for (t = 0; t < m->triangle_count; t++) {
        const float *a = m->vertices + 3 * (size_t)m->triangles[3 * t], *b = m->vertices + 3 * (size_t)m->triangles[3 * t + 1],
                    *c = m->vertices + 3 * (size_t)m->triangles[3 * t + 2];
        sum += fabs(((double)b[0] - a[0]) * ((double)c[1] - a[1]) - ((double)c[0] - a[0]) * ((double)b[1] - a[1])) / 2;
    }
    return sum;
}

/* Each layer's section at its middle, where the slicers cut it. */
int fdm_plan_seconds(const adaslice_mesh *mesh, double z0, const adaslice_plan *p, double *seconds)
{
    adaslice_contours c;
    adaslice_error err;
    double *z = (double *)malloc((p->layer_count ? p->layer_count : 1) * sizeof *z), total = 0;
    size_t k, g, i;
    if (!z) return complain(RC_FAIL, "out of memory for %zu layers", p->layer_count);
    for (k = 0; k < p->layer_count; k++) z[k] = z0 + (p->layers[k].z_bottom + p->layers[k].z_top) / 2;
    if (adaslice_contours_slice(mesh, z, p->layer_count, NULL, &c, &err) != ADASLICE_OK) {
        free(z);
        return library_error(&err);
    }
    free(z);
    for (k = 0; k < p->layer_count; k++) {
        double length = 0, area = 0;
        for (g = c.first_polygon[k]; g < c.first_polygon[k + 1]; g++) {
            const adaslice_polygon *pg = &c.polygons[g];
            for (i = 0; i < pg->count; i++) {
                const double *a = c.points + 2 * (pg->first + i);
                const double *b = c.points + 2 * (pg->first + (i + 1 < pg->count ? i + 1 : 0));
                if (i + 1 == pg->count && !pg->closed) break;
                length += hypot(b[0] - a[0], b[1] - a[1]);
                area += (a[0] * b[1] - b[0] * a[1]) / 2;
            }
        }
        total += FDM_WALLS * length / FDM_WALL_SPEED + FDM_INFILL * fabs(area) / (FDM_WIDTH * FDM_INFILL_SPEED) +
                 FDM_LAYER_CHANGE_S;
    }
    adaslice_contours_free(&c);
    *seconds = total + FDM_SKIN_LAYERS * footprints(mesh) / (FDM_WIDTH * FDM_SKIN_SPEED);
    return RC_OK;
}
