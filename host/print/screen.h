/* The printer's screen when the host drives it: a DIY resin printer's
   masking LCD on a Linux framebuffer (/dev/fbN, fbdev), or a regular file
   laid out as one (tests, and looking at what a panel would show). The same
   drawing code writes both; a file only skips the ioctls.

   The panel's geometry, as the HDMI driver board shows it:
   - packing gray: one mask pixel per framebuffer pixel, R = G = B;
   - packing rgb (bgr): mono panels of 4K and more are driven as RGB panels
     with one mono pixel per subpixel, three mask pixels per framebuffer
     pixel, the leftmost in the red (blue) subpixel: a 3840 x 2400 panel is
     a 1280 x 2400 framebuffer at 24 bpp;
   - rotate (quarter turns clockwise) and mirror (x: left-right, y: top-
     bottom, in the mask's own axes, before the turn): how the panel sits.
   A mask's pixel (x, y), rows top first as the job holds them, lands on the
   panel where the mirror and then the turn put it; nothing is scaled, so a
   job must have the panel's pixels (and pitch, when it is known).

   1-bit masks show as 0 / 255, 8-bit (anti-aliased) ones as their grey
   levels. The screen is dark when every byte of the visible page is 0. */
#ifndef ADASLICE_HOST_PRINT_SCREEN_H
#define ADASLICE_HOST_PRINT_SCREEN_H
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <sys/types.h>

enum { SCREEN_GRAY, SCREEN_RGB, SCREEN_BGR };
enum { SCREEN_MIRROR_NONE, SCREEN_MIRROR_X, SCREEN_MIRROR_Y };

typedef struct screen_options {
    const char *device;      /* --screen: /dev/fbN, or file:PATH,WxH,BPP[,packing]; NULL none */
    int packing;             /* --screen-packing: SCREEN_*, -1 the file spec's (gray) */
    int rotate;              /* --screen-rotate 0|90|180|270, in quarter turns */
    int mirror;              /* --screen-mirror none|x|y */
    double pitch_um;         /* --screen-pitch: the panel's pixel pitch, 0 unknown */
    const char *panel;       /* --screen-panel: a preset (SCREEN_PANELS), NULL none */
} screen_options;

/* DIY panels: the framebuffer their HDMI driver board shows, the packing
   and the pitch (--screen-panel NAME; --screen-packing and --screen-pitch
   still win). */
typedef struct screen_panel {
    const char *name;
    uint32_t fb_width, fb_height;
    int packing;
    double pitch_um;
    const char *about;       /* the panel, and where its figures come from */
} screen_panel;
extern const screen_panel SCREEN_PANELS[];
extern const int SCREEN_PANEL_COUNT;

typedef struct screen {
    int fd, is_file;
    char name[256];                  /* the device or the file, for messages */
    unsigned char *map;
    size_t map_size;
    uint32_t xres, yres, bpp;        /* one page of framebuffer pixels */
    uint32_t line_length;            /* bytes from a row to the next, the driver's */
    uint32_t pages, shown;           /* pages of yres rows (page flipping), the one shown */
    uint32_t frame_us;               /* a refresh, to wait for when there is no vsync ioctl */
    int vsync;                       /* FBIO_WAITFORVSYNC works */
    uint8_t offset[3], length[3];    /* red, green, blue bitfields of a pixel */
    uint32_t lut[3][256];            /* a value into each bitfield */
    int packing, rotate, mirror;
    uint32_t panel_w, panel_h;       /* the panel's mono pixels */
    double pitch_um;
    unsigned char *values;           /* one panel row of grey values */
    pid_t guard;                     /* the guard process (screen_guard), 0 none */
    int guard_fd;                    /* the pipe it watches, -1 none */
} screen;

/* argv[*i] if it is one of the --screen options: *rc set (RC_OK or a
   complaint made), *i past its value, 1 returned; else 0. */
int screen_option(int argc, char **argv, int *i, screen_options *o, int *rc);
/* The options' help lines. */
void screen_usage(FILE *f);
/* Opens, maps and darkens the screen. RC_OK, or a complaint that names the
   device and what it lacks (RC_USAGE for a bad spec). */
int screen_open(screen *s, const screen_options *o);
/* A job of w x h mask pixels at pitch_nm (0 unknown) fits the panel as it
   sits, or a complaint naming both. */
int screen_fits(const screen *s, uint32_t w, uint32_t h, uint32_t pitch_nm);
/* A job directory's pixel pitch (its manifest.json's "pitch_mm", as
   jobdir_read_masks reads it) is the panel's, when the panel's is known;
   else a complaint naming both. */
int screen_fits_job(const screen *s, const char *dir, const double pitch_mm[2]);
/* Draws the mask (rows top first, `stride` bytes apart, 1 or 8 bits) whole
   and waits until the panel shows it: a page flip where the framebuffer
   has a second page, else drawn over the dark page. RC_OK or a complaint. */
int screen_show(screen *s, const unsigned char *mask, size_t stride, uint32_t w, uint32_t h, int bits);
/* Every byte of the visible page 0, and shown so. */
int screen_dark(screen *s);
/* Starts the guard: a process that holds the mapping and waits on a pipe
   from this one; if the pipe closes without screen_close's word (the host
   killed), it sends HELLO and PAUSE on port_fd (-1: none; UV off, the
   exposure's rest kept) and then darkens the screen. RC_OK or a complaint. */
int screen_guard(screen *s, int port_fd);
/* Dark, the guard dismissed, unmapped. */
void screen_close(screen *s);

/* One panel row of grey values (panel_w) into a framebuffer row (xres
   pixels of bpp): the packing. */
void screen_pack_row(const screen *s, const unsigned char *values, unsigned char *out);
/* Panel row py of the mask as it sits (rotate, mirror) into values. */
void screen_panel_row(const screen *s, const unsigned char *mask, size_t stride, int bits, uint32_t w, uint32_t h,
                      uint32_t py, unsigned char *values);
#endif
