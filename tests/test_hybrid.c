/* plan --hybrid: the faces a contour pass will follow, charged their residual
   instead of the cusp. Each plan is held to the optimal plan of a profile the
   test works out from the solid's own construction (band normals, gradients
   and the residual bound of the manual in closed form), planned by
   `plan --profile`: the code under test is the classification and the
   weighted profile, not the DP. */
#include "cli_run.h"
#include "tool_run.h"
#include "../adaslice.h"
#include "meshgen.h"

#include <math.h>

#define PI 3.14159265358979323846
#define TMIN 0.08
#define TMAX 0.28
#define EPS 0.1
#define BIN 0.002
#define SEGMENT 0.2 /* the contour's default resolution */

static const char *const FDM[] = {"--tmin", "0.08", "--tmax", "0.28", "--eps", "0.1"};

/* One band of faces of a solid the test builds: its heights, as the mesh's
   float vertices hold them, and the value the hybrid profile should give it. */
typedef struct band { double lo, hi, phi; } band;

/* The optimal plan's layer count on the max-type profile of these bands
   (bins as adaslice_profile_exact assigns a face's [lo, hi]: floor((z - z0)
   / b) at both ends), by plan --profile; -1 if it fails. */
static long planned_layers(const band *b, size_t n, double z0, double z1)
{
    size_t bins = (size_t)ceil((z1 - z0) / BIN - 1e-9), i, k;
    double *phi = (double *)calloc(bins, sizeof *phi), inverse = 1.0 / BIN;
    const char *path = cli_path("expected.txt");
    FILE *f = fopen(path, "w");
    cli_result r;
    long layers;
    for (k = 0; k < n; k++) {
        double lo = floor((b[k].lo - z0) * inverse), hi = floor((b[k].hi - z0) * inverse);
        if (hi > (double)(bins - 1)) hi = (double)(bins - 1);
        for (i = (size_t)lo; i <= (size_t)hi; i++)
            if (b[k].phi > phi[i]) phi[i] = b[k].phi;
    }
    for (i = 0; f && i < bins; i++) fprintf(f, "%.17g\n", phi[i]);
    if (f) fclose(f);
    free(phi);
    r = cli_run("plan", "--profile", path, "--bin", "0.002", FDM[0], FDM[1], FDM[2], FDM[3], FDM[4], FDM[5], "--json", NULL);
    layers = r.status == 0 ? (long)cli_json_number(r.out, "layers") : -1;
    CHECKF(r.status == 0, "plan --profile: exit %d: %.200s", r.status, r.err);
    cli_free(&r);
    return layers;
}

/* unzip -p: a member of the 3MF as text, by a reader not ours; NULL if
   there is none. */
static char *zip_entry_text(const char *archive, const char *name)
{
    char *argv[] = {(char *)"unzip", (char *)"-p", (char *)archive, (char *)name, NULL};
    char *text = tool_run("unzip", argv, cli_path("member"), cli_path("unzip.log")) == 0
                     ? read_whole_text(cli_path("member")) : NULL;
    remove(cli_path("member"));
    return text;
}

static cli_result plan_hybrid(const char *model, const char *extra)
{
    return cli_run("plan", model, FDM[0], FDM[1], FDM[2], FDM[3], FDM[4], FDM[5], "--3mf", cli_path("h.3mf"), "--hybrid",
                   "--json", extra, NULL);
}

/* A solid of revolution: rings (r[i], z[i]) of n vertices, i = 0..m-1, closed
   by a disc under ring 0 and a fan to an apex at (0, 0, apex) over the last;
   ring i to i+1 is band i of quads, each split into two triangles. */
static adaslice_mesh revolve(const double *r, const double *z, int m, int n, double apex)
{
    adaslice_mesh g = gen_alloc((size_t)m * n + 2, (size_t)2 * n * m);
    uint32_t bottom = gen_vertex(&g, 0, 0, z[0]), top, first = (uint32_t)g.vertex_count;
    int i, k;
    for (i = 0; i < m; i++)
        for (k = 0; k < n; k++) gen_vertex(&g, r[i] * cos(2 * PI * k / n), r[i] * sin(2 * PI * k / n), z[i]);
    top = gen_vertex(&g, 0, 0, apex);
    for (k = 0; k < n; k++) {
        uint32_t k2 = (uint32_t)((k + 1) % n);
        gen_triangle(&g, bottom, first + k2, first + (uint32_t)k);
        for (i = 0; i + 1 < m; i++) {
            uint32_t a = first + (uint32_t)(i * n + k), b = first + (uint32_t)i * n + k2;
            gen_triangle(&g, a, b, b + (uint32_t)n);
            gen_triangle(&g, a, b + (uint32_t)n, a + (uint32_t)n);
        }
        gen_triangle(&g, first + (uint32_t)((m - 1) * n + k), first + (uint32_t)(m - 1) * n + k2, top);
    }
    return g;
}

/* A hemisphere of radius 20 on a cylinder 10 high, 96 around, 48 rings from
   its equator to the pole. Band j (ring j to j + 1, the last to the apex) has
   n_z = dr c / sqrt(dz^2 + (dr c)^2), c = cos(pi / 96), and the gradient
   dz / (dr c) pointing in at its mid-azimuth: faces up to 15 degrees (n_z >=
   cos 15) are contoured (all of them reachable: the dome is the top and falls
   away outwards), with residual SEGMENT D / 4, D the largest gradient change
   to a contoured face sharing a corner: the bands either side and the same
   band, one azimuth step (2 pi / 96) either way at most, and across the pole
   (the opposite fan face) for the last band. */
static void dome_on_a_cylinder_is_planned_on_its_analytic_profile(void)
{
    enum { N = 96, S = 48, M = S + 1 };
    double r[M], z[M], nz[M + 1], g[M + 1], c = cos(PI / N), apex = 30, worst = 0, lowest = 0;
    band b[M + 2];
    int contoured[M + 1], i, j;
    long faces = 0, expect;
    const char *model = cli_path("dome.obj");
    adaslice_mesh mesh;
    cli_result h;
    r[0] = 20; z[0] = 0;
    for (i = 1; i < M; i++) {
        double a = PI / 2 * (i - 1) / S;
        r[i] = 20 * cos(a);
        z[i] = 10 + 20 * sin(a);
    }
    mesh = revolve(r, z, M, N, apex);
    cli_write_obj(model, &mesh);
    gen_free(&mesh);
    for (j = 0; j <= M - 1; j++) {
        double r1 = r[j], r2 = j + 1 < M ? r[j + 1] : 0, dz = (j + 1 < M ? z[j + 1] : apex) - z[j], dr = (r1 - r2) * c;
        nz[j] = dr / sqrt(dz * dz + dr * dr);
        g[j] = dr > 0 ? dz / dr : 0;
        contoured[j] = nz[j] >= cos(15 * PI / 180);
    }
    b[M] = (band){0, 0, 1}; /* the bottom disc */
    b[M + 1] = (band){0, 0, 0};
    for (j = 0; j <= M - 1; j++) {
        double lo = (float)z[j], hi = (float)(j + 1 < M ? z[j + 1] : apex), most = 0, residual;
        int k;
        b[j] = (band){lo, hi, nz[j]};
        if (!contoured[j]) continue;
        for (k = j - 1; k <= j + 1; k++) {
            double same = k >= 0 && k <= M - 1 && contoured[k] ? fabs(g[j] - g[k]) : 0;
            double step = k >= 0 && k <= M - 1 && contoured[k]
                              ? sqrt(g[j] * g[j] + g[k] * g[k] - 2 * g[j] * g[k] * cos(2 * PI / N)) : 0;
            most = fmax(most, fmax(same, step));
        }
        if (j == M - 1) most = fmax(most, 2 * g[j]);
        residual = SEGMENT * most / 4;
        worst = fmax(worst, residual);
        b[j].phi = residual / TMIN;
        faces += j == M - 1 ? N : 2 * N;
        if (!lowest) lowest = lo;
    }
    expect = planned_layers(b, M + 1, 0, apex);
    h = plan_hybrid(model, NULL);
    CHECKF(h.status == 0, "exit %d: %.300s", h.status, h.err);
    CHECKF((long)cli_json_number(h.out, "contoured_faces") == faces, "%g contoured faces, expected %ld",
           cli_json_number(h.out, "contoured_faces"), faces);
    CHECKF(fabs(cli_json_number(h.out, "residual") - worst) < 1e-5 * worst, "residual %.9g, expected %.9g (float vertices)",
           cli_json_number(h.out, "residual"), worst);
    CHECKF(expect > 0 && (long)cli_json_number(h.out, "layers") == expect, "%g layers, the analytic profile plans %ld",
           cli_json_number(h.out, "layers"), expect);
    CHECKF(lowest > 29 && lowest < 29.5, "the contour starts at %g mm: 15 degrees is z = 10 + 20 cos 15 = 29.32", lowest);
    cli_free(&h);
}

/* A 20 x 20 x 10 mm box under a pyramid roof pitched at `pitch` degrees (its
   four faces meeting at the apex), as one closed shell; with `plate`, a
   separate 22 x 22 x 1 mm plate floats 1 mm above the apex, over all of it. */
static adaslice_mesh house(double pitch, int plate)
{
    adaslice_mesh m = gen_alloc(32, 32);
    double top = 10, apex = top + 10 * tan(pitch * PI / 180);
    uint32_t v[8], a;
    int k;
    for (k = 0; k < 8; k++) v[k] = gen_vertex(&m, k & 1 ? 20 : 0, k & 2 ? 20 : 0, k & 4 ? top : 0);
    a = gen_vertex(&m, 10, 10, apex);
    gen_triangle(&m, v[0], v[2], v[3]); gen_triangle(&m, v[0], v[3], v[1]);   /* bottom */
    gen_triangle(&m, v[0], v[1], v[5]); gen_triangle(&m, v[0], v[5], v[4]);   /* y = 0 */
    gen_triangle(&m, v[1], v[3], v[7]); gen_triangle(&m, v[1], v[7], v[5]);   /* x = 20 */
    gen_triangle(&m, v[3], v[2], v[6]); gen_triangle(&m, v[3], v[6], v[7]);   /* y = 20 */
    gen_triangle(&m, v[2], v[0], v[4]); gen_triangle(&m, v[2], v[4], v[6]);   /* x = 0 */
    gen_triangle(&m, v[4], v[5], a); gen_triangle(&m, v[5], v[7], a);
    gen_triangle(&m, v[7], v[6], a); gen_triangle(&m, v[6], v[4], a);
    if (plate) {
        adaslice_mesh p = gen_box(-1, -1, apex + 1, 21, 21, apex + 2);
        gen_append(&m, &p);
        gen_free(&p);
    }
    return m;
}

/* The roof's faces (n_z = cos 10, gradients tan 10 along +-x and +-y, all
   four at the apex: D = 2 tan 10 between opposite ones) are contoured with
   residual 0.2 * 2 tan 10 / 4; the walls are vertical and the bottom counts
   1 in its bin. The printed surface's worst error is then far below what
   planar layers of 0.08 mm give the roof, so planar is the finest plan, and
   an independent `plan --method finest` must have its layers. */
static void box_with_a_shallow_pyramid_roof(void)
{
    const char *model = cli_path("house.obj");
    adaslice_mesh m = house(10, 0);
    double t10 = tan(10 * PI / 180), residual = SEGMENT * 2 * t10 / 4, apex = (float)(10 + 10 * t10);
    band b[3] = {{0, 0, 1}, {0, 10, 0}, {10, apex, residual / TMIN}};
    long expect;
    cli_result h, f;
    cli_write_obj(model, &m);
    gen_free(&m);
    expect = planned_layers(b, 3, 0, apex);
    h = plan_hybrid(model, NULL);
    CHECKF(h.status == 0, "exit %d: %.300s", h.status, h.err);
    CHECKF(cli_json_number(h.out, "contoured_faces") == 4, "%g faces contoured", cli_json_number(h.out, "contoured_faces"));
    CHECKF(fabs(cli_json_number(h.out, "residual") - residual) < 1e-5 * residual, "residual %.9g, expected %.9g",
           cli_json_number(h.out, "residual"), residual);
    CHECKF(expect > 0 && (long)cli_json_number(h.out, "layers") == expect, "%g layers, the analytic profile plans %ld",
           cli_json_number(h.out, "layers"), expect);
    CHECKF(strstr(h.out, "\"planar_method\": \"finest\"") != NULL, "%.300s", strstr(h.out, "\"hybrid\""));
    f = cli_run("plan", model, FDM[0], FDM[1], FDM[2], FDM[3], FDM[4], FDM[5], "--method", "finest", "--json", NULL);
    CHECKF(f.status == 0 && cli_json_number(f.out, "layers") == cli_json_number(h.out, "planar_layers"),
           "planar %g layers, plan --method finest %g", cli_json_number(h.out, "planar_layers"),
           cli_json_number(f.out, "layers"));
    CHECKF(cli_json_number(h.out, "layers_saved") ==
               cli_json_number(h.out, "planar_layers") - cli_json_number(h.out, "layers") &&
               cli_json_number(h.out, "layers_saved") > 0,
           "%g saved", cli_json_number(h.out, "layers_saved"));
    cli_free(&h);
    cli_free(&f);
}

/* The same roof under a plate: every roof face has the plate above it on
   its rays, so it stays in the profile at n_z = cos 10; only the plate's flat
   top (two faces, no crease: residual 0) is contoured. */
static void a_shallow_face_under_an_overhang_stays_planar(void)
{
    const char *model = cli_path("covered.obj");
    adaslice_mesh m = house(10, 1);
    double t10 = tan(10 * PI / 180), apex = (float)(10 + 10 * t10), plate = (float)(apex + 1), up = (float)(apex + 2);
    /* bottom, walls, roof, the plate's underside (1 in its bin), its sides and top (0: contoured, flat) */
    band b[6] = {{0, 0, 1}, {0, 10, 0}, {10, apex, cos(10 * PI / 180)}, {plate, plate, 1}, {plate, up, 0}, {up, up, 0}};
    long expect;
    cli_result h;
    cli_write_obj(model, &m);
    gen_free(&m);
    expect = planned_layers(b, 6, 0, up);
    h = plan_hybrid(model, NULL);
    CHECKF(h.status == 0, "exit %d: %.300s", h.status, h.err);
    CHECKF(cli_json_number(h.out, "contoured_faces") == 2 && cli_json_number(h.out, "blocked_faces") == 4,
           "%g contoured, %g blocked", cli_json_number(h.out, "contoured_faces"), cli_json_number(h.out, "blocked_faces"));
    CHECKF(expect > 0 && (long)cli_json_number(h.out, "layers") == expect, "%g layers, the analytic profile plans %ld",
           cli_json_number(h.out, "layers"), expect);
    cli_free(&h);
}

/* What the hybrid plan saves is against the optimal planar plan at its worst
   printed error: an independent plan at that eps has the layers and the FDM
   time reported, and the 3MF names the contoured faces for adaslice contour. */
static void savings_are_against_an_independent_planar_plan(void)
{
    enum { N = 64, M = 30 };
    double r[M], z[M], cap = 60;
    const char *model = cli_path("shallow.obj");
    char eps[40], *config;
    adaslice_mesh m;
    cli_result h, p;
    int i;
    /* a shallow dome: a cap 5 mm high of a sphere of radius 60 on a 3 mm disc */
    r[0] = 24; z[0] = 0;
    for (i = 1; i < M; i++) {
        double a = asin(24 / cap) * (1 - (double)(i - 1) / (M - 1));
        r[i] = cap * sin(a);
        z[i] = 3 + cap * cos(a) - cap * cos(asin(24 / cap));
    }
    m = revolve(r, z, M, N, 3 + cap - cap * cos(asin(24 / cap)));
    cli_write_obj(model, &m);
    gen_free(&m);
    h = plan_hybrid(model, NULL);
    CHECKF(h.status == 0, "exit %d: %.300s", h.status, h.err);
    snprintf(eps, sizeof eps, "%.17g", cli_json_number(h.out, "planar_eps"));
    p = cli_run("plan", model, "--tmin", "0.08", "--tmax", "0.28", "--eps", eps, "--3mf", cli_path("planar.3mf"), "--json",
                NULL);
    CHECKF(p.status == 0 && strstr(h.out, "\"planar_method\": \"optimal\""), "exit %d: %.200s", p.status, p.err);
    CHECKF(cli_json_number(p.out, "layers") == cli_json_number(h.out, "planar_layers"), "planar %g, independent %g",
           cli_json_number(h.out, "planar_layers"), cli_json_number(p.out, "layers"));
    CHECKF(fabs(cli_json_number(p.out, "fdm_print_time_s") - cli_json_number(h.out, "planar_print_time_s")) < 1e-6 *
               cli_json_number(p.out, "fdm_print_time_s"),
           "planar time %g, independent %g", cli_json_number(h.out, "planar_print_time_s"),
           cli_json_number(p.out, "fdm_print_time_s"));
    CHECKF(cli_json_number(p.out, "worst_error") <= cli_json_number(h.out, "printed_worst_error") * (1 + 1e-9) &&
               cli_json_number(h.out, "layers_saved") > 0 && cli_json_number(h.out, "print_time_saved_s") > 0,
           "planar worst %g, hybrid printed %g, %g layers saved", cli_json_number(p.out, "worst_error"),
           cli_json_number(h.out, "printed_worst_error"), cli_json_number(h.out, "layers_saved"));
    config = zip_entry_text(cli_path("h.3mf"), "Metadata/adaslice_contour.config");
    CHECKF(config && strstr(config, "; contoured_faces = ") && strstr(config, "; max_angle = 15\n"), "%.200s",
           config ? config : "(no Metadata/adaslice_contour.config)");
    free(config);
    config = zip_entry_text(cli_path("planar.3mf"), "Metadata/adaslice_contour.config");
    CHECKF(!config, "a planar project has %s", "Metadata/adaslice_contour.config");
    free(config);
    cli_free(&h);
    cli_free(&p);
}

/* Each refused with exit 2, one line naming the option, and no 3MF. */
static void bad_hybrid_input_is_refused(void)
{
    static const char *const cases[][6] = {
        {"--hybrid", NULL, NULL, NULL, NULL, "--hybrid needs --3mf"},
        {"--hybrid", "--3mf", "@", "--max-angle", "50", "--max-angle 50"},
        {"--hybrid", "--3mf", "@", "--max-angle", "0", "--max-angle"},
        {"--hybrid", "--3mf", "@", "--max-angle", "-5", "--max-angle"},
        {"--hybrid", "--3mf", "@", "--max-angle", "x", "--max-angle"},
        {"--3mf", "@", "--max-angle", "10", NULL, "add it"},
        {"--hybrid", "--3mf", "@", "--metric", "roughness", "--metric roughness"},
        {"--hybrid", "--3mf", "@", "--reach", "0", "--reach"},
        /* limits contour would refuse when it reads the project (exit 0 here before) */
        {"--hybrid", "--3mf", "@", "--resolution", "1e-300", "--resolution 1e-300"},
        {"--hybrid", "--3mf", "@", "--max-rise", "1e300", "--max-rise 1e+300"},
        {"--hybrid", "--3mf", "@", "--max-rise", "999999.9999", "--max-rise 1e+06"}, /* as the project writes it */
    };
    size_t c;
    for (c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const char *arg[5], *out = cli_path("bad.3mf");
        int k;
        cli_result r;
        for (k = 0; k < 5; k++) arg[k] = cases[c][k] && !strcmp(cases[c][k], "@") ? out : cases[c][k];
        r = cli_run("plan", "examples/models/hand_closed.obj", "--scale", "88.7", arg[0], arg[1], arg[2], arg[3], arg[4],
                    NULL);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, cases[c][5]) && !cli_exists(out),
               "case %zu (%s): exit %d: %s", c, cases[c][5], r.status, r.err);
        cli_free(&r);
    }
}

/* The library refuses what the tool would: an angle outside (0, 45], no
   residual array, no triangles; and it leaves every face of a box's steep
   walls and its bottom planar, its flat top contoured with no residual. */
static void the_library_checks_its_options(void)
{
    adaslice_mesh box = gen_box(0, 0, 0, 10, 10, 10), empty;
    adaslice_hybrid_options o;
    adaslice_hybrid_report rep;
    adaslice_error e;
    float residual[12], weights[12];
    size_t t, top = 0;
    memset(&o, 0, sizeof o);
    memset(&empty, 0, sizeof empty);
    o.max_angle = 50;
    CHECK(adaslice_hybrid_faces(&box, &o, residual, NULL, NULL, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "50"));
    o.max_angle = -1;
    CHECK(adaslice_hybrid_faces(&box, &o, residual, NULL, NULL, &e) == ADASLICE_ERR_ARGUMENT);
    o.max_angle = 0;
    CHECK(adaslice_hybrid_faces(&box, &o, NULL, NULL, NULL, &e) == ADASLICE_ERR_ARGUMENT);
    CHECK(adaslice_hybrid_faces(&empty, &o, residual, NULL, NULL, &e) == ADASLICE_ERR_EMPTY);
    for (t = 0; t < 12; t++) weights[t] = 0.5f;
    CHECKF(adaslice_hybrid_faces(&box, NULL, residual, weights, &rep, &e) == ADASLICE_OK, "%s", e.message);
    for (t = 0; t < box.triangle_count; t++) {
        int up = box.vertices[3 * box.triangles[3 * t] + 2] == 10 && box.vertices[3 * box.triangles[3 * t + 1] + 2] == 10 &&
                 box.vertices[3 * box.triangles[3 * t + 2] + 2] == 10;
        top += up;
        CHECKF(up ? residual[t] == 0 && weights[t] == 0 : residual[t] == -1 && weights[t] == 0.5f,
               "face %zu (%s): residual %g, weight %g", t, up ? "top" : "wall or bottom", residual[t], weights[t]);
    }
    CHECKF(top == 2 && rep.contoured == 2 && rep.candidates == 2 && rep.residual == 0 && fabs(rep.area - 100) < 1e-9 &&
               rep.z_low == 10 && rep.z_high == 10,
           "%zu contoured of %zu, area %g", rep.contoured, rep.candidates, rep.area);
    gen_free(&box);
}

void test_hybrid(void)
{
    if (!cli_begin("adaslice-hybrid")) { CHECK(!"no temporary directory"); return; }
    RUN(dome_on_a_cylinder_is_planned_on_its_analytic_profile);
    RUN(box_with_a_shallow_pyramid_roof);
    RUN(a_shallow_face_under_an_overhang_stays_planar);
    RUN(savings_are_against_an_independent_planar_plan);
    RUN(bad_hybrid_input_is_refused);
    RUN(the_library_checks_its_options);
    cli_end();
}
