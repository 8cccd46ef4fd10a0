/* Welding within a tolerance, mean curvature, mesh saliency (checked against
   an all-pairs reference), weighted plans and the curvature planner. */
#include "check.h"
#include "../adaslice.h"
#include "meshgen.h"
#include "failing_alloc.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------ test solids */

/* A surface of revolution about z: profile points (r[k], z[k]) from the bottom
   pole (r = 0) to the top pole (r = 0), `slices` around, wound outwards. */
static adaslice_mesh revolve(const double *r, const double *z, int count, int slices)
{
    adaslice_mesh m = gen_alloc((size_t)(slices * (count - 2) + 2), (size_t)(2 * slices * (count - 2)));
    uint32_t bottom = gen_vertex(&m, 0, 0, z[0]), top;
    int i, k;
    for (k = 1; k < count - 1; k++)
        for (i = 0; i < slices; i++)
            gen_vertex(&m, r[k] * cos(2 * M_PI * i / slices), r[k] * sin(2 * M_PI * i / slices), z[k]);
    top = gen_vertex(&m, 0, 0, z[count - 1]);
#define RING(k, i) ((uint32_t)(1 + ((k) - 1) * slices + (i) % slices))
    for (i = 0; i < slices; i++) {
        gen_triangle(&m, bottom, RING(1, i + 1), RING(1, i));
        gen_triangle(&m, RING(count - 2, i), RING(count - 2, i + 1), top);
        for (k = 1; k < count - 2; k++) {
            gen_triangle(&m, RING(k, i), RING(k, i + 1), RING(k + 1, i + 1));
            gen_triangle(&m, RING(k, i), RING(k + 1, i + 1), RING(k + 1, i));
        }
    }
#undef RING
    return m;
}

/* A cylinder of radius R from z = 0 to h under a hemisphere of radius R: flat
   bottom (H = 0), wall (H = 1/2R), cap (H = 1/R). */
static adaslice_mesh capped_cylinder(double R, double h, int slices)
{
    double r[128], z[128];
    int n = 0, k;
    for (k = 0; k <= 4; k++) { r[n] = R * k / 4; z[n++] = 0; }
    for (k = 1; k <= 40; k++) { r[n] = R; z[n++] = h * k / 40; }
    for (k = 1; k <= 30; k++) { r[n] = R * cos(M_PI / 2 * k / 30); z[n++] = h + R * sin(M_PI / 2 * k / 30); }
    r[n - 1] = 0;
    return revolve(r, z, n, slices);
}

/* An open sheet across x in [0, 10]: vertical (the plane y = 0) from z = 0 to
   5, then bending over along a quarter circle of radius rho to horizontal. */
static adaslice_mesh bent_sheet(double rho)
{
    enum { NX = 20, FLAT = 20, BEND = 24, ROWS = FLAT + BEND + 1 };
    adaslice_mesh m = gen_alloc((size_t)((NX + 1) * ROWS), (size_t)(2 * NX * (ROWS - 1)));
    int i, j;
    for (j = 0; j < ROWS; j++) {
        double a = j <= FLAT ? 0 : M_PI / 2 * (j - FLAT) / BEND;
        double y = j <= FLAT ? 0 : rho * (1 - cos(a)), z = j <= FLAT ? 5.0 * j / FLAT : 5 + rho * sin(a);
        for (i = 0; i <= NX; i++) gen_vertex(&m, 10.0 * i / NX, y, z);
    }
    for (j = 0; j + 1 < ROWS; j++)
        for (i = 0; i < NX; i++) {
            uint32_t a = (uint32_t)(j * (NX + 1) + i), b = a + 1, c = b + NX + 1, d = a + NX + 1;
            gen_triangle(&m, a, b, c);
            gen_triangle(&m, a, c, d);
        }
    return m;
}

/* A UV sphere of radius R about (0, 0, R) with a smooth bump of height A and
   angular width w around the unit direction u (pushed out along the radius). */
static adaslice_mesh bumped_sphere(double R, int stacks, const double u[3], double A, double w)
{
    adaslice_mesh m = gen_sphere(R, 2 * stacks, stacks, 0);
    size_t v;
    for (v = 0; v < m.vertex_count; v++) {
        float *p = m.vertices + 3 * v;
        double d[3] = {p[0], p[1], p[2] - R}, len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        double c = (d[0] * u[0] + d[1] * u[1] + d[2] * u[2]) / len, angle = acos(c > 1 ? 1 : c);
        double s = (R + A * exp(-(angle / w) * (angle / w))) / len;
        p[0] = (float)(d[0] * s); p[1] = (float)(d[1] * s); p[2] = (float)(d[2] * s + R);
    }
    return m;
}

static double face_angle(const adaslice_mesh *m, size_t t, const double u[3], double R)
{
    double c[3] = {0, 0, -R}, len, dot;
    int k, j;
    for (k = 0; k < 3; k++)
        for (j = 0; j < 3; j++) c[j] += m->vertices[3 * m->triangles[3 * t + k] + j] / 3.0;
    len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    dot = (c[0] * u[0] + c[1] * u[1] + c[2] * u[2]) / len;
    return acos(dot > 1 ? 1 : dot);
}

/* with room for `spare` more vertices and triangles */
static adaslice_mesh copy_mesh(const adaslice_mesh *m, size_t spare)
{
    adaslice_mesh c = gen_alloc(m->vertex_count + spare, m->triangle_count + spare);
    memcpy(c.vertices, m->vertices, m->vertex_count * 3 * sizeof(float));
    memcpy(c.triangles, m->triangles, m->triangle_count * 3 * sizeof(uint32_t));
    c.vertex_count = m->vertex_count;
    c.triangle_count = m->triangle_count;
    return c;
}

/* ---------------------------------------------------------------- welding */

static adaslice_result weld(adaslice_mesh *m, double tolerance, adaslice_error *e)
{
    adaslice_weld_options o;
    memset(&o, 0, sizeof o);
    o.tolerance = tolerance;
    return adaslice_mesh_weld(m, &o, e);
}

static void weld_within_merges_into_the_first_vertex_in_reach(void)
{
    /* along x with tolerance 1: 0 | 1.5 | 0.8 (within reach of both 0 and
       1.5: the first, 0, takes it) | 2.4 (0.9 from 1.5) | 3.3 (0.9 from 2.4,
       which merged away, and 1.8 from 1.5: kept) | 10 and 9.999 across a cell
       boundary at 10 */
    static const float xs[] = {0, 1.5f, 0.8f, 2.4f, 3.3f, 9.9995f, 10.0004f};
    static const uint32_t expect[] = {0, 1, 0, 1, 2, 3, 3};
    float v[3 * 7];
    uint32_t tri[3 * 5] = {0, 1, 2, 1, 3, 4, 2, 3, 5, 4, 5, 6, 0, 4, 6};
    adaslice_mesh m;
    adaslice_error e;
    size_t i;
    memset(&m, 0, sizeof m);
    for (i = 0; i < 7; i++) { v[3 * i] = xs[i]; v[3 * i + 1] = 0; v[3 * i + 2] = 0; }
    m.vertices = v; m.vertex_count = 7; m.triangles = tri; m.triangle_count = 5;
    CHECK(weld(&m, 1.0, &e) == ADASLICE_OK);
    CHECKF(m.vertex_count == 4, "kept %zu vertices", m.vertex_count);
    CHECK(v[0] == 0 && v[3] == 1.5f && v[6] == 3.3f && v[9] == 9.9995f);
    {
        static const uint32_t before[15] = {0, 1, 2, 1, 3, 4, 2, 3, 5, 4, 5, 6, 0, 4, 6};
        for (i = 0; i < 15; i++) CHECKF(tri[i] == expect[before[i]], "index %zu is %u", i, tri[i]);
    }
    CHECK(m.triangle_count == 5); /* the collapsed (0, 1, 0) stays, with its repeated index */
}

static void weld_within_zero_is_the_exact_weld(void)
{
    adaslice_mesh sphere = gen_sphere(3, 24, 12, 0), soup, again;
    adaslice_error e;
    size_t t;
    int k;
    soup = gen_alloc(3 * sphere.triangle_count, sphere.triangle_count);
    for (t = 0; t < sphere.triangle_count; t++) {
        for (k = 0; k < 3; k++) {
            const float *p = sphere.vertices + 3 * sphere.triangles[3 * t + k];
            gen_vertex(&soup, p[0], p[1], p[2]);
        }
        gen_triangle(&soup, (uint32_t)(3 * t), (uint32_t)(3 * t + 1), (uint32_t)(3 * t + 2));
    }
    again = copy_mesh(&soup, 0);
    CHECK(weld(&soup, 0, &e) == ADASLICE_OK && soup.vertex_count == sphere.vertex_count);
    /* a tolerance far below the edge length welds the same */
    CHECK(weld(&again, 1e-4, &e) == ADASLICE_OK && again.vertex_count == sphere.vertex_count);
    CHECK(memcmp(soup.triangles, again.triangles, 3 * soup.triangle_count * sizeof(uint32_t)) == 0);
    CHECK(weld(&again, -1, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "-1"));
    CHECK(weld(&again, NAN, &e) == ADASLICE_ERR_ARGUMENT);
    CHECK(weld(&again, 1e-300, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "too small"));
    CHECK(weld(NULL, 1, &e) == ADASLICE_ERR_ARGUMENT);
    gen_free(&sphere);
    gen_free(&soup);
    gen_free(&again);
}

/* ------------------------------------------------------------- curvature */

/* The largest |R H - 1| over a UV sphere's vertices. */
static double sphere_error(int stacks)
{
    adaslice_mesh m = gen_sphere(5, 2 * stacks, stacks, 0);
    double *H = (double *)malloc(m.vertex_count * sizeof *H), worst = 0;
    adaslice_error e;
    size_t i;
    CHECK(adaslice_mean_curvature(&m, H, NULL, &e) == ADASLICE_OK);
    for (i = 0; i < m.vertex_count; i++)
        if (fabs(5 * H[i] - 1) > worst) worst = fabs(5 * H[i] - 1);
    free(H);
    gen_free(&m);
    return worst;
}

/* With every vertex on the sphere and each fan symmetric about its vertex
   (the UV sphere's are, in longitude and latitude), the first-order terms of
   the cotangent Laplacian cancel and the error is second order in the
   angular step d = pi / stacks: measured 0.08 d^2 to 0.14 d^2 from 8 to 64
   stacks; the bound is 0.25 d^2. */
static void mean_curvature_of_a_sphere_is_one_over_r(void)
{
    int stacks;
    double previous = 0;
    for (stacks = 16; stacks <= 64; stacks *= 2) {
        double d = M_PI / stacks, worst = sphere_error(stacks);
        CHECKF(worst <= 0.25 * d * d, "%d stacks: |RH - 1| up to %g, above 0.25 d^2 = %g", stacks, worst, 0.25 * d * d);
        if (previous) CHECKF(worst < previous / 3, "%d stacks: %g, not a third of %g", stacks, worst, previous);
        previous = worst;
    }
}

/* A tilted square patch with its inner vertices jittered: the cotangent
   Laplacian of a linear function is exactly zero on any planar triangulation,
   so only rounding of the float coordinates remains (about 1e-6 mm over
   edges of 0.5 mm: H below 1e-4 per mm). Border vertices take their
   neighbours' 0. */
static void mean_curvature_of_a_plane_is_zero(void)
{
    enum { N = 20 };
    adaslice_mesh m = gen_alloc((N + 1) * (N + 1), 2 * N * N);
    double H[(N + 1) * (N + 1)], worst = 0;
    adaslice_error e;
    int i, j;
    unsigned seed = 7;
    for (j = 0; j <= N; j++)
        for (i = 0; i <= N; i++) {
            double x = 0.5 * i, y = 0.5 * j;
            if (i > 0 && i < N && j > 0 && j < N) {
                seed = seed * 1103515245u + 12345u; x += 0.15 * ((seed >> 16) % 1000 / 1000.0 - 0.5);
                seed = seed * 1103515245u + 12345u; y += 0.15 * ((seed >> 16) % 1000 / 1000.0 - 0.5);
            }
            gen_vertex(&m, x, y, 0.3 * x + 0.2 * y + 1);
        }
    for (j = 0; j < N; j++)
        for (i = 0; i < N; i++) {
            uint32_t a = (uint32_t)(j * (N + 1) + i);
            gen_triangle(&m, a, a + 1, a + N + 2);
            gen_triangle(&m, a, a + N + 2, a + N + 1);
        }
    CHECK(adaslice_mean_curvature(&m, H, NULL, &e) == ADASLICE_OK);
    for (i = 0; i < (N + 1) * (N + 1); i++) if (fabs(H[i]) > worst) worst = fabs(H[i]);
    CHECKF(worst < 1e-4, "|H| up to %g on a plane", worst);
    gen_free(&m);
}

/* An open hemisphere: its border vertices have half a fan, which would read
   about 1/edge; they take their neighbours' 1/R instead. Degenerate triangles
   (repeated corners, collinear corners, a face twice) leave every value finite. */
static void mean_curvature_on_borders_and_degenerate_triangles(void)
{
    adaslice_mesh m = gen_sphere(5, 64, 32, 0), broken;
    double *H = (double *)malloc((m.vertex_count + 3) * sizeof *H), worst = 0;
    adaslice_error e;
    size_t t, kept = 0, i;
    for (t = 0; t < m.triangle_count; t++) { /* keep the upper half */
        const uint32_t *c = m.triangles + 3 * t;
        if (m.vertices[3 * c[0] + 2] + m.vertices[3 * c[1] + 2] + m.vertices[3 * c[2] + 2] < 15) continue;
        memmove(m.triangles + 3 * kept++, c, 3 * sizeof *c);
    }
    m.triangle_count = kept;
    CHECK(adaslice_mean_curvature(&m, H, NULL, &e) == ADASLICE_OK);
    for (i = 0; i < m.vertex_count; i++)
        if (m.vertices[3 * i + 2] >= 5 && fabs(5 * H[i] - 1) > worst) worst = fabs(5 * H[i] - 1);
    CHECKF(worst < 0.01, "|RH - 1| up to %g on the open hemisphere", worst);
    broken = copy_mesh(&m, 3);
    gen_vertex(&broken, 20, 0, 0);
    gen_vertex(&broken, 21, 0, 0);
    gen_vertex(&broken, 22, 0, 0);
    gen_triangle(&broken, 0, 0, 1);                    /* repeated corner */
    gen_triangle(&broken, (uint32_t)m.vertex_count, (uint32_t)m.vertex_count + 1,
                 (uint32_t)m.vertex_count + 2);        /* collinear */
    gen_triangle(&broken, m.triangles[0], m.triangles[1], m.triangles[2]); /* twice */
    CHECK(adaslice_mean_curvature(&broken, H, NULL, &e) == ADASLICE_OK);
    for (i = 0; i < broken.vertex_count; i++) CHECKF(H[i] >= 0 && H[i] < 1e3, "H[%zu] = %g", i, H[i]);
    CHECK(H[m.vertex_count] == 0 && H[m.vertex_count + 2] == 0); /* in no triangle with area */
    free(H);
    gen_free(&m);
    gen_free(&broken);
}

/* --------------------------------------------------------------- saliency */

static const double BUMP_DIR[3] = {0.663413948, 0.556670399, 0.5}; /* latitude 30, longitude 40 degrees */

static double dist2(const adaslice_mesh *m, size_t a, size_t b)
{
    double d = 0;
    int k;
    for (k = 0; k < 3; k++) {
        double e = (double)m->vertices[3 * a + k] - m->vertices[3 * b + k];
        d += e * e;
    }
    return d;
}

/* each |H| capped at its largest neighbour's */
static void cap_at_neighbours(const adaslice_mesh *m, double *H)
{
    double *top = (double *)calloc(m->vertex_count, sizeof *top);
    size_t t, i;
    int k;
    for (t = 0; t < m->triangle_count; t++)
        for (k = 0; k < 3; k++) {
            uint32_t a = m->triangles[3 * t + k], b = m->triangles[3 * t + (k + 1) % 3];
            top[a] = H[b] > top[a] ? H[b] : top[a];
            top[b] = H[a] > top[b] ? H[a] : top[b];
        }
    for (i = 0; i < m->vertex_count; i++) H[i] = H[i] < top[i] ? H[i] : top[i];
    free(top);
}

/* The saliency of the manual by all pairs: every vertex within 2 sigma, no
   pooling. The mesh is indexed and every vertex is in a triangle with area. */
static void reference_saliency(const adaslice_mesh *m, float *face)
{
    static const double sigmas[8] = {2, 3, 4, 5, 6, 8, 10, 12};
    static const int surround[5] = {2, 4, 5, 6, 7};
    size_t n = m->vertex_count, i, j, t, top;
    double *H = (double *)malloc(n * sizeof *H), *G = (double *)malloc(8 * n * sizeof *G);
    double *S = (double *)malloc(n * sizeof *S), *sal = (double *)calloc(n, sizeof *sal);
    double lo[3], hi[3], eps = 0, best = 0;
    adaslice_error e;
    int s, k;
    CHECK(adaslice_mean_curvature(m, H, NULL, &e) == ADASLICE_OK);
    cap_at_neighbours(m, H);
    adaslice_mesh_bounds(m, lo, hi);
    for (k = 0; k < 3; k++) eps += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    eps = 0.003 * sqrt(eps);
    for (s = 0; s < 8; s++) {
        double sigma = sigmas[s] * eps;
        for (i = 0; i < n; i++) {
            double sw = 0, sh = 0;
            for (j = 0; j < n; j++) {
                double d2 = dist2(m, i, j), w = exp(-d2 / (2 * sigma * sigma));
                if (d2 < 4 * sigma * sigma) { sw += w; sh += w * H[j]; }
            }
            G[s * n + i] = sh / sw;
        }
    }
    for (s = 0; s < 5; s++) {
        double r = sigmas[s] * eps, sum = 0;
        size_t others = 0;
        for (i = 0, top = 0; i < n; i++) {
            S[i] = fabs(G[s * n + i] - G[surround[s] * n + i]);
            if (S[i] > S[top]) top = i;
        }
        for (i = 0; i < n; i++) {
            int peak = i != top;
            for (j = 0; j < n && peak; j++) if (S[j] > S[i] && dist2(m, i, j) <= r * r) peak = 0;
            if (peak) { sum += S[i]; others++; }
        }
        for (i = 0; i < n; i++) {
            double f = others ? 1 - sum / (others * S[top]) : 1;
            sal[i] += S[i] / S[top] * f * f;
        }
    }
    for (t = 0; t < m->triangle_count; t++) {
        double w = 0;
        for (k = 0; k < 3; k++) w += sal[m->triangles[3 * t + k]] / 3;
        face[t] = (float)w;
        if (w > best) best = w;
    }
    for (t = 0; t < m->triangle_count; t++) face[t] = (float)(face[t] / best);
    free(H); free(G); free(S); free(sal);
}

/* The library pools vertices into cells sigma/3 wide for the Gaussian means.
   A far-off triangle stretches the bounding box, so eps grows and the cells
   hold up to a dozen vertices of the sphere: the face weights stay within
   0.03 of the all-pairs definition. */
static void saliency_matches_all_pairs(void)
{
    adaslice_mesh m = bumped_sphere(1, 40, BUMP_DIR, 0.1, 0.2), far = gen_alloc(3, 1);
    float *lib, *ref;
    adaslice_error e;
    double worst = 0;
    size_t t;
    gen_triangle(&far, gen_vertex(&far, 20, 0, 0), gen_vertex(&far, 20.5, 0, 0), gen_vertex(&far, 20, 0.5, 0));
    gen_append(&m, &far);
    gen_free(&far);
    lib = (float *)malloc(m.triangle_count * sizeof *lib);
    ref = (float *)malloc(m.triangle_count * sizeof *ref);
    CHECK(adaslice_saliency(&m, lib, NULL, &e) == ADASLICE_OK);
    reference_saliency(&m, ref);
    for (t = 0; t < m.triangle_count; t++) if (fabs((double)lib[t] - ref[t]) > worst) worst = fabs((double)lib[t] - ref[t]);
    CHECKF(worst < 0.03, "face weights differ from all pairs by up to %g", worst);
    free(lib);
    free(ref);
    gen_free(&m);
}

static const float *sort_weights; /* qsort has no context argument */
static int heavier_first(const void *a, const void *b)
{
    float x = sort_weights[*(const size_t *)a], y = sort_weights[*(const size_t *)b];
    return x > y ? -1 : x < y;
}

/* The bump is the salient part: the faces weighing most lie on it. The weights
   are in [0, 1] with 1 reached, the caller's mesh is left alone, and the same
   solid as a triangle soup (as STL gives it) weighs the same after the weld. */
static void saliency_peaks_on_a_bump(void)
{
    adaslice_mesh m = bumped_sphere(10, 64, BUMP_DIR, 0.8, 0.12), before = copy_mesh(&m, 0), soup;
    float *w = (float *)malloc(m.triangle_count * sizeof *w), *ws = (float *)malloc(m.triangle_count * sizeof *ws);
    size_t *order = (size_t *)malloc(m.triangle_count * sizeof *order), t, top = m.triangle_count / 100, on = 0;
    adaslice_error e;
    double worst = 0;
    int k, max_seen = 0;
    CHECK(adaslice_saliency(&m, w, NULL, &e) == ADASLICE_OK);
    CHECK(m.vertex_count == before.vertex_count &&
          memcmp(m.vertices, before.vertices, 3 * m.vertex_count * sizeof(float)) == 0);
    for (t = 0; t < m.triangle_count; t++) {
        CHECKF(w[t] >= 0 && w[t] <= 1, "weight %g", w[t]);
        max_seen |= w[t] == 1;
        order[t] = t;
    }
    CHECK(max_seen);
    sort_weights = w;
    qsort(order, m.triangle_count, sizeof *order, heavier_first);
    CHECKF(face_angle(&m, order[0], BUMP_DIR, 10) < 2 * 0.12, "the heaviest face is %g rad from the bump",
           face_angle(&m, order[0], BUMP_DIR, 10));
    for (t = 0; t < top; t++) on += face_angle(&m, order[t], BUMP_DIR, 10) < 3 * 0.12;
    CHECKF(on == top, "%zu of the %zu heaviest faces lie on the bump", on, top);

    soup = gen_alloc(3 * m.triangle_count, m.triangle_count);
    for (t = 0; t < m.triangle_count; t++) {
        for (k = 0; k < 3; k++) {
            const float *p = m.vertices + 3 * m.triangles[3 * t + k];
            gen_vertex(&soup, p[0], p[1], p[2]);
        }
        gen_triangle(&soup, (uint32_t)(3 * t), (uint32_t)(3 * t + 1), (uint32_t)(3 * t + 2));
    }
    CHECK(adaslice_saliency(&soup, ws, NULL, &e) == ADASLICE_OK);
    for (t = 0; t < m.triangle_count; t++) if (fabs((double)w[t] - ws[t]) > worst) worst = fabs((double)w[t] - ws[t]);
    CHECKF(worst < 1e-4, "the soup's weights differ by %g", worst);

    CHECK(adaslice_saliency(&m, NULL, NULL, &e) == ADASLICE_ERR_ARGUMENT);
    free(w); free(ws); free(order);
    gen_free(&m); gen_free(&before); gen_free(&soup);
}

/* Mean thickness of the layers whose middle lies in [z0, z1), and their count. */
static double mean_thickness(const adaslice_plan *p, double z0, double z1, size_t *count)
{
    double sum = 0;
    size_t k;
    *count = 0;
    for (k = 0; k < p->layer_count; k++) {
        double mid = 0.5 * (p->layers[k].z_bottom + p->layers[k].z_top);
        if (mid >= z0 && mid < z1) { sum += p->layers[k].thickness; ++*count; }
    }
    return *count ? sum / (double)*count : 0;
}

/* The bump sits at latitude 30 degrees, so the heights of latitude -30 are
   the same sphere without it. Weighted by saliency, the optimal plan is
   thinner at the bump's heights than at those mirror heights, and away from
   the bump it has no more layers than the unweighted plan. Weights only ever
   lower phi, so eps must bind on the bump's own faces (about 0.3 weighted):
   0.035 mm, which needs layers of 35 um at the poles, hence tmin 25 um. */
static void weighted_plan_is_thinner_at_the_bump(void)
{
    adaslice_mesh m = bumped_sphere(10, 64, BUMP_DIR, 0.8, 0.12);
    float *w = (float *)malloc(m.triangle_count * sizeof *w);
    adaslice_profile_options po;
    adaslice_profile plain, weighted;
    adaslice_plan_options o;
    adaslice_plan a, b;
    adaslice_error e;
    double z0 = 0, lo[3], hi[3], bump_lo, bump_hi, bump, mirror;
    size_t n_bump, n_mirror, k, outside_plain = 0, outside_weighted = 0;
    CHECK(adaslice_saliency(&m, w, NULL, &e) == ADASLICE_OK);
    adaslice_mesh_bounds(&m, lo, hi);
    z0 = lo[2];
    /* the heights of the bump's core, a width around latitude 30 degrees, from the part's bottom */
    bump_lo = 10 + 10 * sin(M_PI / 6 - 0.12) - z0;
    bump_hi = 10.8 + 10 * sin(M_PI / 6 + 0.12) - z0;
    memset(&po, 0, sizeof po);
    CHECK(adaslice_profile_exact(&m, &po, &plain, &e) == ADASLICE_OK);
    po.weights = w;
    CHECK(adaslice_profile_exact(&m, &po, &weighted, &e) == ADASLICE_OK);
    memset(&o, 0, sizeof o);
    o.eps = 0.035;
    o.tmin = 0.025;
    CHECK(adaslice_plan_profile(&plain, &o, &a, &e) == ADASLICE_OK);
    CHECK(adaslice_plan_profile(&weighted, &o, &b, &e) == ADASLICE_OK);
    bump = mean_thickness(&b, bump_lo, bump_hi, &n_bump);
    mirror = mean_thickness(&b, 20 - z0 - bump_hi, 20 - z0 - bump_lo, &n_mirror);
    CHECKF(n_bump && n_mirror && bump < 0.8 * mirror, "weighted: %g mm at the bump, %g mm at the mirror heights", bump, mirror);
    for (k = 0; k < a.layer_count; k++) {
        double mid = 0.5 * (a.layers[k].z_bottom + a.layers[k].z_top);
        outside_plain += mid < bump_lo || mid >= bump_hi;
    }
    for (k = 0; k < b.layer_count; k++) {
        double mid = 0.5 * (b.layers[k].z_bottom + b.layers[k].z_top);
        outside_weighted += mid < bump_lo || mid >= bump_hi;
    }
    CHECKF(outside_weighted <= outside_plain, "away from the bump: %zu weighted layers, %zu unweighted",
           outside_weighted, outside_plain);
    adaslice_plan_free(&a);
    adaslice_plan_free(&b);
    adaslice_profile_free(&plain);
    adaslice_profile_free(&weighted);
    free(w);
    gen_free(&m);
}

/* ---------------------------------------------------- the curvature planner */

/* The curvature method with these options (NULL: the defaults). */
static adaslice_result plan_curvature(const adaslice_profile *p, const double *kappa, const adaslice_plan_options *o,
                                      adaslice_plan *plan, adaslice_error *e)
{
    adaslice_plan_options po;
    if (o) po = *o; else memset(&po, 0, sizeof po);
    po.method = ADASLICE_METHOD_CURVATURE;
    po.curvature = kappa;
    return adaslice_plan_profile(p, &po, plan, e);
}

/* Planes on bin boundaries from 0 to N, every layer within tmin..tmax and its
   error the metric profile's. */
static void check_plan(const adaslice_profile *p, const adaslice_plan *plan, double eps)
{
    size_t k, over = 0;
    double worst = 0;
    CHECK(plan->layer_count > 0 && plan->planes[0] == 0 && plan->planes[plan->layer_count] == p->bin_count);
    for (k = 0; k < plan->layer_count; k++) {
        uint32_t len = plan->planes[k + 1] - plan->planes[k];
        double err = adaslice_layer_error(p, plan->planes[k], plan->planes[k + 1]);
        CHECKF(len >= plan->bins_min && len <= plan->bins_max, "layer %zu: %u bins", k, len);
        CHECK(plan->layers[k].error == err && plan->layers[k].z_bottom == plan->planes[k] * p->bin);
        if (err > worst) worst = err;
        over += err > eps;
    }
    CHECK(plan->worst_error == worst && plan->over_eps == over);
}

/* The sheet's vertical half is flat (k = 0): the linear mapping gives it tmax;
   its bend has k = 1/(2 rho), the top 95% of the part, so k / kmax is about 1
   there and layers are tmin. The step mapping gives exactly tmin and tmax;
   exp gives tmin + (tmax - tmin) e^-2 in the bend. */
static void curvature_plan_of_a_bent_sheet(void)
{
    static const adaslice_mapping maps[3] = {ADASLICE_MAPPING_LINEAR, ADASLICE_MAPPING_STEP, ADASLICE_MAPPING_EXP};
    static const double bend[3][2] = {{0.05, 0.056}, {0.05, 0.05}, {0.0605, 0.0665}}; /* thickness range in the bend */
    adaslice_mesh m = bent_sheet(2);
    adaslice_profile p;
    adaslice_profile_options po;
    adaslice_plan_options co;
    adaslice_plan plan;
    adaslice_error e;
    double *kappa;
    size_t k, flat = 0, bent = 0;
    int i;
    memset(&po, 0, sizeof po);
    CHECK(adaslice_profile_exact(&m, &po, &p, &e) == ADASLICE_OK);
    kappa = (double *)malloc(p.bin_count * sizeof *kappa);
    CHECK(adaslice_curvature_profile(&m, &p, NULL, kappa, &e) == ADASLICE_OK);
    CHECKF(fabs(kappa[p.bin_count - 200] - 0.25) < 0.01 && kappa[100] < 1e-6, "k %g in the bend, %g low down",
           kappa[p.bin_count - 200], kappa[100]);
    for (i = 0; i < 3; i++) {
        memset(&co, 0, sizeof co);
        co.mapping = maps[i];
        CHECK(plan_curvature(&p, kappa, &co, &plan, &e) == ADASLICE_OK);
        check_plan(&p, &plan, ADASLICE_DEFAULT_EPS);
        for (k = 0; k + 1 < plan.layer_count; k++) { /* the last layer holds the rest */
            const adaslice_layer *l = &plan.layers[k];
            if (l->z_top < 4.7) {
                CHECKF(fabs(l->thickness - 0.15) < 1e-9, "mapping %d: flat layer at %g is %g mm", i, l->z_bottom, l->thickness);
                flat++;
            } else if (l->z_bottom > 5.3) {
                CHECKF(l->thickness >= bend[i][0] - 1e-9 && l->thickness <= bend[i][1] + 1e-9,
                       "mapping %d: bent layer at %g is %g mm", i, l->z_bottom, l->thickness);
                bent++;
            }
        }
        adaslice_plan_free(&plan);
    }
    CHECK(flat > 60 && bent > 60);
    free(kappa);
    adaslice_profile_free(&p);
    gen_free(&m);
}

/* Wall H = 1/(2R), cap H = 1/R: the cap (the part's top 95%) gets about tmin,
   the wall about halfway, linear mapping. */
static void curvature_plan_of_a_capped_cylinder(void)
{
    adaslice_mesh m = capped_cylinder(5, 10, 96);
    adaslice_profile p;
    adaslice_plan_options co;
    adaslice_plan plan;
    adaslice_error e;
    double *kappa, wall, cap;
    size_t n_wall, n_cap;
    CHECK(adaslice_profile_exact(&m, NULL, &p, &e) == ADASLICE_OK);
    kappa = (double *)malloc(p.bin_count * sizeof *kappa);
    CHECK(adaslice_curvature_profile(&m, &p, NULL, kappa, &e) == ADASLICE_OK);
    memset(&co, 0, sizeof co);
    CHECK(plan_curvature(&p, kappa, &co, &plan, &e) == ADASLICE_OK);
    check_plan(&p, &plan, ADASLICE_DEFAULT_EPS);
    wall = mean_thickness(&plan, 1, 9.5, &n_wall);
    cap = mean_thickness(&plan, 10.5, 14.5, &n_cap);
    CHECKF(n_wall && fabs(wall - 0.1) < 0.006, "wall layers %g mm", wall);
    CHECKF(n_cap && cap < 0.06, "cap layers %g mm", cap);
    adaslice_plan_free(&plan);
    free(kappa);
    adaslice_profile_free(&p);
    gen_free(&m);
}

static void curvature_plan_arguments(void)
{
    adaslice_mesh m = capped_cylinder(5, 10, 24);
    adaslice_profile p;
    adaslice_plan_options co;
    adaslice_plan plan;
    adaslice_error e;
    double *kappa;
    CHECK(adaslice_profile_exact(&m, NULL, &p, &e) == ADASLICE_OK);
    kappa = (double *)malloc(p.bin_count * sizeof *kappa);
    CHECK(adaslice_curvature_profile(&m, &p, NULL, NULL, &e) == ADASLICE_ERR_ARGUMENT);
    CHECK(adaslice_curvature_profile(&m, NULL, NULL, kappa, &e) == ADASLICE_ERR_ARGUMENT);
    CHECK(adaslice_curvature_profile(&m, &p, NULL, kappa, &e) == ADASLICE_OK);
    CHECK(plan_curvature(&p, NULL, NULL, &plan, &e) == ADASLICE_ERR_ARGUMENT && plan.layers == NULL);
    memset(&co, 0, sizeof co);
    co.tmin = 0.001;
    CHECK(plan_curvature(&p, kappa, &co, &plan, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "bin size"));
    co.tmin = 0;
    co.mapping = (adaslice_mapping)7;
    CHECK(plan_curvature(&p, kappa, &co, &plan, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "mapping 7"));
    co.mapping = ADASLICE_MAPPING_LINEAR;
    kappa[3] = -1;
    CHECK(plan_curvature(&p, kappa, &co, &plan, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "bin 3"));
    kappa[3] = 0;
    co.kappa_max = 1e-9; /* everything curved: tmin throughout */
    CHECK(plan_curvature(&p, kappa, &co, &plan, &e) == ADASLICE_OK && plan.layer_count == p.bin_count / 25);
    adaslice_plan_free(&plan);
    free(kappa);
    adaslice_profile_free(&p);
    gen_free(&m);
}

/* ------------------------------------------------------- out of memory */

/* An allocator that fails from its n-th call on and counts what is live. */

/* Every call fails cleanly, with nothing left allocated, wherever memory runs
   out, and succeeds once it does not. */
static void nothing_leaks_when_memory_runs_out(void)
{
    adaslice_mesh m = bumped_sphere(4, 12, BUMP_DIR, 0.4, 0.2), w;
    adaslice_allocator al;
    adaslice_surface_options so;
    adaslice_plan_options co;
    adaslice_profile p;
    adaslice_plan plan;
    adaslice_error e;
    failing f;
    float *weight = (float *)malloc(m.triangle_count * sizeof *weight);
    double *kappa;
    int step, done, fail_at;
    al = failing_allocator(&f);
    CHECK(adaslice_profile_exact(&m, NULL, &p, &e) == ADASLICE_OK);
    kappa = (double *)malloc(p.bin_count * sizeof *kappa);
    for (step = 0; step < 4; step++) {
        adaslice_result r;
        done = 0;
        for (fail_at = 0; !done && fail_at < 1000; fail_at++) {
            f.left = fail_at;
            f.live = 0;
            memset(&so, 0, sizeof so);
            memset(&co, 0, sizeof co);
            so.allocator = co.allocator = &al;
            if (step == 0) {
                adaslice_weld_options wo = {0.01, NULL};
                wo.allocator = &al;
                w = copy_mesh(&m, 0);
                r = adaslice_mesh_weld(&w, &wo, &e);
                gen_free(&w);
            } else if (step == 1) {
                r = adaslice_saliency(&m, weight, &so, &e);
            } else if (step == 2) {
                r = adaslice_curvature_profile(&m, &p, &so, kappa, &e);
            } else {
                r = plan_curvature(&p, kappa, &co, &plan, &e);
                if (r == ADASLICE_OK) adaslice_plan_free(&plan);
            }
            CHECKF(r == ADASLICE_OK || r == ADASLICE_ERR_NOMEM, "step %d, failing at %d: %s", step, fail_at, e.message);
            CHECKF(f.live == 0, "step %d, failing at allocation %d: %ld blocks left", step, fail_at, f.live);
            done = r == ADASLICE_OK;
        }
        CHECKF(done, "step %d never succeeded", step);
    }
    free(weight);
    free(kappa);
    adaslice_profile_free(&p);
    gen_free(&m);
}

void test_saliency(void)
{
    RUN(weld_within_merges_into_the_first_vertex_in_reach);
    RUN(weld_within_zero_is_the_exact_weld);
    RUN(mean_curvature_of_a_sphere_is_one_over_r);
    RUN(mean_curvature_of_a_plane_is_zero);
    RUN(mean_curvature_on_borders_and_degenerate_triangles);
    RUN(saliency_matches_all_pairs);
    RUN(saliency_peaks_on_a_bump);
    RUN(weighted_plan_is_thinner_at_the_bump);
    RUN(curvature_plan_of_a_bent_sheet);
    RUN(curvature_plan_of_a_capped_cylinder);
    RUN(curvature_plan_arguments);
    RUN(nothing_leaks_when_memory_runs_out);
}
