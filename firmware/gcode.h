/* G-code mode: lets existing resin hosts (NanoDLP, printrun's printcore,
   Pronterface) drive the Z axis with Marlin-style G-code over serial.
   Portable C99: no float, no libm, no malloc, no stdio; all state lives in
   one fw_gcode the caller owns. The caller owns the fw_axis and steps it;
   this module only starts moves and homing and watches fw_axis_busy.

   The caller's loop:
       fw_gcode_init(&g, &axis, &io);
       for (;;) {
           used = fw_gcode_receive(&g, bytes, n);        keep bytes[used..n)
           step the axis while steps are due (fw_axis_next / fw_axis_step)
           deadline = fw_gcode_run(&g, now);             after stepping
           offer the kept bytes again; sleep until a byte or the deadline
       }
   Bounded work: fw_gcode_receive only gathers bytes into the line; each
   call of fw_gcode_run does at most one piece of work (end a move or a
   dwell with its replies, check a complete line's framing, run a checked
   line, start the move a G0/G1 asked for), each well under a step
   interval of an ATmega2560 at its top speed (gcode.c keeps to 32-bit
   arithmetic for that where values fit), and returns `now` after one so
   the caller comes back in its next pass.

   Commands (units mm and mm/min; Z is the only axis, X/Y/E words are
   ignored):
       G28            home Z; ok when homing has ended
       G90 / G91      absolute / relative Z
       G0/G1 Z F      move; F is remembered and clamped to max_speed
                      (before any F: max_speed)
       G4 P<ms>|S<s>  dwell after the moves before it; ok when it ends
                      (S wins when both are given). The first dwell after
                      M106, with no move or homing between, is the
                      exposure: it counts from M106 and the
                      port's timer puts the light out at its end, so
                      "M106 S255, G4 P3000, M107" (NanoDLP's layer) gives
                      3000 ms of light to the timer's tick, not 3000 ms
                      plus the host's round trips between the lines (a G4
                      that comes after its end puts the light out at once
                      and says "echo:Exposure ran over: G4 came <ms> ms
                      after its end")
       M17 / M18 M84  stepper driver on / off (a move turns it on)
       M106 [S] M107  UV on / off; M106 S0 is off. The light is never on
                      while Z moves: G0/G1/G28 put it out first and say
                      "echo:UV off: Z moves only in the dark". Without a
                      dwell after it, M106's light goes out when the host
                      says nothing for the link timeout ("echo:UV off: the
                      host went silent after M106"), and at the board's
                      longest exposure in any case
       M112           emergency stop, acted on as its line's last byte
                      arrives (lines held before it are dropped
                      unanswered): Z stops dead and is unhomed, UV off;
                      "echo:Emergency stop ..." and ok; M106 is refused
                      until G28 succeeds (so after a STEP_LATE or endstop
                      fault too)
       M410           quick stop, acted on the same way: Z brakes to a
                      stop (it stays homed), UV off
       M105           plain "ok" (no heaters; printcore's handshake)
       M110 [N]       set the line number
       M114           "X:0.00 Y:0.00 Z:12.345 E:0.00 Count Z:4938"
       M115           "FIRMWARE_NAME:adaslice ...", "echo:Z_MAX_MM:200.000
                      STEPS_PER_MM:400" and "echo:Z_MAX_SPEED_MM_S:2.500
                      MAX_EXPOSURE_MS:300000": the running image's own
                      figures
       M400           wait for moves
   Anything else: echo:Unknown command: "..." then ok.

   Replies. Every line that is not blank gets exactly one "ok", after any
   Error:/echo: line of its own. Blank and comment-only lines (";...",
   "(...)") get nothing, as in Marlin, which is also what makes "\r\n" one
   line end. printcore never sends blank lines while printing and only
   counts "ok" then.
     - G0/G1: ok as soon as the move has started (Marlin's "queued");
       "Z_move_comp" once the axis is idle after the move's last step, for
       every started move including one of zero length (NanoDLP waits for it).
       A refused move (not homed, soft limits, bad number) gets Error: and ok
       and no Z_move_comp, nor does a move the core cut short (Error: with
       the position instead), so a host waiting for it stops rather than
       exposing at the wrong height.
     - G28: ok when homing has ended, after "Z_move_comp" on success or
       "Error:Homing failed".
     - G4: ok when the dwell has ended.
   Commands run strictly in order: a line that arrives while a move, homing
   or dwell is under way is held and runs when it has ended, so a UV or
   dwell command never overlaps motion.

   Flow control. The module holds one complete line. While a line is held,
   fw_gcode_receive consumes nothing more and returns how many bytes it took;
   the caller keeps the rest (in its receive ring, where Marlin keeps them
   too) and offers them again after fw_gcode_run. printcore has one line in
   flight while printing, occasionally two after a resend; commands it sends
   outside a print (Pronterface's jog buttons: G91, G1, G90) are not paced,
   so they wait in the caller's buffer.

   Line numbers and checksums: "N<n> <command>*<cs>", cs the XOR of every
   byte before '*', in decimal. A numbered line without '*', with a wrong
   checksum, or whose n is not the last line + 1 (M110 excepted) is not run:
       Error:checksum mismatch, Last Line: <last>
       Error:No Checksum with line number, Last Line: <last>
       Error:Line Number is not Last Line Number+1, Last Line: <last>
   then "Resend: <last + 1>" and "ok", as Marlin. A '*' on an unnumbered
   line is checked too (Error: and ok, no Resend). The last line number
   starts at 0; printcore begins every print with "N-1 M110*15".
   Lines longer than FW_GCODE_LINE_MAX bytes are dropped whole with
   "Error:Line too long" and ok; the line number does not advance, so a
   numbered host is asked to resend when its next line arrives.

   Numbers are decimal fixed point, at most 10^7 in magnitude and 6
   decimals (a 7th rounds), so lengths are exact to the nanometre; anything
   else is an Error: reply. Replies are plain ASCII: bytes echoed from the
   host outside 0x20..0x7e become '?' (printcore stops reading at the
   first reply that is not UTF-8). */
#ifndef FW_GCODE_H
#define FW_GCODE_H
#include <stddef.h>
#include <stdint.h>
#include "motion.h"

/* Text the firmware sends: on an AVR a string literal is copied into SRAM
   (8 KiB, shared with the stack) unless it is put in flash and read from
   there, so every reply's text is FW_TEXT("...") and read through
   FW_TEXT_BYTE; elsewhere both are plain. */
#if defined(__AVR__)
#include <avr/pgmspace.h>
#define FW_TEXT(s) (__extension__({ static const char fw_text_[] PROGMEM = s; &fw_text_[0]; }))
#define FW_TEXT_BYTE(p) ((char)pgm_read_byte(p))
#else
#define FW_TEXT(s) (s)
#define FW_TEXT_BYTE(p) (*(p))
#endif

/* The longest the light may stay on at once, a board setting (board.h
   may set its own): a bottom layer's exposure is 20-60 s, so anything
   longer is a host's mistake, and a light left on is a vat of cured resin.
   Masks and EXPOSE asking for more are refused; in G-code mode it is the
   light's hard limit after M106. IDENTIFY reports it. */
#ifndef FW_EXPOSURE_MAX_MS
#define FW_EXPOSURE_MAX_MS 300000ul
#endif

/* Marlin's MAX_CMD_SIZE: the longest line, without its line end. */
#define FW_GCODE_LINE_MAX 96

typedef struct fw_gcode_io {
    void *ctx;
    /* replies to the host, one line per call; may be NULL */
    void (*write)(void *ctx, const uint8_t *data, size_t size);
    /* UV light on or off at tick `when` (M106 / M107); may be NULL */
    void (*uv)(void *ctx, int on, uint64_t when);
    /* the light M106 put on goes out at tick `when` by the port's timer (at
       once if that has passed): the end of the exposure's dwell; NULL: it
       stays on until M107 */
    void (*uv_end)(void *ctx, uint64_t when);
    /* stepper driver enable (M17 / M18 / M84); may be NULL */
    void (*motor)(void *ctx, int on);
    /* 1 while Z still moves: steps computed but not yet out (a step queue);
       NULL: while the axis is busy */
    int (*moving)(void *ctx);
} fw_gcode_io;

typedef struct fw_gcode { /* fields private to gcode.c */
    fw_axis *axis;
    fw_gcode_io io;
    uint8_t line[FW_GCODE_LINE_MAX];
    uint8_t len;             /* bytes in line; FW_GCODE_LINE_MAX + 1: it outgrew `line` */
    uint8_t held;            /* line is complete and waits (1), or passed its check (2) */
    uint8_t command;         /* a checked line: where its command begins (after N) */
    uint8_t relative;        /* G91 */
    uint8_t wait;            /* what the last command still waits for */
    uint8_t motor_on;        /* as last set through io.motor */
    uint8_t lit;             /* M106 put the light on; no dwell has ended it */
    uint8_t halted;          /* an emergency stop or a fault: no light until G28 */
    int32_t last_line;       /* N of the last numbered line accepted */
    int32_t target;          /* steps: where the move under way ends */
    uint32_t speed;          /* steps/s from the last F; 0: max_speed */
    int64_t z_nm;            /* commanded Z, nm, valid while the axis is at it */
    uint64_t deadline;       /* tick a dwell ends */
    uint64_t lit_at;         /* tick of the last M106 / M107 */
} fw_gcode;

/* The axis must outlive g; io is copied. Sends nothing. */
void fw_gcode_init(fw_gcode *g, fw_axis *axis, const fw_gcode_io *io);
/* Bytes from the host, in order, up to the end of a line: returns how many
   it consumed, all of them unless a line is complete, which waits for
   fw_gcode_run (see Flow control above). */
size_t fw_gcode_receive(fw_gcode *g, const uint8_t *data, size_t size);
/* Call after stepping the axis and at the returned deadline: one piece of
   work (Bounded work above): ends a dwell, sends Z_move_comp and the ok of
   G28, checks or runs the held line, or starts the move a G0/G1 asked for.
   Returns the tick it next needs a call: `now` after a piece of work, the
   dwell's end, or the axis's next step while a move (its own or the
   core's) keeps a command or a held line waiting; FW_NEVER when only a
   byte from the host can change anything. */
uint64_t fw_gcode_run(fw_gcode *g, uint64_t now);
/* Forgets the held line and a G0/G1's move not yet started: the port was
   taken by a binary host, so those bytes were not G-code. */
void fw_gcode_drop(fw_gcode *g);
/* One reply line (text: FW_TEXT), its newline added: for the caller's own
   replies in G-code mode (faults, emergency stops). */
void fw_gcode_say(fw_gcode *g, const char *text);
/* The caller put the light out (an emergency stop, a quick stop, a fault);
   halted: it also stopped Z dead, which lost the position, so M106 is
   refused until G28 succeeds. What the command under way waits for ends as
   it would (a move's Error: line, a homing's failure, a dwell's ok). */
void fw_gcode_dark(fw_gcode *g, int halted);
/* The light M106 left on with no dwell to end it goes out once the host
   has said nothing for `timeout` ticks since `heard` (the tick of its
   last byte) and since M106, as Klipper's max_duration: a host that died
   mid-exposure leaves a dark vat. Returns the tick it next needs a call,
   FW_NEVER while the light is not M106's. */
uint64_t fw_gcode_watch(fw_gcode *g, uint64_t heard, uint64_t timeout, uint64_t now);
#endif
