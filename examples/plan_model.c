#include <stdio.h>
#include <stdlib.h>
#define ADASLICE_IMPLEMENTATION
#include "../adaslice.h"

int main(int argc, char **argv)
{
    adaslice_load_options load = {ADASLICE_FORMAT_AUTO, argc > 2 ? atof(argv[2]) : 1.0, NULL};
    adaslice_mesh mesh; adaslice_profile profile; adaslice_plan plan; adaslice_error err;
    if (argc < 2) return 2;
    if (adaslice_mesh_load_file(argv[1], &load, &mesh, &err) ||
        adaslice_profile_exact(&mesh, NULL, &profile, &err) || /* cusp, b = 2 um */
        adaslice_plan_profile(&profile, NULL, &plan, &err)) {  /* eps 0.065, 0.05-0.15 mm */
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    for (size_t k = 0; k < plan.layer_count; k++)
        printf("%.3f %.3f %.4f\n", plan.layers[k].z_bottom, plan.layers[k].thickness, plan.layers[k].error);
    adaslice_plan_free(&plan); adaslice_profile_free(&profile); adaslice_mesh_free(&mesh);
    return 0;
}
