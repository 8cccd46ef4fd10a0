/* What the tool's figures and reports tell a reader, end to end (the tool
   runs as a child process, as in test_cli.c): the layer SVGs agree with the
   manifest, the orient map tiles and has its colour bar, plan --compare
   gives the saving against uniform layers. format_duration is the tool's. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700 /* mknod of a character device (XSI) */
#endif
#include "cli_run.h"
#include "../adaslice.h"
#include "meshgen.h"
#include "tool_run.h"
#include "../host/json.h"
#include "../host/report.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

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

/* A tube (radii 4 and 8 mm, 10 mm tall, one shell: walls and annular caps)
   with a hole of radius 3 mm punched in its outer wall at mid-height: its
   sections there are an open polyline round the outside and a closed loop
   round the bore. */
static adaslice_mesh punched_tube(void)
{
    enum { SLICES = 64, STACKS = 10 };
    adaslice_mesh m = gen_alloc(4 * SLICES * (STACKS + 1), 4 * SLICES * STACKS + 4 * SLICES);
    uint32_t ring[2][STACKS + 1][SLICES];
    int a, k, side;
    for (side = 0; side < 2; side++)
        for (k = 0; k <= STACKS; k++)
            for (a = 0; a < SLICES; a++) {
                double t = 2 * M_PI * a / SLICES, r = side ? 4 : 8;
                ring[side][k][a] = gen_vertex(&m, r * cos(t), r * sin(t), 10.0 * k / STACKS);
            }
    for (a = 0; a < SLICES; a++) {
        int b = (a + 1) % SLICES;
        double mid = 2 * M_PI * (a + 0.5) / SLICES;
        for (k = 0; k < STACKS; k++) {
            double z = 10.0 * (k + 0.5) / STACKS;
            if (hypot(8 * cos(mid) - 8, hypot(8 * sin(mid), z - 5)) > 3) { /* outside the hole: out of the wall */
                gen_triangle(&m, ring[0][k][a], ring[0][k][b], ring[0][k + 1][b]);
                gen_triangle(&m, ring[0][k][a], ring[0][k + 1][b], ring[0][k + 1][a]);
            }
            /* the bore faces the axis */
            gen_triangle(&m, ring[1][k][a], ring[1][k + 1][b], ring[1][k][b]);
            gen_triangle(&m, ring[1][k][a], ring[1][k + 1][a], ring[1][k + 1][b]);
        }
        gen_triangle(&m, ring[0][STACKS][a], ring[0][STACKS][b], ring[1][STACKS][b]); /* top: up */
        gen_triangle(&m, ring[0][STACKS][a], ring[1][STACKS][b], ring[1][STACKS][a]);
        gen_triangle(&m, ring[0][0][a], ring[1][0][b], ring[0][0][b]); /* bottom: down */
        gen_triangle(&m, ring[0][0][a], ring[1][0][a], ring[1][0][b]);
    }
    return m;
}

/* The filled path's points in the layer SVG `svg` (y back up), its subpaths
   closed: edge k runs from pt[k] to pt[next[k]]; returns the edges. */
static size_t filled_edges(const char *svg, double (*pt)[2], size_t *next, size_t max)
{
    const char *p = strstr(svg, "<path fill-rule=\"nonzero\" d=\"");
    size_t n = 0, begin = 0;
    if (!p) return 0;
    p = strchr(p, 'd') + 3;
    while (*p && *p != '"' && n < max) {
        char c, *end;
        while (*p == ' ') p++;
        c = *p++;
        if (c == 'Z') { if (n > begin) next[n - 1] = begin; begin = n; continue; }
        if (c != 'M' && c != 'L') return 0;
        if (c == 'M') begin = n;
        pt[n][0] = strtod(p, &end);
        pt[n][1] = -strtod(end, &end);
        p = end;
        next[n] = n + 1;
        n++;
    }
    return n;
}

/* The nonzero rule at (x, y) over the edges, and the distance to the nearest. */
static int filled_at(double (*pt)[2], const size_t *next, size_t n, double x, double y, double *distance)
{
    size_t k;
    int w = 0;
    *distance = HUGE_VAL;
    for (k = 0; k < n; k++) {
        const double *a = pt[k], *b = pt[next[k]];
        double dx = b[0] - a[0], dy = b[1] - a[1], len2 = dx * dx + dy * dy, t = 0, side = dx * (y - a[1]) - dy * (x - a[0]);
        if (len2 > 0) t = ((x - a[0]) * dx + (y - a[1]) * dy) / len2;
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        if (hypot(a[0] + t * dx - x, a[1] + t * dy - y) < *distance) *distance = hypot(a[0] + t * dx - x, a[1] + t * dy - y);
        if (a[1] <= y && b[1] > y && side > 0) w++;
        if (a[1] > y && b[1] <= y && side < 0) w--;
    }
    return w != 0;
}

/* A layer SVG of an open mesh fills what the layer's PNG lights: the tube
   punched through its outer wall, rasterised from the SVG's filled path at
   every pixel centre more than 1.5 pixels from its edges, against the PNG
   decoded by oiiotool, at each layer through the hole (before, the bore was
   drawn filled and the lit wall as an unfilled line). */
static void open_layer_svgs_fill_what_the_masks_light(void)
{
    enum { W = 400, H = 400, MAX = 4096 };
    const double pitch = 0.05, centre[2] = {0, 0};
    const char *tube = cli_path("punched_tube.obj");
    adaslice_mesh m = punched_tube();
    adaslice_grid g = adaslice_grid_plate(&m, W, H, pitch, pitch, centre);
    char job[600], png[700], pgm[700], *manifest;
    double (*pt)[2] = (double (*)[2])malloc(MAX * sizeof *pt);
    size_t *next = (size_t *)malloc(MAX * sizeof *next), layers, k, checked = 0, open = 0;
    cli_result r;
    cli_write_obj(tube, &m);
    gen_free(&m);
    snprintf(job, sizeof job, "%s/tubejob", cli_dir);
    r = cli_run("slice", tube, "-o", job, "--pixels", "400x400", "--pitch", "0.05", "--svg", NULL);
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    cli_free(&r);
    snprintf(png, sizeof png, "%s/manifest.json", job);
    manifest = read_whole_text(png);
    layers = manifest ? (size_t)cli_json_number(manifest, "layer_count") : 0;
    for (k = 1; k <= layers && pt && next; k++) {
        char path[700], *argv[] = {(char *)"oiiotool", png, (char *)"-d", (char *)"uint8", (char *)"-o", pgm, NULL};
        char *svg;
        unsigned char *grey;
        size_t n, size, wrong = 0, compared = 0;
        int w, h, maxval, used = 0, i, j;
        snprintf(path, sizeof path, "%s/layer_%05zu.svg", job, k);
        svg = read_whole_text(path);
        /* every third layer with an open contour: oiiotool takes a while to start */
        if (!svg || !strstr(svg, "fill=\"none\" stroke=\"#c0392b\"") || open++ % 3) { free(svg); continue; }
        n = filled_edges(svg, pt, next, MAX);
        free(svg);
        CHECKF(n > 0, "layer %zu: no filled path", k);
        snprintf(png, sizeof png, "%s/layer_%05zu.png", job, k);
        snprintf(pgm, sizeof pgm, "%s/layer.pgm", cli_dir);
        if (tool_run("openimageio-tools", argv, cli_path("oiiotool.log"), cli_path("oiiotool.log")) != 0) break;
        grey = read_whole_file(pgm, &size);
        CHECKF(grey && sscanf((char *)grey, "P5 %d %d %d%n", &w, &h, &maxval, &used) == 3 && w == W && h == H &&
                   size == (size_t)used + 1 + W * H, "layer %zu: oiiotool gave no %dx%d PGM", k, W, H);
        for (j = 0; grey && w == W && h == H && j < H; j++)
            for (i = 0; i < W; i++) {
                /* PNG row 0 is the top: grid row H - 1 */
                double x = g.origin[0] + (i + 0.5) * pitch, y = g.origin[1] + (H - 1 - j + 0.5) * pitch, d;
                int filled = filled_at(pt, next, n, x, y, &d), lit = grey[used + 1 + (size_t)j * W + (size_t)i] > 127;
                if (d < 1.5 * pitch) continue;
                compared++;
                wrong += filled != lit;
            }
        CHECKF(wrong == 0 && compared > W * H / 2, "layer %zu: %zu of %zu pixels filled in the SVG and not lit in the "
               "PNG or the other way", k, wrong, compared);
        free(grey);
        checked++;
    }
    CHECKF(checked >= 3, "%zu layers with an open contour", checked);
    free(manifest);
    free(pt);
    free(next);
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


/* ------------------------------------------------ the kinds of output path */

/* What an output option can be given besides a new file (issue 26): a
   symlink (its target is written, the link stays), a FIFO (a reader gets the
   bytes, the FIFO stays), a character device like /dev/null (stays one) and
   "-" (standard output). */
enum { TO_LINK, TO_FIFO, TO_DEVICE, TO_STDOUT, TO_KINDS };
static const char *const TO_NAMES[TO_KINDS] = {"a symlink", "a FIFO", "a null device", "-"};

typedef struct target {
    int kind;
    char path[400];              /* what the option is given */
    char real[400];              /* TO_LINK: the link's target; TO_FIFO: what the reader got */
    pid_t reader;
} target;

/* The part after the last '/'. */
static const char *base_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

/* A device like `dev` (/dev/null, /dev/full) of our own as root, who could
   replace the machine's if the tool regressed; `dev` itself otherwise
   (nobody else can). 0 if there is none to use. */
static int own_device(char *path, size_t size, const char *dev, const char *name)
{
    struct stat st;
    if (stat(dev, &st) != 0 || !S_ISCHR(st.st_mode)) return 0;
    if (geteuid() != 0) {
        snprintf(path, size, "%s", dev);
        return 1;
    }
    snprintf(path, size, "%s/%s-%s", cli_dir, base_of(dev), name);
    return mknod(path, S_IFCHR | 0666, st.st_rdev) == 0;
}

static int null_device(char *path, size_t size, const char *name) { return own_device(path, size, "/dev/null", name); }

/* The path of `kind` for output `name`; 0 when this machine has none. */
static int target_make(target *t, int kind, const char *name)
{
    memset(t, 0, sizeof *t);
    t->kind = kind;
    switch (kind) {
    case TO_LINK:
        snprintf(t->real, sizeof t->real, "%s/real-%s", cli_dir, name);
        snprintf(t->path, sizeof t->path, "%s/link-%s", cli_dir, name);
        cli_write(t->real, "old");
        {
            char rel[200];
            snprintf(rel, sizeof rel, "real-%s", name); /* relative: read from the link's directory */
            CHECK(symlink(rel, t->path) == 0);
        }
        return 1;
    case TO_FIFO:
        snprintf(t->path, sizeof t->path, "%s/fifo-%s", cli_dir, name);
        snprintf(t->real, sizeof t->real, "%s/got-%s", cli_dir, name);
        CHECK(mkfifo(t->path, 0644) == 0);
        fflush(NULL);
        t->reader = fork();
        if (t->reader == 0) {
            char buf[65536];
            ssize_t n;
            int in, out;
            alarm(5); /* a FIFO replaced by a file is never opened for writing */
            in = open(t->path, O_RDONLY);
            out = open(t->real, O_WRONLY | O_CREAT | O_TRUNC, 0644);
            if (in < 0 || out < 0) _exit(1);
            while ((n = read(in, buf, sizeof buf)) > 0)
                if (write(out, buf, (size_t)n) != n) _exit(1);
            _exit(n < 0);
        }
        CHECK(t->reader > 0);
        return t->reader > 0;
    case TO_DEVICE: return null_device(t->path, sizeof t->path, name);
    default: snprintf(t->path, sizeof t->path, "-"); return 1;
    }
}

/* The output went where t says, starting with `signature` (NULL: any bytes),
   and the path is what it was; then it is removed. */
static void target_check(target *t, const char *what, const cli_result *r, const char *signature)
{
    struct stat st;
    unsigned char *got = NULL;
    size_t size = 0;
    const char *kind = TO_NAMES[t->kind];
    CHECKF(r->status == 0, "%s to %s: exit %d, %s", what, kind, r->status, r->err);
    switch (t->kind) {
    case TO_LINK:
        CHECKF(lstat(t->path, &st) == 0 && S_ISLNK(st.st_mode), "%s: the symlink was replaced", what);
        got = read_whole_file(t->real, &size);
        break;
    case TO_FIFO: {
        int st2 = 0, fd = open(t->path, O_WRONLY | O_NONBLOCK); /* a reader still waiting gets its end */
        if (fd >= 0) close(fd);
        CHECK(waitpid(t->reader, &st2, 0) == t->reader);
        CHECKF(WIFEXITED(st2) && WEXITSTATUS(st2) == 0, "%s: the FIFO's reader got nothing (status %d)", what, st2);
        CHECKF(lstat(t->path, &st) == 0 && S_ISFIFO(st.st_mode), "%s: the FIFO was replaced", what);
        got = read_whole_file(t->real, &size);
        break;
    }
    case TO_DEVICE:
        CHECKF(stat(t->path, &st) == 0 && S_ISCHR(st.st_mode), "%.100s: %.200s is no longer a device", what, t->path);
        break;
    default:
        got = read_whole_file(cli_path("stdout"), &size);
        break;
    }
    if (t->kind != TO_DEVICE) {
        CHECKF(got && size > 3 && memcmp(got, "old", 3) != 0, "%s to %s: nothing written there (%zu bytes)", what, kind, size);
        if (got && signature)
            CHECKF(size >= strlen(signature) && !memcmp(got, signature, strlen(signature)), "%s to %s: not the output", what,
                   kind);
    }
    free(got);
    if (t->kind != TO_STDOUT && strcmp(t->path, "/dev/null")) remove(t->path);
    if (t->kind == TO_LINK || t->kind == TO_FIFO) remove(t->real);
}

/* Every output option: its command (OUT where the path goes) and how its
   bytes begin. */
typedef struct output_option { const char *args[18]; const char *signature; } output_option;
#define MODEL "MODEL"
#define PIXELS "--pixels", "120x120", "--pitch", "0.1", "--uniform", "0.1"
static const output_option OUTPUT_OPTIONS[] = {
    {{"plan", MODEL, "--out", "OUT"}, "layer,"},
    {{"plan", MODEL, "--plot", "OUT"}, "<"},
    {{"plan", MODEL, "--profile-out", "OUT"}, NULL},
    {{"plan", MODEL, "--3mf", "OUT"}, "PK"},
    {{"slice", MODEL, PIXELS, "--format", "ctb", "-o", "OUT"}, NULL},
    {{"slice", MODEL, PIXELS, "--format", "ctb-encrypted", "-o", "OUT"}, NULL},
    {{"slice", MODEL, PIXELS, "--format", "goo", "-o", "OUT"}, NULL},
    {{"slice", MODEL, PIXELS, "--format", "prz", "-o", "OUT"}, NULL},
    {{"slice", MODEL, PIXELS, "--format", "chitu-zip", "-o", "OUT"}, "PK"},
    {{"slice", MODEL, PIXELS, "--format", "sl1", "-o", "OUT"}, "PK"},
    {{"slice", MODEL, PIXELS, "--format", "uvj", "-o", "OUT"}, "PK"},
    {{"slice", MODEL, PIXELS, "--format", "ctb", "-o", "JOB", "--out", "OUT"}, "layer,"},
    {{"orient", MODEL, "--dirs", "8", "--map", "OUT"}, "<"},
    {{"saliency", MODEL, "-o", "OUT"}, NULL},
    {{"saliency", MODEL, "--ply", "OUT"}, "ply"},
    {{"saliency", MODEL, "--png", "OUT"}, "\x89PNG"},
};

static void outputs_never_replace_links_fifos_or_devices(void)
{
    size_t i, a;
    int kind;
    for (i = 0; i < sizeof OUTPUT_OPTIONS / sizeof OUTPUT_OPTIONS[0]; i++)
        for (kind = 0; kind < TO_KINDS; kind++) {
            const output_option *o = &OUTPUT_OPTIONS[i];
            const char *argv[20] = {NULL};
            char what[200] = "", name[40];
            target t;
            cli_result r;
            snprintf(name, sizeof name, "out%zu%s", i, !strcmp(o->args[2], "--3mf") ? ".3mf" : ""); /* --3mf wants one */
            if (!target_make(&t, kind, name)) continue; /* no null device of our own: mknod refused */
            for (a = 0; o->args[a]; a++) {
                argv[a] = !strcmp(o->args[a], MODEL) ? raised_sphere()
                          : !strcmp(o->args[a], "OUT") ? t.path
                          : !strcmp(o->args[a], "JOB") ? cli_path("job.ctb") : o->args[a];
                if (strlen(what) + strlen(o->args[a]) + 2 < sizeof what) {
                    strcat(what, o->args[a]);
                    strcat(what, " ");
                }
            }
            r = cli_run(argv[0], argv[1], argv[2], argv[3], argv[4], argv[5], argv[6], argv[7], argv[8], argv[9],
                        argv[10], argv[11], argv[12], argv[13], argv[14], argv[15], argv[16], argv[17], NULL);
            target_check(&t, what, &r, o->signature);
            cli_free(&r);
            remove(cli_path("job.ctb"));
        }
    {
        DIR *d = opendir(cli_dir); /* nothing left under a temporary name */
        struct dirent *e;
        while (d && (e = readdir(d)) != NULL) CHECKF(!strstr(e->d_name, ".tmp."), "left behind: %s", e->d_name);
        if (d) closedir(d);
    }
}

/* slice adds its format's extension to a new name only: -o /dev/null with a
   printer's format writes /dev/null, not /dev/null.ctb; a job directory
   cannot go to a device. */
static void no_extension_on_a_path_that_exists(void)
{
    char dev[400];
    cli_result r;
    if (!null_device(dev, sizeof dev, "ext")) return;
    r = cli_run("slice", raised_sphere(), "--printer", "elegoo-mars-3", "-o", dev, NULL);
    CHECKF(r.status == 0 && strstr(r.out, dev) && !strstr(r.out, ".ctb"), "exit %d: %s%s", r.status, r.out, r.err);
    cli_free(&r);
    snprintf(dev + strlen(dev), sizeof dev - strlen(dev), ".ctb");
    CHECKF(!cli_exists(dev), "%s written", dev);
    dev[strlen(dev) - 4] = 0;
    r = cli_run("slice", raised_sphere(), "-o", dev, NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "not a directory"), "exit %d: %s", r.status, r.err);
    cli_free(&r);
    if (strcmp(dev, "/dev/null")) remove(dev);
    /* /dev/stdout is standard output, wherever the shell sent it (here a file,
       which a rename would have taken and an open would have cut) */
    r = cli_run("plan", raised_sphere(), "--out", "/dev/stdout", NULL);
    CHECKF(r.status == 0 && !strncmp(r.out, "layer,", 6), "exit %d: %.200s %s", r.status, r.out, r.err);
    /* the data alone: the summary goes to standard error (it followed the
       CSV, and a profile written to "-" and read back failed at its line) */
    CHECKF(!strstr(r.out, "model ") && strstr(r.err, "model "), "the summary went with the data: %.300s", r.out);
    cli_free(&r);
    {
        char csv[600];
        cli_result back;
        snprintf(csv, sizeof csv, "%s/profile_from_stdout.csv", cli_dir);
        r = cli_run("plan", raised_sphere(), "--profile-out", "-", NULL);
        CHECKF(r.status == 0 && !strstr(r.out, "model "), "exit %d: %.300s", r.status, r.out);
        cli_write(csv, r.out);
        cli_free(&r);
        back = cli_run("plan", "--profile", csv, NULL);
        CHECKF(back.status == 0, "the profile written to - read back: exit %d: %s", back.status, back.err);
        cli_free(&back);
    }
}

/* The index of the last argument. */
static size_t argc_last(const char *const *argv)
{
    size_t n = 0;
    while (n < 7 && argv[n + 1]) n++;
    return n;
}

/* Every output path is checked before the model is loaded: a model that
   does not exist is never reached, the output's message wins, exit 2. */
static void output_paths_are_checked_before_the_work(void)
{
    const char *dir = cli_path("a-directory.ctb"), *nothing = cli_path("no-such-model.stl");
    char in_dir[500], missing[500];
    cli_result r;
    size_t i;
    const char *const cases[][8] = {
        {"slice", "MODEL", "--pixels", "100x100", "--pitch", "0.1", "-o", "DIR"},
        {"print", "MODEL", "--port", "/no-such-port", "--report", "DIR"},
        {"plan", "MODEL", "--out", "DIR"},
        {"plan", "MODEL", "--plot", "MISSING"},
        {"plan", "MODEL", "--3mf", "DIR"},
        {"orient", "MODEL", "--map", "DIR"},
        {"saliency", "MODEL", "--png", "MISSING"},
        {"slice", "MODEL", "--pixels", "100x100", "--pitch", "0.1", "-o", "MISSING"},
    };
    mkdir(dir, 0755);
    snprintf(missing, sizeof missing, "%s/no-such-dir/out", cli_dir);
    for (i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const char *argv[8];
        size_t a;
        for (a = 0; a < 8; a++)
            argv[a] = !cases[i][a] ? NULL : !strcmp(cases[i][a], "MODEL") ? nothing : !strcmp(cases[i][a], "DIR") ? dir
                      : !strcmp(cases[i][a], "MISSING") ? missing : cases[i][a];
        r = cli_run(argv[0], argv[1], argv[2], argv[3], argv[4], argv[5], argv[6], argv[7], NULL);
        snprintf(in_dir, sizeof in_dir, "%s", strstr(r.err, dir) ? dir : missing);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, in_dir) && !strstr(r.err, "no-such-model"),
               "%s %s: exit %d, %s", argv[0], argv[argc_last(argv)], r.status, r.err);
        cli_free(&r);
    }
    rmdir(dir);
    /* an empty -o, with a printer whose extension it would have taken */
    r = cli_run("slice", nothing, "--printer", "elegoo-mars-3", "-o", "", NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "-o \"\"") && !cli_exists(".ctb"), "exit %d: %s",
           r.status, r.err);
    cli_free(&r);
}

/* ------------------------------------------------ signals and full disks */

static void pause_ms(long ms)
{
    struct timespec t;
    t.tv_sec = ms / 1000;
    t.tv_nsec = ms % 1000 * 1000000L;
    nanosleep(&t, NULL);
}

/* The tool on argv (argv[0] its command), stderr into err; its pid. */
static pid_t spawn(const char *const *argv, const char *err)
{
    const char *full[24];
    size_t n = 0;
    pid_t pid;
    full[n++] = cli_tool;
    while (argv[n - 1] && n < 23) { full[n] = argv[n - 1]; n++; }
    full[n] = NULL;
    fflush(NULL);
    pid = fork();
    if (pid == 0) {
        int null = open("/dev/null", O_RDWR), e = open(err, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (null < 0 || e < 0 || dup2(null, 0) < 0 || dup2(null, 1) < 0 || dup2(e, 2) < 0) _exit(126);
        execv(cli_tool, (char *const *)full);
        _exit(127);
    }
    CHECK(pid > 0);
    return pid;
}

/* A file whose name holds `part` in dir (the run's temporary file, its first layer). */
static int dir_holds(const char *dir, const char *part)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    int found = 0;
    while (d && !found && (e = readdir(d)) != NULL) found = strstr(e->d_name, part) != NULL;
    if (d) closedir(d);
    return found;
}

static size_t entries(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    size_t n = 0;
    while (d && (e = readdir(d)) != NULL) n += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
    if (d) closedir(d);
    return n;
}

/* Signals `sig` to the run once `part` shows in `watch` (gone: once it has
   gone from there); it exits 128 + sig saying so in one line. */
static void interrupt_when(const char *const *argv, const char *watch, const char *part, int gone, int sig,
                           const char *what)
{
    const char *err = cli_path("interrupted.err");
    char expect[80], *text;
    int st = 0, waited;
    pid_t pid = spawn(argv, err);
    for (waited = 0; waited < 3000 && dir_holds(watch, part) == gone; waited++) pause_ms(10);
    CHECKF(dir_holds(watch, part) != gone, "%s: %s %s in %s after 30 s", what, part, gone ? "still" : "not", watch);
    kill(pid, sig);
    CHECK(waitpid(pid, &st, 0) == pid);
    CHECKF(WIFEXITED(st) && WEXITSTATUS(st) == 128 + sig, "%s: status %d, not exit %d", what, st, 128 + sig);
    text = read_whole_text(err);
    snprintf(expect, sizeof expect, "interrupted by %s", sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "SIGHUP");
    CHECKF(text && cli_one_message(text) && strstr(text, expect), "%s: stderr '%s'", what, text ? text : "");
    free(text);
}

/* SIGTERM, SIGHUP and SIGINT to a slice leave no temporary file and no part
   of a directory job: the run removes every file it wrote. */
static void signals_leave_nothing_behind(void)
{
    static const int signals[] = {SIGTERM, SIGHUP, SIGINT};
    char watch[300], job[400], plan[400];
    size_t i;
    snprintf(watch, sizeof watch, "%s/signalled", cli_dir);
    snprintf(job, sizeof job, "%s/job.ctb", watch);
    snprintf(plan, sizeof plan, "%s/plan.csv", watch);
    for (i = 0; i < 3; i++) {
        const char *file_job[] = {"slice", raised_sphere(), "--pixels", "3000x3000", "--pitch", "0.004", "--uniform",
                                  "0.01", "--threads", "1", "-o", job, "--out", plan, NULL};
        const char *dir_job[] = {"slice", raised_sphere(), "--pixels", "3000x3000", "--pitch", "0.004", "--uniform",
                                 "0.01", "--threads", "2", "-o", job, NULL};
        char what[80];
        mkdir(watch, 0755);
        snprintf(what, sizeof what, "a .ctb job, signal %d", signals[i]);
        interrupt_when(file_job, watch, ".tmp.", 0, signals[i], what);
        CHECKF(entries(watch) == 0, "%s: %zu files left in %s (plan.csv, the temporary file)", what, entries(watch), watch);
        /* a directory job made by the run: gone, with everything in it */
        snprintf(job, sizeof job, "%s/jobdir", watch);
        snprintf(what, sizeof what, "a directory job, signal %d", signals[i]);
        interrupt_when(dir_job, job, "layer_", 0, signals[i], what);
        CHECKF(!cli_exists(job), "%s: %s left (%zu files in it)", what, job, entries(job));
        cli_remove_all(job);
        snprintf(job, sizeof job, "%s/job.ctb", watch);
        cli_remove_all(watch);
    }
    /* an earlier job in the directory, then an interrupted re-slice: it has
       removed the old job and leaves nothing of its own; the directory stays */
    {
        const char *dir_job[] = {"slice", raised_sphere(), "--pixels", "3000x3000", "--pitch", "0.004", "--uniform",
                                 "0.01", "--threads", "2", "-o", watch, NULL};
        cli_result r = cli_run("slice", raised_sphere(), "--pixels", "300x300", "--pitch", "0.05", "-o", watch, NULL);
        CHECKF(r.status == 0, "%s", r.err);
        cli_free(&r);
        interrupt_when(dir_job, watch, "manifest.json", 1, SIGTERM, "a re-slice"); /* the old job is going */
        CHECKF(cli_exists(watch) && entries(watch) == 0, "a re-slice: %zu files left", entries(watch));
        cli_remove_all(watch);
    }
}

/* Ctrl-C while every command works (before anything is written): exit 130
   and one line, slice --orient best and orient alike. */
static void every_command_exits_130_on_ctrl_c(void)
{
    const char *orient[] = {"orient", raised_sphere(), "--dirs", "1000000", NULL};
    /* big enough that Ctrl-C comes during the search or the layers, whichever */
    const char *slice[] = {"slice", raised_sphere(), "--orient", "best", "--pixels", "3000x3000", "--pitch", "0.004",
                           "--uniform", "0.01", "-o", cli_path("never"), NULL};
    const char *const *runs[] = {orient, slice};
    size_t i;
    for (i = 0; i < 2; i++) {
        const char *err = cli_path("ctrl-c.err");
        char *text;
        int st = 0;
        pid_t pid = spawn(runs[i], err);
        pause_ms(700);
        kill(pid, SIGINT);
        CHECK(waitpid(pid, &st, 0) == pid);
        text = read_whole_text(err);
        CHECKF(WIFEXITED(st) && WEXITSTATUS(st) == 130 && text && cli_one_message(text) &&
                   strstr(text, "interrupted by SIGINT"),
               "%s: status %d, '%s'", runs[i][0], st, text ? text : "");
        free(text);
    }
    CHECK(!cli_exists(cli_path("never")));
}

/* A write that fails (a full disk: /dev/full, written straight) fails the
   run with one line naming it, and removes what the run had written. */
static void a_full_disk_leaves_nothing(void)
{
    const char *csv = cli_path("full-plan.csv"), *profile = cli_path("full-profile.csv"), *job = cli_path("full-job");
    const char *weights = cli_path("full-weights.csv"), *ply = cli_path("full.ply");
    char full[400];
    struct stat st;
    cli_result r;
    if (!own_device(full, sizeof full, "/dev/full", "disk")) return; /* none, or mknod refused */
    r = cli_run("plan", raised_sphere(), "--out", csv, "--profile-out", profile, "--plot", full, NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, full), "exit %d: %s", r.status, r.err);
    CHECKF(!cli_exists(csv) && !cli_exists(profile), "plan: plan.csv or profile.csv left after the plot failed");
    cli_free(&r);
    r = cli_run("slice", raised_sphere(), "--pixels", "300x300", "--pitch", "0.05", "-o", job, "--plot", full, NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, full), "exit %d: %s", r.status, r.err);
    CHECKF(!cli_exists(job), "slice: the directory job is left (%zu files)", entries(job));
    cli_free(&r);
    cli_remove_all(job);
    r = cli_run("slice", raised_sphere(), "--pixels", "300x300", "--pitch", "0.05", "--format", "ctb", "-o", full,
                "--out", csv, NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, full), "exit %d: %s", r.status, r.err);
    CHECKF(!cli_exists(csv), "slice: plan.csv left after the job failed");
    cli_free(&r);
    r = cli_run("saliency", raised_sphere(), "-o", weights, "--ply", ply, "--png", full, NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, full), "exit %d: %s", r.status, r.err);
    CHECKF(!cli_exists(weights) && !cli_exists(ply), "saliency: the weights or the PLY left after the PNG failed");
    cli_free(&r);
    { /* the summary on a full standard output fails the run, and takes the files written with it */
        static const char *const commands[] = {"plan '%s' --out '%s'",
                                               "slice '%s' --pixels 300x300 --pitch 0.05 -o '%s'"};
        char cmd[4096], run[1200], err[600], model[600], out[600];
        int k, status;
        /* cli_path's names last eight calls: these are kept */
        snprintf(err, sizeof err, "%s", cli_path("full-stderr.txt"));
        snprintf(model, sizeof model, "%s", raised_sphere());
        for (k = 0; k < 2; k++) {
            snprintf(out, sizeof out, "%s", cli_path(k ? "full-job" : "full-plan.csv"));
            snprintf(run, sizeof run, commands[k], model, out);
            snprintf(cmd, sizeof cmd, "'%s' %s > '%s' 2> '%s'", cli_tool, run, full, err);
            status = system(cmd);
            {
                char *said = read_whole_text(err);
                CHECKF(WIFEXITED(status) && WEXITSTATUS(status) == 1 && said && cli_one_message(said) &&
                           strstr(said, "cannot write standard output"),
                       "%.200s > %.100s: status %d, '%.150s'", run, full, status, said ? said : "");
                free(said);
            }
            CHECKF(k ? !entries(out) : !cli_exists(out), "%.200s > %.100s: its output is left", run, full);
            cli_remove_all(out);
        }
    }
    CHECKF(stat(full, &st) == 0 && S_ISCHR(st.st_mode), "%s is no longer a device", full);
    if (strcmp(full, "/dev/full")) remove(full);
}

/* ------------------------------------------------ a directory job's files */

static int same_text(const char *path, const char *text)
{
    char *got = read_whole_text(path);
    int same = got && !strcmp(got, text);
    free(got);
    return same;
}

/* A slice into a directory of someone's files is refused unless --force;
   then, and on every re-slice, only the files an earlier manifest lists go. */
/* The directory dir made, with files names[i] holding texts[i]: a user's. */
static void make_files(const char *dir, const char *const *names, const char *const *texts, size_t n)
{
    char path[400];
    size_t i;
    mkdir(dir, 0755);
    for (i = 0; i < n; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        cli_write(path, texts[i]);
    }
}

static void a_directory_job_removes_only_its_own_files(void)
{
    static const char *const users[] = {"layer_99999.png", "layer_00070.png", "layer_00001.svg", "notes.txt"};
    char dir[300], path[400], *manifest;
    cli_result r;
    size_t i;
    snprintf(dir, sizeof dir, "%s/userdir", cli_dir);
    make_files(dir, users, users, 4);
    r = cli_run("slice", raised_sphere(), "--pixels", "300x300", "--pitch", "0.05", "-o", dir, NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, dir) && strstr(r.err, "--force"), "exit %d: %s",
           r.status, r.err);
    cli_free(&r);
    for (i = 0; i < 4; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, users[i]);
        CHECKF(same_text(path, users[i]), "refused, yet %s was touched", users[i]);
    }
    CHECK(entries(dir) == 4);

    /* --force: the job among them (its layer 70 written over) */
    r = cli_run("slice", raised_sphere(), "--pixels", "300x300", "--pitch", "0.05", "--uniform", "0.1", "-o", dir,
                "--force", NULL);
    CHECKF(r.status == 0, "--force: exit %d: %s", r.status, r.err);
    cli_free(&r);
    snprintf(path, sizeof path, "%s/manifest.json", dir);
    manifest = read_whole_text(path);
    CHECKF(manifest && strstr(manifest, "\"files\": [") && strstr(manifest, "\"masks.rle\"") &&
               strstr(manifest, "\"layer_00100.png\"") && strstr(manifest, "\"plan.csv\"") &&
               !strstr(manifest, "\"notes.txt\""),
           "the manifest does not list the job's files");
    free(manifest);

    /* a re-slice of fewer layers: the old job's go, the user's stay */
    r = cli_run("slice", raised_sphere(), "--pixels", "300x300", "--pitch", "0.05", "--uniform", "0.5", "-o", dir, NULL);
    CHECKF(r.status == 0, "re-slice: exit %d: %s", r.status, r.err);
    cli_free(&r);
    for (i = 0; i < 4; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, users[i]);
        /* layer_00070.png: --force wrote the job's layer 70 over it, and the job took it away */
        CHECKF(i == 1 ? !cli_exists(path) : same_text(path, users[i]), "a re-slice removed, changed or kept %s", users[i]);
    }
    snprintf(path, sizeof path, "%s/layer_00050.png", dir);
    CHECKF(!cli_exists(path), "the earlier job's layer 50 is left");
    snprintf(path, sizeof path, "%s/layer_00020.png", dir);
    CHECKF(cli_exists(path), "no layer 20");

    /* a manifest from before the list: its layers' files go, nothing else */
    snprintf(path, sizeof path, "%s/manifest.json", dir);
    manifest = read_whole_text(path);
    if (manifest) {
        char *list = strstr(manifest, "\"files\": ["), *end = list ? strchr(list, ']') : NULL;
        if (list && end) {
            memmove(list, end + 3, strlen(end + 3) + 1); /* "files": [...],\n out */
            cli_write(path, manifest);
        }
        free(manifest);
    }
    r = cli_run("slice", raised_sphere(), "--pixels", "300x300", "--pitch", "0.05", "--uniform", "1", "-o", dir, NULL);
    CHECKF(r.status == 0, "after an old manifest: exit %d: %s", r.status, r.err);
    cli_free(&r);
    snprintf(path, sizeof path, "%s/layer_00020.png", dir);
    CHECKF(!cli_exists(path), "an old manifest's layer 20 is left");
    /* (the SVG beside a listed layer goes too: an old job's --svg wrote them unlisted) */
    for (i = 0; i < 4; i++)
        if (i != 1 && i != 2) {
            snprintf(path, sizeof path, "%s/%s", dir, users[i]);
            CHECKF(same_text(path, users[i]), "after an old manifest, %s was removed or changed", users[i]);
        }
    cli_remove_all(dir);
}

/* JSON strings escape what RFC 8259 says they must (the quote, the
   backslash, control characters) and nothing else: a model's name with
   quotes, backslashes, a tab, a newline and UTF-8 in it reads back. */
/* Another program's manifest.json (a web app's) is not an old job: slice
   took it for one and removed it and every file its "files" named, exit 0.
   Refused, --force or not (the job's manifest would replace it), and
   nothing in the directory touched. */
static void another_programs_manifest_is_left_alone(void)
{
    static const char *const files[] = {"manifest.json", "index.html", "app.js"};
    static const char *const texts[] = {"{\"name\": \"app\", \"files\": [\"index.html\", \"app.js\"]}\n", "<html>\n", "run()\n"};
    char dir[300], path[400];
    int force;
    size_t i;
    snprintf(dir, sizeof dir, "%s/webapp", cli_dir);
    make_files(dir, files, texts, 3);
    for (force = 0; force < 2; force++) {
        cli_result r = cli_run("slice", raised_sphere(), "--pixels", "300x300", "--pitch", "0.05", "-o", dir,
                               force ? "--force" : NULL, NULL);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "manifest.json") && strstr(r.err, "adaslice-job"),
               "%s: exit %d: %s", force ? "--force" : "plain", r.status, r.err);
        cli_free(&r);
        for (i = 0; i < 3; i++) {
            snprintf(path, sizeof path, "%s/%s", dir, files[i]);
            CHECKF(same_text(path, texts[i]), "%s: %s was removed or changed", force ? "--force" : "plain", files[i]);
        }
    }
    cli_remove_all(dir);
}

static void json_strings_escape_what_they_must(void)
{
    static const char name[] = "a \"b\" c\\d\te\nf\x01 \xc3\xa9 g";
    static const char want[] = "{\"model\": \"a \\\"b\\\" c\\\\d\\u0009e\\u000af\\u0001 \xc3\xa9 g\", \"\": \"\"}\n";
    char got[200];
    size_t n;
    json_writer w;
    FILE *f = tmpfile();
    CHECK(f != NULL);
    if (!f) return;
    json_init(&w, f);
    json_begin_object(&w, NULL, 1);
    json_string(&w, "model", name);
    json_string(&w, "", "");
    json_end(&w);
    rewind(f);
    n = fread(got, 1, sizeof got - 1, f);
    got[n] = 0;
    fclose(f);
    CHECKF(!strcmp(got, want), "wrote %s", got);
}

/* Numbers in the fewest of 15 to 17 digits that read back, the same text
   when one comes again (the writer keeps the last few): 0 and -0 apart, a
   number its slot lost to another written anew, every one reading back bit
   for bit and in no more digits than it needs. */
static void json_numbers_read_back_when_they_repeat(void)
{
    double v[200];
    char text[8192], *p, *end;
    size_t n, i;
    json_writer w;
    FILE *f = tmpfile();
    CHECK(f != NULL);
    if (!f) return;
    for (i = 0; i < 200; i++) {
        static const double some[] = {0.0, -0.0, 0.1, 0.30000000000000004, 1.2500000000000002, 0.064, 1e-300, -2.5e17};
        /* repeats and fresh values in turn; the fresh ones push the kept ones out */
        v[i] = i % 3 ? some[(i * 7) % 8] : 1832.0525 + (double)i / 7;
    }
    json_init(&w, f);
    json_begin_array(&w, NULL, 1);
    for (i = 0; i < 200; i++) json_number(&w, NULL, v[i]);
    json_end(&w);
    rewind(f);
    n = fread(text, 1, sizeof text - 1, f);
    text[n] = 0;
    fclose(f);
    for (i = 0, p = text + 1; i < 200; i++, p = end + 1) {
        char want[32];
        double back = strtod(p, &end);
        int digits;
        CHECKF(end > p && memcmp(&back, &v[i], sizeof back) == 0, "number %zu (%.17g) wrote %.20s", i, v[i], p);
        for (digits = 15; digits < 17; digits++) {
            snprintf(want, sizeof want, "%.*g", digits, v[i]);
            if (strtod(want, NULL) == v[i]) break;
        }
        if (digits == 17) snprintf(want, sizeof want, "%.17g", v[i]);
        CHECKF((size_t)(end - p) == strlen(want) && !strncmp(p, want, strlen(want)), "number %zu: %.20s, not %s", i, p, want);
        if (*end != ',') break;
        end++; /* the space */
    }
    CHECKF(i == 199, "read %zu of 200 numbers", i + 1);
}

/* A write that fails is kept in the writer (a job's manifest lines go to a
   memory stream, which on glibc drops what it cannot grow for and leaves
   ferror clear): each kind of value written to /dev/full unbuffered,
   where every write fails at once; to a memory stream, none. */
static void json_writes_that_fail_are_kept(void)
{
    int kind, full;
    for (kind = 0; kind < 8; kind++)
        for (full = 0; full < 2; full++) {
            FILE *f = fopen("/dev/full", "w");
            char *text = NULL;
            size_t size = 0;
            FILE *m = open_memstream(&text, &size);
            json_writer w;
            CHECK(f != NULL && m != NULL);
            if (!f || !m) return;
            setvbuf(f, NULL, _IONBF, 0);
            json_init(&w, m);
            json_begin_array(&w, NULL, 1);
            if (full) w.f = f; /* the first value: no comma, no key before it */
            switch (kind) {
            case 0: json_number(&w, NULL, 0.25); break;
            case 1: json_int(&w, NULL, -7); break;
            case 2: json_string(&w, NULL, "x\"y\x01"); break;
            case 3: json_bool(&w, NULL, 1); break;
            case 4: json_null(&w, NULL); break;
            case 5: json_raw(&w, NULL, "[1]", 3); break;
            case 6: json_numbers(&w, NULL, (const double[]){1, 2}, 2); break;
            default: json_string(&w, NULL, NULL); break;
            }
            CHECKF(w.failed == full, "kind %d, %s: failed %d", kind, full ? "/dev/full" : "a memory stream", w.failed);
            w.f = m;
            json_end(&w);
            fclose(f);
            fclose(m);
            free(text);
        }
}

void test_outputs(void)
{
    if (!cli_begin("adaslice-outputs")) return;
    RUN(json_strings_escape_what_they_must);
    RUN(json_numbers_read_back_when_they_repeat);
    RUN(json_writes_that_fail_are_kept);
    RUN(layer_svgs_agree_with_the_manifest);
    RUN(open_layer_svgs_fill_what_the_masks_light);
    RUN(orient_map_tiles_and_has_a_colour_bar);
    RUN(compare_gives_the_saving_against_uniform_layers);
    RUN(outputs_never_replace_links_fifos_or_devices);
    RUN(no_extension_on_a_path_that_exists);
    RUN(output_paths_are_checked_before_the_work);
    RUN(signals_leave_nothing_behind);
    RUN(every_command_exits_130_on_ctrl_c);
    RUN(a_full_disk_leaves_nothing);
    RUN(a_directory_job_removes_only_its_own_files);
    RUN(another_programs_manifest_is_left_alone);
    cli_end();
}
