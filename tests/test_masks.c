/* Layer masks against an independent reference: the contour polygons of the
   same heights, point-in-polygon at pixel centres; lit areas against A(h). */
#include "../adaslice.h"
#include "check.h"
#include "contour_length.h"
#include "meshgen.h"
#include <math.h>
#include <string.h>

static int mask_bit(const adaslice_masker *mk, int i, int j)
{
    return (mk->image[(size_t)j * mk->stride + (size_t)(i >> 3)] >> (7 - (i & 7))) & 1;
}

/* A third and a seventh of a pixel off centre, so centres rarely sit on edges. */
static adaslice_grid plate_around(const adaslice_mesh *m, double px, double py, int w, int h)
{
    double offset[2];
    offset[0] = -px / 3;
    offset[1] = -py / 7;
    return adaslice_grid_plate(m, w, h, px, py, offset);
}

/* Every pixel whose centre is more than a pixel from every contour edge is lit
   exactly when the contours' winding number there is positive; the lit area is
   within the contour's length times a pixel diagonal of the exact A(h).
   Pixels are px x py mm (many panels' are not square). */
static void check_against_contours(const char *what, adaslice_mesh *m, double px, double py, int w, int h, int heights,
                                   int overlapping)
{
    adaslice_grid g = plate_around(m, px, py, w, h);
    double diagonal = hypot(px, py), reach = px > py ? px : py;
    adaslice_masker mk;
    adaslice_contours c;
    adaslice_profile_options po;
    adaslice_profile prof;
    adaslice_error e;
    double lo[3], hi[3], *z = (double *)malloc((size_t)heights * sizeof(double));
    int k;
    adaslice_mesh_bounds(m, lo, hi);
    for (k = 0; k < heights; k++) z[k] = lo[2] + (hi[2] - lo[2]) * (k + 0.37) / heights;
    memset(&po, 0, sizeof po);
    po.metric = ADASLICE_METRIC_VOLUME;
    CHECKF(adaslice_masker_init(&mk, m, &g, &(adaslice_mask_options){1, NULL, ADASLICE_SLICE_MIDDLE, 0, NULL, 0}, &e) == ADASLICE_OK, "%s: %s", what, e.message);
    CHECK(adaslice_mesh_weld(m, NULL, &e) == ADASLICE_OK);
    CHECK(adaslice_contours_slice(m, z, (size_t)heights, NULL, &c, &e) == ADASLICE_OK);
    CHECK(adaslice_profile_exact(m, &po, &prof, &e) == ADASLICE_OK);
    for (k = 0; k < heights; k++) {
        int i, j;
        size_t wrong = 0, near = 0;
        double perimeter = 0, lit, area;
        CHECK(adaslice_masker_slice(&mk, z[k], &e) == ADASLICE_OK);
        for (j = 0; j < h; j++)
            for (i = 0; i < w; i++) {
                double x = g.origin[0] + (i + 0.5) * px, y = g.origin[1] + (j + 0.5) * py;
                if (adaslice_contours_distance(&c, (size_t)k, x, y) <= reach) { near++; continue; }
                wrong += (adaslice_contours_winding(&c, (size_t)k, x, y) > 0) != mask_bit(&mk, i, j);
            }
        perimeter = contour_length(&c, (size_t)k);
        lit = mk.lit * px * py;
        area = prof.area[(size_t)((z[k] - prof.z0) / prof.bin)];
        CHECKF(wrong == 0, "%s at z %g: %zu pixels differ from the contours (%zu near an edge skipped)", what, z[k], wrong, near);
        /* A is taken at the bin's centre: allow the area's change over a bin
           too. The exact A counts overlapping shells twice: no comparison there. */
        CHECKF(overlapping || fabs(lit - area) <= perimeter * diagonal + perimeter * prof.bin + 1e-9,
               "%s at z %g: lit %g mm^2, A %g mm^2, contour %g mm", what, z[k], lit, area, perimeter);
    }
    /* above the top no ray is left inside */
    CHECK(adaslice_masker_slice(&mk, hi[2] + 1, &e) == ADASLICE_OK && mk.lit == 0);
    CHECK(adaslice_masker_slice(&mk, hi[2], &e) == ADASLICE_ERR_ARGUMENT);
    adaslice_masker_free(&mk);
    adaslice_contours_free(&c);
    adaslice_profile_free(&prof);
    free(z);
}

static void sphere_masks_match_contours(void)
{
    adaslice_mesh m = gen_sphere(10, 64, 32, 0);
    check_against_contours("sphere", &m, 0.05, 0.05, 480, 440, 12, 0);
    gen_free(&m);
}

/* A 12K panel's 19 x 24 um pixels, three times larger: the same checks, the
   same tolerance (a pixel's diagonal along the contour). */
static void sphere_masks_match_contours_on_oblong_pixels(void)
{
    adaslice_mesh m = gen_sphere(10, 64, 32, 0);
    check_against_contours("sphere, 57 x 72 um pixels", &m, 0.057, 0.072, 400, 310, 12, 0);
    gen_free(&m);
}

static void box_with_cylinder_masks_match_contours(void)
{
    adaslice_mesh m = gen_box(-10, -6, 0, 10, 6, 5), c = gen_cylinder(4, 8, 48, 5);
    gen_append(&m, &c);
    check_against_contours("box with cylinder", &m, 0.07, 0.07, 320, 200, 10, 0);
    gen_free(&m);
    gen_free(&c);
}

/* Overlapping shells: the winding number is 2 where they overlap, still lit. */
static void overlapping_boxes_stay_lit(void)
{
    adaslice_mesh m = gen_box(0, 0, 0, 6, 4, 3), b = gen_box(3, 1, 1, 9, 6, 5);
    gen_append(&m, &b);
    check_against_contours("overlapping boxes", &m, 0.05, 0.05, 220, 160, 8, 1);
    gen_free(&m);
    gen_free(&b);
}

static void bundled_hand_masks_match_contours(void)
{
    adaslice_load_options lo;
    adaslice_mesh m;
    adaslice_error e;
    memset(&lo, 0, sizeof lo);
    lo.scale = 88.7;
    CHECKF(adaslice_mesh_load_file("examples/models/hand_closed.obj", &lo, &m, &e) == ADASLICE_OK, "%s", e.message);
    check_against_contours("hand", &m, 0.2, 0.2, 350, 440, 6, 0);
    adaslice_mesh_free(&m);
}

/* Pixel centres exactly on the box's vertices and edges (and the sphere's
   poles): inside the outline every pixel is lit, none outside, none above. */
static void rays_through_edges_light_exactly_once(void)
{
    adaslice_mesh box = gen_box(-4, -3, 0, 4, 3, 2);
    adaslice_grid g;
    adaslice_masker mk;
    int i, j, wrong = 0;
    memset(&g, 0, sizeof g);
    g.axis = ADASLICE_AXIS_Z;
    g.pitch[0] = g.pitch[1] = 0.5;
    g.origin[0] = g.origin[1] = -10.25; /* centres at multiples of 0.5 */
    g.width = g.height = 41;
    CHECK(adaslice_masker_init(&mk, &box, &g, &(adaslice_mask_options){1, NULL, ADASLICE_SLICE_MIDDLE, 0, NULL, 0}, NULL) == ADASLICE_OK);
    CHECK(adaslice_masker_slice(&mk, 1, NULL) == ADASLICE_OK);
    for (j = 0; j < g.height; j++)
        for (i = 0; i < g.width; i++) {
            double x = -10 + 0.5 * i, y = -10 + 0.5 * j;
            int inside = fabs(x) < 4 && fabs(y) < 3, on_edge = fabs(x) <= 4 && fabs(y) <= 3 && !inside;
            if (!on_edge) wrong += inside != mask_bit(&mk, i, j);
        }
    CHECKF(wrong == 0, "%d pixels wrong", wrong);
    CHECK(adaslice_masker_slice(&mk, 2.5, NULL) == ADASLICE_OK && mk.lit == 0);
    adaslice_masker_free(&mk);
    gen_free(&box);
}

/* 8-bit masks: grey = 255 * k / s^2, k the covered fraction in s^2 levels,
   so their sum is the covered area to half a level a pixel; a pixel deep
   inside is 255, far outside 0. */
static void antialiased_masks_cover_the_area(void)
{
    adaslice_mesh m = gen_cylinder(5, 4, 256, 0);
    adaslice_grid g = plate_around(&m, 0.1, 0.1, 140, 130);
    adaslice_masker mk;
    size_t p, sum = 0;
    double poly = 256 / 2.0 * 25 * sin(2 * M_PI / 256);
    CHECK(adaslice_masker_init(&mk, &m, &g, &(adaslice_mask_options){4, NULL, ADASLICE_SLICE_MIDDLE, 0, NULL, 0}, NULL) == ADASLICE_OK);
    CHECK(adaslice_masker_slice(&mk, 2, NULL) == ADASLICE_OK);
    for (p = 0; p < (size_t)g.width * g.height; p++) sum += mk.image[p];
    /* rays: 0.025 mm apart; the circle's 31.4 mm of edge misjudges at most a ray's diagonal */
    CHECKF(fabs(mk.lit * 0.01 - poly) <= 2 * M_PI * 5 * 0.025 * sqrt(2.0), "lit %g, area %g", mk.lit * 0.01, poly);
    CHECKF(fabs(sum / 255.0 - mk.lit) <= 0.5 * 0.01 * (double)g.width * g.height / 16 + 1, "grey sum %g, lit %g", sum / 255.0, mk.lit);
    CHECK(mk.image[(size_t)(g.height / 2) * mk.stride + (size_t)(g.width / 2)] == 255 && mk.image[0] == 0);
    adaslice_masker_free(&mk);
    gen_free(&m);
}

/* ---- exact coverage against a 64 x 64 supersampled reference */

#define REF_SAMPLES 64

typedef struct ref_crossing { double x; int step; } ref_crossing;

static int ref_crossing_cmp(const void *a, const void *b)
{
    double x = ((const ref_crossing *)a)->x, y = ((const ref_crossing *)b)->x;
    return x < y ? -1 : x > y;
}

/* The section of m at height z as directed segments (x0, y0, x1, y1), cut
   here from the triangles: a corner at z counts as below, and each cut runs
   along z x n (material on its left, n the facet's normal). Returns the count. */
static size_t ref_section(const adaslice_mesh *m, double z, double **out)
{
    size_t t, n = 0;
    double *seg = (double *)malloc((m->triangle_count + 1) * 4 * sizeof(double));
    if (!seg) abort();
    for (t = 0; t < m->triangle_count; t++) {
        const float *v[3];
        double p[2][2], n3[3], e1[3], e2[3], dx, dy;
        int k, cuts = 0;
        for (k = 0; k < 3; k++) v[k] = m->vertices + 3 * (size_t)m->triangles[3 * t + (size_t)k];
        for (k = 0; k < 3; k++) {
            const float *a = v[k], *b = v[(k + 1) % 3];
            double u;
            if (((double)a[2] <= z) == ((double)b[2] <= z)) continue;
            u = (z - a[2]) / ((double)b[2] - a[2]);
            p[cuts][0] = a[0] + u * ((double)b[0] - a[0]);
            p[cuts][1] = a[1] + u * ((double)b[1] - a[1]);
            cuts++;
        }
        if (cuts != 2) continue;
        for (k = 0; k < 3; k++) { e1[k] = (double)v[1][k] - v[0][k]; e2[k] = (double)v[2][k] - v[0][k]; }
        n3[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n3[1] = e1[2] * e2[0] - e1[0] * e2[2];
        dx = p[1][0] - p[0][0];
        dy = p[1][1] - p[0][1];
        if (dx * -n3[1] + dy * n3[0] < 0) { /* against z x n: turn it round */
            double q[2] = {p[0][0], p[0][1]};
            p[0][0] = p[1][0]; p[0][1] = p[1][1]; p[1][0] = q[0]; p[1][1] = q[1];
        }
        seg[4 * n] = p[0][0]; seg[4 * n + 1] = p[0][1]; seg[4 * n + 2] = p[1][0]; seg[4 * n + 3] = p[1][1];
        n++;
    }
    *out = seg;
    return n;
}

/* Each pixel's fraction of 64 x 64 sample points (at their cells' centres)
   where the segments' winding number is positive: along each sample row the
   segments it crosses, sorted; a segment going down raises the winding past
   it. `twice` (or NULL): the fraction where it is 2 or more. */
static void ref_coverage(const double *seg, size_t n, const adaslice_grid *g, double *ref, double *twice)
{
    size_t j, k, cap = n + 1, w = (size_t)g->width, rows = (size_t)g->height * REF_SAMPLES;
    ref_crossing *cr = (ref_crossing *)malloc(cap * sizeof *cr);
    if (!cr) abort();
    memset(ref, 0, w * (size_t)g->height * sizeof *ref);
    if (twice) memset(twice, 0, w * (size_t)g->height * sizeof *twice);
    for (j = 0; j < rows; j++) {
        double y = g->origin[1] + ((double)j + 0.5) / REF_SAMPLES * g->pitch[1];
        size_t m = 0, c = 0, i;
        int wind = 0;
        for (k = 0; k < n; k++) {
            const double *s = seg + 4 * k;
            double lo = s[1] < s[3] ? s[1] : s[3], hi = s[1] < s[3] ? s[3] : s[1];
            if (!(y >= lo && y < hi)) continue;
            cr[m].x = s[0] + (y - s[1]) * (s[2] - s[0]) / (s[3] - s[1]);
            cr[m++].step = s[3] < s[1] ? 1 : -1;
        }
        qsort(cr, m, sizeof *cr, ref_crossing_cmp);
        for (i = 0; i < w * REF_SAMPLES; i++) {
            double x = g->origin[0] + ((double)i + 0.5) / REF_SAMPLES * g->pitch[0];
            for (; c < m && cr[c].x < x; c++) wind += cr[c].step;
            if (wind > 0) ref[j / REF_SAMPLES * w + i / REF_SAMPLES] += 1.0 / (REF_SAMPLES * REF_SAMPLES);
            if (wind > 1 && twice) twice[j / REF_SAMPLES * w + i / REF_SAMPLES] += 1.0 / (REF_SAMPLES * REF_SAMPLES);
        }
    }
    free(cr);
}

/* The masker's fractions (and its grey, each fraction rounded to s*s + 1
   levels) against the reference at height z: the mean error over the
   pixels either calls partly covered under 1 % of a grey level (1/s^2),
   the worst under half a level. With `overlapping` the reference is the
   masker's documented rule where shells overlap: the area where the winding
   is positive plus the area where it is 2 or more, at most 1. */
static void check_exact_coverage(const char *what, const adaslice_mesh *m, const adaslice_grid *g, double z, int s,
                                 int overlapping)
{
    size_t pixels = (size_t)g->width * g->height, p, n, edge = 0, grey_off = 0, doubled = 0;
    float *fr = (float *)malloc(pixels * sizeof(float));
    double *ref = (double *)malloc(pixels * sizeof(double)), *twice = (double *)malloc(pixels * sizeof(double)), *seg;
    double level = 1.0 / (s * s), sum = 0, worst = 0;
    adaslice_masker mk;
    adaslice_mask_options o;
    adaslice_error e;
    if (!fr || !ref || !twice) abort();
    memset(&o, 0, sizeof o);
    o.supersample = s;
    o.fractions = fr;
    CHECKF(adaslice_masker_init(&mk, m, g, &o, &e) == ADASLICE_OK, "%s: %s", what, e.message);
    CHECKF(adaslice_masker_slice(&mk, z, &e) == ADASLICE_OK, "%s: %s", what, e.message);
    n = ref_section(m, z, &seg);
    ref_coverage(seg, n, g, ref, twice);
    for (p = 0; p < pixels; p++) {
        if (twice[p] > 0 && twice[p] < 1 && ref[p] < 1) doubled++;
        if (overlapping) ref[p] = ref[p] + twice[p] < 1 ? ref[p] + twice[p] : 1;
        double err = fabs(fr[p] - ref[p]);
        /* the fraction's level, either way when it lies on a half level (the float fraction rounds) */
        int k0 = (int)floor(fr[p] / level + 0.5 - 1e-6), k1 = (int)floor(fr[p] / level + 0.5 + 1e-6);
        grey_off += mk.image[p] != (unsigned char)((255 * k0 + s * s / 2) / (s * s)) &&
                    mk.image[p] != (unsigned char)((255 * k1 + s * s / 2) / (s * s));
        if (err > worst) worst = err;
        if ((fr[p] > 0 && fr[p] < 1) || (ref[p] > 0 && ref[p] < 1)) { edge++; sum += err; }
    }
    CHECKF(edge > 0 && sum / (double)edge < 0.01 * level, "%s: mean error %g of a level over %zu edge pixels", what,
           edge ? sum / (double)edge / level : 0, edge);
    CHECKF(worst < 0.5 * level, "%s: worst error %g of a level", what, worst / level);
    CHECKF(grey_off == 0, "%s: %zu pixels' grey is not their fraction's level", what, grey_off);
    CHECKF(overlapping == (doubled > 0), "%s: %zu partly covered pixels are partly covered twice", what, doubled);
    printf("  (%s: %zu edge pixels, mean error %.2g, worst %.2g of a level)\n", what, edge, sum / (double)edge / level, worst / level);
    adaslice_masker_free(&mk);
    free(seg);
    free(ref);
    free(twice);
    free(fr);
}

/* A UV sphere's section between its rings, on pixels a third and a seventh
   off centre, at --aa 4 and 2; then on a display that cuts off its left and
   top (the winding of the part left of the display still counts). */
static void exact_coverage_of_a_sphere_section(void)
{
    adaslice_mesh m = gen_sphere(2, 48, 24, 0);
    adaslice_grid g = plate_around(&m, 0.1, 0.1, 48, 46);
    check_exact_coverage("sphere at z 1.3, aa 4", &m, &g, 1.3, 4, 0);
    check_exact_coverage("sphere at z 3.41, aa 2", &m, &g, 3.41, 2, 0);
    g.origin[0] += 1.5;
    g.origin[1] -= 1.2;
    check_exact_coverage("sphere cut off by the display, aa 4", &m, &g, 2.2, 4, 0);
    gen_free(&m);
}

/* Triangle (a, b, c) (pixel units, 1/8 mm pixels from the origin) as a
   closed prism from z 0 to 1, wound counter-clockwise seen from outside. */
static void add_prism(adaslice_mesh *m, double ax, double ay, double bx, double by, double cx, double cy)
{
    double p[3][2] = {{ax, ay}, {bx, by}, {cx, cy}}, t;
    uint32_t v[6];
    int k;
    if ((bx - ax) * (cy - ay) - (by - ay) * (cx - ax) < 0) { t = p[1][0]; p[1][0] = p[2][0]; p[2][0] = t; t = p[1][1]; p[1][1] = p[2][1]; p[2][1] = t; }
    for (k = 0; k < 6; k++) v[k] = gen_vertex(m, p[k % 3][0] / 8, p[k % 3][1] / 8, k / 3);
    gen_triangle(m, v[0], v[2], v[1]);
    gen_triangle(m, v[3], v[4], v[5]);
    for (k = 0; k < 3; k++) {
        gen_triangle(m, v[k], v[(k + 1) % 3], v[(k + 1) % 3 + 3]);
        gen_triangle(m, v[k], v[(k + 1) % 3 + 3], v[k + 3]);
    }
}

/* A star of 40 spikes, each narrower than a pixel at its root (a fan of
   thin triangles from a pixel corner, tips on pixel corners), and loose
   slivers narrower than a pixel with corners on pixel corners and edges,
   one lying along a row of pixel edges: the section at z 0.5. */
static void exact_coverage_of_slivers(void)
{
    adaslice_mesh m = gen_alloc(6 * 90, 8 * 90);
    adaslice_grid g;
    int i, n = 40;
    for (i = 0; i < n; i++) {
        double a0 = 2 * M_PI * i / n, a1 = 2 * M_PI * (i + 1) / n, am = 2 * M_PI * (i + 0.5) / n;
        double tx = floor(24 + 20 * cos(am) + 0.5), ty = floor(24 + 20 * sin(am) + 0.5);
        add_prism(&m, 24, 24, 24 + 5 * cos(a0), 24 + 5 * sin(a0), tx, ty);
        add_prism(&m, 24, 24, tx, ty, 24 + 5 * cos(a1), 24 + 5 * sin(a1));
    }
    add_prism(&m, 50, 4, 78, 4, 78, 4.5);
    add_prism(&m, 50, 8, 50.5, 8, 60, 40);
    add_prism(&m, 62, 20, 79, 20, 79, 20.25);
    add_prism(&m, 66, 24, 67, 24, 79, 40);
    add_prism(&m, 54, 44, 79, 45, 54, 44.5);
    memset(&g, 0, sizeof g);
    g.axis = ADASLICE_AXIS_Z;
    g.pitch[0] = g.pitch[1] = 0.125;
    g.width = 80;
    g.height = 48;
    check_exact_coverage("slivers, aa 4", &m, &g, 0.5, 4, 0);
    gen_free(&m);
}

/* Two slivers and a disc crossing a square inside pixels: where the winding
   is 2 the pixel counts the overlap again (the integral of the winding,
   clamped), so it is never darker than the union, and whole pixels inside
   both stay lit. */
static void exact_coverage_of_overlapping_shells(void)
{
    adaslice_mesh m = gen_alloc(40, 80), disc = gen_cylinder(1.3, 1, 40, 0);
    adaslice_grid g;
    int i;
    add_prism(&m, 10.5, 10.25, 30, 10.25, 30, 30);
    add_prism(&m, 10.5, 10.25, 30, 30, 10.5, 30);
    add_prism(&m, 4, 20, 36, 20.5, 4, 20.25);
    add_prism(&m, 20, 4, 20.3, 4, 21, 36);
    for (i = 0; i < (int)disc.vertex_count; i++) { disc.vertices[3 * i] += 3.75f; disc.vertices[3 * i + 1] += 1.25f; }
    gen_append(&m, &disc);
    memset(&g, 0, sizeof g);
    g.axis = ADASLICE_AXIS_Z;
    g.pitch[0] = g.pitch[1] = 0.125;
    g.width = g.height = 40;
    check_exact_coverage("overlapping shells, aa 4", &m, &g, 0.5, 4, 1);
    gen_free(&m);
    gen_free(&disc);
}

/* ---- masks of a layer's whole range: envelope (union) and core (intersection) */

static adaslice_result layer_masker(adaslice_masker *mk, const adaslice_mesh *m, const adaslice_grid *g, int s,
                                    adaslice_slice_at rule)
{
    adaslice_mask_options o;
    memset(&o, 0, sizeof o);
    o.supersample = s;
    o.slice_at = rule;
    return adaslice_masker_init(mk, m, g, &o, NULL);
}

/* A 10 x 10 x 1 mm plate with a 1 x 1 mm pin standing 0.04 mm above it (its
   own box, overlapping the plate's), sliced in 0.1 mm layers: the layer
   [1.0, 1.1] holds the whole pin. At its middle (1.05) the pin is gone; the
   envelope lights its footprint, the core nothing; the layer above is empty
   in all three (the envelope lets go of the rays that left). Each layer's
   core lies within its middle section and that within its envelope, pixel
   for pixel. */
static void pin_thinner_than_a_layer_survives_in_the_envelope(void)
{
    adaslice_mesh m = gen_box(0, 0, 0, 10, 10, 1), pin = gen_box(4.5, 4.5, 0.5, 5.5, 5.5, 1.04);
    adaslice_grid g;
    adaslice_masker mk[3];
    static const adaslice_slice_at rules[3] = {ADASLICE_SLICE_CORE, ADASLICE_SLICE_MIDDLE, ADASLICE_SLICE_ENVELOPE};
    int k, r, i, j, nested = 1;
    gen_append(&m, &pin);
    g = plate_around(&m, 0.05, 0.05, 220, 220);
    for (r = 0; r < 3; r++) CHECK(layer_masker(&mk[r], &m, &g, 1, rules[r]) == ADASLICE_OK);
    for (k = 0; k < 12; k++) {
        double zb = 0.1 * k, zt = 0.1 * (k + 1);
        for (r = 0; r < 3; r++) CHECK(adaslice_masker_layer(&mk[r], zb, zt, NULL) == ADASLICE_OK);
        for (j = 0; j < g.height; j++)
            for (i = 0; i < g.width; i++)
                if (mask_bit(&mk[0], i, j) > mask_bit(&mk[1], i, j) || mask_bit(&mk[1], i, j) > mask_bit(&mk[2], i, j)) nested = 0;
        if (k < 10) {
            /* the plate: 200 x 200 pixels in every rule */
            for (r = 0; r < 3; r++) CHECKF(mk[r].lit == 40000, "layer %d, rule %d: %g pixels lit", k, (int)rules[r], mk[r].lit);
        } else if (k == 10) {
            CHECKF(mk[2].lit == 400, "envelope of the pin's layer: %g pixels, want 20 x 20", mk[2].lit);
            CHECKF(mk[1].lit == 0 && mk[0].lit == 0, "middle %g, core %g pixels: want none", mk[1].lit, mk[0].lit);
            CHECK(mask_bit(&mk[2], 110, 110) && !mask_bit(&mk[2], 80, 80));
        } else {
            for (r = 0; r < 3; r++) CHECKF(mk[r].lit == 0, "above the pin, rule %d: %g pixels", (int)rules[r], mk[r].lit);
        }
    }
    CHECK(nested);
    for (r = 0; r < 3; r++) adaslice_masker_free(&mk[r]);
    gen_free(&m);
    gen_free(&pin);
}

/* A UV sphere of radius R = 5 (256 x 256) centred at z = 5, in layers of
   0.05, 0.15 and 0.1 mm in turn (a plan's mix). Every section of a sphere is
   a disc about the axis, so the union of a layer's sections is its largest
   one: radius^2 = R^2 - z*^2, z* the height in the layer nearest the centre
   (0 where the layer spans the equator); the intersection is its smallest,
   z* the end farther from the centre. The polyhedron lies between the sphere
   and the sphere of radius rho R, rho = cos(a), a bounding the angle any
   facet spans (its quad's diagonal), so its sections lie between the two
   discs: tessellation error pi (1 - rho^2) R^2 ~ 0.06 mm^2. Pixel centres
   misjudge only within half a pixel diagonal of the edge: sqrt(2) p times
   the perimeter 2 pi r. p = 0.01 mm (1-bit) or a ray pitch of 0.01 (--aa 2
   on 0.02 mm pixels): the tolerance is 0.44 mm^2 at the equator, where the
   area is 78.5 mm^2. The same layers' middle sections differ from the
   envelope by pi ((z_mid)^2 - z*^2): more than the tolerance in a third of
   the layers or more (counted), so the test tells the rules apart; the
   errors measured are a few hundredths of the tolerance (printed). */
static void sphere_layer_areas(int s, double pixel)
{
    const double R = 5, cz = 5, thick[3] = {0.05, 0.15, 0.1};
    const int slices = 256, stacks = 256;
    adaslice_mesh m = gen_sphere(R, slices, stacks, 0);
    adaslice_grid g = plate_around(&m, pixel, pixel, (int)(10.4 / pixel), (int)(10.4 / pixel));
    adaslice_masker env, core;
    double a = sqrt(pow(M_PI / stacks, 2) + pow(2 * M_PI / slices, 2)), rho = cos(a);
    double tess = M_PI * (1 - rho * rho) * R * R, zb = 0, worst_env = 0, worst_core = 0;
    double ray = pixel / s;
    int k = 0, telling = 0, layers = 0;
    CHECK(layer_masker(&env, &m, &g, s, ADASLICE_SLICE_ENVELOPE) == ADASLICE_OK);
    CHECK(layer_masker(&core, &m, &g, s, ADASLICE_SLICE_CORE) == ADASLICE_OK);
    while (zb < 2 * R - 1e-9) {
        double zt = zb + thick[k++ % 3], lo, hi, near, far, want_env, want_core, tol_env, tol_core, got_env, got_core, mid;
        size_t p, grey = 0;
        if (zt > 2 * R) zt = 2 * R;
        lo = zb - cz; hi = zt - cz;
        near = lo <= 0 && hi >= 0 ? 0 : fmin(fabs(lo), fabs(hi));
        far = fmax(fabs(lo), fabs(hi));
        want_env = M_PI * (R * R - near * near);
        want_core = M_PI * (R * R - far * far);
        tol_env = tess + sqrt(2.0) * ray * 2 * M_PI * sqrt(R * R - near * near) + ray * ray;
        tol_core = tess + sqrt(2.0) * ray * 2 * M_PI * sqrt(R * R - far * far) + ray * ray;
        CHECK(adaslice_masker_layer(&env, zb, zt, NULL) == ADASLICE_OK);
        CHECK(adaslice_masker_layer(&core, zb, zt, NULL) == ADASLICE_OK);
        got_env = env.lit * pixel * pixel;
        got_core = core.lit * pixel * pixel;
        CHECKF(fabs(got_env - want_env) <= tol_env, "s %d, envelope [%g, %g]: %g mm^2, want %g +- %g", s, zb, zt,
               got_env, want_env, tol_env);
        CHECKF(fabs(got_core - want_core) <= tol_core, "s %d, core [%g, %g]: %g mm^2, want %g +- %g", s, zb, zt,
               got_core, want_core, tol_core);
        if (fabs(got_env - want_env) / tol_env > worst_env) worst_env = fabs(got_env - want_env) / tol_env;
        if (fabs(got_core - want_core) / tol_core > worst_core) worst_core = fabs(got_core - want_core) / tol_core;
        mid = 0.5 * (zb + zt) - cz;
        if (M_PI * (mid * mid - near * near) > tol_env) telling++;
        if (s > 1) { /* the grey levels carry the same rays: 255 per pixel, each within half a level */
            for (p = 0; p < (size_t)g.width * g.height; p++) grey += env.image[p];
            CHECKF(fabs(grey / 255.0 - env.lit) <= 0.5 / 255 * (double)g.width * g.height,
                   "grey sum %g, lit %g", grey / 255.0, env.lit);
        }
        layers++;
        zb = zt;
    }
    CHECKF(telling > layers / 3, "only %d of %d layers tell the envelope from the middle section", telling, layers);
    printf("  (sphere --aa %d: %d layers; worst error %.2f of the tolerance (envelope), %.2f (core))\n", s, layers,
           worst_env, worst_core);
    adaslice_masker_free(&env);
    adaslice_masker_free(&core);
    gen_free(&m);
}

static void sphere_envelope_is_the_largest_section(void) { sphere_layer_areas(1, 0.01); }
static void sphere_envelope_antialiased(void) { sphere_layer_areas(2, 0.02); }

/* The hand (overhangs, fingers starting and ending inside layers), layers
   of 0.15 mm: each layer's envelope holds every pixel lit at any of 30
   heights spread through the layer's open range, and its core none that is
   dark at any of them; what the envelope adds to those 30 sections (rays
   inside for less than their spacing, 5 um, near horizontal faces) and what
   the core lacks are few. Over many layers, so the rays a layer changed are
   set right again for the next, and skipped layers are passed in one sweep. */
static void hand_envelope_holds_every_section_of_its_layer(void)
{
    adaslice_load_options lo;
    adaslice_mesh m;
    adaslice_error e;
    adaslice_grid g;
    adaslice_masker env, core, point;
    static unsigned char any[440][350], all[440][350];
    double bounds_lo[3], bounds_hi[3], zb;
    long lit = 0, extra = 0, missing_env = 0, core_lit = 0, core_extra = 0;
    int layers = 0, i, j, h;
    const int heights = 30;
    memset(&lo, 0, sizeof lo);
    lo.scale = 88.7;
    CHECKF(adaslice_mesh_load_file("examples/models/hand_closed.obj", &lo, &m, &e) == ADASLICE_OK, "%s", e.message);
    adaslice_mesh_bounds(&m, bounds_lo, bounds_hi);
    g = plate_around(&m, 0.2, 0.2, 350, 440);
    CHECK(layer_masker(&env, &m, &g, 1, ADASLICE_SLICE_ENVELOPE) == ADASLICE_OK);
    CHECK(layer_masker(&core, &m, &g, 1, ADASLICE_SLICE_CORE) == ADASLICE_OK);
    CHECK(layer_masker(&point, &m, &g, 1, ADASLICE_SLICE_MIDDLE) == ADASLICE_OK);
    for (zb = bounds_lo[2] + 0.013; zb < bounds_hi[2]; zb += layers % 3 ? 0.15 : 0.15 * 8) {
        /* three layers in a row, then seven skipped (the maskers pass them in one sweep) */
        double zt = zb + 0.15;
        memset(any, 0, sizeof any);
        memset(all, 1, sizeof all);
        for (h = 0; h < heights; h++) {
            CHECK(adaslice_masker_slice(&point, zb + 0.15 * (h + 0.5) / heights, NULL) == ADASLICE_OK);
            for (j = 0; j < g.height; j++)
                for (i = 0; i < g.width; i++) {
                    int b = mask_bit(&point, i, j);
                    any[j][i] |= (unsigned char)b;
                    all[j][i] &= (unsigned char)b;
                }
        }
        CHECK(adaslice_masker_layer(&env, zb, zt, NULL) == ADASLICE_OK);
        CHECK(adaslice_masker_layer(&core, zb, zt, NULL) == ADASLICE_OK);
        for (j = 0; j < g.height; j++)
            for (i = 0; i < g.width; i++) {
                int en = mask_bit(&env, i, j), co = mask_bit(&core, i, j);
                lit += en;
                missing_env += any[j][i] && !en;
                extra += en && !any[j][i];
                core_lit += co;
                core_extra += co && !all[j][i];
            }
        layers++;
    }
    CHECKF(missing_env == 0, "%ld pixels lit in a section of their layer but not in its envelope", missing_env);
    CHECKF(core_extra == 0, "%ld pixels of a core dark in a section of their layer", core_extra);
    CHECKF(layers > 20 && lit > 100000 && extra * 200 < lit, "%d layers, %ld pixels lit, %ld beyond the 30 sections",
           layers, lit, extra);
    printf("  (hand: %d layers, %ld envelope pixels, %ld beyond the sections; %ld core pixels)\n", layers, lit, extra, core_lit);
    adaslice_masker_free(&env);
    adaslice_masker_free(&core);
    adaslice_masker_free(&point);
    adaslice_mesh_free(&m);
}

/* Envelope and core read rays: a mesh that cannot be read along them is
   refused, with the count of unbalanced edges; a bad rule is an argument
   error; a layer upside down too. */
static void envelope_needs_a_closed_mesh(void)
{
    adaslice_mesh m = gen_box(0, 0, 0, 4, 4, 2);
    adaslice_grid g = plate_around(&m, 0.1, 0.1, 60, 60);
    adaslice_masker mk;
    adaslice_mask_options o;
    adaslice_error e;
    memset(&o, 0, sizeof o);
    CHECK(layer_masker(&mk, &m, &g, 1, ADASLICE_SLICE_ENVELOPE) == ADASLICE_OK);
    CHECK(adaslice_masker_layer(&mk, 1, 0.9, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "upside down"));
    adaslice_masker_free(&mk);
    o.slice_at = (adaslice_slice_at)7;
    CHECK(adaslice_masker_init(&mk, &m, &g, &o, &e) == ADASLICE_ERR_ARGUMENT);
    m.triangle_count -= 2; /* a face gone */
    CHECK(layer_masker(&mk, &m, &g, 1, ADASLICE_SLICE_MIDDLE) == ADASLICE_OK);
    adaslice_masker_free(&mk);
    o.slice_at = ADASLICE_SLICE_CORE;
    CHECK(adaslice_masker_init(&mk, &m, &g, &o, &e) == ADASLICE_ERR_UNSUPPORTED && strstr(e.message, "closed mesh"));
    m.triangle_count += 2;
    gen_free(&m);
}

/* ---- row bands: a masker split by rows makes the whole masker's bytes */

/* Each rule (1-bit and anti-aliased sections, envelope, core) on a mesh
   over grid rows cut into bands of odd sizes (one-row bands at either end),
   swept layer by layer in turn, the bands in reverse order: each band's
   rows are the whole masker's, byte for byte, and the bands' lit rays add
   up to its. The mesh overhangs the grid's first and last rows (checked
   lit), and on the two boxes one band lies in the gap between them, with no
   facet. */
static void check_bands(const char *what, const adaslice_mesh *m, const adaslice_grid *g, const uint32_t *rows,
                        size_t count, int empty_band)
{
    static const struct { adaslice_slice_at rule; int s; } kinds[] = {{ADASLICE_SLICE_MIDDLE, 1}, {ADASLICE_SLICE_MIDDLE, 4},
                                                                      {ADASLICE_SLICE_BOTTOM, 3}, {ADASLICE_SLICE_ENVELOPE, 1},
                                                                      {ADASLICE_SLICE_CORE, 2}};
    adaslice_masker whole, split, bands[16];
    double lo[3], hi[3], zb;
    size_t k, b;
    adaslice_mesh_bounds(m, lo, hi);
    for (k = 0; k < sizeof kinds / sizeof kinds[0]; k++) {
        long layers = 0, differ = 0, first = 0, last = 0; /* bytes lit in the grid's first and last rows */
        double ss = (double)kinds[k].s * kinds[k].s;
        CHECK(layer_masker(&whole, m, g, kinds[k].s, kinds[k].rule) == ADASLICE_OK);
        CHECK(layer_masker(&split, m, g, kinds[k].s, kinds[k].rule) == ADASLICE_OK);
        CHECK(adaslice_masker_bands(&split, rows, count, bands, NULL) == ADASLICE_OK);
        adaslice_masker_free(&split); /* the bands keep nothing of it */
        if (empty_band >= 0) CHECKF(bands[empty_band].count == 0, "%s: band %d holds %zu facets", what, empty_band, bands[empty_band].count);
        for (zb = lo[2] - 0.05; zb < hi[2] + 0.1; zb += 0.37) {
            long long rays = 0;
            CHECK(adaslice_masker_layer(&whole, zb, zb + 0.37, NULL) == ADASLICE_OK);
            for (b = count; b-- > 0;) {
                size_t n = (size_t)(rows[b + 1] - rows[b]) * whole.stride;
                CHECK(adaslice_masker_layer(&bands[b], zb, zb + 0.37, NULL) == ADASLICE_OK);
                if (memcmp(bands[b].image, whole.image + (size_t)rows[b] * whole.stride, n) && !differ++)
                    printf("  %s, rule %d, s %d: band %zu differs at %g mm\n", what, (int)kinds[k].rule, kinds[k].s, b, zb);
                rays += llround(bands[b].lit * ss);
            }
            CHECKF(rays == llround(whole.lit * ss), "%s: the bands light %lld rays, the whole %g", what, rays, whole.lit * ss);
            /* the part meets the grid's first and last rows */
            for (b = 0; b < whole.stride; b++) {
                first += whole.image[b] != 0;
                last += whole.image[(size_t)(g->height - 1) * whole.stride + b] != 0;
            }
            layers++;
        }
        CHECKF(differ == 0, "%s, rule %d, s %d: %ld of %ld layers differ", what, (int)kinds[k].rule, kinds[k].s, differ, layers);
        CHECKF(first > 0 && last > 0, "%s: %ld bytes lit in the grid's first row, %ld in its last", what, first, last);
        for (b = 0; b < count; b++) adaslice_masker_free(&bands[b]);
        adaslice_masker_free(&whole);
    }
}

static void bands_make_the_whole_maskers_bytes(void)
{
    adaslice_mesh boxes = gen_box(0, 0, 0, 10, 4, 2), upper = gen_box(0, 6, 0.5, 10, 10, 3), hand;
    adaslice_load_options lo;
    adaslice_error e;
    adaslice_grid g;
    /* the boxes: rows 0.35 to 9.65 mm, the gap 4 to 6 mm in rows 12.2 to 18.8 */
    static const uint32_t box_rows[] = {0, 1, 7, 14, 17, 18, 30, 31};
    static const uint32_t hand_rows[] = {0, 1, 2, 50, 51, 99, 150, 200, 201};
    gen_append(&boxes, &upper);
    memset(&g, 0, sizeof g);
    g.axis = ADASLICE_AXIS_Z;
    g.pitch[0] = g.pitch[1] = 0.3;
    g.width = 37;
    g.height = 31;
    g.origin[0] = -0.4;
    g.origin[1] = 0.35;
    check_bands("two boxes", &boxes, &g, box_rows, 7, 3);
    memset(&lo, 0, sizeof lo);
    lo.scale = 88.7;
    CHECKF(adaslice_mesh_load_file("examples/models/hand_closed.obj", &lo, &hand, &e) == ADASLICE_OK, "%s", e.message);
    g = plate_around(&hand, 0.3, 0.3, 157, 201); /* 60 mm of the hand's 88 */
    check_bands("the hand", &hand, &g, hand_rows, 8, -1);
    adaslice_mesh_free(&hand);
    gen_free(&boxes);
    gen_free(&upper);
}

static int zero_area_facet(const adaslice_mesh *m, size_t t)
{
    const float *p = m->vertices + 3 * (size_t)m->triangles[3 * t], *q = m->vertices + 3 * (size_t)m->triangles[3 * t + 1],
                *r = m->vertices + 3 * (size_t)m->triangles[3 * t + 2];
    double u[3], w[3];
    int k;
    for (k = 0; k < 3; k++) { u[k] = (double)q[k] - p[k]; w[k] = (double)r[k] - p[k]; }
    return u[1] * w[2] - u[2] * w[1] == 0 && u[2] * w[0] - u[0] * w[2] == 0 && u[0] * w[1] - u[1] * w[0] == 0;
}

/* Brute force: every edge (zero-area facets left out) run as often one way
   as the other, the half-edges compared all against all. */
static int every_edge_balances(const adaslice_mesh *m)
{
    size_t h, g, n = 3 * m->triangle_count;
    for (h = 0; h < n; h++) {
        uint32_t a = m->triangles[h], b = m->triangles[h % 3 == 2 ? h - 2 : h + 1];
        long net = 0;
        if (zero_area_facet(m, h / 3)) continue;
        for (g = 0; g < n; g++) {
            uint32_t c = m->triangles[g], d = m->triangles[g % 3 == 2 ? g - 2 : g + 1];
            if (zero_area_facet(m, g / 3)) continue;
            net += (c == a && d == b) - (c == b && d == a);
        }
        if (net) return 0;
    }
    return 1;
}

static void turn_facet(adaslice_mesh *m, size_t t)
{
    uint32_t x = m->triangles[3 * t + 1];
    m->triangles[3 * t + 1] = m->triangles[3 * t + 2];
    m->triangles[3 * t + 2] = x;
}

/* Facet t again at the end, turned or not. */
static void repeat_facet(adaslice_mesh *m, size_t t, int turned)
{
    uint32_t *more = (uint32_t *)realloc(m->triangles, (3 * m->triangle_count + 3) * sizeof *more);
    if (!more) abort();
    m->triangles = more;
    memcpy(more + 3 * m->triangle_count, more + 3 * t, 3 * sizeof *more);
    if (turned) turn_facet(m, m->triangle_count);
    m->triangle_count++;
}

/* A masker reads rays exactly when every edge balances and takes whole
   sections otherwise (a hole, a facet turned, a facet twice): against the
   brute force, on a sphere changed one way at a time. */
static void sections_exactly_where_an_edge_does_not_balance(void)
{
    static const struct { const char *what; int balanced; } cases[] = {
        {"closed", 1}, {"a facet turned", 0}, {"two facets turned", 0}, {"a facet gone", 0},
        {"a facet and its reverse added", 1}, {"a facet added again", 0}, {"a zero-area facet added", 1},
        {"every facet turned", 1}};
    size_t c, t;
    for (c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        adaslice_mesh m = gen_sphere(5, 24, 12, 0);
        adaslice_grid g = plate_around(&m, 0.2, 0.2, 60, 60);
        adaslice_masker mk;
        int balanced;
        if (c == 1 || c == 2) turn_facet(&m, 33);
        if (c == 2) turn_facet(&m, 34);
        if (c == 3) m.triangle_count--;
        if (c == 4) { repeat_facet(&m, 50, 0); repeat_facet(&m, 50, 1); }
        if (c == 5) repeat_facet(&m, 50, 0);
        if (c == 6) { repeat_facet(&m, 50, 0); m.triangles[3 * m.triangle_count - 1] = m.triangles[3 * m.triangle_count - 2]; }
        for (t = 0; c == 7 && t < m.triangle_count; t++) turn_facet(&m, t);
        balanced = every_edge_balances(&m);
        CHECKF(balanced == cases[c].balanced, "%s: the brute force says %d", cases[c].what, balanced);
        CHECK(layer_masker(&mk, &m, &g, 1, ADASLICE_SLICE_MIDDLE) == ADASLICE_OK);
        CHECKF((mk.sections == 0) == balanced, "%s: sections %d, every edge balances %d", cases[c].what, mk.sections, balanced);
        adaslice_masker_free(&mk);
        gen_free(&m);
    }
}

/* What cannot be split is refused: an open mesh (its sections need every
   facet), bands that do not rise within the grid, a masker already swept. */
static void bands_refuse_what_cannot_be_split(void)
{
    adaslice_mesh m = gen_box(0, 0, 0, 4, 4, 2);
    adaslice_grid g = plate_around(&m, 0.1, 0.1, 60, 60);
    adaslice_masker mk, bands[3];
    adaslice_error e;
    static const uint32_t flat[] = {0, 20, 20, 60}, tall[] = {0, 20, 40, 61}, good[] = {0, 20, 40, 60};
    CHECK(layer_masker(&mk, &m, &g, 1, ADASLICE_SLICE_MIDDLE) == ADASLICE_OK);
    CHECK(adaslice_masker_bands(&mk, flat, 3, bands, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "band 1"));
    CHECK(adaslice_masker_bands(&mk, tall, 3, bands, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "61"));
    CHECK(adaslice_masker_slice(&mk, 1, NULL) == ADASLICE_OK);
    CHECK(adaslice_masker_bands(&mk, good, 3, bands, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "first layer"));
    adaslice_masker_free(&mk);
    m.triangle_count -= 2; /* a face gone */
    CHECK(layer_masker(&mk, &m, &g, 1, ADASLICE_SLICE_MIDDLE) == ADASLICE_OK);
    CHECK(mk.sections && adaslice_masker_bands(&mk, good, 3, bands, &e) == ADASLICE_ERR_UNSUPPORTED && strstr(e.message, "open mesh"));
    adaslice_masker_free(&mk);
    m.triangle_count += 2;
    gen_free(&m);
}

/* An open box (its top face removed): every ray enters through the bottom
   and never leaves. Counted from above it is outside, so nothing is lit, and
   above the top nothing is lit either; the closed box lights its whole
   footprint. */
void test_masks(void)
{
    RUN(sphere_masks_match_contours);
    RUN(sphere_masks_match_contours_on_oblong_pixels);
    RUN(box_with_cylinder_masks_match_contours);
    RUN(overlapping_boxes_stay_lit);
    RUN(bundled_hand_masks_match_contours);
    RUN(rays_through_edges_light_exactly_once);
    RUN(antialiased_masks_cover_the_area);
    RUN(exact_coverage_of_a_sphere_section);
    RUN(exact_coverage_of_slivers);
    RUN(exact_coverage_of_overlapping_shells);
    RUN(pin_thinner_than_a_layer_survives_in_the_envelope);
    RUN(sphere_envelope_is_the_largest_section);
    RUN(sphere_envelope_antialiased);
    RUN(hand_envelope_holds_every_section_of_its_layer);
    RUN(envelope_needs_a_closed_mesh);
    RUN(bands_make_the_whole_maskers_bytes);
    RUN(bands_refuse_what_cannot_be_split);
    RUN(sections_exactly_where_an_edge_does_not_balance);
}
