/* An FDM print's time from its plan, for comparing plans (plan --3mf): each
   layer lays FDM_WALLS perimeters around its section and fills FDM_INFILL of
   its area with lines FDM_WIDTH apart, at FDM_SPEED, and changes layer in
   FDM_LAYER_CHANGE_S. A model of what grows with the layer count, not a
   slicer's estimate: docs/BENCHMARKS.md holds it against PrusaSlicer's. */
#ifndef ADASLICE_HOST_FDM_H
#define ADASLICE_HOST_FDM_H
#include "../adaslice.h"

#define FDM_WALLS 2
#define FDM_WIDTH 0.45           /* mm */
#define FDM_INFILL 0.25          /* 15 % sparse infill and the solid skins, as a share of the area */
#define FDM_SPEED 50.0           /* mm/s */
#define FDM_LAYER_CHANGE_S 1.0   /* s: retract, lift, travel, prime */

/* The seconds of plan p on the welded mesh whose bottom is z0; RC_OK or a
   complaint made. */
int fdm_plan_seconds(const adaslice_mesh *mesh, double z0, const adaslice_plan *p, double *seconds);
#endif
