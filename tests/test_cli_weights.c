/* End-to-end tests of weights in the tool: adaslice saliency, --weights files,
   --weight regions, --saliency, and --method curvature. */
#include "cli_run.h"
#include "../adaslice.h"
#include "meshgen.h"

#include <math.h>

/* A UV sphere of radius 5 with a bump at latitude 30 degrees. */
static const char *bump_obj(void)
{
    const char *path = cli_path("bump.obj");
    adaslice_mesh m = gen_sphere(5, 64, 32, 0);
    size_t v;
    for (v = 0; v < m.vertex_count; v++) {
        float *p = m.vertices + 3 * v;
        double d[3] = {p[0], p[1], p[2] - 5}, len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        double c = (d[0] * 0.866 + d[2] * 0.5) / len, a = acos(c > 1 ? 1 : c), s = (5 + 0.5 * exp(-a * a / 0.04)) / len;
        p[0] = (float)(d[0] * s); p[1] = (float)(d[1] * s); p[2] = (float)(d[2] * s + 5);
    }
    cli_write_obj(path, &m);
    gen_free(&m);
    return path;
}

/* The values of a weights file, one per line; their count in *n. */
static double *read_values(const char *path, size_t *n)
{
    char *text = read_whole_text(path), *p, *end;
    double *v = NULL;
    size_t cap = 0;
    *n = 0;
    for (p = text; p && *p; p = end) {
        double x = strtod(p, &end);
        if (end == p) break;
        if (*n == cap) v = (double *)realloc(v, (cap = cap ? 2 * cap : 1024) * sizeof *v);
        v[(*n)++] = x;
    }
    free(text);
    return v;
}

/* The weights file has one value in [0,1] per triangle, 1 reached; the PLY
   opens with a colour per vertex; planning with --weights of that file is
   planning with --saliency. */
static void saliency_command_writes_weights_and_a_coloured_mesh(void)
{
    const char *model = bump_obj(), *weights = cli_path("w.txt"), *ply = cli_path("c.ply");
    cli_result r = cli_run("saliency", model, "-o", weights, "--ply", ply, NULL), a, b;
    adaslice_mesh coloured, m;
    adaslice_error e;
    size_t n, i, ones = 0;
    double *w;
    char *header;
    CHECKF(r.status == 0 && !*r.err && strstr(r.out, "triangles"), "exit %d: %s", r.status, r.err);
    CHECK(adaslice_mesh_load_file(model, NULL, &m, &e) == ADASLICE_OK);
    w = read_values(weights, &n);
    CHECKF(n == m.triangle_count, "%zu weights for %zu triangles", n, m.triangle_count);
    for (i = 0; i < n; i++) {
        CHECKF(w[i] >= 0 && w[i] <= 1, "weight %g", w[i]);
        ones += w[i] == 1;
    }
    CHECK(ones >= 1);
    CHECK(adaslice_mesh_load_file(ply, NULL, &coloured, &e) == ADASLICE_OK);
    CHECK(coloured.triangle_count == m.triangle_count && coloured.vertex_count == 3 * m.triangle_count);
    header = read_whole_text(ply);
    CHECK(header && strstr(header, "format binary_little_endian 1.0\n") && strstr(header, "property uchar red\n"));
    a = cli_run("plan", model, "--saliency", "--json", NULL);
    b = cli_run("plan", model, "--weights", weights, "--json", NULL);
    CHECKF(a.status == 0 && b.status == 0, "exits %d, %d: %s %s", a.status, b.status, a.err, b.err);
    CHECK(cli_json_number(a.out, "layers") == cli_json_number(b.out, "layers"));
    CHECK(cli_json_number(a.out, "total_error") == cli_json_number(b.out, "total_error"));
    cli_free(&a);
    cli_free(&b);
    /* with the sampled profile too */
    a = cli_run("plan", model, "--saliency", "--sampler", "ldi", "--res", "256", NULL);
    CHECKF(a.status == 0, "ldi: exit %d: %s", a.status, a.err);
    cli_free(&a);
    free(header);
    free(w);
    adaslice_mesh_free(&coloured);
    adaslice_mesh_free(&m);
    cli_free(&r);
}

static void weight_file_errors(void)
{
    static const struct { const char *text, *named[3]; } cases[] = {
        {"1\n0.5\n", {"w.txt", "2 weights", "4 triangles"}},
        {"1\n1\n1.5\n1\n", {"w.txt:3", "1.5", "[0, 1]"}},
        {"1\nabc\n1\n1\n", {"w.txt:2", "'abc'", "not a number"}},
        {"1\n1\nnan\n1\n", {"w.txt:3", "nan", "not a number"}},
        {"1\n1\n0x1\n1\n", {"w.txt:3", "0x1", "not a number"}}, /* a plain decimal, not hex */
        {"1\n1\n1\n1\n1\n", {"w.txt:5", "more weights", "4 triangles"}},
        {"0.5 junk\n1\n1\n1\n", {"w.txt:1", "0.5 junk", "not a number"}},
    };
    const char *model = cli_path("tet.obj"), *weights = cli_path("w.txt");
    cli_result r;
    size_t i;
    int k;
    cli_write(model, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
    for (i = 0; i < sizeof cases / sizeof *cases; i++) {
        cli_write(weights, cases[i].text);
        r = cli_run("plan", model, "--weights", weights, NULL);
        CHECKF(r.status == 2 && cli_one_message(r.err) && !*r.out, "case %zu: exit %d, '%s'", i, r.status, r.err);
        for (k = 0; k < 3; k++)
            CHECKF(strstr(r.err, cases[i].named[k]) != NULL, "case %zu: '%s' lacks %s", i, r.err, cases[i].named[k]);
        cli_free(&r);
    }
    /* comments and blank lines are skipped */
    cli_write(weights, "# tet\n1\n\n0.5\n0\n1\n");
    r = cli_run("plan", model, "--weights", weights, "--tmin", "0.05", NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    cli_free(&r);
    r = cli_run("plan", model, "--weights", cli_path("missing.txt"), NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "missing.txt"), "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
}

/* A face is in a region when its centroid is (a box's faces count as inside);
   faces in no region keep 1; where regions overlap, the last one given wins;
   weights multiply with a file's. */
static void weight_regions_select_faces_by_centroid(void)
{
    /* t0 inside the box; t1 straddles x = 2 with its centroid exactly on it;
       t2 has a corner in the box and its centroid outside; t3 lies in the
       sphere only; t4 in both box and sphere (the sphere, given last, wins) */
    const char *model = cli_path("faces.obj"), *weights = cli_path("w.txt"), *file = cli_path("half.txt");
    static const double expect[5] = {0.25, 0.25, 1, 0.5, 0.5};
    cli_result r;
    double *w;
    size_t n, i;
    cli_write(model,
              "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
              "v 1.5 0 0\nv 3 0 0\nv 1.5 1 0\n"
              "v 1.8 0 0\nv 4 0 0\nv 4 1 0\n"
              "v 10 0 0\nv 10.5 0 0\nv 10 0.5 0\n"
              "v 1.5 1.5 0\nv 1.9 1.5 0\nv 1.5 1.9 0\n"
              "f 1 2 3\nf 4 5 6\nf 7 8 9\nf 10 11 12\nf 13 14 15\n");
    r = cli_run("saliency", model, "--no-saliency", "--weight", "box:2,2,1,0,0,-1=0.25", "--weight", "sphere:10,0,0,1=0.5",
                "--weight", "sphere:1.6,1.6,0,0.5=0.5", "-o", weights, NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    w = read_values(weights, &n);
    CHECK(n == 5);
    for (i = 0; i < n && i < 5; i++) CHECKF(w[i] == expect[i], "face %zu weighs %g, not %g", i, w[i], expect[i]);
    free(w);
    cli_free(&r);
    cli_write(file, "0.5\n0.5\n0.5\n0.5\n0.5\n");
    r = cli_run("saliency", model, "--no-saliency", "--weights", file, "--weight", "box:0,0,-1,2,2,1=0.5", "-o", weights, NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    w = read_values(weights, &n);
    CHECK(n == 5 && w[0] == 0.25 && w[2] == 0.5 && w[3] == 0.5);
    free(w);
    cli_free(&r);
    /* the blend weighs saliency by --importance: with --no-saliency it was saliency's half all the same, unsaid */
    remove(weights);
    r = cli_run("saliency", model, "--no-saliency", "--view", "top", "-o", weights, NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "--no-saliency with --view") && !cli_exists(weights),
           "exit %d: %s", r.status, r.err);
    cli_free(&r);
}

static void weight_option_errors(void)
{
    static const struct { const char *spec, *named; } cases[] = {
        {"box:1,2,3=0.5", "6 numbers"},
        {"box:0,0,0,1,1,x=0.5", "6 numbers"},
        {"box:0,0,0,1,1,1,1=0.5", "6 numbers"},
        {"sphere:0,0,0,-1=0.5", "radius"},
        {"sphere:0,0,0=0.5", "4 numbers"},
        {"cube:0,0,0,1=1", "unknown region cube"},
        {"box:0,0,0,1,1,1=2", "[0, 1]"},
        {"box:0,0,0,1,1,1=", "[0, 1]"},
        {"box:0,0,0,1,1,1", "expected box:"},
    };
    const char *model = cli_path("tet.obj");
    cli_result r;
    size_t i;
    cli_write(model, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
    for (i = 0; i < sizeof cases / sizeof *cases; i++) {
        r = cli_run("plan", model, "--weight", cases[i].spec, NULL);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, cases[i].spec) && strstr(r.err, cases[i].named),
               "%s: exit %d, '%s'", cases[i].spec, r.status, r.err);
        cli_free(&r);
    }
    r = cli_run("plan", "--profile", cli_path("p.csv"), "--saliency", NULL);
    CHECKF(r.status == 2 && strstr(r.err, "--profile"), "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
    r = cli_run("plan", model, "--weights", "a.txt", "--weights", "b.txt", NULL);
    CHECKF(r.status == 2 && strstr(r.err, "twice"), "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
    r = cli_run("saliency", model, NULL);
    CHECKF(r.status == 2 && strstr(r.err, "-o"), "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
}

/* --method curvature plans, joins --compare, and needs a model. */
static void curvature_method(void)
{
    const char *model = bump_obj(), *profile = cli_path("p.csv");
    cli_result r = cli_run("plan", model, "--method", "curvature", "--mapping", "step", "--json", NULL);
    CHECKF(r.status == 0 && cli_json_number(r.out, "layers") > 0 && strstr(r.out, "\"method\": \"curvature\""),
           "exit %d: %s", r.status, r.err);
    cli_free(&r);
    r = cli_run("plan", model, "--compare", NULL);
    CHECKF(r.status == 0 && strstr(r.out, "\nCurvature "), "exit %d: %s%s", r.status, r.out, r.err);
    cli_free(&r);
    cli_write(profile, "0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n"
                       "0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n0.5\n");
    r = cli_run("plan", "--profile", profile, "--method", "curvature", NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "curvature"), "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
    r = cli_run("plan", "--profile", profile, "--compare", "--tmin", "0.01", "--tmax", "0.02", NULL);
    CHECKF(r.status == 0 && !strstr(r.out, "Curvature"), "exit %d: %s", r.status, r.err);
    cli_free(&r);
    r = cli_run("plan", model, "--method", "curvature", "--mapping", "cubic", NULL);
    CHECKF(r.status == 2 && strstr(r.err, "cubic"), "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
}

/* Regions are in the model's own coordinates even when --orient turns the
   part: a box around the whole model weighing 0 leaves a cusp profile of
   zeros (worst error 0). The direction search neither weighs faces nor plans
   by curvature, and says so. */
static void weights_and_orient(void)
{
    const char *model = bump_obj();
    cli_result r = cli_run("plan", model, "--orient", "1,0,0", "--weight", "box:-6,-6,-1,6,6,12=0", "--json", NULL);
    CHECKF(r.status == 0 && cli_json_number(r.out, "worst_error") == 0, "exit %d: %s %s", r.status, r.out, r.err);
    cli_free(&r);
    r = cli_run("orient", model, "--method", "curvature", NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err), "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
    r = cli_run("orient", model, "--saliency", NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err), "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
    r = cli_run("plan", model, "--orient", "best", "--method", "curvature", NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "curvature"), "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
}

/* The blend of saliency-preserving slicing: with --importance 0,1,0 the
   weights are the view importance alone (divided by its largest), so the
   sphere's top faces weigh 1 and its bottom ones 0; the default blend lies in
   [0, 1] with its largest value 1 and differs from saliency alone; a named
   view and a direction list are taken, bad values refused. */
static void importance_blends_saliency_view_and_user_weights(void)
{
    const char *model = bump_obj(), *out = cli_path("blend.txt"), *only = cli_path("saliency.txt");
    adaslice_mesh m = gen_sphere(5, 64, 32, 0);
    cli_result r;
    double *w, *sal, top = 0, bottom = 1, lo = 1, hi = 0;
    size_t n = 0, ns = 0, t, differ = 0;
    r = cli_run("saliency", model, "--importance", "0,1,0", "-o", out, NULL);
    CHECKF(r.status == 0, "%s", r.err);
    cli_free(&r);
    w = read_values(out, &n);
    CHECK(n == m.triangle_count);
    for (t = 0; w && t < n; t++) {
        const float *a = m.vertices + 3 * m.triangles[3 * t];
        if (a[2] > 9.9) top = top > w[t] ? top : w[t];
        if (a[2] < 0.1) bottom = bottom < w[t] ? bottom : w[t];
    }
    CHECKF(top == 1 && bottom == 0, "view only: top %g, bottom %g", top, bottom);
    free(w);
    r = cli_run("saliency", model, "--view", "hemisphere", "-o", out, NULL);
    CHECKF(r.status == 0, "%s", r.err);
    cli_free(&r);
    r = cli_run("saliency", model, "-o", only, NULL);
    cli_free(&r);
    w = read_values(out, &n);
    sal = read_values(only, &ns);
    for (t = 0; w && sal && t < n && t < ns; t++) {
        lo = lo < w[t] ? lo : w[t];
        hi = hi > w[t] ? hi : w[t];
        differ += fabs(w[t] - sal[t]) > 1e-3;
    }
    CHECKF(n == ns && lo >= 0 && hi == 1 && differ > n / 4, "blend in [%g, %g], %zu of %zu differ from saliency", lo, hi, differ, n);
    free(w);
    free(sal);
    {
        const char *png = cli_path("view.png");
        char *bytes;
        r = cli_run("saliency", model, "--importance", "0,1,0", "--png", png, NULL);
        bytes = read_whole_text(png);
        CHECKF(r.status == 0 && bytes && !memcmp(bytes, "\x89PNG\r\n\x1a\n", 8), "--png: %s", r.err);
        free(bytes);
        cli_free(&r);
    }
    {
        /* four views of 64 px: coarser, so different weights, still in [0, 1] */
        const char *coarse = cli_path("coarse.txt");
        double *a, *b;
        size_t na = 0, nb = 0, k, changed = 0;
        r = cli_run("saliency", model, "--importance", "0,1,0", "--view-count", "4", "--view-res", "64", "-o", coarse, NULL);
        CHECKF(r.status == 0, "%s", r.err);
        cli_free(&r);
        r = cli_run("saliency", model, "--importance", "0,1,0", "-o", out, NULL);
        cli_free(&r);
        a = read_values(coarse, &na);
        b = read_values(out, &nb);
        for (k = 0; a && b && k < na && k < nb; k++) changed += fabs(a[k] - b[k]) > 1e-6 && a[k] >= 0 && a[k] <= 1;
        CHECKF(na == nb && changed > na / 10, "--view-count 4 --view-res 64 changed %zu of %zu weights", changed, na);
        free(a);
        free(b);
    }
    r = cli_run("plan", model, "--view", "front", "--json", NULL);
    CHECKF(r.status == 0 && cli_json_number(r.out, "layers") > 0, "%s", r.err);
    cli_free(&r);
    r = cli_run("plan", model, "--view", "0,0,1,1,0,0", "--importance", "0.2,0.8,0", "--json", NULL);
    CHECKF(r.status == 0, "%s", r.err);
    cli_free(&r);
    {
        static const char *const bad[][2] = {{"--view-count", "0"}, {"--view-res", "9000"}, {"--view", "up"}, {"--view", "0,0"}, {"--view", "0,0,0"}, {"--view", "1,2,x"},
                                             {"--importance", "1,2"}, {"--importance", "-1,0,1"}, {"--importance", "0,0,0"},
                                             {"--importance", "a,b,c"}};
        size_t k;
        for (k = 0; k < sizeof bad / sizeof *bad; k++) {
            r = cli_run("plan", model, bad[k][0], bad[k][1], NULL);
            CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, bad[k][1]), "%s %s: exit %d, '%s'", bad[k][0],
                   bad[k][1], r.status, r.err);
            cli_free(&r);
        }
    }
    gen_free(&m);
}

void test_cli_weights(void)
{
    if (!cli_begin("adaslice-weights")) return;
    RUN(saliency_command_writes_weights_and_a_coloured_mesh);
    RUN(weight_file_errors);
    RUN(weight_regions_select_faces_by_centroid);
    RUN(weight_option_errors);
    RUN(curvature_method);
    RUN(weights_and_orient);
    RUN(importance_blends_saliency_view_and_user_weights);
    cli_end();
}
