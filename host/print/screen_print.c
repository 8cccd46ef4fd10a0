/* adaslice print --screen (screen_print.h). */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "screen_print.h"
#include "../report.h"

#include <stdio.h>
#include <string.h>

/* How often the host asks what the printer does, ms: the latency between
   the end of an exposure and the dark screen that lets Z peel. */
#define SCREEN_POLL_MS 5

int screen_print_said_dark(serial_link *l)
{
    uint8_t buf[LINK_SIZE_SCREEN];
    link_screen m;
    m.layer = 0;
    m.exposure_ms = 0;
    return serial_send(l, LINK_MSG_SCREEN, buf, link_put_screen(buf, &m));
}

/* Our screen dark, then the printer told. */
static int go_dark(screen_print *p)
{
    int rc = screen_dark(p->scr);
    return rc ? rc : screen_print_said_dark(p->l);
}

/* PAUSE, its effect waited for (the light out: a pause takes while the
   layer waits, settles or exposes, after the move under way otherwise),
   then dark. */
static int pause_dark(screen_print *p)
{
    serial_link *l = p->l;
    int rc;
    if ((rc = serial_send(l, LINK_MSG_PAUSE, NULL, 0)) || (rc = serial_status(l))) return rc;
    while (l->st.state == LINK_STATE_PRINTING)
        if ((rc = serial_pump(l, 20)) || (rc = serial_status(l))) return rc;
    return go_dark(p);
}

static int paused(screen_print *p, const char *why)
{
    const link_status *s = &p->l->st;
    fprintf(stderr, "\nadaslice: %s: paused at layer %u of %u (UV off, the screen dark, Z held at %.3f mm); "
                    "continue with --resume-from %u\n", why, s->layer, p->layers, s->z_nm / 1e6, s->exposed + 1);
    return RC_PAUSED;
}

/* Layer k drawn whole, then SCREEN k. A layer that cannot be drawn
   pauses the print: the printer waits for this layer's SCREEN, so no
   light comes on over another image. */
static int show_layer(screen_print *p, uint32_t k, int *failed)
{
    const unsigned char *image;
    size_t stride;
    uint8_t buf[LINK_SIZE_SCREEN];
    link_screen m;
    int rc;
    *failed = 0;
    if ((rc = p->mask(p->ctx, k, &image, &stride)) ||
        (rc = screen_show(p->scr, image, stride, p->width, p->height, (int)p->bits))) {
        *failed = 1;
        return rc;
    }
    m.layer = k;
    m.exposure_ms = k == p->motion.first_layer && p->exposure_left && !p->in_place ? p->exposure_left
                                                                                    : p->exposure_ms[k - 1];
    return serial_send(p->l, LINK_MSG_SCREEN, buf, link_put_screen(buf, &m));
}

static int stopped(serial_link *l)
{
    /* READY mid-print is the core's abort: an ABORT or a fault of the
       print (Z stays homed: the error says which) or of the axis, which
       leaves Z unhomed. STATUS's error is the last refusal, so after an
       ABORT it may be this host's SCREEN of the layer it had drawn */
    int homed = (l->st.flags & LINK_FLAG_HOMED) != 0, e = l->st.error;
    int print_fault = e == LINK_ERR_SCREEN_LIT || e == LINK_ERR_MOVE_FAILED || e == LINK_ERR_WRONG_HEIGHT;
    char what[96];
    snprintf(what, sizeof what, "stopped printing (%s)",
             l->st.state != LINK_STATE_READY ? link_state_name(l->st.state)
             : homed && print_fault ? link_error_name(l->st.error)
             : homed ? "aborted"
             : link_error_name(l->st.error));
    return serial_stopped(l, RC_FAIL, what, 1, homed);
}

static int begin(screen_print *p)
{
    serial_link *l = p->l;
    uint8_t buf[LINK_PAYLOAD_MAX];
    int rc;
    /* the screen is dark since it was opened: the printer hears it first
       (a host before this one may have left it believing otherwise) */
    if ((rc = go_dark(p))) return rc;
    if (p->in_place) {
        if ((rc = serial_status(l))) return rc;
        /* none owed: paused before the light, or in the peel after it */
        if (l->st.exposure_left_ms)
            printf("resuming layer %u in place: %u ms of its exposure left, shown on %s\n", p->motion.first_layer,
                   l->st.exposure_left_ms, p->scr->name);
        else
            printf("resuming layer %u in place: its whole exposure (%u ms) to come, shown on %s\n", p->motion.first_layer,
                   p->exposure_ms[p->motion.first_layer - 1], p->scr->name);
        if (l->st.state == LINK_STATE_PAUSED && (rc = serial_send(l, LINK_MSG_RESUME, NULL, 0))) return rc;
    } else {
        if ((rc = serial_send(l, LINK_MSG_PRINT, buf, link_put_print(buf, &p->motion)))) return rc;
        printf("printing layers %u to %u, shown on %s\n", p->motion.first_layer, p->layers, p->scr->name);
    }
    fflush(stdout);
    if ((rc = serial_status(l))) return rc;
    if (l->st.state != LINK_STATE_PRINTING && l->st.state != LINK_STATE_DONE)
        return complain(RC_FAIL, "the printer would not %s layer %u: %s", p->in_place ? "resume" : "start",
                        p->motion.first_layer, serial_why_not(l));
    return RC_OK;
}

static int run(screen_print *p)
{
    serial_link *l = p->l;
    progress bar;
    uint32_t last = 0, tries = 0;
    int rc, failed;
    memset(&bar, 0, sizeof bar);
    if ((rc = begin(p))) return rc;
    for (;;) {
        const link_status *s = &l->st;
        char z[32];
        if (*p->interrupted) return (rc = pause_dark(p)) ? rc : paused(p, "interrupted");
        if ((rc = serial_status(l))) return rc;
        snprintf(z, sizeof z, "z %.3f mm", s->z_nm / 1e6);
        progress_show(&bar, s->state == LINK_STATE_DONE ? p->layers : s->exposed, p->layers, "layers", z);
        if (s->state == LINK_STATE_DONE) return go_dark(p);
        if (s->state == LINK_STATE_PAUSED) {
            if ((rc = go_dark(p))) return rc;
            if (!(s->flags & LINK_FLAG_LINK_LOST)) return paused(p, "the printer paused");
            /* the link came back: the pause was not the operator's */
            if ((rc = serial_send(l, LINK_MSG_RESUME, NULL, 0))) return rc;
            continue;
        }
        if (s->state != LINK_STATE_PRINTING) {
            if ((rc = go_dark(p))) return rc;
            return stopped(l);
        }
        if (s->screen && s->screen == s->layer) tries = 0;
        if (s->phase == LINK_PHASE_DARK) {
            if ((rc = go_dark(p))) return rc;
            continue;
        }
        if (s->phase == LINK_PHASE_WAIT_MASK && !(s->flags & LINK_FLAG_MOVING) && s->screen != s->layer) {
            tries = s->layer == last ? tries + 1 : 1;
            last = s->layer;
            if (tries > 5) {
                (void)screen_dark(p->scr); /* before the message, as every stop */
                return complain(RC_FAIL, "layer %u: the printer did not take it as shown (%s)", s->layer,
                                link_error_name(s->error));
            }
            if ((rc = show_layer(p, s->layer, &failed))) {
                if (!failed) return rc;
                return (rc = pause_dark(p)) ? rc : paused(p, "the layer could not be shown");
            }
            continue;
        }
        if ((rc = serial_pump(l, SCREEN_POLL_MS))) return rc;
    }
}

static void dark_first(void *scr) { (void)screen_dark((screen *)scr); }

int screen_print_run(screen_print *p)
{
    int rc;
    /* a stop the link finds (a restart, silence, the port gone) darkens
       the screen before its message is said */
    p->l->stopping = dark_first;
    p->l->stopping_ctx = p->scr;
    rc = run(p);
    p->l->stopping = NULL;
    /* whatever ended it, dark (the caller's screen_close says so again) */
    (void)screen_dark(p->scr);
    return rc;
}
