/* The scanline LDI: watertight rays through vertices and edges, and the
   sampled profiles against the exact ones. */
#include "../adaslice.h"
#include "check.h"
#include "meshgen.h"
#include <math.h>
#include <string.h>

/* Along every ray of a closed, consistently wound mesh the winding number
   starts at 0, never drops below 0, and ends at 0; a convex one is met
   exactly twice or not at all, however the ray grazes edges and vertices.
   Counts the rays that break it. */
static size_t broken_rays(const adaslice_ldi *ldi, size_t *rays_hit)
{
    size_t p, bad = 0, pixels = (size_t)ldi->grid.width * (size_t)ldi->grid.height;
    *rays_hit = 0;
    for (p = 0; p < pixels; p++) {
        size_t k;
        int w = 0, ok = 1;
        for (k = ldi->first[p]; k < ldi->first[p + 1]; k++) {
            w += (ldi->samples[k].face & ADASLICE_SAMPLE_LEAVES) ? -1 : 1;
            if (w < 0) ok = 0;
        }
        bad += !ok || w != 0 || (ldi->first[p + 1] - ldi->first[p] != 0 && ldi->first[p + 1] - ldi->first[p] != 2);
        *rays_hit += ldi->first[p + 1] > ldi->first[p];
    }
    return bad;
}

/* Grids whose pixel centres fall exactly on the solids' vertices and edges. */
static void rays_through_vertices_and_edges_are_watertight(void)
{
    adaslice_mesh box = gen_box(-4, -3, -2, 4, 3, 2);
    adaslice_mesh sphere = gen_sphere(4, 16, 8, -4);  /* poles and meridians on x = 0 and y = 0 */
    adaslice_mesh cone = gen_cone(3, 5, 8, 0);
    const adaslice_mesh *meshes[3] = {&box, &sphere, &cone};
    int m, axis;
    for (m = 0; m < 3; m++) {
        for (axis = 0; axis < 3; axis++) {
            adaslice_grid g;
            adaslice_ldi ldi;
            adaslice_error e;
            size_t hit = 0, bad;
            memset(&g, 0, sizeof g);
            g.axis = (adaslice_axis)axis;
            g.pitch[0] = g.pitch[1] = 0.5; /* centres at multiples of 0.5: every box vertex and edge, the poles */
            g.origin[0] = g.origin[1] = -10.25;
            g.width = g.height = 41;
            CHECKF(adaslice_ldi_build(meshes[m], &g, NULL, &ldi, &e) == ADASLICE_OK, "%s", e.message);
            bad = broken_rays(&ldi, &hit);
            CHECKF(bad == 0 && hit > 20, "mesh %d axis %d: %zu of %zu rays broken", m, axis, bad, hit);
            /* and no ray leaks through: well inside the outline, two samples */
            if (m < 2) {
                int i, j, leaks = 0;
                for (j = 0; j < g.height; j++)
                    for (i = 0; i < g.width; i++) {
                        double u = g.origin[0] + (i + 0.5) * g.pitch[0], v = g.origin[1] + (j + 0.5) * g.pitch[1];
                        double half[3] = {4, 3, 2}; /* the box's half sizes along x, y, z */
                        int a = axis == 0 ? 1 : axis == 1 ? 2 : 0;
                        int inside = m == 0 ? fabs(u) < half[a] && fabs(v) < half[(a + 1) % 3] : u * u + v * v < 9;
                        size_t p = (size_t)j * g.width + i;
                        leaks += inside && ldi.first[p + 1] - ldi.first[p] != 2;
                    }
                CHECKF(leaks == 0, "mesh %d axis %d: %d rays inside the outline miss the surface", m, axis, leaks);
            }
            adaslice_ldi_free(&ldi);
        }
    }
    gen_free(&box);
    gen_free(&sphere);
    gen_free(&cone);
}

/* A ray through the middle of the box meets it exactly twice, at its faces. */
static void box_rays_meet_the_faces(void)
{
    adaslice_mesh box = gen_box(-4, -3, -2, 4, 3, 2);
    adaslice_grid g;
    adaslice_ldi ldi;
    size_t p;
    memset(&g, 0, sizeof g);
    g.axis = ADASLICE_AXIS_Z;
    g.pitch[0] = g.pitch[1] = 1;
    g.origin[0] = -4; g.origin[1] = -3;
    g.width = 8; g.height = 6;
    CHECK(adaslice_ldi_build(&box, &g, NULL, &ldi, NULL) == ADASLICE_OK);
    CHECK(ldi.depth_origin == -2 && ldi.sample_count == 96);
    for (p = 0; p < 48; p++) {
        CHECK(ldi.first[p + 1] - ldi.first[p] == 2);
        CHECK(ldi.samples[ldi.first[p]].depth == 0 && !(ldi.samples[ldi.first[p]].face & ADASLICE_SAMPLE_LEAVES));
        CHECK(ldi.samples[ldi.first[p] + 1].depth == 4 && (ldi.samples[ldi.first[p] + 1].face & ADASLICE_SAMPLE_LEAVES));
    }
    adaslice_ldi_free(&ldi);
    gen_free(&box);
}

static adaslice_profile profile_of(const adaslice_mesh *m, adaslice_metric metric, int sampled, size_t limit)
{
    adaslice_profile_options o;
    adaslice_profile p;
    adaslice_error e;
    memset(&o, 0, sizeof o);
    o.metric = metric;
    o.memory_limit = limit;
    if ((sampled ? adaslice_profile_sampled(m, &o, &p, &e) : adaslice_profile_exact(m, &o, &p, &e)) != ADASLICE_OK) {
        CHECKF(0, "%s", e.message);
        memset(&p, 0, sizeof p);
    }
    return p;
}

/* Cusp: every sample lies on a triangle that meets its bin, so a reached bin
   never exceeds the exact value; on a sphere at the default resolution every
   bin is reached and the mean gap stays below 1 % of the mean. Areas: a pixel
   is misjudged only where the contour crosses it, so |A_ldi - A| is at most
   the perimeter times a pixel's diagonal. */
static void sampled_sphere_matches_exact(void)
{
    double R = 10;
    adaslice_mesh m = gen_sphere(R, 96, 48, 0);
    adaslice_profile ex = profile_of(&m, ADASLICE_METRIC_CUSP, 0, 0), sa = profile_of(&m, ADASLICE_METRIC_CUSP, 1, 0);
    adaslice_profile ea = profile_of(&m, ADASLICE_METRIC_VOLUME, 0, 0), sv = profile_of(&m, ADASLICE_METRIC_VOLUME, 1, 0);
    double pitch = 2 * R / ADASLICE_DEFAULT_RESOLUTION, gap = 0, mean = 0;
    size_t i, above = 0, area_off = 0;
    CHECK(sa.unsampled_bins == 0 && sa.bin_count == ex.bin_count);
    for (i = 0; i < ex.bin_count; i++) {
        double rho = sqrt(ea.area[i] / M_PI);
        above += sa.phi[i] > ex.phi[i] + 1e-12;
        gap += fabs(sa.phi[i] - ex.phi[i]);
        mean += ex.phi[i];
        area_off += fabs(sv.area[i] - ea.area[i]) > 2 * M_PI * rho * pitch * sqrt(2.0) + pitch * pitch;
    }
    CHECK(above == 0);
    CHECKF(gap < 0.01 * mean, "mean gap %g, mean %g", gap / ex.bin_count, mean / ex.bin_count);
    CHECKF(area_off == 0, "%zu bins with the area off by more than a pixel along the contour", area_off);
    adaslice_profile_free(&ex);
    adaslice_profile_free(&sa);
    adaslice_profile_free(&ea);
    adaslice_profile_free(&sv);
    gen_free(&m);
}

/* Bands of rows under a small memory limit give the same profile, bit for bit. */
static void bands_do_not_change_the_result(void)
{
    adaslice_mesh m = gen_sphere(6, 48, 24, 0);
    adaslice_mesh c = gen_cylinder(3, 4, 32, 12);
    adaslice_profile a, b;
    size_t i, diff = 0;
    gen_append(&m, &c);
    a = profile_of(&m, ADASLICE_METRIC_AREA, 1, 0);
    b = profile_of(&m, ADASLICE_METRIC_AREA, 1, 200000); /* about 25 bands */
    CHECK(a.bin_count == b.bin_count);
    for (i = 0; i < a.bin_count && i < b.bin_count; i++) diff += a.phi[i] != b.phi[i] || a.area[i] != b.area[i];
    CHECK(diff == 0);
    adaslice_profile_free(&a);
    adaslice_profile_free(&b);
    gen_free(&m);
    gen_free(&c);
}

/* A bin between two rows of x and y rays on a vertical wall is reached by no
   sample: it takes its neighbours' value instead of reading as zero. */
static void unreached_bins_are_filled(void)
{
    adaslice_mesh m = gen_box(0, 0, 0, 40, 40, 1); /* 2048 px over 40 mm: rows 0.0195 mm apart, bins 0.002 */
    adaslice_profile p = profile_of(&m, ADASLICE_METRIC_ROUGHNESS, 1, 0);
    size_t i, zero = 0;
    CHECK(p.unsampled_bins > 0);
    for (i = 0; i < p.bin_count; i++) zero += p.phi[i] == 0;
    CHECK(zero == 0);
    adaslice_profile_free(&p);
    gen_free(&m);
}

/* Weights travel with the samples' triangle ids (eq. 21-24): half weight
   everywhere halves the sampled cusp profile and the volume profile. */
static void sampled_weights_follow_the_faces(void)
{
    adaslice_mesh m = gen_sphere(5, 32, 16, 0);
    float *w = (float *)malloc(m.triangle_count * sizeof(float));
    adaslice_metric metrics[2] = {ADASLICE_METRIC_CUSP, ADASLICE_METRIC_VOLUME};
    size_t i, off = 0;
    int k;
    for (i = 0; i < m.triangle_count; i++) w[i] = 0.5f;
    for (k = 0; k < 2; k++) {
        adaslice_profile_options o;
        adaslice_profile a, b;
        memset(&o, 0, sizeof o);
        o.metric = metrics[k];
        o.resolution = 512;
        CHECK(adaslice_profile_sampled(&m, &o, &a, NULL) == ADASLICE_OK);
        o.weights = w;
        CHECK(adaslice_profile_sampled(&m, &o, &b, NULL) == ADASLICE_OK);
        for (i = 0; i < a.bin_count; i++) off += b.phi[i] != 0.5 * a.phi[i];
        adaslice_profile_free(&a);
        adaslice_profile_free(&b);
    }
    CHECK(off == 0);
    free(w);
    gen_free(&m);
}

static void bad_grids_are_refused(void)
{
    adaslice_mesh m = gen_box(0, 0, 0, 1, 1, 1);
    adaslice_grid g;
    adaslice_ldi ldi;
    adaslice_error e;
    memset(&g, 0, sizeof g);
    g.axis = ADASLICE_AXIS_Z; g.pitch[0] = g.pitch[1] = 0; g.width = 10; g.height = 10;
    CHECK(adaslice_ldi_build(&m, &g, NULL, &ldi, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "grid"));
    g.pitch[0] = g.pitch[1] = 1e-9; /* the mesh lies 10^9 pixels away */
    CHECK(adaslice_ldi_build(&m, &g, NULL, &ldi, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "2^21"));
    gen_free(&m);
}

/* The triangle of m over (x, y) whose plane is highest there, by brute
   force: its index and z; -1 where none is. */
static long top_triangle(const adaslice_mesh *m, double x, double y, double *z)
{
    long best = -1;
    size_t t;
    for (t = 0; t < m->triangle_count; t++) {
        const float *p = m->vertices + 3 * m->triangles[3 * t], *q = m->vertices + 3 * m->triangles[3 * t + 1],
                    *r = m->vertices + 3 * m->triangles[3 * t + 2];
        double d = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]), u, v, h;
        if (fabs(d) < 1e-12) continue;
        u = ((x - p[0]) * (r[1] - p[1]) - (y - p[1]) * (r[0] - p[0])) / d;
        v = ((q[0] - p[0]) * (y - p[1]) - (q[1] - p[1]) * (x - p[0])) / d;
        if (u < 0 || v < 0 || u + v > 1) continue;
        h = p[2] + u * (q[2] - p[2]) + v * (r[2] - p[2]);
        if (best < 0 || h > *z) { best = (long)t; *z = h; }
    }
    return best;
}

/* adaslice_ldi_ray between pixel centres on a dome (a convex solid): two
   crossings in order, in then out; the top one is the triangle's own plane
   where the query lies on the triangle the pixel's ray met (to float
   precision), and elsewhere off by no more than the steepest slope (30
   degrees here) times half a pixel's diagonal. */
static void ray_queries_between_pixels_meet_the_triangles(void)
{
    adaslice_mesh m = gen_dome(10, 20, 1, 8, 24);
    adaslice_grid g = adaslice_grid_fit(&m, ADASLICE_AXIS_Z, 96);
    adaslice_ldi ldi;
    adaslice_error e;
    uint32_t seed = 12345;
    int i, same = 0, queried = 0;
    CHECK(adaslice_ldi_build(&m, &g, NULL, &ldi, &e) == ADASLICE_OK);
    for (i = 0; i < 3000; i++) {
        adaslice_crossing c[8];
        double x, y, z = 0, bound = tan(M_PI / 6) * hypot(g.pitch[0], g.pitch[1]) / 2;
        size_t n;
        long t;
        seed = seed * 1103515245u + 12345u;
        x = -9.5 + 19.0 * (double)(seed >> 8) / 16777216.0;
        seed = seed * 1103515245u + 12345u;
        y = -9.5 + 19.0 * (double)(seed >> 8) / 16777216.0;
        if ((t = top_triangle(&m, x, y, &z)) < 0 || hypot(x, y) > 9.4) continue;
        n = adaslice_ldi_ray(&ldi, &m, x, y, c, 8);
        queried++;
        CHECKF(n == 2 && !c[0].leaves && c[1].leaves && c[0].depth < c[1].depth, "(%g, %g): %zu crossings", x, y, n);
        if (n != 2) continue;
        if ((long)c[1].face == t) {
            same++;
            CHECKF(fabs(c[1].depth - z) < 1e-5, "(%g, %g): %.7g on its own triangle at %.7g", x, y, c[1].depth, z);
        } else {
            CHECKF(fabs(c[1].depth - z) <= bound, "(%g, %g): %.7g, the surface at %.7g", x, y, c[1].depth, z);
        }
        CHECKF(fabs(c[0].depth) < 1e-5, "(%g, %g): the bottom at %.7g", x, y, c[0].depth);
    }
    CHECKF(queried > 2000 && same > queried / 2, "%d of %d queries on the pixel's own triangle", same, queried);
    CHECK(adaslice_ldi_ray(&ldi, &m, 100, 0, NULL, 0) == 0);
    adaslice_ldi_free(&ldi);
    gen_free(&m);
}

void test_ldi(void)
{
    RUN(ray_queries_between_pixels_meet_the_triangles);
    RUN(rays_through_vertices_and_edges_are_watertight);
    RUN(box_rays_meet_the_faces);
    RUN(sampled_sphere_matches_exact);
    RUN(bands_do_not_change_the_result);
    RUN(unreached_bins_are_filled);
    RUN(sampled_weights_follow_the_faces);
    RUN(bad_grids_are_refused);
}
