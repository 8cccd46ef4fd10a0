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
/* The steps the queue may hold: homing's one-step phases queue one at a
   time (each reads the switch after the step before it went out). */
static uint8_t steps_room(const fw_state *fw) { return fw_axis_one_step(&fw->axis) ? 1u : FW_STEP_QUEUE; }
/* The steps a refill leaves room for: FW_STEP_FILL (one pass's), at most
   half the queue, at least one (homing's one step). */
static uint8_t refill_gap(const fw_state *fw)
{
    uint8_t half = (uint8_t)(steps_room(fw) / 2u);
    return half < 1u ? 1u : half < FW_STEP_FILL ? half : (uint8_t)FW_STEP_FILL;
}
/* Steps to compute: the queue is refilled once refill_gap steps have gone
   out, and then to the full (short_by: a refill the budget cut), so that a
   pass computes several steps (its own work is a good part of a step
   interval on an 8-bit core) while the rest covers the wait, and a pass
   that computes none (a frame, a piece of G-code or of the print, a slice
   of a held frame) begins with more than room - refill_gap steps queued. */
static int steps_wanted(const fw_state *fw)
{
    uint8_t queued = steps_queued(fw), room = steps_room(fw);
    return fw_axis_busy(&fw->axis) && queued < room && (queued <= room - refill_gap(fw) || fw->steps.short_by);
}
static void fill_steps(fw_state *fw, uint64_t now);
static void stop_dead(fw_state *fw, uint8_t error, uint64_t now);

/* ------------------------------------------------------------------ replies */

/* A reply goes to the port in pieces as it is made: its head (LEN, SEQ,
   TYPE), the payload from where it was built, the CRC and sync byte. No
   frame is assembled, so no frame-sized buffer sits on the stack. */
static uint16_t reply_put(fw_state *fw, uint16_t crc, const uint8_t *data, size_t size)
{
    fw->port.write(fw->port.ctx, data, size);
    return link_crc16_more(crc, data, size);
}

static uint16_t reply_begin(fw_state *fw, uint8_t type, size_t size)
{
    uint8_t head[3];
    head[0] = (uint8_t)(size + LINK_FRAME_MIN);
    head[1] = fw->expect;
    head[2] = type;
    return reply_put(fw, 0xffffu, head, sizeof head);
}

static void reply_end(fw_state *fw, uint16_t crc)
{
    uint8_t tail[3];
    tail[0] = (uint8_t)(crc >> 8);
    tail[1] = (uint8_t)crc;
    tail[2] = LINK_SYNC;
    fw->port.write(fw->port.ctx, tail, sizeof tail);
}

static void send(fw_state *fw, uint8_t type, const uint8_t *payload, size_t size)
{
    if (size <= LINK_PAYLOAD_MAX) reply_end(fw, reply_put(fw, reply_begin(fw, type, size), payload, size));
}

/* nak: LINK_NAK | the round bit of the frame that showed the gap (PROTOCOL.md) */
static void send_ack(fw_state *fw, int nak)
{
    uint8_t p[LINK_SIZE_ACK];
    link_ack m;
    m.nak = (uint8_t)nak;
    send(fw, LINK_MSG_ACK, p, link_put_ack(p, &m));
}

/* Z in nm, rounded to nearest (half away from 0), in whole steps per mm and
   the rest apart: 32-bit divisions, as every STATUS asks for it and a
   64-bit one is thousands of cycles on an 8-bit core. */
static int32_t z_nm(const fw_state *fw)
{
    int32_t steps = fw->axis.position;
    uint32_t per_mm = fw->config.axis.steps_per_mm;
    uint32_t a = steps < 0 ? 0u - (uint32_t)steps : (uint32_t)steps, q = a / per_mm, r = a % per_mm;
    uint64_t part = (uint64_t)r * 1000000u + per_mm / 2u;
    uint64_t nm = (uint64_t)q * 1000000u + (part >> 32 ? part / per_mm : (uint32_t)part / per_mm);
    return (int32_t)(steps < 0 ? 0u - (uint32_t)nm : (uint32_t)nm);
}

static FW_NOINLINE void send_identify(fw_state *fw)
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
    m.max_exposure_ms = FW_EXPOSURE_MAX_MS;
    m.crc_byte_ns = c->crc_byte_ns;
    m.plan_bin_ns = c->plan_bin_ns;
    send(fw, LINK_MSG_IDENTIFY, p, link_put_identify(p, &m));
}

/* The light a layer still owes, exposing or paused, in whole ms rounded up,
   at the tick the frame asking for it came: a host never believes less
   light is owed than is, and one that loses the printer mid-exposure (a
   reset) resumes with what the last STATUS said. Kept out of line: its
   64-bit work would otherwise widen on_frame's frame, which is under
   send()'s. */
static FW_NOINLINE uint32_t exposure_left_ms(const fw_state *fw)
{
    uint64_t hz = fw->config.tick_hz, left = fw->exposure_left;
    if (fw->state == LINK_STATE_PRINTING && fw->phase == LINK_PHASE_EXPOSE && fw->phase_end > fw->heard)
        left = fw->phase_end - fw->heard;
    if (!left) return 0; /* as a rule: no 64-bit division for it */
    return (uint32_t)((left * 1000u + hz - 1u) / hz);
}

static FW_NOINLINE void send_status(fw_state *fw)
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
    m.screen = fw->screen;
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

/* A refused profile: no plan, and what arrives next is not pushed. */
static void profile_refuse(fw_state *fw, uint8_t error, uint8_t seq)
{
    fw->receiving = 0;
    fw->state = LINK_STATE_IDLE;
    fail(fw, error, seq);
}

/* One pass's share of a PROFILE_DATA frame (fw->decode_at): FW_PLAN_BINS
   bins through the planner at most; once the profile's last bin is in and
   the frame read to its end, FW_REVERSE_PLANES planes of the plan's
   reversal a pass. A frame of a hundred bins is a few hundred thousand
   cycles of planning on an 8-bit core: no pass may hold the steps up that
   long. Returns 1 when the frame is done. */
static int profile_work(fw_state *fw)
{
    uint32_t pushed = 0;
    uint8_t seq = fw->decode_seq;
    while (fw->decode_left && pushed < FW_PLAN_BINS) {
        uint32_t v = 0;
        int done;
        if (adaslice_varint_push(&fw->varint, *fw->decode_at, &done, &v) != ADASLICE_OK) {
            profile_refuse(fw, LINK_ERR_PROFILE_DATA, seq);
            return 1;
        }
        fw->decode_at++;
        fw->decode_left--;
        if (!done) continue;
        /* a number past the last bin: the profile is not what was announced */
        if (fw->bins_in >= fw->bins) { profile_refuse(fw, LINK_ERR_PROFILE_DATA, seq); return 1; }
        adaslice_dp_push(&fw->dp, link_bin_units(v), link_bin_forced(v) && fw->bins_in + 1 < fw->bins);
        fw->bins_in++;
        pushed++;
    }
    if (fw->decode_left) return 0;
    if (fw->bins_in < fw->bins) return 1; /* more frames to come */
    if (adaslice_dp_layers(&fw->dp) == ADASLICE_UNREACHED) { profile_refuse(fw, LINK_ERR_INFEASIBLE, seq); return 1; }
    /* the plan is read bottom-up: turn it around, a slice a pass (the pass
       that pushed bins does not turn planes as well) */
    if (pushed || adaslice_dp_reverse_some(&fw->dp, FW_REVERSE_PLANES)) return 0;
    fw->receiving = 0;
    fw->layers = adaslice_dp_layers(&fw->dp);
    fw->plan_kind = 1;
    fw->cursor_layer = 0;
    fw->state = LINK_STATE_READY;
    return 1;
}

/* Starts a PROFILE_DATA frame's work; 1 when it is done (refused) at once. */
static int profile_data(fw_state *fw, const uint8_t *p, size_t size, uint8_t seq)
{
    if (fw->state != LINK_STATE_PLANNING || fw->receiving != LINK_MSG_PROFILE_DATA) { fail(fw, LINK_ERR_BUSY, seq); return 1; }
    fw->decode_at = p;
    fw->decode_left = size;
    fw->decode_seq = seq;
    fw->decoding = LINK_MSG_PROFILE_DATA;
    return 0;
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

/* The page's bins go out in pieces of this many as they are read. */
#define FW_PLAN_PIECE 32u

static FW_NOINLINE void plan_get(fw_state *fw, const link_plan_get *m, uint8_t seq)
{
    uint8_t head[LINK_SIZE_PLAN], piece[FW_PLAN_PIECE], n, i, left = 0;
    uint32_t k = m->first;
    uint16_t crc;
    link_plan page;
    if (!fw->plan_kind) { fail(fw, LINK_ERR_NO_PLAN, seq); send_ack(fw, 0); return; }
    page.first = m->first;
    page.layers = fw->layers;
    page.bin_nm = fw->bin_nm;
    if (k >= 1 && k <= fw->layers)
        left = (uint8_t)(fw->layers - k < LINK_PAYLOAD_MAX - LINK_SIZE_PLAN ? fw->layers - k + 1u : LINK_PAYLOAD_MAX - LINK_SIZE_PLAN);
    crc = reply_begin(fw, LINK_MSG_PLAN, LINK_SIZE_PLAN + left);
    crc = reply_put(fw, crc, head, link_put_plan(head, &page));
    for (; left; left = (uint8_t)(left - n)) {
        n = left < sizeof piece ? left : (uint8_t)sizeof piece;
        for (i = 0; i < n; i++) piece[i] = (uint8_t)layer_length(fw, k++);
        crc = reply_put(fw, crc, piece, n);
    }
    reply_end(fw, crc);
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

/* One pass's share of the MASK_DATA frame being decoded: FW_DECODE_BYTES
   of code and FW_CRC_BYTES of rows' CRC at most (a row is copied to the
   display when its CRC is in), so that no pass of the loop runs long,
   whatever the code holds: a row of many runs takes several passes, a
   wide row several, a repeat of a thousand rows a thousand or more.
   Returns 1 when the frame is done. */
static int mask_decode(fw_state *fw)
{
    size_t used, bytes = fw->decode_left < FW_DECODE_BYTES ? fw->decode_left : FW_DECODE_BYTES;
    if (adaslice_rle_decode_rows(&fw->decoder, fw->decode_at, bytes, FW_CRC_BYTES, &used, mask_row, fw) != ADASLICE_OK) {
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

/* Starts decoding a MASK_DATA frame (its rows come in the next passes of
   fw_run, after the pass that received it); 1 when it is done (refused) at
   once. */
static int mask_data(fw_state *fw, const uint8_t *p, size_t size, uint8_t seq)
{
    if (!fw->mask_layer) { fail(fw, LINK_ERR_MASK_ORDER, seq); return 1; }
    if (size > fw->mask_size - fw->mask_got) { mask_refuse(fw, LINK_ERR_MASK_CODE, seq); return 1; }
    fw->mask_got += (uint32_t)size;
    fw->decode_at = p;
    fw->decode_left = size;
    fw->decode_seq = seq;
    fw->decoding = LINK_MSG_MASK_DATA;
    return 0;
}

/* -------------------------------------------------------------------- print */

static void say_halted(fw_state *fw);

/* On from `when` until `until`: the port's timer ends it, whatever the loop
   does. A halted core lights nothing, whoever asks (fw_stack_fault). */
static void uv(fw_state *fw, int on, uint64_t when, uint64_t until)
{
    if (on && fw->halted) { say_halted(fw); return; }
    fw->uv_on = (uint8_t)on;
    fw->port.uv(fw->port.ctx, on, when, until);
}

/* A speed under a step a second is one step a second: 0 steps/s is the
   axis's top speed (motion.c), and a peel asked at 2 um/s ran at 10 mm/s. */
static uint32_t um_s_to_steps(const fw_state *fw, uint32_t um_s)
{
    uint64_t p = (uint64_t)um_s * fw->config.axis.steps_per_mm, s;
    /* 32 bits when it fits: a 64-bit division is thousands of cycles on an 8-bit core */
    s = p >> 32 ? p / 1000u : (uint32_t)p / 1000u;
    if (!s && um_s) s = 1;
    return s > 0xffffffffu ? 0xffffffffu : (uint32_t)s;
}

static void abort_all(fw_state *fw, uint64_t now);

/* The print cannot go on safely: it stops with the light off, the plan and
   `exposed` kept, Z where it is (still homed), and STATUS says why. */
static void print_fault(fw_state *fw, uint8_t error, uint64_t now)
{
    abort_all(fw, now);
    fail(fw, error, 0);
}

/* Moves to the top of the current layer (plus `extra_nm`) at `speed` steps/s.
   The move's first step, which shapes its trapezoid, is the next pass's
   work: this one has had the layer's (its height, the phase's bookkeeping).
   A move the axis refuses (busy, unhomed, past a limit) would leave the next
   exposure at the wrong height: a fault. 0 then. */
static int move_layer(fw_state *fw, uint32_t extra_nm, uint32_t speed, uint64_t now)
{
    fw->steps.budget = 0;
    /* never under a mask on the host's screen (the print's phases see to
       it; this is the last word) */
    if (fw->screen) { print_fault(fw, LINK_ERR_SCREEN_LIT, now); return 0; }
    if (fw_axis_move_to(&fw->axis, steps_of_plane(fw, fw->top_plane, extra_nm), speed, now) == FW_AXIS_OK) return 1;
    print_fault(fw, LINK_ERR_MOVE_FAILED, now);
    return 0;
}

/* Z stands (every step out) exactly at the current layer's top. */
static int at_layer_top(const fw_state *fw)
{
    return !moving(fw) && fw->axis.homed && fw->axis.position == steps_of_plane(fw, fw->top_plane, 0);
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
    if (fw->screen) { fail(fw, LINK_ERR_SCREEN_LIT, seq); return; }
    if (first < 1 || first > fw->layers) { fail(fw, LINK_ERR_MESSAGE, seq); return; }
    fw->peel_nm = m->peel_nm;
    fw->peel_speed = um_s_to_steps(fw, m->peel_speed_um_s);
    fw->return_speed = um_s_to_steps(fw, m->return_speed_um_s);
    fw->settle_ms = m->settle_ms;
    fw->job = m->job;
    fw->exposed = first - 1;
    fw->layer = first;
    fw->top_plane = layer_bottom(fw, first) + layer_length(fw, first);
    /* the highest the print goes: the plan's top (its last bin, no walk
       through the plan) and a peel; every layer's top is below it */
    if (steps_of_plane(fw, fw->bins, fw->peel_nm) > fw->config.axis.max_steps) {
        fail(fw, LINK_ERR_LIMIT, seq);
        return;
    }
    fw->mask_ready = first - 1;
    fw->mask_layer = 0;
    fw->host_screen = 0;
    fw->exposure_left = 0;
    fw->pause_wanted = 0;
    fw->paused_by_link = 0;
    fw->state = LINK_STATE_PRINTING;
    fw->phase = LINK_PHASE_MOVE;
    (void)move_layer(fw, 0, fw->return_speed, now);
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
            if (fw->host_screen ? fw->screen != fw->layer : fw->mask_ready < fw->layer) return;
            if (!fw->host_screen) fw->port.show(fw->port.ctx, (int)(fw->layer & 1u), now);
            fw->phase = LINK_PHASE_SETTLE;
            fw->phase_end = now + FW_MS(fw, fw->settle_ms);
            break;
        case LINK_PHASE_SETTLE:
            if (fw->pause_wanted) { fw->state = LINK_STATE_PAUSED; return; }
            if (now < fw->phase_end) return;
            /* the last word before the light: whatever happened since the
               move (a pause, a host's command, a bug), never expose elsewhere */
            if (!at_layer_top(fw)) { print_fault(fw, LINK_ERR_WRONG_HEIGHT, now); return; }
            /* the host's screen went dark meanwhile (a pause): it draws the layer again */
            if (fw->host_screen && fw->screen != fw->layer) { fw->phase = LINK_PHASE_WAIT_MASK; break; }
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
            if (fw->host_screen) { fw->phase = LINK_PHASE_DARK; break; }
            fw->port.show(fw->port.ctx, -1, fw->phase_end);
            fw->phase = LINK_PHASE_PEEL;
            if (!move_layer(fw, fw->peel_nm, fw->peel_speed, fw->phase_end)) return;
            break;
        case LINK_PHASE_DARK:
            if (fw->pause_wanted) { fw->state = LINK_STATE_PAUSED; return; }
            /* the host puts its screen out before Z moves (SCREEN 0) */
            if (fw->screen) return;
            fw->phase = LINK_PHASE_PEEL;
            if (!move_layer(fw, fw->peel_nm, fw->peel_speed, now)) return;
            break;
        case LINK_PHASE_PEEL:
            if (moving(fw)) return;
            if (fw->layer == fw->layers) { fw->state = LINK_STATE_DONE; return; }
            if (fw->pause_wanted) { fw->state = LINK_STATE_PAUSED; return; }
            fw->layer++;
            fw->top_plane += layer_length(fw, fw->layer);
            fw->phase = LINK_PHASE_MOVE;
            if (!move_layer(fw, 0, fw->return_speed, now)) return;
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
    /* the settle time runs again: the resin was left to itself */
    if (fw->phase == LINK_PHASE_SETTLE) fw->phase_end = now + FW_MS(fw, fw->settle_ms);
    /* a layer not yet exposed goes back to its top first, from whichever
       phase the pause held (a peel's pause goes on to the next layer's
       move anyway) */
    if (fw->phase != LINK_PHASE_PEEL && fw->phase != LINK_PHASE_DARK && !at_layer_top(fw)) {
        if (fw->screen) { fw->state = LINK_STATE_PAUSED; fail(fw, LINK_ERR_SCREEN_LIT, seq); return; }
        fw->phase = LINK_PHASE_MOVE;
        if (!move_layer(fw, 0, fw->return_speed, now)) return;
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

/* SCREEN: what the host's screen shows. Layer 0, dark, is taken at any
   time; a light on under a layer the host has put out is a pause (UV off,
   the rest of the exposure kept). A layer is taken only as the one the
   print waits for, with Z standing at its top (or paused there), and its
   exposure as MASK's (a resumed layer's rest comes first). fw_run's next
   pass moves the print on. */
static void screen(fw_state *fw, const link_screen *m, uint8_t seq, uint64_t now)
{
    int printing = fw->state == LINK_STATE_PRINTING || fw->state == LINK_STATE_PAUSED;
    if (!m->layer) {
        if (fw->state == LINK_STATE_PRINTING && fw->phase == LINK_PHASE_EXPOSE) print_pause(fw, 0, now);
        if (fw->exposing) { fw->exposing = 0; uv(fw, 0, now, now); }
        fw->screen = 0;
        return;
    }
    if (m->layer == LINK_SCREEN_PATTERN) {
        /* a test pattern, for EXPOSE: outside a print, Z still */
        if (printing || moving(fw) || fw->uv_on) { fail(fw, LINK_ERR_SCREEN_LAYER, seq); return; }
        fw->screen = m->layer;
        return;
    }
    if (!printing || m->layer != fw->layer || moving(fw) ||
        (fw->phase != LINK_PHASE_WAIT_MASK && fw->phase != LINK_PHASE_SETTLE)) {
        fail(fw, LINK_ERR_SCREEN_LAYER, seq);
        return;
    }
    if (!m->exposure_ms || m->exposure_ms > FW_EXPOSURE_MAX_MS) { fail(fw, LINK_ERR_MASK_EXPOSURE, seq); return; }
    fw->screen = m->layer;
    fw->host_screen = 1;
    fw->exposure_ms[m->layer & 1u] = m->exposure_ms;
}

/* ------------------------------------------------------------------ frames */

/* MOVE and HOME: never while a print is under way or paused (the paused
   layer's height is the print's), nor with the light on. */
static int can_move(const fw_state *fw)
{
    return (fw->state == LINK_STATE_IDLE || fw->state == LINK_STATE_READY || fw->state == LINK_STATE_DONE) && !fw->uv_on;
}

/* Kept out of fw_receive: a compiler inlines a function called once, and
   with it its locals, which would then sit under every G-code byte's call
   into the G-code reader. */
static FW_NOINLINE void on_frame(fw_state *fw, const uint8_t *f, size_t n, uint64_t now)
{
    uint8_t seq = f[1], type = (uint8_t)(f[2] & ~LINK_ROUND_BIT), round = f[2] & LINK_ROUND_BIT;
    const uint8_t *p = f + 3;
    size_t size = n - LINK_FRAME_MIN;
    union { link_profile profile; link_plan_get plan_get; link_plan_set plan_set; link_mask mask; link_screen screen; link_move move;
            link_expose expose; link_print print; link_exit exit; } m;
    if (!fw->binary) {
        /* a binary host: what looked like G-code was not, and a light
           G-code left on is nobody's now */
        fw->gcode_held_len = 0;
        fw_gcode_drop(&fw->gcode);
        if (fw->uv_on) uv(fw, 0, now, now);
        fw->urgent = 0;
    }
    fw->binary = 1;
    if (type == LINK_MSG_HELLO) {
        /* a host (re)connecting: its numbering starts here */
        fw->heard = now;
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
    /* Only a frame taken is the host's word: a host that resends its window
       over and over hears nothing of the printer, and has not heard it go
       on, so its repeats keep no print going (the link timeout runs). */
    fw->heard = now;
    fw->expect++;
    if (fw->halted && type != LINK_MSG_STATUS) { fail(fw, LINK_ERR_STACK, seq); send_ack(fw, 0); return; }
    if (!link_payload_fits(type, size)) { fail(fw, LINK_ERR_MESSAGE, seq); send_ack(fw, 0); return; }
    switch (type) {
    case LINK_MSG_STATUS: send_status(fw); return;
    case LINK_MSG_PLAN_GET: (void)link_get_plan_get(&m.plan_get, p, size); plan_get(fw, &m.plan_get, seq); return;
    case LINK_MSG_PROFILE:
        (void)link_get_profile(&m.profile, p, size);
        if (fw->state == LINK_STATE_PRINTING || fw->state == LINK_STATE_PAUSED || moving(fw)) fail(fw, LINK_ERR_BUSY, seq);
        else profile_begin(fw, &m.profile, seq);
        break;
    case LINK_MSG_PROFILE_DATA:
        /* acknowledged once planned, in later passes */
        if (!profile_data(fw, p, size, seq)) return;
        break;
    case LINK_MSG_PLAN_SET:
        (void)link_get_plan_set(&m.plan_set, p, size);
        if (fw->state == LINK_STATE_PRINTING || fw->state == LINK_STATE_PAUSED || moving(fw)) fail(fw, LINK_ERR_BUSY, seq);
        else plan_set(fw, &m.plan_set, seq);
        break;
    case LINK_MSG_PLAN_DATA: plan_data(fw, p, size, seq); break;
    case LINK_MSG_MASK: (void)link_get_mask(&m.mask, p, size); mask_begin(fw, &m.mask, seq); break;
    case LINK_MSG_MASK_DATA:
        /* acknowledged once decoded, in later passes */
        if (!mask_data(fw, p, size, seq)) return;
        break;
    case LINK_MSG_SCREEN: (void)link_get_screen(&m.screen, p, size); screen(fw, &m.screen, seq, now); break;
    case LINK_MSG_HOME:
        if (!can_move(fw)) fail(fw, LINK_ERR_BUSY, seq);
        else if (fw->screen) fail(fw, LINK_ERR_SCREEN_LIT, seq);
        else if (axis_error(fw, fw_axis_home(&fw->axis, now), seq)) fw->state = LINK_STATE_HOMING;
        break;
    case LINK_MSG_MOVE: {
        int32_t target;
        (void)link_get_move(&m.move, p, size);
        target = m.move.z_nm;
        if (!can_move(fw)) { fail(fw, LINK_ERR_BUSY, seq); break; }
        if (fw->screen) { fail(fw, LINK_ERR_SCREEN_LIT, seq); break; }
        if (target < 0) { fail(fw, LINK_ERR_LIMIT, seq); break; }
        if (axis_error(fw, fw_axis_move_to(&fw->axis, fw_axis_steps_of_nm(&fw->axis, (uint64_t)target),
                                           um_s_to_steps(fw, m.move.speed_um_s), now), seq))
            fw->state = LINK_STATE_MOVING;
        break;
    }
    case LINK_MSG_EXPOSE:
        if ((fw->state != LINK_STATE_READY && fw->state != LINK_STATE_DONE && fw->state != LINK_STATE_IDLE) || moving(fw) ||
            fw->uv_on || (!fw->mask_ready && fw->screen != LINK_SCREEN_PATTERN)) {
            fail(fw, LINK_ERR_BUSY, seq);
            break;
        }
        (void)link_get_expose(&m.expose, p, size);
        if (!m.expose.ms || m.expose.ms > FW_EXPOSURE_MAX_MS) { fail(fw, LINK_ERR_MASK_EXPOSURE, seq); break; }
        /* the host's test pattern, or the last verified mask */
        if (fw->screen != LINK_SCREEN_PATTERN) fw->port.show(fw->port.ctx, (int)(fw->mask_ready & 1u), now);
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
static void gcode_feed(fw_state *fw)
{
    size_t used;
    if (!fw->gcode_held_len) return;
    used = fw_gcode_receive(&fw->gcode, fw->gcode_held, fw->gcode_held_len);
    memmove(fw->gcode_held, fw->gcode_held + used, fw->gcode_held_len - used);
    fw->gcode_held_len = (uint16_t)(fw->gcode_held_len - used);
}

/* G-code takes the byte now, or it waits in order behind those held. A host
   that sends more than fits (an unpaced burst) loses the rest of that line:
   a 0 byte marks the gap, so the damaged line is refused, never run spliced
   to the next; a line that would start with no room left is lost whole. */
static void gcode_byte(fw_state *fw, uint8_t c)
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
    if (!fw->gcode_held_len && fw_gcode_receive(&fw->gcode, &c, 1)) return;
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
    fw->link_timeout = FW_MS(fw, config->link_timeout_ms);
    fw->watchdog_half = FW_MS(fw, config->watchdog_ms) / 2u;
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

/* Marlin's emergency parser: M112 and M410 (after an optional line number,
   with blanks, a checksum or a comment after them) are acted on when their
   line ends, as the bytes arrive, not when the lines held before them have
   run. fw->urgent is where the line's bytes are: */
enum { URGENT_START, URGENT_N, URGENT_AFTER_N, URGENT_M, URGENT_M1, URGENT_M11, URGENT_M4, URGENT_M41, URGENT_M112,
       URGENT_M410, URGENT_M112_REST, URGENT_M410_REST, URGENT_OTHER };

int fw_urgent_byte(uint8_t *state, uint8_t c)
{
    uint8_t st = *state;
    int blank = c == ' ' || c == '\t';
    if (c == '\n' || c == '\r') {
        *state = URGENT_START;
        return st == URGENT_M112 || st == URGENT_M112_REST ? 112 : st == URGENT_M410 || st == URGENT_M410_REST ? 410 : 0;
    }
    if (c >= 'a' && c <= 'z') c = (uint8_t)(c - 'a' + 'A');
    switch (st) {
    case URGENT_START: st = blank ? st : c == 'N' ? URGENT_N : c == 'M' ? URGENT_M : URGENT_OTHER; break;
    case URGENT_N: st = (c >= '0' && c <= '9') || c == '-' ? st : blank ? URGENT_AFTER_N : URGENT_OTHER; break;
    case URGENT_AFTER_N: st = blank ? st : c == 'M' ? URGENT_M : URGENT_OTHER; break;
    case URGENT_M: st = c == '1' ? URGENT_M1 : c == '4' ? URGENT_M4 : URGENT_OTHER; break;
    case URGENT_M1: st = c == '1' ? URGENT_M11 : URGENT_OTHER; break;
    case URGENT_M11: st = c == '2' ? URGENT_M112 : URGENT_OTHER; break;
    case URGENT_M4: st = c == '1' ? URGENT_M41 : URGENT_OTHER; break;
    case URGENT_M41: st = c == '0' ? URGENT_M410 : URGENT_OTHER; break;
    case URGENT_M112: case URGENT_M410:
        if (c == '*' || c == ';') st = st == URGENT_M112 ? URGENT_M112_REST : URGENT_M410_REST;
        else if (!blank) st = URGENT_OTHER;
        break;
    default: break;
    }
    *state = st;
    return 0;
}

/* M112: Z stops dead (unhomed) and the light goes out; M410: Z brakes to a
   stop, still homed. Either drops every line held (they were sent before
   the stop and are not to run after it) and answers the line itself. */
static void urgent_stop(fw_state *fw, int code, uint64_t now)
{
    fw->gcode_held_len = 0;
    fw->gcode_overflow = 0;
    fw_gcode_drop(&fw->gcode);
    if (code == 112) {
        stop_dead(fw, 0, now);
        fw_gcode_say(&fw->gcode, FW_TEXT("echo:Emergency stop (M112): Z stopped dead, UV off; home Z (G28)"));
    } else {
        abort_all(fw, now);
        fw_gcode_dark(&fw->gcode, 0);
        fw_gcode_say(&fw->gcode, FW_TEXT("echo:Quick stop (M410): Z braking to a stop, UV off"));
    }
    fw_gcode_say(&fw->gcode, FW_TEXT("ok"));
}

size_t fw_receive(fw_state *fw, const uint8_t *data, size_t size, uint64_t now)
{
    link_deframer *d = &fw->deframer;
    size_t i = 0, n = 0;
    int gcode = !fw->binary, line = 0; /* only a frame (below) changes `binary` */
    if (fw->decoding) return 0;
    /* the steps come first: the bytes wait (in the port's ring) while the
       queue is to be refilled */
    if (steps_wanted(fw)) return 0;
    /* Up to the byte that ends a frame or a G-code line. A frame's work is
       its pass's share, and the steps (a move it started has its first
       step a step lead on, far beyond a pass) come in the next; a line
       waits for fw_run's passes. */
    if (gcode && size) fw->heard = now; /* the light's watch (fw_gcode_watch) */
    while (i < size && !n && !line) {
        uint8_t c = data[i++];
        if (gcode) {
            int urgent = fw_urgent_byte(&fw->urgent, c);
            line = c == '\n' || c == '\r';
            if (urgent) urgent_stop(fw, urgent, now);
            else gcode_byte(fw, c);
        }
        if (link_deframe_push(d, c)) n = link_deframe_next(d);
    }
    if (!n) return i;
    /* more than one only when a damaged frame left good ones buffered */
    do {
        on_frame(fw, fw->deframer.buf, n, now);
        if (fw->decoding) break; /* it keeps the deframer's buffer */
        link_deframe_consume(&fw->deframer);
    } while ((n = link_deframe_next(&fw->deframer)) != 0);
    fw->steps.budget = 0;
    return i;
}

static uint64_t earliest(uint64_t a, uint64_t b) { return a < b ? a : b; }

/* ------------------------------------------------------------------ steps */

/* A step that cannot go out on time, the endstop closing where it cannot,
   an emergency stop: everything stops dead (Klipper's "timer too close"
   shutdown). The steps still queued are dropped, so the position is lost:
   the axis is left unhomed. A G-code host is told in a line of its own. */
static void stop_dead(fw_state *fw, uint8_t error, uint64_t now)
{
    fw->port.step_arm(fw->port.ctx, FW_NEVER, 0);
    fw->steps.running = 0;
    fw->steps.late = 0;
    fw->steps.tail = fw->steps.head;
    fw_axis_stop(&fw->axis);
    if (fw->port.motor) fw->port.motor(fw->port.ctx, 0);
    abort_all(fw, now);
    if (error) fail(fw, error, 0);
    if (!fw->binary) {
        fw_gcode_dark(&fw->gcode, 1);
        if (error == LINK_ERR_STEP_LATE) fw_gcode_say(&fw->gcode, FW_TEXT("Error:Z step late: stopped, UV off; home Z (G28)"));
        if (error == LINK_ERR_ENDSTOP)
            fw_gcode_say(&fw->gcode, FW_TEXT("Error:Z endstop closed during a move: stopped, UV off; home Z (G28)"));
    }
}

/* The Z-min switch reads closed outside homing. At the switch's point and
   just above it that is the axis at home (its repeatability: an eighth of
   a millimetre, a shift where a division would cost a good part of a pass
   on an 8-bit core for every step the switch stays closed); on the way
   up, as far as homing's back-off may need (the switch's travel); anywhere
   higher the carriage has hit something or lost steps. The carriage is
   within a queue's steps of the position computed. */
static int endstop_misplaced(const fw_state *fw)
{
    const fw_axis *a = &fw->axis;
    int32_t lowest = a->position - (int32_t)FW_STEP_QUEUE;
    int32_t allowed = a->dir < 0 ? (int32_t)(a->config.steps_per_mm >> 3) : (int32_t)a->backoff_limit;
    return lowest > allowed;
}

/* Tops the queue up from the closed form, at most `budget` steps; a fault
   when a step cannot go out on time (its tick passed, or the timer could
   not be armed: STEP_LATE) or the endstop closes outside homing where it
   cannot (ENDSTOP), else 0. Homing's one-step phases queue one step at a time: each reads
   the switch after the step before it went out. The approach queues
   ahead like a move: it sees the switch up to a queue and a refill of
   steps late and brakes from there, and backing off measures
   from where it stopped, so the zero is the same. */
static int fill(fw_state *fw, uint64_t now)
{
    fw_steps *q = &fw->steps;
    uint8_t room = steps_room(fw), first = 1;
    q->short_by = 0;
    if (q->late) return LINK_ERR_STEP_LATE;
    if (fw->halted && fw_axis_busy(&fw->axis)) { /* G-code's G28: a halted core moves nothing */
        fw_axis_stop(&fw->axis);
        say_halted(fw);
    }
    if (!steps_wanted(fw)) return 0;
    while (fw_axis_busy(&fw->axis) && steps_queued(fw) < room) {
        uint8_t at = (uint8_t)(q->head % FW_STEP_QUEUE);
        int dir, closed;
        if (!q->budget) { q->short_by = 1; return 0; }
        /* the steps' ticks only grow and `now` holds for the call: the
           first tells whether any is past */
        if (first && fw_axis_next(&fw->axis) < now) return LINK_ERR_STEP_LATE;
        first = 0;
        closed = fw->port.endstop(fw->port.ctx);
        if (closed && !fw_axis_homing(&fw->axis) && endstop_misplaced(fw)) return LINK_ERR_ENDSTOP;
        dir = fw_axis_step(&fw->axis, closed);
        /* no step (homing braking at the switch): the step after it is
           computed in the same pass, so it is never late for a pass */
        if (!dir) continue;
        q->budget--;
        q->tick[at] = fw->axis.last;
        q->dir[at] = (int8_t)dir;
        q->head = (uint8_t)(q->head + 1u);
        /* the interrupt clears `running` only on an empty queue, so one
           that reads 1 here will also take the step just added */
        if (!q->running) {
            q->running = 1;
            if (!fw->port.step_arm(fw->port.ctx, q->tick[at], dir)) return LINK_ERR_STEP_LATE;
        }
    }
    return 0;
}

/* G-code mode's word of the halt, at the fault and to each command that
   would light or move (a binary host reads STATUS's error). */
static void say_halted(fw_state *fw)
{
    if (!fw->binary) fw_gcode_say(&fw->gcode, FW_TEXT("Error:Printer halted: stack overrun"));
}

void fw_stack_fault(fw_state *fw, uint64_t now)
{
    if (fw->halted) return;
    stop_dead(fw, 0, now);
    uv(fw, 0, now, now); /* again: the light's own state may be what the stack overwrote */
    fw->halted = 1;
    fail(fw, LINK_ERR_STACK, 0);
    say_halted(fw);
}

static void fill_steps(fw_state *fw, uint64_t now)
{
    int fault = fill(fw, now);
    if (fault) stop_dead(fw, (uint8_t)fault, now);
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
    fill_steps(fw, now);
    if (!moving(fw)) {
        if (fw->state == LINK_STATE_HOMING) {
            fw->state = resting(fw);
            if (!fw->axis.homed) fail(fw, LINK_ERR_HOME_FAILED, 0);
        } else if (fw->state == LINK_STATE_MOVING) {
            fw->state = resting(fw);
        }
    }
    /* One piece of work a pass, after the steps: on an 8-bit core a frame,
       a ramp step, a move's start and a slice of a held frame are each a
       good part of a step interval. The pass that received a frame (its
       budget spent) or computed a step leaves the print's next phase and
       the next slice to the next pass; steps leave no faster than one an
       interval, so a full queue leaves passes for them. */
    if (fw->state == LINK_STATE_PRINTING) {
        if (now - fw->heard >= fw->link_timeout) print_pause(fw, 1, now);
        else if (fw->steps.budget == FW_STEP_FILL) print_step(fw, now); /* a move it starts spends the budget */
        else next = now;
    }
    /* the held frame's next slice; the frame is acknowledged once done */
    if (fw->decoding && fw->steps.budget == FW_STEP_FILL) {
        fw->steps.budget = 0; /* the slice is this pass's work: steps in the next */
        if (fw->decoding == LINK_MSG_MASK_DATA ? mask_decode(fw) : profile_work(fw)) {
            fw->decoding = 0;
            link_deframe_consume(&fw->deframer);
            send_ack(fw, 0);
        }
    }
    /* a manual exposure */
    if (fw->exposing && now >= fw->phase_end) {
        fw->exposing = 0;
        fw->uv_on = 0; /* the port's timer put it out */
        fw->port.show(fw->port.ctx, -1, fw->phase_end);
    }
    if (fw->binary && fw->state != LINK_STATE_PRINTING && fw->state != LINK_STATE_PAUSED &&
        now - fw->heard >= FW_BINARY_IDLE * fw->link_timeout)
        fw->binary = 0;
    /* G-code's pieces of work (a line's check, its run, a G0/G1's start, a
       move's or a dwell's end) are passes' work like a frame: one when the
       pass has none yet */
    if (!fw->binary) {
        gcode_feed(fw);
        if (fw->steps.budget != FW_STEP_FILL) next = now;
        else if ((next = fw_gcode_run(&fw->gcode, now)) == now) fw->steps.budget = 0;
        next = earliest(next, fw_gcode_watch(&fw->gcode, fw->heard, fw->link_timeout, now));
    }
    /* what the print or G-code just started */
    fill_steps(fw, now);

    /* the next refill (steps_wanted), and once the last step has gone
       out, the move's end */
    if (fw->steps.short_by) {
        next = now; /* the rest of the queue on the next pass */
    } else {
        uint8_t tail = fw->steps.tail, last = (uint8_t)(fw->steps.head - tail - 1u), gap = (uint8_t)(refill_gap(fw) - 1u);
        if (last != 0xFFu) { /* queued: the tail's index is read once, as the interrupt moves it */
            if (fw_axis_busy(&fw->axis) && gap < last) last = gap;
            next = earliest(next, fw->steps.tick[(uint8_t)(tail + last) % FW_STEP_QUEUE]);
        } else if (fw_axis_busy(&fw->axis)) {
            /* moving with nothing queued: the interrupt took the last
               queued step after fill_steps ran (homing queues one), so
               refill at once; waiting for the next step's own tick would
               find it past */
            next = now;
        }
    }
    if (fw->watchdog_half) next = earliest(next, now + fw->watchdog_half);
    if (fw->decoding) next = now; /* the frame's next slice, in the next pass */
    if (fw->state == LINK_STATE_PRINTING) {
        if (fw->phase == LINK_PHASE_SETTLE || fw->phase == LINK_PHASE_EXPOSE) next = earliest(next, fw->phase_end);
        /* once the pause is asked for, the silence has done its work */
        if (!fw->pause_wanted) next = earliest(next, fw->heard + fw->link_timeout);
    } else if (fw->exposing) {
        next = earliest(next, fw->phase_end);
    }
    if (fw->binary && fw->state != LINK_STATE_PRINTING && fw->state != LINK_STATE_PAUSED)
        next = earliest(next, fw->heard + FW_BINARY_IDLE * fw->link_timeout);
    /* the next pass's steps: its fw_receive and its fw_run share them */
    fw->steps.budget = FW_STEP_FILL;
    return next;
}
