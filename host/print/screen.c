/* The printer's screen on a Linux framebuffer or a file (screen.h). */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "screen.h"
#include "../options.h"
#include "../report.h"
#include "../../link/frame.h"
#include "../../link/messages.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#ifdef __linux__
#include <sys/ioctl.h>
#include <linux/fb.h>
#endif

static const char *const PACKINGS[] = {"gray", "rgb", "bgr"};
static const char *const MIRRORS[] = {"none", "x", "y"};

/* ------------------------------------------------------------ panels */

/* The figures are those of host/printer.c's presets of the same panels. */
const screen_panel SCREEN_PANELS[] = {
    {"2k-5.5", 2560, 1440, SCREEN_GRAY, 47.25,
     "5.5-inch 2K RGB LCD (Elegoo Mars, Anycubic Photon class): 2560 x 1440 pixels of 47.25 um, 120.96 x 68.04 mm, "
     "a mask pixel per RGB pixel (ChiTu Systems, \"5 things you need to know when choosing LCD screen\", 2020)"},
    {"mono-4k-6.1", 1280, 2400, SCREEN_RGB, 35,
     "6.1-inch 4K mono LCD (Anycubic Photon Mono 4K class): 3840 x 2400 mono pixels of 35 um, driven as a 1280 x 2400 "
     "RGB panel, three mask pixels per framebuffer pixel (xyzdims.com, \"MSLA Anycubic Photon Mono 4K\", 2023); red "
     "first is assumed: check the order with adaslice show --pattern ruler"},
};
const int SCREEN_PANEL_COUNT = (int)(sizeof SCREEN_PANELS / sizeof SCREEN_PANELS[0]);

static const screen_panel *panel_find(const char *name)
{
    int k;
    for (k = 0; k < SCREEN_PANEL_COUNT; k++)
        if (!strcmp(SCREEN_PANELS[k].name, name)) return &SCREEN_PANELS[k];
    return NULL;
}

/* ------------------------------------------------------------ options */

int screen_option(int argc, char **argv, int *i, screen_options *o, int *rc)
{
    const char *opt = argv[*i];
    if (!strcmp(opt, "--screen")) *rc = file_option(argc, argv, i, &o->device);
    else if (!strcmp(opt, "--screen-packing")) *rc = name_option(argc, argv, i, PACKINGS, 3, "gray, rgb or bgr", &o->packing);
    else if (!strcmp(opt, "--screen-mirror")) *rc = name_option(argc, argv, i, MIRRORS, 3, "none, x or y", &o->mirror);
    else if (!strcmp(opt, "--screen-pitch")) {
        /* a panel's pixels are tens of micrometres, a projector's a few hundred */
        if (!(*rc = number_option(argc, argv, i, 0, &o->pitch_um)) && (o->pitch_um < 1 || o->pitch_um > 10000))
            *rc = complain(RC_USAGE, "--screen-pitch %g: a pixel pitch in micrometres, from 1 to 10000", o->pitch_um);
    }
    else if (!strcmp(opt, "--screen-panel")) {
        if (!(*rc = file_option(argc, argv, i, &o->panel)) && !panel_find(o->panel)) {
            char names[256] = "";
            int k;
            for (k = 0; k < SCREEN_PANEL_COUNT; k++)
                snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s", k ? ", " : "", SCREEN_PANELS[k].name);
            *rc = complain(RC_USAGE, "--screen-panel %s: not a panel adaslice knows (%s)", o->panel, names);
        }
    }
    else if (!strcmp(opt, "--screen-rotate")) {
        static const char *const turns[] = {"0", "90", "180", "270"};
        *rc = name_option(argc, argv, i, turns, 4, "0, 90, 180 or 270", &o->rotate);
    } else return 0;
    return 1;
}

void screen_usage(FILE *f)
{
    fputs("the host's screen (a DIY printer: the masking LCD on this Linux board)\n"
          "  --screen DEV          show each layer on framebuffer DEV (/dev/fb0); the\n"
          "                        printer's MCU lights the UV only once it is shown.\n"
          "                        file:PATH,WxH,BPP[,packing]: a file laid out as a\n"
          "                        W x H framebuffer of BPP 16|24|32 (tests)\n"
          "  --screen-packing P    gray: a mask pixel per screen pixel; rgb|bgr: three\n"
          "                        (a mono 4K+ panel: one per subpixel)        [gray]\n"
          "  --screen-rotate D     the panel turned 0|90|180|270 degrees clockwise [0]\n"
          "  --screen-mirror M     none|x|y, before the turn                    [none]\n"
          "  --screen-pitch UM     the panel's pixel pitch: a job of another is\n"
          "                        refused                                   [unchecked]\n"
          "  --screen-panel NAME   a panel's framebuffer, packing and pitch:\n",
          f);
    {
        int k;
        for (k = 0; k < SCREEN_PANEL_COUNT; k++)
            fprintf(f, "                          %-12s a %u x %u framebuffer, %s, %g um\n", SCREEN_PANELS[k].name,
                    SCREEN_PANELS[k].fb_width, SCREEN_PANELS[k].fb_height, PACKINGS[SCREEN_PANELS[k].packing],
                    SCREEN_PANELS[k].pitch_um);
    }
}

/* ------------------------------------------------------------ geometry */

static int mask_pixel(const unsigned char *mask, size_t stride, int bits, uint32_t x, uint32_t y)
{
    const unsigned char *row = mask + (size_t)y * stride;
    return bits == 8 ? row[x] : ((row[x >> 3] >> (7u - (x & 7u))) & 1u) * 255;
}

void screen_panel_row(const screen *s, const unsigned char *mask, size_t stride, int bits, uint32_t w, uint32_t h,
                      uint32_t py, unsigned char *values)
{
    long x, y, dx, dy;
    uint32_t px;
    /* the mask's pixel under panel pixel (0, py), and the step to (1, py):
       the turn undone, then the mirror */
    switch (s->rotate) {
    case 1: x = py; y = (long)h - 1; dx = 0; dy = -1; break;
    case 2: x = (long)w - 1; y = (long)h - 1 - py; dx = -1; dy = 0; break;
    case 3: x = (long)w - 1 - py; y = 0; dx = 0; dy = 1; break;
    default: x = 0; y = py; dx = 1; dy = 0; break;
    }
    if (s->mirror == SCREEN_MIRROR_X) { x = (long)w - 1 - x; dx = -dx; }
    if (s->mirror == SCREEN_MIRROR_Y) { y = (long)h - 1 - y; dy = -dy; }
    if (dy == 0 && bits == 8) {
        const unsigned char *row = mask + (size_t)y * stride + x;
        for (px = 0; px < s->panel_w; px++, row += dx) values[px] = *row;
    } else if (dy == 0 && dx == 1 && !(x & 7)) {
        /* the common case, a row as it is: whole bytes at a time */
        static unsigned char expand[256][8];
        const unsigned char *row = mask + (size_t)y * stride;
        if (!expand[255][0]) {
            unsigned b, k;
            for (b = 0; b < 256; b++)
                for (k = 0; k < 8; k++) expand[b][k] = (unsigned char)(((b >> (7u - k)) & 1u) * 255u);
        }
        for (px = 0; px + 8 <= s->panel_w; px += 8) memcpy(values + px, expand[row[px >> 3]], 8);
        for (; px < s->panel_w; px++) values[px] = (unsigned char)mask_pixel(mask, stride, bits, px, (uint32_t)y);
    } else {
        for (px = 0; px < s->panel_w; px++, x += dx, y += dy)
            values[px] = (unsigned char)mask_pixel(mask, stride, bits, (uint32_t)x, (uint32_t)y);
    }
}

/* Pixels out in the framebuffer's depth, one loop per depth (this is the
   print's critical path: a 4K layer is 9 million mask pixels). */
#define SCREEN_PUT_LOOP(count, PIXEL)                                                                               \
    do {                                                                                                            \
        uint32_t x_, v_;                                                                                            \
        if (s->bpp == 32)                                                                                           \
            for (x_ = 0; x_ < (count); x_++, out += 4) { v_ = PIXEL(x_); memcpy(out, &v_, 4); }                     \
        else if (s->bpp == 24)                                                                                      \
            for (x_ = 0; x_ < (count); x_++, out += 3) {                                                            \
                v_ = PIXEL(x_);                                                                                     \
                out[0] = (unsigned char)v_; out[1] = (unsigned char)(v_ >> 8); out[2] = (unsigned char)(v_ >> 16);   \
            }                                                                                                       \
        else                                                                                                        \
            for (x_ = 0; x_ < (count); x_++, out += 2) { uint16_t h_ = (uint16_t)PIXEL(x_); memcpy(out, &h_, 2); } \
    } while (0)

void screen_pack_row(const screen *s, const unsigned char *values, unsigned char *out)
{
    const uint32_t *r = s->lut[0], *g = s->lut[1], *b = s->lut[2];
    if (s->packing == SCREEN_GRAY) {
#define GRAY_PIXEL(x) (r[values[x]] | g[values[x]] | b[values[x]])
        SCREEN_PUT_LOOP(s->xres, GRAY_PIXEL);
#undef GRAY_PIXEL
    } else {
        /* three mono pixels a screen pixel, the first in the red subpixel (rgb) or the blue (bgr) */
        const uint32_t *first = s->packing == SCREEN_RGB ? r : b, *third = s->packing == SCREEN_RGB ? b : r;
#define RGB_PIXEL(x) (first[values[3 * (x)]] | g[values[3 * (x) + 1]] | third[values[3 * (x) + 2]])
        SCREEN_PUT_LOOP(s->xres, RGB_PIXEL);
#undef RGB_PIXEL
    }
}

static void set_format(screen *s, const uint8_t offset[3], const uint8_t length[3])
{
    int c, v;
    for (c = 0; c < 3; c++) {
        s->offset[c] = offset[c];
        s->length[c] = length[c];
        for (v = 0; v < 256; v++)
            s->lut[c][v] = length[c] ? ((uint32_t)v >> (8 - (length[c] > 8 ? 8 : length[c]))) << offset[c] : 0;
    }
}

/* ------------------------------------------------------------ open */

static void wait_us(uint32_t us)
{
    struct timespec t;
    t.tv_sec = (time_t)(us / 1000000u);
    t.tv_nsec = (long)(us % 1000000u) * 1000L;
    while (nanosleep(&t, &t) != 0 && errno == EINTR) {}
}

/* file:PATH,WxH,BPP[,packing] */
static int open_file(screen *s, const char *spec, int *packing)
{
    char path[256];
    unsigned long long w = 0, h = 0, bpp = 0;
    char pack[8] = "";
    int fields = 0, k;
    const char *at;
    struct stat st;
    static const uint8_t off32[3] = {16, 8, 0}, len32[3] = {8, 8, 8}, off16[3] = {11, 5, 0}, len16[3] = {5, 6, 5};
    const char *first = strchr(spec, ',');
    if (!first || (size_t)(first - spec) >= sizeof path)
        return complain(RC_USAGE, "--screen %s: expected file:PATH,WxH,BPP[,gray|rgb|bgr]", spec);
    memcpy(path, spec, (size_t)(first - spec));
    path[first - spec] = 0;
    at = first + 1;
    if ((at = whole_number(at, &w)) && *at++ == 'x' && (at = whole_number(at, &h)) && *at++ == ',' &&
        (at = whole_number(at, &bpp))) {
        fields = 3;
        if (*at == ',' && strlen(at + 1) < sizeof pack) {
            strcpy(pack, at + 1);
            fields = 4;
        } else if (*at) {
            fields = 0; /* trailing junk: "32junk" is not 32 */
        }
    }
    if (fields < 3 || !w || !h || w > 65535 || h > 65535 || (bpp != 16 && bpp != 24 && bpp != 32))
        return complain(RC_USAGE, "--screen file:%s: expected file:PATH,WxH,BPP[,gray|rgb|bgr] with BPP 16, 24 or 32", spec);
    if (fields == 4) {
        for (k = 0; k < 3 && strcmp(pack, PACKINGS[k]); k++) {}
        if (k == 3) return complain(RC_USAGE, "--screen file:%s: packing %s: expected gray, rgb or bgr", spec, pack);
        if (*packing < 0) *packing = k;
    }
    snprintf(s->name, sizeof s->name, "%s", path);
    s->is_file = 1;
    s->xres = (uint32_t)w;
    s->yres = (uint32_t)h;
    s->bpp = (uint32_t)bpp;
    s->line_length = (uint32_t)(w * bpp / 8);
    s->pages = 1;
    if (bpp == 16) set_format(s, off16, len16); else set_format(s, off32, len32);
    s->map_size = (size_t)s->line_length * s->yres;
    if ((s->fd = open(path, O_RDWR | O_CREAT, 0644)) < 0)
        return complain(RC_FAIL, "--screen %s: %s", path, strerror(errno));
    if (fstat(s->fd, &st) != 0 || !S_ISREG(st.st_mode))
        return complain(RC_FAIL, "--screen file:%s: not a regular file (a framebuffer is /dev/fbN, without file:)", path);
    /* a file of another size is not this screen's image (a job's masks.rle
       named by mistake was zeroed and grown): only a new or empty one, or
       one this screen's size, is drawn on */
    if (st.st_size != 0 && (uint64_t)st.st_size != (uint64_t)s->map_size)
        return complain(RC_USAGE, "--screen file:%s: the file holds %lld bytes, not the %zu of a %llux%llu screen at %llu bits: "
                                  "not this screen's image, so it is left alone; give a new file",
                        path, (long long)st.st_size, s->map_size, w, h, bpp);
    if ((size_t)st.st_size < s->map_size && ftruncate(s->fd, (off_t)s->map_size) != 0)
        return complain(RC_FAIL, "--screen %s: cannot make it %zu bytes: %s", path, s->map_size, strerror(errno));
    return RC_OK;
}

#ifdef __linux__
static int open_fb(screen *s, const char *dev)
{
    struct fb_var_screeninfo var;
    struct fb_fix_screeninfo fix;
    uint8_t offset[3], length[3];
    snprintf(s->name, sizeof s->name, "%s", dev);
    if ((s->fd = open(dev, O_RDWR)) < 0) return complain(RC_FAIL, "--screen %s: %s", dev, strerror(errno));
    if (ioctl(s->fd, FBIOGET_VSCREENINFO, &var) != 0 || ioctl(s->fd, FBIOGET_FSCREENINFO, &fix) != 0)
        return complain(RC_FAIL, "--screen %s: not a framebuffer (%s); give /dev/fbN or file:PATH,WxH,BPP", dev, strerror(errno));
    if (var.bits_per_pixel != 16 && var.bits_per_pixel != 24 && var.bits_per_pixel != 32)
        return complain(RC_FAIL, "--screen %s: %u bits per pixel; adaslice draws 16, 24 or 32 (set the mode with fbset "
                                 "or the board's HDMI settings)", dev, var.bits_per_pixel);
    if (fix.type != FB_TYPE_PACKED_PIXELS || fix.visual != FB_VISUAL_TRUECOLOR)
        return complain(RC_FAIL, "--screen %s: not a true-colour packed-pixel framebuffer", dev);
    s->xres = var.xres;
    s->yres = var.yres;
    s->bpp = var.bits_per_pixel;
    s->line_length = fix.line_length;
    offset[0] = (uint8_t)var.red.offset; length[0] = (uint8_t)var.red.length;
    offset[1] = (uint8_t)var.green.offset; length[1] = (uint8_t)var.green.length;
    offset[2] = (uint8_t)var.blue.offset; length[2] = (uint8_t)var.blue.length;
    set_format(s, offset, length);
    s->pages = var.yres_virtual >= 2 * var.yres && fix.ypanstep <= var.yres ? 2 : 1;
    s->map_size = (size_t)fix.line_length * var.yres * s->pages;
    if (s->map_size > fix.smem_len) { s->pages = 1; s->map_size = (size_t)fix.line_length * var.yres; }
    if (var.pixclock) {
        double frame_ps = (double)var.pixclock * (var.xres + var.left_margin + var.right_margin + var.hsync_len) *
                          (var.yres + var.upper_margin + var.lower_margin + var.vsync_len);
        s->frame_us = (uint32_t)(frame_ps / 1e6) + 1;
    } else {
        s->frame_us = 50000; /* unknown: as slow as 20 Hz */
    }
    {
        uint32_t crtc = 0;
        s->vsync = ioctl(s->fd, FBIO_WAITFORVSYNC, &crtc) == 0;
    }
    /* var.width, the driver's millimetres, is rounded or 0: the pitch is
       checked only when --screen-pitch or --screen-panel gives it */
    return RC_OK;
}

/* Page `page` on screen. */
static int pan_to(screen *s, uint32_t page)
{
    struct fb_var_screeninfo var;
    if (s->is_file || s->pages < 2) return RC_OK;
    if (ioctl(s->fd, FBIOGET_VSCREENINFO, &var) != 0) return complain(RC_FAIL, "--screen %s: %s", s->name, strerror(errno));
    var.xoffset = 0;
    var.yoffset = page * s->yres;
    if (ioctl(s->fd, FBIOPAN_DISPLAY, &var) != 0) {
        /* no panning after all: one page, drawn over the dark one */
        s->pages = 1;
        return RC_OK;
    }
    s->shown = page;
    return RC_OK;
}

/* Until the panel shows what the framebuffer holds: the refresh under way
   when the drawing ended, then a whole one. */
static void wait_shown(screen *s)
{
    uint32_t crtc = 0;
    if (s->is_file) return;
    if (s->vsync && ioctl(s->fd, FBIO_WAITFORVSYNC, &crtc) == 0 && ioctl(s->fd, FBIO_WAITFORVSYNC, &crtc) == 0) return;
    wait_us(2 * s->frame_us);
}
#else
static int open_fb(screen *s, const char *dev)
{
    (void)s;
    return complain(RC_USAGE, "--screen %s: framebuffers are Linux's; give file:PATH,WxH,BPP", dev);
}
static int pan_to(screen *s, uint32_t page) { (void)s; (void)page; return RC_OK; }
static void wait_shown(screen *s) { (void)s; }
#endif

static unsigned char *page_at(const screen *s, uint32_t page) { return s->map + (size_t)page * s->line_length * s->yres; }

int screen_open(screen *s, const screen_options *o)
{
    int rc, packing = o->packing;
    memset(s, 0, sizeof *s);
    s->fd = s->guard_fd = -1;
    s->pitch_um = o->pitch_um;
    rc = !strncmp(o->device, "file:", 5) ? open_file(s, o->device + 5, &packing) : open_fb(s, o->device);
    if (rc) { screen_close(s); return rc; }
    if (o->panel) {
        const screen_panel *p = panel_find(o->panel);
        if (p && (s->xres != p->fb_width || s->yres != p->fb_height)) {
            rc = complain(RC_FAIL, "--screen %s is %u x %u px; the %s panel's framebuffer is %u x %u", s->name, s->xres, s->yres,
                          p->name, p->fb_width, p->fb_height);
            screen_close(s);
            return rc;
        }
        if (p && packing < 0) packing = p->packing;
        if (p && !s->pitch_um) s->pitch_um = p->pitch_um;
    }
    s->packing = packing < 0 ? SCREEN_GRAY : packing;
    s->rotate = o->rotate;
    s->mirror = o->mirror;
    s->panel_w = s->xres * (s->packing == SCREEN_GRAY ? 1u : 3u);
    s->panel_h = s->yres;
    if ((size_t)s->xres * (s->bpp / 8) > s->line_length) {
        rc = complain(RC_FAIL, "--screen %s: rows of %u bytes hold no %u pixels of %u bits", s->name, s->line_length,
                      s->xres, s->bpp);
        screen_close(s);
        return rc;
    }
    s->map = (unsigned char *)mmap(NULL, s->map_size, PROT_READ | PROT_WRITE, MAP_SHARED, s->fd, 0);
    if (s->map == MAP_FAILED) {
        s->map = NULL;
        rc = complain(RC_FAIL, "--screen %s: cannot map %zu bytes: %s", s->name, s->map_size, strerror(errno));
        screen_close(s);
        return rc;
    }
    if (!(s->values = (unsigned char *)malloc(s->panel_w + 8))) {
        screen_close(s);
        return complain(RC_FAIL, "out of memory for a screen row");
    }
    memset(s->map, 0, s->map_size);
    if ((rc = pan_to(s, 0))) { screen_close(s); return rc; }
    wait_shown(s);
    return RC_OK;
}

int screen_fits(const screen *s, uint32_t w, uint32_t h, uint32_t pitch_nm)
{
    uint32_t pw = (s->rotate & 1) ? h : w, ph = (s->rotate & 1) ? w : h;
    if (pw != s->panel_w || ph != s->panel_h)
        return complain(RC_FAIL, "the job's masks are %u x %u px; the screen %s shows %u x %u px (%u x %u at %u bpp, %s%s)",
                        w, h, s->name, (s->rotate & 1) ? s->panel_h : s->panel_w, (s->rotate & 1) ? s->panel_w : s->panel_h,
                        s->xres, s->yres, s->bpp, PACKINGS[s->packing], (s->rotate & 1) ? ", turned a quarter" : "");
    if (pitch_nm && s->pitch_um > 0 && fabs(pitch_nm / 1000.0 - s->pitch_um) > 1e-3 * s->pitch_um)
        return complain(RC_FAIL, "the job's pixels are %g um; the screen %s's are %g um (--screen-pitch)", pitch_nm / 1000.0,
                        s->name, s->pitch_um);
    return RC_OK;
}

int screen_fits_job(const screen *s, const char *dir, const double pitch_mm[2])
{
    double x = pitch_mm[0] * 1000, y = pitch_mm[1] * 1000;
    if (s->pitch_um > 0 && (fabs(x - s->pitch_um) > 1e-3 * s->pitch_um || fabs(y - s->pitch_um) > 1e-3 * s->pitch_um))
        return complain(RC_FAIL, "%s's pixels are %g x %g um; the screen %s's are %g um", dir, x, y, s->name, s->pitch_um);
    return RC_OK;
}

static void draw(const screen *s, unsigned char *page, const unsigned char *mask, size_t stride, uint32_t w, uint32_t h,
                 int bits)
{
    uint32_t y;
    for (y = 0; y < s->panel_h; y++) {
        screen_panel_row(s, mask, stride, bits, w, h, y, s->values);
        screen_pack_row(s, s->values, page + (size_t)y * s->line_length);
    }
}

int screen_show(screen *s, const unsigned char *mask, size_t stride, uint32_t w, uint32_t h, int bits)
{
    int rc;
    if ((rc = screen_fits(s, w, h, 0))) return rc;
    if (s->pages > 1) {
        uint32_t back = s->shown ^ 1u;
        draw(s, page_at(s, back), mask, stride, w, h, bits);
        if ((rc = pan_to(s, back))) return rc;
        if (s->pages > 1) { /* the page before, dark for the next */
            memset(page_at(s, back ^ 1u), 0, (size_t)s->line_length * s->yres);
            wait_shown(s);
            return RC_OK;
        }
    }
    /* one page: it is dark (the print keeps it so between layers); the
       light waits for the drawing's end */
    draw(s, page_at(s, s->shown), mask, stride, w, h, bits);
    wait_shown(s);
    return RC_OK;
}

int screen_dark(screen *s)
{
    int rc = RC_OK;
    if (!s->map) return RC_OK;
    if (s->pages > 1) {
        uint32_t was = s->shown;
        /* the hidden page is dark: show it, then darken the other */
        rc = pan_to(s, was ^ 1u);
        memset(page_at(s, was), 0, (size_t)s->line_length * s->yres);
    }
    memset(page_at(s, s->shown), 0, (size_t)s->line_length * s->yres);
    wait_shown(s);
    return rc;
}

/* ------------------------------------------------------------ the guard */

/* The guard's writes give up at `until` (now_ms's clock): a printer that
   reads nothing (hung, its USB buffers full) must not keep the screen lit. */
static void write_until(int fd, const uint8_t *p, size_t n, double until)
{
    while (n && now_ms() < until) {
        ssize_t k = write(fd, p, n);
        if (k > 0) { p += k; n -= (size_t)k; }
        else if (k < 0 && (errno == EINTR || errno == EAGAIN)) wait_us(1000);
        else return;
    }
}

/* How long the guard waits for the printer to say its light is out before
   it darkens the screen all the same (a printer that answers nothing). */
#define GUARD_WAIT_MS 60

/* After PAUSE, a STATUS (SEQ 0x57): until its reply comes (its
   acknowledgement 0x58), the light is out, or `until` passes. */
static void guard_wait_reply(int port_fd, double until)
{
    link_deframer rx;
    link_deframer_init(&rx, link_mcu_to_host_type);
    for (;;) {
        uint8_t b[256];
        ssize_t n, k;
        double left = until - now_ms();
        struct pollfd p;
        if (left <= 0) return;
        p.fd = port_fd;
        p.events = POLLIN;
        p.revents = 0;
        if (poll(&p, 1, (int)left + 1) <= 0) continue;
        if ((n = read(port_fd, b, sizeof b)) <= 0) {
            if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
            return;
        }
        for (k = 0; k < n; k++) {
            size_t m;
            link_deframe_push(&rx, b[k]);
            while ((m = link_deframe_next(&rx)) != 0) {
                int answered = rx.buf[2] == LINK_MSG_STATUS_REPLY && rx.buf[1] == 0x58;
                link_deframe_consume(&rx);
                if (answered) return;
            }
        }
    }
}

/* The host is gone: the light out through the printer, then the screen.
   The printer's word that the light is out is waited for (so that the
   exposure's rest it keeps is what the screen showed), but no longer than
   GUARD_WAIT_MS, and nothing else waits on the printer: the frames get
   20 ms to leave (not tcdrain, which waits for ever on a line that does
   not move). Then page 0 dark and shown before the rest of the mapping. */
static void guard_stop(screen *s, int port_fd)
{
    size_t page = (size_t)s->line_length * s->yres;
    if (port_fd >= 0) {
        uint8_t out[4 * LINK_FRAME_MAX], hello = LINK_PROTOCOL_VERSION;
        size_t n = 0;
        double start = now_ms();
        /* twice: a frame the host was cut off in the middle of may take
           the first (the deframer finds frames again after damage) */
        n += link_frame_build(out + n, 0x55, LINK_MSG_HELLO, &hello, 1);
        n += link_frame_build(out + n, 0x55, LINK_MSG_HELLO, &hello, 1);
        n += link_frame_build(out + n, 0x56, LINK_MSG_PAUSE, NULL, 0);
        n += link_frame_build(out + n, 0x57, LINK_MSG_STATUS, NULL, 0);
        write_until(port_fd, out, n, start + 20);
        guard_wait_reply(port_fd, start + GUARD_WAIT_MS);
    }
    /* the guard's copy of `shown` is as old as the fork: page 0 is made
       the dark one shown */
    s->shown = 0;
    memset(s->map, 0, page);
    (void)pan_to(s, 0);
    if (s->map_size > page) memset(s->map + page, 0, s->map_size - page);
    wait_shown(s);
    if (port_fd >= 0) {
        /* and the printer told, so that it knows the screen as it is */
        uint8_t out[LINK_FRAME_MAX], dark[LINK_SIZE_SCREEN];
        link_screen m;
        m.layer = 0;
        m.exposure_ms = 0;
        (void)link_put_screen(dark, &m);
        write_until(port_fd, out, link_frame_build(out, 0x58, LINK_MSG_SCREEN, dark, sizeof dark), now_ms() + 1000);
    }
}

int screen_guard(screen *s, int port_fd)
{
    int fds[2];
    if (pipe(fds) != 0) return complain(RC_FAIL, "--screen %s: no pipe for its guard: %s", s->name, strerror(errno));
    {
        /* a stop (the printer's reset, Ctrl-C, this host's death) must put
           the screen out within 100 ms on a busy board as on an idle one:
           this host, which finds the reset from its STATUS round trips, and
           the guard it forks (which inherits this) run at the lowest
           real-time priority, ahead of every ordinary task; both block
           between layers, so they take little from the others */
        struct sched_param p;
        memset(&p, 0, sizeof p);
        p.sched_priority = sched_get_priority_min(SCHED_FIFO);
        if (sched_getscheduler(0) != SCHED_FIFO && sched_setscheduler(0, SCHED_FIFO, &p) != 0)
            warn("--screen %s: this host and its guard may not run at real-time priority "
                 "(%s): on a busy machine the screen goes dark later after a stop (the printer's reset, "
                 "this host's death); run as root or give adaslice CAP_SYS_NICE (setcap cap_sys_nice+ep "
                 "adaslice)", s->name, strerror(errno));
    }
    fflush(NULL);
    s->guard = fork();
    if (s->guard < 0) {
        close(fds[0]);
        close(fds[1]);
        s->guard = 0;
        return complain(RC_FAIL, "--screen %s: no guard process: %s", s->name, strerror(errno));
    }
    if (s->guard == 0) {
        char c = 0;
        ssize_t n;
        int null = open("/dev/null", O_RDWR);
        /* the terminal's signals are the host's: the guard outlives it */
        signal(SIGINT, SIG_IGN);
        signal(SIGTERM, SIG_IGN);
        signal(SIGHUP, SIG_IGN);
        signal(SIGQUIT, SIG_IGN);
        signal(SIGPIPE, SIG_IGN);
        if (null >= 0) { dup2(null, 0); dup2(null, 1); close(null); }
        close(fds[1]);
        do n = read(fds[0], &c, 1); while (n < 0 && errno == EINTR);
        if (n != 1 || c != 'q') guard_stop(s, port_fd);
        _exit(0);
    }
    close(fds[0]);
    s->guard_fd = fds[1];
    return RC_OK;
}

void screen_close(screen *s)
{
    if (s->map) (void)screen_dark(s);
    if (s->guard_fd >= 0) {
        write_until(s->guard_fd, (const uint8_t *)"q", 1, now_ms() + 1000);
        close(s->guard_fd);
        (void)waitpid(s->guard, NULL, 0);
    }
    if (s->map) munmap(s->map, s->map_size);
    if (s->fd >= 0) close(s->fd);
    free(s->values);
    memset(s, 0, sizeof *s);
    s->fd = s->guard_fd = -1;
}
