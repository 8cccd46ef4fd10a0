/* adaslice print --screen: a print whose masks the host shows on its own
   screen (screen.h) while the printer's MCU moves Z and switches the UV
   (link/PROTOCOL.md, "The host's screen"). No mask crosses the line: the
   host draws layer k when the MCU waits for it with Z still, says SCREEN k
   once it is on screen, and darkens the screen (SCREEN 0) when the MCU has
   exposed it, before the peel, and whenever the print pauses or stops. */
#ifndef ADASLICE_HOST_PRINT_SCREEN_PRINT_H
#define ADASLICE_HOST_PRINT_SCREEN_PRINT_H
#include <signal.h>
#include "screen.h"
#include "serial.h"

/* Layer k's (1-based) mask into *image (rows of *stride bytes, top first),
   valid until the next call; RC_OK or a complaint made. */
typedef int (*screen_mask_fn)(void *ctx, uint32_t k, const unsigned char **image, size_t *stride);

typedef struct screen_print {
    serial_link *l;
    screen *scr;
    uint32_t layers, width, height, bits;
    const uint32_t *exposure_ms;     /* per layer */
    uint32_t exposure_left;          /* the first layer's light when a stop cut it short (0: all) */
    int in_place;                    /* the printer holds this job, paused: RESUME, not PRINT */
    link_print motion;               /* PRINT's fields, first_layer and job set */
    screen_mask_fn mask;
    void *ctx;
    volatile sig_atomic_t *interrupted; /* Ctrl-C: pause */
} screen_print;

/* SCREEN 0 to the printer: the host's screen is dark (as screen_open
   leaves it), so that Z may home and move before the print begins. */
int screen_print_said_dark(serial_link *l);
/* The print from motion.first_layer to the end: RC_OK, RC_PAUSED (paused,
   said with the layer to resume from), or the stop's code and message.
   The screen is dark whenever this returns. */
int screen_print_run(screen_print *p);
#endif
