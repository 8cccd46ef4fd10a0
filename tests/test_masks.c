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
    CHECKF(adaslice_masker_init(&mk, m, &g, &(adaslice_mask_options){1, NULL}, &e) == ADASLICE_OK, "%s: %s", what, e.message);
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
    CHECK(adaslice_masker_init(&mk, &box, &g, &(adaslice_mask_options){1, NULL}, NULL) == ADASLICE_OK);
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

/* 8-bit masks: grey = 255 * covered rays / s^2, so their sum is the covered
   area; a pixel deep inside is 255, far outside 0. */
static void antialiased_masks_cover_the_area(void)
{
    adaslice_mesh m = gen_cylinder(5, 4, 256, 0);
    adaslice_grid g = plate_around(&m, 0.1, 0.1, 140, 130);
    adaslice_masker mk;
    size_t p, sum = 0;
    double poly = 256 / 2.0 * 25 * sin(2 * M_PI / 256);
    CHECK(adaslice_masker_init(&mk, &m, &g, &(adaslice_mask_options){4, NULL}, NULL) == ADASLICE_OK);
    CHECK(adaslice_masker_slice(&mk, 2, NULL) == ADASLICE_OK);
    for (p = 0; p < (size_t)g.width * g.height; p++) sum += mk.image[p];
    /* rays: 0.025 mm apart; the circle's 31.4 mm of edge misjudges at most a ray's diagonal */
    CHECKF(fabs(mk.lit * 0.01 - poly) <= 2 * M_PI * 5 * 0.025 * sqrt(2.0), "lit %g, area %g", mk.lit * 0.01, poly);
    CHECKF(fabs(sum / 255.0 - mk.lit) <= 0.5 * 0.01 * (double)g.width * g.height / 16 + 1, "grey sum %g, lit %g", sum / 255.0, mk.lit);
    CHECK(mk.image[(size_t)(g.height / 2) * mk.stride + (size_t)(g.width / 2)] == 255 && mk.image[0] == 0);
    adaslice_masker_free(&mk);
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
}
