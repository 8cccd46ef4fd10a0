/* The Z axis: trapezoidal step timing in integers, homing to an endstop,
   soft limits. Portable C99: no float, no libm, no malloc, no stdio.

   Time is a 64-bit tick count at `tick_hz` ticks per second, supplied by the
   caller. Every step is scheduled at an absolute tick computed in closed form
   from the start of its move, so rounding never accumulates and a late call
   never stretches the rest of the move.

   The caller's loop:
       while (fw_axis_busy(&axis)) {
           wait until now >= fw_axis_next(&axis);
           int dir = fw_axis_step(&axis, endstop_pressed());
           pulse the step pin with the direction pin set to dir (+1 up, -1 down)
       }
   Position 0 is where homing found the endstop; up is positive. */
#ifndef FW_MOTION_H
#define FW_MOTION_H
#include <stdint.h>

#define FW_NEVER UINT64_MAX

/* A function a compiler must not inline (where it would otherwise inline
   one called once): its locals, or its registers saved, would weigh on
   every call of the function around it. */
#if defined(__GNUC__)
#define FW_NOINLINE __attribute__((noinline))
#else
#define FW_NOINLINE
#endif

typedef struct fw_axis_config {
    uint32_t steps_per_mm;   /* steps per millimetre of Z */
    uint32_t max_speed;      /* steps per second, every move */
    uint32_t accel;          /* steps per second squared, every move */
    uint32_t home_speed;     /* steps per second of homing's fast approach */
    int32_t max_steps;       /* soft limit: moves must stay in [0, max_steps] */
    int32_t home_travel;     /* the longest approach homing tries, steps */
} fw_axis_config;

enum {
    FW_AXIS_OK = 0,
    FW_AXIS_BUSY,        /* a move is under way */
    FW_AXIS_NOT_HOMED,   /* moves need a homed axis */
    FW_AXIS_LIMIT,       /* the target is outside [0, max_steps] */
    FW_AXIS_HOME_FAILED  /* the endstop never closed (or never opened) */
};

/* Limits fw_axis_init applies to the config it keeps (see motion.c for the
   arithmetic): accel >= 2; max_speed >= 1, and lowered, if need be, until a
   ramp to it lasts under 2^32 ticks (max_speed <= accel * (2^32 - 1) /
   tick_hz, e.g. 59,652 steps/s at 72 MHz and 1000 steps/s^2), which keeps
   every step's tick exact in 64 bits; home_speed 0 or above max_speed means
   max_speed; max_steps and home_travel within [0, FW_AXIS_MAX_TRAVEL] so
   positions cannot overflow. Ticks must stay below 2^62.

   Moves need a homed axis: a printer must know where the vat is before it
   moves. Homing clears `homed` when it starts; it sets it again only on
   success, so a failed or halted homing leaves the axis unhomed. */
#define FW_AXIS_MAX_TRAVEL ((int32_t)1 << 30)
/* Switch travel homing allows, beyond the approach's braking distance, for
   backing off the switch before it gives up. */
#define FW_AXIS_HOME_BACKOFF_MM 2u

typedef struct fw_axis { /* fields private to motion.c; position, homed,
                            error, config and tick_hz may be read */
    fw_axis_config config;   /* as given, after init's limits */
    uint32_t tick_hz;
    int32_t position;        /* steps; valid once homed */
    int homed;
    int error;               /* FW_AXIS_HOME_FAILED after a failed homing */
    /* from the config */
    uint64_t k_quot;         /* tick_hz^2 = k_quot * accel + k_rem */
    uint32_t k_rem;
    uint32_t square_step;    /* 2 k_quot if k_rem is 0 and it fits 32 bits, else 0 */
    uint64_t half_k;         /* floor(tick_hz^2 / (2 accel)) */
    uint64_t half_k_up;      /* the same rounded up */
    uint32_t min_interval;   /* the shortest interval any step may follow */
    uint32_t rest_interval;  /* the interval of a step from rest: homing's
                                slow speed and the pause between moves */
    uint32_t home_interval;  /* the fast approach's cruising interval */
    uint32_t start_lead;     /* ticks from a move's start to its first step at the
                                earliest (0 after init; a caller whose steps go
                                through a timer sets the time it needs to arm it) */
    uint32_t backoff_limit;  /* steps homing may take off the switch */
    /* the move under way: step j (0-based) of `steps` at start + t(j) */
    int dir;                 /* +1, -1; 0 when idle */
    uint32_t steps, done;    /* steps of the move, steps issued */
    uint32_t ramp;           /* steps 0..ramp follow the accelerating form */
    uint32_t interval;       /* ticks per step while cruising */
    uint64_t offset;         /* cruising step j at j * interval + offset */
    uint64_t end;            /* the mirror: t(j) = end - t(steps - 1 - j) */
    uint64_t start;          /* tick of the move's first step */
    uint64_t next;           /* tick of the next step, FW_NEVER when idle */
    uint64_t last;           /* tick of the latest step, if `stepped` */
    /* the accelerating form's last values (motion.c's ramp_ticks): A(i) for
       i = root_lo .. root_lo + roots - 1 */
    uint32_t root_lo, root[3];
    uint8_t roots;
    uint8_t stepped;
    /* homing */
    uint8_t phase;           /* homing's phase, 0 outside homing */
    uint8_t seen;            /* the switch has been seen closed */
    uint32_t count;          /* slow steps of the phase */
} fw_axis;

void fw_axis_init(fw_axis *axis, const fw_axis_config *config, uint32_t tick_hz);
/* Starts a move to `target` steps at up to `speed` steps/s (0 or above
   max_speed: max_speed) at tick `now`. FW_AXIS_OK or why not (BUSY, then
   NOT_HOMED, then LIMIT); nothing changes when refused. A move to where the
   axis stands is FW_AXIS_OK with no step. The first step is at `now`, or
   later if the axis stepped less than a step-from-rest interval before:
   the axis came to rest at that step and may be turning round. */
int fw_axis_move_to(fw_axis *axis, int32_t target, uint32_t speed, uint64_t now);
/* Starts homing at tick `now` (FW_AXIS_OK, or FW_AXIS_BUSY). Off the switch
   first if it is closed; then down at home_speed, braking within `accel`
   once the switch closes (overshooting a little); then up one step at a
   time until it opens and down one step at a time until it closes again:
   there is 0. The one-step phases go at a speed the axis may start and stop
   dead at, sqrt(accel / 2) steps/s at most. FW_AXIS_HOME_FAILED in `error`
   and not homed when home_travel steps down never close the switch, or when
   backing off or coming back takes more than the braking distance plus
   FW_AXIS_HOME_BACKOFF_MM. */
int fw_axis_home(fw_axis *axis, uint64_t now);
/* Brings a move to a stop within the acceleration limit as soon as it can;
   the axis stays homed and its position stays exact. Homing stops the same
   way (its one-step phases at once) and leaves the axis unhomed. */
void fw_axis_halt(fw_axis *axis, uint64_t now);
/* Ends a move or homing at once, without braking, and leaves the axis
   unhomed: for faults, when steps can no longer be issued on time (a motor
   stopped dead from speed may have lost steps, so the position is unknown). */
void fw_axis_stop(fw_axis *axis);
int fw_axis_busy(const fw_axis *axis);
/* 1 while homing (any of its phases). */
int fw_axis_homing(const fw_axis *axis);
/* 1 in homing's one-step phases: each step is decided by the switch read
   after the step before it went out, so none may be queued ahead. */
int fw_axis_one_step(const fw_axis *axis);
/* Tick of the next step, FW_NEVER when idle. */
uint64_t fw_axis_next(const fw_axis *axis);
/* Takes the step due at fw_axis_next(): +1 or -1 for the pin; 0 when the
   step is not taken (homing reacting to the endstop). `endstop`: 1 while the
   switch is closed, read just before the call. The step's tick is then in
   `last`: homing turning from one phase to the next can put it later than
   fw_axis_next() said (a step from rest waits its interval). */
int fw_axis_step(fw_axis *axis, int endstop);
/* Steps for `nm` nanometres, rounded to nearest (exact integers, no drift). */
int32_t fw_axis_steps_of_nm(const fw_axis *axis, uint64_t nm);
#endif
