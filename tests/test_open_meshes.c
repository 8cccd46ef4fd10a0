/* Masks and areas of meshes that are not closed: a sphere with its cap cut
   away, one with a hole punched in its side, open shells overlapping, against
   the closed sphere's masks (rays, exact) and the contours. The manual's
   promise: pixels differ from the closed part's only between each gap's chord
   and the missing surface. */
#include "../adaslice.h"
#include "check.h"
#include "contour_length.h"
#include "meshgen.h"
#include <math.h>
#include <string.h>

enum { W = 240, H = 240 };
static const double PITCH = 0.05;

static int bit(const unsigned char *image, size_t stride, int i, int j)
{
    return (image[(size_t)j * stride + (size_t)(i >> 3)] >> (7 - (i & 7))) & 1;
}

/* m without the facets `drop` says to drop. */
static adaslice_mesh without(const adaslice_mesh *m, int (*drop)(const adaslice_mesh *, size_t, const double *), const double *arg)
{
    adaslice_mesh c = gen_alloc(m->vertex_count, m->triangle_count);
    size_t t;
    memcpy(c.vertices, m->vertices, m->vertex_count * 3 * sizeof(float));
    c.vertex_count = m->vertex_count;
    for (t = 0; t < m->triangle_count; t++)
        if (!drop(m, t, arg)) gen_triangle(&c, m->triangles[3 * t], m->triangles[3 * t + 1], m->triangles[3 * t + 2]);
    return c;
}

static void centroid(const adaslice_mesh *m, size_t t, double c[3])
{
    int k, i;
    for (k = 0; k < 3; k++) {
        c[k] = 0;
        for (i = 0; i < 3; i++) c[k] += m->vertices[3 * m->triangles[3 * t + (size_t)i] + (size_t)k] / 3.0;
    }
}

/* the facets above z = arg[0] */
static int above(const adaslice_mesh *m, size_t t, const double *arg)
{
    double c[3];
    centroid(m, t, c);
    return c[2] > arg[0];
}

/* the facets within arg[3] of (arg[0], arg[1], arg[2]) */
static int near_point(const adaslice_mesh *m, size_t t, const double *arg)
{
    double c[3];
    centroid(m, t, c);
    return hypot(hypot(c[0] - arg[0], c[1] - arg[1]), c[2] - arg[2]) < arg[3];
}

static adaslice_grid plate(void)
{
    adaslice_grid g;
    memset(&g, 0, sizeof g);
    g.axis = ADASLICE_AXIS_Z;
    g.width = W;
    g.height = H;
    g.pitch[0] = g.pitch[1] = PITCH;
    g.origin[0] = -6 + PITCH / 3;
    g.origin[1] = -6 + PITCH / 7;
    return g;
}

/* Compares the masks of `open` with those of `closed` at n heights: a
   differing pixel must lie within `reach` mm of one of the `holes` (x, y, z,
   radius each) or within a pixel of the closed part's contour; the lit areas
   differ by at most `slack` mm^2 (plus a pixel along the contour) and, unless
   shells overlap (A counts them twice), the open mesh's exact A(z) tracks its
   own lit area. */
static void compare(const char *what, const adaslice_mesh *open, const adaslice_mesh *closed, const double *z, int n,
                    const double *holes, int hole_count, double reach, double slack, int supersample, int overlapping)
{
    adaslice_grid g = plate();
    adaslice_masker a, b;
    adaslice_contours c, oc;
    adaslice_profile_options po;
    adaslice_profile pa;
    adaslice_error e;
    adaslice_mesh welded = gen_alloc(closed->vertex_count, closed->triangle_count);
    int k;
    memcpy(welded.vertices, closed->vertices, closed->vertex_count * 3 * sizeof(float));
    memcpy(welded.triangles, closed->triangles, closed->triangle_count * 3 * sizeof(uint32_t));
    welded.vertex_count = closed->vertex_count;
    welded.triangle_count = closed->triangle_count;
    CHECKF(adaslice_masker_init(&a, open, &g, &(adaslice_mask_options){supersample, NULL, ADASLICE_SLICE_MIDDLE, 0, NULL, 0}, &e) == ADASLICE_OK, "%s", e.message);
    CHECKF(a.gaps != NULL, "%s: the open mesh is read by rays", what);
    CHECK(adaslice_masker_init(&b, closed, &g, &(adaslice_mask_options){supersample, NULL, ADASLICE_SLICE_MIDDLE, 0, NULL, 0}, &e) == ADASLICE_OK && !b.gaps);
    CHECK(adaslice_contours_slice(&welded, z, (size_t)n, NULL, &c, &e) == ADASLICE_OK);
    CHECKF(adaslice_contours_slice(open, z, (size_t)n, NULL, &oc, &e) == ADASLICE_OK, "%s: %s", what, e.message);
    memset(&po, 0, sizeof po);
    po.metric = ADASLICE_METRIC_VOLUME;
    po.bin = 0.001;
    CHECK(adaslice_profile_exact(open, &po, &pa, &e) == ADASLICE_OK);
    for (k = 0; k < n; k++) {
        int i, j;
        size_t wrong = 0, unlike = 0;
        double perimeter = 0, area;
        size_t bin = (size_t)((z[k] - pa.z0) / pa.bin);
        CHECKF(adaslice_masker_slice(&a, z[k], &e) == ADASLICE_OK, "%s: %s", what, e.message);
        CHECK(adaslice_masker_slice(&b, z[k], &e) == ADASLICE_OK);
        for (j = 0; j < H; j++)
            for (i = 0; i < W; i++) {
                double x = g.origin[0] + (i + 0.5) * PITCH, y = g.origin[1] + (j + 0.5) * PITCH;
                int differs = supersample > 1 ? a.image[(size_t)j * a.stride + (size_t)i] != b.image[(size_t)j * b.stride + (size_t)i]
                                              : bit(a.image, a.stride, i, j) != bit(b.image, b.stride, i, j);
                int h, at_hole = 0;
                /* the open mesh's contours, closed by their chords, light what its mask lights */
                if (supersample == 1 && adaslice_contours_distance(&oc, (size_t)k, x, y) > PITCH * 1.5)
                    unlike += (adaslice_contours_winding(&oc, (size_t)k, x, y) > 0) != bit(a.image, a.stride, i, j);
                if (!differs || adaslice_contours_distance(&c, (size_t)k, x, y) <= PITCH * 1.5) continue;
                for (h = 0; h < hole_count; h++) at_hole |= hypot(x - holes[4 * h], y - holes[4 * h + 1]) <= reach;
                wrong += !at_hole;
            }
        CHECKF(unlike == 0, "%s at z %g: %zu pixels lit by the mask and not inside the contours or the other way",
               what, z[k], unlike);
        perimeter = contour_length(&c, (size_t)k);
        CHECKF(wrong == 0, "%s at z %g: %zu pixels differ from the closed mesh's away from the gap", what, z[k], wrong);
        CHECKF(fabs(a.lit - b.lit) * PITCH * PITCH <= slack + perimeter * PITCH * 1.5, "%s at z %g: lit %g mm^2, closed %g mm^2",
               what, z[k], a.lit * PITCH * PITCH, b.lit * PITCH * PITCH);
        area = bin < pa.bin_count ? pa.area[bin] : 0;
        CHECKF(overlapping || fabs(a.lit * PITCH * PITCH - area) <= perimeter * PITCH * 1.5 + perimeter * pa.bin + 1e-9,
               "%s at z %g: lit %g mm^2, its A(z) %g mm^2", what, z[k], a.lit * PITCH * PITCH, area);
    }
    adaslice_masker_free(&a);
    adaslice_masker_free(&b);
    adaslice_contours_free(&c);
    adaslice_contours_free(&oc);
    adaslice_profile_free(&pa);
    gen_free(&welded);
}

static void a_sphere_with_its_cap_cut_away_keeps_its_masks_below_the_cut(void)
{
    adaslice_mesh s = gen_sphere(5, 48, 24, 0);
    double cut = 9.0, z[7] = {0.4, 2.0, 3.75, 5.0, 6.6, 8.0, 8.9};
    adaslice_mesh bowl = without(&s, above, &cut);
    adaslice_grid g = plate();
    adaslice_masker mk;
    compare("sphere without its cap", &bowl, &s, z, 7, NULL, 0, 0, 0, 1, 0);
    compare("sphere without its cap, anti-aliased", &bowl, &s, z, 7, NULL, 0, 0, 0, 4, 0);
    /* above the cut there is no material: nothing is lit */
    CHECK(adaslice_masker_init(&mk, &bowl, &g, NULL, NULL) == ADASLICE_OK);
    CHECK(adaslice_masker_slice(&mk, 9.8, NULL) == ADASLICE_OK && mk.lit == 0);
    adaslice_masker_free(&mk);
    gen_free(&s);
    gen_free(&bowl);
}

static void a_sphere_with_a_hole_differs_only_at_the_hole(void)
{
    adaslice_mesh s = gen_sphere(5, 48, 24, 0);
    double hole[4] = {5, 0, 5, 1.5}, z[8] = {0.5, 2.5, 3.9, 4.6, 5.0, 5.7, 6.3, 9.0};
    adaslice_mesh holed = without(&s, near_point, hole);
    CHECK(holed.triangle_count < s.triangle_count);
    /* the chord cuts off at most a 3 mm chord's segment of a 5 mm circle */
    compare("sphere with a hole", &holed, &s, z, 8, hole, 1, 1.7, 0.5, 1, 0);
    compare("sphere with a hole, anti-aliased", &holed, &s, z, 8, hole, 1, 1.7, 0.5, 4, 0);
    gen_free(&s);
    gen_free(&holed);
}

/* Two holes on opposite sides: each section has two gaps, joined end to
   nearest start (closing each by its own chord would leave the middle dark). */
static void two_gaps_in_one_section_are_joined_across(void)
{
    adaslice_mesh s = gen_sphere(5, 48, 24, 0), once, twice;
    double holes[8] = {5, 0, 5, 1.5, -5, 0, 5, 1.5}, z[3] = {4.6, 5.0, 5.4};
    once = without(&s, near_point, holes);
    twice = without(&once, near_point, holes + 4);
    {
        adaslice_grid g = plate();
        adaslice_masker mk;
        int i = (int)((0 - g.origin[0]) / PITCH), j = (int)((0 - g.origin[1]) / PITCH);
        CHECK(adaslice_masker_init(&mk, &twice, &g, NULL, NULL) == ADASLICE_OK);
        CHECK(adaslice_masker_slice(&mk, 5.0, NULL) == ADASLICE_OK);
        CHECKF(bit(mk.image, mk.stride, i, j), "the middle of a section with two gaps is dark");
        adaslice_masker_free(&mk);
    }
    compare("sphere with two holes", &twice, &s, z, 3, holes, 2, 1.7, 1.0, 1, 0);
    gen_free(&s);
    gen_free(&once);
    gen_free(&twice);
}

/* Sections with fewer gaps below, more at the equator: the join's grid
   grows from layer to layer within the room it had (nine cells in the room
   four left once wrote past it, under ASan). */
static void gaps_that_multiply_with_height_are_joined(void)
{
    adaslice_mesh s = gen_sphere(5, 48, 24, 0), holed = gen_alloc(0, 0), next;
    double holes[6 * 4], z[5] = {2.5, 3.9, 4.6, 5.0, 5.4};
    int k;
    gen_append(&holed, &s);
    for (k = 0; k < 6; k++) {
        double a = k < 4 ? k * 3.14159265358979 / 2 + 0.4 : (k - 4) * 3.14159265358979, r = k < 4 ? 5 : 4.33;
        holes[4 * k] = r * cos(a);
        holes[4 * k + 1] = r * sin(a);
        holes[4 * k + 2] = k < 4 ? 5 : 2.5;
        holes[4 * k + 3] = 1.0;
        next = without(&holed, near_point, holes + 4 * k);
        gen_free(&holed);
        holed = next;
    }
    CHECK(holed.triangle_count < s.triangle_count);
    compare("sphere with six holes", &holed, &s, z, 5, holes, 6, 1.2, 2.5, 1, 0);
    gen_free(&s);
    gen_free(&holed);
}

static void overlapping_open_shells_stay_lit(void)
{
    adaslice_mesh a = gen_sphere(3, 40, 20, 0), b = gen_sphere(3, 40, 20, 0), pair, closed;
    double holes[8] = {-3, 0, 3, 1.0, 4.5, 0, 3, 1.0}, z[4] = {0.8, 2.2, 3.0, 4.4};
    size_t v;
    adaslice_mesh oa, ob;
    for (v = 0; v < b.vertex_count; v++) b.vertices[3 * v] += 1.5f; /* overlapping by 4.5 mm */
    oa = without(&a, near_point, holes);
    ob = without(&b, near_point, holes + 4);
    pair = gen_alloc(0, 0);
    gen_append(&pair, &oa);
    gen_append(&pair, &ob);
    closed = gen_alloc(0, 0);
    gen_append(&closed, &a);
    gen_append(&closed, &b);
    compare("two overlapping spheres with holes", &pair, &closed, z, 4, holes, 2, 1.2, 0.3, 1, 1);
    gen_free(&a); gen_free(&b); gen_free(&oa); gen_free(&ob); gen_free(&pair); gen_free(&closed);
}

/* Rays would read nothing under an open top; the sections are whole below it. */
static void an_open_box_is_lit_below_its_rim(void)
{
    adaslice_mesh box = gen_box(-4, -3, 0, 4, 3, 2);
    double rim = 1.99;
    adaslice_mesh open = without(&box, above, &rim);
    adaslice_grid g = plate();
    adaslice_masker mk;
    CHECK(open.triangle_count == 10);
    CHECK(adaslice_masker_init(&mk, &open, &g, NULL, NULL) == ADASLICE_OK);
    CHECK(adaslice_masker_slice(&mk, 1, NULL) == ADASLICE_OK && fabs(mk.lit * PITCH * PITCH - 48) < 28 * PITCH);
    CHECK(adaslice_masker_slice(&mk, 3, NULL) == ADASLICE_OK && mk.lit == 0);
    adaslice_masker_free(&mk);
    gen_free(&box);
    gen_free(&open);
}

/* The sampled profile cannot read an open mesh along rays either: its areas
   are the sections', equal to the exact profile's. */
static void sampled_areas_of_an_open_mesh_are_its_sections(void)
{
    adaslice_mesh s = gen_sphere(5, 48, 24, 0);
    double hole[4] = {5, 0, 5, 1.5};
    adaslice_mesh holed = without(&s, near_point, hole);
    adaslice_profile_options po;
    adaslice_profile ex, sa, closed;
    size_t i;
    memset(&po, 0, sizeof po);
    po.metric = ADASLICE_METRIC_AREA;
    po.bin = 0.01;
    CHECK(adaslice_profile_exact(&holed, &po, &ex, NULL) == ADASLICE_OK);
    CHECK(adaslice_profile_sampled(&holed, &po, &sa, NULL) == ADASLICE_OK);
    CHECK(adaslice_profile_exact(&s, &po, &closed, NULL) == ADASLICE_OK);
    CHECK(ex.bin_count == sa.bin_count && ex.bin_count == closed.bin_count);
    for (i = 0; i < ex.bin_count; i++) {
        CHECKF(fabs(ex.area[i] - sa.area[i]) <= 1e-9 * (1 + ex.area[i]), "bin %zu: sampled %g, exact %g", i, sa.area[i], ex.area[i]);
        CHECKF(ex.area[i] <= closed.area[i] + 1e-9 && ex.area[i] >= closed.area[i] - 0.5, "bin %zu: open %g, closed %g", i,
               ex.area[i], closed.area[i]);
    }
    adaslice_profile_free(&ex);
    adaslice_profile_free(&sa);
    adaslice_profile_free(&closed);
    gen_free(&s);
    gen_free(&holed);
}

void test_open_meshes(void)
{
    RUN(a_sphere_with_its_cap_cut_away_keeps_its_masks_below_the_cut);
    RUN(a_sphere_with_a_hole_differs_only_at_the_hole);
    RUN(two_gaps_in_one_section_are_joined_across);
    RUN(gaps_that_multiply_with_height_are_joined);
    RUN(overlapping_open_shells_stay_lit);
    RUN(an_open_box_is_lit_below_its_rim);
    RUN(sampled_areas_of_an_open_mesh_are_its_sections);
}
