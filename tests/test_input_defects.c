/* Input defects users found, each with the cases that show it fixed: a huge binary
   STL read whole before its count was checked; a profile's z column ignored;
   malformed OBJ vertex references taken; a negative PLY count called not a number;
   too-large numbers called not whole numbers; "1 layers"; a binary file's raw
   bytes in a message; help listing options a command does not take and no adaslice
   help COMMAND. Library cases load files; the tool runs as a child process
   (cli_run.h). */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* ftruncate, setenv */
#endif
#include "cli_run.h"
#include "../adaslice.h"
#include "meshgen.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ------------------------------------------------------------ helpers */

#define HUGE_SIZE 2147483648.0 /* 2 GiB */

/* cli_run with an argument list: up to 15 arguments, NULL-terminated */
static cli_result run_list(const char *const *a)
{
    const char *v[16] = {NULL};
    int n;
    for (n = 0; n < 15 && a[n]; n++) v[n] = a[n];
    return cli_run(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8], v[9], v[10], v[11], v[12], v[13], v[14],
                   (const char *)NULL);
}

/* `head` and then zeros to `size` bytes, which take no disk: a sparse file. */
static int write_sparse(const char *path, const void *head, size_t n, double size)
{
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644), ok;
    ok = fd >= 0 && write(fd, head, n) == (ssize_t)n && ftruncate(fd, (off_t)size) == 0;
    if (fd >= 0) close(fd);
    CHECKF(ok, "cannot make the sparse file %s: %s", path, strerror(errno));
    return ok;
}

/* An 84-byte binary STL header: `text` padded with NULs, then the count. */
static void stl_header(unsigned char h[84], const char *text, uint32_t count)
{
    int i;
    memset(h, 0, 84);
    memcpy(h, text, strlen(text));
    for (i = 0; i < 4; i++) h[80 + i] = (unsigned char)(count >> (8 * i));
}

/* An allocator that refuses any block over 1 MiB: a loader that would read a
   huge file into memory fails with ERR_NOMEM instead of taking seconds. */
static void *small_alloc(void *user, size_t size) { (void)user; return size > (1u << 20) ? NULL : malloc(size); }
static void small_free(void *user, void *p) { (void)user; free(p); }
static const adaslice_allocator small_blocks = {small_alloc, small_free, NULL};

static adaslice_result load_small(const char *path, adaslice_mesh *m, adaslice_error *e)
{
    adaslice_load_options o;
    memset(&o, 0, sizeof o);
    o.allocator = &small_blocks;
    return adaslice_mesh_load_file(path, &o, m, e);
}

static adaslice_result load_text(const char *text, adaslice_mesh *m, adaslice_error *e)
{
    return adaslice_mesh_load(text, strlen(text), NULL, m, e);
}

/* A tetrahedron 1 mm tall, as OBJ: no direction sees it flat. */
static const char *tetra_obj(void)
{
    const char *path = cli_path("tetra.obj");
    cli_write(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0.3 0.3 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
    return path;
}

/* ------------------------------------------------------------ 1: a huge binary STL */

/* A 2 GiB binary STL whose header counts 1000 triangles is refused from its
   first bytes and its size: never read, so the 1 MiB allocator is no
   obstacle. The header may be text, start with "solid" or be all zeros. */
static void huge_binary_stl_is_refused_before_it_is_read(void)
{
    static const char *const headers[] = {"adaslice sparse test", "solid part", ""};
    const char *path = cli_path("huge.stl");
    unsigned char h[84];
    adaslice_mesh m;
    adaslice_error e;
    char want[400];
    size_t i;
    snprintf(want, sizeof want, "%s: binary STL: header says 1000 triangles (50084 bytes) but the data is 2147483648 bytes",
             path);
    for (i = 0; i < sizeof headers / sizeof *headers; i++) {
        stl_header(h, headers[i], 1000);
        if (!write_sparse(path, h, sizeof h, HUGE_SIZE)) return;
        CHECKF(load_small(path, &m, &e) == ADASLICE_ERR_COUNT && e.offset == 80 && !strcmp(e.message, want),
               "header '%s': %s (%s)", headers[i], adaslice_result_name(e.result), e.message);
    }
    remove(path);
}

/* A PLY header that promises more vertices than 2 GiB can hold is refused the
   same way; and files whose first 4 KiB cannot tell their format (a long
   comment) or hold only part of the PLY header still load. */
static void huge_ply_is_refused_and_long_headers_still_load(void)
{
    static const char ply_head[] = "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\n"
                                   "property float x\nproperty float y\nproperty float z\nend_header\n";
    const char *path = cli_path("huge.ply"), *obj = cli_path("commented.obj"), *ply = cli_path("commented.ply");
    adaslice_mesh m;
    adaslice_error e;
    char want[300], comment[6000];
    FILE *f;
    int k;
    if (!write_sparse(path, ply_head, strlen(ply_head), HUGE_SIZE)) return;
    snprintf(want, sizeof want, "%s: PLY byte %zu: element 'vertex' has 1000000000 records of at least 12 bytes, but only "
             "%.0f bytes remain", path, strlen(ply_head), HUGE_SIZE - (double)strlen(ply_head));
    CHECKF(load_small(path, &m, &e) == ADASLICE_ERR_TRUNCATED && !strcmp(e.message, want), "%s", e.message);
    remove(path);

    memset(comment, 'c', sizeof comment - 1);
    comment[sizeof comment - 1] = 0;
    f = fopen(obj, "w");
    if (f) fprintf(f, "# %s\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", comment), fclose(f);
    CHECKF(load_small(obj, &m, &e) == ADASLICE_OK && m.triangle_count == 1, "%s", e.message);
    if (e.result == ADASLICE_OK) adaslice_mesh_free(&m);
    f = fopen(ply, "w");
    if (f) {
        fputs("ply\nformat ascii 1.0\n", f);
        for (k = 0; k < 100; k++) fprintf(f, "comment %.60s\n", comment);
        fputs("element vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\n"
              "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", f);
        fclose(f);
    }
    CHECKF(load_small(ply, &m, &e) == ADASLICE_OK && m.triangle_count == 1, "%s", e.message);
    if (e.result == ADASLICE_OK) adaslice_mesh_free(&m);
}

/* The tool refuses it too, in one line naming the file, the count and the
   size. Under AddressSanitizer the child may not allocate more than 256 MiB, so
   a tool that read the file first would say "out of memory" instead. */
static void huge_binary_stl_is_refused_by_the_tool(void)
{
    const char *path = cli_path("huge.stl"), *was = getenv("ASAN_OPTIONS");
    char options[512], *saved = was ? strdup(was) : NULL;
    unsigned char h[84];
    cli_result r;
    stl_header(h, "solid part", 1000);
    if (!write_sparse(path, h, sizeof h, HUGE_SIZE)) return;
    snprintf(options, sizeof options, "%s%smax_allocation_size_mb=256:allocator_may_return_null=1", was ? was : "",
             was && *was ? ":" : "");
    setenv("ASAN_OPTIONS", options, 1);
    r = cli_run("plan", path, NULL);
    if (saved) setenv("ASAN_OPTIONS", saved, 1);
    else unsetenv("ASAN_OPTIONS");
    free(saved);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, path) && strstr(r.err, "1000 triangles") &&
           strstr(r.err, "2147483648 bytes") && !*r.out, "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
    remove(path);
}

/* ------------------------------------------------------------ 2: a profile's z column */

/* A profile written with --bin 0.01 and read back without --bin plans the
   part at its height: the z column gives the bin (and z0); --bin that agrees is
   taken, one that does not is refused naming the file, the line and both; a
   column that is not evenly spaced is refused naming its line. */
static void profile_z_column_gives_the_bin(void)
{
    const char *model = tetra_obj(), *csv = cli_path("tetra_profile.csv"), *bad = cli_path("uneven.csv");
    cli_result r = cli_run("plan", model, "--bin", "0.01", "--tmin", "0.02", "--tmax", "0.05", "--profile-out", csv,
                           "--json", NULL);
    double layers = cli_json_number(r.out, "layers"), height = cli_json_number(r.out, "height_mm");
    char *text;
    CHECKF(r.status == 0 && cli_json_number(r.out, "bins") == 100, "exit %d: %s", r.status, r.err);
    cli_free(&r);

    r = cli_run("plan", "--profile", csv, "--tmin", "0.02", "--tmax", "0.05", "--json", NULL);
    CHECKF(r.status == 0 && cli_json_number(r.out, "bin") == 0.01 && cli_json_number(r.out, "layers") == layers &&
           fabs(cli_json_number(r.out, "height_mm") - height) < 0.01 + 1e-9,
           "exit %d: bin %g, %g layers (the model's %g), height %g (%g): %s", r.status, cli_json_number(r.out, "bin"),
           cli_json_number(r.out, "layers"), layers, cli_json_number(r.out, "height_mm"), height, r.err);
    cli_free(&r);
    r = cli_run("plan", "--profile", csv, "--bin", "0.01", "--tmin", "0.02", "--tmax", "0.05", "--json", NULL);
    CHECKF(r.status == 0 && cli_json_number(r.out, "layers") == layers, "exit %d: %s", r.status, r.err);
    cli_free(&r);
    r = cli_run("plan", "--profile", csv, "--bin", "0.002", NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "tetra_profile.csv:3:") && strstr(r.err, "0.01") &&
           strstr(r.err, "0.002") && !*r.out, "exit %d, '%s'", r.status, r.err);
    cli_free(&r);

    /* line 7 is missing: line 8 (now 7) is two bins above the one before */
    text = read_whole_text(csv);
    if (text) {
        char *line = text;
        int k;
        for (k = 1; k < 7 && line; k++) line = strchr(line, '\n') ? strchr(line, '\n') + 1 : NULL;
        if (line && strchr(line, '\n')) memmove(line, strchr(line, '\n') + 1, strlen(strchr(line, '\n') + 1) + 1);
        cli_write(bad, text);
        free(text);
    }
    r = cli_run("plan", "--profile", bad, NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "uneven.csv:7:") && strstr(r.err, "evenly"),
           "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
    cli_write(bad, "z,phi\n0.001,1\n0.003,1\n0.002,1\n");
    r = cli_run("plan", "--profile", bad, NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "uneven.csv:4:"), "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
    cli_write(bad, "z,phi\n0.001,1\n0.003,1\n0.5\n");
    r = cli_run("plan", "--profile", bad, NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "uneven.csv:4:"), "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
}

/* ------------------------------------------------------------ 3 and 4: OBJ references, PLY counts */

/* A texture or normal index that is not an integer, or a fourth part, is an
   error at the token, naming the line and the token; left-out indices are not. */
static void malformed_obj_references_are_refused(void)
{
    static const char *const bad[] = {"1/a/", "1/2/3/4", "1/2x", "1//x", "1/2/3x", "1/+/3"};
    static const char *const good[] = {"1//", "1/2/", "1//3", "1/2/3", "1/2", "-3/-1/-2"};
    const char *path = cli_path("bad_ref.obj");
    char text[200], want[200];
    adaslice_mesh m;
    adaslice_error e;
    cli_result r;
    size_t i;
    for (i = 0; i < sizeof bad / sizeof *bad; i++) {
        snprintf(text, sizeof text, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf %s 2 3\n", bad[i]);
        snprintf(want, sizeof want, "OBJ line 4: '%s' is not a vertex reference", bad[i]);
        CHECKF(load_text(text, &m, &e) == ADASLICE_ERR_NUMBER && e.line == 4 && e.offset == 26 &&
               !strncmp(e.message, want, strlen(want)), "%s: %s at %zu: %s", bad[i], adaslice_result_name(e.result),
               e.offset, e.message);
        if (e.result == ADASLICE_OK) adaslice_mesh_free(&m);
    }
    for (i = 0; i < sizeof good / sizeof *good; i++) {
        snprintf(text, sizeof text, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf %s 2 3\n", good[i]);
        CHECKF(load_text(text, &m, &e) == ADASLICE_OK && m.triangles[0] == 0, "%s: %s", good[i], e.message);
        if (e.result == ADASLICE_OK) adaslice_mesh_free(&m);
    }
    cli_write(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/a/ 2 3\n");
    r = cli_run("plan", path, NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, path) && strstr(r.err, "line 4") &&
           strstr(r.err, "'1/a/'"), "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
}

static void negative_ply_count_says_negative(void)
{
    adaslice_mesh m;
    adaslice_error e;
    CHECK(load_text("ply\nformat ascii 1.0\nelement vertex -3\nend_header\n", &m, &e) == ADASLICE_ERR_NUMBER);
    CHECKF(!strcmp(e.message, "PLY line 3: element 'vertex' count -3 is negative"), "%s", e.message);
    CHECK(load_text("ply\nformat ascii 1.0\nelement face x3\nend_header\n", &m, &e) == ADASLICE_ERR_NUMBER);
    CHECKF(!strcmp(e.message, "PLY line 3: element 'face' count 'x3' is not a number"), "%s", e.message);
}

/* ------------------------------------------------------------ 5: too-large numbers */

/* Every whole-number option: a number over its maximum says it is too large
   and gives the maximum; 0 says the least is 1; text is not a number. */
static void too_large_counts_say_the_most(void)
{
    static const struct { const char *command, *option, *most; } cases[] = {
        {"plan", "--budget", "4294967295"}, {"plan", "--res", "65536"},     {"slice", "--aa", "16"},
        {"slice", "--threads", "64"},       {"slice", "--bottom-layers", "4294967295"},
        {"orient", "--dirs", "1000000"},    {"print", "--baud", "4000000"}, {"print", "--resume-from", "4294967295"},
        {"print", "--exposure-left", "4294967295"},
    };
    static const struct { const char *value, *says; } values[] = {
        {"99999999999", "too large, the most is"}, {"99999999999999999999999", "too large, the most is"},
        {"0", "too small, the least is 1"},        {"12a", "not a whole number"},
    };
    size_t i, k;
    for (i = 0; i < sizeof cases / sizeof *cases; i++)
        for (k = 0; k < sizeof values / sizeof *values; k++) {
            cli_result r;
            if (!strcmp(values[k].value, "0") && !strcmp(cases[i].option, "--bottom-layers")) continue; /* 0 is none */
            r = cli_run(cases[i].command, "m.stl", cases[i].option, values[k].value, NULL);
            CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, cases[i].option) &&
                   strstr(r.err, values[k].value) && strstr(r.err, values[k].says) &&
                   (k > 1 || strstr(r.err, cases[i].most)),
                   "%s %s %s: exit %d, '%s'", cases[i].command, cases[i].option, values[k].value, r.status, r.err);
            cli_free(&r);
        }
}

/* ------------------------------------------------------------ 6: one of a thing */

/* "1 " followed by a plural noun ("1 layers"), not a unit (ms), anywhere in s;
   NULL if there is none. */
static const char *one_plural(const char *s)
{
    const char *p;
    for (p = s; (p = strstr(p, "1 ")) != NULL; p++) {
        const char *w = p + 2, *e = w;
        if (p > s && (isdigit((unsigned char)p[-1]) || p[-1] == '.' || p[-1] == '-')) continue;
        while (isalpha((unsigned char)*e)) e++;
        if (e - w >= 3 && e[-1] == 's' && strncmp(w, "ms", 2)) return p;
    }
    return NULL;
}

static void expect_singular(const char *what, const cli_result *r)
{
    const char *at = one_plural(r->out), *err = one_plural(r->err);
    CHECKF(!at && !err, "%s: '%.40s'", what, at ? at : err);
}

/* Runs where the tool counts one of something: a one-triangle model, a
   one-value profile, one direction, one layer, one bottom layer. */
static void counts_of_one_are_singular(void)
{
    const char *tri = cli_path("tri.obj"), *one = cli_path("one.txt"), *stl = cli_path("one.stl");
    unsigned char h[84];
    cli_result r;
    cli_write(tri, "v 0 0 0\nv 1 0 0\nv 0 0 0.1\nf 1 2 3\n");
    cli_write(one, "0.5\n");
    r = cli_run("plan", tri, "--budget", "1", "--compare", NULL);
    CHECKF(r.status == 0 && strstr(r.out, "1 triangle\n") && strstr(r.out, "fits 1 layer)") &&
           strstr(r.out, "budget of 1 layer:"), "exit %d: %s%s", r.status, r.out, r.err);
    expect_singular("plan a triangle", &r);
    cli_free(&r);
    r = cli_run("plan", "--profile", one, "--tmin", "0.002", "--tmax", "0.002", NULL);
    CHECKF(r.status == 0 && strstr(r.out, "1 value\n") && strstr(r.out, "1 bin of") && strstr(r.out, "1 .. 1 bin per"),
           "exit %d: %s%s", r.status, r.out, r.err);
    expect_singular("plan a value", &r);
    cli_free(&r);
    r = cli_run("orient", tetra_obj(), "--dirs", "1", NULL);
    CHECKF(r.status == 0 && strstr(r.out, "1 direction and"), "exit %d: %s%s", r.status, r.out, r.err);
    expect_singular("orient 1 direction", &r);
    cli_free(&r);
    r = cli_run("saliency", tri, "-o", cli_path("tri_w.txt"), NULL);
    CHECKF(r.status == 0 && strstr(r.out, "1 triangle\n") && strstr(r.out, "1 face above"), "exit %d: %s%s", r.status,
           r.out, r.err);
    expect_singular("saliency of a triangle", &r);
    cli_free(&r);
    /* a closed part one layer tall: a lone triangle lights no pixel, and a
       job that lights none is refused */
    cli_write(cli_path("flat.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0.3 0.3 0.1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
    r = cli_run("slice", cli_path("flat.obj"), "-o", cli_path("flat_job"), "--pixels", "64x64", "--pitch", "0.05",
                "--bottom-layers", "1", "--uniform", "0.1", NULL);
    CHECKF(r.status == 0 && strstr(r.out, "1 layer of") && strstr(r.out, "1 bottom layer of"), "exit %d: %s%s", r.status,
           r.out, r.err);
    expect_singular("slice one layer", &r);
    cli_free(&r);
    stl_header(h, "", 1);
    cli_write_bytes(stl, h, sizeof h);
    r = cli_run("plan", stl, NULL);
    CHECKF(r.status == 1 && strstr(r.err, "header says 1 triangle (134 bytes)"), "exit %d: %s", r.status, r.err);
    cli_free(&r);
}

/* ------------------------------------------------------------ 7: binary file content in messages */

/* A message quotes a binary file's line escaped (\xNN) and cut short: one
   printable line, whatever the file holds. */
static int printable_line(const char *s)
{
    size_t n = strlen(s), i;
    for (i = 0; i + 1 < n; i++)
        if ((unsigned char)s[i] < 32 || (unsigned char)s[i] > 126) return 0;
    return n && n < 400 && s[n - 1] == '\n';
}

static void binary_file_content_is_escaped(void)
{
    const char *profile = cli_path("binary_profile.csv"), *weights = cli_path("binary_weights.txt");
    unsigned char junk[300];
    cli_result r;
    size_t i;
    junk[0] = '0'; junk[1] = '.'; junk[2] = '1'; junk[3] = '\n'; /* one good value, then bytes */
    for (i = 4; i < sizeof junk - 1; i++) junk[i] = (unsigned char)(i == 4 ? 0x89 : i == 5 ? 0x01 : 'A' + i % 50);
    junk[sizeof junk - 1] = '\n';
    cli_write_bytes(profile, junk, sizeof junk);
    cli_write_bytes(weights, junk, sizeof junk);
    r = cli_run("plan", "--profile", profile, NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && printable_line(r.err) && strstr(r.err, "binary_profile.csv:2:") &&
           strstr(r.err, "'\\x89\\x01") && strstr(r.err, "...'"), "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
    r = cli_run("plan", tetra_obj(), "--weights", weights, NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && printable_line(r.err) && strstr(r.err, "binary_weights.txt:2:") &&
           strstr(r.err, "\\x89\\x01"), "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
}

/* ------------------------------------------------------------ 8 and 9: help */

/* A value each option takes in the tests below (and what it needs besides),
   by "--option PLACEHOLDER" as help writes it, else by the option alone. */
static const struct { const char *option, *value; } OPTION_VALUES[] = {
    {"-o", "@out"}, {"--output", "@out"}, {"--3mf", "@x.3mf"}, {"--aa", "2"}, {"--alpha", "0.5"}, {"--baud", "115200"}, {"--bin", "0.002"},
    {"--bottom-exposure", "25"}, {"--bottom-layers", "3"}, {"--budget", "100"}, {"--dirs", "10"},
    {"--exposure-left", "500 --resume-from 2"},
    {"--display", "68x120 --pixels 1440x2560"}, {"--eps", "0.065"}, {"--exposure S@T", "2.5@0.05"},
    {"--exposure S1@T1,S2@T2", "2@0.05,6@0.15"}, {"--format", "dir"}, {"--give-up", "30"}, {"--map", "@map.svg"},
    {"--mapping", "exp --method curvature"}, {"--memory", "4000"}, {"--method", "greedy"}, {"--metric", "area"}, {"--mirror", "x"},
    {"--nozzle", "0.4"}, {"--orient", "0,0,1"}, {"--out", "@plan.csv"}, {"--peel", "5"}, {"--peel-speed", "2"},
    {"--penetration", "0.098"}, {"--pitch", "0.05 --pixels 1440x2560"}, {"--pixels", "1440x2560 --pitch 0.05"},
    {"--place", "0,0"}, {"--plot", "@plot.svg"}, {"--ply", "@c.ply"}, {"--port", "/nonexistent/port"},
    {"--printer", "elegoo-saturn"}, {"--profile", "@no-such-profile.csv"}, {"--profile-out", "@profile.csv"},
    {"--report", "@report.json"}, {"--res", "1024 --sampler ldi"}, {"--resume-from", "2"}, {"--return-speed", "4"},
    {"--rotate", "90"}, {"--sampler", "ldi"}, {"--scale", "2"}, {"--settle", "0.5"}, {"--sharp", "0.5"},
    {"--slice-at", "top"}, {"--threads", "2"}, {"--tmax", "0.15"}, {"--tmin", "0.05"}, {"--uniform", "0.05"},
    {"--weight", "box:0,0,0,1,1,1=0.5"}, {"--weights", "@w.txt"}, {"--importance", "0.5,0.3,0.2"}, {"--view", "front"}, {"--png", "@p.png"}, {"--view-count", "8"}, {"--view-res", "64"},
    {"--screen", "file:fb.bin,240x200,24"}, {"--screen-packing", "rgb"}, {"--screen-rotate", "90"}, {"--screen-mirror", "x"},
    {"--screen-pitch", "50"}, {"--screen-panel", "2k-5.5"},
    {"--project", "@x.3mf"}, {"--resolution", "0.2"}, {"--max-rise", "0.05"}, {"--max-angle", "15"},
    /* "COMMAND --option": what it needs there (plan's contour limits set up --hybrid, which needs --3mf, as
       --nozzle does) */
    {"plan --hybrid", "--3mf @x.3mf"}, {"plan --max-angle", "15 --hybrid --3mf @x.3mf"},
    {"plan --reach", "2 --hybrid --3mf @x.3mf"}, {"plan --max-rise", "0.05 --hybrid --3mf @x.3mf"},
    {"plan --resolution", "0.2 --hybrid --3mf @x.3mf"}, {"--svg-path", "1 @path.svg"},
    {"plan --nozzle", "0.4 --3mf @x.3mf"}, /* the 3MF's printer's */
    /* contour's top skins take the nozzle's two figures together */
    {"contour --top-skins", "--nozzle-clearance 1 --clearance-angle 30"},
    {"contour --nozzle-clearance", "1 --top-skins --clearance-angle 30"},
    {"contour --clearance-angle", "30 --top-skins --nozzle-clearance 1"},
};

static const char *option_value(const char *command, const char *option, const char *placeholder)
{
    char key[80];
    size_t i;
    snprintf(key, sizeof key, "%s %s", command, option);
    for (i = 0; i < sizeof OPTION_VALUES / sizeof *OPTION_VALUES; i++)
        if (!strcmp(OPTION_VALUES[i].option, key)) return OPTION_VALUES[i].value;
    snprintf(key, sizeof key, "%s %s", option, placeholder);
    for (i = 0; i < sizeof OPTION_VALUES / sizeof *OPTION_VALUES; i++)
        if (!strcmp(OPTION_VALUES[i].option, key)) return OPTION_VALUES[i].value;
    for (i = 0; i < sizeof OPTION_VALUES / sizeof *OPTION_VALUES; i++)
        if (!strcmp(OPTION_VALUES[i].option, option)) return OPTION_VALUES[i].value;
    return NULL;
}

/* `command` on a model that does not exist, with the arguments it needs, and
   `option` with `value` ("@name": a file in the test directory; words after a
   space: what the option needs besides): every argument is accepted, so the
   run gets as far as the missing model (or port) and fails with exit 1. */
static void expect_accepted(const char *command, const char *option, const char *value)
{
    static char words[4][200];
    const char *args[16];
    char spec[200], *save = NULL, *w;
    int n = 0, k = 0;
    cli_result r;
    args[n++] = command;
    /* --profile replaces the model; print --abort takes none */
    if (strcmp(option, "--profile") && strcmp(option, "--abort")) args[n++] = cli_path("no-such-model.stl");
    if (!strcmp(command, "slice")) { args[n++] = "-o"; args[n++] = cli_path("job"); }
    if (!strcmp(command, "saliency")) { args[n++] = "-o"; args[n++] = cli_path("saliency_out.txt"); } /* not --weights @w.txt */
    if (!strcmp(command, "print")) { args[n++] = "--port"; args[n++] = "/nonexistent/port"; }
    if (!strcmp(command, "contour")) { args[n++] = "--project"; args[n++] = cli_path("x.3mf"); args[n++] = "-o"; args[n++] = cli_path("c.gcode"); }
    args[n++] = option;
    snprintf(spec, sizeof spec, "%s", value ? value : "");
    for (w = strtok_r(spec, " ", &save); w && k < 4; w = strtok_r(NULL, " ", &save), k++) {
        snprintf(words[k], sizeof words[k], "%s", w[0] == '@' ? cli_path(w + 1) : w);
        args[n++] = words[k];
    }
    args[n] = NULL;
    r = run_list(args);
    CHECKF(r.status == 1 && cli_one_message(r.err) && (strstr(r.err, "no-such") || strstr(r.err, "/nonexistent/port")),
           "%s %s %s: exit %d, '%s'", command, option, value ? value : "", r.status, r.err);
    cli_free(&r);
}

/* One option of a help line: by name and placeholder, or (in a list) by name. */
static int check_listed(const char *command, const char *option, const char *placeholder, int takes_value)
{
    const char *v = option_value(command, option, placeholder);
    CHECKF(!takes_value || v, "%s --help lists %s %s: give it a value in OPTION_VALUES", command, option, placeholder);
    CHECKF(strcmp(command, "saliency") || strcmp(option, "--saliency"), "saliency --help lists --saliency");
    if (!takes_value || v) expect_accepted(command, option, v);
    return 1;
}

/* Each option a command's help lists (a line's first column: "--bin MM",
   "--json", "--mirror, --rotate, ...", "-o, --out FILE") is accepted by that command, and
   adaslice saliency does not offer --saliency, which it always does. */
static void every_option_in_help_is_accepted(void)
{
    static const char *const commands[] = {"plan", "slice", "orient", "saliency", "print", "contour"};
    size_t c;
    for (c = 0; c < sizeof commands / sizeof *commands; c++) {
        cli_result h = cli_run(commands[c], "--help", NULL);
        char *line, *save = NULL;
        int listed = 0;
        CHECKF(h.status == 0 && !*h.err, "%s --help: exit %d", commands[c], h.status);
        for (line = strtok_r(h.out, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
            char column[200], option[64], placeholder[64] = "", *item, *next;
            const char *gap;
            if (strncmp(line, "  -", 3)) continue;
            gap = strstr(line + 2, "  ");
            snprintf(column, sizeof column, "%.*s", gap ? (int)(gap - line - 2) : (int)strlen(line + 2), line + 2);
            if (strstr(column, ", -")) { /* several options ("-o, --out FILE": names of one) */
                for (item = column; item; item = next) {
                    next = strstr(item, ", ");
                    if (next) *next = 0, next += 2;
                    placeholder[0] = 0;
                    sscanf(item, "%63s %63s", option, placeholder);
                    listed += check_listed(commands[c], option, placeholder, 1);
                }
                continue;
            }
            /* "--option PLACEHOLDER description" or "--option description" */
            sscanf(column, "%63s %63s", option, placeholder);
            listed += check_listed(commands[c], option, placeholder, isupper((unsigned char)placeholder[0]) != 0);
        }
        CHECKF(listed >= 5, "%s --help lists %d options", commands[c], listed);
        cli_free(&h);
    }
}

/* adaslice help is adaslice --help, and adaslice help COMMAND is adaslice
   COMMAND --help; an unknown COMMAND or a second one is a usage error. */
static void help_command_shows_help(void)
{
    static const char *const commands[] = {"plan", "slice", "orient", "saliency", "print", "contour"};
    cli_result a = cli_run("help", NULL), b = cli_run("--help", NULL);
    size_t i;
    CHECKF(a.status == 0 && !*a.err && !strcmp(a.out, b.out) && strstr(a.out, "help"), "exit %d: %s", a.status, a.err);
    cli_free(&a);
    cli_free(&b);
    for (i = 0; i < sizeof commands / sizeof *commands; i++) {
        a = cli_run("help", commands[i], NULL);
        b = cli_run(commands[i], "--help", NULL);
        CHECKF(a.status == 0 && !*a.err && !strcmp(a.out, b.out) && strstr(a.out, commands[i]), "help %s: exit %d: %s",
               commands[i], a.status, a.err);
        cli_free(&a);
        cli_free(&b);
    }
    a = cli_run("help", "frobnicate", NULL);
    CHECKF(a.status == 2 && cli_one_message(a.err) && strstr(a.err, "frobnicate") && !*a.out, "exit %d: %s", a.status, a.err);
    cli_free(&a);
    a = cli_run("help", "plan", "slice", NULL);
    CHECKF(a.status == 2 && cli_one_message(a.err) && strstr(a.err, "slice") && !*a.out, "exit %d: %s", a.status, a.err);
    cli_free(&a);
}

/* ------------------------------------------------------------ 3: memory and work before the work */

/* An allocator that keeps the most bytes held at once. */
typedef struct held { size_t now, most; } held;
static void *held_alloc(void *user, size_t size)
{
    held *h = (held *)user;
    size_t *p = (size_t *)malloc(size + sizeof(size_t) * 2);
    if (!p) return NULL;
    p[0] = size;
    h->now += size;
    if (h->now > h->most) h->most = h->now;
    return p + 2;
}
static void held_free(void *user, void *q)
{
    size_t *p = q ? (size_t *)q - 2 : NULL;
    if (!p) return;
    ((held *)user)->now -= p[0];
    free(p);
}

/* adaslice_profile_estimate is an upper bound of what each profile holds at
   once (as an allocator counts it), and not a loose one: within 4x. */
static void profile_estimates_bound_what_profiles_hold(void)
{
    adaslice_mesh m = gen_sphere(10, 48, 24, 0), tall = gen_box(0, 0, 0, 3, 3, 200);
    const adaslice_mesh *meshes[2];
    int k, metric, sampled;
    meshes[0] = &m;
    meshes[1] = &tall;
    for (k = 0; k < 2; k++)
        for (metric = ADASLICE_METRIC_CUSP; metric <= ADASLICE_METRIC_VOLUME; metric++)
            for (sampled = 0; sampled < 2; sampled++) {
                held h = {0, 0};
                adaslice_allocator al = {held_alloc, held_free, &h};
                adaslice_profile_options o;
                adaslice_profile_cost c;
                adaslice_profile p;
                adaslice_error e;
                memset(&o, 0, sizeof o);
                o.metric = (adaslice_metric)metric;
                o.resolution = 256;
                o.allocator = &al;
                CHECKF(adaslice_profile_estimate(meshes[k], &o, sampled, &c, &e) == ADASLICE_OK, "%s", e.message);
                CHECKF((sampled ? adaslice_profile_sampled(meshes[k], &o, &p, &e)
                                : adaslice_profile_exact(meshes[k], &o, &p, &e)) == ADASLICE_OK, "%s", e.message);
                CHECKF((double)h.most <= c.bytes && c.bytes <= 4.0 * (double)h.most,
                       "mesh %d, metric %d, sampled %d: held %zu bytes, estimated %.0f", k, metric, sampled, h.most,
                       c.bytes);
                adaslice_profile_free(&p);
            }
    gen_free(&m);
    gen_free(&tall);
}

/* A box whose T-junction a sliver seals, with one more facet of a repeated
   corner: plan --json counts each once, in its repair object (the loader no
   longer drops and counts apart), and the box stays closed; the warning says
   the same in one line. */
static void zero_area_facets_are_counted_once(void)
{
    const char *path = cli_path("tjunction.obj");
    adaslice_mesh m = gen_tjunction_box(1);
    cli_result r;
    m.triangles = (uint32_t *)realloc(m.triangles, (m.triangle_count + 1) * 3 * sizeof(uint32_t));
    if (!m.triangles) abort();
    gen_triangle(&m, 0, 0, 1);
    cli_write_obj(path, &m);
    gen_free(&m);
    r = cli_run("plan", path, "--json", NULL);
    CHECKF(r.status == 0 && cli_count(r.out, "degenerate_dropped") == 1 &&
           cli_json_number(r.out, "degenerate_dropped") == 1 && cli_json_number(r.out, "slivers_collapsed") == 1 &&
           cli_json_number(r.out, "open_edges") == 0 && cli_json_number(r.out, "closed_shells") == 1,
           "exit %d, '%s'", r.status, r.out);
    CHECKF(cli_one_message(r.err) && strstr(r.err, "1 facet of zero area sealing a T-junction collapsed") &&
           strstr(r.err, "1 facet of zero area dropped") && !strstr(r.err, "open edge"), "'%s'", r.err);
    cli_free(&r);
}

/* What a profile tells its progress: shares in [0, 1] that never go back,
   the last 1, for both samplers and an area metric's stored LDI. */
typedef struct told { int calls, backwards; double last; } told;
static void tell(void *user, double done)
{
    told *t = (told *)user;
    if (done < t->last || done < 0 || done > 1) t->backwards++;
    t->last = done;
    t->calls++;
}

static void profiles_tell_their_progress(void)
{
    adaslice_mesh m = gen_sphere(10, 96, 48, 0);
    int sampled, metric;
    for (sampled = 0; sampled < 2; sampled++)
        for (metric = ADASLICE_METRIC_CUSP; metric <= ADASLICE_METRIC_AREA; metric += 2) {
            told t = {0, 0, 0};
            adaslice_profile_options o;
            adaslice_profile p;
            adaslice_error e;
            memset(&o, 0, sizeof o);
            o.metric = (adaslice_metric)metric;
            o.resolution = 256;
            o.progress = tell;
            o.progress_user = &t;
            CHECKF((sampled ? adaslice_profile_sampled(&m, &o, &p, &e) : adaslice_profile_exact(&m, &o, &p, &e)) ==
                   ADASLICE_OK, "%s", e.message);
            CHECKF(t.calls >= 2 && !t.backwards && t.last == 1, "sampled %d, metric %d: %d calls, %d backwards, last %g",
                   sampled, metric, t.calls, t.backwards, t.last);
            adaslice_profile_free(&p);
        }
    gen_free(&m);
}

/* A part in micrometres (100 m tall read as mm) is refused before its
   profile is made, naming the memory it would need, --memory and the units. */
static void a_part_in_micrometres_is_refused_before_profiling(void)
{
    const char *path = cli_path("tall.obj");
    static const char *const samplers[] = {"exact", "ldi"};
    int i;
    cli_write(path, "v 0 0 0\nv 20000 0 0\nv 0 20000 0\nv 0 0 100000\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
    for (i = 0; i < 2; i++) {
        cli_result r = cli_run("plan", path, "--sampler", samplers[i], "--memory", "300", NULL);
        CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, path) && strstr(r.err, "--memory 300 MB") &&
               strstr(r.err, "50000000 bins") && strstr(r.err, "--scale 0.001") && !*r.out,
               "%s: exit %d, '%s'", samplers[i], r.status, r.err);
        cli_free(&r);
    }
    /* the orientation search holds a profile a thread: the same part asked
       14 GB a thread and was killed; refused before any work, with --memory
       and without it (ten times taller: 240 GB, over half of any machine) */
    {
        static const char *const searches[][6] = {{"orient", "--dirs", "10", "--memory", "300", "300 MB"},
                                                  {"orient", "--dirs", "10", "--scale", "10", "more than --memory"},
                                                  {"plan", "--orient", "best", "--scale", "10", "more than --memory"}};
        for (i = 0; i < 3; i++) {
            cli_result r = cli_run(searches[i][0], path, searches[i][1], searches[i][2], searches[i][3], searches[i][4], NULL);
            CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "the search needs up to") &&
                       strstr(r.err, searches[i][5]) && strstr(r.err, "--scale 0.001") && !*r.out,
                   "%s %s: exit %d, '%s'", searches[i][0], searches[i][4], r.status, r.err);
            cli_free(&r);
        }
    }
}

/* One OBJ face of 5,000 references round a pyramid: its fan is facets
   lying a thousand deep, which rays along x, y and z would meet 1e10 times
   (tens of seconds, minutes at 50,000); the LDI sampler refuses it, naming
   the exact sampler and --res, and the exact one profiles it. */
static void an_ldi_of_facets_thousands_deep_is_refused(void)
{
    const char *path = cli_path("fan.obj");
    char *obj = (char *)malloc(100 + 2 * 5000), *last;
    size_t n = 0;
    int i;
    cli_result r;
    if (!obj) abort();
    n += (size_t)sprintf(obj, "v 0 0 0\nv 10 0 0\nv 10 10 0\nv 0 10 0\nv 5 5 10\nf 1");
    for (i = 1; i < 5000; i++) n += (size_t)sprintf(obj + n, " %d", 2 + i % 4);
    sprintf(obj + n, "\n");
    cli_write(path, obj);
    free(obj);
    r = cli_run("plan", path, "--sampler", "ldi", NULL);
    last = strrchr(r.err, '\n');
    while (last && last > r.err && last[-1] != '\n') last--;
    CHECKF(r.status == 1 && last && strstr(last, path) && strstr(last, "samples") && strstr(last, "--sampler exact") &&
           strstr(last, "--res") && !*r.out, "exit %d, '%s'", r.status, r.err);
    cli_free(&r);
    r = cli_run("plan", path, NULL);
    CHECKF(r.status == 0, "exact: exit %d, '%s'", r.status, r.err);
    cli_free(&r);
}

void test_input_defects(void)
{
    if (!cli_begin("adaslice-input")) return;
    RUN(huge_binary_stl_is_refused_before_it_is_read);
    RUN(huge_ply_is_refused_and_long_headers_still_load);
    RUN(huge_binary_stl_is_refused_by_the_tool);
    RUN(profile_z_column_gives_the_bin);
    RUN(malformed_obj_references_are_refused);
    RUN(negative_ply_count_says_negative);
    RUN(too_large_counts_say_the_most);
    RUN(counts_of_one_are_singular);
    RUN(binary_file_content_is_escaped);
    RUN(every_option_in_help_is_accepted);
    RUN(help_command_shows_help);
    RUN(profile_estimates_bound_what_profiles_hold);
    RUN(zero_area_facets_are_counted_once);
    RUN(profiles_tell_their_progress);
    RUN(a_part_in_micrometres_is_refused_before_profiling);
    RUN(an_ldi_of_facets_thousands_deep_is_refused);
    cli_end();
}
