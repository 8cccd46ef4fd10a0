/* Synthetic layer masks for the PNG tests and benchmark: discs, rings and
   rotated rectangles drawn into an 8-bit coverage image (one byte per pixel,
   rows of w bytes) with anti-aliased edges, coverage = signed distance to the
   edge + 0.5, clamped; shapes combine by maximum. mask_pack turns coverage
   into a packed 1-bit mask. */
#ifndef ADASLICE_MASKGEN_H
#define ADASLICE_MASKGEN_H
#include <math.h>
#include <stddef.h>
#include <string.h>

/* A shape: centre (cx, cy), a bounding radius, two sizes, the cosine and sine
   of a turn, and the signed distance from a point to its edge (positive
   inside). */
typedef struct mask_shape {
    double cx, cy, extent, a, b, cos, sin;
    double (*inside)(const struct mask_shape *s, double x, double y);
} mask_shape;

static void mask_paint(unsigned char *g, int w, int h, const mask_shape *s)
{
    int x0 = (int)floor(s->cx - s->extent) - 1, x1 = (int)ceil(s->cx + s->extent) + 1;
    int y0 = (int)floor(s->cy - s->extent) - 1, y1 = (int)ceil(s->cy + s->extent) + 1;
    for (int y = y0 < 0 ? 0 : y0; y < y1 && y < h; y++)
        for (int x = x0 < 0 ? 0 : x0; x < x1 && x < w; x++) {
            double c = s->inside(s, x + 0.5, y + 0.5) + 0.5;
            unsigned char v = (unsigned char)(c <= 0 ? 0 : c >= 1 ? 255 : c * 255 + 0.5);
            unsigned char *q = g + (size_t)y * (size_t)w + (size_t)x;
            if (v > *q) *q = v;
        }
}

static double mask_ring_inside(const mask_shape *s, double x, double y)
{
    double d = hypot(x - s->cx, y - s->cy);
    return fmin(s->b - d, d - s->a);
}

static double mask_box_inside(const mask_shape *s, double x, double y)
{
    double dx = x - s->cx, dy = y - s->cy;
    return fmin(s->a - fabs(dx * s->cos + dy * s->sin), s->b - fabs(dy * s->cos - dx * s->sin));
}

/* A ring of radii r_in < r_out; r_in < 0 makes it a disc. */
static void mask_ring(unsigned char *g, int w, int h, double cx, double cy, double r_in, double r_out)
{
    mask_shape s = {cx, cy, r_out, r_in, r_out, 1, 0, mask_ring_inside};
    mask_paint(g, w, h, &s);
}

static void mask_disc(unsigned char *g, int w, int h, double cx, double cy, double r)
{
    mask_ring(g, w, h, cx, cy, -1, r);
}

/* A rectangle of half sizes hw x hh turned by angle (radians) about its centre. */
static void mask_box(unsigned char *g, int w, int h, double cx, double cy, double hw, double hh, double angle)
{
    mask_shape s = {cx, cy, hypot(hw, hh), hw, hh, cos(angle), sin(angle), mask_box_inside};
    mask_paint(g, w, h, &s);
}

/* Coverage >= 128 lit, packed MSB first; the padding bits stay 0. */
static void mask_pack(const unsigned char *g, int w, int h, unsigned char *bits, size_t stride)
{
    for (int y = 0; y < h; y++) {
        unsigned char *row = bits + (size_t)y * stride;
        memset(row, 0, ((size_t)w + 7) / 8);
        for (int x = 0; x < w; x++)
            if (g[(size_t)y * (size_t)w + x] >= 128) row[x >> 3] |= (unsigned char)(0x80 >> (x & 7));
    }
}

/* A cross-section as a layer of a print might have: a hollow drum, a solid
   disc, a bar and a few posts, growing with the layer (0..99) from 5 % to
   30 % of the image. */
static void mask_scene(unsigned char *g, int w, int h, int layer)
{
    double t = (layer % 100) / 99.0, u = w / 2560.0;
    memset(g, 0, (size_t)w * (size_t)h);
    mask_ring(g, w, h, 0.30 * w, 0.50 * h, (150 + 180 * t) * u, (250 + 330 * t) * u);
    mask_disc(g, w, h, 0.72 * w, 0.40 * h, (110 + 210 * t) * u);
    mask_box(g, w, h, 0.70 * w, 0.82 * h, (150 + 200 * t) * u, (40 + 10 * t) * u, 0.3 + 0.5 * t);
    for (int k = 0; k < 4; k++)
        mask_disc(g, w, h, (0.55 + 0.1 * k) * w, 0.12 * h, (20 + 10 * k) * u);
}

#endif
