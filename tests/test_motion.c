/* The Z axis (firmware/motion.c) on a simulated machine: an endstop at a
   known true position, every step recorded with its tick. Every step stream
   is checked for the shortest interval and for acceleration, and moves
   against the ideal trapezoid computed in floating point. */
#include "../firmware/motion.h"
#include "check.h"
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

/* CHECKF for the per-step paths: CHECKF's message buffer in a function's
   frame costs every call under the address sanitizer. */
static void failed_at(int line, const char *format, ...)
{
    char what[512];
    va_list args;
    va_start(args, format);
    vsnprintf(what, sizeof what, format, args);
    va_end(args);
    check_fail(__FILE__, line, what);
}
#define EXPECTF(cond, ...) do { if (!(cond)) failed_at(__LINE__, __VA_ARGS__); } while (0)

typedef struct rig {
    uint32_t hz, per_mm, max_speed, accel, home_speed;
    int32_t max_steps, home_travel;
} rig;

/* Resin-printer Z axes: 5 mm/s and 10 mm/s^2 at 400 and 1600 steps/mm, a
   non-round 415 steps/mm on a 72 MHz clock (72e6 / 2075 is not whole), and
   a slow acceleration at 72 MHz near the arithmetic's bounds. */
static const rig rigs[] = {
    {10000000u, 400u, 2000u, 4000u, 1200u, 200 * 400, 220 * 400},
    {25000000u, 1600u, 8000u, 16000u, 4800u, 200 * 1600, 220 * 1600},
    {72000000u, 415u, 2075u, 4150u, 1245u, 200 * 415, 220 * 415},
    {72000000u, 3200u, 8000u, 1000u, 3000u, 200 * 3200, 220 * 3200},
};

/* ------------------------------------------------------------ the machine */

#define SEGMENT_MAX (1u << 19)
#define LOG_MAX (1u << 17)

typedef struct machine {
    fw_axis axis;
    rig r;
    int32_t at;           /* true position, steps */
    int32_t switch_at;    /* the switch is closed iff at <= switch_at */
    int switch_dead;      /* never closes */
    int switch_stuck;     /* never opens */
    uint64_t now;
    uint64_t lateness;    /* the caller steps this long after each due tick */
    int quick;            /* skip the windowed acceleration (cheap checks stay) */
    uint32_t min_interval;
    /* the stream */
    int has_last, last_dir;
    uint64_t last_tick, steps;
    int first_dir;        /* of the first step since machine_init */
    uint32_t shortest;    /* shortest interval seen */
    /* the steps since the axis was last at rest, for the acceleration */
    uint64_t *segment;
    size_t segment_n;
    /* optional: every step's tick */
    uint64_t *log;
    size_t log_n;
} machine;

/* What the acceleration checks saw, over every case. */
static double worst_window = 0, worst_corrected = -1, worst_adjacent = 0, worst_rest = 0;
static double worst_trapezoid_error = 0, worst_triangle_ratio = 0;
static uint64_t windows_checked = 0;

static uint64_t segment_buffer[SEGMENT_MAX];

/* ceil(hz / max_speed), with init's clamp of a zero speed to 1 */
static uint32_t min_interval_of(const rig *r)
{
    uint32_t v = r->max_speed ? r->max_speed : 1;
    return (uint32_t)(((uint64_t)r->hz + v - 1) / v);
}

static void machine_init(machine *m, const rig *r, int32_t at, int32_t switch_at)
{
    fw_axis_config c;
    memset(m, 0, sizeof *m);
    m->r = *r;
    m->at = at;
    m->switch_at = switch_at;
    m->shortest = UINT32_MAX;
    m->min_interval = min_interval_of(r);
    m->segment = segment_buffer;
    c.steps_per_mm = r->per_mm;
    c.max_speed = r->max_speed;
    c.accel = r->accel;
    c.home_speed = r->home_speed;
    c.max_steps = r->max_steps;
    c.home_travel = r->home_travel;
    fw_axis_init(&m->axis, &c, r->hz);
    m->now = 12345; /* not 0: a start at 0 could hide an offset */
}

static int closed(const machine *m)
{
    if (m->switch_dead) return 0;
    return m->switch_stuck || m->at <= m->switch_at;
}

/* 2 T^2 <= a I^2 exactly: a step from rest at 0 then one at I reaches the
   mean speed 1/I at I/2, which is an acceleration of 2/I^2. */
static int rest_interval_ok(const rig *r, uint64_t interval)
{
    uint64_t need = ((uint64_t)2 * r->hz * r->hz + r->accel - 1) / r->accel;
    return interval < (1u << 31) ? interval * interval >= need : 1;
}

/* The acceleration over a stretch from rest to rest. Samples: rest at the
   first step, each interval's mean speed hz/I at its midpoint (for a
   constant acceleration that is the speed at the midpoint exactly), rest at
   the last step. Each step is within a tick or so of an ideal trajectory;
   allowing 3 ticks per interval, a speed is off by at most
   hz * 3 / (I (I - 3)), and the estimate between samples i and j by
   (err_i + err_j) / (t_j - t_i). Windows span at least 8 samples and grow
   until that bound is under 1 % of the limit, so a 2 % tolerance leaves
   1 % for nothing but a real excess. */
static void sample(const machine *m, size_t k, double *t, double *v, double *err)
{
    const uint64_t *s = m->segment;
    size_t n = m->segment_n;
    if (k == 0 || k == n) {
        *t = (double)s[k == 0 ? 0 : n - 1];
        *v = *err = 0;
    } else {
        double interval = (double)(s[k] - s[k - 1]);
        *t = 0.5 * ((double)s[k] + (double)s[k - 1]);
        *v = m->r.hz / interval;
        *err = interval > 3 ? m->r.hz * 3.0 / (interval * (interval - 3)) : 1e300;
    }
}

/* Where the segment's step k is kept: all of them, or when quick the first
   two and the latest two. */
static size_t slot(const machine *m, size_t k) { return !m->quick || k < 2 ? k : 2 + (k & 1); }

static void close_segment(machine *m)
{
    size_t n = m->segment_n, i, j = 0;
    const double hz = m->r.hz, a = m->r.accel;
    if (n >= 2) {
        uint64_t first = m->segment[1] - m->segment[0];
        uint64_t last = m->segment[slot(m, n - 1)] - m->segment[slot(m, n - 2)];
        double rest_ratio = 2.0 * hz * hz / (a * (double)(first < last ? first : last) * (double)(first < last ? first : last));
        EXPECTF(rest_interval_ok(&m->r, first), "first interval from rest %llu ticks: %.4f x the acceleration",
               (unsigned long long)first, rest_ratio);
        EXPECTF(rest_interval_ok(&m->r, last), "last interval before rest %llu ticks: %.4f x the acceleration",
               (unsigned long long)last, rest_ratio);
        if (rest_ratio > worst_rest) worst_rest = rest_ratio;
        for (i = 0; i + 1 <= n && !m->quick; i++) {
            double ti, vi, ei, tj, vj, ej, dt, bound, est;
            sample(m, i, &ti, &vi, &ei);
            sample(m, i + 1, &tj, &vj, &ej);
            /* neighbours too: the rounding bound is large there, but nothing
               may exceed the limit by more than the bound */
            dt = (tj - ti) / hz;
            est = fabs(vj - vi) / dt;
            bound = (ei + ej) / dt;
            if (est / a > worst_adjacent) worst_adjacent = est / a;
            if ((est - bound) / a > worst_corrected) worst_corrected = (est - bound) / a;
            EXPECTF(est - bound <= a * (1 + 1e-9), "acceleration %.1f steps/s^2 beyond the rounding %.1f between samples %zu and %zu",
                    est, bound, i, i + 1);
            if (j < i + 8) j = i + 8;
            if (j > n) j = n;
            for (;;) {
                sample(m, j, &tj, &vj, &ej);
                dt = (tj - ti) / hz;
                bound = (ei + ej) / dt;
                if (bound <= 0.01 * a || j == n) break;
                j++;
            }
            est = fabs(vj - vi) / dt;
            windows_checked++;
            if (bound <= 0.01 * a) {
                if (est / a > worst_window) worst_window = est / a;
                EXPECTF(est <= 1.02 * a, "acceleration %.1f steps/s^2 over samples %zu..%zu (limit %.0f, rounding %.1f)",
                       est, i, j, a, bound);
            }
            if ((est - bound) / a > worst_corrected) worst_corrected = (est - bound) / a;
            EXPECTF(est - bound <= a * (1 + 1e-9), "acceleration %.1f steps/s^2 beyond the rounding %.1f over samples %zu..%zu",
                   est, bound, i, j);
        }
    }
    m->segment_n = 0;
}

static void record(machine *m, uint64_t tick, int dir)
{
    if (m->has_last) {
        uint64_t interval = tick - m->last_tick;
        EXPECTF(tick > m->last_tick, "step at %llu after one at %llu", (unsigned long long)tick,
               (unsigned long long)m->last_tick);
        if (interval < m->shortest) m->shortest = (uint32_t)(interval < UINT32_MAX ? interval : UINT32_MAX);
        EXPECTF(interval >= m->min_interval, "interval %llu < %u ticks", (unsigned long long)interval, m->min_interval);
        if (dir != m->last_dir) close_segment(m);
        /* the axis rests at a segment's last step: the next one is from rest */
        if (m->segment_n == 0)
            EXPECTF(rest_interval_ok(&m->r, interval), "a step %llu ticks after rest", (unsigned long long)interval);
    }
    if (m->quick && m->segment_n >= 4) m->segment[slot(m, m->segment_n++)] = tick;
    else if (m->segment_n < SEGMENT_MAX) m->segment[m->segment_n++] = tick;
    else EXPECTF(0, "segment too long for the checker");
    if (m->log && m->log_n < LOG_MAX) m->log[m->log_n++] = tick;
    if (m->steps == 0) m->first_dir = dir;
    m->at += dir;
    m->steps++;
    m->has_last = 1;
    m->last_dir = dir;
    m->last_tick = tick;
}

/* Steps until the axis is idle; returns the steps taken. */
static uint64_t run(machine *m)
{
    uint64_t before = m->steps, calls = 0;
    while (fw_axis_busy(&m->axis)) {
        uint64_t due = fw_axis_next(&m->axis);
        int dir;
        if (m->now < due + m->lateness) m->now = due + m->lateness;
        dir = fw_axis_step(&m->axis, closed(m));
        EXPECTF(dir == 0 || dir == 1 || dir == -1, "step %d", dir);
        if (dir) record(m, due, dir);
        if (++calls > 50000000u) {
            EXPECTF(0, "the axis never stops");
            break;
        }
    }
    close_segment(m);
    return m->steps - before;
}

static int home(machine *m)
{
    CHECK(fw_axis_home(&m->axis, m->now) == FW_AXIS_OK);
    run(m);
    return m->axis.homed;
}

/* The ideal trapezoid in floating point: step j of a move over `distance`
   steps (j = 0..distance) cruising at hz / interval steps/s, in ticks. */
static double ideal_tick(const rig *r, double distance, double interval, double j)
{
    double a = r->accel, v = r->hz / interval, ramp = v * v / (2 * a), total;
    if (distance < 2 * ramp) { /* a triangle peaking halfway */
        total = 2 * sqrt(distance / a);
        return r->hz * (j <= distance / 2 ? sqrt(2 * j / a) : total - sqrt(2 * (distance - j) / a));
    }
    total = distance / v + v / a;
    if (j <= ramp) return r->hz * sqrt(2 * j / a);
    if (j <= distance - ramp) return r->hz * (j / v + v / (2 * a));
    return r->hz * (total - sqrt(2 * (distance - j) / a));
}

static uint64_t rng_next(uint64_t *s)
{
    *s = *s * 6364136223846793005u + 1442695040888963407u;
    return *s >> 33;
}

/* ------------------------------------------------ exact integer reference */

/* a * b as 128 bits, portably */
typedef struct u128 { uint64_t hi, lo; } u128;

static u128 mul64(uint64_t a, uint64_t b)
{
    uint64_t a0 = a & 0xFFFFFFFFu, a1 = a >> 32, b0 = b & 0xFFFFFFFFu, b1 = b >> 32;
    uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
    uint64_t mid = (p00 >> 32) + (p01 & 0xFFFFFFFFu) + (p10 & 0xFFFFFFFFu);
    u128 r;
    r.lo = (mid << 32) | (p00 & 0xFFFFFFFFu);
    r.hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
    return r;
}

static int less128(u128 a, u128 b) { return a.hi < b.hi || (a.hi == b.hi && a.lo < b.lo); }

/* t is the least whole tick with a t^2 >= 2 j hz^2 (the ideal accelerating
   step j rounded up), checked without any rounding */
static int is_accel_tick(const rig *r, uint64_t j, uint64_t t)
{
    u128 want = mul64(2 * j * r->hz, r->hz);
    return !less128(mul64(t * t, r->accel), want) && (t == 0 || less128(mul64((t - 1) * (t - 1), r->accel), want));
}

/* t = j c + ceil(hz^2 / (2 a c)): 2 a c (t - j c) >= hz^2 > 2 a c (t - j c - 1) */
static int is_cruise_tick(const rig *r, uint64_t j, uint64_t c, uint64_t t)
{
    u128 want = mul64(r->hz, r->hz);
    uint64_t rest = t - j * c;
    return t >= j * c && !less128(mul64(2 * r->accel * c, rest), want) &&
           (rest == 0 || less128(mul64(2 * r->accel * c, rest - 1), want));
}

/* Every step of long moves against the closed forms in exact integers, with
   accelerations that do not divide hz^2 (so the remainder matters). */
static void ticks_are_exact(void)
{
    static uint64_t log[LOG_MAX];
    static const rig exact_rigs[] = {
        {72000000u, 415u, 2075u, 4150u, 0u, 200 * 415, 220 * 415},
        {25000000u, 1600u, 8000u, 16001u, 0u, 200 * 1600, 220 * 1600},
        {10000000u, 400u, 2000u, 3999u, 0u, 200 * 400, 220 * 400},
        {72000000u, 3200u, 8000u, 997u, 0u, 200 * 3200, 220 * 3200},
        {16000000u, 333u, 1777u, 7777u, 0u, 200 * 333, 220 * 333},
        /* a ceiling of 2 j hz^2 / a just above a square: rounding it down
           would move steps 2 and 13 by a tick (found by search) */
        {1000000u, 400u, 2000u, 19325u, 0u, 200 * 400, 220 * 400},
        {1000000u, 400u, 2000u, 9096u, 0u, 200 * 400, 220 * 400},
        /* the RAMPS's axis (2 MHz, 50 mm/s^2) at 2.5 mm/s: a ramp of 25
           steps, where the guess from the steps before misses by hundreds
           of ticks and the Newton step lands it; at 10 mm/s, 400 */
        {2000000u, 400u, 1000u, 20000u, 0u, 200 * 400, 220 * 400},
        {2000000u, 400u, 4000u, 20000u, 0u, 200 * 400, 220 * 400},
    };
    size_t k;
    for (k = 0; k < sizeof exact_rigs / sizeof exact_rigs[0]; k++) {
        static machine m;
        const rig *r = &exact_rigs[k];
        uint64_t c = min_interval_of(r), ramp = (uint64_t)r->hz * r->hz / (2u * (uint64_t)r->accel) / c / c, j, bad = 0;
        int32_t length = (int32_t)(2 * ramp) + 2000;
        machine_init(&m, r, 0, 0);
        CHECK(home(&m));
        m.now += r->hz;
        m.log = log;
        CHECK(fw_axis_move_to(&m.axis, length, 0, m.now) == FW_AXIS_OK);
        run(&m);
        CHECK(m.log_n == (size_t)length);
        for (j = 0; j < m.log_n && m.log_n == (size_t)length; j++) {
            uint64_t last = m.log_n - 1, t = log[j] - log[0], end = log[last] - log[0];
            int ok;
            if (2 * j <= last) ok = j <= ramp ? is_accel_tick(r, j, t) : is_cruise_tick(r, j, c, t);
            else ok = t + (log[last - j] - log[0]) == end; /* the first half mirrored about the end */
            if (j == last) /* end = L c + 2 ceil(hz^2 / (2 a c)) */
                ok = ok && (end - last * c) % 2 == 0 && is_cruise_tick(r, 0, c, (end - last * c) / 2);
            if (!ok && bad++ == 0)
                EXPECTF(0, "hz %u a %u: step %llu at %llu ticks", r->hz, r->accel, (unsigned long long)j, (unsigned long long)t);
        }
        CHECKF(bad == 0, "%llu steps off their closed form", (unsigned long long)bad);
    }
}

/* ---------------------------------------------------------------- cases */

/* 1,000 layers of 50..150 um in 2 um bins, each followed by a 5 mm peel at
   a third of the speed and a return to the next layer's absolute height. */
static void print_has_no_drift(void)
{
    size_t k;
    for (k = 0; k < 3; k++) {
        static machine m;
        const rig *r = &rigs[k];
        uint64_t seed = 42 + k, z = 0;
        int32_t target;
        int layer, bad_layers = 0;
        machine_init(&m, r, 3 * (int32_t)r->per_mm + 17, 1000);
        CHECK(home(&m));
        CHECK(m.at == m.switch_at);
        for (layer = 1; layer <= 1000; layer++) {
            uint64_t h = 50000u + 2000u * (rng_next(&seed) % 51u);
            m.quick = layer % 10 != 1;
            z += h;
            target = fw_axis_steps_of_nm(&m.axis, z);
            CHECK(target == (int32_t)floor((double)z * r->per_mm / 1e6 + 0.5));
            CHECK(fw_axis_move_to(&m.axis, target, 0, m.now) == FW_AXIS_OK);
            run(&m);
            if (m.axis.position != target || m.at - m.switch_at != target) bad_layers++;
            /* exposure, then the peel */
            m.now += r->hz * 2u;
            CHECK(fw_axis_move_to(&m.axis, fw_axis_steps_of_nm(&m.axis, z + 5000000u), r->max_speed / 3, m.now) ==
                  FW_AXIS_OK);
            run(&m);
            CHECK(m.axis.position == fw_axis_steps_of_nm(&m.axis, z + 5000000u));
        }
        /* the last return */
        CHECK(fw_axis_move_to(&m.axis, target, 0, m.now) == FW_AXIS_OK);
        run(&m);
        CHECKF(bad_layers == 0, "%d layers off their absolute height at %u steps/mm", bad_layers, r->per_mm);
        CHECKF(m.axis.position == fw_axis_steps_of_nm(&m.axis, z) && m.at - m.switch_at == m.axis.position,
               "at %d steps, true %d, want %d", m.axis.position, m.at - m.switch_at, fw_axis_steps_of_nm(&m.axis, z));
        CHECK(m.shortest >= min_interval_of(r));
    }
}

static void steps_of_nm_round_exactly(void)
{
    static machine m;
    uint64_t seed = 7;
    int i;
    machine_init(&m, &rigs[2], 0, 0);
    CHECK(fw_axis_steps_of_nm(&m.axis, 0) == 0);
    /* 415 steps/mm: 1 step is 2409.6 nm; half a step rounds up */
    CHECK(fw_axis_steps_of_nm(&m.axis, 1204) == 0);
    CHECK(fw_axis_steps_of_nm(&m.axis, 1205) == 1);
    CHECK(fw_axis_steps_of_nm(&m.axis, 1000000) == 415);
    CHECK(fw_axis_steps_of_nm(&m.axis, UINT64_MAX) == INT32_MAX);
    for (i = 0; i < 100000; i++) {
        uint64_t nm = rng_next(&seed) % 400000000u;
        int64_t want = (int64_t)(nm * 415u / 1000000u) + (nm * 415u % 1000000u >= 500000u);
        if (fw_axis_steps_of_nm(&m.axis, nm) != want) {
            CHECKF(0, "%llu nm: %d steps, want %lld", (unsigned long long)nm, fw_axis_steps_of_nm(&m.axis, nm),
                   (long long)want);
            break;
        }
    }
}

/* Moves at speeds whose interval does not divide the clock, on every rig,
   against the shortest interval and the ideal trapezoid. */
static void moves_follow_the_trapezoid(void)
{
    static uint64_t log[LOG_MAX];
    size_t k;
    for (k = 0; k < sizeof rigs / sizeof rigs[0]; k++) {
        static const uint32_t fractions[] = {1, 2, 3, 7};
        const rig *r = &rigs[k];
        size_t f;
        for (f = 0; f < 4; f++) {
            static machine m;
            uint32_t speed = r->max_speed / fractions[f] + (f == 3 ? 13 : 0);
            uint32_t interval = (r->hz + speed - 1) / speed;
            double ramp = (double)r->hz / interval * ((double)r->hz / interval) / (2.0 * r->accel);
            int32_t length = (int32_t)(2 * ramp) + 3 * (int32_t)r->per_mm;
            size_t j;
            double worst = 0, duration_error;
            machine_init(&m, r, 0, 0);
            CHECK(home(&m));
            m.now += r->hz;
            m.log = log;
            CHECK(fw_axis_move_to(&m.axis, length, speed, m.now) == FW_AXIS_OK);
            CHECK(fw_axis_next(&m.axis) == m.now);
            run(&m);
            CHECK(m.log_n == (size_t)length);
            for (j = 1; j < m.log_n; j++)
                CHECKF(log[j] - log[j - 1] >= interval, "interval %llu < %u at step %zu",
                       (unsigned long long)(log[j] - log[j - 1]), interval, j);
            /* rounded up from the ideal: the first half within [0, 1) tick;
               the second half mirrors it from an end rounded up by < 2 */
            for (j = 0; j < m.log_n; j++) {
                double e = (double)(log[j] - log[0]) - ideal_tick(r, length - 1, interval, (double)j);
                int rising = 2 * j <= m.log_n - 1;
                if (fabs(e) > worst) worst = fabs(e);
                EXPECTF(rising ? e > -1e-6 && e < 1 : e > -1 && e < 2, "step %zu of %d: %.4f ticks from the ideal", j,
                        length, e);
            }
            duration_error = (double)(log[m.log_n - 1] - log[0]) - ideal_tick(r, length - 1, interval, length - 1);
            CHECKF(worst < 2.0 && fabs(duration_error) < 2.0,
                   "hz %u speed %u: a step %.2f ticks off the ideal, the duration %.2f", r->hz, speed, worst,
                   duration_error);
            if (worst > worst_trapezoid_error) worst_trapezoid_error = worst;
        }
    }
}

/* Short moves: triangles, 2 steps, 1 step, none. */
static void short_moves(void)
{
    static uint64_t log[LOG_MAX];
    size_t k;
    for (k = 0; k < sizeof rigs / sizeof rigs[0]; k++) {
        static machine m;
        const rig *r = &rigs[k];
        uint32_t interval = min_interval_of(r), i;
        /* the last step of the ideal ramp, as motion.c rounds it */
        uint64_t ramp = (uint64_t)r->hz * r->hz / (2u * (uint64_t)r->accel) / interval / interval;
        int32_t length, top = 2 * (int32_t)ramp + 3 * (int32_t)r->per_mm;
        machine_init(&m, r, 0, 0);
        CHECK(home(&m));
        m.log = log;
        /* none: no step, not busy */
        CHECK(fw_axis_move_to(&m.axis, 0, 0, m.now) == FW_AXIS_OK);
        CHECK(!fw_axis_busy(&m.axis) && fw_axis_next(&m.axis) == FW_NEVER);
        CHECK(fw_axis_step(&m.axis, 0) == 0 && m.axis.position == 0);
        /* one: a single step at once */
        m.now += r->hz;
        CHECK(fw_axis_move_to(&m.axis, 1, 0, m.now) == FW_AXIS_OK);
        CHECK(fw_axis_busy(&m.axis) && fw_axis_next(&m.axis) == m.now);
        CHECK(run(&m) == 1 && m.axis.position == 1 && !fw_axis_busy(&m.axis));
        /* 1..64 steps, a ladder up to past the full ramps, and every length
           where a triangle becomes a trapezoid (2 ramp + 1 steps of
           distance); up and back down */
        for (i = 1; i <= 64 + 40 + 9; i++) {
            int back;
            length = i <= 64 ? (int32_t)i : i <= 104 ? (int32_t)(64 * pow(top / 64.0, (i - 64) / 40.0)) : (int32_t)(2 * ramp) + (int32_t)i - 108;
            for (back = 0; back < 2; back++) {
                m.now += r->hz;
                m.log_n = 0;
                CHECK(fw_axis_move_to(&m.axis, back ? 1 : 1 + length, 0, m.now) == FW_AXIS_OK);
                CHECK(run(&m) == (uint64_t)length);
                if (length >= 2 && m.log_n == (size_t)length) {
                    double ideal = ideal_tick(r, length - 1, interval, length - 1);
                    double ratio = (double)(log[m.log_n - 1] - log[0]) / ideal;
                    if (ratio > worst_triangle_ratio) worst_triangle_ratio = ratio;
                    /* no faster than physics allows, and not much slower */
                    CHECKF(ratio >= 1 - 1e-9 && ratio < 1.25, "%d steps take %.3f x the ideal", length, ratio);
                }
            }
        }
    }
}

/* Homing from above, from on the switch, with a switch that never closes
   and one that never opens; the closing edge becomes 0 exactly. */
static void homing_finds_the_edge(void)
{
    size_t k;
    for (k = 0; k < sizeof rigs / sizeof rigs[0]; k++) {
        static const int32_t starts[] = {5000, 1001, 1002, 1000, 990, 700, 1000 + 3 * 1600};
        const rig *r = &rigs[k];
        size_t s;
        for (s = 0; s < sizeof starts / sizeof starts[0]; s++) {
            static machine m;
            int32_t start = starts[s];
            machine_init(&m, r, start, 1000);
            CHECK(home(&m));
            CHECKF(m.at == m.switch_at && m.axis.position == 0 && m.axis.error == FW_AXIS_OK,
                   "from %d: true %d, switch %d", start, m.at, m.switch_at);
            /* on the switch: off it first, upwards */
            CHECKF(m.first_dir == (start <= m.switch_at ? 1 : -1), "from %d the first step is %d", start, m.first_dir);
            /* and again, from where it stands */
            m.now += r->hz / 10;
            CHECK(home(&m) && m.at == m.switch_at);
            CHECK(m.shortest >= min_interval_of(r));
        }
    }
    {
        static machine m;
        const rig *r = &rigs[0];
        uint64_t steps;
        /* never closes: the approach runs its travel and stops, braking */
        machine_init(&m, r, 50000, 1000);
        m.switch_dead = 1;
        CHECK(!home(&m));
        CHECK(m.axis.error == FW_AXIS_HOME_FAILED && !m.axis.homed && !fw_axis_busy(&m.axis));
        CHECK(m.at == 50000 - r->home_travel);
        CHECK(fw_axis_move_to(&m.axis, 10, 0, m.now) == FW_AXIS_NOT_HOMED);
        /* never opens: backing off gives up within 2 mm plus braking */
        machine_init(&m, r, 50000, 1000);
        m.switch_stuck = 1;
        CHECK(!home(&m));
        steps = m.steps;
        CHECK(m.axis.error == FW_AXIS_HOME_FAILED && !m.axis.homed);
        CHECKF(steps > 0 && m.at - 50000 <= (int32_t)(FW_AXIS_HOME_BACKOFF_MM * r->per_mm) + 200,
               "backed off %d steps", m.at - 50000);
        /* a good switch afterwards: homing recovers */
        m.switch_stuck = 0;
        m.now += r->hz;
        CHECK(home(&m) && m.at == m.switch_at && m.axis.error == FW_AXIS_OK);
        /* the switch closes on the approach's very last step */
        machine_init(&m, r, 1000 + r->home_travel, 1000);
        CHECK(home(&m) && m.at == m.switch_at);
        /* one step short of it: a failure */
        machine_init(&m, r, 1001 + r->home_travel, 1000);
        CHECK(!home(&m) && m.axis.error == FW_AXIS_HOME_FAILED);
    }
}

static void refusals_and_limits(void)
{
    static machine m;
    fw_axis before;
    const rig *r = &rigs[1];
    uint64_t due;
    int dir;
    machine_init(&m, r, 2000, 1000);
    before = m.axis;
    CHECK(fw_axis_move_to(&m.axis, 10, 0, m.now) == FW_AXIS_NOT_HOMED);
    CHECK(!memcmp(&before, &m.axis, sizeof before));
    CHECK(home(&m));
    before = m.axis;
    CHECK(fw_axis_move_to(&m.axis, -1, 0, m.now) == FW_AXIS_LIMIT);
    CHECK(fw_axis_move_to(&m.axis, r->max_steps + 1, 0, m.now) == FW_AXIS_LIMIT);
    CHECK(fw_axis_move_to(&m.axis, INT32_MIN, 0, m.now) == FW_AXIS_LIMIT);
    CHECK(!memcmp(&before, &m.axis, sizeof before));
    CHECK(fw_axis_move_to(&m.axis, 5000, 0, m.now) == FW_AXIS_OK);
    due = fw_axis_next(&m.axis);
    dir = fw_axis_step(&m.axis, 0);
    CHECK(dir == 1);
    record(&m, due, dir);
    before = m.axis;
    CHECK(fw_axis_move_to(&m.axis, 10, 0, m.now) == FW_AXIS_BUSY);
    CHECK(fw_axis_home(&m.axis, m.now) == FW_AXIS_BUSY);
    CHECK(!memcmp(&before, &m.axis, sizeof before));
    run(&m);
    CHECK(m.axis.position == 5000 && m.at - m.switch_at == 5000);
    CHECK(fw_axis_move_to(&m.axis, r->max_steps, 0, m.now) == FW_AXIS_OK);
    run(&m);
    CHECK(m.axis.position == r->max_steps && m.at - m.switch_at == r->max_steps);
    CHECK(fw_axis_move_to(&m.axis, 0, 0, m.now) == FW_AXIS_OK);
    run(&m);
    CHECK(m.axis.position == 0 && m.at == m.switch_at);
}

/* Halts while accelerating, cruising, decelerating, before the first step
   and while homing. */
static void halt_brakes(void)
{
    size_t k;
    for (k = 0; k < sizeof rigs / sizeof rigs[0]; k++) {
        static const uint32_t after[] = {0, 1, 2, 5, 40, 300, 2000, 9000, 19000, 23999};
        const rig *r = &rigs[k];
        uint32_t interval = min_interval_of(r);
        double v = (double)r->hz / interval, braking = v * v / (2.0 * r->accel);
        size_t h;
        for (h = 0; h < sizeof after / sizeof after[0]; h++) {
            static machine m;
            uint32_t i;
            int32_t at_halt;
            uint64_t taken;
            machine_init(&m, r, 2000, 1000);
            CHECK(home(&m));
            m.now += r->hz;
            CHECK(fw_axis_move_to(&m.axis, 24000, 0, m.now) == FW_AXIS_OK);
            for (i = 0; i < after[h] && fw_axis_busy(&m.axis); i++) {
                uint64_t due = fw_axis_next(&m.axis);
                m.now = due;
                record(&m, due, fw_axis_step(&m.axis, 0));
            }
            at_halt = m.axis.position;
            fw_axis_halt(&m.axis, m.now + interval / 2);
            taken = run(&m);
            CHECKF(m.axis.position == m.at - m.switch_at && m.axis.homed, "halted at %d, true %d",
                   m.axis.position, m.at - m.switch_at);
            /* braking from at most the top speed takes at most its ramp */
            CHECKF(taken <= (uint64_t)braking + 2, "%llu steps after the halt, braking %.1f",
                   (unsigned long long)taken, braking);
            if (after[h] == 0) CHECK(taken == 0 && m.axis.position == 0);
            if (after[h] > 0 && after[h] < braking / 2) CHECK(taken <= after[h]);
            CHECK(at_halt + (int32_t)taken == m.axis.position);
            /* the axis moves on normally */
            CHECK(fw_axis_move_to(&m.axis, 100, 0, m.now) == FW_AXIS_OK);
            run(&m);
            CHECK(m.axis.position == 100 && m.at - m.switch_at == 100);
        }
    }
    {
        /* halting the homing approach: it brakes and leaves the axis unhomed */
        static machine m;
        const rig *r = &rigs[0];
        int i;
        machine_init(&m, r, 60000, 1000);
        CHECK(fw_axis_home(&m.axis, m.now) == FW_AXIS_OK);
        for (i = 0; i < 3000; i++) {
            uint64_t due = fw_axis_next(&m.axis);
            int dir = fw_axis_step(&m.axis, closed(&m));
            if (dir) record(&m, due, dir);
        }
        fw_axis_halt(&m.axis, fw_axis_next(&m.axis));
        run(&m);
        CHECK(!m.axis.homed && !fw_axis_busy(&m.axis) && m.at - 60000 == m.axis.position);
        CHECK(fw_axis_move_to(&m.axis, 10, 0, m.now) == FW_AXIS_NOT_HOMED);
    }
}

/* A caller that steps late gets the same schedule: lateness never moves a
   step's tick. */
static void late_caller_keeps_the_schedule(void)
{
    static uint64_t on_time[LOG_MAX], late[LOG_MAX];
    static machine m;
    const rig *r = &rigs[1];
    size_t j;
    uint64_t seed = 3, start;
    int32_t length = 40000;
    machine_init(&m, r, 2000, 1000);
    CHECK(home(&m));
    m.now += r->hz;
    start = m.now;
    m.log = on_time;
    CHECK(fw_axis_move_to(&m.axis, length, 0, start) == FW_AXIS_OK);
    run(&m);
    CHECK(m.log_n == (size_t)length);
    machine_init(&m, r, 2000, 1000);
    CHECK(home(&m));
    m.log = late;
    CHECK(fw_axis_move_to(&m.axis, length, 0, start) == FW_AXIS_OK);
    /* late by up to 20 intervals at random, sometimes very late */
    while (fw_axis_busy(&m.axis)) {
        uint64_t due = fw_axis_next(&m.axis), delay = rng_next(&seed) % 64 == 0 ? r->hz / 10 : rng_next(&seed) % 20000;
        int dir;
        if (m.now < due + delay) m.now = due + delay;
        dir = fw_axis_step(&m.axis, 0);
        CHECK(dir == 1);
        m.log[m.log_n++] = due;
        if (m.log_n >= LOG_MAX) break;
    }
    CHECK(m.log_n == (size_t)length);
    for (j = 0; j < (size_t)length && j < m.log_n; j++)
        if (late[j] != on_time[j]) {
            CHECKF(0, "step %zu at %llu late, %llu on time", j, (unsigned long long)late[j],
                   (unsigned long long)on_time[j]);
            break;
        }
}

/* init keeps the arithmetic in 64 bits: a top speed too high for the
   acceleration is lowered, and what remains is exact. */
static void init_bounds(void)
{
    static machine m;
    rig r = {72000000u, 3200u, 4000000u, 1000u, 0u, 1000, 2000};
    uint64_t ramp_ticks;
    machine_init(&m, &r, 0, 0);
    /* 72e6^2 / (1000 c) < 2^32 needs c >= 1207: 59,652 steps/s */
    CHECK(m.axis.config.max_speed == 72000000u / 1207u);
    CHECK(m.axis.config.home_speed == m.axis.config.max_speed);
    ramp_ticks = (uint64_t)72000000u * 72000000u / 1000u / 1207u;
    CHECK(ramp_ticks < ((uint64_t)1 << 32));
    r.max_speed = m.axis.config.max_speed;
    r.accel = 1000;
    machine_init(&m, &r, 600, 0);
    CHECK(home(&m) && m.at == 0);
    CHECK(fw_axis_move_to(&m.axis, 1000, 0, m.now) == FW_AXIS_OK);
    run(&m);
    CHECK(m.axis.position == 1000);
    memset(&r, 0, sizeof r);
    r.hz = 1000000u;
    machine_init(&m, &r, 0, 0);
    CHECK(m.axis.config.accel == 2 && m.axis.config.max_speed >= 1);
    CHECK(fw_axis_move_to(&m.axis, 0, 0, 0) == FW_AXIS_NOT_HOMED);
}

void test_motion(void)
{
    RUN(print_has_no_drift);
    RUN(steps_of_nm_round_exactly);
    RUN(moves_follow_the_trapezoid);
    RUN(ticks_are_exact);
    RUN(short_moves);
    RUN(homing_finds_the_edge);
    RUN(refusals_and_limits);
    RUN(halt_brakes);
    RUN(late_caller_keeps_the_schedule);
    RUN(init_bounds);
    if (getenv("ADASLICE_MOTION_STATS"))
        printf("motion: worst acceleration %.4f x the limit over %llu windows (%.6f after rounding), adjacent "
               "intervals %.3f, from rest %.4f; trapezoid steps within %.3f ticks of ideal; short moves up to %.3f x "
               "the ideal triangle\n",
               worst_window, (unsigned long long)windows_checked, worst_corrected, worst_adjacent, worst_rest,
               worst_trapezoid_error, worst_triangle_ratio);
}
