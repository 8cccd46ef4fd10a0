/* The firmware core every port shares: link, planner, masks, the print.
   See fw.h for the port's side and PROTOCOL.md for the wire. */
#include "fw.h"
#include <string.h>

#define FW_MS(fw, ms) ((uint64_t)(ms) * (fw)->config.tick_hz / 1000u)
/* a binary host silent for this many link timeouts hands the port back to G-code */
#define FW_BINARY_IDLE 5u

/* ------------------------------------------------------------------ replies */

static void send(fw_state *fw, uint8_t type, const uint8_t *payload, size_t size)
{
    uint8_t frame[FW_FRAME_MAX];
    size_t n = fw_frame_build(frame, fw->expect, type, payload, size);
    if (n) fw->port.write(fw->port.ctx, frame, n);
}

/* nak: 1 | the round bit of the frame that showed the gap (PROTOCOL.md) */
static void send_ack(fw_state *fw, int nak)
{
    uint8_t flag = (uint8_t)nak;
    send(fw, FW_MSG_ACK, &flag, 1);
}

static int32_t z_nm(const fw_state *fw)
{
    int64_t steps = fw->axis.position;
    int64_t per_mm = fw->config.axis.steps_per_mm;
    int64_t nm = steps * 1000000 + (steps >= 0 ? per_mm / 2 : -per_mm / 2);
    return (int32_t)(nm / per_mm);
}

static void send_identify(fw_state *fw)
{
    uint8_t p[32];
    const fw_config *c = &fw->config;
    p[0] = FW_PROTOCOL_VERSION;
    p[1] = c->window;
    fw_put32(p + 2, c->max_bins);
    p[6] = FW_MAX_LAYER_BINS;
    fw_put32(p + 7, c->axis.steps_per_mm);
    fw_put16(p + 11, c->display_width);
    fw_put16(p + 13, c->display_height);
    p[15] = c->display_bits;
    fw_put32(p + 16, c->pitch_nm);
    fw_put32(p + 20, (uint32_t)((uint64_t)c->axis.max_steps * 1000000u / c->axis.steps_per_mm));
    fw_put32(p + 24, c->tick_hz);
    fw_put32(p + 28, c->link_timeout_ms);
    send(fw, FW_MSG_IDENTIFY, p, 32);
}

static void send_status(fw_state *fw)
{
    uint8_t p[40];
    uint8_t flags = 0;
    if (fw->axis.homed) flags |= FW_FLAG_HOMED;
    if (fw->uv_on) flags |= FW_FLAG_UV;
    if (fw_axis_busy(&fw->axis)) flags |= FW_FLAG_MOVING;
    if (fw->paused_by_link) flags |= FW_FLAG_LINK_LOST;
    p[0] = fw->state;
    p[1] = fw->phase;
    p[2] = fw->error;
    p[3] = fw->error_seq;
    p[4] = flags;
    fw_put32(p + 5, fw->layer);
    fw_put32(p + 9, fw->layers);
    fw_put32(p + 13, fw->mask_ready);
    fw_put32(p + 17, fw->mask_layer);
    fw_put32(p + 21, fw->mask_got);
    fw_put16(p + 25, fw->masks_refused);
    fw_put32(p + 27, (uint32_t)z_nm(fw));
    fw_put32(p + 31, fw->bins_in);
    fw_put32(p + 35, fw->deframer.bad);
    p[39] = fw->config.window;
    send(fw, FW_MSG_STATUS_REPLY, p, 40);
}

/* ----------------------------------------------------------------- the plan */

/* Bins of layer k (1-based), read bottom-up through a cursor so a print's
   sequential reads cost O(1) each. */
static uint32_t layer_length(fw_state *fw, uint32_t k)
{
    if (fw->plan_kind == 2) return fw->workspace[k - 1];
    if (k < fw->cursor_layer || !fw->cursor_layer) { fw->cursor_layer = 1; fw->cursor_plane = 0; }
    while (fw->cursor_layer < k) {
        fw->cursor_plane += adaslice_dp_layer_above(&fw->dp, fw->cursor_plane);
        fw->cursor_layer++;
    }
    return adaslice_dp_layer_above(&fw->dp, fw->cursor_plane);
}

/* The plane under layer k (1-based), in bins. */
static uint32_t layer_bottom(fw_state *fw, uint32_t k)
{
    uint32_t plane = 0, j;
    if (fw->plan_kind == 1) { (void)layer_length(fw, k); return fw->cursor_plane; }
    for (j = 1; j < k; j++) plane += fw->workspace[j - 1];
    return plane;
}

static int32_t steps_of_plane(const fw_state *fw, uint32_t plane, uint32_t extra_nm)
{
    return fw_axis_steps_of_nm(&fw->axis, (uint64_t)plane * fw->bin_nm + extra_nm);
}

static void drop_plan(fw_state *fw)
{
    fw->receiving = 0;
    fw->plan_kind = 0;
    fw->layers = 0;
    fw->cursor_layer = 0;
    fw->mask_layer = 0;
    fw->mask_ready = 0;
}

/* the state to come back to after a move, homing or abort */
static uint8_t resting(const fw_state *fw)
{
    if (fw->state == FW_PAUSED) return FW_PAUSED;
    return fw->plan_kind ? FW_READY : FW_IDLE;
}

static int fail(fw_state *fw, uint8_t error, uint8_t seq)
{
    fw->error = error;
    fw->error_seq = seq;
    return 0;
}

static int axis_error(fw_state *fw, int r, uint8_t seq)
{
    switch (r) {
    case FW_AXIS_OK: return 1;
    case FW_AXIS_BUSY: return fail(fw, FW_ERR_BUSY, seq);
    case FW_AXIS_NOT_HOMED: return fail(fw, FW_ERR_NOT_HOMED, seq);
    case FW_AXIS_LIMIT: return fail(fw, FW_ERR_LIMIT, seq);
    default: return fail(fw, FW_ERR_HOME_FAILED, seq);
    }
}

static void profile_begin(fw_state *fw, const uint8_t *p, uint8_t seq)
{
    uint32_t bins = fw_get32(p), eps = fw_get32(p + 6), bin_nm = fw_get32(p + 10);
    uint8_t lo = p[4], hi = p[5];
    if (bins > fw->config.max_bins) { fail(fw, FW_ERR_PLAN_SIZE, seq); return; }
    drop_plan(fw);
    fw->state = FW_IDLE;
    if (!bins || !bin_nm || !eps || lo < 1 || lo > hi || hi > FW_MAX_LAYER_BINS ||
        adaslice_dp_init(&fw->dp, fw->workspace, fw->workspace_size, bins, lo, hi, eps, 0, 0) != ADASLICE_OK) {
        fail(fw, FW_ERR_PROFILE, seq);
        return;
    }
    fw->bins = bins;
    fw->bins_in = 0;
    fw->bin_nm = bin_nm;
    memset(&fw->varint, 0, sizeof fw->varint);
    fw->receiving = FW_MSG_PROFILE_DATA;
    fw->state = FW_PLANNING;
}

static void profile_data(fw_state *fw, const uint8_t *p, size_t size, uint8_t seq)
{
    size_t i;
    if (fw->state != FW_PLANNING || fw->receiving != FW_MSG_PROFILE_DATA) { fail(fw, FW_ERR_BUSY, seq); return; }
    for (i = 0; i < size; i++) {
        uint32_t v = 0;
        int done;
        if (adaslice_varint_push(&fw->varint, p[i], &done, &v) != ADASLICE_OK) break;
        if (!done) continue;
        if (fw->bins_in >= fw->bins) break;
        adaslice_dp_push(&fw->dp, v >> 1, (v & 1u) && fw->bins_in + 1 < fw->bins);
        if (++fw->bins_in == fw->bins) {
            uint32_t k = adaslice_dp_reverse(&fw->dp);
            fw->receiving = 0;
            if (k == ADASLICE_UNREACHED) { fw->state = FW_IDLE; fail(fw, FW_ERR_INFEASIBLE, seq); return; }
            fw->layers = k;
            fw->plan_kind = 1;
            fw->cursor_layer = 0;
            fw->state = FW_READY;
        }
    }
    if (i < size) { fw->receiving = 0; fw->state = FW_IDLE; fail(fw, FW_ERR_PROFILE_DATA, seq); }
}

static void plan_set(fw_state *fw, const uint8_t *p, uint8_t seq)
{
    uint32_t layers = fw_get32(p), bin_nm = fw_get32(p + 4);
    /* a given plan is a byte per layer in the planner's workspace */
    if (layers > fw->workspace_size) { fail(fw, FW_ERR_PLAN_SIZE, seq); return; }
    drop_plan(fw);
    fw->state = FW_IDLE;
    if (!layers || !bin_nm) { fail(fw, FW_ERR_PROFILE, seq); return; }
    fw->layers = layers;
    fw->bin_nm = bin_nm;
    fw->bins = 0;
    fw->bins_in = 0; /* counts layers received here */
    fw->receiving = FW_MSG_PLAN_DATA;
    fw->state = FW_PLANNING;
}

static void plan_data(fw_state *fw, const uint8_t *p, size_t size, uint8_t seq)
{
    size_t i;
    if (fw->state != FW_PLANNING || fw->receiving != FW_MSG_PLAN_DATA) { fail(fw, FW_ERR_BUSY, seq); return; }
    for (i = 0; i < size; i++) {
        if (fw->bins_in >= fw->layers || !p[i]) {
            drop_plan(fw);
            fw->state = FW_IDLE;
            fail(fw, FW_ERR_PROFILE_DATA, seq);
            return;
        }
        fw->workspace[fw->bins_in++] = p[i];
        fw->bins += p[i];
    }
    if (fw->bins_in == fw->layers) { fw->receiving = 0; fw->plan_kind = 2; fw->state = FW_READY; }
}

static void plan_get(fw_state *fw, const uint8_t *p, uint8_t seq)
{
    uint8_t out[FW_PAYLOAD_MAX];
    uint32_t first = fw_get32(p), k;
    size_t n = 12;
    if (!fw->plan_kind) { fail(fw, FW_ERR_NO_PLAN, seq); send_ack(fw, 0); return; }
    fw_put32(out, first);
    fw_put32(out + 4, fw->layers);
    fw_put32(out + 8, fw->bin_nm);
    for (k = first; k >= 1 && k <= fw->layers && n < sizeof out; k++) out[n++] = (uint8_t)layer_length(fw, k);
    send(fw, FW_MSG_PLAN, out, n);
}

/* -------------------------------------------------------------------- masks */

static void mask_row(void *ctx, uint32_t y, const unsigned char *row)
{
    fw_state *fw = (fw_state *)ctx;
    fw->port.mask_row(fw->port.ctx, (int)(fw->mask_layer & 1u), y, row, fw->decoder.stride);
}

static void mask_refuse(fw_state *fw, uint8_t error, uint8_t seq)
{
    fw->mask_layer = 0;
    fw->masks_refused++;
    fail(fw, error, seq);
}

static void mask_begin(fw_state *fw, const uint8_t *p, uint8_t seq)
{
    uint32_t layer = fw_get32(p);
    const fw_config *c = &fw->config;
    int printing = fw->state == FW_PRINTING || fw->state == FW_PAUSED;
    if (!fw->plan_kind) { fail(fw, FW_ERR_NO_PLAN, seq); return; }
    /* the next mask only, and never into the buffer a layer still shows */
    if (layer != fw->mask_ready + 1 || layer > fw->layers || (printing && layer > fw->layer + 1)) {
        fail(fw, FW_ERR_MASK_ORDER, seq);
        return;
    }
    if (adaslice_rle_decoder_init(&fw->decoder, c->display_width, c->display_height, c->display_bits, fw->row,
                                  sizeof fw->row) != ADASLICE_OK) {
        fail(fw, FW_ERR_MASK_CODE, seq);
        return;
    }
    fw->mask_layer = layer;
    fw->mask_size = fw_get32(p + 4);
    fw->mask_crc = fw_get32(p + 8);
    fw->mask_got = 0;
    if (!fw->mask_size) mask_refuse(fw, FW_ERR_MASK_CODE, seq);
}

static void mask_data(fw_state *fw, const uint8_t *p, size_t size, uint8_t seq)
{
    if (!fw->mask_layer) { fail(fw, FW_ERR_MASK_ORDER, seq); return; }
    if (size > fw->mask_size - fw->mask_got ||
        adaslice_rle_decode(&fw->decoder, p, size, mask_row, fw) != ADASLICE_OK) {
        mask_refuse(fw, FW_ERR_MASK_CODE, seq);
        return;
    }
    fw->mask_got += (uint32_t)size;
    if (fw->mask_got < fw->mask_size) return;
    if (!adaslice_rle_finished(&fw->decoder) || ADASLICE_RLE_CRC(&fw->decoder) != fw->mask_crc) {
        mask_refuse(fw, FW_ERR_MASK_CRC, seq);
        return;
    }
    fw->mask_ready = fw->mask_layer;
    fw->mask_layer = 0;
}

/* -------------------------------------------------------------------- print */

static void uv(fw_state *fw, int on, uint64_t when)
{
    fw->uv_on = (uint8_t)on;
    fw->port.uv(fw->port.ctx, on, when);
}

static uint32_t um_s_to_steps(const fw_state *fw, uint32_t um_s)
{
    uint64_t s = (uint64_t)um_s * fw->config.axis.steps_per_mm / 1000u;
    return s > 0xffffffffu ? 0xffffffffu : (uint32_t)s;
}

/* Moves to the top of the current layer (plus `extra_nm`). */
static void move_layer(fw_state *fw, uint32_t extra_nm, uint32_t speed_um_s, uint64_t now)
{
    (void)fw_axis_move_to(&fw->axis, steps_of_plane(fw, fw->top_plane, extra_nm), um_s_to_steps(fw, speed_um_s), now);
}

static void print_start(fw_state *fw, const uint8_t *p, uint8_t seq, uint64_t now)
{
    uint32_t first = fw_get32(p);
    if (!fw->plan_kind) { fail(fw, FW_ERR_NO_PLAN, seq); return; }
    if ((fw->state != FW_READY && fw->state != FW_DONE) || fw->uv_on || fw_axis_busy(&fw->axis)) {
        fail(fw, FW_ERR_BUSY, seq);
        return;
    }
    if (!fw->axis.homed) { fail(fw, FW_ERR_NOT_HOMED, seq); return; }
    if (first < 1 || first > fw->layers) { fail(fw, FW_ERR_MESSAGE, seq); return; }
    fw->exposure_ms = fw_get32(p + 4);
    fw->bottom_layers = fw_get32(p + 8);
    fw->bottom_exposure_ms = fw_get32(p + 12);
    fw->peel_nm = fw_get32(p + 16);
    fw->peel_speed = fw_get32(p + 20);
    fw->return_speed = fw_get32(p + 24);
    fw->settle_ms = fw_get32(p + 28);
    fw->layer = first;
    fw->top_plane = layer_bottom(fw, first) + layer_length(fw, first);
    if (steps_of_plane(fw, fw->top_plane, 0) > fw->config.axis.max_steps ||
        steps_of_plane(fw, layer_bottom(fw, fw->layers) + layer_length(fw, fw->layers), fw->peel_nm) >
            fw->config.axis.max_steps) {
        fail(fw, FW_ERR_LIMIT, seq);
        return;
    }
    fw->mask_ready = first - 1;
    fw->mask_layer = 0;
    fw->exposure_left = 0;
    fw->pause_wanted = 0;
    fw->paused_by_link = 0;
    fw->state = FW_PRINTING;
    fw->phase = FW_PHASE_MOVE;
    move_layer(fw, 0, fw->return_speed, now);
}

static uint64_t exposure_ticks(const fw_state *fw)
{
    return FW_MS(fw, fw->layer <= fw->bottom_layers ? fw->bottom_exposure_ms : fw->exposure_ms);
}

/* Advances the layer cycle as far as `now` allows:
   move to the layer -> its mask verified -> settle -> expose -> peel -> next. */
static void print_step(fw_state *fw, uint64_t now)
{
    for (;;) {
        switch (fw->phase) {
        case FW_PHASE_MOVE:
            if (fw_axis_busy(&fw->axis)) return;
            if (fw->pause_wanted) { fw->state = FW_PAUSED; return; }
            fw->phase = FW_PHASE_WAIT_MASK;
            break;
        case FW_PHASE_WAIT_MASK:
            if (fw->pause_wanted) { fw->state = FW_PAUSED; return; }
            if (fw->mask_ready < fw->layer) return;
            fw->port.show(fw->port.ctx, (int)(fw->layer & 1u), now);
            fw->phase = FW_PHASE_SETTLE;
            fw->phase_end = now + FW_MS(fw, fw->settle_ms);
            break;
        case FW_PHASE_SETTLE:
            if (fw->pause_wanted) { fw->state = FW_PAUSED; return; }
            if (now < fw->phase_end) return;
            uv(fw, 1, fw->phase_end);
            fw->phase = FW_PHASE_EXPOSE;
            fw->phase_end += fw->exposure_left ? fw->exposure_left : exposure_ticks(fw);
            fw->exposure_left = 0;
            break;
        case FW_PHASE_EXPOSE:
            if (now < fw->phase_end) {
                if (!fw->pause_wanted) return;
                /* UV off at once; the rest of the exposure waits for resume */
                fw->exposure_left = fw->phase_end - now;
                uv(fw, 0, now);
                fw->phase = FW_PHASE_SETTLE;
                fw->state = FW_PAUSED;
                return;
            }
            uv(fw, 0, fw->phase_end);
            fw->port.show(fw->port.ctx, -1, fw->phase_end);
            fw->phase = FW_PHASE_PEEL;
            move_layer(fw, fw->peel_nm, fw->peel_speed, fw->phase_end);
            break;
        case FW_PHASE_PEEL:
            if (fw_axis_busy(&fw->axis)) return;
            if (fw->layer == fw->layers) { fw->state = FW_DONE; return; }
            if (fw->pause_wanted) { fw->state = FW_PAUSED; return; }
            fw->layer++;
            fw->top_plane += layer_length(fw, fw->layer);
            fw->phase = FW_PHASE_MOVE;
            move_layer(fw, 0, fw->return_speed, now);
            break;
        default:
            return;
        }
    }
}

static void print_pause(fw_state *fw, int by_link, uint64_t now)
{
    if (fw->state != FW_PRINTING) return;
    fw->pause_wanted = 1;
    fw->paused_by_link = (uint8_t)by_link;
    print_step(fw, now);
}

static void resume(fw_state *fw, uint8_t seq, uint64_t now)
{
    if (fw->state != FW_PAUSED) { fail(fw, FW_ERR_BUSY, seq); return; }
    fw->pause_wanted = 0;
    fw->paused_by_link = 0;
    fw->state = FW_PRINTING;
    if (fw->phase == FW_PHASE_SETTLE) {
        /* the settle time runs again: the platform may have been moved */
        fw->phase_end = now + FW_MS(fw, fw->settle_ms);
        if (fw->axis.position != steps_of_plane(fw, fw->top_plane, 0)) {
            fw->phase = FW_PHASE_MOVE;
            move_layer(fw, 0, fw->return_speed, now);
        }
    } else if (fw->phase == FW_PHASE_WAIT_MASK && fw->axis.position != steps_of_plane(fw, fw->top_plane, 0)) {
        fw->phase = FW_PHASE_MOVE;
        move_layer(fw, 0, fw->return_speed, now);
    }
    print_step(fw, now);
}

static void abort_all(fw_state *fw, uint64_t now)
{
    fw->exposing = 0;
    if (fw->uv_on) uv(fw, 0, now);
    fw->port.show(fw->port.ctx, -1, now);
    fw_axis_halt(&fw->axis, now);
    fw->mask_layer = 0;
    fw->pause_wanted = 0;
    fw->paused_by_link = 0;
    fw->exposure_left = 0;
    if (fw->state == FW_PLANNING) drop_plan(fw);
    fw->state = fw->plan_kind ? FW_READY : FW_IDLE;
    fw->phase = FW_PHASE_MOVE;
}

/* ------------------------------------------------------------------ frames */

static int can_move(const fw_state *fw)
{
    return fw->state == FW_IDLE || fw->state == FW_READY || fw->state == FW_DONE || fw->state == FW_PAUSED;
}

/* Payload sizes each message needs (-1: any). */
static int payload_size(uint8_t type)
{
    switch (type) {
    case FW_MSG_HELLO: return 1;
    case FW_MSG_STATUS: case FW_MSG_HOME: case FW_MSG_PAUSE: case FW_MSG_RESUME: case FW_MSG_ABORT: return 0;
    case FW_MSG_PROFILE: return 14;
    case FW_MSG_PLAN_GET: return 4;
    case FW_MSG_PLAN_SET: return 8;
    case FW_MSG_MASK: return 12;
    case FW_MSG_MOVE: return 8;
    case FW_MSG_EXPOSE: return 4;
    case FW_MSG_PRINT: return 32;
    case FW_MSG_EXIT: return 1;
    case FW_MSG_PROFILE_DATA: case FW_MSG_PLAN_DATA: case FW_MSG_MASK_DATA: return -1;
    default: return -2;
    }
}

static void on_frame(fw_state *fw, const uint8_t *f, size_t n, uint64_t now)
{
    uint8_t seq = f[1], type = (uint8_t)(f[2] & ~FW_ROUND_BIT), round = f[2] & FW_ROUND_BIT;
    const uint8_t *p = f + 3;
    size_t size = n - FW_FRAME_MIN;
    int want = payload_size(type);
    fw->heard = now;
    if (!fw->binary) fw->gcode_held_len = 0; /* a binary host: what looked like G-code was not */
    fw->binary = 1;
    if (type == FW_MSG_HELLO) {
        /* a host (re)connecting: its numbering starts here */
        fw->expect = (uint8_t)(seq + 1);
        send_identify(fw);
        return;
    }
    if (seq != fw->expect) {
        uint8_t behind = (uint8_t)(fw->expect - seq);
        /* a repeat whose ack was lost, or a frame past a lost one: the host
           resends from the ack (and ignores NAKs its resending already answers) */
        send_ack(fw, behind >= 1 && behind <= 128 ? 0 : 1 | round);
        return;
    }
    fw->expect++;
    if (want == -2 || (want >= 0 && size != (size_t)want)) { fail(fw, FW_ERR_MESSAGE, seq); send_ack(fw, 0); return; }
    switch (type) {
    case FW_MSG_STATUS: send_status(fw); return;
    case FW_MSG_PLAN_GET: plan_get(fw, p, seq); return;
    case FW_MSG_PROFILE:
        if (fw->state == FW_PRINTING || fw->state == FW_PAUSED || fw_axis_busy(&fw->axis)) fail(fw, FW_ERR_BUSY, seq);
        else profile_begin(fw, p, seq);
        break;
    case FW_MSG_PROFILE_DATA: profile_data(fw, p, size, seq); break;
    case FW_MSG_PLAN_SET:
        if (fw->state == FW_PRINTING || fw->state == FW_PAUSED || fw_axis_busy(&fw->axis)) fail(fw, FW_ERR_BUSY, seq);
        else plan_set(fw, p, seq);
        break;
    case FW_MSG_PLAN_DATA: plan_data(fw, p, size, seq); break;
    case FW_MSG_MASK: mask_begin(fw, p, seq); break;
    case FW_MSG_MASK_DATA: mask_data(fw, p, size, seq); break;
    case FW_MSG_HOME:
        if (!can_move(fw) || fw->state == FW_PAUSED) fail(fw, FW_ERR_BUSY, seq);
        else if (axis_error(fw, fw_axis_home(&fw->axis, now), seq)) fw->state = FW_HOMING;
        break;
    case FW_MSG_MOVE: {
        int32_t target = (int32_t)fw_get32(p);
        if (!can_move(fw)) { fail(fw, FW_ERR_BUSY, seq); break; }
        if (target < 0) { fail(fw, FW_ERR_LIMIT, seq); break; }
        if (axis_error(fw, fw_axis_move_to(&fw->axis, fw_axis_steps_of_nm(&fw->axis, (uint64_t)target),
                                           um_s_to_steps(fw, fw_get32(p + 4)), now), seq) &&
            fw->state != FW_PAUSED)
            fw->state = FW_MOVING;
        break;
    }
    case FW_MSG_EXPOSE:
        if ((fw->state != FW_READY && fw->state != FW_DONE && fw->state != FW_IDLE) || fw_axis_busy(&fw->axis) ||
            fw->uv_on || !fw->mask_ready) {
            fail(fw, FW_ERR_BUSY, seq);
            break;
        }
        fw->port.show(fw->port.ctx, (int)(fw->mask_ready & 1u), now);
        uv(fw, 1, now);
        fw->exposing = 1;
        fw->phase_end = now + FW_MS(fw, fw_get32(p));
        break;
    case FW_MSG_PRINT: print_start(fw, p, seq, now); break;
    case FW_MSG_PAUSE: print_pause(fw, 0, now); break;
    case FW_MSG_RESUME: resume(fw, seq, now); break;
    case FW_MSG_ABORT: abort_all(fw, now); break;
    case FW_MSG_EXIT:
        send_ack(fw, 0);
        if (fw->port.exit) fw->port.exit(fw->port.ctx, p[0]);
        return;
    }
    send_ack(fw, 0);
}

/* ----------------------------------------------------------------- the port */

static void gcode_uv(void *ctx, int on, uint64_t when) { uv((fw_state *)ctx, on, when); }
static void gcode_write(void *ctx, const uint8_t *data, size_t size) { fw_state *fw = (fw_state *)ctx; fw->port.write(fw->port.ctx, data, size); }
static void gcode_motor(void *ctx, int on) { fw_state *fw = (fw_state *)ctx; if (fw->port.motor) fw->port.motor(fw->port.ctx, on); }

/* Offers G-code the bytes it held back; keeps what it still cannot take. */
static void gcode_feed(fw_state *fw, uint64_t now)
{
    size_t used;
    if (!fw->gcode_held_len) return;
    used = fw_gcode_receive(&fw->gcode, fw->gcode_held, fw->gcode_held_len, now);
    memmove(fw->gcode_held, fw->gcode_held + used, fw->gcode_held_len - used);
    fw->gcode_held_len = (uint16_t)(fw->gcode_held_len - used);
}

/* G-code takes the byte now, or it waits in order behind those held. A host
   that sends more than fits (an unpaced burst) loses the rest of that line:
   a 0 byte marks the gap, so the damaged line is refused, never run spliced
   to the next; a line that would start with no room left is lost whole. */
static void gcode_byte(fw_state *fw, uint8_t c, uint64_t now)
{
    size_t room = sizeof fw->gcode_held - fw->gcode_held_len;
    int eol = c == '\n' || c == '\r';
    if (fw->gcode_overflow) {
        if (!eol) return;
        /* 1: the marker was written and a byte kept free for this line end */
        if (fw->gcode_overflow == 1) fw->gcode_held[fw->gcode_held_len++] = c;
        fw->gcode_overflow = 0;
        return;
    }
    if (!fw->gcode_held_len && fw_gcode_receive(&fw->gcode, &c, 1, now)) return;
    if (room > 2) { fw->gcode_held[fw->gcode_held_len++] = c; return; }
    if (!fw->gcode_held_len || fw->gcode_held[fw->gcode_held_len - 1] == '\n' ||
        fw->gcode_held[fw->gcode_held_len - 1] == '\r') {
        fw->gcode_overflow = eol ? 0 : 2;
        return;
    }
    fw->gcode_held[fw->gcode_held_len++] = 0;
    if (eol) fw->gcode_held[fw->gcode_held_len++] = c;
    else fw->gcode_overflow = 1;
}

void fw_init(fw_state *fw, const fw_config *config, const fw_port *port, void *workspace, size_t workspace_size)
{
    fw_gcode_io io;
    memset(fw, 0, sizeof *fw);
    fw->config = *config;
    fw->port = *port;
    fw->workspace = (unsigned char *)workspace;
    fw->workspace_size = workspace_size;
    /* what fits: the rings, then a byte per bin */
    if (adaslice_dp_workspace(fw->config.max_bins, FW_MAX_LAYER_BINS, 0) > workspace_size) {
        size_t fixed = adaslice_dp_workspace(0, FW_MAX_LAYER_BINS, 0);
        fw->config.max_bins = workspace_size > fixed ? (uint32_t)(workspace_size - fixed) : 0;
    }
    fw_axis_init(&fw->axis, &config->axis, config->tick_hz);
    fw_deframer_init(&fw->deframer, fw_host_to_mcu_type);
    fw->state = FW_IDLE;
    io.ctx = fw;
    io.write = gcode_write;
    io.uv = gcode_uv;
    io.motor = gcode_motor;
    fw_gcode_init(&fw->gcode, &fw->axis, &io);
}

void fw_receive(fw_state *fw, const uint8_t *data, size_t size, uint64_t now)
{
    size_t i;
    for (i = 0; i < size; i++) {
        size_t n;
        if (!fw->binary) gcode_byte(fw, data[i], now);
        fw_deframe_push(&fw->deframer, data[i]);
        while ((n = fw_deframe_next(&fw->deframer)) != 0) {
            on_frame(fw, fw->deframer.buf, n, now);
            fw_deframe_consume(&fw->deframer);
        }
    }
}

static uint64_t earliest(uint64_t a, uint64_t b) { return a < b ? a : b; }

uint64_t fw_run(fw_state *fw, uint64_t now)
{
    uint64_t next = FW_NEVER;
    while (fw_axis_busy(&fw->axis)) {
        uint64_t when = fw_axis_next(&fw->axis);
        int dir;
        if (when > now) break;
        dir = fw_axis_step(&fw->axis, fw->port.endstop(fw->port.ctx));
        if (dir) fw->port.step(fw->port.ctx, dir, when);
    }
    if (!fw_axis_busy(&fw->axis)) {
        if (fw->state == FW_HOMING) {
            fw->state = resting(fw);
            if (!fw->axis.homed) fail(fw, FW_ERR_HOME_FAILED, 0);
        } else if (fw->state == FW_MOVING) {
            fw->state = resting(fw);
        }
    }
    if (fw->state == FW_PRINTING) {
        if (now - fw->heard >= FW_MS(fw, fw->config.link_timeout_ms)) print_pause(fw, 1, now);
        else print_step(fw, now);
    }
    /* a manual exposure */
    if (fw->exposing && now >= fw->phase_end) {
        fw->exposing = 0;
        uv(fw, 0, fw->phase_end);
        fw->port.show(fw->port.ctx, -1, fw->phase_end);
    }
    if (fw->binary && fw->state != FW_PRINTING && fw->state != FW_PAUSED &&
        now - fw->heard >= FW_BINARY_IDLE * FW_MS(fw, fw->config.link_timeout_ms))
        fw->binary = 0;
    if (!fw->binary) {
        next = fw_gcode_run(&fw->gcode, now);
        gcode_feed(fw, now);
    }

    if (fw_axis_busy(&fw->axis)) next = earliest(next, fw_axis_next(&fw->axis));
    if (fw->state == FW_PRINTING) {
        if (fw->phase == FW_PHASE_SETTLE || fw->phase == FW_PHASE_EXPOSE) next = earliest(next, fw->phase_end);
        /* once the pause is asked for, the silence has done its work */
        if (!fw->pause_wanted) next = earliest(next, fw->heard + FW_MS(fw, fw->config.link_timeout_ms));
    } else if (fw->exposing) {
        next = earliest(next, fw->phase_end);
    }
    if (fw->binary && fw->state != FW_PRINTING && fw->state != FW_PAUSED)
        next = earliest(next, fw->heard + FW_BINARY_IDLE * FW_MS(fw, fw->config.link_timeout_ms));
    return next;
}
