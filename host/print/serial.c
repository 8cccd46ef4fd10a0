/* The host's end of the serial link: see serial.h and link/PROTOCOL.md. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "serial.h"
#include "../bytes.h"
#include "../report.h"
#include "../../link/tty.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <termios.h>
#include <unistd.h>

/* ------------------------------------------------------------ the port */

static int serial_open_port(const char *dev, long baud, int *fd_out)
{
    struct termios t;
    int fd;
    if (!tty_baud_ok(baud))
        return complain(RC_USAGE, "--baud %ld: not a standard rate (9600, 19200, 38400, 57600, 115200, 230400)", baud);
    fd = open(dev, O_RDWR | O_NOCTTY | O_NONBLOCK);
    if (fd < 0) return complain(RC_FAIL, "cannot open %s: %s", dev, strerror(errno));
    if (tcgetattr(fd, &t) != 0) {
        close(fd);
        return complain(RC_FAIL, "%s is not a serial port: %s", dev, strerror(errno));
    }
    if (tty_raw(fd, baud) != 0) {
        close(fd);
        return complain(RC_FAIL, "cannot set %s to %ld 8N1: %s", dev, baud, strerror(errno));
    }
    /* what a previous session left unread must not pass for replies */
    tcflush(fd, TCIOFLUSH);
    *fd_out = fd;
    return RC_OK;
}

/* ------------------------------------------------------------- the link */

/* A STATUS round trip of `rtt` ms: the retransmission timeout follows the
   line (a pty answers in a millisecond, a loaded 9600 baud line in seconds). */
static void serial_rtt(serial_link *l, double rtt)
{
    if (!l->srtt) { l->srtt = rtt; l->rttvar = rtt / 2; }
    else {
        l->rttvar = 0.75 * l->rttvar + 0.25 * fabs(l->srtt - rtt);
        l->srtt = 0.875 * l->srtt + 0.125 * rtt;
    }
    l->rto_ms = l->srtt + 4 * l->rttvar;
    if (l->rto_ms < 60) l->rto_ms = 60;
    if (l->rto_ms > 1000) l->rto_ms = 1000;
}

static int printing(const link_status *s) { return s->state == LINK_STATE_PRINTING || s->state == LINK_STATE_PAUSED; }

int serial_stopped(const serial_link *l, int rc, const char *what, int at_layer, int z_kept)
{
    const link_status *s = &l->st;
    char phase[40] = "", owed[96] = "", left[40] = "", heard[200] = "";
    if (l->stopping) l->stopping(l->stopping_ctx);
    if (!at_layer)
        return complain(rc, "the printer on %s %s while %s, before this run exposed a layer: Z must be homed before "
                            "printing again: clear the platform and print again (a --resume-from needs --home)",
                        l->dev, what, l->task ? l->task : link_state_name(s->state));
    if (printing(s)) snprintf(phase, sizeof phase, " (%s)", link_phase_name(s->phase));
    if (z_kept)
        return complain(rc, "the printer on %s %s at layer %u%s: layer %u was the last fully exposed; continue with "
                            "--resume-from %u", l->dev, what, s->layer, phase, s->exposed, s->exposed + 1);
    /* A layer cut short owes the light the last STATUS said was left: never
       less, and more by at most the light since that STATUS was made, which
       went out by now (a restart, a printer without power) or the printer
       holds the rest itself (paused by the lost link: resumed in place).
       Rounded up to the ms as the printer rounds. */
    if (printing(s) && s->exposure_left_ms && s->layer == s->exposed + 1) {
        double since = s->flags & LINK_FLAG_UV ? now_ms() - l->st_after : 0;
        snprintf(owed, sizeof owed, ", layer %u owes %u ms of its light (or up to %.0f ms less)", s->layer,
                 s->exposure_left_ms, ceil(since) + 1);
        snprintf(left, sizeof left, " --exposure-left %u", s->exposure_left_ms);
    }
    /* What the printer said last. One that still runs goes on until its
       link timeout, as far as the masks it has: the layer it was at and the
       next (the host sends a mask only one layer ahead of what it heard);
       --resume-from is checked against where it stands. */
    if (rc == RC_LOST && printing(s))
        snprintf(heard, sizeof heard, ", as last heard (a printer still running pauses itself its link timeout after the "
                                      "host's last frame, perhaps a layer or two on: the resume then names the layer)");
    /* a printer that lost only the line pauses itself and keeps Z homed:
       the same command resumes it in place */
    return complain(rc, "the printer on %s %s at layer %u%s: layer %u was the last fully exposed%s%s; Z must be homed before "
                        "printing again%s: clear the platform, then continue with --resume-from %u --home%s%s",
                    l->dev, what, s->layer, phase, s->exposed, owed, heard,
                    rc == RC_LOST ? " (unless the printer kept the print paused)" : "", s->exposed + 1, left,
                    rc == RC_LOST ? ", which resumes a paused print in place" : "");
}

/* The port went away (an adapter unplugged, the emulator gone): as a
   printer that stopped answering, which may still hold the print paused. */
static int serial_gone(serial_link *l, const char *doing, int err)
{
    char what[96];
    l->gone = 1;
    if (l->ending) return RC_LOST; /* EXIT sent: the emulator went, and its port with it */
    snprintf(what, sizeof what, "went away (%s the port: %s)", doing, err ? strerror(err) : "it hung up");
    return serial_stopped(l, RC_LOST, what, printing(&l->st), 0);
}

/* The printer answered nothing for `ms` while the host waited (`how`). */
static int serial_silent(const serial_link *l, const char *how, double ms)
{
    char what[80];
    snprintf(what, sizeof what, "stopped answering (%s for %.1f s)", how, ms / 1000);
    return serial_stopped(l, RC_LOST, what, printing(&l->st), 0);
}

/* The work the frames in flight ask of the printer: the last one's
   acknowledgement comes after all of it (an earlier reply may be lost). */
static double serial_work(const serial_link *l)
{
    double ms = 0;
    int i;
    for (i = 0; i < l->count; i++) ms += l->work_ms[i];
    return ms;
}

/* How long the printer may answer nothing: silent_ms and that work. */
static double serial_bound(const serial_link *l)
{
    return l->silent_ms + serial_work(l);
}

/* A printer that stopped reads nothing, and the line fills: a write that
   cannot get a byte out for as long as the printer may be silent is lost. */
static int serial_write(serial_link *l, const uint8_t *data, size_t size)
{
    double moved = now_ms();
    while (size) {
        ssize_t n = write(l->fd, data, size);
        if (n > 0) {
            data += n;
            size -= (size_t)n;
            l->bytes_out += (unsigned long)n;
            moved = now_ms();
            continue;
        }
        if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) return serial_gone(l, "writing", errno);
        /* the printer's silence, as serial_pump would find it, or the line's;
           waiting here is waiting for the printer, not time away */
        l->last_looked = now_ms();
        if (l->count && now_ms() - l->waiting_since > serial_bound(l))
            return serial_silent(l, "nothing", now_ms() - l->waiting_since);
        if (now_ms() - moved > serial_bound(l)) return serial_silent(l, "the line took no byte", now_ms() - moved);
        {
            struct pollfd p = {l->fd, POLLOUT, 0};
            (void)poll(&p, 1, 100);
        }
    }
    return RC_OK;
}

/* Go back N: everything unacknowledged again, in a new round (its NAKs are
   told apart from those older copies draw), and smaller data frames. */
static int serial_resend_all(serial_link *l)
{
    int i, rc;
    l->round ^= LINK_ROUND_BIT;
    for (i = 0; i < l->count; i++) {
        uint8_t *f = l->frames[i];
        size_t n = l->lens[i];
        uint16_t crc;
        f[2] = (uint8_t)((f[2] & ~LINK_ROUND_BIT) | l->round);
        crc = link_crc16(f, n - 3);
        put_be16(f + n - 3, crc);
        if ((rc = serial_write(l, f, n))) return rc;
    }
    l->retransmits += (unsigned long)l->count;
    l->last_progress = now_ms();
    l->clean = 0;
    if (l->data_max > 32) l->data_max /= 2;
    return RC_OK;
}

static void take_reply(serial_link *l, const uint8_t *f, size_t n)
{
    const uint8_t *p = f + 3;
    size_t size = n - LINK_FRAME_MIN;
    uint8_t ack = f[1], acked = (uint8_t)(ack - l->base);
    /* every reply acknowledges what came before ack; one outside the frames
       in flight is of a numbering this host did not give (the line's damage
       and loss never make one: acknowledgements come in order) */
    if (l->count && acked > l->count) l->stray = 1;
    if (acked && acked <= l->count) {
        memmove(l->frames[0], l->frames[acked], (size_t)(l->count - acked) * sizeof l->frames[0]);
        memmove(l->lens, l->lens + acked, (size_t)(l->count - acked) * sizeof l->lens[0]);
        memmove(l->work_ms, l->work_ms + acked, (size_t)(l->count - acked) * sizeof l->work_ms[0]);
        l->acked_sent = l->sent_ms[acked - 1];
        memmove(l->sent_ms, l->sent_ms + acked, (size_t)(l->count - acked) * sizeof l->sent_ms[0]);
        l->count -= acked;
        l->base = ack;
        l->last_progress = now_ms();
        l->rehellos = 0;
        l->clean += acked;
        if (l->clean >= 32 && l->data_max < LINK_PAYLOAD_MAX) {
            l->data_max = l->data_max * 2 > LINK_PAYLOAD_MAX ? LINK_PAYLOAD_MAX : l->data_max * 2;
            l->clean = 0;
        }
    }
    switch (f[2]) {
    case LINK_MSG_ACK: {
        link_ack m;
        /* frames sent before our last resend still draw NAKs: those are answered */
        if (link_get_ack(&m, p, size) && (m.nak & LINK_NAK) && l->count) {
            l->naks++;
            /* said already; serial_pump returns it */
            if ((m.nak & LINK_ROUND_BIT) == l->round && !l->failed) l->failed = serial_resend_all(l);
        }
        break;
    }
    case LINK_MSG_STATUS_REPLY: {
        link_status st;
        if (!link_get_status(&st, p, size)) break;
        if (l->boot_id && st.boot_id != l->boot_id) { l->new_boot_id = st.boot_id; break; }
        l->st = st;
        l->st_after = l->acked_sent;
        l->status_count++;
        l->status_ack = ack;
        break;
    }
    case LINK_MSG_IDENTIFY:
        if (!link_get_identify(&l->id, p, size)) break;
        if (l->boot_id && l->id.boot_id != l->boot_id) l->new_boot_id = l->id.boot_id;
        l->identify_count++;
        break;
    case LINK_MSG_PLAN:
        memcpy(l->plan, p, size);
        l->plan_size = size;
        l->plan_count++;
        break;
    default:
        break;
    }
}

/* Reads what has arrived, waiting up to wait_ms. */
static int serial_read(serial_link *l, int wait_ms)
{
    uint8_t buf[4096];
    struct pollfd p = {l->fd, POLLIN, 0};
    if (poll(&p, 1, wait_ms) > 0) {
        ssize_t n = read(l->fd, buf, sizeof buf), i;
        if (n < 0 && errno != EAGAIN && errno != EINTR) return serial_gone(l, "reading", errno);
        /* a port hung up reads nothing, at once, for ever */
        if (n <= 0 && (p.revents & (POLLHUP | POLLERR | POLLNVAL))) return serial_gone(l, "reading", 0);
        for (i = 0; i < n; i++) {
            size_t m;
            link_deframe_push(&l->rx, buf[i]);
            while ((m = link_deframe_next(&l->rx)) != 0) {
                double t = now_ms();
                if (l->count && t - l->waiting_since > l->longest_wait) l->longest_wait = t - l->waiting_since;
                l->waiting_since = t;
                take_reply(l, l->rx.buf, m);
                link_deframe_consume(&l->rx);
            }
        }
        if (n > 0) l->bytes_in += (unsigned long)n;
    }
    return RC_OK;
}

/* The printer restarted: what it last said before (l->st) is what is known. */
static int serial_restarted(const serial_link *l)
{
    char what[64];
    snprintf(what, sizeof what, "restarted (boot id %u -> %u)", l->boot_id, l->new_boot_id);
    return serial_stopped(l, RC_RESET, what, printing(&l->st), 0);
}

/* The printer acknowledged a number this host never sent: a restarted MCU
   answers every frame with a NAK or an ACK of its own count (each of which
   restarts the silence timer), and one that another host said HELLO to
   counts from that host's numbers. HELLO asks who is there, at once, so
   that a restart is known within a round trip of the first frame it
   answered. It carries base - 1, so an MCU that did not restart but lost
   the numbering expects `base` next, and the frames in flight stay valid. */
static int serial_rehello(serial_link *l)
{
    uint8_t payload[LINK_SIZE_HELLO], frame[LINK_FRAME_MAX];
    unsigned long seen = l->identify_count;
    double start = now_ms(), sent = 0;
    link_hello m;
    size_t n;
    int rc;
    m.version = LINK_PROTOCOL_VERSION;
    n = link_frame_build(frame, (uint8_t)(l->base - 1), LINK_MSG_HELLO, payload, link_put_hello(payload, &m));
    while (l->identify_count == seen && !l->new_boot_id) {
        if (now_ms() - start > 2000) {
            return serial_stopped(l, RC_LOST, "stopped answering (no IDENTIFY to HELLO in 2 s, after acknowledgements out "
                                              "of step)", printing(&l->st), 0);
        }
        if (now_ms() - sent > 250) {
            if ((rc = serial_write(l, frame, n))) return rc;
            sent = now_ms();
        }
        if ((rc = serial_read(l, 20))) return rc;
    }
    if (l->new_boot_id) return serial_restarted(l);
    if (++l->rehellos > 1)
        return serial_stopped(l, RC_LOST, "takes no frame (out of step again after a HELLO, without progress)",
                              printing(&l->st), 0);
    /* what came out of step before the HELLO's answer is answered by it */
    l->stray = 0;
    return serial_resend_all(l);
}

/* Reads what has arrived (waiting up to wait_ms), resends on a timeout. */
int serial_pump(serial_link *l, int wait_ms)
{
    double t;
    int rc;
    if (l->failed) return l->failed;
    /* a host that was away (its own work, descheduled, stopped) did not
       wait for the printer meanwhile: the wait starts again */
    t = now_ms();
    if (l->count && t - l->last_looked > SERIAL_AWAY_MS) l->waiting_since = t;
    l->last_looked = t;
    if ((rc = serial_read(l, wait_ms)) || (rc = l->failed)) return rc;
    if (l->new_boot_id) return serial_restarted(l);
    t = now_ms();
    /* what arrived was read first: a reply the host was too busy to read is not silence */
    if (l->count && t - l->waiting_since > serial_bound(l)) return serial_silent(l, "nothing", t - l->waiting_since);
    if (l->count && t - l->last_progress > l->rto_ms + serial_work(l) && (rc = serial_resend_all(l))) return rc;
    if (l->stray) return serial_rehello(l);
    return RC_OK;
}

/* Queues a frame that asks work_ms of the printer, waiting while its
   window is full. */
static int serial_send_work(serial_link *l, uint8_t type, const uint8_t *payload, size_t size, double work_ms)
{
    int rc;
    while (l->count >= l->window || l->count >= SERIAL_QUEUE)
        if ((rc = serial_pump(l, 20))) return rc;
    l->lens[l->count] = link_frame_build(l->frames[l->count], l->next_seq, (uint8_t)(type | l->round), payload, size);
    l->work_ms[l->count] = work_ms;
    l->sent_ms[l->count] = now_ms();
    if (!l->count) l->last_progress = l->waiting_since = now_ms();
    rc = serial_write(l, l->frames[l->count], l->lens[l->count]);
    l->count++;
    l->next_seq++;
    return rc;
}

int serial_send(serial_link *l, uint8_t type, const uint8_t *payload, size_t size)
{
    return serial_send_work(l, type, payload, size, 0);
}

int serial_send_mask_data(serial_link *l, const uint8_t *code, size_t size, uint32_t crc_bytes)
{
    return serial_send_work(l, LINK_MSG_MASK_DATA, code, size, crc_bytes * (l->id.crc_byte_ns / 1e6));
}

int serial_send_profile_data(serial_link *l, const uint8_t *data, size_t size, uint32_t bins)
{
    return serial_send_work(l, LINK_MSG_PROFILE_DATA, data, size, bins * (l->id.plan_bin_ns / 1e6));
}

/* A fresh STATUS: asked again if its reply is lost. */
/* A STATUS_REPLY since `seen` that answers a request from sequence number
   `first` on: its acknowledgement is past that request. Replies to older
   requests may still come (a printer that held them while it decoded a mask,
   a resend round) and say what was true before. */
static int fresh_status(const serial_link *l, unsigned long seen, uint8_t first)
{
    return l->status_count != seen && (uint8_t)(l->status_ack - (uint8_t)(first + 1)) < 128;
}

/* How long a STATUS goes unanswered before another is asked: a few round
   trips and the work the frames ahead of it ask, 10 ms at least. */
static double serial_reask_ms(const serial_link *l)
{
    double ms = 4 * l->srtt + serial_work(l);
    return ms > 10 ? ms : 10;
}

int serial_status(serial_link *l)
{
    unsigned long seen = l->status_count;
    uint8_t first = l->next_seq;
    int rc;
    for (;;) {
        double asked;
        unsigned long resends;
        int reasked = 0;
        if ((rc = serial_send(l, LINK_MSG_STATUS, NULL, 0))) return rc;
        asked = now_ms(); /* after any wait for the window: that is not the line's round trip */
        resends = l->retransmits;
        while (!fresh_status(l, seen, first) && now_ms() - asked < l->rto_ms * 2) {
            /* Asked once more after a few round trips. An MCU just restarted
               has no numbering of ours: it acknowledges every frame with its
               own count, 0, and when our STATUS was number 255 that reads as
               taken, so nothing is resent and the reply never comes; the
               next number, 0, is the first the new boot takes, and its reply
               carries the new boot id. Without it the restart was heard at
               twice the retransmission timeout (a screen put out 127 ms
               after an MCU reset, where it takes 5-7 ms). Requests are
               idempotent. */
            if (!reasked && l->count < l->window && now_ms() - asked > serial_reask_ms(l)) {
                reasked = 1;
                if ((rc = serial_send(l, LINK_MSG_STATUS, NULL, 0))) return rc;
            }
            if ((rc = serial_pump(l, 2))) return rc;
        }
        if (fresh_status(l, seen, first)) {
            /* Karn: no sample across a resend, nor across a second request */
            if (l->retransmits == resends && !reasked) serial_rtt(l, now_ms() - asked);
            return RC_OK;
        }
    }
}

int serial_ask_status(serial_link *l)
{
    if ((uint8_t)(l->asked_seq - l->base) < (uint8_t)l->count) return RC_OK;
    l->asked_seq = l->next_seq;
    return serial_send(l, LINK_MSG_STATUS, NULL, 0);
}

static int serial_hello(serial_link *l)
{
    uint8_t payload[LINK_SIZE_HELLO], frame[LINK_FRAME_MAX];
    double start = now_ms(), sent = 0;
    link_hello m;
    size_t n;
    int rc;
    m.version = LINK_PROTOCOL_VERSION;
    n = link_frame_build(frame, l->next_seq, LINK_MSG_HELLO, payload, link_put_hello(payload, &m));
    /* an emulator may drop what arrives before it looks at the port: say hello until answered */
    while (!l->identify_count) {
        if (now_ms() - start > 5000) return complain(RC_FAIL, "no adaslice printer answers on %s (5 s)", l->dev);
        if (now_ms() - sent > 250) {
            if ((rc = serial_write(l, frame, n))) return rc;
            sent = now_ms();
        }
        if ((rc = serial_pump(l, 20))) return rc;
    }
    if (l->id.version != LINK_PROTOCOL_VERSION)
        return complain(RC_FAIL, "the printer speaks protocol %u; this tool speaks %u", l->id.version, LINK_PROTOCOL_VERSION);
    l->next_seq++;
    l->base = l->next_seq;
    l->count = 0;
    l->window = l->id.window ? l->id.window : 1;
    l->boot_id = l->id.boot_id;
    return RC_OK;
}

/* Waits until a STATUS shows `done` true. */
int serial_wait(serial_link *l, int (*done)(const link_status *, const void *), const void *ctx, double timeout_ms,
                const char *what)
{
    double start = now_ms();
    int rc;
    for (;;) {
        if ((rc = serial_status(l))) return rc;
        if (done(&l->st, ctx)) return RC_OK;
        if (now_ms() - start > timeout_ms)
            return complain(RC_FAIL, "the printer on %s did not %s in %.0f s", l->dev, what, timeout_ms / 1000);
        if ((rc = serial_pump(l, 20))) return rc;
    }
}


int serial_connect(serial_link *l, const char *dev, long baud, double give_up_s)
{
    /* a full frame's time on the line both ways, in ms */
    double frame_ms = 2000.0 * LINK_FRAME_MAX * 10 / (double)baud;
    int rc;
    memset(l, 0, sizeof *l);
    l->fd = -1;
    if ((rc = serial_open_port(dev, baud, &l->fd))) return rc;
    l->dev = dev;
    link_deframer_init(&l->rx, link_mcu_to_host_type);
    l->silent_ms = give_up_s * 1000 + frame_ms;
    /* a window of frames at the line rate, with room for the printer's turnaround */
    l->rto_ms = 200 + frame_ms;
    if ((rc = serial_hello(l))) return rc;
    l->rto_ms += frame_ms * l->window;
    /* the reply to the last frame of a window comes after the whole window */
    l->silent_ms += frame_ms * (l->window - 1);
    l->data_max = LINK_PAYLOAD_MAX;
    return RC_OK;
}

void serial_close(serial_link *l)
{
    if (l->fd >= 0) close(l->fd);
    l->fd = -1;
}

const char *serial_why_not(const serial_link *l)
{
    static char why[64];
    if (l->st.error) return link_error_name(l->st.error);
    snprintf(why, sizeof why, "it stayed %s, refusing nothing", link_state_name(l->st.state));
    return why;
}

int serial_plan_page(serial_link *l, uint32_t first, int *rc)
{
    uint8_t buf[LINK_SIZE_PLAN_GET];
    unsigned long seen = l->plan_count;
    link_plan_get m;
    link_plan page;
    double asked;
    m.first = first;
    if ((*rc = serial_send(l, LINK_MSG_PLAN_GET, buf, link_put_plan_get(buf, &m)))) return 0;
    asked = now_ms();
    while (l->plan_count == seen && now_ms() - asked < l->rto_ms * 2)
        if ((*rc = serial_pump(l, 10))) return 0;
    return l->plan_count != seen && link_get_plan(&page, l->plan, l->plan_size) && page.first == first;
}
