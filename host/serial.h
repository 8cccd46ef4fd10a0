/* The host's end of the serial link (link/PROTOCOL.md): a port opened with
   termios, go-back-N frames with resends timed from the round trips, and the
   printer's latest replies. adaslice print drives a printer through it. */
#ifndef ADASLICE_HOST_SERIAL_H
#define ADASLICE_HOST_SERIAL_H
#include <stddef.h>
#include <stdint.h>
#include "../link/frame.h"
#include "../link/messages.h"

#define SERIAL_QUEUE 16

typedef struct serial_link {
    int fd;
    const char *dev;
    link_deframer rx;
    uint8_t next_seq, base;     /* frames base .. next_seq - 1 await their ack */
    int count, window;
    uint8_t frames[SERIAL_QUEUE][LINK_FRAME_MAX];
    size_t lens[SERIAL_QUEUE];
    double rto_ms, last_progress, last_heard, give_up_ms;
    /* the latest replies, each with a count so a caller sees a fresh one */
    link_status st;
    unsigned long status_count, identify_count, plan_count;
    link_identify id;
    uint8_t plan[LINK_FRAME_MAX];
    size_t plan_size;
    unsigned long retransmits, naks, bytes_out, bytes_in;
    /* bulk data frames shrink when frames are lost and grow back when the
       line is clean: a frame's chance to arrive falls with its length */
    size_t data_max;
    unsigned clean;
    uint8_t round;              /* LINK_ROUND_BIT of the frames sent now */
    double srtt, rttvar;        /* request-to-reply times, as TCP keeps them (RFC 6298) */
    /* resets: IDENTIFY's boot id at connect; a reply from another boot is
       not taken (l->st stays what the old boot said last) */
    uint32_t boot_id, new_boot_id;
    /* resend rounds in which the acknowledged number did not advance and
       the printer acknowledged a number outside the frames in flight (as a
       restarted MCU does); the re-HELLOs that followed them without progress */
    unsigned stalled, rehellos;
    int stray;
} serial_link;

/* Resend rounds without progress, the printer answering out of step, after
   which the host says HELLO again to learn whether it restarted. */
#define SERIAL_STALL_ROUNDS 8

/* Opens DEV raw 8N1 at a standard baud rate, says hello until the printer
   answers (IDENTIFY), and sizes the window and timeouts. RC_OK, or a
   complaint made (RC_USAGE for a bad rate). */
int serial_connect(serial_link *l, const char *dev, long baud, double give_up_s);
void serial_close(serial_link *l);
/* Reads what has arrived (waiting up to wait_ms), resends on a timeout; a
   printer silent for give_up_s ends it with a complaint. A reply with
   another boot id, or SERIAL_STALL_ROUNDS resend rounds without progress
   and then an IDENTIFY with another boot id, ends it with RC_RESET and the
   message of serial_restarted; no answer to that HELLO with RC_FAIL. */
int serial_pump(serial_link *l, int wait_ms);
/* Queues a frame, waiting while the printer's window is full. */
int serial_send(serial_link *l, uint8_t type, const uint8_t *payload, size_t size);
/* A fresh STATUS in l->st: asked again if its reply is lost. */
int serial_status(serial_link *l);
/* Asks for STATUS until `done` holds (RC_FAIL after timeout_ms). */
int serial_wait(serial_link *l, int (*done)(const link_status *, const void *), const void *ctx, double timeout_ms);
/* Page `first` of the printer's plan into l->plan: 1 if it came. */
int serial_plan_page(serial_link *l, uint32_t first, int *rc);
#endif
