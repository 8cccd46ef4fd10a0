/* adaslice firmware core: the part of the printer's MCU code that every port
   shares (protocol, planner from adaslice_mcu.h, Z motion, the print state
   machine, the mask sink, G-code mode). Portable C99 with no float, no libm,
   no malloc and no stdio; all state lives in one fw_state the port owns.

   A port supplies the hardware through fw_port and runs one loop:

       fw_init(&fw, &config, &port, workspace, sizeof workspace);
       for (;;) {
           feed received bytes:         taken = fw_receive(&fw, bytes, n, now);
           when now >= deadline:        deadline = fw_run(&fw, now);
           otherwise sleep until a byte arrives or the deadline
       }

   Steps leave from the port's step timer, never from the loop (Klipper's and
   GRBL's rule): fw_run computes the next steps from motion.c's closed form
   into a small queue (fw_steps) ahead of their ticks; the port's compare
   interrupt calls fw_step_interrupt at each step's tick, which puts the
   step out and arms the timer for the next one. A step that could not be
   queued before its tick, or a timer that could not be armed in time, is a
   fault (LINK_ERR_STEP_LATE): the motion stops dead, the axis is unhomed, UV
   off, the motor disabled. A step is never sent late. The Z-min switch
   closing during a move where the carriage cannot be at it is the same
   stop (LINK_ERR_ENDSTOP), and so is G-code's M112.

   The UV light is switched off by the port's own timer at the end the core
   gives with it (uv's `until`), so an exposure ends on time, whatever the
   loop is doing. fw_run refreshes the port's watchdog and never returns a
   deadline further than half its period away.

   fw_run issues nothing itself: it refills the step queue, ends exposures,
   notices a silent link and returns the tick of the next thing it must do
   (FW_NEVER: nothing until a byte arrives). Nothing in the core blocks.

   Bounded work a pass: a pass of the loop (fw_receive, then fw_run) does
   one piece of work beyond its bookkeeping, so that it stays shorter than
   the time the step queue, less a refill, covers at the top speed, whatever else it
   does: up to FW_STEP_FILL steps (the first of a move shapes it), or one
   frame received (its reply; the rest
   of the bytes wait for the next pass), or one of G-code's pieces (a
   line's check, its run, a G0/G1's start, a move's or a dwell's end:
   gcode.h), or a move's start by the print, or one slice of a held
   frame's work (FW_DECODE_BYTES of a mask's code and FW_CRC_BYTES of its
   rows, FW_PLAN_BINS of a profile, FW_REVERSE_PLANES of the plan's
   reversal). The steps come first: the queue is refilled once FW_STEP_FILL
   steps (at most half of it) have gone out (bytes wait in the port's ring
   meanwhile), and the others wait for a pass that computed none, which so
   begins with the queue less a refill. The wire protocol is in
   link/PROTOCOL.md. */
#ifndef FW_H
#define FW_H
#include <stddef.h>
#include <stdint.h>
#include "../adaslice_mcu.h"
#include "../link/frame.h"
#include "../link/messages.h"
#include "motion.h"
#include "gcode.h"


/* The steps queued for the step timer: written by the loop (head), read by
   the interrupt (tail). Single producer, single consumer, indices of one
   byte so that each side's update is one store on any MCU. The queue, less
   a refill, must cover the steps due while the loop is away: more than the loop's
   worst pass (plus its wake-up) divided by the shortest step interval. A port
   whose passes are long against its steps sets its own (a power of two up
   to 128; each entry costs 9 bytes of RAM). */
#ifndef FW_STEP_QUEUE
#define FW_STEP_QUEUE 8u
#endif
/* At most this many steps are computed in one pass of the loop (fw_run's
   two fills share them), so that a pass does a bounded amount of motion
   arithmetic; fw_run asks to be called again at once (its deadline `now`)
   while a refill is short for want of it. The default is the queue's
   length. */
#ifndef FW_STEP_FILL
#define FW_STEP_FILL FW_STEP_QUEUE
#endif
typedef struct fw_steps {
    volatile uint64_t tick[FW_STEP_QUEUE];
    volatile int8_t dir[FW_STEP_QUEUE];
    volatile uint8_t head;     /* the loop's: the next free entry */
    volatile uint8_t tail;     /* the interrupt's: the next step out */
    volatile uint8_t running;  /* the timer is armed; the interrupt clears it when the queue ends */
    volatile uint8_t late;     /* the timer could not be armed for the next step in time */
    uint8_t budget;            /* the loop's: steps it may still compute before fw_run */
    uint8_t short_by;          /* the loop's: the last fill stopped for want of budget */
} fw_steps;

typedef struct fw_port {
    void *ctx;
    /* bytes to the host, into the port's transmit ring (sent by its
       interrupt); must not wait for the line */
    void (*write)(void *ctx, const uint8_t *data, size_t size);
    /* Arms the step timer to call fw_step_interrupt at tick `when`, with the
       direction pin set to `dir` (+1 up, -1 down) by then; returns 0 if
       `when` is too close or past to be armed. `when` FW_NEVER: disarm. From
       the loop (the first step of a run) and from fw_step_interrupt. */
    int (*step_arm)(void *ctx, uint64_t when, int dir);
    /* In fw_step_interrupt: the step pulse in direction `dir`, now (a port
       whose compare unit sets the pin itself ends the pulse here). */
    void (*step_pulse)(void *ctx, int dir);
    /* 1 while the Z endstop is closed */
    int (*endstop)(void *ctx);
    /* The UV light on at tick `when` (at once if that has passed) for
       `until` - `when` ticks, ended by the port's own timer (on = 1): the
       core never ends an exposure itself, so its length is the timer's
       whatever the loop does. Or off at `when` (on = 0), by the same timer
       if that is still ahead and earlier than the end it has, else at once:
       a pause, an abort or a fault pass the present tick, G-code's lit
       dwell its end. A port that switches on late by L keeps the length and
       ends L late (an off at a later tick too); L stays under step_lead, so
       the light is out before a move that starts at the exposure's end
       takes its first step. */
    void (*uv)(void *ctx, int on, uint64_t when, uint64_t until);
    /* stepper driver enable (M17/M18) */
    void (*motor)(void *ctx, int on);
    /* a decoded mask row into display buffer `slot` (0 or 1): row y of the
       picture as shown, top first; 1-bit rows are packed MSB first, 8-bit
       rows one byte per pixel */
    void (*mask_row)(void *ctx, int slot, uint32_t y, const uint8_t *row, uint32_t size);
    /* display buffer `slot` on the screen (a verified mask), or -1: dark */
    void (*show)(void *ctx, int slot, uint64_t when);
    /* refreshes the hardware watchdog (NULL: none); from fw_run only */
    void (*watchdog)(void *ctx);
    /* emulators only (NULL on a real board): end the program with `code` */
    void (*exit)(void *ctx, int code);
} fw_port;

typedef struct fw_config {
    uint32_t tick_hz;          /* ticks per second of the port's clock */
    fw_axis_config axis;
    uint16_t display_width, display_height;
    uint8_t display_bits;      /* 1 or 8 */
    uint32_t pitch_nm;         /* display pixel pitch */
    uint32_t max_bins;         /* the planner's limit; bins_max <= 255 */
    uint32_t link_timeout_ms;  /* printing pauses when the host is silent this long;
                                  5 times as long outside a print hands the port to G-code */
    uint8_t window;            /* frames the host may have unacknowledged */
    uint32_t watchdog_ms;      /* the watchdog's period (0: none) */
    uint32_t step_lead;        /* ticks the step timer needs to be armed: a move's
                                  first step comes this long after it starts */
    uint32_t boot_id;          /* differs at every start of the MCU (a boot counter
                                  or random): the host sees a reset */
    /* The port's pace, which IDENTIFY tells the host so that it waits as
       long as this board needs for a frame's answer: the time, ns, the
       loop takes at most per byte of a MASK_DATA frame's rows' CRC, and per
       bin of a PROFILE_DATA frame planned (its plane's reversal included),
       with what else its passes do meanwhile (steps, replies, interrupts).
       Each port's board.h gives its figures and how they were measured. */
    uint32_t crc_byte_ns, plan_bin_ns;
} fw_config;

/* Layers of up to 127 bins: the planner's rings have 128 entries of 24
   bytes, plus 1 byte of back-pointer per bin. */
#define FW_MAX_LAYER_BINS 127u
#define FW_PLAN_WORKSPACE(max_bins) (128u * 24u + (size_t)(max_bins) + 1u)

/* The work of a long frame goes on over passes of the loop (fw_run), the
   frame held in the deframer and acknowledged once done, so that a pass
   stays short whatever a frame holds. In one pass: mask code bytes
   decoded and bytes of finished rows put through the CRC (a row is copied
   to the display once its CRC is in; a repeat of a thousand rows takes a
   thousand rows of CRC, over as many passes as their bytes need), profile
   bins pushed through the planner,
   and planes of the plan's reversal once its last bin is in. A port whose
   passes must be shorter than these make them sets its own. */
#ifndef FW_CRC_BYTES
#define FW_CRC_BYTES 64u
#endif
#ifndef FW_DECODE_BYTES
#define FW_DECODE_BYTES 64u
#endif
#ifndef FW_PLAN_BINS
#define FW_PLAN_BINS 8u
#endif
#ifndef FW_REVERSE_PLANES
#define FW_REVERSE_PLANES 64u
#endif
/* A display row at most this many bytes (1-bit: 8 pixels a byte). */
#ifndef FW_ROW_BYTES
#define FW_ROW_BYTES 480u
#endif

typedef struct fw_state {
    fw_config config;
    fw_port port;
    /* the config's times in ticks, worked out once (on an 8-bit core a
       64-bit division is thousands of cycles, and fw_run needs these on
       every pass) */
    uint64_t link_timeout, watchdog_half;
    fw_axis axis;
    fw_steps steps;
    /* link */
    link_deframer deframer;
    uint64_t heard;            /* tick of the last frame taken (a HELLO, or the SEQ expected: not a
                                  repeat); in G-code mode, of the last byte */
    /* planner: the profile streams through the DP, never stored */
    unsigned char *workspace;
    size_t workspace_size;
    adaslice_dp dp;
    uint32_t bins, bins_in, bin_nm;
    adaslice_varint varint;    /* the profile's next number */
    uint8_t plan_kind;         /* 0 none, 1 from the profile, 2 given by the host */
    uint8_t receiving;         /* LINK_MSG_PROFILE_DATA or LINK_MSG_PLAN_DATA while one arrives */
    uint32_t layers;           /* K */
    uint32_t cursor_layer, cursor_plane; /* reading the plan bottom-up */
    /* masks: decoded into display buffer (layer & 1) as they stream */
    adaslice_rle_decoder decoder;
    const uint8_t *decode_at;  /* the held frame's bytes still to work through */
    size_t decode_left;
    uint8_t decode_seq;
    uint8_t decoding;          /* the held frame's type (MASK_DATA, PROFILE_DATA), 0 none */
    uint8_t row[FW_ROW_BYTES];
    uint32_t mask_layer, mask_size, mask_got, mask_crc, mask_exposure_ms;
    uint32_t exposure_ms[2];   /* of the ready mask in each display buffer */
    uint32_t mask_ready;       /* highest layer whose mask passed its CRC */
    uint16_t masks_refused;
    /* print */
    uint8_t state, phase, error, error_seq, pause_wanted, paused_by_link;
    uint8_t expect;            /* the host's next sequence number */
    uint8_t binary;            /* a good frame arrived: G-code mode is off */
    uint32_t layer;            /* the layer being printed (1-based), 0 before */
    uint32_t top_plane;        /* its top, in bins */
    uint32_t peel_nm, settle_ms;
    uint32_t peel_speed, return_speed; /* steps/s */
    uint64_t phase_end;        /* tick when a timed phase ends */
    uint64_t exposure_left;    /* ticks of exposure a pause interrupted */
    uint32_t exposed;          /* the last layer whose exposure ended, 0 none */
    uint32_t job;              /* the job hash PRINT came with, 0 none */
    /* the host's screen (SCREEN): the layer it says is drawn whole and on
       screen, 0 dark. Z moves only while it is 0; a print lights a layer
       only while it is that layer, once host_screen says the print's masks
       are the host's (the first SCREEN of a layer since PRINT) */
    uint32_t screen;
    uint8_t host_screen;
    uint8_t uv_on;
    uint8_t exposing;          /* an EXPOSE message's light, until phase_end */
    uint8_t halted;            /* fw_stack_fault: nothing lights or moves until reset */
    /* G-code mode, until a good frame arrives */
    fw_gcode gcode;
    uint8_t gcode_held[2 * FW_GCODE_LINE_MAX]; /* bytes G-code could not take yet */
    uint16_t gcode_held_len;
    uint8_t gcode_overflow;    /* dropping the rest of a line that did not fit */
    uint8_t urgent;            /* where the bytes are in an M112 / M410 line (acted on at its end) */
} fw_state;

/* plan_workspace: FW_PLAN_WORKSPACE(config->max_bins) bytes, 8-byte aligned. */
void fw_init(fw_state *fw, const fw_config *config, const fw_port *port, void *plan_workspace, size_t workspace_size);
/* Bytes from the host, in order, from the main loop (not an interrupt).
   Returns how many it took: none while the step queue is to be refilled
   (the steps come first: fw_run refills it), and it stops after a frame
   whose work goes on in the next passes of fw_run (a mask or profile
   frame); offer the rest again after fw_run. */
size_t fw_receive(fw_state *fw, const uint8_t *data, size_t size, uint64_t now);
/* Does what is due at tick `now`; returns the tick of the next deadline. */
uint64_t fw_run(fw_state *fw, uint64_t now);
/* The step timer's interrupt, at the tick it was armed for: the step out
   (port.step_pulse), the timer armed for the next one or stopped. */
void fw_step_interrupt(fw_state *fw);
/* G-code's urgent lines, byte by byte: *state (0 to begin) follows a line
   and 112 or 410 comes back at the end of an M112 or M410 line, else 0.
   The core runs it on the bytes it reads; a port may run it on its own
   copy of the state in its receive interrupt too (while fw_gcode_mode),
   to stop Z and put the light out at M112's last byte, before the loop
   has read the line (the core then does the rest). */
int fw_urgent_byte(uint8_t *state, uint8_t c);
/* 1 while the port is read as G-code (no good frame lately). */
#define fw_gcode_mode(fw) (!(fw)->binary)
/* The port found its stack's canary overwritten (from its loop, between
   passes): everything stops as after STEP_LATE (UV off, the steps dropped,
   Z unhomed, the motor off), STATUS reports error LINK_ERR_STACK and
   G-code mode says "Error:Printer halted", and the core stays halted
   until reset: every frame but HELLO and STATUS is refused with that
   error, the light and Z stay off whatever G-code asks. */
void fw_stack_fault(fw_state *fw, uint64_t now);
#endif
