/* make bench: the planner against Procedure 1 as printed, in the same process,
   and the exact profiles on the largest shared models. Medians of repeated runs. */
#include "../adaslice.h"
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "../host/codec/png.h"
#include <stdio.h>
#include "models.h"
#include "timing.h"
#include <stdlib.h>
#include <string.h>
#include <time.h>


/* Procedure 1 exactly as the paper prints it: the inner summation included.
   Returns K, or -1 when infeasible. */
static long procedure1(const double *phi, size_t n, double bin, double eps, double tmin, double tmax)
{
    long lo = (long)ceil(tmin / bin - 1e-9), hi = (long)floor(tmax / bin + 1e-9), i, l, m;
    long *K = (long *)malloc((n + 1) * sizeof(long)), *D = (long *)malloc((n + 1) * sizeof(long)), k;
    for (i = 0; i <= (long)n; i++) { K[i] = LONG_MAX; D[i] = -1; }
    K[0] = 0;
    for (i = 1; i <= (long)n; i++) {
        for (l = i - hi; l <= i - lo; l++) {
            double sum = 0;
            if (l < 0) continue;
            for (m = l + 1; m <= i; m++) sum += phi[m - 1];
            if (sum * bin <= eps && K[l] != LONG_MAX && K[i] > K[l] + 1) { K[i] = K[l] + 1; D[i] = l; }
        }
    }
    k = K[n] == LONG_MAX ? -1 : K[n];
    free(K);
    free(D);
    return k;
}

static void bench_planner(const char *label, const adaslice_profile *p, int runs, int slow_runs)
{
    adaslice_plan_options o;
    adaslice_plan plan;
    adaslice_error e;
    double fast[64], slow[8], t;
    long k_slow = 0;
    int r;
    memset(&o, 0, sizeof o);
    o.sharp = ADASLICE_SHARP_OFF; /* Procedure 1 has no pre-pass */
    for (r = 0; r < runs; r++) {
        t = now();
        if (adaslice_plan_profile(p, &o, &plan, &e) != ADASLICE_OK) { printf("plan failed: %s\n", e.message); exit(1); }
        fast[r] = now() - t;
        if (r + 1 < runs) adaslice_plan_free(&plan);
    }
    for (r = 0; r < slow_runs; r++) {
        t = now();
        k_slow = procedure1(p->phi, p->bin_count, p->bin, o.eps ? o.eps : ADASLICE_DEFAULT_EPS, ADASLICE_DEFAULT_TMIN,
                            ADASLICE_DEFAULT_TMAX);
        slow[r] = now() - t;
    }
    {
        double f = median(fast, runs), s = median(slow, slow_runs);
        printf("planner %-28s N = %8zu  K = %6zu (Procedure 1: %ld)  optimal %9.3f ms  Procedure 1 %10.1f ms  ratio %6.0fx\n",
               label, p->bin_count, plan.layer_count, k_slow, f * 1e3, s * 1e3, s / f);
        if ((long)plan.layer_count != k_slow) { printf("MISMATCH in layer count\n"); exit(1); }
    }
    adaslice_plan_free(&plan);
}

static int load(const char *path, double height, adaslice_mesh *m)
{
    adaslice_load_options lo;
    adaslice_error e;
    double a[3], b[3];
    memset(&lo, 0, sizeof lo);
    if (adaslice_mesh_load_file(path, &lo, m, &e) != ADASLICE_OK) { printf("%s\n", e.message); return 0; }
    if (height > 0) {
        size_t i;
        double s;
        adaslice_mesh_bounds(m, a, b);
        s = height / (b[2] - a[2]);
        for (i = 0; i < 3 * m->vertex_count; i++) m->vertices[i] = (float)(m->vertices[i] * s);
    }
    return 1;
}

/* The paper's pipeline, sampled: load + LDIs along x, y, z at 2048 + cusp
   profile + optimal plan; and the memory a stored LDI along each axis takes. */
static void bench_sampled(const char *dir, const char *name, double scale)
{
    char path[1024];
    double t[5], ms_load = 0, ms_prof = 0, ms_plan = 0, mem = 0;
    size_t k = 0, tris = 0;
    int r, axis;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    for (r = 0; r < 5; r++) {
        adaslice_mesh m;
        adaslice_load_options lo;
        adaslice_profile p;
        adaslice_plan plan;
        adaslice_profile_options po;
        double t0 = now(), t1, t2, t3;
        memset(&lo, 0, sizeof lo);
        lo.scale = scale;
        memset(&po, 0, sizeof po);
        if (adaslice_mesh_load_file(path, &lo, &m, NULL) != ADASLICE_OK) { printf("cannot load %s\n", path); exit(1); }
        t1 = now();
        if (adaslice_profile_sampled(&m, &po, &p, NULL) != ADASLICE_OK) exit(1);
        t2 = now();
        if (adaslice_plan_profile(&p, NULL, &plan, NULL) != ADASLICE_OK) exit(1);
        t3 = now();
        t[r] = t3 - t0;
        ms_load += (t1 - t0) * 200; ms_prof += (t2 - t1) * 200; ms_plan += (t3 - t2) * 200;
        k = plan.layer_count;
        tris = m.triangle_count;
        if (r == 0)
            for (axis = 0; axis < 3; axis++) {
                adaslice_grid g = adaslice_grid_fit(&m, (adaslice_axis)axis, ADASLICE_DEFAULT_RESOLUTION);
                adaslice_ldi ldi;
                if (adaslice_ldi_build(&m, &g, NULL, &ldi, NULL) != ADASLICE_OK) exit(1);
                mem += (double)ldi.sample_count * sizeof(adaslice_sample) + ((double)g.width * g.height + 1) * sizeof(size_t);
                adaslice_ldi_free(&ldi);
            }
        adaslice_plan_free(&plan);
        adaslice_profile_free(&p);
        adaslice_mesh_free(&m);
    }
    printf("sampled %-24s %7zu triangles  pipeline %7.1f ms (load %.1f, LDIs + cusp profile %.1f, plan %.2f; means)  "
           "K %4zu  stored LDIs x+y+z %6.1f MB\n", name, tris, median(t, 5) * 1e3, ms_load, ms_prof, ms_plan, k, mem / 1e6);
}

/* Masks for every layer of a plan at 2560 x 1440 px of 47.25 um, PNG-encoded
   in memory (no disk): the turbine blade scaled to fill the plate. */
static void bench_masks(const char *dir, int supersample)
{
    char path[1024];
    adaslice_mesh m;
    adaslice_load_options lo;
    adaslice_profile p;
    adaslice_plan plan;
    adaslice_masker mk;
    adaslice_grid g;
    double a[3], b[3], scale, t0, t_mask = 0, t_png = 0, bytes = 0;
    size_t k;
    snprintf(path, sizeof path, "%s/turbineblade.ply", dir);
    memset(&lo, 0, sizeof lo);
    if (adaslice_mesh_load_file(path, &lo, &m, NULL) != ADASLICE_OK) exit(1);
    adaslice_mesh_bounds(&m, a, b);
    scale = 0.95 * (2560 * 0.04725 / (b[0] - a[0]) < 1440 * 0.04725 / (b[1] - a[1]) ? 2560 * 0.04725 / (b[0] - a[0])
                                                                                      : 1440 * 0.04725 / (b[1] - a[1]));
    for (k = 0; k < 3 * m.vertex_count; k++) m.vertices[k] = (float)(m.vertices[k] * scale);
    adaslice_mesh_bounds(&m, a, b);
    if (adaslice_profile_exact(&m, NULL, &p, NULL) != ADASLICE_OK || adaslice_plan_profile(&p, NULL, &plan, NULL) != ADASLICE_OK) exit(1);
    g = adaslice_grid_plate(&m, 2560, 1440, 0.04725, 0.04725, NULL);
    t0 = now();
    if (adaslice_masker_init(&mk, &m, &g, &(adaslice_mask_options){supersample, NULL, ADASLICE_SLICE_MIDDLE, 0, NULL, 0}, NULL) != ADASLICE_OK) exit(1);
    t_mask += now() - t0;
    for (k = 0; k < plan.layer_count; k++) {
        unsigned char *png;
        size_t size;
        double t1 = now(), t2;
        if (adaslice_masker_slice(&mk, p.z0 + 0.5 * (plan.layers[k].z_bottom + plan.layers[k].z_top), NULL) != ADASLICE_OK) exit(1);
        t2 = now();
        if (png_encode_gray(mk.image, g.width, g.height, mk.stride, supersample > 1 ? 8 : 1, &png, &size)) exit(1);
        t_png += now() - t2;
        t_mask += t2 - t1;
        bytes += (double)size;
        free(png);
    }
    printf("masks   turbine blade x%.2f (%.0f x %.0f x %.0f mm, %zu triangles), %zu layers, %s: %.0f layers/s "
           "(masks %.2f ms, PNG %.2f ms per layer; %.1f KB per PNG); masker memory %.0f MB\n",
           scale, b[0] - a[0], b[1] - a[1], b[2] - a[2], m.triangle_count, plan.layer_count,
           supersample > 1 ? "8-bit, exact coverage in 17 levels" : "1-bit", plan.layer_count / (t_mask + t_png),
           t_mask * 1e3 / plan.layer_count, t_png * 1e3 / plan.layer_count, bytes / plan.layer_count / 1024,
           (double)adaslice_masker_bytes((uint32_t)g.width, (uint32_t)g.height, supersample, ADASLICE_SLICE_MIDDLE, m.triangle_count) / 1e6);
    adaslice_masker_free(&mk);
    adaslice_plan_free(&plan);
    adaslice_profile_free(&p);
    adaslice_mesh_free(&m);
}

/* 1000 directions by the tool itself (threads on every core, load included),
   timed from outside as a user would see it. */
static void bench_orient(const char *path, const char *extra)
{
    char cmd[2048];
    double t[3];
    int r;
    snprintf(cmd, sizeof cmd, "build/adaslice orient %s %s --dirs 1000 > build/orient_bench.txt", path, extra);
    for (r = 0; r < 3; r++) {
        double t0 = now();
        if (system(cmd) != 0) { printf("failed: %s\n", cmd); exit(1); }
        t[r] = now() - t0;
    }
    printf("orient  %-58s 1000 directions: %6.2f s (median of 3, both cores, load included)\n", path, median(t, 3));
}

/* Five dragons side by side, in mm: a plate of about a million triangles. */
static void write_dragon_plate(const char *models, const char *out)
{
    char path[1024];
    adaslice_mesh m;
    adaslice_load_options lo;
    double a[3], b[3];
    FILE *f;
    size_t k, v, t;
    snprintf(path, sizeof path, "%s/dragon_vrip_res2.ply", models);
    memset(&lo, 0, sizeof lo);
    lo.scale = 1000;
    if (adaslice_mesh_load_file(path, &lo, &m, NULL) != ADASLICE_OK) exit(1);
    adaslice_mesh_bounds(&m, a, b);
    f = fopen(out, "wb");
    if (!f) exit(1);
    fprintf(f, "ply\nformat binary_little_endian 1.0\nelement vertex %zu\nproperty float x\nproperty float y\nproperty float z\n"
               "element face %zu\nproperty list uchar int vertex_indices\nend_header\n", 5 * m.vertex_count, 5 * m.triangle_count);
    for (k = 0; k < 5; k++)
        for (v = 0; v < m.vertex_count; v++) {
            float p[3];
            p[0] = (float)(m.vertices[3 * v] + k * (b[0] - a[0] + 5));
            p[1] = m.vertices[3 * v + 1];
            p[2] = m.vertices[3 * v + 2];
            fwrite(p, sizeof p, 1, f);
        }
    for (k = 0; k < 5; k++)
        for (t = 0; t < m.triangle_count; t++) {
            unsigned char three = 3;
            int32_t idx[3];
            int c;
            for (c = 0; c < 3; c++) idx[c] = (int32_t)(m.triangles[3 * t + c] + k * m.vertex_count);
            fwrite(&three, 1, 1, f);
            fwrite(idx, sizeof idx, 1, f);
        }
    if (fclose(f) != 0) exit(1);
    adaslice_mesh_free(&m);
}

int main(int argc, char **argv)
{
    const char *models = argc > 1 ? argv[1] : "../shared/models";
    static const char *big[] = {"turbineblade.ply", "dragon_vrip_res2.ply", "lucy.ply", "counter.unitsmm.STL"};
    static const double big_height[] = {0, 92.0, 0, 0}; /* the dragon is in metres */
    static const char *metric_name[] = {"cusp", "roughness", "area", "volume"};
    adaslice_mesh hand;
    adaslice_profile_options po;
    adaslice_profile p, tiled;
    size_t i, j;
    int mi;

    /* the paper's Table 1 row: the Hand, b = 2 um, 23.77 mm tall: N = 11,885 */
    if (!load("examples/models/hand_closed.obj", 23.77, &hand)) return 1;
    memset(&po, 0, sizeof po);
    if (adaslice_profile_exact(&hand, &po, &p, NULL) != ADASLICE_OK) return 1;
    bench_planner("hand, b = 2 um", &p, 41, 5);
    /* N = 1,000,000: the same profile repeated, 2 m of part */
    tiled = p;
    tiled.bin_count = 1000000;
    tiled.phi = (double *)malloc(tiled.bin_count * sizeof(double));
    tiled.area = NULL;
    memset(&tiled.allocator, 0, sizeof tiled.allocator);
    for (i = 0; i < tiled.bin_count; i++) tiled.phi[i] = p.phi[i % p.bin_count];
    bench_planner("hand repeated to 1M bins", &tiled, 11, 1);
    free(tiled.phi);
    adaslice_profile_free(&p);
    adaslice_mesh_free(&hand);

    for (j = 0; j < BENCH_MODEL_COUNT; j++) bench_sampled(models, BENCH_MODELS[j].name, BENCH_MODELS[j].scale);
    bench_masks(models, 1);
    bench_masks(models, 4);
    {
        char path[1024];
        snprintf(path, sizeof path, "%s/turbineblade.ply", models);
        bench_orient(path, "");
        snprintf(path, sizeof path, "%s/dragon_vrip_res2.ply", models);
        bench_orient(path, "--scale 1000");
        write_dragon_plate(models, "build/dragon_plate.ply");
        bench_orient("build/dragon_plate.ply", "");
    }
    for (j = 0; j < sizeof big / sizeof big[0]; j++) {
        char path[1024];
        adaslice_mesh m;
        double t, tl;
        snprintf(path, sizeof path, "%s/%s", models, big[j]);
        t = now();
        if (!load(path, big_height[j], &m)) return 1;
        tl = now() - t;
        printf("profile %-24s %7zu triangles  load %7.1f ms", big[j], m.triangle_count, tl * 1e3);
        for (mi = 0; mi < 4; mi++) {
            double times[9];
            int r;
            memset(&po, 0, sizeof po);
            po.metric = (adaslice_metric)mi;
            for (r = 0; r < 9; r++) {
                t = now();
                if (adaslice_profile_exact(&m, &po, &p, NULL) != ADASLICE_OK) return 1;
                times[r] = now() - t;
                if (r < 8) adaslice_profile_free(&p);
            }
            printf("  %s %6.1f ms", metric_name[mi], median(times, 9) * 1e3);
            if (mi == 3) printf("  (N = %zu)", p.bin_count);
            adaslice_profile_free(&p);
        }
        printf("\n");
        adaslice_mesh_free(&m);
    }
    return 0;
}
