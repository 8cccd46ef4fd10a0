/* The mps2-an385 board as QEMU models it, and the printer this image
   pretends to be (-D to change). For cm3/main.c and board.c. */
#ifndef FW_MPS2_BOARD_H
#define FW_MPS2_BOARD_H

#define BOARD_CLOCK_HZ 25000000u /* QEMU's an385 core and peripheral clock */

#ifndef BOARD_STEPS_PER_MM
#define BOARD_STEPS_PER_MM 400u
#endif
#ifndef BOARD_DISPLAY_W
#define BOARD_DISPLAY_W 240u
#endif
#ifndef BOARD_DISPLAY_H
#define BOARD_DISPLAY_H 200u
#endif
#ifndef BOARD_DISPLAY_BITS
#define BOARD_DISPLAY_BITS 1u
#endif
#ifndef BOARD_PITCH_NM
#define BOARD_PITCH_NM 100000u
#endif
#ifndef BOARD_MAX_BINS
#define BOARD_MAX_BINS 12000u
#endif
/* Frames the host may send ahead. QEMU's UART holds the line while the
   receive ring is full, so no window overruns that; the limit is the
   transmit ring, which must hold a reply to each (BOARD_TX_WORST): 4, as on
   the STM32F103, whose 20 KiB this image is held to. */
#ifndef BOARD_WINDOW
#define BOARD_WINDOW 4u
#endif
/* The watchdog's period: the loop refreshes it at least every half of it
   (fw_run bounds its deadline so); a hung loop is reset within it. */
#define BOARD_WATCHDOG_MS 250u
/* The transmit ring: the window's frames each answered by at most one
   reply of LINK_FRAME_MAX (255) bytes, rounded up to a power of two
   (CM3_TX_SIZE, 1024 by default; board.c checks it). */
#define BOARD_TX_WORST (BOARD_WINDOW * 255u)
/* EXIT ends QEMU with its code (semihosting) */
#define BOARD_CAN_EXIT 1
/* the carriage's start above the endstop */
#ifndef MPS2_Z_START_MM
#define MPS2_Z_START_MM 30u
#endif

/* QEMU's exit status when the firmware stops itself on a fault:
   MPS2_EXIT_FAULT + CM3_FAULT_STACK or + CM3_FAULT_HARD. */
#define MPS2_EXIT_FAULT 100
#endif
