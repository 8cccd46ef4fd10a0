/* adaslice slice end to end: every layer's exposure from the working curve
   (checked against the closed form, not the tool's code), the two-point fit,
   the one-exposure warning, and the refusals a printer owner meets (an
   unknown extension, the wrong format for a printer, a part too big or too
   tall, layers a format cannot hold, an adaptive plan for .sl1, bad exposure
   values): a one-line message, a non-zero exit and nothing written. */
#include "util.h"
#include "cli_run.h"
#include <signal.h>
#include <time.h>
#include "job_readers.h"
#include "meshgen.h"
#include "../adaslice_mcu.h"
#include "../host/formats/pipeline.h"
#include "../host/pages.h"
#include "../host/report.h"
#include <pthread.h>

/* A sphere 10 mm across: its layers are of every thickness from tmin to tmax. */
static const char *sphere_obj(void)
{
    const char *path = cli_path("sphere.obj");
    if (!cli_exists(path)) {
        adaslice_mesh m = gen_sphere(5, 64, 32, 0);
        cli_write_obj(path, &m);
        gen_free(&m);
    }
    return path;
}

typedef struct manifest_layer { double thickness, exposure; } manifest_layer;

/* The layers of DIR/manifest.json, in order; their count in *n (0: none). */
static manifest_layer *read_manifest(const char *dir, size_t *n, char **text_out)
{
    char path[600], *text, *at;
    manifest_layer *l;
    size_t k = 0, count;
    snprintf(path, sizeof path, "%s/manifest.json", dir);
    *n = 0;
    *text_out = text = read_whole_text(path);
    if (!text) return NULL;
    count = (size_t)cli_json_number(text, "layer_count");
    l = (manifest_layer *)calloc(count + 1, sizeof *l);
    for (at = strstr(text, "\"layers\": ["); at && k < count; k++) {
        if (!(at = strstr(at, "\"thickness\": "))) break;
        l[k].thickness = strtod(at + 13, &at);
        if (!(at = strstr(at, "\"exposure_s\": "))) break;
        l[k].exposure = strtod(at + 14, &at);
    }
    *n = k == count ? count : 0;
    return l;
}

/* No file or directory at path, and none beside it named like a temporary. */
static int nothing_written(const char *path)
{
    DIR *d = opendir(cli_dir);
    struct dirent *e;
    const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    int clean = !cli_exists(path);
    while (d && (e = readdir(d)) != NULL)
        if (!strncmp(e->d_name, base, strlen(base))) clean = 0;
    if (d) closedir(d);
    return clean;
}

/* --exposure S@T --penetration DP: layer k of thickness t gets
   S exp((t - T) / Dp), the bottom layers their own. */
static void exposure_follows_the_working_curve(void)
{
    const char *job = cli_path("curve");
    cli_result r = cli_run("slice", sphere_obj(), "--pixels", "240x240", "--pitch", "0.05", "-o", job, "--exposure",
                           "2@0.08", "--penetration", "0.07", "--bottom-layers", "4", "--bottom-exposure", "30", NULL);
    manifest_layer *l;
    char *text;
    size_t n, k, bad = 0;
    double lo = 1, hi = 0;
    CHECKF(r.status == 0 && !*r.err, "exit %d: %s", r.status, r.err);
    CHECK(strstr(r.out, "exposure ") && strstr(r.out, "(4 bottom layers of 30 s)"));
    cli_free(&r);
    l = read_manifest(job, &n, &text);
    CHECKF(n > 60, "%zu layers in the manifest", n);
    for (k = 0; k < n; k++) {
        double want = k < 4 ? 30 : 2 * exp((l[k].thickness - 0.08) / 0.07);
        if (fabs(l[k].exposure - want) > 1e-9 * want && bad++ < 3)
            CHECKF(0, "layer %zu, %g mm: %.9g s, the curve gives %.9g", k + 1, l[k].thickness, l[k].exposure, want);
        if (k >= 4 && l[k].thickness < lo) lo = l[k].thickness;
        if (k >= 4 && l[k].thickness > hi) hi = l[k].thickness;
    }
    /* the curve is exercised over most of [tmin, tmax] */
    CHECKF(hi - lo > 0.06, "layers of %g to %g mm only", lo, hi);
    CHECK(text && cli_json_number(text, "penetration_mm") == 0.07 && cli_json_number(text, "thickness_mm") == 0.08);
    free(l);
    free(text);
}

/* --slice-at envelope and core: the summary and the manifest name the rule;
   the resin follows the rules' nesting (core <= middle <= envelope), and on a
   sphere the envelope takes more resin than the sphere and the core less:
   every layer's envelope is its largest section, its core its smallest. */
static void slice_at_envelope_and_core(void)
{
    static const char *const rules[3] = {"core", "middle", "envelope"};
    double volume[3] = {0, 0, 0}, sphere = 0;
    int k;
    for (k = 0; k < 3; k++) {
        char name[600], *text, *at;
        const char *job;
        cli_result r;
        snprintf(name, sizeof name, "at_%s", rules[k]);
        job = cli_path(name);
        r = cli_run("slice", sphere_obj(), "--pixels", "240x240", "--pitch", "0.05", "-o", job, "--slice-at", rules[k], NULL);
        CHECKF(r.status == 0 && !*r.err, "%s: exit %d: %s", rules[k], r.status, r.err);
        snprintf(name, sizeof name, "masks %s: ", rules[k]);
        CHECKF(strstr(r.out, name) != NULL, "%s: the summary does not say the rule: %s", rules[k], r.out);
        cli_free(&r);
        snprintf(name, sizeof name, "%s/manifest.json", job);
        text = read_whole_text(name);
        CHECK(text != NULL);
        if (!text) continue;
        at = strstr(text, "\"slice_at\"");
        snprintf(name, sizeof name, "\"%s\"", rules[k]);
        CHECKF(at && strstr(at, name) && strstr(at, name) - at < 16, "%s: the manifest's slice_at", rules[k]);
        volume[k] = cli_json_number(text, "volume_mm3");
        free(text);
    }
    {   /* the 64 x 32 sphere's own volume, from its triangles */
        adaslice_mesh m = gen_sphere(5, 64, 32, 0);
        size_t t;
        for (t = 0; t < m.triangle_count; t++) {
            const float *a = m.vertices + 3 * m.triangles[3 * t], *b = m.vertices + 3 * m.triangles[3 * t + 1],
                        *c = m.vertices + 3 * m.triangles[3 * t + 2];
            sphere += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                       a[2] * (b[0] * c[1] - b[1] * c[0])) / 6;
        }
        gen_free(&m);
    }
    CHECKF(volume[0] < volume[1] && volume[1] < volume[2], "resin: core %g, middle %g, envelope %g mm^3", volume[0],
           volume[1], volume[2]);
    CHECKF(volume[0] < sphere && sphere < volume[2], "sphere %g mm^3, core %g, envelope %g", sphere, volume[0], volume[2]);
    CHECKF(fabs(volume[1] - sphere) < 0.01 * sphere, "middle %g mm^3, sphere %g", volume[1], sphere);
    printf("  (sphere %.1f mm^3: core %.1f, middle %.1f, envelope %.1f)\n", sphere, volume[0], volume[1], volume[2]);
}

/* Two calibrated points: Dp = (t2 - t1) / ln(s2 / s1), and the curve passes
   through both. */
static void two_points_fit_the_penetration(void)
{
    const char *job = cli_path("fit");
    cli_result r = cli_run("slice", sphere_obj(), "--pixels", "240x240", "--pitch", "0.05", "-o", job, "--exposure",
                           "1.8@0.05,3@0.1", NULL);
    manifest_layer *l;
    char *text;
    size_t n, k, bad = 0;
    double dp = 0.05 / log(3 / 1.8);
    CHECKF(r.status == 0 && !*r.err, "exit %d: %s", r.status, r.err);
    cli_free(&r);
    l = read_manifest(job, &n, &text);
    CHECK(n > 0 && text);
    if (text) CHECKF(fabs(cli_json_number(text, "penetration_mm") - dp) < 1e-12, "Dp %.12g, want %.12g",
                     cli_json_number(text, "penetration_mm"), dp);
    for (k = 3; k < n; k++) {
        double want = 1.8 * exp((l[k].thickness - 0.05) / dp);
        if (fabs(l[k].exposure - want) > 1e-9 * want && bad++ < 3) CHECKF(0, "layer %zu: %.9g s, want %.9g", k + 1, l[k].exposure, want);
    }
    CHECK(fabs(1.8 * exp(0.05 / dp) - 3) < 1e-12);
    free(l);
    free(text);
}

/* One exposure for layers of many thicknesses: the job is written, with a
   warning naming the thickest layer and its dose. */
static void one_exposure_for_adaptive_layers_warns(void)
{
    const char *job = cli_path("plain");
    cli_result r = cli_run("slice", sphere_obj(), "--pixels", "240x240", "--pitch", "0.05", "-o", job, "--exposure", "2.5",
                           NULL);
    manifest_layer *l;
    char *text;
    size_t n, k, same = 1;
    CHECKF(r.status == 0 && cli_one_message(r.err) && strstr(r.err, "warning") && strstr(r.err, "layer ") &&
               strstr(r.err, "x the dose"),
           "exit %d: %s", r.status, r.err);
    cli_free(&r);
    l = read_manifest(job, &n, &text);
    for (k = 3; k < n; k++) same &= l[k].exposure == 2.5;
    CHECK(n > 0 && same);
    free(l);
    free(text);
}

/* Bad exposure and motion values: exit 2, one line naming the option, and
   no job. */
static void bad_exposure_values_exit_2(void)
{
    static const char *const cases[][3] = {
        {"--penetration", "0", "--penetration"},
        {"--penetration", "-0.1", "--penetration"},
        {"--exposure", "0", "not a positive exposure"},
        {"--exposure", "-2", "--exposure"},
        {"--exposure", "2@0.5", "outside tmin"},
        {"--exposure", "2@0.01", "outside tmin"},
        {"--exposure", "3@0.05,2@0.1", "thicker layer must need the longer"},
        {"--exposure", "2@0.06,3@0.06", "thicker layer must need the longer"},
        {"--exposure", "2@0.06,", "expected S"},
        {"--exposure", "two", "expected S"},
        {"--bottom-exposure", "0", "--bottom-exposure"},
        {"--peel-speed", "0", "--peel-speed"},
        {"--exposure", "4000", "exposures are 0.001 to 3600 s"},
        {"--exposure", "1@0.05,60@0.06", "exposures are 0.001 to 3600 s"},
        {"--exposure", "0.0001", "exposures are 0.001 to 3600 s"},
        {"--penetration", "0.001", "exposures are 0.001 to 3600 s"},
    };
    char job[256], model[256];
    size_t c;
    snprintf(job, sizeof job, "%s", cli_path("bad"));
    snprintf(model, sizeof model, "%s", sphere_obj());
    for (c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        cli_result r = cli_run("slice", model, "--pixels", "240x240", "--pitch", "0.05", "-o", job, cases[c][0],
                               cases[c][1], NULL);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, cases[c][2]), "%s %s: exit %d: %s", cases[c][0],
               cases[c][1], r.status, r.err);
        CHECKF(nothing_written(job), "%s %s left %s behind", cases[c][0], cases[c][1], job);
        cli_free(&r);
    }
    {   /* --penetration beside two points is one Dp too many */
        cli_result r = cli_run("slice", model, "-o", job, "--exposure", "1.8@0.05,3@0.1", "--penetration", "0.1", NULL);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "one or the other"), "%d %s", r.status, r.err);
        CHECK(nothing_written(job));
        cli_free(&r);
    }
}

/* What a format or a printer cannot take is refused before a byte is
   written: the message names the file and what is wrong. */
static void refusals_leave_nothing_behind(void)
{
    char model[256];
    struct { const char *out, *args[10], *says; int status; } cases[] = {
        {"job.pwmx", {NULL}, ".pwmx is no job format's extension", 2},
        {"job.goo", {"--printer", "elegoo-saturn", NULL}, "reads ctb jobs, not goo", 2},
        {"job.ctb", {"--printer", "elegoo-mars-3", "--format", "ctb", NULL}, "reads ctb-encrypted jobs, not ctb", 2},
        {"job.goo", {"--printer", "phrozen-sonic-mini-8k-s", NULL}, "reads prz jobs, not goo", 2},
        {"job.sl1", {"--printer", "prusa-sl1s", NULL}, "--uniform T", 2},
        {"job.sl1", {"--pixels", "240x240", "--pitch", "0.05", NULL}, "holds one layer height", 2},
        {"job.zip", {"--pixels", "240x240", "--pitch", "0.05", "--uniform", "0.0005", "--bin", "0.0005", NULL},
         "is 0.0005 mm thick", 2},
        {"job.ctb", {"--pixels", "240x240", "--pitch", "0.05", "--uniform", "0.0005", "--bin", "0.0005", NULL},
         "is 0.0005 mm thick", 2},
        {"job.ctb", {"--printer", "elegoo-saturn", "--scale", "25", NULL}, "mm tall: the elegoo-saturn builds 200 mm", 1},
        {"job.ctb", {"--printer", "elegoo-saturn", "--scale", "15", NULL}, "does not fit the 192 x 120 mm plate: 30 mm too wide along y", 1},
        {"job.ctb", {"--printer", "elegoo-saturn", "--place", "0,60", NULL}, "overhangs the 192 x 120 mm plate by 5 mm along y", 1},
        {"job", {"--format", "pwmx", NULL}, "--format pwmx: unknown", 2},
        {"job.goo", {"--pixels", "240x240", "--pitch", "0.05", "--svg", NULL}, "--svg writes into a job directory", 2},
        {"job.goo", {NULL}, "which printer?", 2},
        {"job", {"--pixels", "65536x65536", "--pitch", "0.001", NULL}, "a 65536 x 65536 px grid at --aa 1 needs", 2},
        {"job.ctb", {"--pixels", "3840x2400", "--pitch", "0.05", "--aa", "4", "--memory", "100", NULL},
         "more than --memory 100 MB", 2},
        /* on two threads the masker is set up beside the profile and the
           plan, and the previews drawn: their failures leave nothing of it
           (the sanitizers' leak check), the previews' thread is joined before
           the mesh it reads is freed, and they say one line */
        {"job", {"--eps", "0.000001", "--tmin", "0.05", "--threads", "2", NULL}, "eps 1e-06 is too small", 1},
        {"job", {"--bin", "0.000001", "--memory", "100", "--threads", "2", NULL}, "more than --memory 100 MB", 1},
    };
    size_t c;
    snprintf(model, sizeof model, "%s", sphere_obj());
    for (c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const char *out = cli_path(cases[c].out), **a = cases[c].args;
        cli_result r = cli_run("slice", model, "-o", out, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], NULL);
        CHECKF(r.status == cases[c].status && cli_one_message(r.err) && strstr(r.err, cases[c].says), "%s %s: exit %d: %s", cases[c].out,
               a[0] ? a[0] : "", r.status, r.err);
        if (!strstr(cases[c].says, "does not fit") && !strstr(cases[c].says, "overhangs") && !strstr(cases[c].says, "tall") &&
            !strstr(cases[c].says, "grid") && !strstr(cases[c].says, "eps") &&
            !strstr(cases[c].says, "--memory"))
            CHECKF(strstr(r.err, out) || strstr(r.err, "--format") || strstr(r.err, "--svg"), "the message does not name %s: %s",
                   out, r.err);
        CHECKF(nothing_written(out), "%s: something was left behind", cases[c].out);
        cli_free(&r);
    }
}

/* ------------------------------------------- the formats against the masks */

typedef struct dir_masks {
    uint32_t width, height, bits, layers;
    unsigned char **grey;        /* per layer, width x height, 0..255 */
} dir_masks;

static void grey_row(void *ctx, uint32_t y, const unsigned char *row)
{
    dir_masks *m = (dir_masks *)((void **)ctx)[0];
    unsigned char *out = (unsigned char *)((void **)ctx)[1] + (size_t)y * m->width;
    uint32_t x;
    for (x = 0; x < m->width; x++) out[x] = m->bits == 8 ? row[x] : (row[x >> 3] >> (7 - (x & 7)) & 1) ? 255 : 0;
}

static uint32_t le32(const unsigned char *p) { return p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }

/* DIR/masks.rle as jobdir.h lays it out, every layer decoded (its CRC held
   against the masker's, which the file carries). */
static int read_dir_masks(const char *dir, dir_masks *m)
{
    char path[600];
    size_t size = 0, at = 44;
    unsigned char *f, row[8192];
    uint32_t k;
    FILE *in;
    long n;
    memset(m, 0, sizeof *m);
    snprintf(path, sizeof path, "%s/masks.rle", dir);
    if (!(in = fopen(path, "rb"))) return 0;
    fseek(in, 0, SEEK_END);
    n = ftell(in);
    fseek(in, 0, SEEK_SET);
    f = (unsigned char *)malloc((size_t)n);
    if (f) size = fread(f, 1, (size_t)n, in);
    fclose(in);
    if (!f || size < 44 || memcmp(f, "ADASMSK2", 8)) { free(f); return 0; }
    m->width = le32(f + 8);
    m->height = le32(f + 12);
    m->bits = le32(f + 16);
    m->layers = le32(f + 20);
    m->grey = (unsigned char **)calloc(m->layers, sizeof *m->grey);
    for (k = 0; k < m->layers && at + 16 <= size; k++) {
        adaslice_rle_decoder dec;
        uint32_t crc = le32(f + at + 8), code = le32(f + at + 12);
        void *ctx[2];
        m->grey[k] = (unsigned char *)malloc((size_t)m->width * m->height);
        ctx[0] = m;
        ctx[1] = m->grey[k];
        CHECK(adaslice_rle_decoder_init(&dec, m->width, m->height, (int)m->bits, row, sizeof row) == ADASLICE_OK);
        CHECKF(at + 16 + code <= size && adaslice_rle_decode(&dec, f + at + 16, code, grey_row, ctx) == ADASLICE_OK &&
                   adaslice_rle_finished(&dec) && ADASLICE_RLE_CRC(&dec) == crc,
               "masks.rle: layer %u does not decode to its CRC", k + 1);
        at += 16 + code;
    }
    free(f);
    return k == m->layers && !check_case_failed();
}

static void dir_masks_free(dir_masks *m)
{
    uint32_t k;
    for (k = 0; m->grey && k < m->layers; k++) free(m->grey[k]);
    free(m->grey);
}


/* One model, one display, sliced as a directory and as each resin file: the
   file's reader (tests/job_readers.c, from the formats' documentation) finds
   every layer's Z and exposure as the manifest has them and every pixel of
   the masker's mask; 1-bit and anti-aliased, on oblong pixels. The .prz,
   a GOO file, has no diff chunk in any layer, which the anti-aliased .goo
   has (so the reader is seen to count them). */
static void resin_files_hold_the_directory_jobs_masks(void)
{
    static const char *const formats[] = {"ctb", "goo", "ctb-encrypted", "prz"};
    const char *aa[2] = {"1", "4"};
    int pass, f;
    char model[256];
    snprintf(model, sizeof model, "%s", sphere_obj());
    for (pass = 0; pass < 2; pass++) {
        char dir[256], *text;
        dir_masks m;
        manifest_layer *l;
        size_t n, k;
        cli_result r;
        snprintf(dir, sizeof dir, "%s", cli_path(pass ? "aa_dir" : "bw_dir"));
#define SAME_JOB "--pixels", "300x250", "--pitch", "0.05,0.06", "--aa", aa[pass], "--exposure", "2@0.08", "--penetration", "0.07"
        r = cli_run("slice", model, "-o", dir, SAME_JOB, NULL);
        CHECKF(r.status == 0, "directory: %s", r.err);
        cli_free(&r);
        l = read_manifest(dir, &n, &text);
        free(text);
        if (!read_dir_masks(dir, &m) || m.layers != n || n < 50) { CHECKF(0, "%s: %u masks, %zu layers", dir, m.layers, n); free(l); dir_masks_free(&m); return; }
        CHECK(m.width == 300 && m.height == 250 && m.bits == (pass ? 8u : 1u));
        for (f = 0; f < 4; f++) {
            static const char *const ext[] = {"ctb", "goo", "ctb", "prz"};
            int goo = f == 1 || f == 3;   /* .prz is a GOO file */
            char out[300];
            unsigned char *data;
            size_t size, bad_z = 0, bad_px = 0;
            unsigned long long diffs = 0;
            jr_job job;
            snprintf(out, sizeof out, "%s/job_%s.%s", cli_dir, formats[f], ext[f]);
            r = cli_run("slice", model, "-o", out, "--format", formats[f], SAME_JOB, NULL);
            CHECKF(r.status == 0, "%s: %s", out, r.err);
            cli_free(&r);
            data = read_whole_file(out, &size);
            if (!data || (f == 0 ? jr_read_ctb(data, size, &job)
                          : goo  ? jr_read_goo(data, size, &job)
                                 : jr_read_ctb_encrypted(data, size, &job)) != 0) {
                CHECKF(0, "%.200s: the reader refuses it: %.200s", out, data ? job.error : "no file");
                free(data);
                continue;
            }
            CHECKF(job.width == 300 && job.height == 250 && job.layer_count == n, "%s: %d x %d, %u layers", out, job.width,
                   job.height, job.layer_count);
            CHECKF(fabs(job.bed_mm[0] - 15) < 1e-4 && fabs(job.bed_mm[1] - 15) < 1e-4, "%s: display %g x %g mm", out,
                   job.bed_mm[0], job.bed_mm[1]);
            /* the ctb's layers are coded with a key, as UVtools codes them
               (sn4k3/UVtools @7b510f0d ChituboxFile.cs:1786-1789), and read
               below through it; adaptive layers need the goo's advance mode
               (GooFile.cs:1205) */
            if (f == 0) CHECKF(job.ctb_encryption_key != 0, "%s: EncryptionKey 0", out);
            else if (goo) CHECKF(job.per_layer_raw == 1, "%s: advance mode %u for adaptive layers", out, job.per_layer_raw);
            else CHECKF(job.per_layer_raw == 0x40, "%s: per-layer settings 0x%x for adaptive layers", out, job.per_layer_raw);
            for (k = 0; k < n && k < job.layer_count; k++) {
                const jr_layer *L = &job.layers[k];
                double top = 0;
                size_t i, q, px = (size_t)m.width * m.height;
                for (q = 0; q <= k; q++) top += l[q].thickness;
                if ((fabs(L->z_mm - top) > 2e-5 || fabs(L->exposure_s - l[k].exposure) > 1e-5 * l[k].exposure) && bad_z++ < 3)
                    CHECKF(0, "%s layer %zu: z %.6f, exposure %.6f; the manifest: %.6f, %.6f", out, k + 1, L->z_mm, L->exposure_s,
                           top, l[k].exposure);
                for (i = 0; i < px; i++) {
                    unsigned char want = !goo ? jr_ctb_grey(m.grey[k][i]) : m.grey[k][i];
                    if (L->image[i] != want) { if (bad_px++ < 3) CHECKF(0, "%s layer %zu pixel %zu: %u, the mask %u", out, k + 1, i, L->image[i], want); break; }
                }
                if (f == 3) CHECKF(L->diff_chunks == 0, "%s layer %zu: %llu diff chunks", out, k + 1, L->diff_chunks);
                diffs += L->diff_chunks;
            }
            if (f == 1 && pass) CHECKF(diffs > 0, "%s: no diff chunk in an anti-aliased .goo", out);
            jr_free(&job);
            free(data);
        }
#undef SAME_JOB
        dir_masks_free(&m);
        free(l);
    }
}

/* -o job.ctb for a printer that reads only the encrypted CTB writes that:
   the Saturn 4 Ultra's display and build height, its name, mirrored across,
   every layer's own Z and exposure as the plan has them (the plan is the
   model's, the same on any display: the manifest of a small directory job
   gives them), and every layer's code covering its 11520 x 5120 pixels
   exactly (the images are too large to keep). */
static void ctb_for_an_encrypted_ctb_printer(void)
{
    char model[256], out[300], dir[300], *text;
    unsigned char *data;
    size_t size, n = 0, k, bad = 0;
    manifest_layer *l;
    jr_job job;
    cli_result r;
    double top = 0, thinnest = 1, thickest = 0;
    snprintf(model, sizeof model, "%s", sphere_obj());
    snprintf(out, sizeof out, "%s/s4u.ctb", cli_dir);
    snprintf(dir, sizeof dir, "%s/s4u_plan", cli_dir);
    r = cli_run("slice", model, "--scale", "0.4", "--printer", "elegoo-saturn-4-ultra", "-o", out, NULL);
    CHECKF(r.status == 0 && strstr(r.out, "(ctb-encrypted)"), "%s: %s%s", out, r.out, r.err);
    cli_free(&r);
    r = cli_run("slice", model, "--scale", "0.4", "--pixels", "100x100", "--pitch", "0.05", "-o", dir, NULL);
    CHECKF(r.status == 0, "%s: %s", dir, r.err);
    cli_free(&r);
    l = read_manifest(dir, &n, &text);
    free(text);
    data = read_whole_file(out, &size);
    if (!data || jr_read_ctb_encrypted_ex(data, size, &job, JR_SKIP_IMAGES | JR_SKIP_PREVIEWS) != 0) {
        CHECKF(0, "%.200s: the reader refuses it: %.200s", out, data ? job.error : "no file");
        free(data);
        free(l);
        return;
    }
    CHECKF(job.magic == 0x12FD0107u && job.version == 5 && job.width == 11520 && job.height == 5120 && job.mirror == 1 &&
               !strcmp(job.machine_name, "ELEGOO SATURN 4 ULTRA"),
           "%s: 0x%08X v%u, %d x %d, mirror %d, \"%s\"", out, job.magic, job.version, job.width, job.height, job.mirror,
           job.machine_name);
    CHECKF(fabs(job.bed_mm[0] - 218.88) < 1e-4 && fabs(job.bed_mm[1] - 122.88) < 1e-4 && job.bed_mm[2] == 220,
           "%s: %g x %g x %g mm", out, job.bed_mm[0], job.bed_mm[1], job.bed_mm[2]);
    CHECKF(n > 10 && job.layer_count == n && job.per_layer_raw == 0x40 && job.bottom_layers == 3, "%s: %u layers, the plan %zu",
           out, job.layer_count, n);
    for (k = 0; k < n && k < job.layer_count; k++) {
        const jr_layer *L = &job.layers[k];
        top += l[k].thickness;
        if (l[k].thickness < thinnest) thinnest = l[k].thickness;
        if (l[k].thickness > thickest) thickest = l[k].thickness;
        if ((fabs(L->z_mm - top) > 2e-5 || fabs(L->exposure_s - l[k].exposure) > 1e-5 * l[k].exposure) && bad++ < 3)
            CHECKF(0, "%s layer %zu: z %.6f, exposure %.6f; the plan: %.6f, %.6f", out, k + 1, L->z_mm, L->exposure_s, top,
                   l[k].exposure);
    }
    CHECKF(thickest > thinnest + 0.02, "layers of %g to %g mm: not an adaptive plan", thinnest, thickest);
    CHECK(fabs(job.total_height_mm - top) < 2e-5);
    jr_free(&job);
    free(data);
    free(l);
}

/* The same job twice is the same bytes, given SOURCE_DATE_EPOCH for the
   headers' dates. */
static void jobs_are_reproducible(void)
{
    static const char *const ext[] = {"ctb", "goo", "zip", "sl1", "ctb", "prz", "uvj"};
    static const char *const format[] = {"ctb", "goo", "chitu-zip", "sl1", "ctb-encrypted", "prz", "uvj"};
    char model[256];
    int f;
    snprintf(model, sizeof model, "%s", sphere_obj());
    setenv("SOURCE_DATE_EPOCH", "1700000000", 1);
    for (f = 0; f < (int)(sizeof ext / sizeof ext[0]); f++) {
        char a[300], b[400], dir_b[200];
        unsigned char *x, *y;
        size_t nx, ny;
        cli_result r;
        snprintf(a, sizeof a, "%s/same_%s.%s", cli_dir, format[f], ext[f]);
        snprintf(dir_b, sizeof dir_b, "%s/again", cli_dir);
        mkdir(dir_b, 0755);
        snprintf(b, sizeof b, "%s/same_%s.%s", dir_b, format[f], ext[f]);
        r = cli_run("slice", model, "--pixels", "300x250", "--pitch", "0.05", "--uniform", "0.05", "--format", format[f], "-o",
                    a, NULL);
        CHECKF(r.status == 0, "%s: %s", a, r.err);
        cli_free(&r);
        r = cli_run("slice", model, "--pixels", "300x250", "--pitch", "0.05", "--uniform", "0.05", "--format", format[f], "-o",
                    b, NULL);
        CHECKF(r.status == 0, "%s: %s", b, r.err);
        cli_free(&r);
        x = read_whole_file(a, &nx);
        y = read_whole_file(b, &ny);
        CHECKF(x && y && nx == ny && !memcmp(x, y, nx), "%s: two runs differ", format[f]);
        free(x);
        free(y);
    }
    unsetenv("SOURCE_DATE_EPOCH");
}

/* Every file of directory a is in b with the same bytes, and b has no more;
   what differs in *what. */
static int same_directories(const char *a, const char *b, char what[300])
{
    DIR *d = opendir(a);
    struct dirent *e;
    size_t files = 0, others = 0;
    int same = d != NULL;
    snprintf(what, 300, "%s: cannot read", a);
    while (same && (e = readdir(d)) != NULL) {
        char x[600], y[600];
        unsigned char *p, *q;
        size_t np = 0, nq = 0;
        if (e->d_name[0] == '.') continue;
        snprintf(x, sizeof x, "%s/%s", a, e->d_name);
        snprintf(y, sizeof y, "%s/%s", b, e->d_name);
        p = read_whole_file(x, &np);
        q = read_whole_file(y, &nq);
        same = p && q && np == nq && !memcmp(p, q, np);
        if (!same) snprintf(what, 300, "%s differs", e->d_name);
        files++;
        free(p);
        free(q);
    }
    if (d) closedir(d);
    for (d = same ? opendir(b) : NULL; d && (e = readdir(d)) != NULL;) others += e->d_name[0] != '.';
    if (d) closedir(d);
    if (same && others != files) { snprintf(what, 300, "%zu files against %zu", others, files); same = 0; }
    return same && files > 0;
}

/* Any number of threads writes the same job as one, byte for byte: each step
   of the pipeline (a row band of a layer, coding, putting) may run on any
   thread. Two models (the sphere and the bundled hand), 1-bit and --aa 4
   masks on a grid of odd width and height, 2, 3 and 8 threads (16, 24 and
   64 bands; bands of a few rows at 8), a job
   directory (every file) and a ctb; the directory re-sliced over a job with
   more and larger layers (its layer files are written over in place) is the
   same as well. */
/* The layer loop's promise (pipeline.c): a thread held inside a band, as a
   descheduled one is, holds up only that band. Band 0 of layer 0 is held
   until the other thread has rendered every other band of as many layers as
   there are images (a layer keeps its image until all its bands are in):
   were the other waiting on it, the hold would time out (after a minute,
   where the renders take microseconds). Then the job goes on to the end:
   each band's layers in turn, each layer once, put in order. */
enum { HOLD_LAYERS = 24, HOLD_BANDS_MAX = 64 };

typedef struct hold_run {
    pthread_mutex_t lock;
    pthread_cond_t change;
    int bands, others, reached, target;
    size_t next[HOLD_BANDS_MAX], put;
    int in_order;
} hold_run;

static int hold_render(void *ctx, int b, size_t k, unsigned char *image, mask_band *rows)
{
    hold_run *h = (hold_run *)ctx;
    pthread_mutex_lock(&h->lock);
    if (b < 0 || b >= h->bands || h->next[b] != k) h->in_order = 0;
    if (b >= 0 && b < h->bands) h->next[b] = k + 1;
    if (b == 0 && k == 0) {
        struct timespec until;
        clock_gettime(CLOCK_REALTIME, &until);
        until.tv_sec += 60;
        while (h->others < h->target)
            if (pthread_cond_timedwait(&h->change, &h->lock, &until) != 0) break;
        h->reached = h->others;
    } else {
        h->others++;
        pthread_cond_broadcast(&h->change);
    }
    pthread_mutex_unlock(&h->lock);
    image[0] = (unsigned char)k;
    if (rows) h->in_order = 0; /* not asked for */
    return RC_OK;
}

static int hold_encode(const void *writer, size_t k, const unsigned char *image, size_t stride, job_blob *blob)
{
    (void)writer;
    (void)stride;
    if (!(blob->data = (unsigned char *)malloc(1))) return RC_FAIL;
    blob->data[0] = (unsigned char)(image[0] == (unsigned char)k);
    blob->size = 1;
    return RC_OK;
}

static int hold_put(void *writer, size_t k, job_blob *blob)
{
    hold_run *h = (hold_run *)writer;
    if (k != h->put++ || !blob->data[0]) h->in_order = 0;
    free(blob->data);
    blob->data = NULL;
    return RC_OK;
}

/* The host's large blocks (the masker's, the repair's, the layer images)
   start on a 2 MB boundary from 1 MB up, so that their pages can be huge
   ones; smaller blocks are malloc's. Each holds its bytes (under
   AddressSanitizer a short block fails here). */
static void large_blocks_start_on_huge_pages(void)
{
    static const size_t sizes[] = {0, 1, 4096, (1u << 20) - 1, 1u << 20, (2u << 20) + 1, 5u << 20};
    size_t i;
    for (i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        unsigned char *p = (unsigned char *)pages_alloc(sizes[i]);
        CHECKF(p != NULL, "pages_alloc(%zu) failed", sizes[i]);
        if (!p) continue;
        memset(p, 0xa5, sizes[i]);
        if (sizes[i] >= 1u << 20) CHECKF((uintptr_t)p % (2u << 20) == 0, "a block of %zu bytes at %p", sizes[i], (void *)p);
        if (sizes[i]) CHECK(p[sizes[i] - 1] == 0xa5);
        free(p);
    }
    CHECK(pages_allocator()->alloc && pages_allocator()->free && !pages_allocator()->user);
}

static void a_held_band_holds_up_only_itself(void)
{
    job_format format;
    job_desc d;
    job_writer out;
    pipeline_job job;
    hold_run h;
    int b;
    memset(&format, 0, sizeof format);
    memset(&d, 0, sizeof d);
    memset(&out, 0, sizeof out);
    memset(&job, 0, sizeof job);
    memset(&h, 0, sizeof h);
    format.name = "held";
    format.encode = hold_encode;
    format.put = hold_put;
    d.layer_count = HOLD_LAYERS;
    out.format = &format;
    out.state = &h;
    out.d = &d;
    out.path = "held";
    pthread_mutex_init(&h.lock, NULL);
    pthread_cond_init(&h.change, NULL);
    h.bands = pipeline_bands(2);
    h.target = pipeline_images(2) * (h.bands - 1);
    h.in_order = 1;
    CHECK(h.bands > 2 && h.bands <= HOLD_BANDS_MAX && pipeline_images(2) < HOLD_LAYERS);
    job.out = &out;
    job.layers = HOLD_LAYERS;
    job.image_bytes = job.stride = 1;
    job.threads = 2;
    job.bands = h.bands;
    job.render = hold_render;
    job.ctx = &h;
    CHECK(pipeline_run(&job) == RC_OK);
    CHECKF(h.reached == h.target, "the other thread rendered %d bands while band 0 of layer 0 was held, not %d",
           h.reached, h.target);
    CHECK(h.in_order);
    CHECK(h.put == HOLD_LAYERS && out.layers_put == HOLD_LAYERS);
    for (b = 0; b < h.bands; b++) CHECK(h.next[b] == HOLD_LAYERS);
    pthread_cond_destroy(&h.change);
    pthread_mutex_destroy(&h.lock);
}

/* A mesh whose edges do not all balance is masked by its sections, whose
   gaps the masker closes, not by rays, which cannot tell inside from
   outside there (the host tells the masker that edges balance only when the
   repair found none open): a box without its bottom, whose rays meet only
   its top, gives the closed box's masks. */
static void an_open_mesh_is_masked_by_its_sections(void)
{
    static const char *const threads[] = {"1", "2"};
    char path[2][300], job[2][300], what[400];
    adaslice_mesh box[2];
    int k, t;
    for (k = 0; k < 2; k++) {
        box[k] = gen_box(0, 0, 0, 6.013, 5.021, 4); /* no edge through a pixel's centre */
        snprintf(path[k], sizeof path[k], "%s/%s.obj", cli_dir, k ? "bottomless" : "box");
        snprintf(job[k], sizeof job[k], "%s/%s_job", cli_dir, k ? "bottomless" : "box");
    }
    /* gen_box's first two facets are its bottom */
    memmove(box[1].triangles, box[1].triangles + 6, (box[1].triangle_count - 2) * 3 * sizeof *box[1].triangles);
    box[1].triangle_count -= 2;
    for (k = 0; k < 2; k++) {
        cli_write_obj(path[k], &box[k]);
        gen_free(&box[k]);
    }
    for (t = 0; t < 2; t++) {
        for (k = 0; k < 2; k++) {
            cli_result r = cli_run("slice", path[k], "--uniform", "0.5", "--pixels", "301x253", "--pitch", "0.05",
                                   "--threads", threads[t], "-o", job[k], NULL);
            CHECKF(r.status == 0 && (!k || strstr(r.err, "open edges")), "%s: %s", path[k], r.err);
            cli_free(&r);
        }
        for (k = 1; k <= 8; k++) {
            char name[40], a[400], b[400];
            unsigned char *p, *q;
            size_t np = 0, nq = 0;
            snprintf(name, sizeof name, "layer_%05d.png", k);
            snprintf(a, sizeof a, "%s/%s", job[0], name);
            snprintf(b, sizeof b, "%s/%s", job[1], name);
            p = read_whole_file(a, &np);
            q = read_whole_file(b, &nq);
            CHECKF(p && q && np == nq && !memcmp(p, q, np), "--threads %s: %s of the bottomless box differs from the box's",
                   threads[t], name);
            free(p);
            free(q);
        }
        snprintf(what, sizeof what, "%s/layer_00009.png", job[1]);
        CHECKF(access(what, F_OK) != 0, "%s: more layers than the box's 8", what);
    }
}

/* mesh written to NAME in the test's directory, sliced on one thread (its
   repair's warning saying `warned`) and on `threads`: the same job. */
static void same_job_on_threads(const adaslice_mesh *mesh, const char *name, const char *warned, const char *threads)
{
    char path[300], one[300], many[300], what[300];
    cli_result r;
    snprintf(path, sizeof path, "%s/%s", cli_dir, name);
    snprintf(one, sizeof one, "%s/one", cli_dir);
    snprintf(many, sizeof many, "%s/many", cli_dir);
    cli_write_obj(path, mesh);
    r = cli_run("slice", path, "--pixels", "301x253", "--pitch", "0.05", "--threads", "1", "-o", one, NULL);
    CHECKF(r.status == 0 && strstr(r.err, warned), "%s: %s", name, r.err);
    cli_free(&r);
    r = cli_run("slice", path, "--pixels", "301x253", "--pitch", "0.05", "--threads", threads, "-o", many, NULL);
    CHECKF(r.status == 0, "%s: %s", name, r.err);
    cli_free(&r);
    CHECKF(same_directories(one, many, what), "%s on %s threads: %s", name, threads, what);
}

static void threads_write_the_same_job(void)
{
    static const char *const aa[] = {"1", "4"}, *const threads[] = {"2", "3", "8"};
    char models[2][256], one[300], many[300], what[300];
    int m, a, t;
    snprintf(models[0], sizeof models[0], "%s", sphere_obj());
    snprintf(models[1], sizeof models[1], "examples/models/hand_closed.obj");
    snprintf(one, sizeof one, "%s/one", cli_dir);
    snprintf(many, sizeof many, "%s/many", cli_dir);
    setenv("SOURCE_DATE_EPOCH", "1700000000", 1);
    for (m = 0; m < 2; m++)
        for (a = 0; a < 2; a++) {
            const char *scale = m ? "12" : "1";
            cli_result r = cli_run("slice", models[m], "--scale", scale, "--pixels", "301x253", "--pitch", "0.05",
                                   "--aa", aa[a], "--threads", "1", "-o", one, NULL);
            CHECKF(r.status == 0, "%s: %s", models[m], r.err);
            cli_free(&r);
            for (t = 0; t < 3; t++) {
                r = cli_run("slice", models[m], "--scale", scale, "--pixels", "301x253", "--pitch", "0.05", "--aa", aa[a],
                            "--threads", threads[t], "-o", many, NULL);
                CHECKF(r.status == 0, "%s: %s", models[m], r.err);
                cli_free(&r);
                CHECKF(same_directories(one, many, what), "%s --aa %s --threads %s: %s", models[m], aa[a], threads[t], what);
            }
        }
    /* an open mesh (a box without one side), which keeps one masker: its gaps' chords need whole sections */
    {
        adaslice_mesh box = gen_box(0, 0, 0, 6, 5, 4);
        box.triangle_count -= 2; /* gen_box's last two facets: its side at x = 6 */
        same_job_on_threads(&box, "open_box.obj", "open edges", "3");
        gen_free(&box);
    }
    /* a box whose top is cracked off by 10^-4 mm, which the repair welds
       (moving vertices) */
    {
        static const int quads[6][4] = {
            {0, 2, 3, 1}, {8, 9, 11, 10}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
        adaslice_mesh box = gen_alloc(12, 12);
        int i;
        for (i = 0; i < 12; i++) { /* 8-11: the top's corners 4-7 again, moved */
            int c = i < 8 ? i : i - 4;
            gen_vertex(&box, ((c & 1) ? 6 : 0) + (i >= 8) * 1e-4, (c & 2) ? 5 : 0, (c & 4) ? 4 : 0);
        }
        for (i = 0; i < 6; i++) {
            gen_triangle(&box, (uint32_t)quads[i][0], (uint32_t)quads[i][1], (uint32_t)quads[i][2]);
            gen_triangle(&box, (uint32_t)quads[i][0], (uint32_t)quads[i][2], (uint32_t)quads[i][3]);
        }
        same_job_on_threads(&box, "cracked_box.obj", "vertices of cracks welded", "2");
        gen_free(&box);
    }
    /* over the hand's --aa 4 job in `many`: the sphere's 1-bit layers, fewer and smaller */
    {
        cli_result r = cli_run("slice", models[0], "--pixels", "301x253", "--pitch", "0.05", "--threads", "1", "-o", one, NULL);
        CHECKF(r.status == 0, "%s", r.err);
        cli_free(&r);
        r = cli_run("slice", models[0], "--pixels", "301x253", "--pitch", "0.05", "--threads", "2", "-o", many, NULL);
        CHECKF(r.status == 0, "%s", r.err);
        cli_free(&r);
        CHECKF(same_directories(one, many, what), "re-sliced over a larger job: %s", what);
    }
    for (a = 0; a < 2; a++) {
        char x[320], y[320];
        unsigned char *p, *q;
        size_t np = 0, nq = 0;
        cli_result r;
        snprintf(x, sizeof x, "%s/one.ctb", cli_dir);
        snprintf(y, sizeof y, "%s/many.ctb", cli_dir);
        r = cli_run("slice", models[1], "--scale", "12", "--pixels", "301x253", "--pitch", "0.05", "--aa", aa[a],
                    "--threads", "1", "-o", x, NULL);
        CHECKF(r.status == 0, "%s", r.err);
        cli_free(&r);
        r = cli_run("slice", models[1], "--scale", "12", "--pixels", "301x253", "--pitch", "0.05", "--aa", aa[a],
                    "--threads", "2", "-o", y, NULL);
        CHECKF(r.status == 0, "%s", r.err);
        cli_free(&r);
        p = read_whole_file(x, &np);
        q = read_whole_file(y, &nq);
        CHECKF(p && q && np == nq && !memcmp(p, q, np), "ctb --aa %s: one thread and two differ", aa[a]);
        free(p);
        free(q);
    }
    unsetenv("SOURCE_DATE_EPOCH");
}

/* Turned and mirrored images on 8 threads are one thread's, byte for byte:
   a quarter-turned 1-bit image packs 8 grid rows into each byte, counted
   from the grid's top or bottom (253 or, turned, 301 rows: not multiples
   of 8), so the bands must part where the bytes do. The sphere placed
   against the grid's last rows (its box 10 mm across, the grid 12.65 mm
   tall, or 15.05 mm turned), 1-bit and --aa 4, a quarter turn each way and
   a half turn, with mirrors. */
static void turned_jobs_are_the_same_on_many_threads(void)
{
    static const char *const turns[][3] = {{"90", "none", "0,2.52"}, {"270", "y", "0,2.52"}, {"90", "y", "0,2.52"}, {"180", "x", "0,1.32"}};
    static const char *const aa[] = {"1", "4"};
    char one[300], many[300], what[300];
    int t, a;
    snprintf(one, sizeof one, "%s/turned_one", cli_dir);
    snprintf(many, sizeof many, "%s/turned_many", cli_dir);
    setenv("SOURCE_DATE_EPOCH", "1700000000", 1);
    for (t = 0; t < 4; t++)
        for (a = 0; a < 2; a++) {
            cli_result r = cli_run("slice", sphere_obj(), "--pixels", "301x253", "--pitch", "0.05", "--place", turns[t][2],
                                   "--rotate", turns[t][0], "--mirror", turns[t][1], "--aa", aa[a], "--threads", "1",
                                   "-o", one, NULL);
            CHECKF(r.status == 0, "%s", r.err);
            cli_free(&r);
            r = cli_run("slice", sphere_obj(), "--pixels", "301x253", "--pitch", "0.05", "--place", turns[t][2], "--rotate",
                        turns[t][0], "--mirror", turns[t][1], "--aa", aa[a], "--threads", "8", "-o", many, NULL);
            CHECKF(r.status == 0, "%s", r.err);
            cli_free(&r);
            CHECKF(same_directories(one, many, what), "--rotate %s --mirror %s --aa %s: %s", turns[t][0], turns[t][1], aa[a], what);
        }
    unsetenv("SOURCE_DATE_EPOCH");
}

/* Turned and mirrored jobs are the plain job's pixels moved, read back by
   the GOO reader written from the format's documentation: pixel (i, r) of
   --rotate R (counter-clockwise) is the upright picture's (x, y) = (i, r),
   (w - 1 - r, i), (w - 1 - i, h - 1 - r) or (r, h - 1 - i) for R = 0, 90,
   180, 270, mirrored after (x to w - 1 - x, y to h - 1 - y); the display is
   301 x 253 pixels (no multiple of 8), so a quarter-turned job's upright
   picture is the plain job of 253 x 301. The sphere off the plate's centre,
   1-bit and
   --aa 4. Such jobs (most printers' presets mirror or turn) are now made a
   row a byte at a time, or over the part's box only, not pixel by pixel
   over the whole plate. */
static void turned_and_mirrored_jobs_move_the_plain_pixels(void)
{
    /* the first of each display size is the plain job the next are held to */
    static const char *const turns[][3] = {{"0", "none", "301x253"}, {"0", "x", "301x253"}, {"0", "y", "301x253"},
                                           {"0", "xy", "301x253"}, {"180", "none", "301x253"}, {"180", "x", "301x253"},
                                           {"0", "none", "253x301"}, {"90", "none", "301x253"}, {"270", "x", "301x253"},
                                           {"90", "xy", "301x253"}, {"270", "y", "301x253"}};
    static const char *const aa[] = {"1", "4"};
    const int count = (int)(sizeof turns / sizeof *turns);
    char out[300];
    int t, a;
    snprintf(out, sizeof out, "%s/turned.goo", cli_dir);
    for (a = 0; a < 2; a++) {
        unsigned char *plain[64] = {NULL};
        unsigned layers = 0, k;
        int w = 0, h = 0;
        for (t = 0; t < count; t++) {
            int rot = atoi(turns[t][0]) / 90, mx = strchr(turns[t][1], 'x') != NULL, my = strchr(turns[t][1], 'y') != NULL;
            int plain_job = t == 0 || t == 6, tw = rot & 1 ? h : w, th = rot & 1 ? w : h;
            size_t size, bad = 0;
            unsigned char *data;
            jr_job job;
            cli_result r = cli_run("slice", sphere_obj(), "--pixels", turns[t][2], "--pitch", "0.05", "--place", "1.13,-0.91",
                                   "--uniform", "1", "--rotate", turns[t][0], "--mirror", turns[t][1], "--aa", aa[a], "-o", out,
                                   NULL);
            CHECKF(r.status == 0, "%s", r.err);
            cli_free(&r);
            data = read_whole_file(out, &size);
            if (!data || jr_read_goo(data, size, &job) != 0) {
                CHECKF(0, "--mirror %s --rotate %s: the reader refuses it", turns[t][1], turns[t][0]);
                free(data);
                break;
            }
            if (plain_job) {
                for (k = 0; k < layers; k++) free(plain[k]);
                w = job.width;
                h = job.height;
                layers = job.layer_count < 64 ? job.layer_count : 64;
                for (k = 0; k < layers; k++) {
                    plain[k] = job.layers[k].image;
                    job.layers[k].image = NULL; /* kept */
                }
            } else {
                CHECKF(job.width == tw && job.height == th && job.layer_count >= layers, "%d x %d, %u layers", job.width,
                       job.height, job.layer_count);
                for (k = 0; k < layers && job.width == tw && job.height == th; k++) {
                    int i, rr;
                    for (rr = 0; rr < th; rr++)
                        for (i = 0; i < tw; i++) {
                            int x = rot == 0 ? i : rot == 1 ? w - 1 - rr : rot == 2 ? w - 1 - i : rr;
                            int y = rot == 0 ? rr : rot == 1 ? i : rot == 2 ? h - 1 - rr : h - 1 - i;
                            if (mx) x = w - 1 - x;
                            if (my) y = h - 1 - y;
                            bad += job.layers[k].image[(size_t)rr * tw + i] != plain[k][(size_t)y * w + x];
                        }
                }
                CHECKF(bad == 0, "--rotate %s --mirror %s --aa %s: %zu pixels are not the plain job's moved", turns[t][0],
                       turns[t][1], aa[a], bad);
            }
            jr_free(&job);
            free(data);
        }
        CHECKF(layers >= 8 && w == 253 && h == 301, "%u layers of %d x %d", layers, w, h);
        for (k = 0; k < layers; k++) free(plain[k]);
    }
}

/* A uniform job's top layer is what is left of the part: the headers' one
   layer height and exposure are the regular layers', not the top's. */
static void headers_hold_the_regular_layers(void)
{
    static const char *const ext[] = {"ctb", "goo"};
    char model[256];
    int f;
    snprintf(model, sizeof model, "%s", sphere_obj());
    for (f = 0; f < 2; f++) {
        char out[300];
        unsigned char *data;
        size_t size;
        jr_job job;
        cli_result r;
        snprintf(out, sizeof out, "%s/uniform.%s", cli_dir, ext[f]);
        r = cli_run("slice", model, "--pixels", "300x250", "--pitch", "0.05", "--uniform", "0.06", "--exposure", "2@0.06",
                    "--penetration", "0.1", "-o", out, NULL);
        CHECKF(r.status == 0, "%s: %s", out, r.err);
        cli_free(&r);
        data = read_whole_file(out, &size);
        if (!data || (f == 0 ? jr_read_ctb(data, size, &job) : jr_read_goo(data, size, &job)) != 0) {
            CHECKF(0, "%.200s: the reader refuses it", out);
            free(data);
            continue;
        }
        CHECKF(fabs(job.layer_height_mm - 0.06) < 1e-6 && fabs(job.exposure_s - 2) < 1e-5, "%s: header %g mm, %g s", ext[f],
               job.layer_height_mm, job.exposure_s);
        /* while the top layer itself is thinner and exposed for its thickness */
        CHECK(job.layer_count > 2 && job.layers[job.layer_count - 1].exposure_s < 2);
        /* the globals describe a uniform job, so the goo leaves advance mode
           off, as UVtools does (sn4k3/UVtools @7b510f0d GooFile.cs:1205) */
        if (f == 1) CHECKF(job.per_layer_raw == 0, "%s: advance mode %u for a uniform job", out, job.per_layer_raw);
        jr_free(&job);
        free(data);
    }
}

/* The Phrozen Sonic Mini 8K S reads .prz: -o without an extension gets it,
   a GOO file of its display and name whose anti-aliased layers hold no diff
   chunk. */
static void the_8k_s_preset_writes_prz(void)
{
    char out[300], path[320];
    unsigned char *data;
    size_t size;
    unsigned long long diffs = 0;
    unsigned k;
    jr_job job;
    cli_result r;
    snprintf(out, sizeof out, "%s/small", cli_dir);
    snprintf(path, sizeof path, "%s.prz", out);
    r = cli_run("slice", sphere_obj(), "--scale", "0.1", "--aa", "2", "--printer", "phrozen-sonic-mini-8k-s", "-o", out,
                NULL);
    CHECKF(r.status == 0, "%s", r.err);
    cli_free(&r);
    data = read_whole_file(path, &size);
    if (!data || jr_read_goo_ex(data, size, &job, JR_SKIP_IMAGES) != 0) {
        CHECKF(0, "%.200s: %.200s", path, data ? job.error : "not written");
        free(data);
        return;
    }
    CHECKF(job.width == 7536 && job.height == 3240 && job.layer_count > 3 &&
               !strcmp(job.machine_name, "Phrozen Sonic Mini 8K S"),
           "%d x %d, %u layers, machine %s", job.width, job.height, job.layer_count, job.machine_name);
    for (k = 0; k < job.layer_count; k++) diffs += job.layers[k].diff_chunks;
    CHECKF(diffs == 0, "%llu diff chunks in %u layers", diffs, job.layer_count);
    jr_free(&job);
    free(data);
    remove(path);
}

/* A job directory cannot go stale: a shorter job after a longer one leaves
   none of the old layers, and print takes masks.rle only with the manifest
   that names it. */
static void job_directories_cannot_go_stale(void)
{
    char model[256], job[300], other[300], path[400], *text;
    size_t layers = 0, pngs = 0;
    cli_result r;
    DIR *d;
    struct dirent *e;
    snprintf(model, sizeof model, "%s", sphere_obj());
    snprintf(job, sizeof job, "%s/stale", cli_dir);
    snprintf(other, sizeof other, "%s/other", cli_dir);
    r = cli_run("slice", model, "--pixels", "300x250", "--pitch", "0.05", "--uniform", "0.05", "-o", job, NULL);
    CHECKF(r.status == 0, "%s", r.err);
    cli_free(&r);
    r = cli_run("slice", model, "--pixels", "300x250", "--pitch", "0.05", "--uniform", "0.15", "-o", job, NULL);
    CHECKF(r.status == 0, "%s", r.err);
    cli_free(&r);
    snprintf(path, sizeof path, "%s/manifest.json", job);
    text = read_whole_text(path);
    if (text) layers = (size_t)cli_json_number(text, "layer_count");
    free(text);
    for (d = opendir(job); d && (e = readdir(d)) != NULL;) pngs += !strncmp(e->d_name, "layer_", 6);
    if (d) closedir(d);
    CHECKF(layers > 50 && pngs == layers, "%zu layer files for %zu layers", pngs, layers);

    /* masks.rle from another job, then no manifest at all */
    r = cli_run("slice", model, "--pixels", "300x250", "--pitch", "0.05", "--uniform", "0.1", "-o", other, NULL);
    CHECKF(r.status == 0, "%s", r.err);
    cli_free(&r);
    {
        char from[400], to[400];
        size_t n;
        unsigned char *bytes;
        FILE *f;
        snprintf(from, sizeof from, "%s/masks.rle", other);
        snprintf(to, sizeof to, "%s/masks.rle", job);
        bytes = read_whole_file(from, &n);
        f = fopen(to, "wb");
        CHECK(bytes && f && fwrite(bytes, 1, n, f) == n);
        if (f) fclose(f);
        free(bytes);
    }
    r = cli_run("print", job, "--port", "/dev/null", NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "belongs to another job"), "%d %s", r.status, r.err);
    cli_free(&r);
    remove(path);
    r = cli_run("print", other, "--port", "/dev/null", NULL); /* whole: gets past the job to the port */
    CHECKF(r.status == 1 && !strstr(r.err, "manifest"), "%d %s", r.status, r.err);
    cli_free(&r);
    r = cli_run("print", job, "--port", "/dev/null", NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "manifest.json: missing"), "%d %s", r.status, r.err);
    cli_free(&r);
}

/* A re-slice killed mid-job (a crash, a power cut, ^C) leaves no manifest,
   since slice removes it first and writes it last, so print refuses the
   directory instead of printing the old job's masks.rle. */
static void pause_ms(long ms)
{
    struct timespec t;
    t.tv_sec = ms / 1000;
    t.tv_nsec = ms % 1000 * 1000000L;
    nanosleep(&t, NULL);
}

static void an_interrupted_reslice_cannot_be_printed(void)
{
    char job[300], manifest[400];
    const char *argv[] = {cli_tool, "slice", NULL, "--pixels", "3000x3000", "--pitch", "0.004", "--uniform", "0.01",
                          "--threads", "1", "-o", job, NULL};
    cli_result r;
    pid_t pid;
    int st = 0, waited;
    snprintf(job, sizeof job, "%s/killed", cli_dir);
    snprintf(manifest, sizeof manifest, "%s/manifest.json", job);
    argv[2] = sphere_obj();
    r = cli_run("slice", sphere_obj(), "--pixels", "300x250", "--pitch", "0.05", "-o", job, NULL);
    CHECKF(r.status == 0 && cli_exists(manifest), "%s", r.err);
    cli_free(&r);
    fflush(NULL);
    pid = fork();
    if (pid == 0) {
        int devnull = open("/dev/null", O_WRONLY);
        if (devnull >= 0) { dup2(devnull, 1); dup2(devnull, 2); }
        execv(cli_tool, (char *const *)argv);
        _exit(127);
    }
    CHECK(pid > 0);
    /* the old manifest goes before any layer is written; then a moment of work */
    for (waited = 0; waited < 2000 && cli_exists(manifest); waited++) pause_ms(10);
    pause_ms(300);
    kill(pid, SIGKILL);
    CHECK(waitpid(pid, &st, 0) == pid);
    CHECKF(WIFSIGNALED(st), "the re-slice finished before it could be killed (status %d)", st);
    CHECKF(!cli_exists(manifest), "a killed re-slice left a manifest");
    r = cli_run("print", job, "--port", "/dev/null", NULL);
    CHECKF(r.status == 1 && cli_one_message(r.err) && strstr(r.err, "manifest.json: missing"), "%d %s", r.status, r.err);
    cli_free(&r);
}

void test_slice_jobs(void)
{
    if (!cli_begin("adaslice-jobs")) { CHECK(!"no temporary directory"); return; }
    RUN(exposure_follows_the_working_curve);
    RUN(two_points_fit_the_penetration);
    RUN(slice_at_envelope_and_core);
    RUN(one_exposure_for_adaptive_layers_warns);
    RUN(bad_exposure_values_exit_2);
    RUN(refusals_leave_nothing_behind);
    RUN(resin_files_hold_the_directory_jobs_masks);
    RUN(ctb_for_an_encrypted_ctb_printer);
    RUN(jobs_are_reproducible);
    RUN(an_open_mesh_is_masked_by_its_sections);
    RUN(threads_write_the_same_job);
    RUN(turned_jobs_are_the_same_on_many_threads);
    RUN(turned_and_mirrored_jobs_move_the_plain_pixels);
    RUN(headers_hold_the_regular_layers);
    RUN(the_8k_s_preset_writes_prz);
    RUN(job_directories_cannot_go_stale);
    RUN(an_interrupted_reslice_cannot_be_printed);
    RUN(a_held_band_holds_up_only_itself);
    RUN(large_blocks_start_on_huge_pages);
    cli_end();
}
