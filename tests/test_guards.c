/* What adaslice slice says or refuses before a printer owner wastes a print:
   which printers take each layer's own Z (adaslice printers, the slice help
   and an adaptive job's summary), a part taller than the default printer
   builds, a part in the wrong unit, and a job that lights no pixel. */
#include "cli_run.h"
#include "meshgen.h"
#include "../host/formats/jobfile.h"
#include "../host/formats/layer_z.h"
#include "../host/printer.h"

#include <time.h>

/* A sphere 10 mm across: an adaptive plan's layers differ. */
static const char *sphere_obj(void)
{
    const char *path = cli_path("sphere.obj");
    if (!cli_exists(path)) {
        adaslice_mesh m = gen_sphere(5, 32, 16, 0);
        cli_write_obj(path, &m);
        gen_free(&m);
    }
    return path;
}

/* A closed box x by y by z mm, its corner at the origin. */
static const char *box_obj(const char *name, double x, double y, double z)
{
    const char *path = cli_path(name);
    char text[600];
    snprintf(text, sizeof text,
             "v 0 0 0\nv %.17g 0 0\nv %.17g %.17g 0\nv 0 %.17g 0\nv 0 0 %.17g\nv %.17g 0 %.17g\nv %.17g %.17g %.17g\n"
             "v 0 %.17g %.17g\nf 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\n"
             "f 3 8 7\nf 4 1 5\nf 4 5 8\n",
             x, x, y, y, z, x, z, x, y, z, y, z);
    cli_write(path, text);
    return path;
}

/* The capability each format's printers are known for (formats.md, "Field
   facts on per-layer Z"), written out here rather than read from layer_z.c. */
static const char *expected_z(const char *format)
{
    if (!strcmp(format, "dir")) return "yes (adaslice print and firmware)";
    if (!strcmp(format, "chitu-zip")) return "yes by construction";
    if (!strcmp(format, "ctb")) return "per the format, not field-verified";
    if (!strcmp(format, "goo")) return "per the format, field reports of trouble";
    if (!strcmp(format, "sl1")) return "no";
    if (!strcmp(format, "ctb-encrypted") || !strcmp(format, "uvj")) return "per the format, not field-verified";
    if (!strcmp(format, "prz")) return "per the format, field reports of trouble";
    return NULL;
}

/* The line of `text` that starts with `start`, copied into line; 0 if none. */
static int line_starting(const char *text, const char *start, char *line, size_t size)
{
    const char *at = text;
    size_t n = strlen(start);
    for (; at && *at; at = strchr(at, '\n') ? strchr(at, '\n') + 1 : NULL)
        if (!strncmp(at, start, n) && at[n] == ' ') {
            const char *end = strchr(at, '\n');
            size_t len = end ? (size_t)(end - at) : strlen(at);
            if (len >= size) len = size - 1;
            memcpy(line, at, len);
            line[len] = 0;
            return 1;
        }
    return 0;
}

/* Every job format has a row in the one table, and "no" there is exactly
   the formats that hold one layer height: a format added without its row
   fails here. */
static void every_format_has_a_per_layer_z_row(void)
{
    int i;
    for (i = 0; JOB_FORMATS[i]; i++) {
        const layer_z *z = layer_z_of(JOB_FORMATS[i]->name);
        const char *want = expected_z(JOB_FORMATS[i]->name);
        CHECKF(z->support != LAYER_Z_UNKNOWN, "%s: no per-layer Z row (host/formats/layer_z.c)", JOB_FORMATS[i]->name);
        CHECKF((z->support == LAYER_Z_NO) == !JOB_FORMATS[i]->adaptive, "%s: per-layer Z '%s', adaptive %d",
               JOB_FORMATS[i]->name, layer_z_says(z->support), JOB_FORMATS[i]->adaptive);
        if (want) CHECKF(!strcmp(layer_z_says(z->support), want), "%s: '%s'", JOB_FORMATS[i]->name, layer_z_says(z->support));
    }
    CHECK(layer_z_of("no-such-format")->support == LAYER_Z_UNKNOWN);
}

/* adaslice printers (and slice --printer list) shows every preset with its
   format, pixels, pitch, build height and its format's per-layer Z; the GOO
   row names the field reports. */
static void printers_lists_every_preset(void)
{
    cli_result r = cli_run("printers", NULL), list;
    int i;
    CHECKF(r.status == 0 && !*r.err, "exit %d: %s", r.status, r.err);
    for (i = 0; i < PRINTER_COUNT; i++) {
        const printer *p = &PRINTERS[i];
        const char *want = expected_z(p->format);
        char line[400], pixels[40], pitch[40], height[40];
        if (!line_starting(r.out, p->name, line, sizeof line)) {
            CHECKF(0, "%s: not listed", p->name);
            continue;
        }
        snprintf(pixels, sizeof pixels, " %d x %d ", p->width, p->height);
        snprintf(pitch, sizeof pitch, " %g", p->pitch[0] * 1000);
        snprintf(height, sizeof height, " %g ", p->z_max);
        CHECKF(strstr(line, p->format) && strstr(line, pixels) && strstr(line, pitch) && strstr(line, height), "%s: %s",
               p->name, line);
        CHECKF(want ? strstr(line, want) != NULL : !strstr(line, "not known"), "%s: %s", p->name, line);
    }
    CHECK(strstr(r.out, "#997") && strstr(r.out, "#1040") && strstr(r.out, "Saturn 4") && strstr(r.out, "Mega 8K S"));
    list = cli_run("slice", "--printer", "list", NULL);
    CHECKF(list.status == 0 && !strcmp(list.out, r.out), "slice --printer list: exit %d: %s", list.status, list.err);
    cli_free(&list);
    cli_free(&r);
    r = cli_run("printers", "extra", NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err), "exit %d: %s", r.status, r.err);
    cli_free(&r);
}

/* The table is in slice's help, a line per format. */
static void help_has_the_table(void)
{
    cli_result r = cli_run("slice", "--help", NULL);
    int i;
    CHECKF(r.status == 0, "exit %d", r.status);
    CHECK(strstr(r.out, "per-layer Z") != NULL);
    for (i = 0; JOB_FORMATS[i]; i++) {
        char start[64], line[600];
        snprintf(start, sizeof start, "  %s", JOB_FORMATS[i]->name);
        CHECKF(line_starting(r.out, start, line, sizeof line) &&
                   strstr(line, layer_z_says(layer_z_of(JOB_FORMATS[i]->name)->support)),
               "%s: no line in slice --help", JOB_FORMATS[i]->name);
    }
    CHECK(strstr(r.out, "#997") && strstr(r.out, "#1040"));
    cli_free(&r);
}

/* An adaptive slice says its printer's per-layer Z; a GOO's adds the
   advance-mode line with its risk; a uniform one says neither; an adaptive
   plan for the SL1 (one layer height) is refused with nothing written. */
static void adaptive_summaries_and_refusals(void)
{
    const char *goo = cli_path("adaptive.goo"), *ctb = cli_path("adaptive.ctb"), *sl1 = cli_path("adaptive.sl1");
    cli_result r = cli_run("slice", sphere_obj(), "--pixels", "240x240", "--pitch", "0.05", "-o", goo, NULL);
    const char *risk;
    CHECKF(r.status == 0, "exit %d: %s", r.status, r.err);
    CHECKF(strstr(r.out, "adaptive layers: per-layer Z on the display (goo): per the format, field reports of trouble\n"),
           "%s", r.out);
    risk = strstr(r.out, "advance-mode flag is on");
    CHECKF(risk && strstr(risk, "#997") && strstr(risk, "#1040") && strstr(risk, "froze") && strstr(risk, "mm high"),
           "%s", r.out);
    cli_free(&r);
    r = cli_run("slice", sphere_obj(), "--pixels", "240x240", "--pitch", "0.05", "--uniform", "0.05", "-o", goo, NULL);
    CHECKF(r.status == 0 && !strstr(r.out, "per-layer Z") && !strstr(r.out, "advance-mode"), "exit %d: %s%s", r.status,
           r.out, r.err);
    cli_free(&r);
    r = cli_run("slice", sphere_obj(), "--pixels", "240x240", "--pitch", "0.05", "-o", ctb, NULL);
    CHECKF(r.status == 0 && strstr(r.out, "per-layer Z on the display (ctb): per the format, not field-verified\n") &&
           !strstr(r.out, "advance-mode"), "exit %d: %s%s", r.status, r.out, r.err);
    cli_free(&r);
    r = cli_run("slice", sphere_obj(), "--pixels", "240x240", "--pitch", "0.05", "-o", sl1, NULL);
    CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, sl1) && strstr(r.err, "holds one layer height"),
           "exit %d: %s", r.status, r.err);
    CHECK(!cli_exists(sl1));
    cli_free(&r);
}

/* No file under `name` in the test directory, nor one beginning with it. */
static int nothing_named(const char *name)
{
    DIR *d = opendir(cli_dir);
    struct dirent *e;
    int clean = 1;
    while (d && (e = readdir(d)) != NULL)
        if (!strncmp(e->d_name, name, strlen(name))) clean = 0;
    if (d) closedir(d);
    return clean;
}

/* A part 100 m tall with no --printer: the default printer's height refuses
   it at once, in one line naming both heights and the unit to try; nothing
   is written. */
static void too_tall_for_the_default_printer(void)
{
    struct timespec t0, t1;
    cli_result r;
    double s;
    const char *tall = box_obj("tall.obj", 2, 2, 100000);
    clock_gettime(CLOCK_MONOTONIC, &t0);
    r = cli_run("slice", tall, "-o", cli_path("tall_job"), NULL);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    s = (double)(t1.tv_sec - t0.tv_sec) + (t1.tv_nsec - t0.tv_nsec) / 1e9;
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "100000 mm tall") &&
               strstr(r.err, "default printer (2k-5.5") && strstr(r.err, "builds 150 mm") && strstr(r.err, "--scale 0.001"),
           "exit %d: %s", r.status, r.err);
    CHECKF(s < 30, "refused after %.1f s", s);
    CHECK(nothing_named("tall_job"));
    cli_free(&r);
}

/* A part under a millimetre every way is most likely a model in metres: a
   one-line warning; the job is still written. A part over a metre tall on a
   display of no known height: the same for micrometres. */
static void wrong_units_warn(void)
{
    cli_result r = cli_run("slice", box_obj("tiny.obj", 0.5, 0.4, 0.3), "--pixels", "100x100", "--pitch", "0.01",
                           "--bottom-layers", "1", "-o", cli_path("tiny_job"), NULL);
    CHECKF(r.status == 0 && cli_one_message(r.err) && strstr(r.err, "warning: the part is 0.5 x 0.4 x 0.3 mm") &&
               strstr(r.err, "metres? --scale 1000") && strstr(r.err, "300 mm tall"),
           "exit %d: %s", r.status, r.err);
    cli_free(&r);
    r = cli_run("slice", box_obj("big.obj", 1, 1, 1500), "--pixels", "40x40", "--pitch", "0.1", "--uniform", "100",
                "--bin", "1", "-o", cli_path("big_job"), NULL);
    CHECKF(r.status == 0 && cli_one_message(r.err) &&
               strstr(r.err, "warning: the part is 1500 mm tall; a model in micrometres? --scale 0.001") &&
               strstr(r.err, "1.5 mm tall"),
           "exit %d: %s", r.status, r.err);
    cli_free(&r);
    r = cli_run("slice", box_obj("coin.obj", 20, 20, 0.5), "--pixels", "500x500", "--pitch", "0.05", "-o",
                cli_path("coin_job"), NULL);
    CHECKF(r.status == 0 && !*r.err, "a thin part wide enough: exit %d: %s", r.status, r.err);
    cli_free(&r);
}

/* A job that lights no pixel (a lone triangle, or a part between the
   centres of pixels a kilometre wide) is refused with the reason, and leaves
   nothing: no file, no directory, no layer. A directory that was there stays,
   emptied of the job. */
static void empty_jobs_are_refused(void)
{
    const char *tri = cli_path("tri.obj");
    static const char *const outs[] = {"empty_job", "empty_job.ctb", "empty_job.goo"};
    size_t i;
    cli_result r;
    cli_write(tri, "v 0 0 0\nv 1 0 0\nv 0 1 1\nf 1 2 3\n");
    for (i = 0; i < sizeof outs / sizeof outs[0]; i++) {
        r = cli_run("slice", tri, "--pixels", "64x64", "--pitch", "1e9", "-o", cli_path(outs[i]), NULL);
        CHECKF(r.status == 1 && strstr(r.err, "no pixel is lit in its") && strstr(r.err, "smaller than a pixel") &&
                   strstr(r.err, outs[i]),
               "%s: exit %d: %s", outs[i], r.status, r.err);
        CHECKF(!strstr(r.out, "ml of resin"), "%s: %s", outs[i], r.out);
        CHECKF(nothing_named("empty_job"), "%s: something was left behind", outs[i]);
        cli_free(&r);
    }
    /* a closed part between the pixels' centres */
    r = cli_run("slice", box_obj("small.obj", 2, 2, 2), "--pixels", "64x64", "--pitch", "1e6", "-o",
                cli_path("empty_job"), "--svg", NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "no pixel is lit"), "exit %d: %s", r.status, r.err);
    CHECKF(nothing_named("empty_job"), "the directory job was left behind");
    cli_free(&r);
    /* into a directory that was there: it stays, with what else it held
       (--force: a directory of other files and no manifest is refused without) */
    mkdir(cli_path("kept_dir"), 0777);
    cli_write(cli_path("kept_dir/notes.txt"), "mine\n");
    r = cli_run("slice", cli_path("small.obj"), "--pixels", "64x64", "--pitch", "1e6", "-o", cli_path("kept_dir"),
                "--force", NULL);
    CHECKF(r.status == 1 && strstr(r.err, "no pixel is lit"), "exit %d: %s", r.status, r.err);
    {
        DIR *d = opendir(cli_path("kept_dir"));
        struct dirent *e;
        int others = 0;
        while (d && (e = readdir(d)) != NULL)
            if (e->d_name[0] != '.' && strcmp(e->d_name, "notes.txt")) others++;
        CHECKF(d && cli_exists(cli_path("kept_dir/notes.txt")) && !others, "kept_dir: %d files of the job left", others);
        if (d) closedir(d);
    }
    cli_free(&r);
}

void test_guards(void)
{
    if (!cli_begin("adaslice-guards")) return;
    RUN(every_format_has_a_per_layer_z_row);
    RUN(printers_lists_every_preset);
    RUN(help_has_the_table);
    RUN(adaptive_summaries_and_refusals);
    RUN(too_tall_for_the_default_printer);
    RUN(wrong_units_warn);
    RUN(empty_jobs_are_refused);
    cli_end();
}
