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

/* The same, searched from `guess` (0: none): the result is still the
   least t with t * t >= x, whatever the guess. The ramps' guesses
   (ramp_ticks) are a tick or two off past their first few dozen steps, and
   tens to hundreds before: one Newton step, t - g being about
   (x - g^2) / 2g, brings a miss within a tick or two. Then the search walks
   the squares by 2g + 1 in 32 bits (an 8-bit core does 32 bits several
   times faster than 64), for roots under 2^26 (a ramp of 0.9 s at 72 MHz,
   33 s at 2 MHz; longer ones take the full root): one multiplication, at
   most one 32-bit division where the root costs 30 rounds. */
static uint64_t ceil_sqrt_near(uint64_t x, uint64_t guess)
{
    int tries;
    uint32_t g;
    int32_t d; /* g^2 - x */
    uint64_t sq, off;
    if (guess == 0 || guess >= (uint32_t)1 << 26) return ceil_sqrt(x);
    g = (uint32_t)guess;
    sq = mul32(g, g);
    off = sq < x ? x - sq : sq - x;
    if (off > 8u * (uint64_t)g) { /* more than about 4 off */
        uint32_t step;
        if (off > 0xFFFFFFFFu) return ceil_sqrt(x);
        step = (uint32_t)off / (2u * g); /* from above: < g / 2 */
        if (sq < x && step >= ((uint32_t)1 << 26) - g) return ceil_sqrt(x);
        g = sq < x ? g + step : g - step;
        sq = mul32(g, g);
        off = sq < x ? x - sq : sq - x;
        if (off > 8u * (uint64_t)g) return ceil_sqrt(x);
    }
    /* |d| <= 8g < 2^29, and each move below adds less than 2^27 */
    d = sq < x ? -(int32_t)off : (int32_t)off;
    for (tries = 0; tries < 6; tries++) {
        if (d < 0) { /* (g + 1)^2 */
            d += (int32_t)(2u * g + 1u);
            g++;
        } else if ((uint32_t)d >= 2u * g - 1u) { /* (g - 1)^2 >= x; g >= 1 as x > 0 or d > 0 */
            d -= (int32_t)(2u * g - 1u);
            g--;
        } else {
            return g;
        }
    }
    return ceil_sqrt(x);
}

/* X_i = ceil(2 i T^2 / a), the accelerating form's square at step i. T^2
   is split as k_quot a + k_rem so that the ceiling is exact without a
   128-bit product; 2 i k_rem < T^2 / c^2 fits as i <= ramp (or i = 1). */
static uint64_t ramp_square(const fw_axis *axis, uint32_t i)
{
    uint64_t twice = 2u * (uint64_t)i;
    if (axis->square_step) return mul32(i, axis->square_step); /* a divides T^2, as it often does */
    if (twice <= 0xFFFFFFFFu && axis->k_quot <= 0xFFFFFFFFu)
        return mul32((uint32_t)twice, (uint32_t)axis->k_quot) + ceil_div(mul32((uint32_t)twice, axis->k_rem), axis->config.accel);
    return twice * axis->k_quot + ceil_div(twice * axis->k_rem, axis->config.accel);
}

/* A(i) = ceil(sqrt(X_i)): ticks from a move's start to its accelerating
   step i, and from decelerating step n - 1 - i to its end. A depends on i
   alone, and the ramps ask for the i next to the last ones (up the
   accelerating ramp, down the decelerating one, back down after a brake,
   from 1 again at the next move), so the last three values are kept
   (root_lo .. root_lo + roots - 1) and the root is searched from their
   extrapolation by the second difference, which changes slowly: a tick
   or two off past a ramp's first few dozen steps. A ramp lasts under 2^32
   ticks (init), so the values are 32 bits. */
static uint32_t ramp_ticks(fw_axis *axis, uint32_t i)
{
    uint32_t lo = axis->root_lo, n = axis->roots, *v = axis->root, t, guess = 0;
    if (i >= lo && i - lo < n) return v[i - lo];
    /* the guesses in 32 bits: ceil_sqrt_near searches from roots under 2^26 */
    if (i == lo + n) { /* up: v[n - 1] + d1 + (d1 - d0), the differences below it */
        if (v[n - 1] < (uint32_t)1 << 26) guess = n == 3 ? v[2] + 2u * (v[2] - v[1]) - (v[1] - v[0]) : n == 2 ? 2u * v[1] - v[0] : 0;
        t = (uint32_t)ceil_sqrt_near(ramp_square(axis, i), guess);
        if (n == 3) { v[0] = v[1]; v[1] = v[2]; v[2] = t; axis->root_lo = lo + 1u; }
        else { v[n] = t; axis->roots = (uint8_t)(n + 1u); }
    } else if (i + 1u == lo) { /* down: v[0] - d0 - (d0 - d1), the differences above it */
        uint32_t below = n == 3 ? 2u * (v[1] - v[0]) - (v[2] - v[1]) : n == 2 ? v[1] - v[0] : 0;
        if (v[n - 1] < (uint32_t)1 << 26 && below < v[0]) guess = v[0] - below;
        t = (uint32_t)ceil_sqrt_near(ramp_square(axis, i), guess);
        v[2] = v[1];
        v[1] = v[0];
        v[0] = t;
        axis->root_lo = i;
        if (n < 3) axis->roots = (uint8_t)(n + 1u);
    } else {
        t = (uint32_t)ceil_sqrt(ramp_square(axis, i));
        v[0] = t;
        axis->root_lo = i;
        axis->roots = 1;
    }
    return t;
}

/* The first half's form: accelerating, then cruising. */
static uint64_t rising_ticks(fw_axis *axis, uint32_t j)
{
    if (j <= axis->ramp) return ramp_ticks(axis, j);
    return mul32(j, axis->interval) + axis->offset;
}

static uint64_t step_ticks(fw_axis *axis, uint32_t j)
{
    uint32_t last = axis->steps - 1;
    if (j <= last / 2u) return rising_ticks(axis, j);
    return axis->end - rising_ticks(axis, last - j);
}

/* The trapezoid's constants for cruising at `interval` ticks per step. */
static uint32_t ramp_of(const fw_axis *axis, uint64_t interval)
{
    return (uint32_t)div64(div64(axis->half_k, interval), interval);
}

/* Not inlined into take_step: its divisions' registers would be saved
   and restored on every step. */
static FW_NOINLINE void shape(fw_axis *axis, uint64_t interval)
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
        uint32_t j = axis->done;
        /* cruising, j - 1 and j both: t(j) = j c + offset on either half
           (the mirror of the cruise is the same line), so t(j - 1) + c */
        if (j - 1u > axis->ramp && j + axis->ramp < axis->steps - 1u) axis->next += axis->interval;
        else axis->next = axis->start + step_ticks(axis, j);
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
        axis->end = 2u * (uint64_t)ramp_ticks(axis, p);
    } else {
        /* cruising: the deceleration's first step follows step p */
        uint32_t stop = p + axis->ramp + 1;
        if (stop >= distance) return;
        axis->steps = stop + 1;
        axis->end = (uint64_t)stop * axis->interval + 2u * axis->offset;
    }
    if (axis->done >= axis->steps) move_over(axis);
    else axis->next = axis->start + step_ticks(axis, axis->done);
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
    axis->k_rem = (uint32_t)(t2 % c->accel);
    axis->square_step = !axis->k_rem && axis->k_quot <= 0x7FFFFFFFu ? 2u * (uint32_t)axis->k_quot : 0;
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
    axis->root_lo = 0; /* A(0) = 0 */
    axis->root[0] = 0;
    axis->roots = 1;
    axis->rest_interval = ramp_ticks(axis, 1);
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
    axis->offset = axis->end = 0;
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
