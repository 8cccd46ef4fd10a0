/* The firmware core every port shares: link, planner, masks, the print.
   See fw.h for the port's side and PROTOCOL.md for the wire. */
#include "fw.h"
#include <string.h>

#define FW_MS(fw, ms) ((uint64_t)(ms) * (fw)->config.tick_hz / 1000u)
/* a binary host silent for this many link timeouts hands the port back to G-code */
#define FW_BINARY_IDLE 5u

static uint8_t steps_queued(const fw_state *fw) { return (uint8_t)(fw->steps.head - fw->steps.tail); }

/* Z moves until its last step is out, not merely computed. */
static int moving(const fw_state *fw) { return fw_axis_busy(&fw->axis) || steps_queued(fw); }
static void fill_steps(fw_state *fw, uint64_t now);

/* ------------------------------------------------------------------ replies */

static void send(fw_state *fw, uint8_t type, const uint8_t *payload, size_t size)
{
    uint8_t frame[LINK_FRAME_MAX];
    size_t n = link_frame_build(frame, fw->expect, type, payload, size);
    if (n) fw->port.write(fw->port.ctx, frame, n);
}

/* nak: LINK_NAK | the round bit of the frame that showed the gap (PROTOCOL.md) */
static void send_ack(fw_state *fw, int nak)
{
    uint8_t p[LINK_SIZE_ACK];
    link_ack m;
    m.nak = (uint8_t)nak;
    send(fw, LINK_MSG_ACK, p, link_put_ack(p, &m));
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
    uint8_t p[LINK_SIZE_IDENTIFY];
    const fw_config *c = &fw->config;
    link_identify m;
    m.version = LINK_PROTOCOL_VERSION;
    m.window = c->window;
    m.max_bins = c->max_bins;
    m.max_layer_bins = FW_MAX_LAYER_BINS;
    m.steps_per_mm = c->axis.steps_per_mm;
    m.width = c->display_width;
    m.height = c->display_height;
    m.bits = c->display_bits;
    m.pitch_nm = c->pitch_nm;
    m.z_max_nm = (uint32_t)((uint64_t)c->axis.max_steps * 1000000u / c->axis.steps_per_mm);
    m.tick_hz = c->tick_hz;
    m.link_timeout_ms = c->link_timeout_ms;
    m.boot_id = c->boot_id;
    send(fw, LINK_MSG_IDENTIFY, p, link_put_identify(p, &m));
}

/* A paused exposure's rest, in whole ms rounded up: a host never believes
   less light is owed than is. */
static uint32_t exposure_left_ms(const fw_state *fw)
{
    uint64_t hz = fw->config.tick_hz;
    return (uint32_t)((fw->exposure_left * 1000u + hz - 1u) / hz);
}

static void send_status(fw_state *fw)
{
    uint8_t p[LINK_SIZE_STATUS_REPLY];
    link_status m;
    m.state = fw->state;
    m.phase = fw->phase;
    m.error = fw->error;
    m.error_seq = fw->error_seq;
    m.flags = 0;
    if (fw->axis.homed) m.flags |= LINK_FLAG_HOMED;
    if (fw->uv_on) m.flags |= LINK_FLAG_UV;
    if (moving(fw)) m.flags |= LINK_FLAG_MOVING;
    if (fw->paused_by_link) m.flags |= LINK_FLAG_LINK_LOST;
    m.layer = fw->layer;
    m.layers = fw->layers;
    m.mask_ready = fw->mask_ready;
    m.mask_layer = fw->mask_layer;
    m.mask_got = fw->mask_got;
    m.masks_refused = fw->masks_refused;
    m.z_nm = z_nm(fw);
    m.bins_in = fw->bins_in;
    m.bad_frames = fw->deframer.bad;
    m.window = fw->config.window;
    m.boot_id = fw->config.boot_id;
    m.exposed = fw->exposed;
    m.exposure_left_ms = exposure_left_ms(fw);
    m.job = fw->job;
    send(fw, LINK_MSG_STATUS_REPLY, p, link_put_status(p, &m));
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
    if (fw->state == LINK_STATE_PAUSED) return LINK_STATE_PAUSED;
    return fw->plan_kind ? LINK_STATE_READY : LINK_STATE_IDLE;
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
    case FW_AXIS_BUSY: return fail(fw, LINK_ERR_BUSY, seq);
    case FW_AXIS_NOT_HOMED: return fail(fw, LINK_ERR_NOT_HOMED, seq);
    case FW_AXIS_LIMIT: return fail(fw, LINK_ERR_LIMIT, seq);
    default: return fail(fw, LINK_ERR_HOME_FAILED, seq);
    }
}

static void profile_begin(fw_state *fw, const link_profile *m, uint8_t seq)
{
    uint32_t bins = m->bins, eps = m->eps_units, bin_nm = m->bin_nm;
    uint8_t lo = m->bins_min, hi = m->bins_max;
    if (bins > fw->config.max_bins) { fail(fw, LINK_ERR_PLAN_SIZE, seq); return; }
    drop_plan(fw);
    fw->state = LINK_STATE_IDLE;
    if (!bins || !bin_nm || !eps || lo < 1 || lo > hi || hi > FW_MAX_LAYER_BINS ||
        adaslice_dp_init(&fw->dp, fw->workspace, fw->workspace_size, bins, lo, hi, eps, 0, 0) != ADASLICE_OK) {
        fail(fw, LINK_ERR_PROFILE, seq);
        return;
    }
    fw->bins = bins;
    fw->bins_in = 0;
    fw->bin_nm = bin_nm;
    memset(&fw->varint, 0, sizeof fw->varint);
    fw->receiving = LINK_MSG_PROFILE_DATA;
    fw->state = LINK_STATE_PLANNING;
}

static void profile_data(fw_state *fw, const uint8_t *p, size_t size, uint8_t seq)
{
    size_t i;
    if (fw->state != LINK_STATE_PLANNING || fw->receiving != LINK_MSG_PROFILE_DATA) { fail(fw, LINK_ERR_BUSY, seq); return; }
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
            if (k == ADASLICE_UNREACHED) { fw->state = LINK_STATE_IDLE; fail(fw, LINK_ERR_INFEASIBLE, seq); return; }
            fw->layers = k;
            fw->plan_kind = 1;
            fw->cursor_layer = 0;
            fw->state = LINK_STATE_READY;
        }
    }
    if (i < size) { fw->receiving = 0; fw->state = LINK_STATE_IDLE; fail(fw, LINK_ERR_PROFILE_DATA, seq); }
}

static void plan_set(fw_state *fw, const link_plan_set *m, uint8_t seq)
{
    uint32_t layers = m->layers, bin_nm = m->bin_nm;
    /* a given plan is a byte per layer in the planner's workspace */
    if (layers > fw->workspace_size) { fail(fw, LINK_ERR_PLAN_SIZE, seq); return; }
    drop_plan(fw);
    fw->state = LINK_STATE_IDLE;
    if (!layers || !bin_nm) { fail(fw, LINK_ERR_PROFILE, seq); return; }
    fw->layers = layers;
    fw->bin_nm = bin_nm;
    fw->bins = 0;
    fw->bins_in = 0; /* counts layers received here */
    fw->receiving = LINK_MSG_PLAN_DATA;
    fw->state = LINK_STATE_PLANNING;
}

static void plan_data(fw_state *fw, const uint8_t *p, size_t size, uint8_t seq)
{
    size_t i;
    if (fw->state != LINK_STATE_PLANNING || fw->receiving != LINK_MSG_PLAN_DATA) { fail(fw, LINK_ERR_BUSY, seq); return; }
    for (i = 0; i < size; i++) {
        if (fw->bins_in >= fw->layers || !p[i]) {
            drop_plan(fw);
            fw->state = LINK_STATE_IDLE;
            fail(fw, LINK_ERR_PROFILE_DATA, seq);
            return;
        }
        fw->workspace[fw->bins_in++] = p[i];
        fw->bins += p[i];
    }
    if (fw->bins_in == fw->layers) { fw->receiving = 0; fw->plan_kind = 2; fw->state = LINK_STATE_READY; }
}

static void plan_get(fw_state *fw, const link_plan_get *m, uint8_t seq)
{
    uint8_t out[LINK_PAYLOAD_MAX];
    uint32_t k;
    link_plan page;
    size_t n;
    if (!fw->plan_kind) { fail(fw, LINK_ERR_NO_PLAN, seq); send_ack(fw, 0); return; }
    page.first = m->first;
    page.layers = fw->layers;
    page.bin_nm = fw->bin_nm;
    n = link_put_plan(out, &page);
    for (k = m->first; k >= 1 && k <= fw->layers && n < sizeof out; k++) out[n++] = (uint8_t)layer_length(fw, k);
    send(fw, LINK_MSG_PLAN, out, n);
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

static void mask_begin(fw_state *fw, const link_mask *m, uint8_t seq)
{
    uint32_t layer = m->layer;
    const fw_config *c = &fw->config;
    int printing = fw->state == LINK_STATE_PRINTING || fw->state == LINK_STATE_PAUSED;
    if (!fw->plan_kind) { fail(fw, LINK_ERR_NO_PLAN, seq); return; }
    /* the next mask only, and never into the buffer a layer still shows */
    if (layer != fw->mask_ready + 1 || layer > fw->layers || (printing && layer > fw->layer + 1)) {
        fail(fw, LINK_ERR_MASK_ORDER, seq);
        return;
    }
    if (adaslice_rle_decoder_init(&fw->decoder, c->display_width, c->display_height, c->display_bits, fw->row,
                                  sizeof fw->row) != ADASLICE_OK) {
        fail(fw, LINK_ERR_MASK_CODE, seq);
        return;
    }
    fw->mask_layer = layer;
    fw->mask_size = m->code_bytes;
    fw->mask_crc = m->crc32;
    fw->mask_exposure_ms = m->exposure_ms;
    fw->mask_got = 0;
    if (!fw->mask_size) mask_refuse(fw, LINK_ERR_MASK_CODE, seq);
    else if (!m->exposure_ms || m->exposure_ms > FW_EXPOSURE_MAX_MS) mask_refuse(fw, LINK_ERR_MASK_EXPOSURE, seq);
}

/* One pass's share of the MASK_DATA frame being decoded: FW_DECODE_ROWS
   rows at most (each a row's CRC and its copy to the display), so that no
   pass of the loop runs long, whatever the code holds: a repeat of a
   thousand rows takes a thousand passes. Returns 1 when the frame is done. */
static int mask_decode(fw_state *fw)
{
    size_t used;
    if (adaslice_rle_decode_rows(&fw->decoder, fw->decode_at, fw->decode_left, FW_DECODE_ROWS, &used, mask_row, fw) !=
        ADASLICE_OK) {
        mask_refuse(fw, LINK_ERR_MASK_CODE, fw->decode_seq);
        return 1;
    }
    fw->decode_at += used;
    fw->decode_left -= used;
    if (fw->decode_left || ADASLICE_RLE_PENDING(&fw->decoder)) return 0;
    if (fw->mask_got < fw->mask_size) return 1;
    if (!adaslice_rle_finished(&fw->decoder) || ADASLICE_RLE_CRC(&fw->decoder) != fw->mask_crc) {
        mask_refuse(fw, LINK_ERR_MASK_CRC, fw->decode_seq);
        return 1;
    }
    fw->exposure_ms[fw->mask_layer & 1u] = fw->mask_exposure_ms;
    fw->mask_ready = fw->mask_layer;
    fw->mask_layer = 0;
    return 1;
}

/* Starts decoding a MASK_DATA frame; 1 when it is done at once. */
static int mask_data(fw_state *fw, const uint8_t *p, size_t size, uint8_t seq)
{
    if (!fw->mask_layer) { fail(fw, LINK_ERR_MASK_ORDER, seq); return 1; }
    if (size > fw->mask_size - fw->mask_got) { mask_refuse(fw, LINK_ERR_MASK_CODE, seq); return 1; }
    fw->mask_got += (uint32_t)size;
    fw->decode_at = p;
    fw->decode_left = size;
    fw->decode_seq = seq;
    if (mask_decode(fw)) return 1;
    fw->decoding = 1;
    return 0;
}

/* -------------------------------------------------------------------- print */

/* On from `when` until `until`: the port's timer ends it, whatever the loop does. */
static void uv(fw_state *fw, int on, uint64_t when, uint64_t until)
{
    fw->uv_on = (uint8_t)on;
    fw->port.uv(fw->port.ctx, on, when, until);
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

static void print_start(fw_state *fw, const link_print *m, uint8_t seq, uint64_t now)
{
    uint32_t first = m->first_layer;
    if (!fw->plan_kind) { fail(fw, LINK_ERR_NO_PLAN, seq); return; }
    if ((fw->state != LINK_STATE_READY && fw->state != LINK_STATE_DONE) || fw->uv_on || moving(fw)) {
        fail(fw, LINK_ERR_BUSY, seq);
        return;
    }
    if (!fw->axis.homed) { fail(fw, LINK_ERR_NOT_HOMED, seq); return; }
    if (first < 1 || first > fw->layers) { fail(fw, LINK_ERR_MESSAGE, seq); return; }
    fw->peel_nm = m->peel_nm;
    fw->peel_speed = m->peel_speed_um_s;
    fw->return_speed = m->return_speed_um_s;
    fw->settle_ms = m->settle_ms;
    fw->job = m->job;
    fw->exposed = first - 1;
    fw->layer = first;
    fw->top_plane = layer_bottom(fw, first) + layer_length(fw, first);
    if (steps_of_plane(fw, fw->top_plane, 0) > fw->config.axis.max_steps ||
        steps_of_plane(fw, layer_bottom(fw, fw->layers) + layer_length(fw, fw->layers), fw->peel_nm) >
            fw->config.axis.max_steps) {
        fail(fw, LINK_ERR_LIMIT, seq);
        return;
    }
    fw->mask_ready = first - 1;
    fw->mask_layer = 0;
    fw->exposure_left = 0;
    fw->pause_wanted = 0;
    fw->paused_by_link = 0;
    fw->state = LINK_STATE_PRINTING;
    fw->phase = LINK_PHASE_MOVE;
    move_layer(fw, 0, fw->return_speed, now);
}

static uint64_t exposure_ticks(const fw_state *fw)
{
    return FW_MS(fw, fw->exposure_ms[fw->layer & 1u]);
}

/* Advances the layer cycle as far as `now` allows:
   move to the layer -> its mask verified -> settle -> expose -> peel -> next. */
static void print_step(fw_state *fw, uint64_t now)
{
    for (;;) {
        switch (fw->phase) {
        case LINK_PHASE_MOVE:
            if (moving(fw)) return;
            if (fw->pause_wanted) { fw->state = LINK_STATE_PAUSED; return; }
            fw->phase = LINK_PHASE_WAIT_MASK;
            break;
        case LINK_PHASE_WAIT_MASK:
            if (fw->pause_wanted) { fw->state = LINK_STATE_PAUSED; return; }
            if (fw->mask_ready < fw->layer) return;
            fw->port.show(fw->port.ctx, (int)(fw->layer & 1u), now);
            fw->phase = LINK_PHASE_SETTLE;
            fw->phase_end = now + FW_MS(fw, fw->settle_ms);
            break;
        case LINK_PHASE_SETTLE:
            if (fw->pause_wanted) { fw->state = LINK_STATE_PAUSED; return; }
            if (now < fw->phase_end) return;
            fw->phase = LINK_PHASE_EXPOSE;
            {
                uint64_t on = fw->phase_end;
                fw->phase_end += fw->exposure_left ? fw->exposure_left : exposure_ticks(fw);
                uv(fw, 1, on, fw->phase_end);
            }
            fw->exposure_left = 0;
            break;
        case LINK_PHASE_EXPOSE:
            if (now < fw->phase_end) {
                if (!fw->pause_wanted) return;
                /* UV off at once; the rest of the exposure waits for resume */
                fw->exposure_left = fw->phase_end - now;
                uv(fw, 0, now, now);
                fw->phase = LINK_PHASE_SETTLE;
                fw->state = LINK_STATE_PAUSED;
                return;
            }
            fw->uv_on = 0; /* the port's timer put it out at phase_end */
            fw->exposed = fw->layer;
            fw->port.show(fw->port.ctx, -1, fw->phase_end);
            fw->phase = LINK_PHASE_PEEL;
            move_layer(fw, fw->peel_nm, fw->peel_speed, fw->phase_end);
            break;
        case LINK_PHASE_PEEL:
            if (moving(fw)) return;
            if (fw->layer == fw->layers) { fw->state = LINK_STATE_DONE; return; }
            if (fw->pause_wanted) { fw->state = LINK_STATE_PAUSED; return; }
            fw->layer++;
            fw->top_plane += layer_length(fw, fw->layer);
            fw->phase = LINK_PHASE_MOVE;
            move_layer(fw, 0, fw->return_speed, now);
            break;
        default:
            return;
        }
    }
}

static void print_pause(fw_state *fw, int by_link, uint64_t now)
{
    if (fw->state != LINK_STATE_PRINTING) return;
    fw->pause_wanted = 1;
    fw->paused_by_link = (uint8_t)by_link;
    print_step(fw, now);
}

static void resume(fw_state *fw, uint8_t seq, uint64_t now)
{
    if (fw->state != LINK_STATE_PAUSED) { fail(fw, LINK_ERR_BUSY, seq); return; }
    fw->pause_wanted = 0;
    fw->paused_by_link = 0;
    fw->state = LINK_STATE_PRINTING;
    if (fw->phase == LINK_PHASE_SETTLE) {
        /* the settle time runs again: the platform may have been moved */
        fw->phase_end = now + FW_MS(fw, fw->settle_ms);
        if (fw->axis.position != steps_of_plane(fw, fw->top_plane, 0)) {
            fw->phase = LINK_PHASE_MOVE;
            move_layer(fw, 0, fw->return_speed, now);
        }
    } else if (fw->phase == LINK_PHASE_WAIT_MASK && fw->axis.position != steps_of_plane(fw, fw->top_plane, 0)) {
        fw->phase = LINK_PHASE_MOVE;
        move_layer(fw, 0, fw->return_speed, now);
    }
    print_step(fw, now);
}

static void abort_all(fw_state *fw, uint64_t now)
{
    fw->exposing = 0;
    if (fw->uv_on) uv(fw, 0, now, now);
    fw->port.show(fw->port.ctx, -1, now);
    fw_axis_halt(&fw->axis, now);
    fw->mask_layer = 0;
    fw->pause_wanted = 0;
    fw->paused_by_link = 0;
    fw->exposure_left = 0;
    if (fw->state == LINK_STATE_PLANNING) drop_plan(fw);
    fw->state = fw->plan_kind ? LINK_STATE_READY : LINK_STATE_IDLE;
    fw->phase = LINK_PHASE_MOVE;
}

/* ------------------------------------------------------------------ frames */

static int can_move(const fw_state *fw)
{
    return fw->state == LINK_STATE_IDLE || fw->state == LINK_STATE_READY || fw->state == LINK_STATE_DONE || fw->state == LINK_STATE_PAUSED;
}

static void on_frame(fw_state *fw, const uint8_t *f, size_t n, uint64_t now)
{
    uint8_t seq = f[1], type = (uint8_t)(f[2] & ~LINK_ROUND_BIT), round = f[2] & LINK_ROUND_BIT;
    const uint8_t *p = f + 3;
    size_t size = n - LINK_FRAME_MIN;
    union { link_profile profile; link_plan_get plan_get; link_plan_set plan_set; link_mask mask; link_move move;
            link_expose expose; link_print print; link_exit exit; } m;
    fw->heard = now;
    if (!fw->binary) fw->gcode_held_len = 0; /* a binary host: what looked like G-code was not */
    fw->binary = 1;
    if (type == LINK_MSG_HELLO) {
        /* a host (re)connecting: its numbering starts here */
        fw->expect = (uint8_t)(seq + 1);
        send_identify(fw);
        return;
    }
    if (seq != fw->expect) {
        uint8_t behind = (uint8_t)(fw->expect - seq);
        /* a repeat whose ack was lost, or a frame past a lost one: the host
           resends from the ack (and ignores NAKs its resending already answers) */
        send_ack(fw, behind >= 1 && behind <= 128 ? 0 : LINK_NAK | round);
        return;
    }
    fw->expect++;
    if (!link_payload_fits(type, size)) { fail(fw, LINK_ERR_MESSAGE, seq); send_ack(fw, 0); return; }
    switch (type) {
    case LINK_MSG_STATUS: send_status(fw); return;
    case LINK_MSG_PLAN_GET: (void)link_get_plan_get(&m.plan_get, p, size); plan_get(fw, &m.plan_get, seq); return;
    case LINK_MSG_PROFILE:
        (void)link_get_profile(&m.profile, p, size);
        if (fw->state == LINK_STATE_PRINTING || fw->state == LINK_STATE_PAUSED || moving(fw)) fail(fw, LINK_ERR_BUSY, seq);
        else profile_begin(fw, &m.profile, seq);
        break;
    case LINK_MSG_PROFILE_DATA: profile_data(fw, p, size, seq); break;
    case LINK_MSG_PLAN_SET:
        (void)link_get_plan_set(&m.plan_set, p, size);
        if (fw->state == LINK_STATE_PRINTING || fw->state == LINK_STATE_PAUSED || moving(fw)) fail(fw, LINK_ERR_BUSY, seq);
        else plan_set(fw, &m.plan_set, seq);
        break;
    case LINK_MSG_PLAN_DATA: plan_data(fw, p, size, seq); break;
    case LINK_MSG_MASK: (void)link_get_mask(&m.mask, p, size); mask_begin(fw, &m.mask, seq); break;
    case LINK_MSG_MASK_DATA:
        /* acknowledged once decoded, in a later pass if it is long */
        if (!mask_data(fw, p, size, seq)) return;
        break;
    case LINK_MSG_HOME:
        if (!can_move(fw) || fw->state == LINK_STATE_PAUSED) fail(fw, LINK_ERR_BUSY, seq);
        else if (axis_error(fw, fw_axis_home(&fw->axis, now), seq)) fw->state = LINK_STATE_HOMING;
        break;
    case LINK_MSG_MOVE: {
        int32_t target;
        (void)link_get_move(&m.move, p, size);
        target = m.move.z_nm;
        if (!can_move(fw)) { fail(fw, LINK_ERR_BUSY, seq); break; }
        if (target < 0) { fail(fw, LINK_ERR_LIMIT, seq); break; }
        if (axis_error(fw, fw_axis_move_to(&fw->axis, fw_axis_steps_of_nm(&fw->axis, (uint64_t)target),
                                           um_s_to_steps(fw, m.move.speed_um_s), now), seq) &&
            fw->state != LINK_STATE_PAUSED)
            fw->state = LINK_STATE_MOVING;
        break;
    }
    case LINK_MSG_EXPOSE:
        if ((fw->state != LINK_STATE_READY && fw->state != LINK_STATE_DONE && fw->state != LINK_STATE_IDLE) || moving(fw) ||
            fw->uv_on || !fw->mask_ready) {
            fail(fw, LINK_ERR_BUSY, seq);
            break;
        }
        (void)link_get_expose(&m.expose, p, size);
        if (!m.expose.ms || m.expose.ms > FW_EXPOSURE_MAX_MS) { fail(fw, LINK_ERR_MASK_EXPOSURE, seq); break; }
        fw->port.show(fw->port.ctx, (int)(fw->mask_ready & 1u), now);
        fw->phase_end = now + FW_MS(fw, m.expose.ms);
        uv(fw, 1, now, fw->phase_end);
        fw->exposing = 1;
        break;
    case LINK_MSG_PRINT: (void)link_get_print(&m.print, p, size); print_start(fw, &m.print, seq, now); break;
    case LINK_MSG_PAUSE: print_pause(fw, 0, now); break;
    case LINK_MSG_RESUME: resume(fw, seq, now); break;
    case LINK_MSG_ABORT: abort_all(fw, now); break;
    case LINK_MSG_EXIT:
        (void)link_get_exit(&m.exit, p, size);
        send_ack(fw, 0);
        if (fw->port.exit) fw->port.exit(fw->port.ctx, m.exit.code);
        return;
    }
    send_ack(fw, 0);
}

/* ----------------------------------------------------------------- the port */

static int gcode_moving(void *ctx) { return moving((const fw_state *)ctx); }
/* M106 has no end: the light's hard limit is the longest exposure */
static void gcode_uv(void *ctx, int on, uint64_t when)
{
    fw_state *fw = (fw_state *)ctx;
    uv(fw, on, when, on ? when + FW_MS(fw, FW_EXPOSURE_MAX_MS) : when);
}
/* uv_on stays set: the light is the port's until M107 says it is out */
static void gcode_uv_end(void *ctx, uint64_t when)
{
    fw_state *fw = (fw_state *)ctx;
    fw->port.uv(fw->port.ctx, 0, when, when);
}
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
    fw->axis.start_lead = config->step_lead;
    fw->steps.budget = FW_STEP_FILL;
    link_deframer_init(&fw->deframer, link_host_to_mcu_type);
    fw->state = LINK_STATE_IDLE;
    io.ctx = fw;
    io.write = gcode_write;
    io.uv = gcode_uv;
    io.uv_end = gcode_uv_end;
    io.motor = gcode_motor;
    io.moving = gcode_moving;
    fw_gcode_init(&fw->gcode, &fw->axis, &io);
}

size_t fw_receive(fw_state *fw, const uint8_t *data, size_t size, uint64_t now)
{
    size_t i;
    for (i = 0; i < size && !fw->decoding; i++) {
        size_t n;
        if (!fw->binary) { gcode_byte(fw, data[i], now); fill_steps(fw, now); }
        link_deframe_push(&fw->deframer, data[i]);
        while (!fw->decoding && (n = link_deframe_next(&fw->deframer)) != 0) {
            on_frame(fw, fw->deframer.buf, n, now);
            /* a frame still decoding keeps the deframer's buffer */
            if (!fw->decoding) link_deframe_consume(&fw->deframer);
            /* a move just asked for starts one step lead from `now` */
            fill_steps(fw, now);
        }
    }
    return i;
}

static uint64_t earliest(uint64_t a, uint64_t b) { return a < b ? a : b; }

/* ------------------------------------------------------------------ steps */

/* A step that cannot go out on time: everything stops dead (Klipper's "timer
   too close" shutdown). The steps still queued are dropped, so the position
   is lost: the axis is left unhomed. */
static void step_fault(fw_state *fw, uint64_t now)
{
    fw->port.step_arm(fw->port.ctx, FW_NEVER, 0);
    fw->steps.running = 0;
    fw->steps.late = 0;
    fw->steps.tail = fw->steps.head;
    fw_axis_stop(&fw->axis);
    if (fw->port.motor) fw->port.motor(fw->port.ctx, 0);
    abort_all(fw, now);
    fail(fw, LINK_ERR_STEP_LATE, 0);
}

/* Tops the queue up from the closed form, at most `budget` steps; 0 when a
   step cannot go out on time (its tick passed, or the timer could not be
   armed). Homing queues one step at a time: each reads the switch after
   the step before it went out. */
static int fill(fw_state *fw, uint64_t now)
{
    fw_steps *q = &fw->steps;
    uint8_t room = fw->axis.phase ? 1u : FW_STEP_QUEUE;
    q->short_by = 0;
    if (q->late) return 0;
    while (fw_axis_busy(&fw->axis) && steps_queued(fw) < room) {
        uint8_t at = (uint8_t)(q->head % FW_STEP_QUEUE);
        int dir;
        if (!q->budget) { q->short_by = 1; return 1; }
        q->budget--;
        if (fw_axis_next(&fw->axis) < now) return 0;
        dir = fw_axis_step(&fw->axis, fw->port.endstop(fw->port.ctx));
        if (!dir) continue;
        q->tick[at] = fw->axis.last;
        q->dir[at] = (int8_t)dir;
        q->head = (uint8_t)(q->head + 1u);
        /* the interrupt clears `running` only on an empty queue, so one
           that reads 1 here will also take the step just added */
        if (!q->running) {
            q->running = 1;
            if (!fw->port.step_arm(fw->port.ctx, q->tick[at], dir)) return 0;
        }
    }
    return 1;
}

static void fill_steps(fw_state *fw, uint64_t now)
{
    if (!fill(fw, now)) step_fault(fw, now);
}

void fw_step_interrupt(fw_state *fw)
{
    fw_steps *q = &fw->steps;
    uint8_t t = q->tail;
    fw->port.step_pulse(fw->port.ctx, q->dir[t % FW_STEP_QUEUE]);
    t = (uint8_t)(t + 1u);
    q->tail = t;
    if (t == q->head) { q->running = 0; return; }
    if (!fw->port.step_arm(fw->port.ctx, q->tick[t % FW_STEP_QUEUE], q->dir[t % FW_STEP_QUEUE])) {
        q->late = 1;
        q->running = 0;
    }
}

uint64_t fw_run(fw_state *fw, uint64_t now)
{
    uint64_t next = FW_NEVER;
    if (fw->port.watchdog) fw->port.watchdog(fw->port.ctx);
    fw->steps.budget = FW_STEP_FILL;
    fill_steps(fw, now);
    if (fw->decoding && mask_decode(fw)) {
        fw->decoding = 0;
        link_deframe_consume(&fw->deframer);
        send_ack(fw, 0);
    }
    if (!moving(fw)) {
        if (fw->state == LINK_STATE_HOMING) {
            fw->state = resting(fw);
            if (!fw->axis.homed) fail(fw, LINK_ERR_HOME_FAILED, 0);
        } else if (fw->state == LINK_STATE_MOVING) {
            fw->state = resting(fw);
        }
    }
    if (fw->state == LINK_STATE_PRINTING) {
        if (now - fw->heard >= FW_MS(fw, fw->config.link_timeout_ms)) print_pause(fw, 1, now);
        else print_step(fw, now);
    }
    /* a manual exposure */
    if (fw->exposing && now >= fw->phase_end) {
        fw->exposing = 0;
        fw->uv_on = 0; /* the port's timer put it out */
        fw->port.show(fw->port.ctx, -1, fw->phase_end);
    }
    if (fw->binary && fw->state != LINK_STATE_PRINTING && fw->state != LINK_STATE_PAUSED &&
        now - fw->heard >= FW_BINARY_IDLE * FW_MS(fw, fw->config.link_timeout_ms))
        fw->binary = 0;
    if (!fw->binary) {
        next = fw_gcode_run(&fw->gcode, now);
        gcode_feed(fw, now);
    }
    /* what the print or G-code just started */
    fill_steps(fw, now);

    /* refilled as each step leaves; homing reads the switch after each */
    if (fw->steps.short_by) next = now; /* the rest of the queue on the next pass */
    else if (steps_queued(fw)) next = earliest(next, fw->steps.tick[fw->steps.tail % FW_STEP_QUEUE]);
    /* moving with nothing queued: the interrupt took the last queued step
       after fill_steps ran (homing queues one), so refill at once; waiting
       for the next step's own tick would find it past (STEP_LATE) */
    else if (fw_axis_busy(&fw->axis)) next = now;
    if (fw->config.watchdog_ms) next = earliest(next, now + FW_MS(fw, fw->config.watchdog_ms) / 2u);
    if (fw->decoding) next = now; /* the next rows, in the next pass */
    if (fw->state == LINK_STATE_PRINTING) {
        if (fw->phase == LINK_PHASE_SETTLE || fw->phase == LINK_PHASE_EXPOSE) next = earliest(next, fw->phase_end);
        /* once the pause is asked for, the silence has done its work */
        if (!fw->pause_wanted) next = earliest(next, fw->heard + FW_MS(fw, fw->config.link_timeout_ms));
    } else if (fw->exposing) {
        next = earliest(next, fw->phase_end);
    }
    if (fw->binary && fw->state != LINK_STATE_PRINTING && fw->state != LINK_STATE_PAUSED)
        next = earliest(next, fw->heard + FW_BINARY_IDLE * FW_MS(fw, fw->config.link_timeout_ms));
    return next;
}
