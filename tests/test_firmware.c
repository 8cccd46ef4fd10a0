/* The firmware core in process, on a make-believe printer (tests/fakeport.h):
   its plans against the host's bit for bit, the link's recovery, masks
   checked before they are shown, and a 1,000-layer print's motion. */
#include "fakeport.h"
#include "../adaslice.h"
#include "check.h"
#include "plan_oracle.h"
#include <stdlib.h>
#include <string.h>

static unsigned fw_rng_state = 4242u;
static unsigned fw_rng(void) { fw_rng_state = fw_rng_state * 1103515245u + 12345u; return (fw_rng_state >> 8) & 0xffffffu; }

/* Thousands of random profiles: the MCU's plan, made from the integers on
   the wire, has the fewest layers and the smallest worst layer that the
   quadratic oracle finds (tests/plan_oracle.h) and keeps every rule; it
   equals adaslice_plan_profile's with the same options, layer by layer; where
   the host finds no plan, neither does the MCU. */
static void mcu_plans_like_the_host(void)
{
    static fake_printer p;
    static double phi[3000];
    static uint32_t units[3000], lengths[3000];
    static unsigned char forced[3000];
    int trial, mismatches = 0, plans = 0, infeasible = 0, oracle_misses = 0;
    for (trial = 0; trial < 2000; trial++) {
        adaslice_profile prof;
        adaslice_plan_options o;
        adaslice_plan plan;
        uint32_t n = 40 + fw_rng() % (trial % 10 == 0 ? 2900 : 400), i, k, layers;
        double bin = 0.002;
        int feasible;
        fake_init(&p, 8, 8, 1);
        memset(&prof, 0, sizeof prof);
        for (i = 0; i < n; i++) phi[i] = fw_rng() % 60 == 0 ? 2.0 + (fw_rng() % 100) / 20.0 : (fw_rng() % 100000) / 99991.0;
        prof.metric = trial % 3 ? ADASLICE_METRIC_CUSP : ADASLICE_METRIC_AREA;
        prof.bin_count = n; prof.bin = bin; prof.phi = phi; prof.height = n * bin;
        memset(&o, 0, sizeof o);
        o.eps_units = ADASLICE_PRINTER_EPS_UNITS;
        o.eps = 0.02 + (fw_rng() % 80) / 1000.0;
        o.tmin = 0.05; o.tmax = trial % 4 == 0 ? 0.25 : 0.15;
        o.sharp = trial % 2 ? ADASLICE_SHARP_OFF : 1.0;
        CHECK(adaslice_plan_units(&prof, &o, units, forced, NULL) == ADASLICE_OK);
        feasible = adaslice_plan_profile(&prof, &o, &plan, NULL) == ADASLICE_OK;
        fake_send_profile(&p, units, forced, n, 25, (uint8_t)(o.tmax / bin + 0.5), o.eps_units, 2000, fw_rng);
        {   /* the oracle: fewest layers, then the smallest worst, and the MCU's plan keeps every rule */
            oracle_plan want = oracle_fewest_layers(units, forced, n, 25, (uint32_t)(o.tmax / bin + 0.5), o.eps_units);
            uint32_t got = fake_state(&p) == LINK_STATE_READY ? fake_read_plan(&p, lengths, 3000) : 0;
            uint64_t worst;
            if (got != want.layers ||
                (got && (!oracle_plan_is_valid(units, forced, n, 25, (uint32_t)(o.tmax / bin + 0.5), o.eps_units, lengths,
                                               got, &worst) || worst != want.worst)))
                oracle_misses++;
        }
        if (!feasible) {
            infeasible++;
            if (fake_state(&p) != LINK_STATE_IDLE || p.status.error != LINK_ERR_INFEASIBLE) mismatches++;
            continue;
        }
        plans++;
        layers = fake_state(&p) == LINK_STATE_READY ? fake_read_plan(&p, lengths, 3000) : 0;
        if (layers != plan.layer_count) mismatches++;
        else for (k = 0; k < layers; k++) if (lengths[k] != plan.planes[k + 1] - plan.planes[k]) { mismatches++; break; }
        adaslice_plan_free(&plan);
    }
    CHECKF(oracle_misses == 0, "%d of 2000 MCU plans differ from the oracle", oracle_misses);
    CHECKF(mismatches == 0 && plans > 1000 && infeasible > 20, "%d of %d plans differ (%d infeasible)", mismatches,
           plans + infeasible, infeasible);
}

/* N = 12,000 bins plan in the MCU's workspace, which is under 16 KiB. */
static void twelve_thousand_bins_fit(void)
{
    static fake_printer p;
    static uint32_t units[12000];
    uint32_t i;
    CHECKF(FW_PLAN_WORKSPACE(12000) <= 16384, "workspace %zu bytes", (size_t)FW_PLAN_WORKSPACE(12000));
    CHECK(adaslice_dp_workspace(12000, FW_MAX_LAYER_BINS, 0) <= FW_PLAN_WORKSPACE(12000));
    fake_init(&p, 8, 8, 1);
    for (i = 0; i < 12000; i++) units[i] = 1000 + fw_rng() % 30000;
    fake_send_profile(&p, units, NULL, 12000, 25, 75, ADASLICE_PRINTER_EPS_UNITS, 2000, fw_rng);
    CHECK(fake_state(&p) == LINK_STATE_READY && p.status.bins_in == 12000 && p.status.layers >= 160);
    {
        uint8_t hdr[LINK_SIZE_PROFILE];
        link_profile m = {12001, 25, 75, ADASLICE_PRINTER_EPS_UNITS, 2000};
        fake_send(&p, LINK_MSG_PROFILE, hdr, link_put_profile(hdr, &m));
        /* refused, and the plan made before is kept */
        CHECK(fake_state(&p) == LINK_STATE_READY && p.status.error == LINK_ERR_PLAN_SIZE);
    }
}

/* Damaged, repeated and missing frames. */
static void link_recovers(void)
{
    static fake_printer p;
    uint8_t frame[LINK_FRAME_MAX], hello = LINK_PROTOCOL_VERSION;
    size_t n;
    int acks;
    fake_init(&p, 8, 8, 1);
    n = link_frame_build(frame, 77, LINK_MSG_HELLO, &hello, 1);
    fake_bytes(&p, (const uint8_t *)"\x7e\x00\x03garbage~", 11);
    fake_bytes(&p, frame, n);
    CHECK(p.identifies == 1 && p.fw.deframer.bad == 1); /* the garbage: a frame of no known type */
    p.seq = 78;
    /* a corrupted STATUS is ignored and counted; the next one is answered */
    n = link_frame_build(frame, p.seq, LINK_MSG_STATUS, NULL, 0);
    frame[2] ^= 0x10;
    fake_bytes(&p, frame, n);
    CHECK(p.statuses == 0 && p.fw.deframer.bad == 2);
    CHECK(fake_state(&p) == LINK_STATE_IDLE && p.statuses == 1);
    /* frames from the future (one was lost): each draws a NAK, none is run */
    n = link_frame_build(frame, (uint8_t)(p.seq + 1), LINK_MSG_STATUS, NULL, 0);
    fake_bytes(&p, frame, n);
    fake_bytes(&p, frame, n);
    CHECK(p.naks == 2 && p.statuses == 1);
    /* a repeat of a frame already taken is acknowledged, not run again */
    acks = p.acks;
    n = link_frame_build(frame, (uint8_t)(p.seq - 1), LINK_MSG_HOME, NULL, 0);
    fake_bytes(&p, frame, n);
    CHECK(p.acks == acks + 1 && p.fw.state == LINK_STATE_IDLE);
    /* sequence numbers wrap */
    for (n = 0; n < 300; n++) fake_send(&p, LINK_MSG_STATUS, NULL, 0);
    CHECK(p.statuses == 301 && p.naks == 2);
    /* data out of place is refused, never pushed into a planner not set up for it
       (fuzzing found PROFILE_DATA after PLAN_SET doing that) */
    {
        uint8_t hdr[LINK_SIZE_PLAN_SET], data[4] = {0x81, 0x02, 0x03, 0x04};
        link_plan_set m = {3, 2000};
        fake_send(&p, LINK_MSG_PLAN_SET, hdr, link_put_plan_set(hdr, &m));
        fake_send(&p, LINK_MSG_PROFILE_DATA, data, 4);
        CHECK(fake_state(&p) == LINK_STATE_PLANNING && p.status.error == LINK_ERR_BUSY);
        fake_send(&p, LINK_MSG_PLAN_DATA, data + 1, 3);
        CHECK(fake_state(&p) == LINK_STATE_READY && p.status.layers == 3);
        fake_send(&p, LINK_MSG_PLAN_DATA, data + 1, 3);
        CHECK(fake_state(&p) == LINK_STATE_READY && p.status.error == LINK_ERR_BUSY);
    }
    /* a wrong payload size is refused with its sequence number */
    fake_send(&p, LINK_MSG_MOVE, frame, 3);
    CHECK(fake_state(&p) == LINK_STATE_READY && p.status.error == LINK_ERR_MESSAGE && p.status.error_seq == (uint8_t)(p.seq - 2));
    fake_free(&p);
}

static void send_plan(fake_printer *p, const uint8_t *lengths, uint32_t layers, uint32_t bin_nm)
{
    uint8_t hdr[LINK_SIZE_PLAN_SET];
    link_plan_set m;
    m.layers = layers;
    m.bin_nm = bin_nm;
    fake_send(p, LINK_MSG_PLAN_SET, hdr, link_put_plan_set(hdr, &m));
    fake_send_chunks(p, LINK_MSG_PLAN_DATA, lengths, layers, LINK_PAYLOAD_MAX);
}

static void send_mask(fake_printer *p, uint32_t layer, const uint8_t *code, size_t size, uint32_t crc, uint32_t exposure_ms)
{
    uint8_t hdr[LINK_SIZE_MASK];
    link_mask m;
    m.layer = layer;
    m.code_bytes = (uint32_t)size;
    m.crc32 = crc;
    m.exposure_ms = exposure_ms;
    fake_send(p, LINK_MSG_MASK, hdr, link_put_mask(hdr, &m));
    fake_send_chunks(p, LINK_MSG_MASK_DATA, code, size, LINK_PAYLOAD_MAX);
}

static void start_print(fake_printer *p, uint32_t first)
{
    uint8_t pr[LINK_SIZE_PRINT];
    link_print m;
    m.first_layer = first;
    m.peel_nm = 5000000;        /* peel 5 mm */
    m.peel_speed_um_s = 3000;   /* 3 mm/s up */
    m.return_speed_um_s = 0;    /* down as fast as the axis goes */
    m.settle_ms = 200;
    m.job = 0x600d;
    fake_send(p, LINK_MSG_PRINT, pr, link_put_print(pr, &m));
}

static void home(fake_printer *p)
{
    fake_send(p, LINK_MSG_HOME, NULL, 0);
    fake_run(p, p->now + 60ull * FAKE_TICK_HZ);
    CHECK(fake_state(p) == LINK_STATE_IDLE || p->status.state == LINK_STATE_READY);
    CHECK((p->status.flags & LINK_FLAG_HOMED) && p->true_position == 0);
}

/* A mask of 400 equal rows is a row and one repeat record: the core puts
   at most FW_CRC_BYTES of rows through the CRC a pass (a row is copied once
   its CRC is in; a repeated row costs at most ADASLICE_RLE_REPEAT_COST, its
   CRC being a multiplication), never the whole repeat in one call nor
   a wide row's CRC, and acknowledges the frame once it is decoded. */
static void mask_rows_of_width(uint32_t width)
{
    static fake_printer p;
    static uint8_t image[400 * FW_ROW_BYTES], code[256], frame[LINK_FRAME_MAX];
    uint8_t lengths[1] = {30}, hdr[LINK_SIZE_MASK];
    uint32_t stride = (width + 7u) / 8u, cheapest = stride > ADASLICE_RLE_REPEAT_COST ? ADASLICE_RLE_REPEAT_COST : stride;
    uint32_t most = (FW_CRC_BYTES - 1u) / cheapest + 1u; /* rows a pass can finish */
    size_t n, k, taken, framed;
    uint32_t rows, passes = 0, worst = 0;
    int acks;
    link_mask m;
    fake_init(&p, (uint16_t)width, 400, 1);
    memset(image, 0, sizeof image);
    for (k = 0; k < 400u * stride; k++) image[k] = (uint8_t)(k % stride == 3 ? 0x3c : 0);
    CHECK(adaslice_rle_encode(image, stride, width, 400, 1, code, sizeof code, &n) == ADASLICE_OK && n < 16);
    send_plan(&p, lengths, 1, 2000);
    m.layer = 1;
    m.code_bytes = (uint32_t)n;
    m.crc32 = adaslice_crc32(0, image, 400u * stride);
    m.exposure_ms = 1000;
    fake_send(&p, LINK_MSG_MASK, hdr, link_put_mask(hdr, &m));
    framed = link_frame_build(frame, p.seq++, LINK_MSG_MASK_DATA, code, n);
    acks = p.acks;
    rows = p.rows;
    taken = fw_receive(&p.fw, frame, framed, p.now);
    CHECKF(taken == framed && p.fw.decoding && p.rows - rows <= most && p.acks == acks,
           "took %zu of %zu bytes, %u rows at once", taken, framed, p.rows - rows);
    CHECK(fw_receive(&p.fw, frame, framed, p.now) == 0); /* nothing more while it decodes */
    while (p.fw.decoding && passes < 100000) {
        rows = p.rows;
        (void)fw_run(&p.fw, p.now);
        if (p.rows - rows > worst) worst = p.rows - rows;
        passes++;
    }
    CHECKF(worst <= most && passes + 1 >= (stride + 399u * cheapest) / FW_CRC_BYTES && p.rows == 400 && p.acks == acks + 1,
           "%u-pixel rows: %u passes for %u bytes of rows' CRC, at most %u rows in one, %u rows, %d acks", width, passes,
           stride + 399u * cheapest, worst, p.rows, p.acks - acks);
    CHECK(fake_state(&p) == LINK_STATE_READY && p.status.mask_ready == 1 && p.status.masks_refused == 0);
}

static void mask_decoding_takes_bounded_slices(void)
{
    mask_rows_of_width(64);
    mask_rows_of_width(FW_ROW_BYTES * 8u); /* the widest row a display may have */
}

/* Homed, recording, half a second into a MOVE to 10 mm. */
static void start_a_move(fake_printer *p)
{
    uint8_t mv[LINK_SIZE_MOVE];
    link_move move;
    fake_init(p, 8, 8, 1);
    home(p);
    p->keep_events = 1;
    move.z_nm = 10000000;
    move.speed_um_s = 0;
    fake_send(p, LINK_MSG_MOVE, mv, link_put_move(mv, &move));
    fake_run(p, p->now + FAKE_TICK_HZ / 2);
    CHECK(fake_state(p) == LINK_STATE_MOVING);
}

/* A speed under a step a second is a step a second: 0 steps/s is the
   axis's top speed, and a peel asked at 2 um/s (0.8 steps/s at 400
   steps/mm) ran at 10 mm/s. 1 um/s, 4 steps up: one step in the first
   1.5 s, not all four in milliseconds. */
static void speeds_under_a_step_a_second_are_one(void)
{
    static fake_printer p;
    uint8_t mv[LINK_SIZE_MOVE];
    link_move move;
    fake_init(&p, 8, 8, 1);
    home(&p);
    move.z_nm = 4 * 1000000 / 400;
    move.speed_um_s = 1;
    fake_send(&p, LINK_MSG_MOVE, mv, link_put_move(mv, &move));
    fake_run(&p, p.now + FAKE_TICK_HZ * 3 / 2);
    CHECKF(p.true_position >= 1 && p.true_position <= 2 && fake_state(&p) == LINK_STATE_MOVING,
           "1 um/s: %d of 4 steps in 1.5 s", (int)p.true_position);
    fake_run(&p, p.now + FAKE_TICK_HZ * 5);
    CHECKF(p.true_position == 4, "1 um/s: %d of 4 steps in 6.5 s", (int)p.true_position);
}

/* The loop stalls 20 ms in the middle of a move while the step interrupt
   goes on: the queued steps leave on time, then the core finds the next step
   past due and stops dead (STEP_LATE, UV and motor off, Z unhomed) instead of
   sending the missed steps in a burst. */
static void a_stalled_loop_stops_the_motion(void)
{
    static fake_printer p;
    uint64_t stall;
    size_t k, steps = 0;
    uint64_t last = 0, shortest = UINT64_MAX;
    start_a_move(&p);
    /* only the interrupts run for 20 ms */
    stall = p.now + FAKE_TICK_HZ / 50;
    while (p.step_at <= stall) { p.now = p.step_at; fake_interrupts(&p); }
    p.now = stall;
    fake_run(&p, p.now + FAKE_TICK_HZ);
    CHECK(fake_state(&p) != LINK_STATE_MOVING && p.status.error == LINK_ERR_STEP_LATE);
    CHECK(!(p.status.flags & (LINK_FLAG_HOMED | LINK_FLAG_MOVING | LINK_FLAG_UV)));
    for (k = 0; k < p.event_count; k++) {
        if (p.events[k].kind != ZEV_STEP) continue;
        if (steps && p.events[k].when - last < shortest) shortest = p.events[k].when - last;
        last = p.events[k].when;
        steps++;
    }
    /* 4000 steps/s: no two steps closer than 2500 ticks; the move stopped short of its 4000 steps */
    CHECKF(steps > 100 && steps < 4000 && shortest >= FAKE_TICK_HZ / 4000u, "%zu steps, the closest %llu ticks apart",
           steps, (unsigned long long)shortest);
    CHECK(last < stall);
}

/* The port finds its stack's canary overwritten (fw_stack_fault) in the
   middle of a move, then of a G-code exposure: the motion stops dead and
   the light goes out at once, STATUS says STACK, and the core stays
   halted: a binary host's commands are refused with that error, G-code's
   M106 and G28 are told so, and nothing lights or steps again. */
static size_t events_after(const fake_printer *p, uint64_t t, int kind, int value)
{
    size_t k, n = 0;
    for (k = 0; k < p->event_count; k++)
        n += p->events[k].when > t && p->events[k].kind == kind && (value < 0 || p->events[k].value == value);
    return n;
}

static void a_stack_fault_halts_the_core(void)
{
    static fake_printer p;
    uint8_t ex[LINK_SIZE_EXPOSE];
    link_expose expose;
    uint64_t at;
    start_a_move(&p);
    at = p.now;
    fw_stack_fault(&p.fw, at);
    fake_run(&p, p.now + FAKE_TICK_HZ);
    CHECK(fake_state(&p) != LINK_STATE_MOVING && p.status.error == LINK_ERR_STACK);
    CHECK(!(p.status.flags & (LINK_FLAG_HOMED | LINK_FLAG_MOVING | LINK_FLAG_UV)));
    fake_send(&p, LINK_MSG_HOME, NULL, 0);
    fake_run(&p, p.now + 30ull * FAKE_TICK_HZ);
    CHECK(fake_state(&p) == LINK_STATE_IDLE && p.status.error == LINK_ERR_STACK && p.status.error_seq == (uint8_t)(p.seq - 2));
    expose.ms = 100;
    fake_send(&p, LINK_MSG_EXPOSE, ex, link_put_expose(ex, &expose));
    fake_run(&p, p.now + FAKE_TICK_HZ);
    CHECK(fake_state(&p) == LINK_STATE_IDLE && p.status.error == LINK_ERR_STACK && !(p.status.flags & LINK_FLAG_HOMED));
    CHECKF(!events_after(&p, at, ZEV_STEP, -1) && !events_after(&p, at, ZEV_UV, 1), "%zu steps, %zu lights after the fault",
           events_after(&p, at, ZEV_STEP, -1), events_after(&p, at, ZEV_UV, 1));
    fake_free(&p);

    /* G-code: the light M106 put on goes out at the fault */
    fake_init(&p, 8, 8, 1);
    fake_bytes(&p, (const uint8_t *)"G28\n", 4);
    fake_run(&p, p.now + 60ull * FAKE_TICK_HZ);
    p.keep_events = 1;
    fake_bytes(&p, (const uint8_t *)"M106\n", 5);
    fake_run(&p, p.now + FAKE_TICK_HZ / 10);
    CHECK(p.uv_off_at != FW_NEVER);
    at = p.now;
    fw_stack_fault(&p.fw, at);
    CHECK(p.uv_off_at == FW_NEVER && events_after(&p, at - 1, ZEV_UV, 0) == 1);
    CHECK(strstr(p.text, "Error:Printer halted") != NULL);
    p.text_len = 0;
    p.text[0] = 0;
    fake_bytes(&p, (const uint8_t *)"M106 S255\nG28\n", 15);
    fake_run(&p, p.now + 30ull * FAKE_TICK_HZ);
    /* M106 is G-code's own refusal after a stop (home first), G28 the halted core's */
    CHECKF(strstr(p.text, "Error:Stopped: home Z (G28) before UV") && strstr(p.text, "Error:Printer halted"),
           "M106 and G28 after the halt: %.200s", p.text);
    CHECKF(!events_after(&p, at, ZEV_STEP, -1) && !events_after(&p, at, ZEV_UV, 1), "%zu steps, %zu lights after the fault",
           events_after(&p, at, ZEV_STEP, -1), events_after(&p, at, ZEV_UV, 1));
    fake_free(&p);
}

/* A mask whose decoded CRC-32 differs is refused, never shown, and the layer
   waits with UV off until a good copy arrives. */
static void bad_masks_are_never_shown(void)
{
    static fake_printer p;
    static uint8_t image[64 * 48 / 8], code[4096];
    uint8_t lengths[2] = {30, 30};
    size_t n, k;
    uint32_t crc;
    fake_init(&p, 64, 48, 1);
    p.keep_events = 1;
    p.heartbeat = FAKE_TICK_HZ / 5;
    for (k = 0; k < sizeof image; k++) image[k] = (uint8_t)(k * 37 % 7 == 0 ? 0xf0 : 0);
    CHECK(adaslice_rle_encode(image, 8, 64, 48, 1, code, sizeof code, &n) == ADASLICE_OK);
    crc = adaslice_crc32(0, image, sizeof image);
    send_plan(&p, lengths, 2, 2000);
    home(&p);
    start_print(&p, 1);
    fake_run(&p, p.now + 5ull * FAKE_TICK_HZ);
    CHECK(fake_state(&p) == LINK_STATE_PRINTING && p.status.phase == LINK_PHASE_WAIT_MASK);
    send_mask(&p, 1, code, n, crc ^ 1, 1000);             /* the sender's CRC is wrong */
    CHECK(fake_state(&p) == LINK_STATE_PRINTING && p.status.error == LINK_ERR_MASK_CRC && p.status.masks_refused == 1);
    code[n / 2] ^= 0x01;                            /* the code is damaged */
    send_mask(&p, 1, code, n, crc, 1000);
    code[n / 2] ^= 0x01;
    CHECK(fake_state(&p) == LINK_STATE_PRINTING && p.status.masks_refused == 2 && p.status.mask_ready == 0);
    send_mask(&p, 2, code, n, crc, 1000);           /* out of order */
    CHECK(fake_state(&p) == LINK_STATE_PRINTING && p.status.error == LINK_ERR_MASK_ORDER);
    fake_run(&p, p.now + 5ull * FAKE_TICK_HZ);
    for (k = 0; k < p.event_count; k++) CHECK(p.events[k].kind != ZEV_UV && !(p.events[k].kind == ZEV_SHOW && p.events[k].value >= 0));
    {   /* no light, or more than an hour of it: refused at the header */
        uint8_t hdr[LINK_SIZE_MASK];
        link_mask m;
        uint32_t bad[2] = {0, FW_EXPOSURE_MAX_MS + 1};
        int b;
        for (b = 0; b < 2; b++) {
            m.layer = 1;
            m.code_bytes = (uint32_t)n;
            m.crc32 = crc;
            m.exposure_ms = bad[b];
            fake_send(&p, LINK_MSG_MASK, hdr, link_put_mask(hdr, &m));
            CHECKF(fake_state(&p) == LINK_STATE_PRINTING && p.status.error == LINK_ERR_MASK_EXPOSURE &&
                       p.status.masks_refused == 3 + b && p.status.mask_ready == 0,
                   "exposure %u ms: error %u", bad[b], p.status.error);
        }
    }
    send_mask(&p, 1, code, n, crc, 1000);
    fake_run(&p, p.now + FAKE_TICK_HZ / 10);
    CHECK(fake_state(&p) == LINK_STATE_PRINTING && p.status.mask_ready == 1 && p.status.phase >= LINK_PHASE_SETTLE);
    send_mask(&p, 2, code, n, crc, 1000);
    fake_run(&p, p.now + 30ull * FAKE_TICK_HZ);
    CHECK(fake_state(&p) == LINK_STATE_DONE);
    {
        int shown = 0;
        for (k = 0; k < p.event_count; k++)
            if (p.events[k].kind == ZEV_SHOW && p.events[k].value >= 0) { shown++; CHECK(p.events[k].crc == crc); }
        CHECK(shown == 2);
    }
    fake_free(&p);
}

/* A 1,000-layer print, masks streamed one layer ahead: the pins' record
   passes tests/zcheck.h (Z exact at every exposure, no UV while moving,
   speed and acceleration within limits, each move from rest, exposure
   times exact, the steps the heights moved). */
static void thousand_layers_without_drift(void)
{
    static fake_printer p;
    static uint8_t lengths[1000], image[32 * 16 / 8], code[1024];
    static uint32_t tops[1000], crcs[1000], exposures[1000];
    static uint64_t path[2000];
    uint32_t k, sent = 0, top = 0;
    zexpect e;
    zsummary s;
    fake_init(&p, 32, 16, 1);
    p.keep_events = 1;
    p.heartbeat = FAKE_TICK_HZ / 4;
    for (k = 0; k < 1000; k++) {
        lengths[k] = (uint8_t)(25 + fw_rng() % 51);
        top += lengths[k];
        tops[k] = top;
        path[2 * k] = (uint64_t)top * 2000u; /* the layer's top, then the 5 mm peel */
        path[2 * k + 1] = path[2 * k] + 5000000u;
        /* the bottom layers' long light, then each layer its own, as thickness asks */
        exposures[k] = k < 3 ? 2000 : 200 + 4 * lengths[k];
    }
    send_plan(&p, lengths, 1000, 2000);
    home(&p);
    start_print(&p, 1);
    CHECKF(fake_state(&p) == LINK_STATE_PRINTING, "state %u error %u", p.status.state, p.status.error);
    while (fake_state(&p) == LINK_STATE_PRINTING) {
        uint32_t layer = p.status.layer, ready = p.status.mask_ready;
        if (ready == sent && sent < 1000 && sent + 1 <= layer + 1) {
            size_t n, b;
            for (b = 0; b < sizeof image; b++) image[b] = (uint8_t)((sent + 1) * 31 + b * 7);
            CHECK(adaslice_rle_encode(image, 4, 32, 16, 1, code, sizeof code, &n) == ADASLICE_OK);
            crcs[sent] = adaslice_crc32(0, image, sizeof image);
            send_mask(&p, sent + 1, code, n, crcs[sent], exposures[sent]);
            sent++;
        }
        fake_run(&p, p.now + FAKE_TICK_HZ / 20);
    }
    CHECKF(p.status.state == LINK_STATE_DONE && sent == 1000, "state %u after %u masks", p.status.state, sent);
    memset(&e, 0, sizeof e);
    e.tick_hz = FAKE_TICK_HZ;
    e.steps_per_mm = 400;
    e.max_speed = 4000;
    e.accel = 20000;
    e.start_position = 400 * 37 + 123;
    e.layers = 1000;
    e.first = 1;
    e.top_bins = tops;
    e.bin_nm = 2000;
    e.crcs = crcs;
    e.exposure_ms = exposures;
    e.path_nm = path;
    e.path_len = 2000;
    s = zcheck_record(p.events, p.event_count, &e);
    /* after the last peel: its top plus 5 mm, exactly */
    CHECKF(p.true_position == zcheck_steps_of(&e, top) + 2000, "ends at %d steps", (int)p.true_position);
    CHECKF(s.worst_accel_ratio > 0.95 && s.worst_speed_ratio > 0.95 && s.moves >= 2000 && s.ramp_windows,
           "the limits were never approached: %.3f, %.3f; %zu moves, %zu ramp windows", s.worst_accel_ratio,
           s.worst_speed_ratio, s.moves, s.ramp_windows);
    fake_free(&p);
}

/* Pause takes the UV off at once and keeps the rest of the exposure; a
   silent host pauses the print by itself; resume finishes the layer. STATUS
   gives the light still owed, rounded up to the ms, while the layer exposes
   (what a host that loses the printer then resumes with) and once paused. */
static void pause_and_link_loss(void)
{
    static fake_printer p;
    static uint8_t image[8], code[64];
    uint8_t lengths[3] = {40, 40, 40};
    uint64_t on = 0, total = 0, lit_at = 0, owed;
    const uint64_t tick_ms = FAKE_TICK_HZ / 1000u;
    size_t n, k;
    uint32_t crc;
    int uv = 0;
    fake_init(&p, 8, 8, 1);
    p.keep_events = 1;
    p.heartbeat = FAKE_TICK_HZ / 5;
    CHECK(adaslice_rle_encode(image, 1, 8, 8, 1, code, sizeof code, &n) == ADASLICE_OK);
    crc = adaslice_crc32(0, image, sizeof image);
    send_plan(&p, lengths, 3, 2000);
    home(&p);
    start_print(&p, 1);
    send_mask(&p, 1, code, n, crc, 4000);
    while (fake_state(&p) == LINK_STATE_PRINTING && p.status.phase != LINK_PHASE_EXPOSE) fake_run(&p, p.now + FAKE_TICK_HZ / 100);
    fake_run(&p, p.now + FAKE_TICK_HZ + tick_ms / 3); /* a part of a ms: the rounding shows */
    CHECK(fake_state(&p) == LINK_STATE_PRINTING && (p.status.flags & LINK_FLAG_UV));
    for (k = 0; k < p.event_count; k++) if (p.events[k].kind == ZEV_UV && p.events[k].value) lit_at = p.events[k].when;
    owed = (lit_at + 4u * FAKE_TICK_HZ - p.now + tick_ms - 1u) / tick_ms;
    CHECKF(lit_at && p.status.exposure_left_ms == owed, "exposing: %u ms left, the UV edge says %llu",
           p.status.exposure_left_ms, (unsigned long long)owed);
    fake_send(&p, LINK_MSG_PAUSE, NULL, 0);
    CHECK(fake_state(&p) == LINK_STATE_PAUSED && !(p.status.flags & LINK_FLAG_UV));
    CHECKF(p.status.exposure_left_ms == owed, "paused: %u ms left of %llu", p.status.exposure_left_ms, (unsigned long long)owed);
    fake_run(&p, p.now + 10ull * FAKE_TICK_HZ);
    fake_send(&p, LINK_MSG_RESUME, NULL, 0);
    send_mask(&p, 2, code, n, crc, 4000);
    /* the host falls silent during layer 2: UV off, Z held, a pause flagged as link loss */
    while (fake_state(&p) == LINK_STATE_PRINTING && !(p.status.layer == 2 && p.status.phase == LINK_PHASE_EXPOSE))
        fake_run(&p, p.now + FAKE_TICK_HZ / 100);
    p.heartbeat = 0;
    fake_run(&p, p.now + 5ull * FAKE_TICK_HZ);
    p.heartbeat = FAKE_TICK_HZ / 5;
    CHECK(fake_state(&p) == LINK_STATE_PAUSED && (p.status.flags & LINK_FLAG_LINK_LOST) && !(p.status.flags & LINK_FLAG_UV));
    fake_send(&p, LINK_MSG_RESUME, NULL, 0);
    send_mask(&p, 3, code, n, crc, 4000);
    fake_run(&p, p.now + 60ull * FAKE_TICK_HZ);
    CHECK(fake_state(&p) == LINK_STATE_DONE);
    /* every layer got its full 4 s of light, in pieces where it was paused */
    for (k = 0; k < p.event_count; k++)
        if (p.events[k].kind == ZEV_UV) {
            if (p.events[k].value && !uv) on = p.events[k].when;
            if (!p.events[k].value && uv) total += p.events[k].when - on;
            uv = p.events[k].value;
        }
    CHECKF(total == 3 * 4ull * FAKE_TICK_HZ, "%llu ticks of light for 3 layers of 4 s", (unsigned long long)total);
    fake_free(&p);
}

/* G-code mode through the core: an unpaced burst larger than the core holds
   loses whole lines or has them refused, but never runs two spliced into a
   different move. */
static void gcode_burst_never_splices(void)
{
    static fake_printer p;
    char burst[1024];
    size_t n = 0;
    int k;
    fake_init(&p, 8, 8, 1);
    fake_bytes(&p, (const uint8_t *)"G28\n", 4);
    fake_run(&p, p.now + 60ull * FAKE_TICK_HZ);
    CHECK(p.fw.axis.homed && strstr(p.text, "ok") != NULL);
    for (k = 1; k <= 40; k++) n += (size_t)snprintf(burst + n, sizeof burst - n, "G1 Z%d.000 F600\n", k);
    fake_bytes(&p, (const uint8_t *)burst, n);
    fake_run(&p, p.now + 600ull * FAKE_TICK_HZ);
    CHECKF(p.fw.axis.position % 400 == 0 && p.fw.axis.position > 0 && p.fw.axis.position <= 40 * 400,
           "ends at %d steps", (int)p.fw.axis.position);
    CHECK(strstr(p.text, "Error") != NULL || strstr(p.text, "Unknown") != NULL);
    CHECK(!p.fw.binary);
}

/* A HELLO numbered 0x0A (a line feed) in one burst: the bytes before it
   look like a G-code line, held to run in later passes; the frame makes the
   port binary and that line is dropped, so no G-code reply ever comes, even
   once the binary host has gone quiet and G-code mode is back. */
static void a_frame_drops_what_looked_like_gcode(void)
{
    static fake_printer p;
    uint8_t payload[LINK_SIZE_HELLO], frame[LINK_FRAME_MAX];
    link_hello m;
    size_t n, k;
    fake_init(&p, 8, 8, 1);
    m.version = LINK_PROTOCOL_VERSION;
    n = link_frame_build(frame, 0x0A, LINK_MSG_HELLO, payload, link_put_hello(payload, &m));
    for (k = 0; k < n && frame[k] != 0x0A; k++) {}
    CHECK(k > 0 && k < n);
    fake_bytes(&p, frame, n);
    CHECK(p.fw.binary);
    p.text_len = 0; /* the IDENTIFY it drew, binary */
    p.text[0] = 0;
    fake_run(&p, p.now + 60ull * FAKE_TICK_HZ);
    CHECK(!p.fw.binary); /* the binary host went quiet: G-code mode again */
    CHECKF(!strstr(p.text, "ok") && !strstr(p.text, "echo:"), "G-code replies: %.200s", p.text);
    fake_free(&p);
}

/* MOVE, HOME and EXPOSE outside a print: refused until homed and outside
   the soft limits; a move lands on its exact step; EXPOSE lights the last
   verified mask for its time, then the display goes dark. */
static void manual_commands(void)
{
    static fake_printer p;
    static uint8_t image[8], code[64];
    uint8_t mv[LINK_SIZE_MOVE], ms[LINK_SIZE_EXPOSE], lengths[1] = {40};
    link_move move = {12345678, 0};
    link_expose expose = {1500};
    size_t n, k;
    uint64_t on = 0, off = 0;
    fake_init(&p, 8, 8, 1);
    p.keep_events = 1;
    fake_send(&p, LINK_MSG_MOVE, mv, link_put_move(mv, &move));
    CHECK(fake_state(&p) == LINK_STATE_IDLE && p.status.error == LINK_ERR_NOT_HOMED);
    home(&p);
    fake_send(&p, LINK_MSG_MOVE, mv, LINK_SIZE_MOVE);
    fake_run(&p, p.now + 30ull * FAKE_TICK_HZ);
    CHECKF(fake_state(&p) == LINK_STATE_IDLE && p.true_position == 4938 && p.status.z_nm == 12345000,
           "at %d steps, %d nm", (int)p.true_position, (int)p.status.z_nm);
    move.z_nm = 250000000; /* 250 mm: past the 200 mm of travel */
    fake_send(&p, LINK_MSG_MOVE, mv, link_put_move(mv, &move));
    CHECK(fake_state(&p) == LINK_STATE_IDLE && p.status.error == LINK_ERR_LIMIT && p.true_position == 4938);
    fake_send(&p, LINK_MSG_EXPOSE, ms, link_put_expose(ms, &expose));
    CHECK(fake_state(&p) == LINK_STATE_IDLE && p.status.error == LINK_ERR_BUSY); /* no verified mask yet */
    send_plan(&p, lengths, 1, 2000);
    CHECK(adaslice_rle_encode(image, 1, 8, 8, 1, code, sizeof code, &n) == ADASLICE_OK);
    send_mask(&p, 1, code, n, adaslice_crc32(0, image, sizeof image), 1000);
    fake_send(&p, LINK_MSG_EXPOSE, ms, LINK_SIZE_EXPOSE);
    CHECK(fake_state(&p) == LINK_STATE_READY && (p.status.flags & LINK_FLAG_UV));
    fake_run(&p, p.now + 2ull * FAKE_TICK_HZ);
    CHECK(fake_state(&p) == LINK_STATE_READY && !(p.status.flags & LINK_FLAG_UV));
    for (k = 0; k < p.event_count; k++)
        if (p.events[k].kind == ZEV_UV) { if (p.events[k].value) on = p.events[k].when; else off = p.events[k].when; }
    CHECKF(off - on == FAKE_TICK_HZ * 15ull / 10, "lit for %llu ticks", (unsigned long long)(off - on));
    fake_free(&p);
}


/* The light a record gave and the steps taken while it was on. */
static uint64_t lit_ticks(const fake_printer *p, size_t *steps_lit)
{
    uint64_t on = 0, total = 0;
    size_t k;
    int uv = 0;
    *steps_lit = 0;
    for (k = 0; k < p->event_count; k++) {
        const zevent *e = &p->events[k];
        if (e->kind == ZEV_STEP && uv) (*steps_lit)++;
        if (e->kind != ZEV_UV) continue;
        if (e->value && !uv) on = e->when;
        if (!e->value && uv) total += e->when - on;
        uv = e->value;
    }
    return total;
}

/* A one-layer print of 40 bins of 2 um (0.08 mm) up to its settle. */
static void print_to_settle(fake_printer *p)
{
    static uint8_t image[8], code[64];
    uint8_t lengths[1] = {40};
    size_t n;
    fake_init(p, 8, 8, 1);
    p->keep_events = 1;
    p->heartbeat = FAKE_TICK_HZ / 5;
    CHECK(adaslice_rle_encode(image, 1, 8, 8, 1, code, sizeof code, &n) == ADASLICE_OK);
    send_plan(p, lengths, 1, 2000);
    home(p);
    start_print(p, 1);
    send_mask(p, 1, code, n, adaslice_crc32(0, image, sizeof image), 2000);
    while (fake_state(p) == LINK_STATE_PRINTING && p->status.phase != LINK_PHASE_SETTLE) fake_run(p, p->now + FAKE_TICK_HZ / 1000);
    CHECK(p->status.phase == LINK_PHASE_SETTLE && p->true_position == 32);
}

/* PAUSE, MOVE to 20 mm, RESUME once exposed a layer at 20 mm: MOVE and HOME
   are refused while a print is paused (and with the light on), the resumed
   layer is exposed at its own top; the core's last check before the light
   (Z at the layer's top) and a print move the axis refuses are faults that
   leave the light off. */
static void a_pause_never_exposes_elsewhere(void)
{
    static fake_printer p;
    uint8_t mv[LINK_SIZE_MOVE];
    link_move move = {20000000, 0};
    size_t lit_steps;
    print_to_settle(&p);
    fake_send(&p, LINK_MSG_PAUSE, NULL, 0);
    CHECK(fake_state(&p) == LINK_STATE_PAUSED);
    fake_send(&p, LINK_MSG_MOVE, mv, link_put_move(mv, &move));
    CHECK(fake_state(&p) == LINK_STATE_PAUSED && p.status.error == LINK_ERR_BUSY);
    fake_send(&p, LINK_MSG_HOME, NULL, 0);
    CHECK(fake_state(&p) == LINK_STATE_PAUSED && p.status.error == LINK_ERR_BUSY);
    fake_run(&p, p.now + FAKE_TICK_HZ);
    CHECK(p.true_position == 32);
    /* had anything moved it while paused, RESUME goes back to the top first */
    p.fw.axis.position += 800;
    p.true_position += 800;
    {
        size_t k, from = p.event_count, exposures = 0;
        int32_t pos = p.true_position;
        fake_send(&p, LINK_MSG_RESUME, NULL, 0);
        fake_run(&p, p.now + 20ull * FAKE_TICK_HZ);
        CHECK(fake_state(&p) == LINK_STATE_DONE);
        CHECK(lit_ticks(&p, &lit_steps) == 2ull * FAKE_TICK_HZ && !lit_steps);
        /* the light came on at the layer's top: 32 steps (40 x 2 um x 400 / mm) */
        for (k = from; k < p.event_count; k++) {
            if (p.events[k].kind == ZEV_STEP) pos += p.events[k].value;
            if (p.events[k].kind == ZEV_UV && p.events[k].value) {
                exposures++;
                CHECKF(pos == 32, "exposed at %d steps", (int)pos);
            }
        }
        CHECK(exposures == 1);
    }
    fake_free(&p);

    /* Z moved under the print's feet during the settle: no light, a fault */
    print_to_settle(&p);
    p.fw.axis.position += 4;
    p.true_position += 4;
    fake_run(&p, p.now + 5ull * FAKE_TICK_HZ);
    CHECKF(fake_state(&p) == LINK_STATE_READY && p.status.error == LINK_ERR_WRONG_HEIGHT, "state %d error %d", p.status.state,
           p.status.error);
    CHECK(lit_ticks(&p, &lit_steps) == 0 && (p.status.flags & LINK_FLAG_HOMED) && p.status.exposed == 0);
    fake_free(&p);

    /* the peel refused (the axis lost its home during the exposure): a fault */
    print_to_settle(&p);
    while (fake_state(&p) == LINK_STATE_PRINTING && p.status.phase != LINK_PHASE_EXPOSE) fake_run(&p, p.now + FAKE_TICK_HZ / 1000);
    fake_send(&p, LINK_MSG_MOVE, mv, link_put_move(mv, &move)); /* MOVE under the light */
    CHECK(fake_state(&p) == LINK_STATE_PRINTING && p.status.error == LINK_ERR_BUSY && p.true_position == 32);
    p.fw.axis.homed = 0;
    fake_run(&p, p.now + 5ull * FAKE_TICK_HZ);
    CHECKF(fake_state(&p) == LINK_STATE_READY && p.status.error == LINK_ERR_MOVE_FAILED, "state %d error %d", p.status.state,
           p.status.error);
    CHECK(!(p.status.flags & LINK_FLAG_UV) && p.true_position == 32 && p.status.exposed == 1);
    fake_free(&p);
}

static void send_screen(fake_printer *p, uint32_t layer, uint32_t exposure_ms)
{
    uint8_t b[LINK_SIZE_SCREEN];
    link_screen m;
    m.layer = layer;
    m.exposure_ms = exposure_ms;
    fake_send(p, LINK_MSG_SCREEN, b, link_put_screen(b, &m));
}

/* Runs until the print waits for the host's screen (WAIT_MASK, Z still) or
   10 s pass. */
static void run_to_wait(fake_printer *p)
{
    uint64_t end = p->now + 10ull * FAKE_TICK_HZ;
    while (p->now < end && fake_state(p) == LINK_STATE_PRINTING &&
           (p->status.phase != LINK_PHASE_WAIT_MASK || (p->status.flags & LINK_FLAG_MOVING)))
        fake_run(p, p->now + FAKE_TICK_HZ / 1000);
}

/* The host's screen (SCREEN): the light comes on only under the layer the
   host says it shows, for the exposure it gives; Z waits in DARK after the
   exposure until the host says the screen is dark; SCREEN 0 mid-exposure
   is a pause that keeps the rest, which the layer gets once shown again;
   another layer, a bad exposure, or SCREEN outside a print is refused; and
   a screen left lit (an ABORT) keeps Z still until SCREEN 0. */
static void host_screen_rules(void)
{
    static fake_printer p;
    uint8_t lengths[2] = {40, 40}, mv[LINK_SIZE_MOVE];
    link_move move = {20000000, 0};
    size_t lit_steps;
    int32_t at;
    fake_init(&p, 8, 8, 1);
    p.keep_events = 1;
    p.heartbeat = FAKE_TICK_HZ / 5; /* the host's polls: the link stays alive */
    send_plan(&p, lengths, 2, 2000);
    home(&p);
    send_screen(&p, 1, 500); /* not printing */
    CHECK(fake_state(&p) == LINK_STATE_READY && p.status.error == LINK_ERR_SCREEN_LAYER && !p.status.screen);
    start_print(&p, 1);
    run_to_wait(&p);
    CHECK(p.status.phase == LINK_PHASE_WAIT_MASK && p.true_position == 32);
    fake_run(&p, p.now + FAKE_TICK_HZ);
    CHECK(lit_ticks(&p, &lit_steps) == 0 && fake_state(&p) == LINK_STATE_PRINTING && p.status.phase == LINK_PHASE_WAIT_MASK);
    send_screen(&p, 2, 500);
    CHECK(fake_state(&p) == LINK_STATE_PRINTING && p.status.error == LINK_ERR_SCREEN_LAYER && !p.status.screen);
    send_screen(&p, 1, 0);
    CHECK(fake_state(&p) == LINK_STATE_PRINTING && p.status.error == LINK_ERR_MASK_EXPOSURE && !p.status.screen);
    send_screen(&p, 1, 500);
    CHECK(fake_state(&p) == LINK_STATE_PRINTING && p.status.screen == 1);
    /* settle (200 ms), 500 ms of light, then Z waits for the dark */
    fake_run(&p, p.now + 3ull * FAKE_TICK_HZ);
    CHECKF(fake_state(&p) == LINK_STATE_PRINTING && p.status.phase == LINK_PHASE_DARK && p.true_position == 32 &&
           p.status.exposed == 1, "phase %d at %d steps", p.status.phase, (int)p.true_position);
    CHECK(lit_ticks(&p, &lit_steps) == FAKE_TICK_HZ / 2 && !lit_steps);
    send_screen(&p, 0, 0);
    run_to_wait(&p);
    CHECK(p.status.layer == 2 && p.status.phase == LINK_PHASE_WAIT_MASK && p.true_position == 64 && !p.status.screen);
    /* SCREEN 0 while layer 2 exposes: a pause, the rest kept */
    send_screen(&p, 2, 500);
    while (fake_state(&p) == LINK_STATE_PRINTING && p.status.phase != LINK_PHASE_EXPOSE) fake_run(&p, p.now + FAKE_TICK_HZ / 1000);
    fake_run(&p, p.now + FAKE_TICK_HZ / 5);
    send_screen(&p, 0, 0);
    CHECKF(fake_state(&p) == LINK_STATE_PAUSED && !(p.status.flags & LINK_FLAG_UV) && p.status.exposure_left_ms == 300,
           "state %d, %u ms left", p.status.state, p.status.exposure_left_ms);
    fake_send(&p, LINK_MSG_RESUME, NULL, 0);
    fake_run(&p, p.now + 2ull * FAKE_TICK_HZ);
    CHECK(fake_state(&p) == LINK_STATE_PRINTING && p.status.phase == LINK_PHASE_WAIT_MASK); /* shown again first */
    CHECK(lit_ticks(&p, &lit_steps) == FAKE_TICK_HZ / 2 + FAKE_TICK_HZ / 5);
    send_screen(&p, 2, 500);
    fake_run(&p, p.now + 2ull * FAKE_TICK_HZ);
    CHECK(fake_state(&p) == LINK_STATE_PRINTING && p.status.phase == LINK_PHASE_DARK && p.status.exposed == 2);
    CHECKF(lit_ticks(&p, &lit_steps) == FAKE_TICK_HZ && !lit_steps, "%llu ticks of light",
           (unsigned long long)lit_ticks(&p, &lit_steps));
    /* an ABORT with the screen lit: nothing moves until the host says it is dark */
    fake_send(&p, LINK_MSG_ABORT, NULL, 0);
    at = p.true_position;
    fake_send(&p, LINK_MSG_MOVE, mv, link_put_move(mv, &move));
    CHECK(fake_state(&p) == LINK_STATE_READY && p.status.error == LINK_ERR_SCREEN_LIT && p.status.screen == 2);
    fake_send(&p, LINK_MSG_HOME, NULL, 0);
    CHECK(fake_state(&p) == LINK_STATE_READY && p.status.error == LINK_ERR_SCREEN_LIT);
    start_print(&p, 1);
    CHECK(fake_state(&p) == LINK_STATE_READY && p.status.error == LINK_ERR_SCREEN_LIT);
    fake_run(&p, p.now + FAKE_TICK_HZ);
    CHECK(p.true_position == at);
    send_screen(&p, 0, 0);
    fake_send(&p, LINK_MSG_MOVE, mv, link_put_move(mv, &move));
    fake_run(&p, p.now + 20ull * FAKE_TICK_HZ);
    CHECK(fake_state(&p) == LINK_STATE_READY && p.true_position == 8000);
    fake_free(&p);
}

/* The Z-min switch closing during a move, where the carriage cannot be at
   it (lost steps, a crash into the vat): stopped dead with the light off,
   Z unhomed, error ENDSTOP; a move down to the switch's own point and the
   way up off it are no fault. */
static void endstop_during_a_move(void)
{
    static fake_printer p;
    uint8_t mv[LINK_SIZE_MOVE];
    link_move move = {20000000, 0};
    size_t k, steps_after = 0;
    uint64_t hit = 0;
    fake_init(&p, 8, 8, 1);
    home(&p);
    p.keep_events = 1;
    fake_send(&p, LINK_MSG_MOVE, mv, link_put_move(mv, &move));
    fake_run(&p, p.now + 10ull * FAKE_TICK_HZ);
    CHECK(fake_state(&p) == LINK_STATE_IDLE && p.status.error == LINK_ERR_NONE && p.true_position == 8000);
    move.z_nm = 0;
    fake_send(&p, LINK_MSG_MOVE, mv, link_put_move(mv, &move));
    fake_run(&p, p.now + 10ull * FAKE_TICK_HZ);
    CHECK(fake_state(&p) == LINK_STATE_IDLE && p.status.error == LINK_ERR_NONE && p.true_position == 0 &&
          (p.status.flags & LINK_FLAG_HOMED));
    move.z_nm = 20000000;
    fake_send(&p, LINK_MSG_MOVE, mv, link_put_move(mv, &move));
    fake_run(&p, p.now + 10ull * FAKE_TICK_HZ);
    CHECK(p.status.error == LINK_ERR_NONE && p.true_position == 8000);
    /* down again; half way the carriage finds the switch 10 mm early */
    move.z_nm = 0;
    fake_send(&p, LINK_MSG_MOVE, mv, link_put_move(mv, &move));
    while (p.true_position > 4000) fake_run(&p, p.now + FAKE_TICK_HZ / 1000);
    p.true_position -= 4000;
    hit = p.now;
    fake_run(&p, p.now + 10ull * FAKE_TICK_HZ);
    CHECKF(fake_state(&p) == LINK_STATE_IDLE && p.status.error == LINK_ERR_ENDSTOP, "state %d error %d", p.status.state,
           p.status.error);
    CHECK(!(p.status.flags & (LINK_FLAG_HOMED | LINK_FLAG_MOVING | LINK_FLAG_UV)));
    for (k = 0; k < p.event_count; k++)
        if (p.events[k].kind == ZEV_STEP && p.events[k].when > hit) steps_after++;
    /* the queued steps at most */
    CHECKF(steps_after <= FW_STEP_QUEUE, "%zu steps after the switch closed", steps_after);
    fake_free(&p);
}

/* G-code through the core: the light never on while Z moves, out when the
   host falls silent after M106, and M112 / M410 acted on when their line
   ends, ahead of the lines held before them. */
static void gcode_uv_safety(void)
{
    static fake_printer p;
    size_t lit_steps;
    uint64_t end;
    const char *burst = "G1 Z30 F6000\nG1 Z31\nM106\nG4 P1000\n";
    fake_init(&p, 8, 8, 1);
    fake_bytes(&p, (const uint8_t *)"G28\n", 4);
    fake_run(&p, p.now + 60ull * FAKE_TICK_HZ);
    CHECK(p.fw.axis.homed);
    p.keep_events = 1;
    /* M106 then a move: the light goes out before the first step */
    fake_bytes(&p, (const uint8_t *)"M106 S255\n", 10);
    fake_run(&p, p.now + FAKE_TICK_HZ / 10);
    fake_bytes(&p, (const uint8_t *)"G1 Z5\n", 6);
    fake_run(&p, p.now + 5ull * FAKE_TICK_HZ);
    end = lit_ticks(&p, &lit_steps);
    CHECKF(end > 0 && !lit_steps && p.true_position == 2000, "lit %llu, %zu steps lit, at %d: %.200s", (unsigned long long)end,
           lit_steps, (int)p.true_position, p.text);
    CHECK(strstr(p.text, "echo:UV off: Z moves only in the dark") != NULL);
    /* M106 and a silent host: out after the link timeout (1 s) */
    p.event_count = 0;
    fake_bytes(&p, (const uint8_t *)"M106\n", 5);
    fake_run(&p, p.now + 3ull * FAKE_TICK_HZ);
    end = lit_ticks(&p, &lit_steps);
    CHECKF(end >= FAKE_TICK_HZ - FAKE_TICK_HZ / 1000 && end <= FAKE_TICK_HZ + FAKE_TICK_HZ / 1000,
           "lit %llu ticks with the host silent", (unsigned long long)end);
    CHECK(strstr(p.text, "echo:UV off: the host went silent after M106") != NULL);
    /* M112 mid-move: no step after the line's end, the light out, the
       lines held behind the move dropped, Z unhomed, M106 refused until G28 */
    p.event_count = 0;
    p.text_len = 0;
    fake_bytes(&p, (const uint8_t *)burst, strlen(burst));
    fake_run(&p, p.now + FAKE_TICK_HZ);
    CHECK(p.true_position > 2000 && p.true_position < 12000);
    fake_bytes(&p, (const uint8_t *)"M112\n", 5);
    end = p.now;
    fake_run(&p, p.now + 5ull * FAKE_TICK_HZ);
    {
        size_t k, after = 0;
        for (k = 0; k < p.event_count; k++)
            if (p.events[k].kind == ZEV_STEP && p.events[k].when > end) after++;
        CHECKF(!after, "%zu steps after M112", after);
    }
    CHECK(!p.fw.axis.homed && lit_ticks(&p, &lit_steps) == 0);
    CHECKF(strstr(p.text, "echo:Emergency stop (M112)") && strstr(p.text, "Error:Z move stopped at"), "%.300s", p.text);
    fake_bytes(&p, (const uint8_t *)"M106\nG1 Z5\n", 11);
    fake_run(&p, p.now + FAKE_TICK_HZ);
    CHECKF(strstr(p.text, "Error:Stopped: home Z (G28) before UV") && strstr(p.text, "Error:Home Z first") &&
           lit_ticks(&p, &lit_steps) == 0, "%.300s", p.text);
    /* M410: Z brakes to a stop and stays homed */
    fake_bytes(&p, (const uint8_t *)"G28\n", 4);
    fake_run(&p, p.now + 60ull * FAKE_TICK_HZ);
    fake_bytes(&p, (const uint8_t *)burst, strlen(burst));
    fake_run(&p, p.now + FAKE_TICK_HZ);
    p.text_len = 0;
    fake_bytes(&p, (const uint8_t *)"N7 M410*33\n", 11);
    fake_run(&p, p.now + 5ull * FAKE_TICK_HZ);
    CHECKF(p.fw.axis.homed && p.fw.axis.position == p.true_position && !fw_axis_busy(&p.fw.axis) &&
           strstr(p.text, "echo:Quick stop (M410)") && p.true_position < 12000, "at %d: %.300s", (int)p.true_position, p.text);
    CHECK(lit_ticks(&p, &lit_steps) == 0);
    fake_free(&p);
}

void test_firmware(void)
{
    RUN(manual_commands);
    RUN(gcode_burst_never_splices);
    RUN(a_frame_drops_what_looked_like_gcode);
    RUN(mcu_plans_like_the_host);
    RUN(twelve_thousand_bins_fit);
    RUN(link_recovers);
    RUN(bad_masks_are_never_shown);
    RUN(mask_decoding_takes_bounded_slices);
    RUN(speeds_under_a_step_a_second_are_one);
    RUN(a_stalled_loop_stops_the_motion);
    RUN(a_stack_fault_halts_the_core);
    RUN(thousand_layers_without_drift);
    RUN(pause_and_link_loss);
    RUN(a_pause_never_exposes_elsewhere);
    RUN(endstop_during_a_move);
    RUN(host_screen_rules);
    RUN(gcode_uv_safety);
}
