/* Exact profiles against closed forms, on meshes the tests build at several
   tessellations. Two references each time: the smooth solid's formula, within a
   tolerance derived from the tessellation, and the tessellated solid's own
   formula, which must agree to rounding. */
#include "../adaslice.h"
#include "check.h"
#include "meshgen.h"
#include <math.h>
#include <string.h>

static adaslice_profile profile_of(const adaslice_mesh *m, adaslice_metric metric, double bin, const float *w)
{
    adaslice_profile_options o;
    adaslice_profile p;
    adaslice_error e;
    memset(&o, 0, sizeof o);
    o.metric = metric;
    o.bin = bin;
    o.weights = w;
    if (adaslice_profile_exact(m, &o, &p, &e) != ADASLICE_OK) {
        CHECKF(0, "profile failed: %s", e.message);
        memset(&p, 0, sizeof p);
    }
    return p;
}

/* |n_z| of the planar band between polar angles t1 and t2 of a UV sphere with
   `slices` segments: the band's plane runs through the midpoints of its two
   horizontal edges, at radii R sin(t) cos(pi/slices). */
static double band_nz(double t1, double t2, int slices)
{
    double c = cos(M_PI / slices), dr = c * (sin(t2) - sin(t1)), dz = cos(t2) - cos(t1);
    return fabs(dr) / sqrt(dr * dr + dz * dz);
}

static void sphere_cusp_is_distance_from_equator(void)
{
    static const int tess[3][2] = {{12, 8}, {48, 24}, {192, 96}};
    double R = 10, bin = 0.002, last_tol = 1;
    int t;
    for (t = 0; t < 3; t++) {
        int slices = tess[t][0], stacks = tess[t][1];
        adaslice_mesh m = gen_sphere(R, slices, stacks, 0);
        adaslice_profile p = profile_of(&m, ADASLICE_METRIC_CUSP, bin, NULL);
        double dth = M_PI / stacks;
        /* a band's normal is within dth/2 of any point's in the band (polar
           tilt), 1 - cos(pi/slices) off for the azimuthal chord, and the
           value moves by bin/R across a bin */
        double tol = dth / 2 + (1 - cos(M_PI / slices)) + bin / R + 1e-6, worst = 0, worst_tess = 0;
        size_t i;
        CHECK(p.bin_count == (size_t)ceil(2 * R / bin - 1e-9));
        for (i = 0; i < p.bin_count; i++) {
            double zlo = i * bin, zhi = (i + 1) * bin, exact = 0, edge = 0, smooth, d;
            int k;
            /* the tessellated solid: max over bands whose z-range meets the
               bin; a ring within rounding of the bin's top may fall either
               side, so such a band is accepted but not required */
            for (k = 0; k < stacks; k++) {
                double ztop = (float)(R + R * cos(k * dth)), zbot = (float)(R + R * cos((k + 1) * dth));
                double v = band_nz(k * dth, (k + 1) * dth, slices);
                if (zbot < zhi - 1e-9 && ztop >= zlo) { if (v > exact) exact = v; }
                else if (fabs(zbot - zhi) <= 1e-9 && v > edge) edge = v;
            }
            d = fabs(p.phi[i] - exact);
            if (edge > exact && fabs(p.phi[i] - edge) < d) d = fabs(p.phi[i] - edge);
            if (d > worst_tess) worst_tess = d;
            smooth = fabs((i + 0.5) * bin - R) / R;
            d = fabs(p.phi[i] - smooth);
            if (d > worst) worst = d;
        }
        CHECKF(worst_tess < 1e-5, "%dx%d: %g from the tessellated formula", slices, stacks, worst_tess);
        CHECKF(worst <= tol, "%dx%d: %g from |z-R|/R, tolerance %g", slices, stacks, worst, tol);
        CHECKF(tol < last_tol, "tolerance must shrink with the tessellation");
        last_tol = tol;
        adaslice_profile_free(&p);
        gen_free(&m);
    }
}

static void cone_cusp_is_constant(void)
{
    int slices;
    for (slices = 8; slices <= 512; slices *= 4) {
        double r = 6, h = 9, c = cos(M_PI / slices);
        adaslice_mesh m = gen_cone(r, h, slices, 0);
        adaslice_profile p = profile_of(&m, ADASLICE_METRIC_CUSP, 0.002, NULL);
        double tess = r * c / sqrt(h * h + r * r * c * c), smooth = r / sqrt(r * r + h * h);
        double tol = 1 - c + 1e-6;
        size_t i, off = 0;
        CHECK(p.phi[0] == 1); /* the base */
        for (i = 1; i < p.bin_count; i++) off += fabs(p.phi[i] - tess) > 1e-6;
        CHECKF(off == 0, "%d slices: %zu bins off the constant %g", slices, off, tess);
        CHECKF(fabs(tess - smooth) <= tol, "%d slices: %g vs %g", slices, tess, smooth);
        adaslice_profile_free(&p);
        gen_free(&m);
    }
}

static void cylinder_cusp_is_zero_but_caps(void)
{
    adaslice_mesh m = gen_cylinder(5, 7, 64, 3);
    adaslice_profile p = profile_of(&m, ADASLICE_METRIC_CUSP, 0.002, NULL);
    adaslice_profile q = profile_of(&m, ADASLICE_METRIC_ROUGHNESS, 0.002, NULL);
    size_t i, nonzero = 0, off = 0;
    CHECK(p.bin_count == 3500 && p.z0 == 3);
    CHECK(p.phi[0] == 1 && p.phi[p.bin_count - 1] == 1);
    for (i = 1; i + 1 < p.bin_count; i++) nonzero += p.phi[i] != 0;
    CHECK(nonzero == 0);
    /* roughness: 1/sin(90 deg) = 1 on the wall, the clamp on the caps */
    CHECK(q.phi[0] == ADASLICE_DEFAULT_ROUGHNESS_MAX && q.phi[q.bin_count - 1] == ADASLICE_DEFAULT_ROUGHNESS_MAX);
    for (i = 1; i + 1 < q.bin_count; i++) off += fabs(q.phi[i] - 1) > 1e-12;
    CHECK(off == 0);
    adaslice_profile_free(&p);
    adaslice_profile_free(&q);
    gen_free(&m);
}

/* Fig. 4: a box with a cylinder on top. Its top face is a jump in the profile
   at a height off the tmax grid; the §3.3 pre-pass must put a plane there. */
static void box_with_cylinder_gets_a_plane_at_the_step(void)
{
    adaslice_mesh m = gen_box(-10, -10, 0, 10, 10, 10.013);
    adaslice_mesh c = gen_cylinder(5, 8, 64, 10.013);
    adaslice_profile p;
    adaslice_plan_options o;
    adaslice_plan with, without;
    size_t i, step = (size_t)(10.013 / 0.002), has_with = 0, has_without = 0;
    gen_append(&m, &c);
    p = profile_of(&m, ADASLICE_METRIC_CUSP, 0.002, NULL);
    CHECK(p.phi[step] == 1 && p.phi[step - 1] == 0 && p.phi[step + 1] == 0);
    memset(&o, 0, sizeof o);
    CHECK(adaslice_plan_profile(&p, &o, &with, NULL) == ADASLICE_OK);
    o.sharp = ADASLICE_SHARP_OFF;
    CHECK(adaslice_plan_profile(&p, &o, &without, NULL) == ADASLICE_OK);
    for (i = 0; i <= with.layer_count; i++) has_with += with.planes[i] == step;
    for (i = 0; i <= without.layer_count; i++) has_without += without.planes[i] == step;
    CHECKF(has_with == 1 && with.forced_planes == 1, "plane at the step: %zu, forced %zu", has_with, with.forced_planes);
    CHECK(has_without == 0 && without.forced_planes == 0);
    CHECK(with.worst_error <= 0.065 && without.worst_error <= 0.065);
    adaslice_plan_free(&with);
    adaslice_plan_free(&without);
    adaslice_profile_free(&p);
    gen_free(&m);
    gen_free(&c);
}

/* Vertex j of ring r of gen_sphere: r = 0 is the top pole, r = stacks the bottom. */
static const float *ring_vertex(const adaslice_mesh *m, int slices, int stacks, int r, int j)
{
    if (r == 0) return m->vertices;
    if (r == stacks) return m->vertices + 3 * (m->vertex_count - 1);
    return m->vertices + 3 * (1 + (r - 1) * slices + j % slices);
}

static void sphere_area_is_a_circle(void)
{
    static const int tess[3][2] = {{12, 8}, {48, 24}, {192, 96}};
    double R = 10, bin = 0.002;
    int t;
    for (t = 0; t < 3; t++) {
        int slices = tess[t][0], stacks = tess[t][1];
        adaslice_mesh m = gen_sphere(R, slices, stacks, 0);
        adaslice_profile p = profile_of(&m, ADASLICE_METRIC_VOLUME, bin, NULL);
        double dth = M_PI / stacks, poly = slices / 2.0 * sin(2 * M_PI / slices);
        /* the polygon inscribed in each circle loses (1 - sinc) of its area and
           the straight band between two rings sags up to R(1 - cos(dth/2)) */
        double tol = M_PI * R * R * ((1 - poly / M_PI) + 2 * (1 - cos(dth / 2))) + 1e-6;
        double worst = 0, worst_tess = 0;
        size_t i;
        for (i = 0; i < p.bin_count; i++) {
            double z = (i + 0.5) * bin, d;
            /* the cut through the band of the mesh's own (float) vertices: each
               meridian edge meets z at one point; shoelace over those */
            double a = 0, x0 = 0, y0 = 0, xp = 0, yp = 0;
            int k = 0, j;
            while (k + 1 < stacks && ring_vertex(&m, slices, stacks, k + 1, 0)[2] > z) k++;
            for (j = 0; j <= slices; j++) {
                const float *hi_v = ring_vertex(&m, slices, stacks, k, j), *lo_v = ring_vertex(&m, slices, stacks, k + 1, j);
                double u = (z - lo_v[2]) / ((double)hi_v[2] - lo_v[2]);
                double x = lo_v[0] + u * ((double)hi_v[0] - lo_v[0]), y = lo_v[1] + u * ((double)hi_v[1] - lo_v[1]);
                if (j == 0) { x0 = x; y0 = y; }
                else a += xp * y - yp * x;
                xp = x; yp = y;
            }
            (void)x0; (void)y0;
            d = fabs(p.area[i] - 0.5 * fabs(a));
            if (d > worst_tess) worst_tess = d;
            d = fabs(p.area[i] - M_PI * (R * R - (z - R) * (z - R)));
            if (d > worst) worst = d;
            CHECK(p.phi[i] == p.area[i]);
        }
        CHECKF(worst_tess < 1e-9 * R * R, "%dx%d: %g mm^2 from the polygon formula", slices, stacks, worst_tess);
        CHECKF(worst <= tol, "%dx%d: %g mm^2 from pi(R^2-(z-R)^2), tolerance %g", slices, stacks, worst, tol);
        adaslice_profile_free(&p);
        gen_free(&m);
    }
}

/* eq. 14 on a cone: A = k (h - z)^2, so |A'|/A = 2 / (h - z); the forward
   difference over one bin is off by about bin / (h - z) of that. */
static void cone_area_deviation_is_two_over_depth(void)
{
    double r = 6, h = 9, bin = 0.002;
    adaslice_mesh m = gen_cone(r, h, 96, 0);
    adaslice_profile p = profile_of(&m, ADASLICE_METRIC_AREA, bin, NULL);
    size_t i, off = 0;
    for (i = 0; i < p.bin_count; i++) {
        double z = (i + 0.5) * bin, want = 2 / (h - z);
        if (h - z < 1) break;
        off += fabs(p.phi[i] - want) > want * (2 * bin / (h - z - bin)) + 1e-9;
    }
    CHECKF(off == 0, "%zu bins off 2/(h-z)", off);
    adaslice_profile_free(&p);
    gen_free(&m);
}

static void weights_scale_the_profile(void)
{
    adaslice_mesh m = gen_sphere(5, 24, 12, 0);
    float *w = (float *)malloc(m.triangle_count * sizeof(float));
    adaslice_metric metrics[3] = {ADASLICE_METRIC_CUSP, ADASLICE_METRIC_ROUGHNESS, ADASLICE_METRIC_VOLUME};
    size_t i, j, off = 0, upper = 0;
    for (i = 0; i < m.triangle_count; i++) w[i] = 0.5f;
    for (j = 0; j < 3; j++) {
        adaslice_profile a = profile_of(&m, metrics[j], 0.002, NULL), b = profile_of(&m, metrics[j], 0.002, w);
        for (i = 0; i < a.bin_count; i++) off += b.phi[i] != 0.5 * a.phi[i];
        adaslice_profile_free(&a);
        adaslice_profile_free(&b);
    }
    CHECK(off == 0);
    /* weight only on triangles wholly above the equator: zero below the
       lowest weighted vertex, positive above it */
    {
        float zw = 100;
        for (i = 0; i < m.triangle_count; i++) {
            float *v0 = m.vertices + 3 * m.triangles[3 * i], *v1 = m.vertices + 3 * m.triangles[3 * i + 1],
                  *v2 = m.vertices + 3 * m.triangles[3 * i + 2];
            w[i] = (v0[2] > 5.001f && v1[2] > 5.001f && v2[2] > 5.001f) ? 1.0f : 0.0f;
            if (w[i] > 0 && v0[2] < zw) zw = v0[2];
            if (w[i] > 0 && v1[2] < zw) zw = v1[2];
            if (w[i] > 0 && v2[2] < zw) zw = v2[2];
        }
        {
            adaslice_profile b = profile_of(&m, ADASLICE_METRIC_CUSP, 0.002, w);
            for (i = 0; i < b.bin_count; i++) {
                if ((i + 1) * 0.002 < zw - 1e-9) off += b.phi[i] != 0;
                else if (i * 0.002 > zw + 1e-9) upper += b.phi[i] == 0;
            }
            CHECKF(off == 0 && upper == 0 && zw > 5 && zw < 7, "%zu bins below %g weighted, %zu above not", off, zw, upper);
            adaslice_profile_free(&b);
        }
    }
    w[3] = 1.5f;
    {
        adaslice_profile_options o;
        adaslice_profile p;
        adaslice_error e;
        memset(&o, 0, sizeof o);
        o.weights = w;
        CHECK(adaslice_profile_exact(&m, &o, &p, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "triangle 3"));
    }
    free(w);
    gen_free(&m);
}

void test_profiles(void)
{
    RUN(sphere_cusp_is_distance_from_equator);
    RUN(cone_cusp_is_constant);
    RUN(cylinder_cusp_is_zero_but_caps);
    RUN(box_with_cylinder_gets_a_plane_at_the_step);
    RUN(sphere_area_is_a_circle);
    RUN(cone_area_deviation_is_two_over_depth);
    RUN(weights_scale_the_profile);
}
