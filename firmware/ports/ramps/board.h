/* RAMPS 1.4 on an Arduino Mega 2560: the printer's figures (-D to change)
   and the board layer (ramps.c) that main.c hands to the core. Plain
   #defines and prototypes only, so the simavr harness (tests/avr_run.c)
   includes this file for the same figures.

   Pins (RAMPS 1.4 as Marlin's pins_RAMPS.h names them, Arduino Mega 2560
   pin mapping from the Arduino "mega" variant's pins_arduino.h):
       Z_STEP    D46 = PL3 (OC5A)   step pulses from Timer5's compare unit A
       Z_DIR     D48 = PL1          high = up (away from the vat)
       Z_ENABLE  D62 = PK0 (A8)     active low: high = driver off
       Z_MIN     D18 = PD3          endstop: NC switch to ground with the pull-up on,
                                    so high = pressed (a broken wire reads pressed)
       UV        D8  = PH5 (OC4C)   RAMPS's D8 MOSFET, switched by Timer4's compare unit C
       UART0     PE0/PE1            through the Mega's USB bridge to the host */
#ifndef FW_RAMPS_BOARD_H
#define FW_RAMPS_BOARD_H

#define BOARD_CPU_HZ   16000000u           /* the Mega's crystal */
#define BOARD_TICK_DIV 8u                  /* Timer5's prescaler */
#define BOARD_CLOCK_HZ (BOARD_CPU_HZ / BOARD_TICK_DIV) /* the tick: 2 MHz, 0.5 us */
#define BOARD_BAUD     115200u             /* U2X, UBRR 16: 117,647 baud, the Arduino setting */

#ifndef BOARD_STEPS_PER_MM
#define BOARD_STEPS_PER_MM 400u            /* T8x8 lead screw, 1/16 microsteps */
#endif
/* Z's top speed on this MCU. An 8-bit core computes motion.c's closed form
   in 64-bit integers (make bench, bench/avr_bench.c, times each step); the
   loop refills the step queue once FW_STEP_FILL steps have gone out, and
   every pass, interrupts included, ends within seven eighths of the time
   the rest of the queue covers at this speed
   (tests/test_avr.c asserts it from simavr's pin edges and the loop's
   marks, in G-code mode and with masks streaming while Z moves). */
#ifndef BOARD_MAX_SPEED_UM_S
#define BOARD_MAX_SPEED_UM_S 10000ul
#endif
#define BOARD_ACCEL_MM_S2    50u
/* homing's approach, slower: braking at the switch overshoots it by v^2 / 2a */
#define BOARD_HOME_SPEED_UM_S 5000ul
/* the same in steps per second (the core's units) */
#define BOARD_MAX_STEPS_S  ((uint32_t)BOARD_MAX_SPEED_UM_S * BOARD_STEPS_PER_MM / 1000u)
#define BOARD_HOME_STEPS_S ((uint32_t)BOARD_HOME_SPEED_UM_S * BOARD_STEPS_PER_MM / 1000u)
#define BOARD_Z_MAX_MM       200u
#define BOARD_HOME_TRAVEL_MM 220u
/* Products of these figures overflow int, which is 16 bits here: every
   derived figure is worked out in 32 bits (main.c checks each one in the
   part's own arithmetic at compile time). */
#define BOARD_Z_MAX_STEPS       ((uint32_t)BOARD_Z_MAX_MM * BOARD_STEPS_PER_MM)
#define BOARD_HOME_TRAVEL_STEPS ((uint32_t)BOARD_HOME_TRAVEL_MM * BOARD_STEPS_PER_MM)
#define BOARD_ACCEL_STEPS_S2    ((uint32_t)BOARD_ACCEL_MM_S2 * BOARD_STEPS_PER_MM)
#define BOARD_LINK_TIMEOUT_MS 1000u

/* The display is driven by another computer: adaslice print --screen on a
   Linux board (SCREEN messages: the light only under the layer the host
   shows, Z only under a dark screen; link/PROTOCOL.md), or NanoDLP in
   G-code mode. Masks sent here are decoded and CRC-checked by the core and
   counted. The display's size is the panel's, as the host checks its jobs. */
#ifndef BOARD_DISPLAY_W
#define BOARD_DISPLAY_W 2560u
#endif
#ifndef BOARD_DISPLAY_H
#define BOARD_DISPLAY_H 1440u
#endif
#define BOARD_DISPLAY_BITS 1u
/* the core's row buffer: one row (firmware.mk force-includes this file) */
#define FW_ROW_BYTES ((BOARD_DISPLAY_W + 7u) / 8u)
#ifndef BOARD_PITCH_NM
#define BOARD_PITCH_NM 50000u
#endif
/* The planner's largest profile: 8 KiB of SRAM hold the core's state, the
   planner's 3 KiB of rings and a byte per bin, the UART rings and the
   stack's reserve (the link refuses an image they do not fit; firmware.mk
   prints the figures, make bench the largest that fits). Larger parts are
   planned by the host. */
#ifndef BOARD_MAX_BINS
#define BOARD_MAX_BINS 1200u
#endif
/* A UART cannot hold the line: the receive ring takes the whole window. */
#define BOARD_RX_SIZE 512u
#define BOARD_TX_SIZE 256u
#define BOARD_WINDOW  2u

/* The watchdog (reset mode), refreshed by the main loop only (fw_run). */
#define BOARD_WDT_MS 120u

/* Steps: a move's first step comes BOARD_STEP_LEAD ticks after it starts,
   computed in the pass after the one that started it. The queue holds
   FW_STEP_QUEUE steps (9 bytes of SRAM each); the loop refills it once
   FW_STEP_FILL steps have gone out, in one pass (a move's first step
   shapes it: several divisions), so a pass computing steps stays short and
   the rest of the queue covers the wait. 32 deep: near the top speed a
   ramp's step costs about its interval, and bytes streaming in meanwhile
   (a G-code host's burst of lines, each byte an interrupt) take the rest;
   16 ran dry under such a burst at a ramp's top. The other pieces of a pass, each a
   few thousand cycles here (avr-run --profile-passes): 8 mask code bytes
   and 16 bytes of rows' CRC (a 2560-pixel display's 320-byte row takes 20
   passes; a repeated row costs one multiplication), 2 profile bins, 32
   planes of the plan's reversal. */
#define BOARD_STEP_LEAD (BOARD_CLOCK_HZ / 125u) /* 8 ms */
#define FW_STEP_QUEUE 32u
#define FW_STEP_FILL 4u
#define FW_DECODE_BYTES 8u
#define FW_CRC_BYTES 16u
#define FW_PLAN_BINS 2u
#define FW_REVERSE_PLANES 32u

/* The pace IDENTIFY states (fw.h, fw_config's crc_byte_ns and plan_bin_ns):
   a slice of a held frame's work is one pass, FW_CRC_BYTES of rows' CRC or
   FW_PLAN_BINS bins, and a pass of steps may come between two slices (a
   refill of FW_STEP_FILL steps at most every 16,000 cycles at the top
   speed). The host allows two passes of 2 ms (32,000 cycles) a slice: 4 ms
   for 16 bytes of CRC, and for 2 bins with their planes' share of the
   reversal (32 a pass). The worst pass of a print under simavr is a
   move's first steps while masks stream, longer than a slice of a mask's
   CRC (avr-run --profile-passes); tests/test_avr.c holds two of a binary
   print's worst passes, interrupts in (avr-run's worst_pass), to the
   slice's allowance its IDENTIFY states (docs/BENCHMARKS.md: the figures). */
#define BOARD_CRC_BYTE_NS 250000u   /* 4 ms / 16 bytes */
#define BOARD_PLAN_BIN_NS 2125000u  /* 4 ms / 2 bins + 4 ms / 32 planes */

/* Test hooks the simavr harness watches (one OUT instruction each): the
   general purpose I/O registers, never read by the firmware. */
#define BOARD_MARK_LOOP  1u   /* GPIOR0: a loop pass begins */
#define BOARD_MARK_IDLE  2u   /* GPIOR0: the pass ends, the loop sleeps */
#define BOARD_MARK_BOOT  3u   /* GPIOR0: reset, before anything else */
#define BOARD_MARK_LATE  4u   /* GPIOR0: a step could not be issued on time */
#define BOARD_MARK_MOVING 5u  /* GPIOR0: a pass begins while Z moves (steps computed or queued) */
/* GPIOR1: the display buffer shown + 1, 0 for dark (there is no display here) */

#ifndef __ASSEMBLER__
#include <stdint.h>
#include <stddef.h>
/* The state a stack overrun must reach last (the tick's extension, the
   step and UV compare state, the core's fw_state): at the start of .bss,
   the far end of SRAM from the stack. The default avr6 linker script
   places the input sections named exactly .bss before the .bss.* that
   -fdata-sections makes; firmware.mk checks the image. */
#define BOARD_SAFETY __attribute__((section(".bss")))
/* ---- ramps.c ---------------------------------------------------------- */
void board_init(void);
uint32_t board_boot_count(void);          /* from EEPROM, counted at this boot */
uint8_t board_reset_cause(void);          /* MCUSR as it was at reset */
uint64_t board_ticks(void);               /* 2 MHz, from Timer5 */
void board_watchdog(void);                /* refresh: the main loop only */
/* Sleeps until an interrupt, at the latest at tick `deadline` or after a Timer5 wrap. */
void board_idle(uint64_t deadline);
/* UART0: the receive ring (filled by the RX interrupt) and the transmit ring
   (drained by the data-register-empty interrupt); board_write never blocks:
   bytes that do not fit are counted and dropped. */
size_t board_rx_peek(const uint8_t **data);
void board_rx_consume(size_t n);
void board_write(const uint8_t *data, size_t size);
uint16_t board_rx_lost(void);
uint16_t board_tx_lost(void);
/* Z: arms Timer5's compare unit A to raise STEP at tick `when` with DIR set
   to `dir` (+1 up) now; 0 (nothing armed, a BOARD_MARK_LATE) when `when` is
   too close or past; UINT64_MAX disarms. board_step_pulse ends the pulse
   (in the compare interrupt, which calls ramps_step_due: main.c's, 1 when
   the queue ran out and the loop must wake). */
int board_step_arm(uint64_t when, int dir);
void board_step_pulse(void);
int ramps_step_due(void);
int ramps_gcode_mode(void);               /* main.c's: the core reads G-code now */
int fw_urgent_byte(uint8_t *state, uint8_t c); /* the core's (fw.h) */
int board_endstop(void);
void board_motor(int on);
/* UV on from tick `when` to `until` (on = 1), switched by Timer4's compare
   unit C at both ticks (a start already past moves both by as much), or off
   at `when` (on = 0; now if that has passed). */
void board_uv(int on, uint64_t when, uint64_t until);
uint8_t board_uv_lit(void);
/* 0 once the stack has written over its canary (below its room) */
int board_stack_ok(void);
void board_test_overrun(void);            /* RAMPS_TEST_OVERRUN builds: the stack down to the canary */
void board_show(int slot);
void board_mask_row(void);
#endif
#endif
