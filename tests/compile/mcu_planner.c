/* The integer planner (adaslice_mcu.h) built for a Cortex-M3:
   N = 12,000 bins, layers of 25 to 75 bins, its whole state in a static
   workspace. make check fails if that workspace passes 16 KiB. */
#define ADASLICE_STATIC
#define ADASLICE_MCU_IMPLEMENTATION
#define ADASLICE_CRC32_SMALL /* no 16 KiB of tables on a small stack */
#include "../../adaslice_mcu.h"

#define BINS 12000u
#define BINS_MIN 25u
#define BINS_MAX 75u

/* 128-slot rings of 24 bytes and one back-pointer byte per plane */
static uint64_t workspace[(128u * 24u + BINS + 1u + 7u) / 8u];

uint32_t plan_on_mcu(const uint16_t *units, uint64_t eps);
uint32_t plan_on_mcu(const uint16_t *units, uint64_t eps)
{
    adaslice_dp dp;
    uint32_t i;
    if (adaslice_dp_init(&dp, workspace, sizeof workspace, BINS, BINS_MIN, BINS_MAX, eps, 0, 0) != ADASLICE_OK) return 0;
    for (i = 0; i < BINS; i++) adaslice_dp_push(&dp, units[i], 0);
    return adaslice_dp_layers(&dp);
}
