/* The curvature-based planner of the notes as the tool's fifth plan method. */
#include "curvature.h"

#include <stdlib.h>
#include <string.h>

const char *const MAPPING_NAMES[] = {"linear", "exp", "step"};

int curvature_for_plan(const adaslice_mesh *mesh, const adaslice_profile *profile, double **kappa)
{
    adaslice_error e;
    *kappa = (double *)malloc(profile->bin_count * sizeof **kappa);
    if (!*kappa) return complain(RC_FAIL, "out of memory for the curvature of %zu bins", profile->bin_count);
    if (adaslice_curvature_profile(mesh, profile, NULL, *kappa, &e) != ADASLICE_OK) {
        free(*kappa);
        *kappa = NULL;
        return library_error(&e);
    }
    return RC_OK;
}

adaslice_result plan_curvature_with(const plan_args *a, const plan_job *j, adaslice_plan *plan, adaslice_error *why)
{
    adaslice_plan_options o;
    plan_options_of(a, ADASLICE_METHOD_CURVATURE, &o);
    o.curvature = j->kappa;
    o.mapping = (adaslice_mapping)a->mapping;
    return adaslice_plan_profile(&j->profile, &o, plan, why);
}
