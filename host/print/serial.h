/* The host's end of the serial link (link/PROTOCOL.md): a port opened with
   termios, go-back-N frames with resends timed from the round trips, and the
   printer's latest replies. adaslice print drives a printer through it. */
#ifndef ADASLICE_HOST_SERIAL_H
#define ADASLICE_HOST_SERIAL_H
#include <stddef.h>
#include <stdint.h>
#include "../../link/frame.h"
#include "../../link/messages.h"

#define SERIAL_QUEUE 16

typedef struct serial_link {
    int fd;
    const char *dev;
    link_deframer rx;
    uint8_t next_seq, base;     /* frames base .. next_seq - 1 await their ack */
    int count, window;
    uint8_t frames[SERIAL_QUEUE][LINK_FRAME_MAX];
    size_t lens[SERIAL_QUEUE];
    /* what each frame in flight asks of the printer before it answers (a
       mask frame's rows' CRC, a profile frame's bins), ms at the pace the
       printer's IDENTIFY states (crc_byte_ns, plan_bin_ns): the resend and
       silence timers allow it */
    double work_ms[SERIAL_QUEUE];
    double sent_ms[SERIAL_QUEUE];   /* when each was first sent */
    double rto_ms, last_progress;
    /* A printer that answers nothing for silent_ms while the host waits for
       it (frames in flight) has stopped: the firmware answers every frame
       within a loop pass or a few, bar a mask or profile frame worked
       through over many (work_ms). */
    double silent_ms;
    double waiting_since;       /* the host has waited for a reply since then */
    double last_looked;         /* the host last read or waited on the line */
    double longest_wait;        /* the longest wait for a reply that came, ms */
    const char *task;           /* what the caller is doing before a layer prints
                                   ("planning"), for messages; NULL: the printer's state */
    /* the latest replies, each with a count so a caller sees a fresh one */
    link_status st;
    unsigned long status_count, identify_count, plan_count;
    uint8_t status_ack;         /* the acknowledgement l->st came with */
    /* l->st was made after this (ms): the first sending of the newest
       frame it acknowledges, which the printer had taken before it answered */
    double st_after, acked_sent;
    uint8_t asked_seq;          /* serial_ask_status's last request */
    int ending;                 /* EXIT sent: the port may go with the emulator */
    int gone;                   /* the port went away (RC_LOST said, unless ending) */
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
    /* the printer acknowledged a number outside the frames in flight (as a
       restarted MCU does); the re-HELLOs that followed such without progress */
    int stray;
    unsigned rehellos;
    int failed;                 /* a resend in a reply's handling failed (and said so): its code */
    /* called before serial_stopped says a stop, NULL none: a host that shows
       the layers puts its screen out first, not after the message */
    void (*stopping)(void *ctx);
    void *stopping_ctx;
} serial_link;

/* A gap longer than this, ms, between two looks at the line (serial_pump,
   a write waiting for room) is the host's own absence, not time it waited
   for the printer. */
#define SERIAL_AWAY_MS 1000

/* Opens DEV raw 8N1 at a standard baud rate, says hello until the printer
   answers (IDENTIFY), and sizes the window and timeouts: a printer that
   answers nothing for give_up_s, plus the time a window of frames takes on
   the line both ways, has stopped. RC_OK, or a complaint made (RC_USAGE for
   a bad rate). */
int serial_connect(serial_link *l, const char *dev, long baud, double give_up_s);
void serial_close(serial_link *l);
/* Reads what has arrived (waiting up to wait_ms), resends on a timeout. A
   printer that answers nothing for silent_ms (see above) while
   frames wait, or a line that takes no byte that long, ends it with
   RC_LOST; a reply with another boot id, or an acknowledgement out of step
   and then an IDENTIFY with another boot id, with RC_RESET; no answer to
   that HELLO with RC_LOST; a port that goes away (an error reading or
   writing it: EIO, ENODEV, a hangup) with RC_LOST. Each complaint is one
   line made by serial_stopped. */
int serial_pump(serial_link *l, int wait_ms);
/* The one line for a print the printer ended or lost (rc returned): `what`
   happened ("restarted (boot id 1 -> 2)"); at_layer: l->st's layer and
   the last fully exposed are where the print stands, and it continues at
   the layer after that one; z_kept: Z is still homed, so no --home. A
   layer cut short mid-exposure (l->st lit, or paused with light owed) is
   named with the light l->st said it owes (--exposure-left), and how much
   less it may owe: the time since l->st was made (st_after), had the
   light stayed on that long. */
int serial_stopped(const serial_link *l, int rc, const char *what, int at_layer, int z_kept);
/* Queues a frame, waiting while the printer's window is full. */
int serial_send(serial_link *l, uint8_t type, const uint8_t *payload, size_t size);
/* The same for a MASK_DATA frame whose code asks crc_bytes of rows' CRC
   of the printer's decoder (adaslice_rle_decode_rows' budget: a row's
   bytes, a repeated row's ADASLICE_RLE_REPEAT_COST); the printer answers
   it once they are done, and the host allows them IDENTIFY's crc_byte_ns
   each before it resends the frame or takes the printer's silence for a
   stop. */
int serial_send_mask_data(serial_link *l, const uint8_t *code, size_t size, uint32_t crc_bytes);
/* The same for a PROFILE_DATA frame whose code holds `bins` bins (the
   last frame also the whole profile's, whose plan the printer turns
   around before it answers): IDENTIFY's plan_bin_ns each. */
int serial_send_profile_data(serial_link *l, const uint8_t *data, size_t size, uint32_t bins);
/* A fresh STATUS in l->st: asked again if its reply is lost. */
int serial_status(serial_link *l);
/* A STATUS asked for and not waited for, unless the one asked so before
   is still unanswered: its reply lands in l->st as it comes. */
int serial_ask_status(serial_link *l);
/* Asks for STATUS until `done` holds; after timeout_ms, RC_FAIL and "the
   printer did not <what> in N s". */
int serial_wait(serial_link *l, int (*done)(const link_status *, const void *), const void *ctx, double timeout_ms,
                const char *what);
/* Why the printer did not do what was asked, for a message: the last
   command it refused, or, when it refused none, the state it stayed in
   ("it stayed ready, refusing nothing"). */
const char *serial_why_not(const serial_link *l);
/* Page `first` of the printer's plan into l->plan: 1 if it came. */
int serial_plan_page(serial_link *l, uint32_t first, int *rc);
#endif
