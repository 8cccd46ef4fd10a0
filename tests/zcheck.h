/* What a print must look like from the printer's pins, checked on a record
   of events (steps with their ticks, UV on/off, masks shown) from first
   principles, with no firmware code: the one check of every edge log the
   tests make (the in-process firmware, fw-sim's log, the QEMU trace, the
   AVR image's pins under simavr), binary-protocol and G-code prints alike.
     - at every exposure Z is exactly at the layer's top: round(top bins x
       bin_nm x steps/mm / 1e6) steps above the endstop (no drift);
     - the UV light is never on while a step is taken;
     - no step interval is shorter than the maximum speed allows,
       ceil(tick_hz / max_speed) ticks, less twice the edges' stated jitter;
     - acceleration, measured between the mean speeds of consecutive
       windows of 8 steps (for constant acceleration that estimate is
       exact), is nowhere above the limit by more than 2 %, and within 2 %
       of it wherever the axis accelerates or brakes (a window inside a run
       of intervals that all shrink, or all grow: a ramp);
     - a move starts from rest: its first step is followed by its second
       sqrt(2 / accel) s later, the time a step takes from rest at the
       limit (within a tick of rounding and twice the jitter), in every
       move that gets as fast as one step of acceleration leaves it,
       sqrt(2 accel) steps/s (a slower move never reaches that interval);
       moves are told apart at rests, gaps longer than that interval, and
       at reversals (so a first step late on its move shows; a whole move
       late, every step by as much, leaves the pins' shape as it was);
     - each layer shows the expected mask once and gets exactly its light
       (in pieces if a pause came in between; an emulator's UV edges may
       come late by a stated jitter); a record without masks (a G-code
       print) starts a layer at each light-on;
     - with a path (the heights Z visits after homing), the steps taken
       after homing's end, the last time Z stood at the switch, are the
       heights moved, the sum of |dz| x steps/mm, and Z ends at the last. */
#ifndef ADASLICE_ZCHECK_H
#define ADASLICE_ZCHECK_H
#include "check.h"
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct zevent { uint64_t when; int kind, value; uint32_t crc; } zevent;
enum { ZEV_STEP = 1, ZEV_UV, ZEV_SHOW };

typedef struct zexpect {
    uint64_t tick_hz;
    uint32_t steps_per_mm, max_speed, accel;
    uint32_t jitter;              /* ticks a step's edge may read away from its true time */
    uint32_t uv_jitter;           /* ticks a UV edge may come after its time (an emulator's interrupts) */
    int64_t start_position;       /* steps above the switch before homing */
    uint32_t layers, first;       /* layers exposed: first .. layers */
    const uint32_t *top_bins;     /* [layers]: top plane of each layer, bins */
    uint32_t bin_nm;
    const uint32_t *crcs;         /* [layers] or NULL; 0: a mask not known */
    const uint32_t *exposure_ms;  /* [layers]: the light each layer must get */
    const uint64_t *path_nm;      /* [path_len] or NULL: heights Z visits after homing, in order */
    size_t path_len;
} zexpect;

typedef struct zsummary {
    size_t steps, exposures, shows, moves, ramp_windows;
    double worst_accel_ratio, worst_speed_ratio, lowest_ramp_ratio, worst_first_ticks;
} zsummary;

static inline int64_t zcheck_steps_of_nm(const zexpect *e, uint64_t nm)
{
    return (int64_t)((nm * e->steps_per_mm + 500000u) / 1000000u);
}

static inline int64_t zcheck_steps_of(const zexpect *e, uint32_t bins) { return zcheck_steps_of_nm(e, (uint64_t)bins * e->bin_nm); }

/* The light a layer got, all its pieces together. */
static inline void zcheck_exposure(const zexpect *e, uint32_t layer, uint64_t lit, size_t *bad, zsummary *s)
{
    uint64_t want = (uint64_t)e->exposure_ms[layer - 1] * e->tick_hz / 1000u;
    if ((lit + e->uv_jitter < want || lit > want + e->uv_jitter) && (*bad)++ < 3)
        CHECKF(0, "layer %u got %llu ticks of light, not %llu", layer, (unsigned long long)lit, (unsigned long long)want);
    s->exposures++;
}

typedef struct zmotion { size_t bad_accel, bad_ramp, bad_first; } zmotion;

/* One move's steps (ticks): its first interval and its windows. */
static inline void zcheck_move(const zexpect *e, const uint64_t *t, size_t n, double from_rest, zmotion *m, zsummary *s)
{
    const double slack = 2.0 * e->jitter;
    size_t k, j;
    uint64_t shortest = UINT64_MAX;
    for (k = 1; k < n; k++)
        if (t[k] - t[k - 1] < shortest) shortest = t[k] - t[k - 1];
    /* as fast as a step of acceleration leaves the axis: an interval of
       half the one from rest */
    if (n >= 4 && (double)shortest <= from_rest / 2 + slack) {
        double off = fabs((double)(t[1] - t[0]) - from_rest);
        s->moves++;
        if (off > s->worst_first_ticks) s->worst_first_ticks = off;
        if (off > 1.0 + slack && m->bad_first++ < 3)
            CHECKF(0, "a move's first interval is %llu ticks, from rest it takes %.1f", (unsigned long long)(t[1] - t[0]), from_rest);
    }
    for (k = 0; k + 16 < n; k++) {
        double d1 = (double)(t[k + 8] - t[k]), d2 = (double)(t[k + 16] - t[k + 8]);
        double v1 = 8.0 * e->tick_hz / d1, v2 = 8.0 * e->tick_hz / d2;
        double dt = (double)(t[k + 16] - t[k]) / 2 / e->tick_hz;
        double ratio = fabs(v2 - v1) / dt / e->accel;
        /* a step's tick is its ideal time rounded to a whole tick: each
           window's span is within a tick of the ideal's, which moves its
           speed by up to 8 hz / (d (d - 1)); at a fast step rate that is
           more than the 2 % */
        double rounding = (d1 > 1 && d2 > 1 ? 8.0 * e->tick_hz / (d1 * (d1 - 1)) + 8.0 * e->tick_hz / (d2 * (d2 - 1)) : 1e300) /
                          dt / e->accel;
        int sign = 0, ramp = k >= 1 && k + 17 < n;
        if (ratio > s->worst_accel_ratio) s->worst_accel_ratio = ratio;
        if (ratio - rounding > 1.02) m->bad_accel++;
        /* a ramp: every interval from the one before the window to the one
           after it shorter than the last (or every one longer) */
        for (j = k + 1; ramp && j <= k + 17; j++) {
            double d = (double)(t[j] - t[j - 1]) - (double)(t[j - 1] - t[j - 2]);
            int sj = d < -slack ? -1 : d > slack ? 1 : 0;
            if (j == k + 1) sign = sj;
            if (!sj || sj != sign) ramp = 0;
        }
        if (!ramp) continue;
        s->ramp_windows++;
        if (!s->lowest_ramp_ratio || ratio < s->lowest_ramp_ratio) s->lowest_ramp_ratio = ratio;
        if (ratio + rounding < 0.98 && m->bad_ramp++ < 3)
            CHECKF(0, "a ramp accelerates at %.4f of the limit (steps %llu..%llu)", ratio, (unsigned long long)t[k],
                   (unsigned long long)t[k + 16]);
    }
}

static inline zsummary zcheck_record(const zevent *ev, size_t count, const zexpect *e)
{
    zsummary s;
    zmotion m = {0, 0, 0};
    int64_t pos = e->start_position, home_pos = 0;
    uint64_t min_interval = (e->tick_hz + e->max_speed - 1) / e->max_speed;
    /* a step from rest at the limit: x = a t^2 / 2 reaches 1 at sqrt(2 / a) */
    double from_rest = sqrt(2.0 / e->accel) * (double)e->tick_hz;
    double rest_gap = from_rest * 1.01 + 1 + 2.0 * e->jitter;
    uint64_t *seg = (uint64_t *)malloc((count + 1) * sizeof *seg);
    size_t seg_n = 0, i, bad_interval = 0, uv_moves = 0, bad_height = 0, bad_time = 0, bad_mask = 0;
    size_t steps_after_home = 0, homed_at = 0, shows_in_record = 0;
    int uv = 0, last_dir = 0, homed = 0;
    uint64_t uv_since = 0, last_step = 0, lit = 0;
    uint32_t layer = e->first, starts = 0;
    uint32_t shown_crc = 0;
    memset(&s, 0, sizeof s);
    if (!seg) { CHECK(!"out of memory"); return s; }
    for (i = 0; i < count; i++) shows_in_record += ev[i].kind == ZEV_SHOW && ev[i].value >= 0;
    for (i = 0; i <= count; i++) {
        const zevent *v = i < count ? &ev[i] : NULL;
        int boundary = !v || (v->kind == ZEV_STEP && seg_n &&
                              (v->value != last_dir || (double)(v->when - seg[seg_n - 1]) > rest_gap));
        if (boundary && seg_n) {
            zcheck_move(e, seg, seg_n, from_rest, &m, &s);
            seg_n = 0;
        }
        if (!v) break;
        if (v->kind == ZEV_STEP) {
            if (s.steps && v->when - last_step + 2u * e->jitter < min_interval) bad_interval++;
            if (s.steps && v->when > last_step) {
                double ratio = (double)e->tick_hz / (double)(v->when - last_step) / e->max_speed;
                if (ratio > s.worst_speed_ratio) s.worst_speed_ratio = ratio;
            }
            if (uv) uv_moves++;
            pos += v->value;
            last_dir = v->value;
            last_step = v->when;
            seg[seg_n++] = v->when;
            s.steps++;
            steps_after_home++;
            if (pos == 0) { homed = 1; homed_at = s.steps; steps_after_home = 0; }
        } else if (v->kind == ZEV_SHOW) {
            if (v->value >= 0) {
                /* each layer shows its mask once; a pause splits only its light */
                if (s.shows) zcheck_exposure(e, layer++, lit, &bad_time, &s);
                lit = 0;
                s.shows++;
                shown_crc = v->crc;
                if (layer <= e->layers && e->crcs && e->crcs[layer - 1] && shown_crc != e->crcs[layer - 1] && bad_mask++ < 3)
                    CHECKF(0, "layer %u shows a mask of CRC %08x, the host sent %08x", layer, (unsigned)shown_crc,
                           (unsigned)e->crcs[layer - 1]);
            }
        } else if (v->kind == ZEV_UV && v->value && !uv) {
            if (!shows_in_record && starts++) { zcheck_exposure(e, layer++, lit, &bad_time, &s); lit = 0; }
            uv = 1;
            uv_since = v->when;
            if (layer <= e->layers) {
                int64_t want = zcheck_steps_of(e, e->top_bins[layer - 1]);
                if (pos != want && bad_height++ < 3)
                    CHECKF(0, "layer %u exposed at %lld steps, its top is %lld", layer, (long long)pos, (long long)want);
            }
        } else if (v->kind == ZEV_UV && !v->value && uv) {
            uv = 0;
            lit += v->when - uv_since;
        }
    }
    if (s.shows || (!shows_in_record && starts)) zcheck_exposure(e, layer, lit, &bad_time, &s);
    free(seg);
    CHECKF(s.exposures == e->layers - e->first + 1, "%zu exposures for layers %u..%u", s.exposures, e->first, e->layers);
    CHECKF(!bad_interval, "%zu step intervals shorter than %llu ticks less twice %u of jitter", bad_interval,
           (unsigned long long)min_interval, (unsigned)e->jitter);
    CHECKF(!m.bad_accel, "%zu windows accelerate beyond the limit (worst %.3f of it)", m.bad_accel, s.worst_accel_ratio);
    CHECKF(!m.bad_ramp && !m.bad_first, "%zu ramp windows under 0.98 of the limit (lowest %.4f), %zu moves off from rest",
           m.bad_ramp, s.lowest_ramp_ratio, m.bad_first);
    CHECKF(!uv_moves, "%zu steps taken with the UV light on", uv_moves);
    CHECK(!bad_height && !bad_time && !bad_mask);
    if (e->path_nm && e->path_len) {
        int64_t want = 0, at = 0;
        size_t k;
        for (k = 0; k < e->path_len; k++) {
            int64_t to = zcheck_steps_of_nm(e, e->path_nm[k]);
            want += to > at ? to - at : at - to;
            at = to;
        }
        home_pos = pos;
        CHECKF(homed && (int64_t)steps_after_home == want && home_pos == at,
               "%zu steps after homing (step %zu), the heights moved come to %lld; Z ends at %lld steps, the path at %lld",
               steps_after_home, homed_at, (long long)want, (long long)home_pos, (long long)at);
    }
    return s;
}
#endif
