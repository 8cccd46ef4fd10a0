/* The firmware core on a make-believe printer, in process: a port that keeps
   what the core did (steps with their ticks, UV, masks shown with the CRC-32
   of the display buffer, bytes sent) and a host side that frames messages.
   For tests/test_firmware.c and tests/fuzz_firmware.c. One includer per
   program (static functions). */
#ifndef ADASLICE_FAKEPORT_H
#define ADASLICE_FAKEPORT_H
#include "../firmware/fw.h"
#include "zcheck.h"
#include <stdlib.h>
#include <string.h>

#define FAKE_TICK_HZ 10000000u
#ifndef FAKE_MAX_BINS
#define FAKE_MAX_BINS 12000u
#endif


typedef struct fake_printer {
    fw_state fw;
    fw_config config;
    uint64_t workspace[(FW_PLAN_WORKSPACE(FAKE_MAX_BINS) + 7) / 8];
    uint64_t now;
    uint64_t step_at;            /* the step timer's compare, FW_NEVER when disarmed */
    uint64_t uv_off_at;          /* the UV timer's end, FW_NEVER when the light is off */
    int32_t true_position;       /* steps above the endstop's switching point */
    uint8_t display[2][64 * 1024];
    /* what the core did */
    zevent *events;
    size_t event_count, event_cap;
    int keep_events;
    int exit_code;
    /* the host's side */
    uint8_t seq;
    link_deframer rx;
    link_status status;          /* the latest STATUS reply */
    uint8_t plan[LINK_FRAME_MAX];
    size_t plan_size;
    int acks, naks, statuses, identifies, plans;
    uint32_t rows;               /* mask rows the core wrote to the display */
    char text[16384];            /* everything sent, as text (G-code replies) */
    size_t text_len;
    uint64_t heartbeat, last_beat; /* a STATUS every `heartbeat` ticks while running, if set */
} fake_printer;

static inline void fake_record(fake_printer *p, uint64_t when, int kind, int value, uint32_t crc)
{
    if (!p->keep_events) return;
    if (p->event_count == p->event_cap) {
        size_t cap = p->event_cap ? 2 * p->event_cap : 4096;
        zevent *e = (zevent *)realloc(p->events, cap * sizeof *e);
        if (!e) return;
        p->events = e;
        p->event_cap = cap;
    }
    p->events[p->event_count].when = when;
    p->events[p->event_count].kind = kind;
    p->events[p->event_count].value = value;
    p->events[p->event_count].crc = crc;
    p->event_count++;
}

static inline void fake_write(void *ctx, const uint8_t *data, size_t size)
{
    fake_printer *p = (fake_printer *)ctx;
    size_t i, n;
    for (i = 0; i < size; i++) {
        if (p->text_len + 1 < sizeof p->text) { p->text[p->text_len++] = (char)data[i]; p->text[p->text_len] = 0; }
        link_deframe_push(&p->rx, data[i]);
        while ((n = link_deframe_next(&p->rx)) != 0) {
            const uint8_t *f = p->rx.buf;
            switch (f[2]) {
            case LINK_MSG_ACK: if (f[3]) p->naks++; else p->acks++; break;
            case LINK_MSG_STATUS_REPLY: if (link_get_status(&p->status, f + 3, n - LINK_FRAME_MIN)) p->statuses++; break;
            case LINK_MSG_IDENTIFY: p->identifies++; break;
            case LINK_MSG_PLAN: memcpy(p->plan, f + 3, n - LINK_FRAME_MIN); p->plan_size = n - LINK_FRAME_MIN; p->plans++; break;
            default: break;
            }
            link_deframe_consume(&p->rx);
        }
    }
}

/* The timers are ideal: the step interrupt runs at the tick it was armed
   for (fake_run stops there), so a step is late only if the core queued it
   late, which the core itself refuses. */
static inline int fake_step_arm(void *ctx, uint64_t when, int dir)
{
    fake_printer *p = (fake_printer *)ctx;
    (void)dir;
    if (when != FW_NEVER && when < p->now) return 0;
    p->step_at = when;
    return 1;
}

static inline void fake_step_pulse(void *ctx, int dir)
{
    fake_printer *p = (fake_printer *)ctx;
    p->true_position += dir;
    fake_record(p, p->now, ZEV_STEP, dir, 0);
}

static inline int fake_endstop(void *ctx) { return ((fake_printer *)ctx)->true_position <= 0; }

static inline void fake_uv(void *ctx, int on, uint64_t when, uint64_t until)
{
    fake_printer *p = (fake_printer *)ctx;
    if (on) p->uv_off_at = until;
    else if (p->uv_off_at == FW_NEVER) return; /* its timer has put it out already */
    else p->uv_off_at = FW_NEVER;
    fake_record(p, when, ZEV_UV, on, 0);
}

/* The interrupts due by p->now, in the order their ticks come. */
static inline void fake_interrupts(fake_printer *p)
{
    for (;;) {
        uint64_t t = p->step_at < p->uv_off_at ? p->step_at : p->uv_off_at;
        if (t > p->now) return;
        if (t == p->uv_off_at) {
            p->uv_off_at = FW_NEVER;
            fake_record(p, t, ZEV_UV, 0, 0);
        } else {
            uint64_t now = p->now;
            p->step_at = FW_NEVER;
            p->now = t;
            fw_step_interrupt(&p->fw);
            p->now = now;
        }
    }
}

static inline void fake_motor(void *ctx, int on) { (void)ctx; (void)on; }

static inline void fake_mask_row(void *ctx, int slot, uint32_t y, const uint8_t *row, uint32_t size)
{
    fake_printer *p = (fake_printer *)ctx;
    p->rows++;
    if ((size_t)(y + 1) * size <= sizeof p->display[0]) memcpy(p->display[slot] + (size_t)y * size, row, size);
}

static inline void fake_show(void *ctx, int slot, uint64_t when)
{
    fake_printer *p = (fake_printer *)ctx;
    const fw_config *c = &p->config;
    size_t stride = c->display_bits == 1 ? (c->display_width + 7u) / 8u : c->display_width;
    uint32_t crc = slot >= 0 ? adaslice_crc32(0, p->display[slot], stride * c->display_height) : 0;
    fake_record(p, when, ZEV_SHOW, slot, crc);
}

static inline void fake_exit(void *ctx, int code) { ((fake_printer *)ctx)->exit_code = code; }

/* A printer of 400 steps/mm, 10 mm/s, 50 mm/s^2 with a w x h display. */
static inline void fake_init(fake_printer *p, uint16_t w, uint16_t h, uint8_t bits)
{
    fw_port port;
    memset(p, 0, sizeof *p);
    p->config.tick_hz = FAKE_TICK_HZ;
    p->config.axis.steps_per_mm = 400;
    p->config.axis.max_speed = 4000;
    p->config.axis.accel = 20000;
    p->config.axis.home_speed = 2000;
    p->config.axis.max_steps = 400 * 200;
    p->config.axis.home_travel = 400 * 220;
    p->config.display_width = w;
    p->config.display_height = h;
    p->config.display_bits = bits;
    p->config.pitch_nm = 50000;
    p->config.max_bins = FAKE_MAX_BINS;
    p->config.link_timeout_ms = 1000;
    p->config.window = 8;
    p->true_position = 400 * 37 + 123;
    p->step_at = p->uv_off_at = FW_NEVER;
    port.ctx = p;
    port.write = fake_write;
    port.step_arm = fake_step_arm;
    port.step_pulse = fake_step_pulse;
    port.watchdog = NULL;
    port.endstop = fake_endstop;
    port.uv = fake_uv;
    port.motor = fake_motor;
    port.mask_row = fake_mask_row;
    port.show = fake_show;
    port.exit = fake_exit;
    link_deframer_init(&p->rx, link_mcu_to_host_type);
    fw_init(&p->fw, &p->config, &port, p->workspace, sizeof p->workspace);
}

static inline void fake_free(fake_printer *p) { free(p->events); p->events = NULL; }

/* Bytes to the core, which may take them over several passes (a long mask
   frame, or none while its step queue is to be refilled first): the
   passes run at once, at p->now. */
static inline void fake_bytes(fake_printer *p, const uint8_t *data, size_t size)
{
    while (size) {
        size_t n = fw_receive(&p->fw, data, size, p->now);
        data += n;
        size -= n;
        while (p->fw.decoding) (void)fw_run(&p->fw, p->now);
        if (!n) (void)fw_run(&p->fw, p->now);
    }
}

/* Frames a message from the host with the next sequence number. */
static inline void fake_send(fake_printer *p, uint8_t type, const uint8_t *payload, size_t size)
{
    uint8_t frame[LINK_FRAME_MAX];
    size_t n = link_frame_build(frame, p->seq++, type, payload, size);
    fake_bytes(p, frame, n);
}

/* Sends `size` bytes as messages of `type`, at most `max` a frame. */
static inline void fake_send_chunks(fake_printer *p, uint8_t type, const uint8_t *data, size_t size, size_t max)
{
    size_t at = 0;
    while (at < size) {
        size_t chunk = size - at > max ? max : size - at;
        fake_send(p, type, data + at, chunk);
        at += chunk;
    }
}

/* A quantised profile as a host sends it. With `rng`, frames of random size
   split varints across frames; without, frames are full. */
static inline void fake_send_profile(fake_printer *p, const uint32_t *units, const unsigned char *forced, uint32_t n,
                                     uint8_t lo, uint8_t hi, uint32_t eps_units, uint32_t bin_nm, unsigned (*rng)(void))
{
    uint8_t hdr[LINK_SIZE_PROFILE], *code = (uint8_t *)malloc((size_t)n * 5 + 1);
    size_t size = 0, at = 0;
    uint32_t i = 0;
    link_profile m;
    m.bins = n;
    m.bins_min = lo;
    m.bins_max = hi;
    m.eps_units = eps_units;
    m.bin_nm = bin_nm;
    fake_send(p, LINK_MSG_PROFILE, hdr, link_put_profile(hdr, &m));
    if (!code) return;
    size = link_profile_chunk(code, (size_t)n * 5 + 1, units, forced, n, &i);
    while (at < size) {
        size_t chunk = rng ? 1 + rng() % LINK_PAYLOAD_MAX : LINK_PAYLOAD_MAX;
        if (chunk > size - at) chunk = size - at;
        fake_send(p, LINK_MSG_PROFILE_DATA, code + at, chunk);
        at += chunk;
    }
    free(code);
}

/* The printer's plan, page by page, into lengths[0 .. cap); returns its
   layer count, 0 if a page did not come. */
static inline uint32_t fake_read_plan(fake_printer *p, uint32_t *lengths, uint32_t cap)
{
    uint32_t k = 1, layers = 0;
    do {
        uint8_t req[LINK_SIZE_PLAN_GET];
        link_plan_get get;
        link_plan page;
        size_t m;
        get.first = k;
        fake_send(p, LINK_MSG_PLAN_GET, req, link_put_plan_get(req, &get));
        if (!link_get_plan(&page, p->plan, p->plan_size) || page.first != k) return 0;
        layers = page.layers;
        for (m = LINK_SIZE_PLAN; m < p->plan_size && k <= layers && k <= cap; m++) lengths[k++ - 1] = p->plan[m];
    } while (k <= layers && k <= cap);
    return layers;
}

/* Runs the core until `until` (ticks), jumping from deadline to deadline. */
static inline void fake_run(fake_printer *p, uint64_t until)
{
    for (;;) {
        uint64_t next;
        fake_interrupts(p);
        next = fw_run(&p->fw, p->now);
        if (p->step_at < next) next = p->step_at;
        if (p->uv_off_at < next) next = p->uv_off_at;
        if (p->heartbeat) {
            if (p->now - p->last_beat >= p->heartbeat) { fake_send(p, LINK_MSG_STATUS, NULL, 0); p->last_beat = p->now; continue; }
            if (next > p->last_beat + p->heartbeat) next = p->last_beat + p->heartbeat;
        }
        if (next > until) { p->now = until; fake_interrupts(p); fw_run(&p->fw, p->now); return; }
        if (next > p->now) p->now = next;
    }
}

static inline uint8_t fake_state(fake_printer *p)
{
    fake_send(p, LINK_MSG_STATUS, NULL, 0);
    return p->status.state;
}
#endif
