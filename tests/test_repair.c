/* Mesh repair: meshes broken on purpose (facets turned, shells inside out,
   soups of unshared corners, cracks, cavities wound either way) repair to the
   clean mesh's masks and areas, and the report counts each defect. */
#include "../adaslice.h"
#include "check.h"
#include "meshgen.h"
#include <math.h>
#include <string.h>

static adaslice_mesh_report repaired(adaslice_mesh *m)
{
    adaslice_mesh_report r;
    adaslice_error e;
    CHECKF(adaslice_mesh_repair(m, NULL, &r, &e) == ADASLICE_OK, "repair: %s", e.message);
    return r;
}

static adaslice_mesh copy_of(const adaslice_mesh *m)
{
    adaslice_mesh c = gen_alloc(m->vertex_count, m->triangle_count);
    memcpy(c.vertices, m->vertices, m->vertex_count * 3 * sizeof(float));
    memcpy(c.triangles, m->triangles, m->triangle_count * 3 * sizeof(uint32_t));
    c.vertex_count = m->vertex_count;
    c.triangle_count = m->triangle_count;
    return c;
}

static void turn_facet(adaslice_mesh *m, size_t t)
{
    uint32_t *c = m->triangles + 3 * t, x = c[1];
    c[1] = c[2];
    c[2] = x;
}

/* Every corner its own vertex, as STL stores a mesh. */
static adaslice_mesh soup_of(const adaslice_mesh *m)
{
    adaslice_mesh s = gen_alloc(3 * m->triangle_count, m->triangle_count);
    size_t t;
    int k;
    for (t = 0; t < m->triangle_count; t++) {
        uint32_t c[3];
        for (k = 0; k < 3; k++) {
            const float *v = m->vertices + 3 * (size_t)m->triangles[3 * t + (size_t)k];
            c[k] = gen_vertex(&s, v[0], v[1], v[2]);
        }
        gen_triangle(&s, c[0], c[1], c[2]);
    }
    return s;
}

/* The masks at a few heights, one bit per pixel, and the exact areas. */
typedef struct views {
    unsigned char *bits;
    size_t bytes;
    double area[9];
} views;

static views views_of(const adaslice_mesh *m, const adaslice_mesh *frame)
{
    double lo[3], hi[3], offset[2] = {-0.1 / 3, -0.1 / 7};
    adaslice_grid g;
    adaslice_masker mk;
    adaslice_profile_options po;
    adaslice_profile p;
    adaslice_error e;
    views v;
    int k;
    adaslice_mesh_bounds(frame, lo, hi);
    g = adaslice_grid_plate(frame, 160, 160, (hi[0] - lo[0]) / 140, (hi[1] - lo[1]) / 140, offset);
    memset(&v, 0, sizeof v);
    CHECKF(adaslice_masker_init(&mk, m, &g, NULL, &e) == ADASLICE_OK, "%s", e.message);
    v.bytes = mk.stride * 160;
    v.bits = (unsigned char *)calloc(9, v.bytes);
    memset(&po, 0, sizeof po);
    po.metric = ADASLICE_METRIC_VOLUME;
    CHECKF(adaslice_profile_exact(m, &po, &p, &e) == ADASLICE_OK, "%s", e.message);
    for (k = 0; k < 9; k++) {
        double z = lo[2] + (hi[2] - lo[2]) * (k + 0.41) / 9;
        size_t bin = (size_t)((z - p.z0) / p.bin);
        CHECK(adaslice_masker_slice(&mk, z, &e) == ADASLICE_OK);
        memcpy(v.bits + (size_t)k * v.bytes, mk.image, v.bytes);
        v.area[k] = bin < p.bin_count ? p.area[bin] : -1;
    }
    adaslice_masker_free(&mk);
    adaslice_profile_free(&p);
    return v;
}

static void check_same_views(const char *what, const adaslice_mesh *m, const adaslice_mesh *clean)
{
    views a = views_of(m, clean), b = views_of(clean, clean);
    int k;
    CHECKF(memcmp(a.bits, b.bits, 9 * a.bytes) == 0, "%s: masks differ from the clean mesh's", what);
    for (k = 0; k < 9; k++)
        CHECKF(fabs(a.area[k] - b.area[k]) <= 1e-9 * (1 + fabs(b.area[k])), "%s: area %g, clean %g", what, a.area[k], b.area[k]);
    free(a.bits);
    free(b.bits);
}

static double sphere_volume(const adaslice_mesh *m)
{
    double v = 0;
    size_t t;
    for (t = 0; t < m->triangle_count; t++) {
        const float *a = m->vertices + 3 * m->triangles[3 * t], *b = m->vertices + 3 * m->triangles[3 * t + 1],
                    *c = m->vertices + 3 * m->triangles[3 * t + 2];
        v += ((double)a[0] * ((double)b[1] * c[2] - (double)b[2] * c[1]) + (double)a[1] * ((double)b[2] * c[0] - (double)b[0] * c[2]) +
              (double)a[2] * ((double)b[0] * c[1] - (double)b[1] * c[0])) / 6;
    }
    return v;
}

static void a_clean_mesh_is_left_as_it_is(void)
{
    adaslice_mesh s = gen_sphere(5, 24, 12, 0), c = copy_of(&s);
    adaslice_mesh_report r = repaired(&c);
    CHECK(r.shells == 1 && r.closed_shells == 1 && r.open_edges == 0 && r.nonmanifold_edges == 0);
    CHECK(r.flipped_facets == 0 && r.flipped_shells == 0 && r.degenerate_dropped == 0 && r.welded_nearby == 0);
    CHECK(r.inconsistent_edges == 0);
    CHECK(c.vertex_count == s.vertex_count && c.triangle_count == s.triangle_count);
    CHECK(memcmp(c.triangles, s.triangles, 3 * s.triangle_count * sizeof(uint32_t)) == 0);
    CHECK(memcmp(c.vertices, s.vertices, 3 * s.vertex_count * sizeof(float)) == 0);
    CHECKF(fabs(r.volume - sphere_volume(&s)) < 1e-9 * sphere_volume(&s), "volume %g, want %g", r.volume, sphere_volume(&s));
    gen_free(&s);
    gen_free(&c);
}

static void turned_facets_are_turned_back(void)
{
    adaslice_mesh s = gen_sphere(5, 24, 12, 0), c = copy_of(&s);
    adaslice_mesh_report r;
    size_t t, turned = 0;
    for (t = 0; t < c.triangle_count; t += 3) { turn_facet(&c, t); turned++; }
    r = repaired(&c);
    CHECKF(r.flipped_facets == turned, "%zu turned back, %zu were turned", r.flipped_facets, turned);
    CHECK(r.flipped_shells == 0 && r.open_edges == 0 && r.inconsistent_edges == 0);
    CHECK(memcmp(c.triangles, s.triangles, 3 * s.triangle_count * sizeof(uint32_t)) == 0);
    check_same_views("sphere with a third of its facets turned", &c, &s);
    gen_free(&s);
    gen_free(&c);
}

static void an_inside_out_shell_is_turned_whole(void)
{
    adaslice_mesh s = gen_sphere(5, 24, 12, 0), c = copy_of(&s);
    adaslice_mesh_report r;
    size_t t;
    for (t = 0; t < c.triangle_count; t++) turn_facet(&c, t);
    r = repaired(&c);
    CHECK(r.flipped_shells == 1 && r.flipped_facets == s.triangle_count && r.volume > 0);
    CHECK(memcmp(c.triangles, s.triangles, 3 * s.triangle_count * sizeof(uint32_t)) == 0);
    check_same_views("inside-out sphere", &c, &s);
    gen_free(&s);
    gen_free(&c);
}

static void a_soup_of_corners_is_welded(void)
{
    adaslice_mesh s = gen_sphere(5, 24, 12, 0), soup = soup_of(&s);
    adaslice_mesh_report r = repaired(&soup);
    CHECK(soup.vertex_count == s.vertex_count && soup.triangle_count == s.triangle_count);
    CHECK(r.shells == 1 && r.closed_shells == 1 && r.open_edges == 0 && r.flipped_facets == 0);
    check_same_views("sphere as a soup of corners", &soup, &s);
    gen_free(&s);
    gen_free(&soup);
}

/* The upper half's facets use copies of the equator's vertices moved by
   1e-5 mm: a crack all round that exact welding cannot close. */
static void a_crack_is_stitched(void)
{
    adaslice_mesh s = gen_sphere(5, 24, 12, 0), c = copy_of(&s), plain;
    adaslice_mesh_report r;
    size_t t, moved = 0, ring = 1 + 5 * 24; /* ring 6 of 11 is the equator */
    int k;
    gen_free(&c);
    c = gen_alloc(s.vertex_count + 24, s.triangle_count);
    memcpy(c.vertices, s.vertices, s.vertex_count * 3 * sizeof(float));
    memcpy(c.triangles, s.triangles, s.triangle_count * 3 * sizeof(uint32_t));
    c.vertex_count = s.vertex_count;
    c.triangle_count = s.triangle_count;
    for (k = 0; k < 24; k++) {
        const float *v = s.vertices + 3 * (ring + (size_t)k);
        gen_vertex(&c, v[0] + 1e-5, v[1] - 1e-5, v[2]);
    }
    for (t = 0; t < c.triangle_count; t++) {
        uint32_t *tri = c.triangles + 3 * t;
        double zc = (s.vertices[3 * tri[0] + 2] + s.vertices[3 * tri[1] + 2] + s.vertices[3 * tri[2] + 2]) / 3.0;
        if (zc <= 5) continue;
        for (k = 0; k < 3; k++)
            if (tri[k] >= ring && tri[k] < ring + 24) { tri[k] = (uint32_t)(s.vertex_count + tri[k] - ring); moved++; }
    }
    CHECK(moved > 0);
    plain = copy_of(&c);
    CHECK(adaslice_mesh_repair(&plain, &(adaslice_repair_options){1e-9, NULL}, &r, NULL) == ADASLICE_OK);
    CHECKF(r.open_edges == 48 && r.welded_nearby == 0 && r.closed_shells == 0, "a tolerance of 1e-9 mm: %zu open edges",
           r.open_edges);
    r = repaired(&c);
    CHECKF(r.welded_nearby == 24 && r.open_edges == 0 && r.closed_shells == 1, "%zu welded nearby, %zu open edges",
           r.welded_nearby, r.open_edges);
    CHECK(memcmp(c.triangles, s.triangles, 3 * s.triangle_count * sizeof(uint32_t)) == 0);
    check_same_views("sphere cracked at its equator", &c, &s);
    gen_free(&s);
    gen_free(&c);
    gen_free(&plain);
}

static adaslice_mesh box_with_cavity(int cavity_faces_out)
{
    adaslice_mesh outer = gen_box(0, 0, 0, 10, 8, 6), inner = gen_box(3, 2, 2, 6, 5, 4);
    size_t t;
    if (!cavity_faces_out)
        for (t = 0; t < inner.triangle_count; t++) turn_facet(&inner, t);
    gen_append(&outer, &inner);
    gen_free(&inner);
    return outer;
}

static void a_cavity_stays_hollow(void)
{
    adaslice_mesh hollow = box_with_cavity(0), c = copy_of(&hollow), wrong = box_with_cavity(1);
    adaslice_mesh_report r = repaired(&c);
    double want = 10 * 8 * 6 - 3 * 3 * 2;
    CHECK(r.shells == 2 && r.closed_shells == 2 && r.flipped_facets == 0 && r.flipped_shells == 0);
    CHECKF(fabs(r.volume - want) < 1e-6, "volume %g, want %g", r.volume, want);
    check_same_views("box with a cavity", &c, &hollow);
    r = repaired(&wrong);
    CHECK(r.flipped_shells == 1 && r.flipped_facets == 12);
    CHECKF(fabs(r.volume - want) < 1e-6, "cavity wound outward: volume %g, want %g", r.volume, want);
    check_same_views("box with a cavity wound the wrong way", &wrong, &hollow);
    gen_free(&hollow);
    gen_free(&c);
    gen_free(&wrong);
}

/* A solid island inside the cavity of a box: depth 2, so it faces out. */
static void an_island_in_a_cavity_faces_out(void)
{
    adaslice_mesh m = box_with_cavity(0), island = gen_box(4, 3, 2.5, 5, 4, 3.5), clean;
    size_t t;
    for (t = 0; t < island.triangle_count; t++) turn_facet(&island, t);
    gen_append(&m, &island);
    gen_free(&island);
    clean = box_with_cavity(0);
    island = gen_box(4, 3, 2.5, 5, 4, 3.5);
    gen_append(&clean, &island);
    {
        adaslice_mesh_report r = repaired(&m);
        CHECK(r.shells == 3 && r.flipped_shells == 1 && r.flipped_facets == 12);
        CHECKF(fabs(r.volume - (480 - 18 + 1)) < 1e-6, "volume %g", r.volume);
    }
    check_same_views("an island in a cavity", &m, &clean);
    gen_free(&m);
    gen_free(&island);
    gen_free(&clean);
}

static void separate_and_intersecting_boxes_face_out(void)
{
    adaslice_mesh m = gen_box(0, 0, 0, 4, 4, 4), b = gen_box(6, 0, 0, 10, 4, 4), x = gen_box(2, 2, 1, 8, 3, 3), clean;
    size_t t;
    /* the second box inside out; the third crosses both, inside out too */
    for (t = 0; t < b.triangle_count; t++) turn_facet(&b, t);
    for (t = 0; t < x.triangle_count; t++) turn_facet(&x, t);
    gen_append(&m, &b);
    gen_append(&m, &x);
    {
        adaslice_mesh_report r = repaired(&m);
        CHECKF(r.shells == 3 && r.flipped_shells == 2 && r.flipped_facets == 24, "%zu shells, %zu turned", r.shells,
               r.flipped_shells);
        CHECKF(fabs(r.volume - (64 + 64 + 12)) < 1e-6, "volume %g", r.volume);
    }
    gen_free(&b);
    gen_free(&x);
    clean = gen_box(0, 0, 0, 4, 4, 4);
    b = gen_box(6, 0, 0, 10, 4, 4);
    x = gen_box(2, 2, 1, 8, 3, 3);
    gen_append(&clean, &b);
    gen_append(&clean, &x);
    check_same_views("two boxes and a bar through both", &m, &clean);
    gen_free(&m);
    gen_free(&b);
    gen_free(&x);
    gen_free(&clean);
}

static void defects_are_counted(void)
{
    /* two boxes sharing an edge: that edge has four facets */
    adaslice_mesh m = gen_box(0, 0, 0, 1, 1, 1), b = gen_box(1, 1, 0, 2, 2, 1), cut;
    adaslice_mesh_report r;
    uint32_t a0, a1, a2;
    size_t kept = 0, t;
    gen_append(&m, &b);
    gen_free(&b);
    r = repaired(&m);
    CHECKF(r.nonmanifold_edges == 1 && r.open_edges == 0 && r.shells == 2 && r.closed_shells == 2, "%zu non-manifold edges",
           r.nonmanifold_edges);
    gen_free(&m);
    /* a box missing one facet: three open edges, no closed shell */
    cut = gen_box(0, 0, 0, 1, 1, 1);
    cut.triangle_count--;
    r = repaired(&cut);
    CHECK(r.open_edges == 3 && r.closed_shells == 0 && r.shells == 1);
    gen_free(&cut);
    /* a sliver whose corners weld into one point is dropped */
    cut = gen_box(0, 0, 0, 10, 10, 10);
    cut.vertices = (float *)realloc(cut.vertices, (cut.vertex_count + 3) * 3 * sizeof(float));
    cut.triangles = (uint32_t *)realloc(cut.triangles, (cut.triangle_count + 1) * 3 * sizeof(uint32_t));
    a0 = gen_vertex(&cut, 20, 20, 20);
    a1 = gen_vertex(&cut, 20.0001, 20, 20);
    a2 = gen_vertex(&cut, 20, 20.0001, 20);
    gen_triangle(&cut, a0, a1, a2);
    r = repaired(&cut);
    CHECKF(r.degenerate_dropped == 1 && cut.triangle_count == 12 && cut.vertex_count == 8, "%zu dropped, %zu facets left",
           r.degenerate_dropped, cut.triangle_count);
    for (t = 0; t < cut.triangle_count; t++) kept += cut.triangles[3 * t] < cut.vertex_count;
    CHECK(kept == 12);
    gen_free(&cut);
}

/* Zero-area facets sealing T-junctions (a CAD export's) are collapsed onto
   their long edge, a stack of them too, and the box stays closed with its
   volume: dropping them left three open edges each. */
static void slivers_sealing_t_junctions_are_collapsed(void)
{
    int middles;
    for (middles = 1; middles <= 3; middles++) {
        adaslice_mesh m = gen_tjunction_box(middles);
        size_t facets = m.triangle_count;
        adaslice_mesh_report r = repaired(&m);
        CHECKF(r.open_edges == 0 && r.closed_shells == 1 && r.shells == 1 && r.slivers_collapsed == (size_t)middles &&
               r.degenerate_dropped == 0 && m.triangle_count == facets && fabs(r.volume - 1000) < 1e-6,
               "%d middle points: %zu open edges, %zu collapsed, %zu dropped, volume %g", middles, r.open_edges,
               r.slivers_collapsed, r.degenerate_dropped, r.volume);
        gen_free(&m);
    }
}

/* An open scan wound inward: the shell turns to face out by its volume about
   its own centroid. */
static void an_open_inside_out_scan_faces_out(void)
{
    adaslice_mesh s = gen_sphere(5, 24, 12, 0);
    adaslice_mesh_report r;
    size_t t;
    s.triangle_count -= 24; /* gen_sphere's last facets: a strip down one side */
    for (t = 0; t < s.triangle_count; t++) turn_facet(&s, t);
    r = repaired(&s);
    CHECK(r.open_edges > 0 && r.closed_shells == 0 && r.flipped_shells == 1 && r.volume > 0);
    gen_free(&s);
}

/* Repair's work grows with the facets, not with the square of the facets on
   one edge: edge_steps counts the facets met walking edges, which a repair
   judging each facet of an edge against every other made quadratic (an OBJ
   face of 200,000 references loaded in a minute). */
static void many_facets_on_one_edge_cost_linear_work(void)
{
    enum { PAGES = 20000, REFS = 200000 };
    adaslice_mesh book = gen_alloc(2 + PAGES, PAGES), fan;
    adaslice_mesh_report r;
    adaslice_error e;
    size_t i, n = 0;
    char *obj = (char *)malloc(64 + 2 * REFS);
    uint32_t a = gen_vertex(&book, 0, 0, 0), b = gen_vertex(&book, 0, 0, 1);
    /* a book: every page a triangle on the spine a-b, each its own shell */
    for (i = 0; i < PAGES; i++) {
        double t = 2 * M_PI * (double)i / PAGES;
        gen_triangle(&book, a, b, gen_vertex(&book, cos(t), sin(t), 0.5));
    }
    r = repaired(&book);
    CHECKF(r.nonmanifold_edges == 1 && r.open_edges == 2 * PAGES && r.shells == PAGES && r.closed_shells == 0,
           "%zu non-manifold, %zu open edges, %zu shells", r.nonmanifold_edges, r.open_edges, r.shells);
    CHECKF(r.edge_steps <= 9 * (size_t)PAGES, "%zu steps for %d facets", r.edge_steps, PAGES);
    gen_free(&book);
    /* one OBJ face going round a pyramid's five vertices: its fan is four
       facets over and over, each of its eight edges shared by thousands */
    if (!obj) abort();
    n += (size_t)sprintf(obj, "v 0 0 0\nv 10 0 0\nv 10 10 0\nv 0 10 0\nv 5 5 10\nf 1");
    for (i = 1; i < REFS; i++) n += (size_t)sprintf(obj + n, " %d", 2 + (int)(i % 4));
    CHECKF(adaslice_mesh_load(obj, n, NULL, &fan, &e) == ADASLICE_OK, "%s", e.message);
    CHECK(fan.triangle_count == REFS - 2);
    r = repaired(&fan);
    CHECKF(r.nonmanifold_edges == 8 && r.open_edges == 0, "%zu non-manifold, %zu open edges", r.nonmanifold_edges,
           r.open_edges);
    CHECKF(r.edge_steps <= 9 * fan.triangle_count, "%zu steps for %zu facets", r.edge_steps, fan.triangle_count);
    adaslice_mesh_free(&fan);
    free(obj);
}

static void bad_repairs_are_refused(void)
{
    adaslice_mesh m = gen_box(0, 0, 0, 1, 1, 1);
    adaslice_error e;
    CHECK(adaslice_mesh_repair(&m, &(adaslice_repair_options){-1, NULL}, NULL, &e) == ADASLICE_ERR_ARGUMENT);
    CHECK(strstr(e.message, "tolerance") != NULL);
    m.triangles[5] = 99;
    CHECK(adaslice_mesh_repair(&m, NULL, NULL, &e) == ADASLICE_ERR_INDEX);
    CHECK(adaslice_mesh_repair(NULL, NULL, NULL, &e) == ADASLICE_ERR_ARGUMENT);
    gen_free(&m);
}

void test_repair(void)
{
    RUN(a_clean_mesh_is_left_as_it_is);
    RUN(turned_facets_are_turned_back);
    RUN(an_inside_out_shell_is_turned_whole);
    RUN(a_soup_of_corners_is_welded);
    RUN(a_crack_is_stitched);
    RUN(a_cavity_stays_hollow);
    RUN(an_island_in_a_cavity_faces_out);
    RUN(separate_and_intersecting_boxes_face_out);
    RUN(defects_are_counted);
    RUN(an_open_inside_out_scan_faces_out);
    RUN(many_facets_on_one_edge_cost_linear_work);
    RUN(slivers_sealing_t_junctions_are_collapsed);
    RUN(bad_repairs_are_refused);
}
