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
/* The pace IDENTIFY states (fw.h, fw_config's crc_byte_ns and plan_bin_ns):
   a slice of a held frame's work is one pass, 64 bytes of rows' CRC
   (FW_CRC_BYTES) or 8 bins (FW_PLAN_BINS), and a pass of steps may come
   between two slices. The host allows two passes of 2.5 ms (62,500
   cycles, fw.h's looser bound on a pass: half the step lead, with Z
   still) a slice: 5 ms for 64 bytes of CRC, and for 8 bins with their
   planes' share of the reversal (64 a pass). tests/test_qemu_timing.c
   holds two of the trace image's worst passes, the loop's own work, to
   the slice's allowance its IDENTIFY states (docs/BENCHMARKS.md: the
   figures); with its interrupts in a pass can be longer, as QEMU's UART
   hands a burst of the host's bytes over at once where a line spreads
   them over milliseconds. */
#define BOARD_CRC_BYTE_NS 78125u   /* 5 ms / 64 bytes */
#define BOARD_PLAN_BIN_NS 703125u  /* 5 ms / 8 bins + 5 ms / 64 planes */
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
