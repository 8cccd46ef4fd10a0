/* The deterministic quantised profile of make bench's MCU planner run
   (bench/bench_mcu_plan.c on the host, bench/mcu_plan_mps2.c on the
   Cortex-M3): the same code on both sides, 32-bit integers only (the M3 has
   UMULL and UDIV), no C library.

   MCU_BINS bins in printer units with eps = MCU_EPS_UNITS (2^20, the tool's),
   layers of MCU_BINS_MIN..MCU_BINS_MAX bins. The profile is made of segments
   of 64..1023 bins; each segment picks a mean between eps/75 and eps/25
   units per bin, and its bins are that mean uniformly jittered by +-50 %,
   capped at eps/25 (so any 25 bins make a layer within eps). Over the whole
   profile a bin is about eps/40 units, and the optimal plan has layers of
   25..75 bins.
   About one bin in 1024 is forced (a plane on top of it, as the §3.3
   pre-pass marks sharp changes), never within 25 bins of the last forced
   plane, the bottom or the top. */
#ifndef ADASLICE_BENCH_MCU_PROFILE_H
#define ADASLICE_BENCH_MCU_PROFILE_H
#include <stdint.h>

#define MCU_BINS 12000u
#define MCU_BINS_MIN 25u
#define MCU_BINS_MAX 75u
#define MCU_EPS_UNITS 1048576u
#define MCU_SEED 0x2545F491u

typedef struct mcu_gen {
    uint32_t state;       /* xorshift32 */
    uint32_t mean;        /* this segment's mean units per bin */
    uint32_t left;        /* bins left in this segment */
    uint32_t since;       /* bins since the last forced plane (or the bottom) */
    uint32_t i, n;        /* next bin, bins in all */
} mcu_gen;

static uint32_t mcu_gen_rand(mcu_gen *g)
{
    uint32_t x = g->state;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return g->state = x;
}

/* Uniform in [lo, hi]. */
static uint32_t mcu_gen_range(mcu_gen *g, uint32_t lo, uint32_t hi)
{
    return lo + (uint32_t)(((uint64_t)mcu_gen_rand(g) * (uint64_t)(hi - lo + 1u)) >> 32);
}

static void mcu_gen_init(mcu_gen *g, uint32_t n, uint32_t seed)
{
    g->state = seed ? seed : 1u;
    g->mean = 0;
    g->left = 0;
    g->since = 0;
    g->i = 0;
    g->n = n;
}

/* The next bin's units; *forced is 1 when a plane goes on top of it. */
static uint32_t mcu_gen_next(mcu_gen *g, int *forced)
{
    uint32_t u, cap = MCU_EPS_UNITS / MCU_BINS_MIN;
    if (!g->left) {
        g->left = mcu_gen_range(g, 64u, 1023u);
        g->mean = mcu_gen_range(g, MCU_EPS_UNITS / MCU_BINS_MAX, MCU_EPS_UNITS / MCU_BINS_MIN);
    }
    g->left--;
    u = mcu_gen_range(g, g->mean / 2u, g->mean + g->mean / 2u);
    if (u > cap) u = cap;
    g->since++;
    g->i++;
    *forced = 0;
    if (g->since >= MCU_BINS_MIN && g->i + MCU_BINS_MIN <= g->n && (mcu_gen_rand(g) & 1023u) == 0) {
        *forced = 1;
        g->since = 0;
    }
    return u;
}

/* FNV-1a, 32 bits, over 32-bit words (little-endian bytes): the plan's
   layer lengths bottom-up, or the profile's units and forced flags. */
#define MCU_HASH_START 2166136261u
static uint32_t mcu_hash(uint32_t h, uint32_t word)
{
    int k;
    for (k = 0; k < 4; k++) {
        h ^= (word >> (8 * k)) & 255u;
        h *= 16777619u;
    }
    return h;
}
#endif
