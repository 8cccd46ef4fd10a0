/* The build-direction search (§4.3). */
#include "../adaslice.h"
#include "../host/report.h"
#include "../host/search.h"
#include "check.h"
#include "failing_alloc.h"
#include "meshgen.h"
#include <math.h>
#include <string.h>

static adaslice_direction_score *search(const adaslice_mesh *m, size_t n, double alpha)
{
    adaslice_orienter o;
    adaslice_error e;
    adaslice_direction_score *s = (adaslice_direction_score *)calloc(n, sizeof *s);
    double *d = (double *)malloc(3 * n * sizeof(double));
    size_t i;
    CHECK(adaslice_orienter_init(&o, m, NULL, NULL, &e) == ADASLICE_OK);
    adaslice_fibonacci_directions(n, d);
    for (i = 0; i < n; i++) CHECKF(adaslice_orienter_score(&o, d + 3 * i, s + i, &e) == ADASLICE_OK, "%s", e.message);
    adaslice_orient_scores(s, n, alpha);
    adaslice_orienter_free(&o);
    free(d);
    return s;
}

/* Unit vectors, spread evenly: every lattice point's nearest neighbour is
   about sqrt(4 pi / n) away, none much closer. */
static void fibonacci_directions_cover_the_sphere(void)
{
    size_t n = 500, i, j, bad = 0;
    double *d = (double *)malloc(3 * n * sizeof(double)), spacing = sqrt(4 * M_PI / n), mean = 0;
    adaslice_fibonacci_directions(n, d);
    for (i = 0; i < n; i++) {
        double best = 4;
        bad += fabs(d[3 * i] * d[3 * i] + d[3 * i + 1] * d[3 * i + 1] + d[3 * i + 2] * d[3 * i + 2] - 1) > 1e-12;
        for (j = 0; j < n; j++)
            if (j != i) {
                double dist = acos(fmin(1, d[3 * i] * d[3 * j] + d[3 * i + 1] * d[3 * j + 1] + d[3 * i + 2] * d[3 * j + 2]));
                if (dist < best) best = dist;
            }
        mean += best / n;
        bad += best < 0.5 * spacing || best > 1.5 * spacing;
    }
    CHECKF(bad == 0 && fabs(mean - 0.9 * spacing) < 0.2 * spacing, "%zu bad points, mean nearest %g (spacing %g)", bad, mean, spacing);
    free(d);
}

/* A sphere looks the same from everywhere. Along any direction a bin's cusp
   value is the |n . d| of some facet meeting it, within the facet's angular
   diameter t = sqrt(dtheta^2 + dphi^2) (+ a bin's worth) of the smooth
   |h - R| / R at that height; the integral of that is R, so K moves by at most
   about 2 t relative each way: a spread below 4 t of K (+ a layer). The
   spread must also shrink as the tessellation gets finer. */
static void sphere_scores_the_same_everywhere(void)
{
    static const int tess[2][2] = {{96, 48}, {288, 144}};
    double R = 10, last = 1;
    int k;
    for (k = 0; k < 2; k++) {
        int slices = tess[k][0], stacks = tess[k][1];
        double dth = M_PI / stacks, dph = 2 * M_PI / slices, t = sqrt(dth * dth + dph * dph) + 0.002 / R, spread;
        adaslice_mesh m = gen_sphere(R, slices, stacks, 0);
        adaslice_direction_score *s = search(&m, 40, 0.5);
        size_t i, kmin = (size_t)-1, kmax = 0;
        for (i = 0; i < 40; i++) {
            CHECK(s[i].feasible);
            if (s[i].layers < kmin) kmin = s[i].layers;
            if (s[i].layers > kmax) kmax = s[i].layers;
        }
        spread = (double)(kmax - kmin) / (double)kmax;
        CHECKF(spread <= 4 * t + 1.0 / kmax, "%dx%d: K from %zu to %zu, spread %g above 4t = %g", slices, stacks, kmin, kmax,
               spread, 4 * t);
        CHECKF(spread < last, "the spread %g does not shrink with the tessellation", spread);
        last = spread;
        free(s);
        gen_free(&m);
    }
}

/* A 10 x 10 x 50 mm box: lying down it needs a third of the layers of
   standing up, so the best directions are its short axes, never the long one. */
static void long_box_lies_down(void)
{
    adaslice_mesh m = gen_box(0, 0, 0, 10, 10, 50);
    size_t n = 400, minima[4], count, i;
    adaslice_direction_score *s = search(&m, n, 0.5);
    count = adaslice_orient_minima(s, n, 2.5 * sqrt(4 * M_PI / n), minima, 4);
    CHECK(count >= 2);
    for (i = 0; i < count && i < 2; i++) {
        const double *d = s[minima[i]].direction;
        CHECKF(fabs(d[2]) < 0.1 && (fabs(d[0]) > 0.95 || fabs(d[1]) > 0.95), "minimum %zu at (%g, %g, %g)", i, d[0], d[1], d[2]);
    }
    for (i = 0; i < n; i++)
        if (fabs(s[i].direction[2]) > 0.99) CHECKF(s[i].score > s[minima[0]].score, "a long-axis direction scores best");
    free(s);
    gen_free(&m);
}

/* The rotation reported for a direction, applied to the mesh, plans the same
   K: the search profiles exactly the turned mesh. */
static void turning_the_mesh_reproduces_the_search(void)
{
    adaslice_load_options lo;
    adaslice_mesh m, turned;
    adaslice_orienter o;
    adaslice_error e;
    double d[3 * 7], r[9];
    int k;
    memset(&lo, 0, sizeof lo);
    lo.scale = 88.7;
    CHECK(adaslice_mesh_load_file("examples/models/hand_closed.obj", &lo, &m, &e) == ADASLICE_OK);
    CHECK(adaslice_mesh_load_file("examples/models/hand_closed.obj", &lo, &turned, &e) == ADASLICE_OK);
    CHECK(adaslice_orienter_init(&o, &m, NULL, NULL, &e) == ADASLICE_OK);
    adaslice_fibonacci_directions(7, d);
    for (k = 0; k < 7; k++) {
        adaslice_direction_score s;
        adaslice_profile p;
        adaslice_plan plan;
        CHECK(adaslice_orienter_score(&o, d + 3 * k, &s, &e) == ADASLICE_OK && s.feasible);
        memcpy(turned.vertices, m.vertices, 3 * m.vertex_count * sizeof(float));
        adaslice_rotation_to_z(s.direction, r);
        CHECK(fabs(r[0] * r[0] + r[1] * r[1] + r[2] * r[2] - 1) < 1e-12 && fabs(r[0] * r[6] + r[1] * r[7] + r[2] * r[8]) < 1e-12);
        adaslice_mesh_rotate(&turned, r);
        CHECK(adaslice_profile_exact(&turned, NULL, &p, &e) == ADASLICE_OK);
        CHECK(adaslice_plan_profile(&p, NULL, &plan, &e) == ADASLICE_OK);
        CHECKF(plan.layer_count == s.layers && plan.worst_error == s.worst_error,
               "direction %d: turned mesh %zu layers, search %zu", k, plan.layer_count, s.layers);
        adaslice_plan_free(&plan);
        adaslice_profile_free(&p);
    }
    adaslice_orienter_free(&o);
    adaslice_mesh_free(&m);
    adaslice_mesh_free(&turned);
}

/* The cusp profile along d by brute force, the definition itself: the mesh
   turned by adaslice_mesh_rotate, each triangle's |n_z| / |n| over every bin
   from its lowest corner's to its highest's, the largest per bin, one bin
   at a time. bins: n of height b from z0, as the profile under test has them
   (their own rule is checked against the turned heights). */
static double *brute_force_cusp(const adaslice_mesh *m, const double d[3], double z0, double b, size_t n)
{
    adaslice_mesh t = *m;
    double r[9], *phi = (double *)calloc(n, sizeof *phi), lo = 1e300, hi = -1e300;
    size_t k, i;
    t.vertices = (float *)malloc(3 * m->vertex_count * sizeof(float));
    memcpy(t.vertices, m->vertices, 3 * m->vertex_count * sizeof(float));
    adaslice_rotation_to_z(d, r);
    adaslice_mesh_rotate(&t, r);
    for (k = 0; k < 3 * t.triangle_count; k++) {
        double z = t.vertices[3 * (size_t)t.triangles[k] + 2];
        lo = z < lo ? z : lo;
        hi = z > hi ? z : hi;
    }
    CHECKF(lo == z0 && n == (size_t)ceil((hi - lo) / b - 1e-9), "bins from %g, %zu of them", lo, n);
    for (k = 0; k < t.triangle_count; k++) {
        const float *v[3];
        double u[3], w[3], c[3], zl = 1e300, zh = -1e300, value;
        int j;
        for (j = 0; j < 3; j++) {
            v[j] = t.vertices + 3 * (size_t)t.triangles[3 * k + j];
            zl = v[j][2] < zl ? v[j][2] : zl;
            zh = v[j][2] > zh ? v[j][2] : zh;
        }
        for (j = 0; j < 3; j++) { u[j] = (double)v[1][j] - v[0][j]; w[j] = (double)v[2][j] - v[0][j]; }
        c[0] = u[1] * w[2] - u[2] * w[1];
        c[1] = u[2] * w[0] - u[0] * w[2];
        c[2] = u[0] * w[1] - u[1] * w[0];
        if (c[0] == 0 && c[1] == 0 && c[2] == 0) continue;
        value = fabs(c[2]) / sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        for (i = 0; i < n; i++) {
            /* the bins of its lowest and highest corner (z - z0) * (1 / b),
               rounded down, clamped to the bins, and all between */
            double f = (zl - z0) * (1 / b), g = (zh - z0) * (1 / b);
            size_t first = f < (double)(n - 1) ? (size_t)f : n - 1, last = g < (double)(n - 1) ? (size_t)g : n - 1;
            if (i >= first && i <= last && value > phi[i]) phi[i] = value;
        }
    }
    free(t.vertices);
    return phi;
}

/* The search's profiles, K and errors equal those of the brute-force
   profile bit for bit, so its best direction is the exhaustive reference's,
   on meshes whose triangles meet one bin or thousands (a box's and a cone's
   sides run the whole height). */
static void search_matches_a_brute_force_reference(void)
{
    adaslice_mesh meshes[4];
    adaslice_load_options lo;
    adaslice_error e;
    size_t n = 40, k, i, c;
    double *d = (double *)malloc(3 * n * sizeof(double));
    memset(&lo, 0, sizeof lo);
    lo.scale = 88.7;
    CHECK(adaslice_mesh_load_file("examples/models/hand_closed.obj", &lo, &meshes[0], &e) == ADASLICE_OK);
    meshes[1] = gen_box(0, 0, 0, 1, 2, 6);
    meshes[2] = gen_sphere(1.5, 24, 12, 0);
    meshes[3] = gen_cone(1, 3, 7, 0);
    adaslice_fibonacci_directions(n, d);
    for (c = 0; c < 4; c++) {
        adaslice_orienter o;
        adaslice_profile_options po;
        adaslice_direction_score *fast = (adaslice_direction_score *)calloc(n, sizeof *fast);
        adaslice_direction_score *ref = (adaslice_direction_score *)calloc(n, sizeof *ref);
        size_t best_fast = 0, best_ref = 0;
        memset(&po, 0, sizeof po);
        po.bin = c ? 0.002 : 0.01; /* the hand is 83 mm: 8,300 bins, not 41,500, to keep the brute force quick */
        CHECK(adaslice_orienter_init(&o, &meshes[c], &po, NULL, &e) == ADASLICE_OK);
        for (k = 0; k < n; k++) {
            adaslice_profile p, bp;
            adaslice_plan plan;
            double *phi;
            CHECK(adaslice_profile_along(&o, d + 3 * k, &p, &e) == ADASLICE_OK);
            phi = brute_force_cusp(&meshes[c], d + 3 * k, p.z0, p.bin, p.bin_count);
            for (i = 0; i < p.bin_count; i++)
                if (phi[i] != p.phi[i]) break;
            CHECKF(i == p.bin_count, "mesh %zu, direction %zu: bin %zu of %zu is %.17g, brute force %.17g", c, k, i,
                   p.bin_count, i < p.bin_count ? p.phi[i] : 0, i < p.bin_count ? phi[i] : 0);
            bp = p;
            bp.phi = phi;
            CHECK(adaslice_orienter_score(&o, d + 3 * k, &fast[k], &e) == ADASLICE_OK);
            ref[k] = fast[k];
            ref[k].feasible = adaslice_plan_profile(&bp, NULL, &plan, &e) == ADASLICE_OK;
            if (ref[k].feasible) {
                ref[k].layers = plan.layer_count;
                ref[k].worst_error = plan.worst_error;
                adaslice_plan_free(&plan);
            }
            CHECK(ref[k].feasible == fast[k].feasible && ref[k].layers == fast[k].layers &&
                  ref[k].worst_error == fast[k].worst_error);
            free(phi);
            adaslice_profile_free(&p);
        }
        adaslice_orient_scores(fast, n, 0.5);
        adaslice_orient_scores(ref, n, 0.5);
        for (k = 1; k < n; k++) {
            if (fast[k].score < fast[best_fast].score) best_fast = k;
            if (ref[k].score < ref[best_ref].score) best_ref = k;
        }
        CHECKF(best_fast == best_ref && fast[best_fast].score == ref[best_ref].score, "mesh %zu: best %zu, reference %zu",
               c, best_fast, best_ref);
        adaslice_orienter_free(&o);
        free(fast);
        free(ref);
    }
    adaslice_mesh_free(&meshes[0]);
    for (c = 1; c < 4; c++) gen_free(&meshes[c]);
    free(d);
}

/* count spheres of radius 2 in a row along x, 5 mm apart: a long part of
   small facets */
static adaslice_mesh sphere_row(int count, int slices, int stacks)
{
    adaslice_mesh row = gen_sphere(2, slices, stacks, 0);
    int k;
    size_t v;
    for (k = 1; k < count; k++) {
        adaslice_mesh s = gen_sphere(2, slices, stacks, 0);
        for (v = 0; v < s.vertex_count; v++) s.vertices[3 * v] += (float)(5 * k);
        gen_append(&row, &s);
        gen_free(&s);
    }
    return row;
}

static double ripples(double x, double y) { return 3 + sin(x) * cos(0.7 * y) + 0.3 * sin(5 * x); }

/* The search as the tool runs it (host/search.c: threads share the
   directions; along a long part each profile is cut into chunks, facets'
   runs crossing their borders) gives every direction the K and errors of
   the exhaustive way, one direction at a time on one thread: the mesh turned
   by adaslice_mesh_rotate and profiled whole by adaslice_profile_exact. So
   the best direction, its score and the minima are the reference's. The
   rows of spheres and the ripples run to 30,000-60,000 bins of 1-2 um along
   x, their facets' runs to a few hundred (many chunks); the box's sides span
   every bin (one). */
static void threaded_search_matches_the_turned_meshes(void)
{
    static const double axes[SEARCH_AXES][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
    adaslice_mesh meshes[4];
    adaslice_load_options lo;
    adaslice_error e;
    const double bins[4] = {0.001, 0.002, 0.002, 0.002};
    size_t n = 60, total = n + SEARCH_AXES, c, k, i;
    double *d = (double *)malloc(3 * total * sizeof(double));
    memset(&lo, 0, sizeof lo);
    lo.scale = 88.7;
    meshes[0] = sphere_row(10, 24, 24);
    meshes[1] = gen_heightfield(200, 10, 0, 0, 60, 6, ripples);
    CHECK(adaslice_mesh_load_file("examples/models/hand_closed.obj", &lo, &meshes[2], &e) == ADASLICE_OK);
    meshes[3] = gen_box(0, 0, 0, 3, 5, 40);
    adaslice_fibonacci_directions(n, d);
    memcpy(d + 3 * n, axes, sizeof axes);
    for (c = 0; c < 4; c++) {
        adaslice_profile_options po;
        adaslice_direction_score *fast = NULL, *ref = (adaslice_direction_score *)calloc(total, sizeof *ref);
        adaslice_mesh t = meshes[c];
        size_t minima[SEARCH_MINIMA + 1], ref_minima[SEARCH_MINIMA + 1], count = 0, ref_count, longest = 0;
        memset(&po, 0, sizeof po);
        po.bin = bins[c];
        CHECK(orient_search("test", &meshes[c], &po, NULL, n, 0.5, 0, &fast, minima, &count) == RC_OK && fast);
        t.vertices = (float *)malloc(3 * t.vertex_count * sizeof(float));
        for (k = 0; k < total; k++) {
            const double *dk = d + 3 * k;
            double len = sqrt(dk[0] * dk[0] + dk[1] * dk[1] + dk[2] * dk[2]), u[3], r[9];
            adaslice_profile p;
            adaslice_plan plan;
            u[0] = dk[0] / len; u[1] = dk[1] / len; u[2] = dk[2] / len;
            memcpy(t.vertices, meshes[c].vertices, 3 * t.vertex_count * sizeof(float));
            adaslice_rotation_to_z(u, r);
            adaslice_mesh_rotate(&t, r);
            CHECK(adaslice_profile_exact(&t, &po, &p, &e) == ADASLICE_OK);
            longest = p.bin_count > longest ? p.bin_count : longest;
            memcpy(ref[k].direction, u, sizeof u);
            ref[k].feasible = adaslice_plan_profile(&p, NULL, &plan, &e) == ADASLICE_OK;
            if (ref[k].feasible) {
                ref[k].layers = plan.layer_count;
                ref[k].worst_error = plan.worst_error;
                ref[k].mean_error = plan.total_error / (double)plan.layer_count;
                adaslice_plan_free(&plan);
            }
            adaslice_profile_free(&p);
            CHECKF(fast[k].feasible == ref[k].feasible && fast[k].layers == ref[k].layers &&
                       fast[k].worst_error == ref[k].worst_error && fast[k].mean_error == ref[k].mean_error,
                   "mesh %zu, direction %zu: %zu layers, worst %.17g; reference %zu, %.17g", c, k, fast[k].layers,
                   fast[k].worst_error, ref[k].layers, ref[k].worst_error);
        }
        CHECKF(c == 3 || longest > 25000, "mesh %zu: at most %zu bins", c, longest);
        adaslice_orient_scores(ref, total, 0.5);
        /* the neighbourhood orient_search takes */
        ref_count = adaslice_orient_minima(ref, total, 2.5 * sqrt(4 * 3.14159265358979 / (double)n), ref_minima,
                                           SEARCH_MINIMA + 1);
        CHECK(count == ref_count && count > 0);
        for (i = 0; i < count && i < ref_count; i++)
            CHECKF(minima[i] == ref_minima[i] && fast[minima[i]].score == ref[ref_minima[i]].score,
                   "mesh %zu: minimum %zu is direction %zu (F %.17g), reference %zu (F %.17g)", c, i, minima[i],
                   fast[minima[i]].score, ref_minima[i], ref[ref_minima[i]].score);
        free(t.vertices);
        free(fast);
        free(ref);
    }
    gen_free(&meshes[0]);
    gen_free(&meshes[1]);
    adaslice_mesh_free(&meshes[2]);
    gen_free(&meshes[3]);
    free(d);
}

/* Every profile the orienter gives along d[0..count-1] against
   adaslice_profile_exact of m turned by adaslice_mesh_rotate, bit for bit;
   returns how many were long enough to be cut into chunks (times 9 levels or
   more: over 262,144). */
static size_t profiles_along_match(const adaslice_orienter *o, const adaslice_mesh *m, const adaslice_profile_options *po,
                                   const double *d, size_t count)
{
    adaslice_mesh t = *m;
    adaslice_error e;
    size_t k, v, chunked = 0;
    t.vertices = (float *)malloc(3 * m->vertex_count * sizeof(float));
    for (k = 0; k < count; k++) {
        adaslice_profile p, ref;
        double r[9];
        CHECK(adaslice_profile_along(o, d + 3 * k, &p, &e) == ADASLICE_OK);
        memcpy(t.vertices, m->vertices, 3 * m->vertex_count * sizeof(float));
        adaslice_rotation_to_z(d + 3 * k, r);
        adaslice_mesh_rotate(&t, r);
        CHECK(adaslice_profile_exact(&t, po, &ref, &e) == ADASLICE_OK);
        CHECKF(p.z0 == ref.z0 && p.bin_count == ref.bin_count, "metric %d, direction %zu: %zu bins from %g, reference %zu from %g",
               (int)po->metric, k, p.bin_count, p.z0, ref.bin_count, ref.z0);
        for (v = 0; v < p.bin_count && v < ref.bin_count && p.phi[v] == ref.phi[v]; v++) {}
        CHECKF(v == p.bin_count, "metric %d, direction %zu: bin %zu is %.17g, reference %.17g", (int)po->metric, k, v,
               v < p.bin_count ? p.phi[v] : 0, v < ref.bin_count ? ref.phi[v] : 0);
        chunked += p.bin_count > 40000;
        adaslice_profile_free(&p);
        adaslice_profile_free(&ref);
    }
    free(t.vertices);
    return chunked;
}

/* The orienter profiles its own copy of the mesh, the triangles sorted in
   space and the vertices renumbered: with weights (which must follow their
   triangles into the new order) and vertices no triangle uses (far above and
   below the part, which must not stretch its height), every profile along
   every direction is adaslice_profile_exact's of the turned mesh, bit for
   bit, the row of spheres cut into chunks along x and kept whole along z. */
static void sorted_copy_keeps_weights_and_heights(void)
{
    static const double axes[6][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
    adaslice_mesh row = sphere_row(10, 16, 12), m = row;
    adaslice_error e;
    size_t n = 24, i, chunked = 0;
    float *w = (float *)malloc(row.triangle_count * sizeof *w);
    double *d = (double *)malloc(3 * (n + 6) * sizeof(double));
    int metric;
    m.vertex_count = row.vertex_count + 2;
    m.vertices = (float *)calloc(3 * m.vertex_count, sizeof(float));
    m.triangles = (uint32_t *)malloc(3 * m.triangle_count * sizeof(uint32_t));
    memcpy(m.vertices + 3, row.vertices, 3 * row.vertex_count * sizeof(float));
    m.vertices[2] = 100;                         /* vertex 0, unused */
    m.vertices[3 * (m.vertex_count - 1) + 2] = -100; /* the last, unused */
    for (i = 0; i < 3 * m.triangle_count; i++) m.triangles[i] = row.triangles[i] + 1;
    for (i = 0; i < m.triangle_count; i++) w[i] = (float)((i * 37) % 11) / 10;
    adaslice_fibonacci_directions(n, d);
    memcpy(d + 3 * n, axes, sizeof axes);
    for (metric = ADASLICE_METRIC_CUSP; metric <= ADASLICE_METRIC_ROUGHNESS; metric++) {
        adaslice_orienter o;
        adaslice_profile_options po;
        memset(&po, 0, sizeof po);
        po.bin = 0.001;
        po.metric = (adaslice_metric)metric;
        po.weights = w;
        CHECK(adaslice_orienter_init(&o, &m, &po, NULL, &e) == ADASLICE_OK);
        chunked += profiles_along_match(&o, &m, &po, d, n + 6);
        adaslice_orienter_free(&o);
    }
    CHECKF(chunked >= 4, "%zu profiles long enough to be cut into chunks", chunked);
    free(m.vertices);
    free(m.triangles);
    gen_free(&row);
    free(w);
    free(d);
}

/* The cusp profile along a direction leaves out the facets whose values
   cannot pass it (adaslice__prune), by bounds on how far a facet's value,
   from its corners turned and rounded to float, can be from its normal's:
   far from the origin, where the rounding is coarse, and with slivers,
   whose normals the rounding turns most, every profile is still
   adaslice_profile_exact's of the turned mesh, bit for bit, in chunks along
   x and whole along z. Spheres of fine facets at 3,000 mm, and beside them
   slivers: fans of facets 4 mm long and 10^-4 to 10^-7 mm wide, tilted a
   little from level, which along most directions the spheres' facets
   outweigh only by a hair. */
static void pruned_profiles_match_far_away_and_with_slivers(void)
{
    static const double axes[6][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
    adaslice_mesh m = sphere_row(10, 24, 16);
    adaslice_error e;
    adaslice_orienter o;
    adaslice_profile_options po;
    size_t n = 40, v, i, base, chunked;
    double *d = (double *)malloc(3 * (n + 6) * sizeof(double));
    base = m.vertex_count;
    m.vertices = (float *)realloc(m.vertices, 3 * (m.vertex_count + 4 * 60) * sizeof(float));
    m.triangles = (uint32_t *)realloc(m.triangles, 3 * (m.triangle_count + 2 * 60) * sizeof(uint32_t));
    for (i = 0; i < 60; i++) { /* a sliver pair: two facets sharing a long edge, 10^-4.. wide */
        float x = (float)(2 * (i % 20)), y = 6 + (float)(i / 20), wide = (float)pow(10, -4 - (double)(i % 4));
        float *q = m.vertices + 3 * (base + 4 * i);
        uint32_t *f = m.triangles + 3 * (m.triangle_count + 2 * i), c = (uint32_t)(base + 4 * i);
        q[0] = x;     q[1] = y;        q[2] = (float)(i % 7) * 0.3f;
        q[3] = x + 4; q[4] = y;        q[5] = q[2] + 0.01f * (float)(i % 3);
        q[6] = x + 2; q[7] = y + wide; q[8] = q[2] + 0.002f;
        q[9] = x + 2; q[10] = y - wide; q[11] = q[2] - 0.002f;
        f[0] = c; f[1] = c + 1; f[2] = c + 2;
        f[3] = c + 1; f[4] = c; f[5] = c + 3;
    }
    m.vertex_count += 4 * 60;
    m.triangle_count += 2 * 60;
    for (v = 0; v < m.vertex_count; v++) { m.vertices[3 * v] += 3000; m.vertices[3 * v + 1] += 3000; }
    adaslice_fibonacci_directions(n, d);
    memcpy(d + 3 * n, axes, sizeof axes);
    memset(&po, 0, sizeof po);
    po.bin = 0.001;
    CHECK(adaslice_orienter_init(&o, &m, &po, NULL, &e) == ADASLICE_OK);
    chunked = profiles_along_match(&o, &m, &po, d, n + 6);
    CHECKF(chunked >= 4, "%zu profiles long enough to be cut into chunks", chunked);
    adaslice_orienter_free(&o);
    gen_free(&m);
    free(d);
}

/* Out of memory at any allocation, the orienter's set-up (its sorted copy,
   the weights in that order) or a profile along a direction whole or in
   chunks: ADASLICE_ERR_NOMEM and no block left behind. */
static void out_of_memory_leaks_nothing(void)
{
    static const double d[2][3] = {{1, 0, 0}, {0, 0, 1}}; /* in chunks (49,000 bins), whole */
    adaslice_mesh m = sphere_row(10, 16, 12);
    adaslice_allocator al = {0, 0, 0};
    adaslice_error e;
    failing f;
    float *w = (float *)malloc(m.triangle_count * sizeof *w);
    size_t i;
    int fail_at, done = 0;
    for (i = 0; i < m.triangle_count; i++) w[i] = (float)(i % 5) / 4;
    al = failing_allocator(&f);
    for (fail_at = 0; !done && fail_at < 100; fail_at++) {
        adaslice_orienter o;
        adaslice_profile_options po;
        adaslice_result r;
        int k;
        memset(&po, 0, sizeof po);
        po.bin = 0.001;
        po.weights = w;
        po.allocator = &al;
        f.left = fail_at;
        f.live = 0;
        r = adaslice_orienter_init(&o, &m, &po, NULL, &e);
        for (k = 0; k < 2 && r == ADASLICE_OK; k++) {
            adaslice_direction_score s;
            r = adaslice_orienter_score(&o, d[k], &s, &e);
            CHECK(r != ADASLICE_OK || s.feasible);
        }
        adaslice_orienter_free(&o); /* a failed set-up leaves it zeroed */
        CHECKF(r == ADASLICE_OK || r == ADASLICE_ERR_NOMEM, "failing at allocation %d: %s", fail_at, e.message);
        CHECKF(f.live == 0, "failing at allocation %d: %ld blocks left", fail_at, f.live);
        done = r == ADASLICE_OK;
    }
    CHECKF(done && fail_at > 8, "succeeded at allocation %d", fail_at);
    gen_free(&m);
    free(w);
}

/* Minima are lower than everything around them, so no two are neighbours. */
static void minima_are_apart(void)
{
    adaslice_mesh m = gen_box(0, 0, 0, 10, 20, 40);
    size_t n = 300, minima[4], count, i, j;
    double radius = 2.5 * sqrt(4 * M_PI / n);
    adaslice_direction_score *s = search(&m, n, 0.5);
    count = adaslice_orient_minima(s, n, radius, minima, 4);
    CHECK(count >= 3);
    for (i = 0; i < count; i++) {
        for (j = 0; j < i; j++) {
            const double *a = s[minima[i]].direction, *b = s[minima[j]].direction;
            CHECK(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] < cos(radius));
            CHECK(s[minima[j]].score <= s[minima[i]].score);
        }
    }
    free(s);
    gen_free(&m);
}

/* Equal scores go to the part as loaded (+z: no turn), then to the lower
   index: among neighbours, +z is the one minimum even listed last (as the
   tool lists it after the lattice), and among directions apart, +z comes
   first and the rest keep their order. */
static void ties_go_to_the_part_as_loaded(void)
{
    static const double d[4][3] = {{1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
    adaslice_direction_score s[4];
    size_t minima[4], count, i;
    memset(s, 0, sizeof s);
    for (i = 0; i < 4; i++) {
        memcpy(s[i].direction, d[i], sizeof d[i]);
        s[i].score = 0.5;
    }
    count = adaslice_orient_minima(s, 4, 2.0, minima, 4); /* 2 rad: every one a neighbour of every other */
    CHECKF(count == 1 && minima[0] == 3, "%zu minima, the first %zu", count, count ? minima[0] : 99);
    count = adaslice_orient_minima(s, 4, 0.1, minima, 4); /* none a neighbour */
    CHECKF(count == 4 && minima[0] == 3 && minima[1] == 0 && minima[2] == 1 && minima[3] == 2,
           "%zu minima: %zu %zu %zu %zu", count, minima[0], minima[1], minima[2], minima[3]);
    s[1].score = 0.4; /* a lower score still wins */
    count = adaslice_orient_minima(s, 4, 2.0, minima, 4);
    CHECKF(count == 1 && minima[0] == 1, "%zu minima, the first %zu", count, count ? minima[0] : 99);
}

static unsigned orient_rng_state = 2026;
static unsigned orient_rng(void)
{
    orient_rng_state = orient_rng_state * 1103515245u + 12345u;
    return (orient_rng_state >> 8) & 0xffffffu;
}

/* Every pair tried, as adaslice_orient_minima did before it searched runs of
   falling z: the reference for the windowed search. */
static size_t minima_of_every_pair(const adaslice_direction_score *s, size_t n, double radius, size_t *out, size_t max)
{
    double c = cos(radius);
    size_t i, j, count = 0;
    for (i = 0; i < n; i++) {
        int lowest = 1;
        for (j = 0; j < n && lowest; j++) {
            const double *a = s[i].direction, *b = s[j].direction;
            if (j == i || a[0] * b[0] + a[1] * b[1] + a[2] * b[2] < c) continue;
            if (s[j].score != s[i].score ? s[j].score < s[i].score
                : a[2] != b[2] ? b[2] > a[2] : j < i)
                lowest = 0;
        }
        if (!lowest) continue;
        for (j = count < max ? count++ : max; j > 0; j--) { /* by score, ties as adaslice__orient_before */
            const adaslice_direction_score *p = &s[i], *q = &s[out[j - 1]];
            if (!(p->score != q->score ? p->score < q->score
                  : p->direction[2] != q->direction[2] ? p->direction[2] > q->direction[2] : i < out[j - 1]))
                break;
            if (j < max) out[j] = out[j - 1];
        }
        if (j < max) out[j] = i;
    }
    return count;
}

/* The lattice and the axes as the tool lists them, scores random or in five
   levels (ties), radii from the tool's to past pi; and directions in no order
   (each its own run: every pair tried). */
static void minima_windowed_equal_every_pair(void)
{
    static const double axes[6][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
    int trial;
    for (trial = 0; trial < 60; trial++) {
        size_t n = 10 + (size_t)(orient_rng() % 1500), i, a[12], b[12], ca, cb;
        int k, mode = trial % 3;
        double *d = (double *)malloc(3 * (n + 6) * sizeof *d), radius;
        adaslice_direction_score *s = (adaslice_direction_score *)calloc(n + 6, sizeof *s);
        if (!d || !s) { CHECK(0); free(d); free(s); return; }
        adaslice_fibonacci_directions(n, d);
        memcpy(d + 3 * n, axes, sizeof axes);
        for (i = 0; i < n + 6; i++) {
            if (mode == 2) { /* a random unit direction */
                double v[3], len;
                for (k = 0; k < 3; k++) v[k] = (double)(orient_rng() % 20001) / 10000 - 1;
                len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                for (k = 0; k < 3; k++) d[3 * i + k] = len > 0 ? v[k] / len : k == 2;
            }
            memcpy(s[i].direction, d + 3 * i, sizeof s[i].direction);
            s[i].score = mode == 1 ? (double)(orient_rng() % 5) / 10 : (double)(orient_rng() % 1000000) / 1e6;
        }
        radius = trial % 7 == 0 ? 3.5 : 2.5 * sqrt(4 * M_PI / (double)n) * (1 + trial % 4);
        ca = adaslice_orient_minima(s, n + 6, radius, a, 12);
        cb = minima_of_every_pair(s, n + 6, radius, b, 12);
        CHECKF(ca == cb && !memcmp(a, b, (ca < 12 ? ca : 12) * sizeof a[0]),
               "trial %d (n %zu, mode %d): %zu minima, every pair %zu", trial, n, mode, ca, cb);
        free(d);
        free(s);
    }
}

void test_orient(void)
{
    RUN(fibonacci_directions_cover_the_sphere);
    RUN(sphere_scores_the_same_everywhere);
    RUN(long_box_lies_down);
    RUN(turning_the_mesh_reproduces_the_search);
    RUN(minima_are_apart);
    RUN(ties_go_to_the_part_as_loaded);
    RUN(minima_windowed_equal_every_pair);
    RUN(search_matches_a_brute_force_reference);
    RUN(threaded_search_matches_the_turned_meshes);
    RUN(sorted_copy_keeps_weights_and_heights);
    RUN(pruned_profiles_match_far_away_and_with_slivers);
    RUN(out_of_memory_leaks_nothing);
}
