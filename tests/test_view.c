/* Viewpoint importance: the fraction of view directions from which each face
   is seen first, against a closed form (a sphere under the upper hemisphere:
   1 - theta/pi), a hidden cavity (never seen) and a brute-force ray cast from
   every face's centroid against every triangle. */
#include "../adaslice.h"
#include "check.h"
#include "meshgen.h"
#include <math.h>
#include <string.h>

static void centroid_normal(const adaslice_mesh *m, size_t t, double c[3], double n[3])
{
    const float *a = m->vertices + 3 * m->triangles[3 * t], *b = m->vertices + 3 * m->triangles[3 * t + 1],
                *d = m->vertices + 3 * m->triangles[3 * t + 2];
    double u[3], w[3], len;
    int k;
    for (k = 0; k < 3; k++) { c[k] = ((double)a[k] + b[k] + d[k]) / 3; u[k] = (double)b[k] - a[k]; w[k] = (double)d[k] - a[k]; }
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
    len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (k = 0; k < 3; k++) n[k] /= len;
}

static void a_hidden_cavity_is_never_seen(void)
{
    adaslice_mesh m = gen_box(0, 0, 0, 10, 8, 6), cavity = gen_box(3, 2, 2, 6, 5, 4);
    float *w;
    size_t t;
    double top = 0, bottom = 0;
    for (t = 0; t < cavity.triangle_count; t++) {
        uint32_t *c = cavity.triangles + 3 * t, x = c[1];
        c[1] = c[2];
        c[2] = x;
    }
    gen_append(&m, &cavity);
    w = (float *)malloc(m.triangle_count * sizeof *w);
    CHECK(adaslice_view_importance(&m, w, NULL, NULL) == ADASLICE_OK);
    for (t = 0; t < 12; t++) {
        double c[3], n[3];
        centroid_normal(&m, t, c, n);
        if (n[2] > 0.9) top = top > w[t] ? top : w[t];
        if (n[2] < -0.9) bottom = bottom > w[t] ? bottom : w[t];
    }
    for (t = 12; t < m.triangle_count; t++) CHECKF(w[t] == 0, "cavity face %zu seen from %g of the views", t, w[t]);
    CHECKF(top == 1 && bottom == 0, "top %g, bottom %g", top, bottom);
    free(w);
    gen_free(&m);
    gen_free(&cavity);
}

/* Seen from the upper hemisphere, a convex part's face whose normal is theta
   from +z is seen from the lune of directions within 90 degrees of its normal:
   1 - theta/pi of them. Allowed: the lattice's unevenness over a lune, and
   views so oblique that a face covers no pixel centre. */
static void a_sphere_follows_the_closed_form(void)
{
    adaslice_mesh s = gen_sphere(5, 32, 16, 0);
    adaslice_view_options o;
    float *w = (float *)malloc(s.triangle_count * sizeof *w);
    double ring_lo[24], ring_hi[24], ring_sum[24], worst = 0;
    size_t t, ring_n[24];
    int k;
    memset(&o, 0, sizeof o);
    o.count = 160;
    o.resolution = 512;
    CHECK(adaslice_view_importance(&s, w, &o, NULL) == ADASLICE_OK);
    for (k = 0; k < 24; k++) { ring_lo[k] = 2; ring_hi[k] = -1; ring_sum[k] = 0; ring_n[k] = 0; }
    for (t = 0; t < s.triangle_count; t++) {
        double c[3], n[3], theta, want;
        centroid_normal(&s, t, c, n);
        theta = acos(n[2] > 1 ? 1 : n[2] < -1 ? -1 : n[2]);
        want = 1 - theta / M_PI;
        if (fabs(w[t] - want) > worst) worst = fabs(w[t] - want);
        k = (int)(theta / M_PI * 24);
        if (k > 23) k = 23;
        if (w[t] < ring_lo[k]) ring_lo[k] = w[t];
        if (w[t] > ring_hi[k]) ring_hi[k] = w[t];
        ring_sum[k] += w[t];
        ring_n[k]++;
    }
    CHECKF(worst <= 0.05, "a face differs from 1 - theta/pi by %g", worst);
    for (k = 0; k < 24; k++) {
        CHECKF(ring_n[k] == 0 || ring_hi[k] - ring_lo[k] <= 0.05, "latitude band %d: %g to %g", k, ring_lo[k], ring_hi[k]);
        if (k && ring_n[k] && ring_n[k - 1])
            CHECKF(ring_sum[k] / (double)ring_n[k] < ring_sum[k - 1] / (double)ring_n[k - 1], "band %d not below band %d", k, k - 1);
    }
    free(w);
    gen_free(&s);
}

/* The ray from p along d meets triangle t at some s > 0 (Moller-Trumbore). */
static int ray_hits(const adaslice_mesh *m, size_t t, const double p[3], const double d[3])
{
    const float *a = m->vertices + 3 * m->triangles[3 * t], *b = m->vertices + 3 * m->triangles[3 * t + 1],
                *c = m->vertices + 3 * m->triangles[3 * t + 2];
    double e1[3], e2[3], h[3], q[3], sv[3], det, f, u, v, s;
    int k;
    for (k = 0; k < 3; k++) { e1[k] = (double)b[k] - a[k]; e2[k] = (double)c[k] - a[k]; sv[k] = p[k] - a[k]; }
    h[0] = d[1] * e2[2] - d[2] * e2[1]; h[1] = d[2] * e2[0] - d[0] * e2[2]; h[2] = d[0] * e2[1] - d[1] * e2[0];
    det = e1[0] * h[0] + e1[1] * h[1] + e1[2] * h[2];
    if (fabs(det) < 1e-12) return 0;
    f = 1 / det;
    u = f * (sv[0] * h[0] + sv[1] * h[1] + sv[2] * h[2]);
    if (u < 0 || u > 1) return 0;
    q[0] = sv[1] * e1[2] - sv[2] * e1[1]; q[1] = sv[2] * e1[0] - sv[0] * e1[2]; q[2] = sv[0] * e1[1] - sv[1] * e1[0];
    v = f * (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]);
    if (v < 0 || u + v > 1) return 0;
    s = f * (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]);
    return s > 1e-9;
}

/* A ball over a plate shades part of it: every face's visibility along every
   direction against a ray from its centroid past every other triangle. Faces
   only partly hidden may go either way (the raster sees any pixel of them). */
static void visibility_agrees_with_a_brute_force_ray_cast(void)
{
    adaslice_mesh m = gen_box(-8, -8, 0, 8, 8, 1), ball = gen_sphere(3, 16, 8, 4);
    double dirs[3 * 48];
    float *w;
    size_t t, j, agree = 0, pairs = 0;
    int k;
    gen_append(&m, &ball);
    /* the plate's top as a grid of facets small enough to be hidden or not */
    {
        adaslice_mesh plate = gen_alloc(17 * 17, 2 * 16 * 16);
        int x, y;
        for (y = 0; y <= 16; y++)
            for (x = 0; x <= 16; x++) gen_vertex(&plate, -8 + x, -8 + y, 1.001);
        for (y = 0; y < 16; y++)
            for (x = 0; x < 16; x++) {
                uint32_t a = (uint32_t)(y * 17 + x);
                gen_triangle(&plate, a, a + 1, a + 18);
                gen_triangle(&plate, a, a + 18, a + 17);
            }
        gen_append(&m, &plate);
        gen_free(&plate);
    }
    adaslice_fibonacci_directions(48, dirs); /* the first 24: the upper hemisphere */
    w = (float *)malloc(m.triangle_count * sizeof *w);
    for (k = 0; k < 24; k++) {
        CHECK(adaslice_view_importance(&m, w, &(adaslice_view_options){dirs + 3 * k, 1, 512, NULL}, NULL) == ADASLICE_OK);
        for (t = 0; t < m.triangle_count; t++) {
            double c[3], n[3], p[3];
            int seen;
            centroid_normal(&m, t, c, n);
            seen = n[0] * dirs[3 * k] + n[1] * dirs[3 * k + 1] + n[2] * dirs[3 * k + 2] > 1e-9;
            for (j = 0; j < 3; j++) p[j] = c[j] + 1e-6 * n[j];
            for (j = 0; seen && j < m.triangle_count; j++) if (j != t && ray_hits(&m, j, p, dirs + 3 * k)) seen = 0;
            agree += seen == (w[t] > 0);
            pairs++;
        }
    }
    CHECKF((double)agree >= 0.97 * (double)pairs, "%zu of %zu face-direction pairs agree", agree, pairs);
    free(w);
    gen_free(&m);
    gen_free(&ball);
}

static void bad_views_are_refused(void)
{
    adaslice_mesh m = gen_box(0, 0, 0, 1, 1, 1);
    float w[12];
    double zero[6] = {0, 0, 1, 0, 0, 0}, huge[3] = {1e308, 1e308, 1e308};
    adaslice_error e;
    CHECK(adaslice_view_importance(&m, w, &(adaslice_view_options){NULL, 0, 9000, NULL}, &e) == ADASLICE_ERR_ARGUMENT &&
          strstr(e.message, "9000"));
    CHECK(adaslice_view_importance(&m, w, &(adaslice_view_options){zero, 2, 0, NULL}, &e) == ADASLICE_ERR_ARGUMENT &&
          strstr(e.message, "direction 2"));
    CHECK(adaslice_view_importance(&m, w, &(adaslice_view_options){zero, 0, 0, NULL}, &e) == ADASLICE_ERR_ARGUMENT);
    CHECK(adaslice_view_importance(&m, NULL, NULL, &e) == ADASLICE_ERR_ARGUMENT);
    /* a huge direction is still a direction: the top, seen from straight above */
    CHECK(adaslice_view_importance(&m, w, &(adaslice_view_options){huge, 1, 0, NULL}, &e) == ADASLICE_OK);
    gen_free(&m);
    /* a part near the floats' largest overflowed when turned: "out of memory" for a grid of NaN pixels */
    m = gen_box(0, 0, 0, 3e38f, 3e38f, 3e38f);
    CHECKF(adaslice_view_importance(&m, w, NULL, &e) == ADASLICE_ERR_OVERFLOW && strstr(e.message, "across"), "%s", e.message);
    gen_free(&m);
}

/* The preview shows each face in its own colour when given them: a box with
   a red top and blue sides, seen from above, shows both and nothing else. */
static void the_preview_paints_faces_their_colours(void)
{
    adaslice_mesh m = gen_box(0, 0, 0, 10, 8, 6);
    unsigned char colours[36], *rgb = (unsigned char *)malloc(200 * 150 * 3);
    adaslice_preview_options o;
    size_t t, red = 0, blue = 0, other = 0, p;
    for (t = 0; t < 12; t++) {
        double c[3], n[3];
        centroid_normal(&m, t, c, n);
        colours[3 * t] = n[2] > 0.9 ? 255 : 0;
        colours[3 * t + 1] = 0;
        colours[3 * t + 2] = n[2] > 0.9 ? 0 : 255;
    }
    memset(&o, 0, sizeof o);
    o.face_colours = colours;
    CHECK(adaslice_preview(&m, 200, 150, &o, rgb, NULL) == ADASLICE_OK);
    for (p = 0; p < 200 * 150; p++) {
        const unsigned char *c = rgb + 3 * p;
        if (!c[0] && !c[1] && !c[2]) continue;
        if (c[0] > 0 && !c[1] && !c[2]) red++;
        else if (!c[0] && !c[1] && c[2] > 0) blue++;
        else other++;
    }
    CHECKF(red > 1000 && blue > 1000 && other == 0, "%zu red, %zu blue, %zu other pixels", red, blue, other);
    free(rgb);
    gen_free(&m);
}

void test_view(void)
{
    RUN(the_preview_paints_faces_their_colours);
    RUN(a_hidden_cavity_is_never_seen);
    RUN(a_sphere_follows_the_closed_form);
    RUN(visibility_agrees_with_a_brute_force_ray_cast);
    RUN(bad_views_are_refused);
}
