/* The Z axis: see motion.h for the interface.

   A move of n steps is the ideal trapezoid over n - 1 steps of distance,
   sampled where it crosses each whole step and rounded up to a tick: the
   first step is at the move's start, where the axis is at rest, and the
   last one where it comes to rest again. With T = tick_hz, a = accel and a
   cruising interval of c ticks (speed T/c), step j is at

       accelerating, j <= ramp:   ceil(sqrt(2 j T^2 / a))
       cruising:                  j c + ceil(T^2 / (2 a c))
       decelerating:              end - t(n - 1 - j),  end = (n-1) c + 2 ceil(T^2 / (2 a c))

   where ramp = floor(T^2 / (2 a c^2)) is the last step before the ideal
   trapezoid reaches its speed. Each form is the ceiling of the ideal time,
   and ceil(x + c) = ceil(x) + c for whole c: where the ideal allows no
   interval under c ticks, none of the rounded intervals is under c either.
   So no clamp is needed. The deceleration is the acceleration's exact
   mirror; `end` is chosen so that mirroring the cruise reproduces it.

   A move too short to reach its speed cruises at the smallest longer
   interval whose ramps fit (ramp <= (n - 2) / 2) instead of being cut into
   a triangle: mirroring rounded ramps about a peak between two steps can
   leave the middle interval a tick under c, while this keeps the forms
   above and their proof. When the ideal would peak between the middle
   steps, their interval comes out a little longer than c: the axis slows
   slightly there, which the limit allows.

   Bounds: T^2 < 2^64 as T is 32 bits. The accelerating form needs
   2 j T^2 / a < 2^64 for j <= ramp, that is (T^2 / (a c))^2 < 2^64; init
   keeps c large enough that T^2 / (a c) < 2^32 (a ramp lasts under 2^32
   ticks). Cruising ticks j c stay below 2^62 since moves are under 2^30
   steps (FW_AXIS_MAX_TRAVEL) and c <= T < 2^32. */
#include "motion.h"

enum { PHASE_NONE, PHASE_PROBE, PHASE_APPROACH, PHASE_BACKOFF, PHASE_SLOW };

/* floor(sqrt(x)) for x < 2^32, one result bit per round, no division: in
   32 bits, which an 8-bit core does several times faster than 64. */
static uint32_t floor_sqrt32(uint32_t x)
{
    uint32_t root = 0, bit = (uint32_t)1 << 30;
    while (bit > x) bit >>= 2;
    while (bit) {
        if (x >= root + bit) {
            x -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    return root;
}

/* a * b for a, b < 2^32: written so that a compiler for a small core uses
   its widening 32 x 32 -> 64 multiplication (avr-gcc's __umulsidi3) rather
   than a full 64-bit one. */
static uint64_t mul32(uint32_t a, uint32_t b) { return (uint64_t)a * b; }

/* 32-bit division when both fit: the same quotient, a fraction of the
   cycles of a 64-bit one on a small core (and on the Cortex-M3, UDIV). */
static uint64_t div64(uint64_t x, uint64_t y)
{
    if (((x | y) >> 32) == 0) return (uint32_t)x / (uint32_t)y;
    return x / y;
}

/* Above 2^32: the root of x's top 30 to 32 bits, shifted back, is within
   2^k of the root (k the half shift), one Newton step from below brings it
   within 2 above, and the squares settle it. Same result as one bit per
   round in 64 bits, in about half the time on an 8-bit core. */
static uint64_t floor_sqrt(uint64_t x)
{
    unsigned k = 1;
    uint64_t s, e;
    if (x <= 0xFFFFFFFFu) return floor_sqrt32((uint32_t)x);
    while ((x >> (2u * k)) > 0xFFFFFFFFu) k++;
    s = (uint64_t)floor_sqrt32((uint32_t)(x >> (2u * k))) << k; /* s * s <= x, s < 2^32 */
    e = x - mul32((uint32_t)s, (uint32_t)s);
    s += div64(e, 2u * s); /* e is small: 32 bits as a rule */
    if (s > 0xFFFFFFFFu) s = 0xFFFFFFFFu;
    while (mul32((uint32_t)s, (uint32_t)s) > x) s--;
    return s;
}

/* Smallest t with t * t >= x; x < 2^64 so t <= 2^32 and t * t for the
   floor fits. */
static uint64_t ceil_sqrt(uint64_t x)
{
    uint64_t s = floor_sqrt(x);
    /* s <= 2^32 - 1 as x < 2^64 */
    return mul32((uint32_t)s, (uint32_t)s) < x ? s + 1 : s;
}

static uint64_t ceil_div(uint64_t x, uint64_t y)
{
    if (x == 0) return 0; /* T^2 is often a multiple of accel: k_rem 0 */
    if (((x | y) >> 32) == 0) {
        uint32_t a = (uint32_t)x, b = (uint32_t)y;
        return a / b + (a % b != 0);
    }
    return x / y + (x % y != 0);
}

/* The same, searched from `guess`: the result is still the least t with
   t * t >= x, whatever the guess. A step's tick is its extrapolation from
   the three before give or take a few ticks past a ramp's first few dozen
   steps; short ramps (an 8-bit core's, two dozen steps at its top speed)
   miss by tens to hundreds. One Newton step from the guess, t - g being
   about (x - g^2) / 2g, brings a miss within a tick or two, and the search
   walks the squares by adding 2g + 1: one multiplication and at most one
   32-bit division where the root costs 30 rounds. */
static uint64_t ceil_sqrt_near(uint64_t x, uint64_t guess)
{
    int tries;
    uint32_t g;
    uint64_t sq, off;
    if (guess == 0 || guess >= 0xFFFFFFFFu) return ceil_sqrt(x);
    g = (uint32_t)guess;
    sq = mul32(g, g);
    off = sq < x ? x - sq : sq - x;
    if (off > 8u * (uint64_t)g) { /* more than about 4 off */
        uint64_t step;
        if (off >> 32) return ceil_sqrt(x);
        step = div64(off, 2u * (uint64_t)g); /* from above: < g / 2 */
        if (sq < x && step >= 0xFFFFFFFFu - g) return ceil_sqrt(x);
        g = sq < x ? g + (uint32_t)step : g - (uint32_t)step;
        sq = mul32(g, g);
    }
    for (tries = 0; tries < 4; tries++) {
        if (sq < x) { /* (g + 1)^2 */
            sq += 2u * (uint64_t)g + 1u;
            g++;
        } else if (sq - 2u * (uint64_t)g + 1u >= x) { /* (g - 1)^2 >= x; g >= 1 here */
            sq -= 2u * (uint64_t)g - 1u;
            g--;
        } else {
            return g;
        }
        if (g == 0 || g == 0xFFFFFFFFu) break;
    }
    return ceil_sqrt(x);
}

/* Ticks from the start to accelerating step j: the least t with
   t^2 >= 2 j T^2 / a. T^2 is split as k_quot a + k_rem so that the
   ceiling of 2 j T^2 / a is exact without a 128-bit product; 2 j k_rem
   < T^2 / c^2 fits as j <= ramp (or j = 1). `guess` only saves time (0:
   none). */
static uint64_t accel_ticks(const fw_axis *axis, uint32_t j, uint64_t guess)
{
    uint64_t twice = 2u * (uint64_t)j, quot, rem;
    if (((twice | axis->k_quot | axis->k_rem) >> 32) == 0) {
        quot = mul32((uint32_t)twice, (uint32_t)axis->k_quot);
        rem = axis->k_rem ? mul32((uint32_t)twice, (uint32_t)axis->k_rem) : 0; /* 0 when a divides T^2 */
    } else {
        quot = twice * axis->k_quot;
        rem = twice * axis->k_rem;
    }
    return ceil_sqrt_near(quot + ceil_div(rem, axis->config.accel), guess);
}

/* The first half's form: accelerating, then cruising. */
static uint64_t rising_ticks(const fw_axis *axis, uint32_t j, uint64_t guess)
{
    if (j <= axis->ramp) return accel_ticks(axis, j, guess);
    return mul32(j, axis->interval) + axis->offset;
}

/* `guess`: roughly step j's ticks, or 0. */
static uint64_t step_ticks(const fw_axis *axis, uint32_t j, uint64_t guess)
{
    uint32_t last = axis->steps - 1;
    if (2u * (uint64_t)j <= last) return rising_ticks(axis, j, guess);
    return axis->end - rising_ticks(axis, last - j, guess && guess < axis->end ? axis->end - guess : 0);
}

/* Step `done`'s ticks, guessed from the three steps before it (the last
   at `latest`) by their second difference, which changes slowly. */
static uint64_t next_ticks(const fw_axis *axis, uint64_t latest)
{
    uint64_t guess = 0;
    if (axis->done >= 3) {
        uint64_t up = latest + 2 * (latest - axis->latest), down = axis->latest - axis->earlier;
        if (up > down) guess = up - down;
    }
    return step_ticks(axis, axis->done, guess);
}

/* The trapezoid's constants for cruising at `interval` ticks per step. */
static uint32_t ramp_of(const fw_axis *axis, uint64_t interval)
{
    return (uint32_t)div64(div64(axis->half_k, interval), interval);
}

static void shape(fw_axis *axis, uint64_t interval)
{
    uint32_t distance = axis->steps - 1, ramp = ramp_of(axis, interval);
    if (distance > 0) {
        /* ramps that do not fit (ramp > m, i.e. half_k / c^2 >= m + 1):
           the smallest interval whose ramps fit. Tested on the ramp, so a
           move long enough to reach its speed takes no root */
        uint32_t m = (distance - 1) / 2;
        if (ramp > m) {
            interval = ceil_sqrt(div64(axis->half_k, (uint64_t)m + 1) + 1);
            ramp = ramp_of(axis, interval);
        }
    }
    axis->interval = (uint32_t)interval;
    axis->ramp = ramp;
    axis->offset = ceil_div(axis->half_k_up, interval);
    axis->end = (uint64_t)distance * interval + 2u * axis->offset;
}

static void go_idle(fw_axis *axis)
{
    axis->dir = 0;
    axis->steps = axis->done = 0;
    axis->next = FW_NEVER;
    axis->phase = PHASE_NONE;
}

/* At rest the axis has just stepped: the next step is a step from rest, so
   it waits at least the interval that a step from rest needs. */
static uint64_t earliest(const fw_axis *axis, uint64_t now)
{
    if (axis->stepped && now < axis->last + axis->rest_interval) return axis->last + axis->rest_interval;
    return now;
}

/* The first step is at the start, whatever the trapezoid: it is shaped
   when that step is taken (take_step), so starting a move costs no
   division, and a caller that budgets the steps it computes in a pass
   budgets the shaping with them. `interval` waits in axis->interval. */
static void begin_move(fw_axis *axis, int dir, uint32_t steps, uint64_t interval, uint64_t now)
{
    axis->dir = dir;
    axis->steps = steps;
    axis->done = 0;
    axis->interval = (uint32_t)interval;
    axis->start = earliest(axis, now);
    axis->next = axis->start;
}

static uint64_t interval_of(const fw_axis *axis, uint32_t speed)
{
    uint64_t c;
    if (speed == 0 || speed > axis->config.max_speed) speed = axis->config.max_speed;
    c = ceil_div(axis->tick_hz, speed);
    return c < axis->min_interval ? axis->min_interval : c;
}

static void fail_homing(fw_axis *axis)
{
    axis->error = FW_AXIS_HOME_FAILED;
    axis->homed = 0;
    go_idle(axis);
}

/* A move's last step has been taken, or a halt left nothing to take. */
static void move_over(fw_axis *axis)
{
    if (axis->phase == PHASE_APPROACH) {
        /* the switch is read once more at rest: it may have closed on the
           last step, and backing off starts from rest */
        axis->phase = PHASE_BACKOFF;
        axis->count = 0;
        axis->steps = axis->done = 0;
        axis->next = earliest(axis, axis->last);
    } else {
        go_idle(axis);
    }
}

static int take_step(fw_axis *axis)
{
    int dir = axis->dir;
    if (axis->done == 0) shape(axis, axis->interval);
    axis->position += dir;
    axis->last = axis->next;
    axis->stepped = 1;
    axis->done++;
    if (axis->done >= axis->steps) {
        move_over(axis);
    } else {
        uint64_t latest = axis->next - axis->start;
        axis->next = axis->start + next_ticks(axis, latest);
        axis->earlier = axis->latest;
        axis->latest = latest;
    }
    return dir;
}

/* Shortens the move so it decelerates from its latest step on. The steps
   already taken keep their ticks under the new shape, so the velocity the
   axis has is the one the deceleration starts from. */
static void brake(fw_axis *axis)
{
    uint32_t p, distance;
    if (axis->done == 0) { /* not started: nothing moves */
        axis->steps = 0;
        move_over(axis);
        return;
    }
    p = axis->done - 1;
    distance = axis->steps - 1;
    if (distance - p <= axis->ramp) return; /* decelerating already */
    if (p <= axis->ramp) {
        /* accelerating: the way down mirrors the way up about step p, which
           is exactly the braking distance from the speed reached at p */
        axis->steps = 2 * p + 1;
        axis->end = 2 * accel_ticks(axis, p, axis->latest);
    } else {
        /* cruising: the deceleration's first step follows step p */
        uint32_t stop = p + axis->ramp + 1;
        if (stop >= distance) return;
        axis->steps = stop + 1;
        axis->end = (uint64_t)stop * axis->interval + 2u * axis->offset;
    }
    /* the guess (one more interval like the last) only saves time: the
       step after the peak mirrors the one before it */
    if (axis->done >= axis->steps) move_over(axis);
    else axis->next = axis->start + step_ticks(axis, axis->done, 2u * axis->latest - axis->earlier);
}

void fw_axis_init(fw_axis *axis, const fw_axis_config *config, uint32_t tick_hz)
{
    uint64_t t2, min_c, ramp_c;
    fw_axis_config *c = &axis->config;
    axis->config = *config;
    axis->tick_hz = tick_hz ? tick_hz : 1;
    /* accel 1 could make 2 T^2 / a overflow; 2 steps/s^2 is slow enough */
    if (c->accel < 2) c->accel = 2;
    if (c->max_speed == 0) c->max_speed = 1;
    if (c->max_steps < 0) c->max_steps = 0;
    if (c->max_steps > FW_AXIS_MAX_TRAVEL) c->max_steps = FW_AXIS_MAX_TRAVEL;
    if (c->home_travel < 0) c->home_travel = 0;
    if (c->home_travel > FW_AXIS_MAX_TRAVEL) c->home_travel = FW_AXIS_MAX_TRAVEL;
    t2 = (uint64_t)axis->tick_hz * axis->tick_hz;
    axis->k_quot = t2 / c->accel;
    axis->k_rem = t2 % c->accel;
    axis->half_k = t2 / (2u * (uint64_t)c->accel);
    axis->half_k_up = ceil_div(t2, 2u * (uint64_t)c->accel);
    /* T^2 / (a c) <= 2^32 - 1 keeps the accelerating form in 64 bits */
    min_c = ceil_div(axis->tick_hz, c->max_speed);
    ramp_c = ceil_div(ceil_div(t2, c->accel), 0xFFFFFFFFu);
    if (ramp_c > min_c) {
        min_c = ramp_c;
        c->max_speed = (uint32_t)(axis->tick_hz / min_c);
    }
    axis->min_interval = (uint32_t)min_c;
    if (c->home_speed == 0 || c->home_speed > c->max_speed) c->home_speed = c->max_speed;
    axis->home_interval = (uint32_t)interval_of(axis, c->home_speed);
    /* a step from rest, then one after t: the mean speed 1/t over the
       interval is reached at t/2, which needs 2/t^2 <= a */
    axis->rest_interval = (uint32_t)accel_ticks(axis, 1, 0);
    if (axis->rest_interval < min_c) axis->rest_interval = (uint32_t)min_c;
    {
        /* the approach brakes over about its ramp, then the switch may
           need some travel to open again */
        uint64_t limit = axis->half_k / axis->home_interval / axis->home_interval + 2u +
                         (uint64_t)FW_AXIS_HOME_BACKOFF_MM * c->steps_per_mm;
        axis->backoff_limit = limit > FW_AXIS_MAX_TRAVEL ? (uint32_t)FW_AXIS_MAX_TRAVEL : (uint32_t)limit;
    }
    axis->position = 0;
    axis->homed = 0;
    axis->error = FW_AXIS_OK;
    axis->last = 0;
    axis->stepped = 0;
    axis->start = 0;
    axis->seen = 0;
    axis->count = 0;
    axis->interval = (uint32_t)min_c;
    axis->start_lead = 0;
    axis->offset = axis->end = axis->latest = axis->earlier = 0;
    go_idle(axis);
}

int fw_axis_move_to(fw_axis *axis, int32_t target, uint32_t speed, uint64_t now)
{
    int64_t delta;
    if (fw_axis_busy(axis)) return FW_AXIS_BUSY;
    if (!axis->homed) return FW_AXIS_NOT_HOMED;
    if (target < 0 || target > axis->config.max_steps) return FW_AXIS_LIMIT;
    delta = (int64_t)target - axis->position;
    if (delta == 0) return FW_AXIS_OK;
    begin_move(axis, delta > 0 ? 1 : -1, (uint32_t)(delta > 0 ? delta : -delta), interval_of(axis, speed),
               now + axis->start_lead);
    return FW_AXIS_OK;
}

/* Homing invalidates the position until it finds the switch again, so a
   homing that fails or is halted leaves the axis unhomed. */
int fw_axis_home(fw_axis *axis, uint64_t now)
{
    if (fw_axis_busy(axis)) return FW_AXIS_BUSY;
    axis->homed = 0;
    axis->error = FW_AXIS_OK;
    axis->position = 0;
    axis->phase = PHASE_PROBE;
    axis->seen = 0;
    axis->count = 0;
    axis->dir = 0;
    axis->steps = axis->done = 0;
    axis->next = earliest(axis, now + axis->start_lead);
    return FW_AXIS_OK;
}

/* The schedule hangs on the latest step, not on `now`: the axis has not
   moved since it, however late the halt comes. */
void fw_axis_halt(fw_axis *axis, uint64_t now)
{
    (void)now;
    if (!fw_axis_busy(axis)) return;
    if (axis->phase == PHASE_APPROACH) {
        axis->phase = PHASE_NONE;
        brake(axis);
    } else if (axis->phase != PHASE_NONE) {
        /* probing or creeping at the speed that may stop dead */
        go_idle(axis);
    } else {
        brake(axis);
    }
}

void fw_axis_stop(fw_axis *axis)
{
    go_idle(axis);
    axis->homed = 0;
}

int fw_axis_busy(const fw_axis *axis) { return axis->next != FW_NEVER; }

int fw_axis_homing(const fw_axis *axis) { return axis->phase != PHASE_NONE; }

int fw_axis_one_step(const fw_axis *axis) { return axis->phase != PHASE_NONE && axis->phase != PHASE_APPROACH; }

uint64_t fw_axis_next(const fw_axis *axis) { return axis->next; }

/* One step of homing's slow phases, at the speed that may start and stop
   dead. */
static int creep(fw_axis *axis, int dir)
{
    axis->position += dir;
    axis->last = axis->next;
    axis->stepped = 1;
    axis->count++;
    axis->next += axis->rest_interval;
    return dir;
}

int fw_axis_step(fw_axis *axis, int endstop)
{
    if (!fw_axis_busy(axis)) return 0;
    switch (axis->phase) {
    case PHASE_PROBE:
        if (endstop) { /* on the switch already: off it first */
            axis->seen = 1;
            axis->phase = PHASE_BACKOFF;
            axis->count = 0;
            return creep(axis, 1);
        }
        if (axis->config.home_travel == 0) {
            fail_homing(axis);
            return 0;
        }
        axis->phase = PHASE_APPROACH;
        begin_move(axis, -1, (uint32_t)axis->config.home_travel, axis->home_interval, axis->next);
        return take_step(axis);
    case PHASE_APPROACH:
        if (endstop && !axis->seen) {
            /* this step waits: the braking schedule decides when */
            axis->seen = 1;
            brake(axis);
            return 0;
        }
        return take_step(axis);
    case PHASE_BACKOFF:
        if (endstop) {
            axis->seen = 1;
            if (axis->count >= axis->backoff_limit) {
                fail_homing(axis);
                return 0;
            }
            return creep(axis, 1);
        }
        if (!axis->seen) { /* the approach ran out without the switch */
            fail_homing(axis);
            return 0;
        }
        axis->phase = PHASE_SLOW;
        axis->count = 0;
        return creep(axis, -1);
    case PHASE_SLOW:
        if (endstop) {
            axis->position = 0;
            axis->homed = 1;
            go_idle(axis);
            return 0;
        }
        if (axis->count >= axis->backoff_limit) {
            fail_homing(axis);
            return 0;
        }
        return creep(axis, -1);
    default:
        return take_step(axis);
    }
}

int32_t fw_axis_steps_of_nm(const fw_axis *axis, uint64_t nm)
{
    uint64_t per_mm = axis->config.steps_per_mm, mm, rest, whole, steps;
    /* in 32 bits when nm fits, as heights do (4 m): on an 8-bit core a
       64-bit division is thousands of cycles */
    if (nm >> 32) { mm = nm / 1000000u; rest = nm % 1000000u; }
    else { mm = (uint32_t)nm / 1000000u; rest = (uint32_t)nm % 1000000u; }
    if (per_mm == 0) return 0;
    /* whole millimetres exactly, then the rest rounded: rest * per_mm
       < 10^6 * 2^32 fits */
    if (mm >> 32) return INT32_MAX;
    whole = mul32((uint32_t)mm, (uint32_t)per_mm);
    if (whole > (uint64_t)INT32_MAX) return INT32_MAX;
    steps = whole + div64(rest * per_mm + 500000u, 1000000u);
    return steps > (uint64_t)INT32_MAX ? INT32_MAX : (int32_t)steps;
}
