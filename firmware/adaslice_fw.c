/* adaslice_mcu.h's implementation, as firmware images link it: the integer
   planner, CRC-32, varints and the mask run-length code (no float, libm,
   malloc or stdio). Programs that link adaslice.h's implementation have it. */
#define ADASLICE_MCU_IMPLEMENTATION
#define ADASLICE_CRC32_SMALL /* no 16 KiB of tables on a small stack */
#include "../adaslice_mcu.h"
