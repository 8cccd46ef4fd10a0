/* An oracle for the integer planner (adaslice_dp, the firmware's planner):
   the fewest layers over integer per-bin errors by the textbook quadratic
   recurrence, every allowed layer below every plane tried, not the
   library's monotone queue. A layer [a, b) is allowed when lo <= b - a <= hi,
   its units add up to at most eps and no forced plane (the top of a forced
   bin) lies strictly inside it; among the plans of fewest layers, the one
   with the smallest worst layer. */
#ifndef TESTS_PLAN_ORACLE_H
#define TESTS_PLAN_ORACLE_H
#include <stdint.h>
#include <stdlib.h>

typedef struct {
    uint32_t layers; /* 0 when no plan reaches the top */
    uint64_t worst;  /* the worst layer's units in that plan */
} oracle_plan;

static oracle_plan oracle_fewest_layers(const uint32_t *units, const unsigned char *forced, uint32_t n, uint32_t lo,
                                        uint32_t hi, uint64_t eps)
{
    oracle_plan best = {0, 0};
    uint32_t *layers = (uint32_t *)malloc((n + 1) * sizeof *layers);
    uint64_t *worst = (uint64_t *)malloc((n + 1) * sizeof *worst);
    uint32_t a, b;
    if (!layers || !worst) { free(layers); free(worst); return best; }
    layers[0] = 0; worst[0] = 0;
    for (b = 1; b <= n; b++) {
        uint64_t sum = 0;
        layers[b] = UINT32_MAX; worst[b] = 0;
        /* a goes down from b, so the layer [a, b) grows by one bin at a time */
        for (a = b; a-- > 0 && b - a <= hi;) {
            sum += units[a];
            if (sum > eps) break;
            if (b - a >= lo && layers[a] != UINT32_MAX) {
                uint32_t l = layers[a] + 1;
                uint64_t w = worst[a] > sum ? worst[a] : sum;
                if (l < layers[b] || (l == layers[b] && w < worst[b])) { layers[b] = l; worst[b] = w; }
            }
            if (a > 0 && forced && forced[a - 1]) break; /* plane a is forced: no layer reaches across it */
        }
    }
    if (layers[n] != UINT32_MAX) { best.layers = layers[n]; best.worst = worst[n]; }
    free(layers); free(worst);
    return best;
}

/* A plan given as layer lengths in bins, bottom up, checked against the same
   rules independently of how it was found: 1 when every layer is allowed and
   the plan reaches exactly n; *worst gets its worst layer's units. */
static int oracle_plan_is_valid(const uint32_t *units, const unsigned char *forced, uint32_t n, uint32_t lo, uint32_t hi,
                                uint64_t eps, const uint32_t *lengths, uint32_t count, uint64_t *worst)
{
    uint32_t k, at = 0, i;
    *worst = 0;
    for (k = 0; k < count; k++) {
        uint64_t sum = 0;
        if (lengths[k] < lo || lengths[k] > hi || at + lengths[k] > n) return 0;
        for (i = at; i < at + lengths[k]; i++) {
            sum += units[i];
            if (forced && forced[i] && i + 1 < at + lengths[k]) return 0;
        }
        if (sum > eps) return 0;
        if (sum > *worst) *worst = sum;
        at += lengths[k];
    }
    return at == n;
}
#endif
