/* The curvature-based planner of the notes as the tool's fifth plan method,
   ADASLICE_METHOD_CURVATURE (cli.h). */
#ifndef ADASLICE_HOST_CURVATURE_H
#define ADASLICE_HOST_CURVATURE_H
#include "cli.h"

enum { MAPPING_COUNT = 3 };
extern const char *const MAPPING_NAMES[]; /* by adaslice_mapping */

/* k per bin of the profile of `mesh` into *kappa (malloc'd); RC_OK or a complaint made. */
int curvature_for_plan(const adaslice_mesh *mesh, const adaslice_profile *profile, double **kappa);
/* The curvature plan of the job's profile, its errors measured on that profile. */
adaslice_result plan_curvature_with(const plan_args *a, const plan_job *j, adaslice_plan *plan, adaslice_error *why);
#endif
