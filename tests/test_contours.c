/* Contours: closed polygons whose signed areas match the tessellated solids'
   own cross-sections, the vertex-on-plane rule, holes, welding, open meshes,
   overlaps, the sweep's work bound, the exact winding query, and the bundled
   hand against the exact area profile. */
#include "../adaslice.h"
#include "check.h"
#include "meshgen.h"
#include "failing_alloc.h"
#include <float.h>
#include <math.h>
#include <string.h>

/* ------------------------------------------------------------ helpers */

static adaslice_contours slice(const adaslice_mesh *m, const double *h, size_t k)
{
    adaslice_contours c;
    adaslice_error e;
    if (adaslice_contours_slice(m, h, k, NULL, &c, &e) != ADASLICE_OK) {
        CHECKF(0, "contours failed: %s", e.message);
        memset(&c, 0, sizeof c);
    }
    return c;
}

static size_t polygons_at(const adaslice_contours *c, size_t i)
{
    return c->first_polygon[i + 1] - c->first_polygon[i];
}

static double polygon_area(const adaslice_contours *c, size_t p)
{
    const double *pt = c->points + 2 * c->polygons[p].first;
    size_t n = c->polygons[p].count, k;
    double a = 0;
    for (k = 0; k < n; k++) {
        const double *u = pt + 2 * k, *v = pt + 2 * ((k + 1) % n);
        a += u[0] * v[1] - u[1] * v[0];
    }
    return a / 2;
}

static double area_at(const adaslice_contours *c, size_t i)
{
    size_t p;
    double a = 0;
    for (p = c->first_polygon[i]; p < c->first_polygon[i + 1]; p++) a += polygon_area(c, p);
    return a;
}

static size_t open_polygons(const adaslice_contours *c)
{
    size_t p, n = 0;
    for (p = 0; p < c->polygon_count; p++) n += !c->polygons[p].closed;
    return n;
}

/* Shoelace over the points where the plane meets the given mesh edges, in order. */
static double edge_polygon_area(const adaslice_mesh *m, const uint32_t (*edge)[2], int n, double z)
{
    double a = 0, first[2] = {0, 0}, prev[2] = {0, 0};
    int k;
    for (k = 0; k <= n; k++) {
        const float *p = m->vertices + 3 * edge[k % n][0], *q = m->vertices + 3 * edge[k % n][1];
        double u = (z - p[2]) / ((double)q[2] - p[2]);
        double x = p[0] + u * ((double)q[0] - p[0]), y = p[1] + u * ((double)q[1] - p[1]);
        if (k == 0) { first[0] = x; first[1] = y; }
        else a += prev[0] * y - prev[1] * x;
        prev[0] = x; prev[1] = y;
    }
    (void)first;
    return a / 2;
}

/* A second, independent route to the section's area: every triangle's own cut,
   turned along z x n, summed by Green's theorem. */
static double green_area(const adaslice_mesh *m, double z)
{
    size_t t;
    double a = 0;
    for (t = 0; t < m->triangle_count; t++) {
        const float *v[3];
        double pts[2][2], e1[3], e2[3], nx, ny;
        int k, found = 0;
        for (k = 0; k < 3; k++) v[k] = m->vertices + 3 * m->triangles[3 * t + k];
        for (k = 0; k < 3 && found < 2; k++) {
            const float *p = v[k], *q = v[(k + 1) % 3];
            if (p[2] > q[2]) { const float *s = p; p = q; q = s; }
            if (p[2] <= z && z < q[2]) {
                double u = (z - p[2]) / ((double)q[2] - p[2]);
                pts[found][0] = p[0] + u * ((double)q[0] - p[0]);
                pts[found][1] = p[1] + u * ((double)q[1] - p[1]);
                found++;
            }
        }
        if (found < 2) continue;
        for (k = 0; k < 3; k++) { e1[k] = (double)v[1][k] - v[0][k]; e2[k] = (double)v[2][k] - v[0][k]; }
        nx = e1[1] * e2[2] - e1[2] * e2[1];
        ny = e1[2] * e2[0] - e1[0] * e2[2];
        if ((pts[1][0] - pts[0][0]) * -ny + (pts[1][1] - pts[0][1]) * nx < 0)
            a -= pts[0][0] * pts[1][1] - pts[0][1] * pts[1][0];
        else
            a += pts[0][0] * pts[1][1] - pts[0][1] * pts[1][0];
    }
    return a / 2;
}

/* Vertex j of ring r of gen_sphere (0: the top pole, stacks: the bottom one). */
static uint32_t ring_index(const adaslice_mesh *m, int slices, int stacks, int r, int j)
{
    if (r == 0) return 0;
    if (r == stacks) return (uint32_t)m->vertex_count - 1;
    return (uint32_t)(1 + (r - 1) * slices + j % slices);
}

static double ring_z(const adaslice_mesh *m, int slices, int stacks, int r)
{
    return m->vertices[3 * ring_index(m, slices, stacks, r, 0) + 2];
}

/* A prism over a convex polygon given counter-clockwise, from z0 to z1. */
static adaslice_mesh gen_prism(const double (*xy)[2], int n, double z0, double z1)
{
    adaslice_mesh m = gen_alloc((size_t)(2 * n), (size_t)(4 * n - 4));
    int i;
    for (i = 0; i < n; i++) { gen_vertex(&m, xy[i][0], xy[i][1], z0); gen_vertex(&m, xy[i][0], xy[i][1], z1); }
    for (i = 0; i < n; i++) {
        uint32_t b0 = (uint32_t)(2 * i), b1 = (uint32_t)(2 * ((i + 1) % n));
        gen_triangle(&m, b0, b1, b1 + 1);
        gen_triangle(&m, b0, b1 + 1, b0 + 1);
        if (i >= 2) {
            gen_triangle(&m, 0, b0, (uint32_t)(2 * (i - 1)));
            gen_triangle(&m, 1, (uint32_t)(2 * (i - 1) + 1), b0 + 1);
        }
    }
    return m;
}

/* The square [0, 10]^2 with the square hole [3, 7]^2, from z = 0 to 5. */
static adaslice_mesh gen_frame(void)
{
    static const double outer[4][2] = {{0, 0}, {10, 0}, {10, 10}, {0, 10}};
    static const double inner[4][2] = {{3, 3}, {7, 3}, {7, 7}, {3, 7}};
    adaslice_mesh m = gen_alloc(16, 32);
    int i;
    /* vertex 4*s + {0: outer bottom, 1: outer top, 2: inner bottom, 3: inner top} */
    for (i = 0; i < 4; i++) {
        gen_vertex(&m, outer[i][0], outer[i][1], 0); gen_vertex(&m, outer[i][0], outer[i][1], 5);
        gen_vertex(&m, inner[i][0], inner[i][1], 0); gen_vertex(&m, inner[i][0], inner[i][1], 5);
    }
    for (i = 0; i < 4; i++) {
        uint32_t o = (uint32_t)(4 * i), p = (uint32_t)(4 * ((i + 1) % 4));
        gen_triangle(&m, o, p, p + 1);         /* outer wall, facing out */
        gen_triangle(&m, o, p + 1, o + 1);
        gen_triangle(&m, p + 2, o + 2, o + 3); /* inner wall, facing the hole */
        gen_triangle(&m, p + 2, o + 3, p + 3);
        gen_triangle(&m, o + 1, p + 1, p + 3); /* top, facing +z */
        gen_triangle(&m, o + 1, p + 3, o + 3);
        gen_triangle(&m, o, p + 2, p);         /* bottom, facing -z */
        gen_triangle(&m, o, o + 2, p + 2);
    }
    return m;
}

/* Every triangle with its own three vertices, as STL stores them. */
static adaslice_mesh soup_of(const adaslice_mesh *m)
{
    adaslice_mesh s = gen_alloc(3 * m->triangle_count, m->triangle_count);
    size_t i;
    for (i = 0; i < 3 * m->triangle_count; i++) {
        const float *v = m->vertices + 3 * m->triangles[i];
        memcpy(s.vertices + 3 * i, v, 3 * sizeof(float));
        s.triangles[i] = (uint32_t)i;
    }
    s.vertex_count = 3 * m->triangle_count;
    s.triangle_count = m->triangle_count;
    return s;
}

static void drop_triangles(adaslice_mesh *m, size_t first, size_t count)
{
    memmove(m->triangles + 3 * first, m->triangles + 3 * (first + count),
            3 * (m->triangle_count - first - count) * sizeof(uint32_t));
    m->triangle_count -= count;
}

/* -------------------------------------------------------------- cases */

static void solids_give_closed_polygons_of_the_right_area(void)
{
    enum { K = 97, SLICES = 48, STACKS = 24 };
    adaslice_mesh m[3];
    double H[3] = {20, 7, 9};
    int s;
    m[0] = gen_sphere(10, SLICES, STACKS, 0);
    m[1] = gen_cylinder(5, 7, SLICES, 0);
    m[2] = gen_cone(6, 9, SLICES, 0);
    for (s = 0; s < 3; s++) {
        double h[K], worst = 0, worst_green = 0;
        adaslice_contours c;
        size_t i;
        for (i = 0; i < K; i++) h[i] = H[s] * ((double)i + 0.37) / K;
        c = slice(&m[s], h, K);
        CHECKF(open_polygons(&c) == 0, "solid %d: %zu open polygons", s, open_polygons(&c));
        for (i = 0; i < K; i++) {
            uint32_t edge[2 * SLICES][2];
            int j, n = 0, k = 0;
            double ref, a = area_at(&c, i);
            CHECKF(polygons_at(&c, i) == 1, "solid %d z %g: %zu polygons", s, h[i], polygons_at(&c, i));
            if (s == 0) { /* the meridians of the band that holds z */
                while (k + 1 < STACKS && ring_z(&m[0], SLICES, STACKS, k + 1) > h[i]) k++;
                for (j = 0; j < SLICES; j++) {
                    edge[n][0] = ring_index(&m[0], SLICES, STACKS, k + 1, j);
                    edge[n++][1] = ring_index(&m[0], SLICES, STACKS, k, j);
                }
            } else {
                for (j = 0; j < SLICES; j++, n++) { /* cylinder wall edges; cone edges to the apex */
                    edge[n][0] = (uint32_t)(s == 1 ? 2 + 2 * j : 2 + j);
                    edge[n][1] = s == 1 ? edge[n][0] + 1 : 0;
                }
            }
            ref = edge_polygon_area(&m[s], (const uint32_t(*)[2])edge, n, h[i]);
            if (fabs(a - ref) / ref > worst) worst = fabs(a - ref) / ref;
            if (fabs(a - green_area(&m[s], h[i])) / ref > worst_green)
                worst_green = fabs(a - green_area(&m[s], h[i])) / ref;
        }
        CHECKF(worst < 1e-9, "solid %d: area %g relative from the tessellated polygon", s, worst);
        CHECKF(worst_green < 1e-12, "solid %d: area %g relative from the per-triangle sum", s, worst_green);
        adaslice_contours_free(&c);
        gen_free(&m[s]);
    }
}

/* A plane exactly through a ring of vertices gives the section just above it:
   the ring's own polygon, each vertex once; nothing at a top, nothing at a
   lowest vertex (the loop collapses to a point). */
static void heights_at_vertices_give_the_section_just_above(void)
{
    enum { SLICES = 16, STACKS = 9 };
    adaslice_mesh sphere = gen_sphere(10, SLICES, STACKS, 0), cyl = gen_cylinder(5, 7, SLICES, 1);
    adaslice_mesh cone = gen_cone(6, 9, SLICES, 2);
    double h[STACKS + 1], ch[2] = {1, 8}, kh[2] = {2, 11};
    adaslice_contours c;
    uint32_t ring[SLICES][2];
    int r, j;
    for (r = 0; r <= STACKS; r++) h[r] = ring_z(&sphere, SLICES, STACKS, STACKS - r);
    c = slice(&sphere, h, STACKS + 1);
    CHECK(polygons_at(&c, 0) == 0 && polygons_at(&c, STACKS) == 0);
    for (r = 1; r < STACKS; r++) {
        int k = STACKS - r;
        double ref;
        for (j = 0; j < SLICES; j++) { /* meridians cut at their lower ends */
            ring[j][0] = ring_index(&sphere, SLICES, STACKS, k, j);
            ring[j][1] = ring_index(&sphere, SLICES, STACKS, k - 1, j);
        }
        ref = edge_polygon_area(&sphere, (const uint32_t(*)[2])ring, SLICES, h[r]);
        CHECKF(polygons_at(&c, (size_t)r) == 1, "ring %d: %zu polygons", k, polygons_at(&c, (size_t)r));
        if (polygons_at(&c, (size_t)r) == 1) {
            const adaslice_polygon *p = c.polygons + c.first_polygon[r];
            CHECK(p->closed && p->count == SLICES);
            CHECKF(fabs(area_at(&c, (size_t)r) - ref) <= 1e-12 * ref, "ring %d: %g vs %g", k, area_at(&c, (size_t)r), ref);
        }
    }
    adaslice_contours_free(&c);

    c = slice(&cyl, ch, 2); /* bottom cap: the whole base polygon; top: nothing */
    CHECK(polygons_at(&c, 0) == 1 && polygons_at(&c, 1) == 0 && open_polygons(&c) == 0);
    for (j = 0; j < SLICES; j++) { ring[j][0] = (uint32_t)(2 + 2 * j); ring[j][1] = ring[j][0] + 1; }
    CHECK(fabs(area_at(&c, 0) - edge_polygon_area(&cyl, (const uint32_t(*)[2])ring, SLICES, 1)) < 1e-12);
    CHECK(c.polygon_count == 1 && c.polygons[0].count == SLICES);
    adaslice_contours_free(&c);

    c = slice(&cone, kh, 2);
    CHECK(polygons_at(&c, 0) == 1 && polygons_at(&c, 1) == 0 && open_polygons(&c) == 0);
    for (j = 0; j < SLICES; j++) { ring[j][0] = (uint32_t)(2 + j); ring[j][1] = 0; }
    CHECK(fabs(area_at(&c, 0) - edge_polygon_area(&cone, (const uint32_t(*)[2])ring, SLICES, 2)) < 1e-12);
    adaslice_contours_free(&c);
    gen_free(&sphere);
    gen_free(&cyl);
    gen_free(&cone);
}

static void a_hole_turns_clockwise(void)
{
    adaslice_mesh m = gen_frame();
    double h[3] = {0, 2.5, 4.999};
    adaslice_contours c = slice(&m, h, 3);
    size_t i, p;
    for (i = 0; i < 3; i++) {
        int outer = 0, inner = 0;
        CHECKF(polygons_at(&c, i) == 2, "z %g: %zu polygons", h[i], polygons_at(&c, i));
        for (p = c.first_polygon[i]; p < c.first_polygon[i + 1]; p++) {
            double a = polygon_area(&c, p);
            CHECK(c.polygons[p].closed);
            outer += fabs(a - 100) < 1e-12;
            inner += fabs(a + 16) < 1e-12;
        }
        CHECK(outer == 1 && inner == 1);
        CHECK(adaslice_contours_winding(&c, i, 1, 1) == 1);
        CHECK(adaslice_contours_winding(&c, i, 8.5, 5) == 1);
        CHECK(adaslice_contours_winding(&c, i, 5, 5) == 0);
        CHECK(adaslice_contours_winding(&c, i, 11, 5) == 0);
        CHECK(adaslice_contours_winding(&c, i, -1, 5) == 0);
        CHECK(adaslice_contours_winding(&c, i, 5, 3.5) == 0);
        CHECK(adaslice_contours_distance(&c, i, 5, 5) == 2);
        CHECK(adaslice_contours_distance(&c, i, 1, 1) == 1);
        CHECK(fabs(adaslice_contours_distance(&c, i, 13, 14) - 5) < 1e-12);
    }
    CHECK(adaslice_contours_winding(&c, 3, 1, 1) == 0);
    CHECK(adaslice_contours_distance(&c, 3, 1, 1) == HUGE_VAL);
    adaslice_contours_free(&c);
    gen_free(&m);
}

static void welded_soup_slices_like_the_indexed_mesh(void)
{
    adaslice_mesh m = gen_sphere(10, 40, 20, 0), s = soup_of(&m);
    adaslice_contours a, b;
    double h[40];
    size_t i;
    adaslice_error e;
    for (i = 0; i < 40; i++) h[i] = 0.5 * (double)i + 0.01;
    a = slice(&s, h, 40); /* unwelded: every cut is its own open piece */
    CHECK(open_polygons(&a) == a.polygon_count && a.polygon_count == a.segment_count);
    adaslice_contours_free(&a);
    CHECK(adaslice_mesh_weld(&s, NULL, &e) == ADASLICE_OK);
    CHECK(s.vertex_count == m.vertex_count && s.triangle_count == m.triangle_count);
    a = slice(&m, h, 40);
    b = slice(&s, h, 40);
    CHECK(a.polygon_count == b.polygon_count && a.point_count == b.point_count && open_polygons(&b) == 0);
    if (a.point_count == b.point_count && a.polygon_count == b.polygon_count) {
        CHECK(memcmp(a.points, b.points, 2 * a.point_count * sizeof(double)) == 0);
        CHECK(memcmp(a.first_polygon, b.first_polygon, 41 * sizeof(size_t)) == 0);
    }
    adaslice_contours_free(&a);
    adaslice_contours_free(&b);
    gen_free(&m);
    gen_free(&s);
}

static void weld_merges_signed_zeros_and_keeps_order(void)
{
    adaslice_mesh m = gen_alloc(6, 2);
    adaslice_error e;
    gen_vertex(&m, 1, 2, 3);
    gen_vertex(&m, 0.0, 0, 1);
    gen_vertex(&m, 4, 5, 6);
    gen_vertex(&m, -0.0, -0.0, 1);
    gen_vertex(&m, 1, 2, 3);
    gen_vertex(&m, 7, 8, 9);
    gen_triangle(&m, 0, 1, 2);
    gen_triangle(&m, 3, 4, 5);
    CHECK(adaslice_mesh_weld(&m, NULL, &e) == ADASLICE_OK);
    CHECK(m.vertex_count == 4);
    CHECK(m.triangles[0] == 0 && m.triangles[1] == 1 && m.triangles[2] == 2);
    CHECK(m.triangles[3] == 1 && m.triangles[4] == 0 && m.triangles[5] == 3);
    CHECK(m.vertices[9] == 7 && m.vertices[11] == 9);
    m.triangles[5] = 4;
    CHECK(adaslice_mesh_weld(&m, NULL, &e) == ADASLICE_ERR_INDEX && strstr(e.message, "triangle 1") != NULL);
    CHECK(adaslice_mesh_weld(NULL, NULL, &e) == ADASLICE_ERR_ARGUMENT);
    gen_free(&m);
}

static void open_meshes_give_open_polylines(void)
{
    adaslice_mesh side = gen_box(0, 0, 0, 4, 3, 2), top = gen_box(0, 0, 0, 4, 3, 2), tri = gen_alloc(3, 1);
    double h[3] = {0, 1, 2};
    adaslice_contours c;
    size_t i;
    drop_triangles(&side, 4, 2); /* the face y = 0 */
    c = slice(&side, h, 3);
    for (i = 0; i < 2; i++) {
        const adaslice_polygon *p = c.polygons + c.first_polygon[i];
        const double *end = c.points + 2 * (p->first + p->count - 1);
        CHECK(polygons_at(&c, i) == 1 && !p->closed);
        /* the walls x = 4, y = 3, x = 0 in turn (diagonals add points in between) */
        CHECK(c.points[2 * p->first] == 4 && c.points[2 * p->first + 1] == 0 && end[0] == 0 && end[1] == 0);
        /* the chord stands in for the missing face */
        CHECK(fabs(area_at(&c, i) - 12) < 1e-12);
        CHECK(adaslice_contours_winding(&c, i, 2, 1) == 1 && adaslice_contours_winding(&c, i, 2, -1) == 0);
    }
    CHECK(polygons_at(&c, 2) == 0);
    adaslice_contours_free(&c);

    drop_triangles(&top, 2, 2); /* the face z = 2: sections stay closed */
    c = slice(&top, h, 3);
    CHECK(polygons_at(&c, 1) == 1 && c.polygons[c.first_polygon[1]].closed);
    adaslice_contours_free(&c);

    {   /* one wall triangle turned inside out */
        uint32_t v = top.triangles[6];
        top.triangles[6] = top.triangles[7];
        top.triangles[7] = v;
    }
    c = slice(&top, h + 1, 1);
    CHECK(c.polygon_count >= 1 && open_polygons(&c) >= 1);
    adaslice_contours_free(&c);

    gen_vertex(&tri, 0, 0, 0); gen_vertex(&tri, 1, 0, 0); gen_vertex(&tri, 0, 0, 1);
    gen_triangle(&tri, 0, 1, 2);
    c = slice(&tri, h, 2);
    CHECK(polygons_at(&c, 0) == 1 && c.polygons[0].count == 2 && !c.polygons[0].closed);
    CHECK(polygons_at(&c, 1) == 0);
    adaslice_contours_free(&c);
    gen_free(&side);
    gen_free(&top);
    gen_free(&tri);
}

static void overlapping_boxes_wind_twice(void)
{
    adaslice_mesh a = gen_box(0, 0, 0, 10, 10, 10), b = gen_box(5, 2, 3, 15, 12, 13);
    double h[3] = {1, 5, 12};
    adaslice_contours c;
    gen_append(&a, &b);
    c = slice(&a, h, 3);
    CHECK(polygons_at(&c, 0) == 1 && polygons_at(&c, 1) == 2 && polygons_at(&c, 2) == 1);
    CHECK(fabs(area_at(&c, 1) - 200) < 1e-12 && open_polygons(&c) == 0);
    CHECK(adaslice_contours_winding(&c, 1, 7, 5) == 2);
    CHECK(adaslice_contours_winding(&c, 1, 2, 5) == 1);
    CHECK(adaslice_contours_winding(&c, 1, 12, 5) == 1);
    CHECK(adaslice_contours_winding(&c, 1, 7, 11) == 1);
    CHECK(adaslice_contours_winding(&c, 1, 20, 5) == 0);
    CHECK(adaslice_contours_winding(&c, 0, 7, 5) == 1);
    CHECK(adaslice_contours_winding(&c, 2, 2, 5) == 0 && adaslice_contours_winding(&c, 2, 7, 5) == 1);
    adaslice_contours_free(&c);
    gen_free(&a);
    gen_free(&b);
}

static size_t first_at_or_above(const double *h, size_t n, double z)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (h[mid] < z) lo = mid + 1; else hi = mid;
    }
    return lo;
}

/* O(n log k + k + m): each triangle is cut once per height it spans, and
   visited at most once more (when it leaves the sweep). */
static void each_triangle_is_cut_only_where_it_spans(void)
{
    enum { K = 1000 };
    adaslice_mesh m = gen_sphere(10, 250, 201, 0);
    static double h[K];
    adaslice_contours c;
    size_t i, spans = 0;
    CHECK(m.triangle_count == 100000);
    for (i = 0; i < K; i++) h[i] = 20 * ((double)i + 0.5) / K;
    for (i = 0; i < m.triangle_count; i++) {
        double z[3], lo, hi;
        int k;
        for (k = 0; k < 3; k++) z[k] = m.vertices[3 * m.triangles[3 * i + k] + 2];
        lo = fmin(z[0], fmin(z[1], z[2]));
        hi = fmax(z[0], fmax(z[1], z[2]));
        spans += first_at_or_above(h, K, hi) - first_at_or_above(h, K, lo);
    }
    c = slice(&m, h, K);
    CHECKF(c.segment_count == spans, "%zu cuts for %zu spans", c.segment_count, spans);
    CHECKF(c.triangle_visits <= spans + m.triangle_count, "%zu visits", c.triangle_visits);
    CHECK(open_polygons(&c) == 0 && c.polygon_count == K);
    adaslice_contours_free(&c);
    gen_free(&m);
}

/* Points a few ulps either side of the edge (-12,-12) -> (24,24): the exact
   answer is the sign of y - x, but in doubles y + 12 and x + 12 round to the
   same value, so an unfiltered determinant would call them all "on the edge". */
static void winding_is_exact_next_to_an_edge(void)
{
    static const double tri[3][2] = {{-12, -12}, {24, 24}, {-12, 24}};
    adaslice_mesh m = gen_prism(tri, 3, 0, 1);
    double h = 0.5, u = DBL_EPSILON / 2; /* one ulp of 0.5 */
    adaslice_contours c = slice(&m, &h, 1);
    int i, j, wrong = 0;
    CHECK(c.polygon_count == 1 && c.polygons[0].closed);
    CHECK(area_at(&c, 0) == 648); /* the corners came through exactly */
    for (i = -20; i <= 20; i++)
        for (j = -20; j <= 20; j++) {
            double x = 0.5 + i * u, y = 0.5 + j * u;
            if (j != i) wrong += adaslice_contours_winding(&c, 0, x, y) != (y > x);
        }
    CHECKF(wrong == 0, "%d points on the wrong side", wrong);
    adaslice_contours_free(&c);
    gen_free(&m);
}

/* The bundled hand (CC BY 4.0, see examples/models/README.md): closed loops
   whose signed areas are the exact profile's A(z) at bin centres. */
static void hand_matches_the_exact_area_profile(void)
{
    adaslice_load_options lo;
    adaslice_profile_options po;
    adaslice_mesh m;
    adaslice_profile p;
    adaslice_contours c;
    adaslice_error e;
    double h[20], worst = 0;
    size_t bin[20], i;
    memset(&lo, 0, sizeof lo);
    lo.scale = 88.7;
    memset(&po, 0, sizeof po);
    po.metric = ADASLICE_METRIC_VOLUME;
    if (adaslice_mesh_load_file("examples/models/hand_closed.obj", &lo, &m, &e) != ADASLICE_OK) {
        CHECKF(0, "%s", e.message);
        return;
    }
    CHECK(adaslice_profile_exact(&m, &po, &p, &e) == ADASLICE_OK);
    for (i = 0; i < 20; i++) {
        bin[i] = (2 * i + 1) * p.bin_count / 40;
        h[i] = p.z0 + ((double)bin[i] + 0.5) * p.bin;
    }
    c = slice(&m, h, 20);
    CHECKF(open_polygons(&c) == 0, "%zu open polygons", open_polygons(&c));
    for (i = 0; i < 20; i++) {
        double d = fabs(area_at(&c, i) - p.area[bin[i]]) / p.area[bin[i]];
        if (d > worst) worst = d;
    }
    CHECKF(worst < 1e-6, "area %g relative from the profile", worst);
    adaslice_contours_free(&c);
    adaslice_profile_free(&p);
    adaslice_mesh_free(&m);
}

static void bad_arguments_are_named(void)
{
    adaslice_mesh m = gen_box(0, 0, 0, 1, 1, 1);
    adaslice_contours c;
    adaslice_error e;
    double h[3] = {0.5, 0.2, 0.7}, nan_h = NAN;
    CHECK(adaslice_contours_slice(&m, h, 3, NULL, &c, &e) == ADASLICE_ERR_ARGUMENT);
    CHECK(strstr(e.message, "height 1 is 0.2 after 0.5") != NULL && c.polygons == NULL);
    CHECK(adaslice_contours_slice(&m, &nan_h, 1, NULL, &c, &e) == ADASLICE_ERR_ARGUMENT);
    CHECK(adaslice_contours_slice(&m, NULL, 1, NULL, &c, &e) == ADASLICE_ERR_ARGUMENT);
    CHECK(adaslice_contours_slice(&m, h, 1, NULL, NULL, &e) == ADASLICE_ERR_ARGUMENT);
    m.triangles[7] = 8;
    CHECK(adaslice_contours_slice(&m, h, 1, NULL, &c, &e) == ADASLICE_ERR_INDEX);
    CHECK(strstr(e.message, "triangle 2 uses vertex 8 of 8") != NULL);
    m.triangles[7] = 1;
    CHECK(adaslice_contours_slice(&m, h, 0, NULL, &c, &e) == ADASLICE_OK);
    CHECK(c.height_count == 0 && c.polygon_count == 0 && c.first_polygon[0] == 0);
    adaslice_contours_free(&c);
    adaslice_contours_free(NULL);
    gen_free(&m);
}

/* An allocator that fails the n-th request and counts what is outstanding. */
static void running_out_of_memory_leaks_nothing(void)
{
    adaslice_mesh m = gen_sphere(10, 64, 32, 0), s = soup_of(&m);
    failing f;
    adaslice_allocator a;
    adaslice_contour_options o;
    adaslice_weld_options wo = {0, NULL};
    adaslice_contours c;
    adaslice_error e;
    double h[50];
    int n, done = 0;
    size_t i;
    for (i = 0; i < 50; i++) h[i] = 0.4 * (double)i;
    a = failing_allocator(&f);
    o.allocator = &a;
    for (n = 0; n < 100 && !done; n++) {
        adaslice_result r;
        f.left = n;
        f.live = 0;
        r = adaslice_contours_slice(&m, h, 50, &o, &c, &e);
        if (r == ADASLICE_OK) {
            done = 1;
            CHECK(c.polygon_count == 49 && f.live == 4); /* none at the bottom pole */
            adaslice_contours_free(&c);
        } else {
            CHECKF(r == ADASLICE_ERR_NOMEM && c.points == NULL, "failure %d: %s", n, e.message);
        }
        CHECKF(f.live == 0, "failure %d: %ld blocks left", n, f.live);
    }
    CHECK(done && n > 8); /* the output grew more than once on the way */
    f.left = 0;
    f.live = 0;
    wo.allocator = &a;
    CHECK(adaslice_mesh_weld(&s, &wo, &e) == ADASLICE_ERR_NOMEM && s.vertex_count == 3 * s.triangle_count);
    f.left = 1;
    CHECK(adaslice_mesh_weld(&s, &wo, &e) == ADASLICE_ERR_NOMEM && f.live == 0);
    f.left = 2;
    CHECK(adaslice_mesh_weld(&s, &wo, &e) == ADASLICE_OK && f.live == 0 && s.vertex_count == m.vertex_count);
    gen_free(&m);
    gen_free(&s);
}

void test_contours(void);
void test_contours(void)
{
    RUN(solids_give_closed_polygons_of_the_right_area);
    RUN(heights_at_vertices_give_the_section_just_above);
    RUN(a_hole_turns_clockwise);
    RUN(welded_soup_slices_like_the_indexed_mesh);
    RUN(weld_merges_signed_zeros_and_keeps_order);
    RUN(open_meshes_give_open_polylines);
    RUN(overlapping_boxes_wind_twice);
    RUN(each_triangle_is_cut_only_where_it_spans);
    RUN(winding_is_exact_next_to_an_edge);
    RUN(hand_matches_the_exact_area_profile);
    RUN(bad_arguments_are_named);
    RUN(running_out_of_memory_leaks_nothing);
}
