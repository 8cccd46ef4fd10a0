/* What the tool's figures and reports tell a reader, end to end (the tool
   runs as a child process, as in test_cli.c): the layer SVGs agree with the
   manifest, the orient map tiles and has its colour bar, plan --compare
   gives the saving against uniform layers. format_duration is the tool's. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "cli_run.h"
#include "../adaslice.h"
#include "meshgen.h"
#include "../host/report.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A 10 mm sphere standing 20 mm above the model's origin, so that heights
   above the part's bottom and the model's z differ. */
static const char *raised_sphere(void)
{
    const char *path = cli_path("raised_sphere.obj");
    if (!cli_exists(path)) {
        adaslice_mesh m = gen_sphere(5, 48, 24, 20);
        cli_write_obj(path, &m);
        gen_free(&m);
    }
    return path;
}

/* The number in an XML attribute name="..." after p, or NAN. */
static double attribute(const char *p, const char *name)
{
    char pat[64];
    snprintf(pat, sizeof pat, " %s=\"", name);
    p = p ? strstr(p, pat) : NULL;
    return p ? strtod(p + strlen(pat), NULL) : NAN;
}

/* Every layer's SVG names the layer and gives, in its caption and its data,
   the heights above the part's bottom and the thickness the manifest gives
   that layer; a legend and a scale bar are there. */
static void layer_svgs_agree_with_the_manifest(void)
{
    char job[600], path[800], *manifest;
    cli_result r;
    size_t layers, k;
    snprintf(job, sizeof job, "%s/svgjob", cli_dir);
    r = cli_run("slice", raised_sphere(), "-o", job, "--pixels", "400x400", "--pitch", "0.05", "--svg", NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    cli_free(&r);
    snprintf(path, sizeof path, "%s/manifest.json", job);
    manifest = read_whole_text(path);
    CHECK(manifest != NULL);
    if (!manifest) return;
    layers = (size_t)cli_json_number(manifest, "layer_count");
    CHECKF(layers > 50, "%zu layers", layers);
    for (k = 1; k <= layers; k++) {
        char index[32], title[64], *svg;
        const char *entry, *caption, *g;
        double z0, z1, t, shown[2] = {NAN, NAN};
        snprintf(index, sizeof index, "{\"index\": %zu,", k);
        entry = strstr(manifest, index);
        CHECKF(entry != NULL, "the manifest has no layer %zu", k);
        if (!entry) break;
        z0 = cli_json_number(entry, "z_bottom");
        z1 = cli_json_number(entry, "z_top");
        t = cli_json_number(entry, "thickness");
        snprintf(path, sizeof path, "%s/layer_%05zu.svg", job, k);
        svg = read_whole_text(path);
        CHECKF(svg != NULL, "no layer_%05zu.svg", k);
        if (!svg) continue;
        snprintf(title, sizeof title, "layer %zu of %zu", k, layers);
        CHECKF(strstr(svg, "<title>") && strstr(strstr(svg, "<title>"), title), "layer %zu: no <title> naming it", k);
        caption = strstr(svg, "</title>");
        caption = caption ? strstr(caption, " mm above the part's bottom") : NULL;
        while (caption && caption > svg && caption[-1] != '>') caption--; /* the start of the caption's text */
        CHECKF(caption && sscanf(caption, "%lf to %lf", &shown[0], &shown[1]) == 2 &&
                   fabs(shown[0] - z0) < 1e-6 && fabs(shown[1] - z1) < 1e-6,
               "layer %zu: the caption says %g to %g mm, the manifest %.9g to %.9g", k, shown[0], shown[1], z0, z1);
        CHECKF(strstr(svg, "mm thick"), "layer %zu: no thickness in the caption", k);
        g = strstr(svg, "<g id=\"layer-");
        CHECKF(g && fabs(attribute(g, "data-z-bottom") - z0) < 1e-9 && fabs(attribute(g, "data-z-top") - z1) < 1e-9 &&
                   fabs(attribute(g, "data-thickness") - t) < 1e-9 && attribute(g, "data-layer") == (double)k,
               "layer %zu: data-z-bottom %g, data-z-top %g, data-thickness %g; the manifest %.9g, %.9g, %.9g", k,
               attribute(g, "data-z-bottom"), attribute(g, "data-z-top"), attribute(g, "data-thickness"), z0, z1, t);
        CHECKF(g && attribute(g, "data-cut") >= z0 && attribute(g, "data-cut") <= z1, "layer %zu: cut at %g", k,
               attribute(g, "data-cut"));
        CHECKF(strstr(svg, "inside the part") && strstr(svg, " mm</text>"), "layer %zu: no legend or scale bar", k);
        free(svg);
    }
    free(manifest);
    cli_remove_all(job);
}

/* The rectangles of the group that starts at g (up to its first "</g>"):
   x, y, width, height each; returns how many, at most max. */
static size_t group_rects(const char *g, double (*rect)[4], size_t max)
{
    const char *end = g ? strstr(g, "</g>") : NULL, *p = g;
    size_t n = 0;
    while (end && n < max && (p = strstr(p, "<rect ")) != NULL && p < end) {
        rect[n][0] = attribute(p, "x");
        rect[n][1] = attribute(p, "y");
        rect[n][2] = attribute(p, "width");
        rect[n][3] = attribute(p, "height");
        n++;
        p++;
    }
    return n;
}

static int by_row_then_column(const void *a, const void *b)
{
    const double *r = (const double *)a, *s = (const double *)b;
    return r[1] != s[1] ? (r[1] > s[1]) - (r[1] < s[1]) : (r[0] > s[0]) - (r[0] < s[0]);
}

/* The orient map's cells tile its rectangle exactly, row after row (each
   cell starts where its left neighbour ends, each row where the one above
   ends), with crispEdges so that no renderer anti-aliases the shared edges
   into white seams; a colour bar gives the lowest F (the best direction's)
   and the highest, as data and as text. */
static void orient_map_tiles_and_has_a_colour_bar(void)
{
    enum { MAX_RECTS = 20000 };
    const char *box = cli_path("map_box.obj"), *map = cli_path("map.svg");
    adaslice_mesh m = gen_box(0, 0, 0, 10, 20, 40);
    double (*rect)[4] = (double (*)[4])malloc(MAX_RECTS * sizeof *rect), left, right, row_top, row_bottom, best, lo, hi;
    char *svg = NULL, label[32];
    const char *cells, *crisp, *bar;
    cli_result r;
    size_t n, k, rows = 0;
    cli_write_obj(box, &m);
    gen_free(&m);
    r = cli_run("orient", box, "--dirs", "300", "--json", "--map", map, NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    best = cli_json_number(r.out, "F");
    svg = read_whole_text(map);
    cli_free(&r);
    CHECK(rect && svg);
    if (!rect || !svg) goto done;
    CHECK(strstr(svg, "viewBox=\"") != NULL);

    cells = strstr(svg, "<g id=\"cells\"");
    crisp = cells ? strstr(cells, "shape-rendering=\"crispEdges\"") : NULL;
    CHECKF(crisp && crisp < strchr(cells, '>'), "the cells' group is not crispEdges");
    n = group_rects(cells, rect, MAX_RECTS);
    CHECKF(n > 0 && n < MAX_RECTS, "%zu cells", n);
    if (!n || n == MAX_RECTS) goto done;
    qsort(rect, n, sizeof *rect, by_row_then_column);
    left = rect[0][0];
    row_top = row_bottom = rect[0][1];
    for (k = 0; k + 1 < n && rect[k + 1][1] == rect[0][1]; k++) {}
    right = rect[k][0] + rect[k][2]; /* where the first row ends, every row must */
    for (k = 0; k < n; k++) {
        const double *c = rect[k], *before = k ? rect[k - 1] : NULL;
        CHECKF(c[2] > 0 && c[3] > 0, "a cell of %g x %g", c[2], c[3]);
        if (!before || c[1] != before[1]) {
            /* a row begins at the left edge, right below the row above, which
               ended at the right edge */
            CHECKF(!before || before[0] + before[2] == right, "the row at y %g ends at %g, not %g", before[1],
                   before[0] + before[2], right);
            CHECKF(c[0] == left && c[1] == row_bottom, "a row starts at (%g, %g), not (%g, %g)", c[0], c[1], left, row_bottom);
            row_top = c[1];
            row_bottom = c[1] + c[3];
            rows++;
        } else {
            CHECKF(c[0] == before[0] + before[2], "row at y %g: a cell at x %g, its neighbour ends at %g", c[1], c[0],
                   before[0] + before[2]);
            CHECKF(c[1] + c[3] == row_bottom, "row at y %g: a cell ends at %g, the row at %g", row_top, c[1] + c[3],
                   row_bottom);
        }
    }
    CHECKF(rect[n - 1][0] + rect[n - 1][2] == right, "the last row ends at %g, not %g", rect[n - 1][0] + rect[n - 1][2], right);
    CHECKF(rows > 10 && right > left, "%zu rows from x %g to %g", rows, left, right);

    bar = strstr(svg, "<g id=\"colour-bar\"");
    lo = attribute(bar, "data-min");
    hi = attribute(bar, "data-max");
    CHECKF(bar && fabs(lo - best) < 1e-8 && hi > lo && hi <= 1 + 1e-12, "colour bar from %g to %g; the best F is %g", lo, hi,
           best);
    if (!bar) goto done;
    snprintf(label, sizeof label, ">%.4g</text>", lo);
    CHECKF(strstr(bar, label) != NULL, "the colour bar has no label %s", label);
    snprintf(label, sizeof label, ">%.4g</text>", hi);
    CHECKF(strstr(bar, label) != NULL, "the colour bar has no label %s", label);
    CHECKF(group_rects(strstr(bar + 1, "<g"), rect, MAX_RECTS) >= 10, "the colour bar has no steps");
done:
    free(rect);
    free(svg);
}

/* plan --compare gives the thickest uniform layers no worse than the optimal
   plan, both layer counts and print times and the saving, and the numbers
   hold: --uniform plans the same layers; their worst error is within the
   optimal plan's (so within eps) and a bin thicker it would not be; they are
   no fewer; the saving is 1 - the ratio of the times; the text says what the
   JSON does; and the optimal plan's time is the one slice gives its job. */
static void compare_gives_the_saving_against_uniform_layers(void)
{
    char arg[64], line[160], when[32], instead[32], job[600], path[700], *manifest;
    const char *u, *o;
    double eps, bin, tmax, worst, t, wu, tu, to, pct, nu, no;
    cli_result r = cli_run("plan", raised_sphere(), "--compare", "--json", NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    eps = cli_json_number(r.out, "eps");
    bin = cli_json_number(r.out, "bin");
    tmax = cli_json_number(r.out, "tmax");
    o = strstr(r.out, "{\"method\": \"optimal\"");
    u = strstr(r.out, "\"uniform_no_worse\": {");
    CHECKF(o && u, "no optimal row or uniform plan: %.400s", r.out);
    if (!o || !u) { cli_free(&r); return; }
    worst = cli_json_number(o, "worst_error");
    t = cli_json_number(u, "thickness");
    nu = cli_json_number(u, "uniform_layers");
    wu = cli_json_number(u, "uniform_worst_error");
    tu = cli_json_number(u, "uniform_print_time_s");
    no = cli_json_number(u, "optimal_layers");
    to = cli_json_number(u, "optimal_print_time_s");
    pct = cli_json_number(u, "print_time_saved_percent");
    CHECKF(no == cli_json_number(r.out, "layers") && no == cli_json_number(o, "layers") &&
               to == cli_json_number(o, "print_time_s"), "the optimal plan: %g layers, %g s", no, to);
    CHECKF(wu <= worst && worst <= eps, "uniform worst error %g, optimal %g, eps %g", wu, worst, eps);
    CHECKF(nu >= no && nu > 0, "uniform %g layers, optimal %g", nu, no);
    CHECKF(to > 0 && tu >= to && fabs(pct - 100 * (1 - to / tu)) < 1e-9, "%g s against %g s: %g %% saved", to, tu, pct);
    CHECKF(nu > no && pct > 0, "a sphere gains nothing: %g layers against %g", no, nu);
    cli_free(&r);

    /* the same layers from --uniform, and one bin thicker is worse than optimal */
    snprintf(arg, sizeof arg, "%.9g", t);
    r = cli_run("plan", raised_sphere(), "--uniform", arg, "--json", NULL);
    CHECKF(r.status == 0 && cli_json_number(r.out, "layers") == nu && fabs(cli_json_number(r.out, "worst_error") - wu) < 1e-12,
           "--uniform %s: %g layers, worst %g; --compare said %g, %g", arg, cli_json_number(r.out, "layers"),
           cli_json_number(r.out, "worst_error"), nu, wu);
    cli_free(&r);
    if (t + bin <= tmax + 1e-9) {
        snprintf(arg, sizeof arg, "%.9g", t + bin);
        r = cli_run("plan", raised_sphere(), "--uniform", arg, "--json", NULL);
        CHECKF(r.status == 0 && cli_json_number(r.out, "worst_error") > worst, "--uniform %s: worst %g, optimal %g: not the thickest",
               arg, cli_json_number(r.out, "worst_error"), worst);
        cli_free(&r);
    }

    /* the summary's table and its saving line */
    r = cli_run("plan", raised_sphere(), "--compare", NULL);
    format_duration(when, sizeof when, to);
    format_duration(instead, sizeof instead, tu);
    snprintf(line, sizeof line, "%.0f layers instead of %.0f", no, nu);
    CHECKF(strstr(r.out, "\nUniform ") && strstr(r.out, line), "no Uniform row or no '%s' in\n%s", line, r.out);
    snprintf(line, sizeof line, "%s instead of %s to print: %.1f %% saved", when, instead, pct);
    CHECKF(strstr(r.out, line), "no '%s' in\n%s", line, r.out);
    cli_free(&r);

    /* slice estimates the optimal plan's job as --compare does */
    snprintf(job, sizeof job, "%s/timejob", cli_dir);
    r = cli_run("slice", raised_sphere(), "-o", job, "--pixels", "400x400", "--pitch", "0.05", NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    cli_free(&r);
    snprintf(path, sizeof path, "%s/manifest.json", job);
    manifest = read_whole_text(path);
    CHECKF(manifest && fabs(cli_json_number(manifest, "print_time_s") - to) < 1e-6 * to, "slice: %g s, --compare: %g s",
           manifest ? cli_json_number(manifest, "print_time_s") : NAN, to);
    free(manifest);
    cli_remove_all(job);
}

void test_outputs(void)
{
    if (!cli_begin("adaslice-outputs")) return;
    RUN(layer_svgs_agree_with_the_manifest);
    RUN(orient_map_tiles_and_has_a_colour_bar);
    RUN(compare_gives_the_saving_against_uniform_layers);
    cli_end();
}
