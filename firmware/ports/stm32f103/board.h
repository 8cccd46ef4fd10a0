/* The STM32F103C8 board ("blue pill" class: Cortex-M3 at 72 MHz, 64 KiB
   flash, 20 KiB RAM) driving a resin printer's Z stepper, UV light and
   endstop: pins, clock and the printer's figures, for cm3/main.c and board.c.
   Built, not run here.

   Pins:
     PA9   USART1 TX  -> host's RX (3.3 V levels; a USB-serial adapter)
     PA10  USART1 RX  <- host's TX (pulled up so a loose wire reads idle)
     PB12  STEP       stepper driver step input, a >= 2 us high pulse per step
     PB13  DIR        high = up (+1), set >= 1 us before the pulse
     PB14  ENABLE     low = driver enabled (A4988 / DRV8825 / TMC2209 EN)
     PB15  UV         high = UV light source on (the LED driver's enable)
     PB11  ENDSTOP    input with pull-up: a normally open switch to ground,
                      so closed (at the bottom) reads low
     PC13  LED        the board's LED, low = on: lit after a fault
   At reset every pin is a floating input until board_init drives UV low and
   ENABLE high (light off, motor free) before making them outputs: the UV
   and ENABLE lines need external pull-down / pull-up resistors for the
   microseconds before that. */
#ifndef FW_STM32F103_BOARD_H
#define FW_STM32F103_BOARD_H
#include <stdint.h>

#define BOARD_CLOCK_HZ 72000000u /* SYSCLK = HSE 8 MHz x 9 (PLL) */

/* The printer; -D to change. 400 steps/mm: a 1.8 degree motor at 1/16
   microsteps on an 8 mm lead screw. The display is the printer's own (see
   board.c). */
#ifndef BOARD_STEPS_PER_MM
#define BOARD_STEPS_PER_MM 400u
#endif
#ifndef BOARD_DISPLAY_W
#define BOARD_DISPLAY_W 2560u
#endif
#ifndef BOARD_DISPLAY_H
#define BOARD_DISPLAY_H 1440u
#endif
#ifndef BOARD_DISPLAY_BITS
#define BOARD_DISPLAY_BITS 1u
#endif
#ifndef BOARD_PITCH_NM
#define BOARD_PITCH_NM 50000u
#endif
#ifndef BOARD_MAX_BINS
#define BOARD_MAX_BINS 12000u
#endif
/* Frames the host may send ahead: the receive ring (CM3_RX_SIZE, set by
   firmware.mk) holds this many full frames, so a core busy planning never
   makes the USART overrun. */
#ifndef BOARD_WINDOW
#define BOARD_WINDOW 4u
#endif
/* The independent watchdog's period at the LSI's nominal 40 kHz (board.c):
   the loop refreshes it at least every half of it, 125 ms, below the
   shortest the LSI's spread (30-60 kHz) can make it, 167 ms. */
#define BOARD_WATCHDOG_MS 250u
/* The transmit ring: the window's frames each answered by at most one
   reply of LINK_FRAME_MAX (255) bytes (CM3_TX_SIZE, set by firmware.mk). */
#define BOARD_TX_WORST (BOARD_WINDOW * 255u)
#define BOARD_CAN_EXIT 0 /* a real board does not end */
/* The pace IDENTIFY states (fw.h): the mps2 image's (ports/mps2/board.h),
   whose passes run the same code at 25 MHz under QEMU; this part's 72 MHz
   at 1.0 to 1.5 cycles an instruction passes them faster. */
#define BOARD_CRC_BYTE_NS 78125u
#define BOARD_PLAN_BIN_NS 703125u
#endif
