/* The host's screen on the print's critical path (between the peel and the
   light): a 3840 x 2400 layer packed and drawn on a 6.1-inch 4K mono panel's
   framebuffer (1280 x 2400 at 24 bpp, three mask pixels per framebuffer
   pixel), the budget 50 ms on one core. The framebuffer is a file in
   /dev/shm (or /tmp) through the same drawing code as /dev/fb0, the
   ioctls skipped; the layer a disc with holes, as a part's section is.
   Also a 1-bit layer turned a quarter, and an 8-bit (anti-aliased) one. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "timing.h"
#include "../host/print/screen.h"
#include <stdio.h>
#include <string.h>
#include <unistd.h>

enum { W = 3840, H = 2400, REPS = 15 };

static void layer(unsigned char *mask, int bits)
{
    size_t stride = bits == 8 ? W : W / 8;
    int x, y;
    memset(mask, 0, stride * H);
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x++) {
            long dx = x - W / 2, dy = y - H / 2, hx = (x % 400) - 200, hy = (y % 400) - 200;
            int lit = dx * dx + dy * dy < 1100L * 1100L && hx * hx + hy * hy > 60L * 60L;
            if (!lit) continue;
            if (bits == 8) mask[(size_t)y * stride + x] = (unsigned char)(128 + (x ^ y) % 128);
            else mask[(size_t)y * stride + x / 8] |= (unsigned char)(0x80u >> (x % 8));
        }
}

static int run(const char *what, const char *dir, int bits, int rotate, int packing)
{
    static unsigned char mask[W * H];
    char spec[300], path[256];
    screen s;
    screen_options o;
    double t[REPS], mid;
    int k, fb_w = packing == SCREEN_GRAY ? (rotate & 1 ? H : W) : (rotate & 1 ? H : W) / 3, fb_h = rotate & 1 ? W : H;
    layer(mask, bits);
    memset(&o, 0, sizeof o);
    snprintf(path, sizeof path, "%s/adaslice-bench-screen-%ld", dir, (long)getpid());
    snprintf(spec, sizeof spec, "file:%s,%dx%d,%d", path, fb_w, fb_h, packing == SCREEN_GRAY ? 32 : 24);
    o.device = spec;
    o.packing = packing;
    o.rotate = rotate;
    if (screen_open(&s, &o) != 0) return 1;
    for (k = 0; k < REPS; k++) {
        double t0 = now();
        if (screen_show(&s, mask, bits == 8 ? W : W / 8, W, H, bits) != 0) { screen_close(&s); return 1; }
        t[k] = (now() - t0) * 1000;
        (void)screen_dark(&s);
    }
    screen_close(&s);
    remove(path);
    mid = median(t, REPS); /* sorts t */
    printf("  %-44s %7.2f ms median, %7.2f min  (%dx%d fb)\n", what, mid, t[0], fb_w, fb_h);
    return 0;
}

int main(void)
{
    const char *dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
    printf("screen: a 3840 x 2400 layer packed and drawn (budget 50 ms, one core), %s\n", dir);
    if (run("1-bit, rgb packing (mono 4K panel)", dir, 1, 0, SCREEN_RGB)) return 1;
    if (run("1-bit, rgb packing, turned 90", dir, 1, 1, SCREEN_RGB)) return 1;
    if (run("8-bit anti-aliased, rgb packing", dir, 8, 0, SCREEN_RGB)) return 1;
    if (run("1-bit, gray 32 bpp (an RGB panel)", dir, 1, 0, SCREEN_GRAY)) return 1;
    return 0;
}
