/* The mps2-an385 board's constants, for its port (main.c). */
#ifndef FW_MPS2_BOARD_H
#define FW_MPS2_BOARD_H

#define MPS2_CLOCK_HZ 25000000u /* QEMU's an385 core and peripheral clock */

/* QEMU's exit status when the firmware stops itself on a fault:
   MPS2_EXIT_FAULT + CM3_FAULT_STACK or + CM3_FAULT_HARD. */
#define MPS2_EXIT_FAULT 100
#endif
