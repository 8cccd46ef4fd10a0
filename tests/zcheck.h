/* What a print must look like from the printer's pins, checked on a record
   of events (steps with their ticks, UV on/off, masks shown): shared by the
   in-process firmware tests and the simulator's log over a pty.
     - at every exposure Z is exactly at the layer's top: round(top bins x
       bin_nm x steps/mm / 1e6) steps above the endstop (no drift);
     - the UV light is never on while a step is taken;
     - no step interval is shorter than the maximum speed allows;
     - acceleration stays within its limit, measured between the mean
       speeds of consecutive windows of 8 steps (for constant acceleration
       that estimate is exact; a tick of rounding moves it well under 2 %);
     - each layer shows the expected mask once and gets exactly its light
       (in pieces if a pause came in between). */
#ifndef ADASLICE_ZCHECK_H
#define ADASLICE_ZCHECK_H
#include "check.h"
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

typedef struct zevent { uint64_t when; int kind, value; uint32_t crc; } zevent;
enum { ZEV_STEP = 1, ZEV_UV, ZEV_SHOW };

typedef struct zexpect {
    uint64_t tick_hz;
    uint32_t steps_per_mm, max_speed, accel;
    int64_t start_position;       /* steps above the switch before homing */
    uint32_t layers, first;       /* layers exposed: first .. layers */
    const uint32_t *top_bins;     /* [layers]: top plane of each layer, bins */
    uint32_t bin_nm;
    const uint32_t *crcs;         /* [layers] or NULL; 0: a mask not known */
    const uint32_t *exposure_ms;  /* [layers]: the light each layer must get */
} zexpect;

typedef struct zsummary { size_t steps, exposures, shows; double worst_accel_ratio, worst_speed_ratio; } zsummary;

static inline int64_t zcheck_steps_of(const zexpect *e, uint32_t bins)
{
    uint64_t num = (uint64_t)bins * e->bin_nm * e->steps_per_mm;
    return (int64_t)((num + 500000u) / 1000000u);
}

/* The light a layer got, all its pieces together. */
static inline void zcheck_exposure(const zexpect *e, uint32_t layer, uint64_t lit, size_t *bad, zsummary *s)
{
    uint64_t want = (uint64_t)e->exposure_ms[layer - 1] * e->tick_hz / 1000u;
    if (lit != want && (*bad)++ < 3)
        CHECKF(0, "layer %u got %llu ticks of light, not %llu", layer, (unsigned long long)lit, (unsigned long long)want);
    s->exposures++;
}

static inline zsummary zcheck_record(const zevent *ev, size_t count, const zexpect *e)
{
    zsummary s = {0, 0, 0, 0, 0};
    int64_t pos = e->start_position;
    uint64_t min_interval = (e->tick_hz + e->max_speed - 1) / e->max_speed;
    /* the first interval from rest, sqrt(2/a) s, is the longest within a move */
    double from_rest = sqrt(2.0 / e->accel) * (double)e->tick_hz * 1.01 + 2;
    uint64_t *seg = (uint64_t *)malloc((count + 1) * sizeof *seg);
    size_t seg_n = 0, i, bad_interval = 0, bad_accel = 0, uv_moves = 0, bad_height = 0, bad_time = 0, bad_mask = 0;
    int uv = 0, last_dir = 0;
    uint64_t uv_since = 0, last_step = 0, lit = 0;
    uint32_t layer = e->first;
    uint32_t shown_crc = 0;
    if (!seg) { CHECK(!"out of memory"); return s; }
    for (i = 0; i <= count; i++) {
        const zevent *v = i < count ? &ev[i] : NULL;
        int boundary = !v || (v->kind == ZEV_STEP && seg_n &&
                              (v->value != last_dir || (double)(v->when - seg[seg_n - 1]) > from_rest));
        if (boundary && seg_n) {
            size_t k;
            for (k = 0; k + 16 < seg_n; k++) {
                double d1 = (double)(seg[k + 8] - seg[k]), d2 = (double)(seg[k + 16] - seg[k + 8]);
                double v1 = 8.0 * e->tick_hz / d1, v2 = 8.0 * e->tick_hz / d2;
                double dt = (double)(seg[k + 16] - seg[k]) / 2 / e->tick_hz;
                double ratio = fabs(v2 - v1) / dt / e->accel;
                /* a step's tick is its ideal time rounded to a whole tick:
                   each window's span is within a tick of the ideal's, which
                   moves its speed by up to 8 hz / (d (d - 1)); at a fast
                   step rate that is more than the 2 % */
                double rounding = (d1 > 1 && d2 > 1 ? 8.0 * e->tick_hz / (d1 * (d1 - 1)) + 8.0 * e->tick_hz / (d2 * (d2 - 1)) : 1e300) / dt / e->accel;
                if (ratio > s.worst_accel_ratio) s.worst_accel_ratio = ratio;
                if (ratio - rounding > 1.02) bad_accel++;
            }
            seg_n = 0;
        }
        if (!v) break;
        if (v->kind == ZEV_STEP) {
            if (s.steps && v->when - last_step < min_interval) bad_interval++;
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
    if (s.shows) zcheck_exposure(e, layer, lit, &bad_time, &s);
    free(seg);
    CHECKF(s.exposures == e->layers - e->first + 1, "%zu exposures for layers %u..%u", s.exposures, e->first, e->layers);
    CHECKF(!bad_interval, "%zu step intervals shorter than %llu ticks", bad_interval, (unsigned long long)min_interval);
    CHECKF(!bad_accel, "%zu windows accelerate beyond the limit (worst %.3f of it)", bad_accel, s.worst_accel_ratio);
    CHECKF(!uv_moves, "%zu steps taken with the UV light on", uv_moves);
    CHECK(!bad_height && !bad_time && !bad_mask);
    return s;
}
#endif
