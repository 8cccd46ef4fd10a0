/* An FDM print's time from its plan, for comparing plans (plan --3mf), with
   PrusaSlicer's default print settings: each layer lays FDM_WALLS perimeters
   around its section at FDM_WALL_SPEED (60 mm/s inside, 30 outside) and fills
   FDM_INFILL of its area with lines FDM_WIDTH apart at FDM_INFILL_SPEED, and
   changes layer in FDM_LAYER_CHANGE_S; the solid skins, FDM_SKIN_LAYERS over
   every upward and under every downward face's footprint, cost the same
   whatever the plan (a layer's exposed band widens as it thickens) at
   FDM_SKIN_SPEED. A model of what the plan changes, not a slicer's
   estimate: docs/BENCHMARKS.md holds it against PrusaSlicer's. */
#ifndef ADASLICE_HOST_FDM_H
#define ADASLICE_HOST_FDM_H
#include "../adaslice.h"

#define FDM_WALLS 3
#define FDM_WALL_SPEED 45.0      /* mm/s */
#define FDM_WIDTH 0.45           /* mm */
#define FDM_INFILL 0.2
#define FDM_INFILL_SPEED 80.0    /* mm/s */
#define FDM_SKIN_LAYERS 3
#define FDM_SKIN_SPEED 20.0      /* mm/s */
#define FDM_LAYER_CHANGE_S 1.0   /* s: retract, lift, travel, prime */

/* The seconds of plan p on the welded mesh whose bottom is z0; RC_OK or a
   complaint made. */
int fdm_plan_seconds(const adaslice_mesh *mesh, double z0, const adaslice_plan *p, double *seconds);
#endif
