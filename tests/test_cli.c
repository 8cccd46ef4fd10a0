/* End-to-end tests of the adaslice tool: the binary named by $ADASLICE_BIN
   (default build/adaslice, relative to the repository root) runs as a child
   process with its output captured in files of a temporary directory. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#endif
#include "check.h"
#include "../adaslice.h"
#include "meshgen.h"

#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static const char *tool = "build/adaslice";
static char dir[64];

/* DIR/name; the last eight results stay valid (run() uses none of them). */
static const char *in_dir(const char *name)
{
    static char ring[8][512];
    static int next;
    char *p = ring[next++ & 7];
    snprintf(p, sizeof ring[0], "%s/%s", dir, name);
    return p;
}

static char *read_all(const char *path)
{
    FILE *f = fopen(path, "rb");
    char *s = NULL;
    long n;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (s = (char *)malloc((size_t)n + 1)) != NULL) {
        s[fread(s, 1, (size_t)n, f)] = 0;
    }
    fclose(f);
    return s;
}

static void write_all(const char *path, const void *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    CHECKF(f && fwrite(data, 1, size, f) == size && fclose(f) == 0, "cannot write %s", path);
}

static int exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

typedef struct run_result {
    int status; /* exit status, or -1 if the tool did not exit normally */
    char *out, *err;
} run_result;

static run_result run_argv(const char *const *args)
{
    char *argv[32], out_path[600], err_path[600];
    run_result r;
    pid_t pid;
    int n = 0, st;
    snprintf(out_path, sizeof out_path, "%s/stdout", dir);
    snprintf(err_path, sizeof err_path, "%s/stderr", dir);
    argv[n++] = (char *)tool;
    while (*args && n < 31) argv[n++] = (char *)*args++;
    argv[n] = NULL;
    fflush(NULL);
    pid = fork();
    if (pid == 0) {
        int in = open("/dev/null", O_RDONLY);
        int out = open(out_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        int err = open(err_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (in < 0 || out < 0 || err < 0 || dup2(in, 0) < 0 || dup2(out, 1) < 0 || dup2(err, 2) < 0) _exit(126);
        execv(tool, argv);
        _exit(127);
    }
    r.status = -1;
    if (pid > 0 && waitpid(pid, &st, 0) == pid && WIFEXITED(st)) r.status = WEXITSTATUS(st);
    CHECKF(r.status != 127, "cannot run %s (build it first; tests run from the repository root)", tool);
    r.out = read_all(out_path);
    r.err = read_all(err_path);
    if (!r.out) r.out = (char *)calloc(1, 1);
    if (!r.err) r.err = (char *)calloc(1, 1);
    return r;
}

/* run(arg, ..., NULL) */
static run_result run(const char *first, ...)
{
    const char *args[32];
    va_list ap;
    int n = 0;
    va_start(ap, first);
    for (args[n] = first; args[n] && n < 31; args[n] = va_arg(ap, const char *)) n++;
    va_end(ap);
    args[n] = NULL;
    return run_argv(args);
}

static void run_free(run_result *r)
{
    free(r->out);
    free(r->err);
}

/* One line on stderr, "adaslice: ..." */
static int one_message(const char *err)
{
    const char *nl = strchr(err, '\n');
    return !strncmp(err, "adaslice: ", 10) && nl && nl[1] == 0;
}

/* The number after "key": in a JSON text (its first occurrence), or NAN. */
static double json_field(const char *json, const char *key)
{
    char pat[64];
    const char *p;
    snprintf(pat, sizeof pat, "\"%s\":", key);
    p = strstr(json, pat);
    return p ? strtod(p + strlen(pat), NULL) : NAN;
}

static size_t count_of(const char *s, const char *what)
{
    size_t n = 0;
    while ((s = strstr(s, what)) != NULL) n++, s++;
    return n;
}

static void put_u32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v; p[1] = (unsigned char)(v >> 8); p[2] = (unsigned char)(v >> 16); p[3] = (unsigned char)(v >> 24);
}

static void put_f32(unsigned char *p, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    put_u32(p, v);
}

/* Binary STL of m, little-endian whatever the host; normals left zero, as
   loaders recompute them from the winding. `keep` triangles are written of
   the count the header claims (truncated files for the error path). */
static void write_stl(const char *path, const adaslice_mesh *m, size_t keep)
{
    size_t size = 84 + 50 * keep, t;
    unsigned char *buf = (unsigned char *)calloc(size, 1);
    int c, k;
    if (!buf) abort();
    memcpy(buf, "adaslice test_cli", 17);
    put_u32(buf + 80, (uint32_t)m->triangle_count);
    for (t = 0; t < keep; t++)
        for (c = 0; c < 3; c++)
            for (k = 0; k < 3; k++)
                put_f32(buf + 84 + 50 * t + 12 + 12 * c + 4 * k, m->vertices[3 * m->triangles[3 * t + c] + k]);
    write_all(path, buf, size);
    free(buf);
}

static const char *sphere_stl(void)
{
    const char *path = in_dir("sphere.stl");
    if (!exists(path)) {
        adaslice_mesh m = gen_sphere(5, 64, 32, 0);
        write_stl(path, &m, m.triangle_count);
        gen_free(&m);
    }
    return path;
}

/* ------------------------------------------------------------------ cases */

static void test_cli_help_and_version(void)
{
    run_result r = run("--help", NULL);
    CHECK(r.status == 0 && strstr(r.out, "plan") && !*r.err);
    run_free(&r);
    r = run("plan", "--help", NULL);
    CHECK(r.status == 0 && strstr(r.out, "--eps") && strstr(r.out, "--profile") && !*r.err);
    run_free(&r);
    r = run("--version", NULL);
    CHECK(r.status == 0 && strstr(r.out, ADASLICE_VERSION));
    run_free(&r);
    r = run(NULL);
    CHECK(r.status == 2 && strstr(r.err, "usage") && !*r.out);
    run_free(&r);
    r = run("frobnicate", NULL);
    CHECK(r.status == 2 && one_message(r.err) && strstr(r.err, "frobnicate"));
    run_free(&r);
}

static void test_cli_bad_arguments(void)
{
    /* the model does not exist: arguments are checked before anything is read */
    static const struct { const char *args[8]; const char *named[2]; } cases[] = {
        {{"plan", "m.stl", "--frobnicate"}, {"--frobnicate"}},
        {{"plan", "m.stl", "-x"}, {"-x"}},
        {{"plan", "m.stl", "--eps"}, {"--eps"}},
        {{"plan", "m.stl", "--out", "--json"}, {"--out"}},
        {{"plan", "m.stl", "--eps", "abc"}, {"--eps", "abc"}},
        {{"plan", "m.stl", "--eps", "0.1x"}, {"--eps", "0.1x"}},
        {{"plan", "m.stl", "--eps", "-1"}, {"--eps", "-1"}},
        {{"plan", "m.stl", "--tmin", "0"}, {"--tmin", "0"}},
        {{"plan", "m.stl", "--bin", "inf"}, {"--bin", "inf"}},
        {{"plan", "m.stl", "--tmax", "nan"}, {"--tmax", "nan"}},
        {{"plan", "m.stl", "--scale", "1e999"}, {"--scale", "1e999"}},
        {{"plan", "m.stl", "--sharp", "-0.5"}, {"--sharp", "-0.5"}},
        {{"plan", "m.stl", "--metric", "curvature"}, {"--metric", "curvature"}},
        {{"plan", "m.stl", "--method", "fastest"}, {"--method", "fastest"}},
        {{"plan", "m.stl", "--budget", "0"}, {"--budget", "0"}},
        {{"plan", "m.stl", "--budget", "2.5"}, {"--budget", "2.5"}},
        {{"plan", "m.stl", "--budget", "-3"}, {"--budget", "-3"}},
        {{"plan", "m.stl", "--budget", "99999999999999999999999"}, {"--budget"}},
        {{"plan"}, {"MODEL"}},
        {{"plan", "--json"}, {"MODEL"}},
        {{"plan", "m.stl", "--profile", "p.csv"}, {"m.stl", "--profile"}},
        {{"plan", "m.stl", "n.stl"}, {"n.stl"}},
        {{"plan", "m.stl", "--tmin", "0.2", "--tmax", "0.1"}, {"--tmin", "--tmax"}},
        {{"plan", "m.stl", "--method", "greedy", "--budget", "10"}, {"--budget"}},
        {{"plan", "--profile", "p.csv", "--scale", "2"}, {"--scale"}},
    };
    size_t i;
    int k;
    for (i = 0; i < sizeof cases / sizeof *cases; i++) {
        run_result r = run_argv(cases[i].args);
        CHECKF(r.status == 2, "case %zu (%s %s): exit %d", i, cases[i].args[1], cases[i].args[2] ? cases[i].args[2] : "", r.status);
        CHECKF(one_message(r.err) && !*r.out, "case %zu: stderr '%s'", i, r.err);
        for (k = 0; k < 2; k++)
            CHECKF(!cases[i].named[k] || strstr(r.err, cases[i].named[k]), "case %zu: '%s' does not name %s",
                   i, r.err, cases[i].named[k]);
        run_free(&r);
    }
}

/* The plan of a sphere: the CSV tiles [0, N*b] with layers inside the bounds
   and error limits, and agrees with the JSON report. */
static void test_cli_plan_sphere(void)
{
    const char *plan_csv = in_dir("plan.csv"), *profile_csv = in_dir("profile.csv"), *svg = in_dir("plot.svg");
    run_result r = run("plan", sphere_stl(), "--json", "--out", plan_csv, "--profile-out", profile_csv,
                       "--plot", svg, NULL);
    char *csv = read_all(plan_csv), *prof = read_all(profile_csv), *plot = read_all(svg), *line, *save = NULL;
    double layers = json_field(r.out, "layers"), bins = json_field(r.out, "bins"), bin = json_field(r.out, "bin");
    double height = json_field(r.out, "height_mm"), eps = json_field(r.out, "eps");
    double tmin = json_field(r.out, "tmin"), tmax = json_field(r.out, "tmax"), top = 0;
    size_t rows = 0;

    CHECKF(r.status == 0 && !*r.err, "exit %d: %s", r.status, r.err);
    CHECK(layers > 0 && bins > 0 && bin == 0.002 && eps == 0.065 && tmin == 0.05 && tmax == 0.15);
    CHECK(fabs(height - 10) < 1e-6 && json_field(r.out, "triangles") == 2 * 64 * 31);
    CHECK(count_of(r.out, "\"z_bottom\"") == (size_t)layers);
    CHECK(csv && prof && plot);
    if (!csv || !prof || !plot) goto done;

    line = strtok_r(csv, "\n", &save);
    CHECK(line && !strcmp(line, "layer,z_bottom,z_top,thickness,error"));
    while ((line = strtok_r(NULL, "\n", &save)) != NULL) {
        size_t k;
        double z0, z1, t, e;
        CHECKF(sscanf(line, "%zu,%lf,%lf,%lf,%lf", &k, &z0, &z1, &t, &e) == 5 && k == ++rows, "row %zu: %s", rows, line);
        CHECKF(fabs(z0 - top) <= 1e-9, "row %zu starts at %.17g, the previous ends at %.17g", rows, z0, top);
        CHECKF(t >= tmin - 1e-9 && t <= tmax + 1e-9 && fabs(t - (z1 - z0)) <= 1e-9, "row %zu: thickness %g", rows, t);
        CHECKF(e >= 0 && e <= eps + 1e-9, "row %zu: error %g", rows, e);
        top = z1;
    }
    CHECK(rows == (size_t)layers);
    CHECKF(fabs(top - bins * bin) <= 1e-9 && top >= height - 1e-9 && top < height + bin, "top %.17g", top);

    CHECK(!strncmp(prof, "z,phi\n", 6) && count_of(prof, "\n") == (size_t)bins + 1);
    CHECK((!strncmp(plot, "<?xml", 5) || !strncmp(plot, "<svg", 4)) && strlen(plot) < 200000);
    CHECK(strstr(plot, "</svg>") && !strcmp(strstr(plot, "</svg>"), "</svg>\n"));
done:
    free(csv);
    free(prof);
    free(plot);
    run_free(&r);

    r = run("plan", sphere_stl(), NULL);
    CHECK(r.status == 0 && strstr(r.out, "layers") && strstr(r.out, "sphere.stl") && !*r.err);
    run_free(&r);
}

/* --sampler ldi plans from the paper's sampled profile: on a sphere it
   agrees with the exact profile's plan to within 2 % of the layers. */
static void test_cli_sampler(void)
{
    run_result a = run("plan", sphere_stl(), "--json", NULL), b = run("plan", sphere_stl(), "--json", "--sampler", "ldi",
                                                                       "--res", "1024", NULL);
    double ka = json_field(a.out, "layers"), kb = json_field(b.out, "layers");
    CHECKF(a.status == 0 && b.status == 0, "%s %s", a.err, b.err);
    CHECKF(ka > 0 && fabs(ka - kb) <= 0.02 * ka, "exact %g layers, ldi %g", ka, kb);
    CHECK(strstr(b.out, "\"sampler\": \"ldi\"") != NULL);
    run_free(&a);
    run_free(&b);
    a = run("plan", sphere_stl(), "--sampler", "gpu", NULL);
    CHECK(a.status == 2 && one_message(a.err) && strstr(a.err, "--sampler gpu"));
    run_free(&a);
    a = run("plan", sphere_stl(), "--sampler", "ldi", "--res", "0", NULL);
    CHECK(a.status == 2 && one_message(a.err) && strstr(a.err, "--res"));
    run_free(&a);
}

static void test_cli_profile_input(void)
{
    const char *csv = in_dir("p.csv"), *plain = in_dir("p.txt");
    FILE *f = fopen(csv, "w");
    run_result r;
    int i;
    if (f) {
        fputs("z,phi\n", f);
        for (i = 0; i < 300; i++) fprintf(f, "%g,%g\n", (i + 0.5) * 0.01, i < 100 ? 0.2 : 0.5);
        fclose(f);
    }
    /* 2..5 bins per layer; a layer holds two bins of 0.5 or five of 0.2 */
    r = run("plan", "--profile", csv, "--bin", "0.01", "--tmin", "0.02", "--tmax", "0.05", "--eps", "0.0105",
            "--json", NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    CHECK(json_field(r.out, "bins") == 300 && json_field(r.out, "layers") >= 115);
    CHECK(json_field(r.out, "worst_error") <= 0.0105);
    run_free(&r);

    r = run("plan", "--profile", csv, "--bin", "0.01", "--tmin", "0.02", "--tmax", "0.05", "--budget", "100",
            "--json", NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    CHECK(json_field(r.out, "layers") <= 100 && json_field(r.out, "eps") > 0.0105);
    run_free(&r);

    f = fopen(plain, "w");
    if (f) {
        fputs("# one value per line\n\n", f);
        for (i = 0; i < 50; i++) fprintf(f, "%g\n", i % 10 ? 0.1 : 0.9);
        fputs("\n", f);
        fclose(f);
    }
    r = run("plan", "--profile", plain, "--json", "--sharp", "0", NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    CHECK(json_field(r.out, "bins") == 50 && json_field(r.out, "layers") >= 1);
    run_free(&r);
}

static void test_cli_profile_bad_lines(void)
{
    static const struct { const char *text, *named; } cases[] = {
        {"phi\n0.1\n0.2\nabc\n0.3\n", ":4"},
        {"0.1\n0.2,x\n", ":2"},
        {"0.1\n-0.2\n", ":2"},
        {"# c\n0.1\nnan\n", ":3"},
        {"0.1\n1e999\n", ":2"},
        {"h1\nh2\n", ":2"},
    };
    const char *path = in_dir("bad.csv");
    size_t i;
    for (i = 0; i < sizeof cases / sizeof *cases; i++) {
        run_result r;
        write_all(path, cases[i].text, strlen(cases[i].text));
        r = run("plan", "--profile", path, NULL);
        CHECKF(r.status == 1 && one_message(r.err) && strstr(r.err, "bad.csv") && strstr(r.err, cases[i].named),
               "case %zu: exit %d, '%s'", i, r.status, r.err);
        run_free(&r);
    }
}

static void test_cli_infeasible(void)
{
    run_result r = run("plan", sphere_stl(), "--eps", "0.0001", NULL);
    CHECKF(r.status == 1 && one_message(r.err) && strstr(r.err, "eps"), "exit %d, '%s'", r.status, r.err);
    run_free(&r);
}

static void test_cli_compare(void)
{
    run_result r = run("plan", sphere_stl(), "--compare", NULL);
    CHECK(r.status == 0 && strstr(r.out, "Coarsest") && strstr(r.out, "Optimal") && strstr(r.out, "Greedy") &&
          strstr(r.out, "Finest"));
    run_free(&r);
}

/* Outputs that cannot be written fail with exit 1 and leave no file, not even
   the temporary one. */
/* adaslice slice: a complete job directory, its manifest agreeing with the
   plan and the PNGs; a part too big for the plate, an unknown printer, and a
   run that fails part-way leaving no manifest behind. */
static void test_cli_slice(void)
{
    char job[600], path[1000], *manifest, *csv, *png;
    run_result r;
    size_t layers, rows, k;
    snprintf(job, sizeof job, "%s/job", dir);
    r = run("slice", sphere_stl(), "-o", job, "--printer", "2k-5.5", "--svg", NULL);
    CHECKF(r.status == 0 && !*r.err, "exit %d: %s", r.status, r.err);
    run_free(&r);
    snprintf(path, sizeof path, "%s/manifest.json", job);
    manifest = read_all(path);
    snprintf(path, sizeof path, "%s/plan.csv", job);
    csv = read_all(path);
    CHECK(manifest && csv);
    if (!manifest || !csv) { free(manifest); free(csv); return; }
    layers = (size_t)json_field(manifest, "layer_count");
    rows = count_of(csv, "\n") - 1;
    CHECKF(layers > 50 && layers == rows && count_of(manifest, "\"lit_area_mm2\"") == layers, "%zu layers, %zu rows", layers, rows);
    CHECK(strstr(manifest, "\"complete\": true") && strstr(manifest, "\"width_px\": 2560") && strstr(manifest, "\"bits\": 1"));
    for (k = 1; k <= layers; k++) {
        snprintf(path, sizeof path, "%s/layer_%05zu.png", job, k);
        png = read_all(path);
        CHECKF(png && !memcmp(png, "\x89PNG\r\n\x1a\n", 8) && png[24] == 1, "layer %zu: not a 1-bit PNG", k);
        free(png);
        snprintf(path, sizeof path, "%s/layer_%05zu.svg", job, k);
        CHECKF(exists(path), "layer %zu: no contour SVG", k);
    }
    snprintf(path, sizeof path, "%s/layer_%05zu.png", job, layers + 1);
    CHECK(!exists(path));
    free(manifest);
    free(csv);

    /* 8-bit anti-aliased masks */
    r = run("slice", sphere_stl(), "-o", job, "--aa", "4", "--pixels", "600x400", "--pitch", "0.05", NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    run_free(&r);
    snprintf(path, sizeof path, "%s/layer_00001.png", job);
    png = read_all(path);
    CHECK(png && png[24] == 8);
    free(png);

    /* turning or mirroring the image changes no mask but its orientation:
       a 2560 x 1440 display turned a quarter still gets 2560 x 1440 images */
    r = run("slice", sphere_stl(), "-o", job, "--rotate", "90", "--mirror", "xy", NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    run_free(&r);
    snprintf(path, sizeof path, "%s/layer_00001.png", job);
    png = read_all(path);
    CHECK(png && (unsigned char)png[18] == 0x0a && (unsigned char)png[19] == 0x00 && (unsigned char)png[22] == 0x05 &&
          (unsigned char)png[23] == 0xa0); /* width 2560, height 1440 */
    free(png);
    {
        char first[64] = "", other[64] = "";
        const char *turns[2][4] = {{"--rotate", "0", "--mirror", "none"}, {"--rotate", "270", "--mirror", "x"}};
        int t;
        for (t = 0; t < 2; t++) {
            char *mf, *lit;
            r = run("slice", sphere_stl(), "-o", job, "--pixels", "400x400", "--pitch", "0.05", turns[t][0], turns[t][1],
                    turns[t][2], turns[t][3], NULL);
            CHECK(r.status == 0);
            run_free(&r);
            snprintf(path, sizeof path, "%s/manifest.json", job);
            mf = read_all(path);
            lit = mf ? strstr(mf, "\"lit_area_mm2\"") : NULL;
            if (lit) snprintf(t ? other : first, 64, "%.40s", lit);
            free(mf);
        }
        CHECKF(*first && !strcmp(first, other), "lit areas differ: %s / %s", first, other);
    }

    /* a 10 mm sphere on a 5 x 5 mm plate */
    r = run("slice", sphere_stl(), "-o", job, "--pixels", "100x100", "--pitch", "0.05", NULL);
    CHECKF(r.status == 1 && one_message(r.err) && strstr(r.err, "does not fit") && strstr(r.err, "5 mm too wide"),
           "exit %d: %s", r.status, r.err);
    run_free(&r);
    snprintf(path, sizeof path, "%s/manifest.json", job);
    CHECK(!exists(path));
    r = run("slice", sphere_stl(), "-o", job, "--printer", "laser-9000", NULL);
    CHECK(r.status == 2 && one_message(r.err) && strstr(r.err, "laser-9000"));
    run_free(&r);
    r = run("slice", sphere_stl(), NULL);
    CHECK(r.status == 2 && one_message(r.err) && strstr(r.err, "-o JOBDIR"));
    run_free(&r);

    /* a complete job, then a run that cannot write its third layer */
    r = run("slice", sphere_stl(), "-o", job, NULL);
    CHECK(r.status == 0 && exists(path));
    run_free(&r);
    snprintf(path, sizeof path, "%s/layer_00003.png", job);
    remove(path);
    mkdir(path, 0755);
    r = run("slice", sphere_stl(), "-o", job, NULL);
    CHECKF(r.status == 1 && one_message(r.err) && strstr(r.err, "layer_00003.png"), "exit %d: %s", r.status, r.err);
    run_free(&r);
    rmdir(path);
    snprintf(path, sizeof path, "%s/manifest.json", job);
    CHECKF(!exists(path), "an interrupted job still has a manifest");
    {
        DIR *d = opendir(job);
        struct dirent *e;
        while (d && (e = readdir(d)) != NULL) {
            snprintf(path, sizeof path, "%s/%s", job, e->d_name);
            if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) remove(path);
        }
        if (d) closedir(d);
        rmdir(job);
    }
}

/* adaslice orient: a long box lies down; plan --orient with the direction
   found plans the same layers; bad counts and weights are usage errors. */
static void test_cli_orient(void)
{
    const char *box = in_dir("box.stl"), *bad[][2] = {{"--dirs", "0"}, {"--dirs", "-3"}, {"--dirs", "2000000"},
                                                     {"--dirs", "1.5"}, {"--alpha", "1.5"}, {"--alpha", "-0.1"},
                                                     {"--alpha", "x"}};
    adaslice_mesh m = gen_box(0, 0, 0, 10, 10, 50);
    run_result r;
    char dir_arg[128];
    double d[3], k;
    const char *p;
    size_t i;
    write_stl(box, &m, m.triangle_count);
    gen_free(&m);
    r = run("orient", box, "--dirs", "1000", "--json", "--map", in_dir("map.svg"), NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    p = strstr(r.out, "\"direction\": [");
    CHECK(p && sscanf(p, "\"direction\": [%lf, %lf, %lf]", &d[0], &d[1], &d[2]) == 3);
    k = json_field(r.out, "layers");
    CHECKF(fabs(d[2]) < 0.1 && (fabs(d[0]) > 0.95 || fabs(d[1]) > 0.95) && k > 60 && k < 200, "best (%g, %g, %g), %g layers", d[0], d[1], d[2], k);
    CHECK(exists(in_dir("map.svg")));
    run_free(&r);
    snprintf(dir_arg, sizeof dir_arg, "%.9g,%.9g,%.9g", d[0], d[1], d[2]);
    r = run("plan", box, "--orient", dir_arg, "--json", NULL);
    CHECKF(r.status == 0 && json_field(r.out, "layers") == k, "plan --orient %s: %g layers, orient said %g", dir_arg,
           json_field(r.out, "layers"), k);
    run_free(&r);
    for (i = 0; i < sizeof bad / sizeof *bad; i++) {
        r = run("orient", box, bad[i][0], bad[i][1], NULL);
        CHECKF(r.status == 2 && one_message(r.err) && strstr(r.err, bad[i][0]), "%s %s: exit %d, '%s'", bad[i][0], bad[i][1],
               r.status, r.err);
        run_free(&r);
    }
    r = run("plan", box, "--orient", "0,0,0", NULL);
    CHECK(r.status == 2 && one_message(r.err) && strstr(r.err, "--orient"));
    run_free(&r);
}

static void test_cli_unwritable_output(void)
{
    const char *missing = in_dir("missing/plan.csv");
    run_result r = run("plan", sphere_stl(), "--out", missing, NULL);
    DIR *d;
    struct dirent *e;
    CHECKF(r.status == 1 && one_message(r.err) && strstr(r.err, "missing/plan.csv"), "exit %d, '%s'", r.status, r.err);
    CHECK(!exists(missing));
    run_free(&r);

    /* a directory in the way: the temporary file is written, the rename fails */
    mkdir(in_dir("taken"), 0755);
    r = run("plan", sphere_stl(), "--plot", in_dir("taken"), NULL);
    CHECKF(r.status == 1 && one_message(r.err), "exit %d, '%s'", r.status, r.err);
    run_free(&r);
    d = opendir(dir);
    while (d && (e = readdir(d)) != NULL) CHECKF(!strstr(e->d_name, ".tmp."), "left behind: %s", e->d_name);
    if (d) closedir(d);
    rmdir(in_dir("taken"));
}

static void test_cli_bad_model(void)
{
    const char *path = in_dir("truncated.stl");
    adaslice_mesh m = gen_sphere(5, 16, 8, 0);
    adaslice_mesh loaded;
    adaslice_error err;
    char expect[400];
    run_result r;
    write_stl(path, &m, 3);
    gen_free(&m);
    CHECK(adaslice_mesh_load_file(path, NULL, &loaded, &err) != ADASLICE_OK);
    snprintf(expect, sizeof expect, "adaslice: %s\n", err.message);
    r = run("plan", path, NULL);
    CHECKF(r.status == 1 && !strcmp(r.err, expect), "exit %d, '%s', expected '%s'", r.status, r.err, expect);
    run_free(&r);

    r = run("plan", in_dir("no-such-model.stl"), NULL);
    CHECKF(r.status == 1 && one_message(r.err) && strstr(r.err, "no-such-model.stl"), "exit %d, '%s'", r.status, r.err);
    run_free(&r);
}

static void remove_dir(void)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) remove(in_dir(e->d_name));
    if (d) closedir(d);
    rmdir(dir);
}

void test_cli(void)
{
    const char *tmp = getenv("TMPDIR"), *bin = getenv("ADASLICE_BIN");
    if (bin && *bin) tool = bin;
    snprintf(dir, sizeof dir, "%s/adaslice-cli-XXXXXX", tmp && strlen(tmp) < 40 ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        perror("test_cli: mkdtemp");
        return;
    }
    RUN(test_cli_help_and_version);
    RUN(test_cli_bad_arguments);
    RUN(test_cli_plan_sphere);
    RUN(test_cli_sampler);
    RUN(test_cli_profile_input);
    RUN(test_cli_profile_bad_lines);
    RUN(test_cli_infeasible);
    RUN(test_cli_compare);
    RUN(test_cli_slice);
    RUN(test_cli_orient);
    RUN(test_cli_unwritable_output);
    RUN(test_cli_bad_model);
    remove_dir();
}
