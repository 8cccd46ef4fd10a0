/* Compile test: this translation unit holds the implementation (C99 or C++),
   with every option macro a user might set. */
#ifdef TWO_STATIC
#define ADASLICE_STATIC
#endif
#define ADASLICE_IMPLEMENTATION
#include "../../adaslice.h"
#include "../../adaslice.h" /* a second include is harmless */

int one_plan_layers(void);
int one_plan_layers(void)
{
    static double phi[100];
    adaslice_profile p;
    adaslice_plan plan;
    int k;
    memset(&p, 0, sizeof p);
    for (k = 0; k < 100; k++) phi[k] = 0.5;
    p.phi = phi; p.bin_count = 100; p.bin = 0.002; p.height = 0.2;
    if (adaslice_plan_profile(&p, NULL, &plan, NULL) != ADASLICE_OK) return -1;
    k = (int)plan.layer_count;
    adaslice_plan_free(&plan);
    return k;
}
