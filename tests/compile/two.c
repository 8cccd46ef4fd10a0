/* Compile test: a second translation unit that includes the header, without
   (or, under TWO_STATIC, with its own static) implementation. */
#ifdef TWO_STATIC
#define ADASLICE_STATIC
#define ADASLICE_IMPLEMENTATION
#endif
#include "../../adaslice.h"
#include <stdio.h>
#include <string.h>

int one_plan_layers(void);

int main(void)
{
    double phi[100];
    adaslice_profile p;
    adaslice_plan plan;
    int k;
    memset(&p, 0, sizeof p);
    for (k = 0; k < 100; k++) phi[k] = 0.5;
    p.phi = phi; p.bin_count = 100; p.bin = 0.002; p.height = 0.2;
    if (adaslice_plan_profile(&p, NULL, &plan, NULL) != ADASLICE_OK) return 1;
    k = (int)plan.layer_count;
    adaslice_plan_free(&plan);
    if (k != one_plan_layers()) { printf("translation units disagree\n"); return 1; }
    (void)adaslice_result_name(ADASLICE_OK);
    return 0;
}
