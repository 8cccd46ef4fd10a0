/* The trimmed build of adaslice.h that firmware images link: the integer
   planner, CRC-32 and the mask run-length code (no float, libm, malloc or
   stdio). Host programs that link the full library leave this file out. */
#define ADASLICE_FIRMWARE
#define ADASLICE_IMPLEMENTATION
#include "../adaslice.h"
