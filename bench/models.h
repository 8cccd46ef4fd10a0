/* The shared models the benchmarks use (../shared/models), each with the
   scale that brings it to tens of mm like the paper's parts: the scans are in
   metres or normalised units. */
#ifndef ADASLICE_BENCH_MODELS_H
#define ADASLICE_BENCH_MODELS_H
#include <string.h>

static const struct bench_model { const char *name; double scale; } BENCH_MODELS[] = {
    {"counter.unitsmm.STL", 1}, {"turbineblade.ply", 1}, {"dragon_vrip_res2.ply", 300}, {"lucy.ply", 0.05},
    {"armadillo.obj", 60}, {"stanford-bunny.obj", 300}, {"hand_closed.obj", 88.7},
    {"cprc_nyu_n0300_ULM3_WS_EDJ_GEO.ply", 5},
    {"geometry_bracelet_ring_1-70mmID_8mmT_40mmW_3x20deg_360deg_31scale.stl", 1}, {"teapot.obj", 10},
    {"conrod.stl", 10}, {"Spider_ascii.stl", 10}};
#define BENCH_MODEL_COUNT (sizeof BENCH_MODELS / sizeof BENCH_MODELS[0])

/* The scale of a shared model, 1 for any other. */
static inline double bench_model_scale(const char *name)
{
    size_t i;
    for (i = 0; i < BENCH_MODEL_COUNT; i++)
        if (!strcmp(BENCH_MODELS[i].name, name)) return BENCH_MODELS[i].scale;
    return 1;
}
#endif
