/* Tests of the resin job writers (host/formats/fmt_ctb.c, host/formats/fmt_ctb_encrypted.c,
   host/formats/fmt_goo.c): every file
   is read back by the independent readers of tests/job_readers.c (written
   from the byte layouts, not from the writers), header, layer table and
   every pixel of every layer compared with what was handed in. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#endif
#include "util.h"
#include "check.h"
#include "job_readers.h"
#include "../host/formats/jobfile.h"
#include "../host/printer.h"
#include "../host/report.h"

#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char dir[64];

static const char *in_dir(const char *name)
{
    static char path[160];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return path;
}


static int exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* Entries of the test directory besides . and .. */
static int entries_in_dir(void)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    int n = 0;
    if (!d) return -1;
    while ((e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) n++;
    closedir(d);
    return n;
}

static double le_f32(const unsigned char *p)
{
    uint32_t u = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static double be_f32(const unsigned char *p)
{
    uint32_t u = (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | (uint32_t)p[3];
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static uint32_t le_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* While a complaint is expected: stderr into a file beside the test
   directory; complaint_ends gives it back and checks the complaint is one
   line naming `path`. */
static int saved_stderr = -1;

static const char *complaint_file(void)
{
    static char path[80];
    snprintf(path, sizeof path, "%s.stderr", dir);
    return path;
}

static void complaint_begins(void)
{
    int fd;
    fflush(stderr);
    saved_stderr = dup(2);
    fd = open(complaint_file(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
        dup2(fd, 2);
        close(fd);
    }
}

static void complaint_ends(const char *path, const char *about)
{
    unsigned char *text;
    size_t n;
    fflush(stderr);
    if (saved_stderr >= 0) {
        dup2(saved_stderr, 2);
        close(saved_stderr);
        saved_stderr = -1;
    }
    text = read_whole_file(complaint_file(), &n);
    if (text) text[n] = 0;
    CHECKF(text && strstr((char *)text, path) && strstr((char *)text, about) && strchr((char *)text, '\n') == (char *)text + n - 1,
           "wanted one line naming %s and \"%s\", got \"%s\"", path, about, text ? (char *)text : "");
    free(text);
    remove(complaint_file());
}

/* ---- a job: the desc, its layers and every image as handed in ---------- */

typedef struct test_job {
    printer preset;
    job_desc d;
    job_layer *layers;
    unsigned char **images;     /* as handed to `layer` (d.bits per pixel) */
    size_t stride;
    int preview_calls, preview_sizes[4][2];
    int preview_fails;
} test_job;

/* A picture no format could mistake for black: a colour ramp. */
static int test_preview(void *ctx, int w, int h, unsigned char *rgb)
{
    test_job *j = (test_job *)ctx;
    int x, y;
    if (j->preview_calls < 4) {
        j->preview_sizes[j->preview_calls][0] = w;
        j->preview_sizes[j->preview_calls][1] = h;
    }
    j->preview_calls++;
    if (j->preview_fails) return -1;
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            unsigned char *p = rgb + ((size_t)y * (size_t)w + (size_t)x) * 3;
            p[0] = (unsigned char)(255 * x / w);
            p[1] = (unsigned char)(255 * y / h);
            p[2] = 200;
        }
    return 0;
}

/* The 8-bit value the format must hold for pixel (x, y) of layer k. */
static unsigned char source_grey(const test_job *j, size_t k, int x, int y)
{
    const unsigned char *row = j->images[k] + (size_t)y * j->stride;
    if (j->d.bits == 8) return row[x];
    return (row[x >> 3] >> (7 - (x & 7)) & 1) ? 255 : 0;
}

static void set_pixel(test_job *j, size_t k, int x, int y, unsigned v)
{
    unsigned char *row = j->images[k] + (size_t)y * j->stride;
    if (j->d.bits == 8) row[x] = (unsigned char)v;
    else if (v >= 128) row[x >> 3] |= (unsigned char)(0x80 >> (x & 7));
    else row[x >> 3] &= (unsigned char)~(0x80 >> (x & 7));
}

/* Layers of the given thicknesses, exposures by a working curve
   (E = 1.2 s * exp(t / 0.08 mm)), the first two bottom layers at 25 s;
   images zeroed; padding bits of 1-bit rows set, which the writers must
   ignore. */
static test_job *job_new(int width, int height, int bits, size_t count, const double *thickness)
{
    test_job *j = (test_job *)calloc(1, sizeof *j);
    double z = 0, thinnest = 1e9;
    size_t k;
    j->layers = (job_layer *)calloc(count, sizeof *j->layers);
    j->images = (unsigned char **)calloc(count, sizeof *j->images);
    j->stride = bits == 8 ? (size_t)width + 3 : ((size_t)width + 7) / 8 + 1;
    for (k = 0; k < count; k++) {
        double t = thickness[k];
        j->layers[k].z_bottom = z;
        z += t;
        j->layers[k].z_top = z;
        j->layers[k].thickness = t;
        j->layers[k].exposure_s = k < 2 ? 25.0 : 1.2 * exp(t / 0.08);
        if (t < thinnest) thinnest = t;
        j->images[k] = (unsigned char *)calloc(j->stride, (size_t)height);
        if (bits == 1 && (width & 7)) {
            int y;
            for (y = 0; y < height; y++) j->images[k][(size_t)y * j->stride + (size_t)width / 8] = (unsigned char)(0xFF >> (width & 7));
        }
    }
    j->preset.name = "test-printer";
    j->preset.machine = "Test Printer 12K";
    j->preset.width = width;
    j->preset.height = height;
    j->d.preset = &j->preset;
    j->d.model = "sphere.stl";
    j->d.width = width;
    j->d.height = height;
    j->d.pitch[0] = j->d.pitch[1] = 0.05;
    j->d.display_mm[0] = width * 0.05;
    j->d.display_mm[1] = height * 0.05;
    j->d.z_max_mm = 150;
    j->d.bits = bits;
    j->d.supersample = bits == 8 ? 4 : 1;
    j->d.layer_count = count;
    j->d.layers = j->layers;
    j->d.exposure_s = 1.2 * exp(thinnest / 0.08);
    j->d.bottom_exposure_s = 25;
    j->d.bottom_layers = 2;
    j->d.layer_height_mm = thinnest;
    j->d.motion.lift_mm = 6;
    j->d.motion.lift_speed = 1.5;
    j->d.motion.retract_speed = 3;
    j->d.motion.wait_before_cure_s = 1.25;
    j->d.motion.bottom_lift_mm = 8;
    j->d.motion.bottom_lift_speed = 1;
    j->d.print_time_s = 3600.4;
    j->d.preview = test_preview;
    j->d.preview_ctx = j;
    return j;
}

static void job_free(test_job *j)
{
    size_t k;
    if (!j) return;
    for (k = 0; k < j->d.layer_count; k++) free(j->images[k]);
    free(j->images);
    free(j->layers);
    free(j);
}

static void set_pitch(test_job *j, double across, double down)
{
    j->d.pitch[0] = across;
    j->d.pitch[1] = down;
    j->d.display_mm[0] = j->d.width * across;
    j->d.display_mm[1] = j->d.height * down;
}

/* Writes every layer; the volume is set only after the last, as the slicer
   knows it only then. */
static int job_write(test_job *j, const job_format *f, const char *path)
{
    job_writer w;
    size_t k;
    int rc = job_open(&w, f, path, &j->d);
    if (rc != RC_OK) return rc;
    for (k = 0; k < j->d.layer_count; k++)
        if ((rc = job_write_layer(&w, k, j->images[k], j->stride)) != RC_OK) {
            job_close(&w, 0);
            return rc;
        }
    j->d.volume_mm3 = 1234.5;
    return job_close(&w, 1);
}

enum { AS_CTB3, AS_CTB4, AS_GOO, AS_CTBE };

static const job_format *format_of(int as)
{
    return as == AS_GOO ? &JOB_FORMAT_GOO : as == AS_CTBE ? &JOB_FORMAT_CTB_ENCRYPTED : &JOB_FORMAT_CTB;
}

static int read_as(int as, const unsigned char *file, size_t size, jr_job *r, unsigned flags)
{
    return as == AS_GOO ? jr_read_goo_ex(file, size, r, flags)
           : as == AS_CTBE ? jr_read_ctb_encrypted_ex(file, size, r, flags)
                           : jr_read_ctb_ex(file, size, r, flags);
}

/* Writes the job as `as` to `name` and reads it back; 0 if either failed. */
static int write_and_read(test_job *j, int as, const char *name, jr_job *out, unsigned char **file, size_t *size)
{
    const char *path = in_dir(name);
    int rc, read_rc;
    j->preset.version = as == AS_CTB3 ? 3 : as == AS_CTB4 ? 4 : 0;
    j->preset.format = format_of(as)->name;
    rc = job_write(j, format_of(as), path);
    CHECKF(rc == RC_OK, "%s: writer returned %d", name, rc);
    if (rc != RC_OK) return 0;
    *file = read_whole_file(path, size);
    CHECKF(*file != NULL, "%s: not there after a good close", name);
    if (!*file) return 0;
    read_rc = read_as(as, *file, *size, out, 0);
    CHECKF(read_rc == 0, "%s: the reader refuses it: %s", name, out->error);
    if (read_rc != 0) {
        free(*file);
        *file = NULL;
        return 0;
    }
    return 1;
}

/* Pixels of layer k that differ from what was handed in; the first is told. */
static long image_differences(const test_job *j, int as, const jr_job *r, size_t k, const char *name)
{
    long bad = 0;
    int x, y;
    if (!r->layers[k].image) return -1;
    for (y = 0; y < j->d.height; y++)
        for (x = 0; x < j->d.width; x++) {
            unsigned char src = source_grey(j, k, x, y);
            unsigned char want = as == AS_GOO ? src : jr_ctb_grey(src);
            unsigned char got = r->layers[k].image[(size_t)y * (size_t)j->d.width + (size_t)x];
            if (got != want && bad++ == 0)
                CHECKF(0, "%s: layer %zu pixel (%d, %d) is %u, handed in %u (want %u)", name, k, x, y, got, src, want);
        }
    return bad;
}

static int all_black(const unsigned char *rgb, int w, int h)
{
    size_t i, n = (size_t)w * (size_t)h * 3;
    for (i = 0; i < n; i++)
        if (rgb[i]) return 0;
    return 1;
}

static int same_f32(double got, double want) { return got == (double)(float)want; }

/* ---- 1. a sphere job, every header field and pixel --------------------- */

/* A sphere of radius 0.55 mm standing on the plate (its bottom at z = 0):
   layer k's cross-section at its middle, an ellipse in pixels where the pitch
   is not square; 8-bit from 4 x 4 samples a pixel (17 levels), 1-bit from the
   centre; the 8-bit images also get a ramp 0-255 along the bottom rows. */
static void draw_sphere(test_job *j)
{
    const double radius = 0.55, cx = j->d.display_mm[0] / 2, cy = j->d.display_mm[1] / 2;
    size_t k;
    int x, y, sx, sy;
    for (k = 0; k < j->d.layer_count; k++) {
        double zm = (j->layers[k].z_bottom + j->layers[k].z_top) / 2 - radius;
        double r2 = radius * radius - zm * zm;
        for (y = 0; y < j->d.height; y++)
            for (x = 0; x < j->d.width; x++) {
                int hits = 0, n = j->d.bits == 8 ? 4 : 1;
                for (sy = 0; sy < n; sy++)
                    for (sx = 0; sx < n; sx++) {
                        double px = (x + (sx + 0.5) / n) * j->d.pitch[0] - cx;
                        double py = (y + (sy + 0.5) / n) * j->d.pitch[1] - cy;
                        hits += px * px + py * py <= r2;
                    }
                set_pixel(j, k, x, y, (unsigned)(255 * hits / (n * n)));
            }
        if (j->d.bits == 8)
            for (y = j->d.height - 3; y < j->d.height; y++)
                for (x = 0; x < j->d.width; x++) set_pixel(j, k, x, y, (unsigned)(255 * x / (j->d.width - 1)));
    }
}

static void check_sphere(int as, int bits, const char *name)
{
    /* Adaptive: thin layers where the sphere's wall is steep or flat. */
    static const double t[20] = {0.05, 0.05, 0.05, 0.04, 0.03, 0.02, 0.02, 0.03, 0.05, 0.08,
                                 0.1,  0.08, 0.05, 0.03, 0.02, 0.02, 0.03, 0.04, 0.05, 0.05};
    test_job *j = job_new(bits == 8 ? 90 : 96, bits == 8 ? 64 : 70, bits, 20, t);
    jr_job r;
    unsigned char *file = NULL;
    size_t size = 0, k;
    int ctb = as != AS_GOO;
    if (as == AS_CTB4) set_pitch(j, 0.05, 0.035); /* a non-square panel */
    if (bits == 8) j->d.mirror_x = 1;
    draw_sphere(j);
    if (!write_and_read(j, as, name, &r, &file, &size)) {
        remove(in_dir(name));
        job_free(j);
        return;
    }
    CHECKF(r.width == j->d.width && r.height == j->d.height, "%s: %dx%d pixels", name, r.width, r.height);
    CHECK(same_f32(r.bed_mm[0], j->d.display_mm[0]) && same_f32(r.bed_mm[1], j->d.display_mm[1]));
    CHECK(same_f32(r.bed_mm[2], 150));
    CHECK(r.layer_count == 20 && r.bottom_layers == 2);
    CHECK(same_f32(r.exposure_s, j->d.exposure_s) && same_f32(r.bottom_exposure_s, 25));
    CHECK(same_f32(r.layer_height_mm, 0.02));
    CHECKF(!strcmp(r.machine_name, "Test Printer 12K"), "%s: machine \"%s\"", name, r.machine_name);
    CHECK(r.print_time == 3600);
    CHECKF(r.per_layer_settings, "%s: per-layer settings off", name);
    if (as == AS_CTBE) {
        unsigned char s[288];
        CHECKF(r.version == 5 && r.magic == 0x12FD0107u, "%s: version %u magic 0x%08X", name, r.version, r.magic);
        CHECKF(r.per_layer_raw == 0x40, "%s: PerLayerSettings 0x%02X", name, r.per_layer_raw);
        CHECKF(r.anti_alias == (bits == 8 ? 4 : 1), "%s: AntiAliasLevel %d", name, r.anti_alias);
        CHECK(r.ctb_aa_flag == 0x0F && r.ctb_encryption_key == 0xEFBEADDEu);
        CHECK(same_f32(r.total_height_mm, j->layers[19].z_top));
        CHECK(r.mirror == (bits == 8));
        CHECK(same_f32(r.light_off_s, 0));
        CHECK(r.ctb_v4_last_layer_index == 19 && r.ctb_v4_disclaimer_length == 320);
        /* The volume is written at close: settings+104, in ml; the settings
           are ciphertext, so no plain float of theirs shows in the file */
        CHECK(jr_ctb_encrypted_settings(file, size, s) == 0 && same_f32(le_f32(s + 104), 1.2345));
        CHECK(memcmp(file + 48 + 52, s + 52, 4) != 0);
        CHECKF(r.preview_w[1] == 400 && r.preview_h[1] == 300 && r.preview_w[0] == 200 && r.preview_h[0] == 125,
               "%s: previews %dx%d and %dx%d", name, r.preview_w[1], r.preview_h[1], r.preview_w[0], r.preview_h[0]);
    } else if (ctb) {
        unsigned v = as == AS_CTB3 ? 3 : 4;
        CHECKF(r.version == v && r.magic == (v == 3 ? 0x12FD0086u : 0x12FD0106u), "%s: version %u magic 0x%08X", name,
               r.version, r.magic);
        /* PerLayerSettings as current UVtools writes it for per-layer jobs:
           Version x 0x10, 0x30 for v3 and 0x40 for v4 (sn4k3/UVtools @7b510f0d,
           UVtools.Core/FileFormats/ChituboxFile.cs:44-45, PERLAYER_SETTINGS_CTBv3/v4,
           and :1771-1773 in OnBeforeEncode). */
        CHECKF(r.per_layer_raw == (v == 3 ? 0x30u : 0x40u), "%s: PerLayerSettings 0x%02X", name, r.per_layer_raw);
        CHECKF(r.anti_alias == (bits == 8 ? 4 : 1), "%s: AntiAliasLevel %d", name, r.anti_alias);
        CHECK(r.ctb_aa_flag == 0x0F);
        /* EncryptionKey: UVtools writes one in [255, 2^31 - 1) into every ctb
           (@7b510f0d ChituboxFile.cs:1786-1789, new Random().Next(byte.MaxValue,
           int.MaxValue)); the layers decode below through its XOR stream. */
        CHECKF(r.ctb_encryption_key >= 255 && r.ctb_encryption_key < 0x7FFFFFFFu, "%s: EncryptionKey %u", name,
               r.ctb_encryption_key);
        CHECK(same_f32(r.total_height_mm, j->layers[19].z_top));
        CHECK(r.mirror == (bits == 8));
        /* Light-off (v3) or a rest before cure (v4), never both. v3's light-off
           runs through the peel, so UVtools writes lift / lift speed + lift /
           retract speed + the rest, to 0.01 s (@7b510f0d ChituboxFile.cs:1358-1371,
           WaitTimeBeforeCure below v4 -> FileFormat.cs:6405-6423 ->
           Operations/OperationCalculator.cs:195-216): normal layers 6 mm at
           1.5 mm/s up and 3 mm/s down, 4 + 2 + 1.25 = 7.25 s; bottom layers 8 mm
           at 1 mm/s up, 8 + 2.667 + 1.25 = 11.92 s. */
        CHECK(same_f32(r.light_off_s, v == 3 ? 7.25 : 0));
        CHECK(same_f32(le_f32(file + le_u32(file + 84) + 32), v == 3 ? 11.92 : 0)); /* BottomLightOffDelay */
        CHECK(same_f32(le_f32(file + le_u32(file + 84) + 36), v == 3 ? 7.25 : 0));  /* LightOffDelay */
        if (v == 4) CHECK(r.ctb_v4_last_layer_index == 19 && r.ctb_v4_disclaimer_length == 320);
        /* The volume is written at close: PrintParameters+20, in ml. */
        CHECK(same_f32(le_f32(file + le_u32(file + 84) + 20), 1.2345));
        CHECKF(r.preview_w[1] == 400 && r.preview_h[1] == 300 && r.preview_w[0] == 200 && r.preview_h[0] == 125,
               "%s: previews %dx%d and %dx%d", name, r.preview_w[1], r.preview_h[1], r.preview_w[0], r.preview_h[0]);
    } else {
        CHECK(r.version == 3 && r.per_layer_raw == 1);
        CHECKF(r.anti_alias == (bits == 8 ? 4 : 1), "%s: AntiAliasingLevel %d", name, r.anti_alias);
        CHECK(r.goo_delay_mode == 1 && r.goo_grey_scale_level == 1 && same_f32(r.light_off_s, 0));
        CHECK(r.mirror == (bits == 8 ? 1 : 0));
        CHECK(same_f32(be_f32(file + 195450), 1234.5));
        CHECKF(r.preview_w[0] == 116 && r.preview_w[1] == 290, "%s: previews %d and %d", name, r.preview_w[0],
               r.preview_w[1]);
    }
    CHECKF(j->preview_calls == 2, "%s: %d preview calls", name, j->preview_calls);
    CHECK(j->preview_sizes[0][0] == (ctb ? 400 : 116) && j->preview_sizes[1][0] == (ctb ? 200 : 290));
    CHECK(r.preview_rgb[0] && !all_black(r.preview_rgb[0], r.preview_w[0], r.preview_h[0]));
    CHECK(r.preview_rgb[1] && !all_black(r.preview_rgb[1], r.preview_w[1], r.preview_h[1]));

    for (k = 0; k < 20; k++) {
        const jr_layer *L = &r.layers[k];
        int bottom = k < 2;
        double lift = bottom ? 8 : 6, speed = bottom ? 60 : 90;
        CHECKF(same_f32(L->z_mm, j->layers[k].z_top), "%s: layer %zu at %g mm, not %g", name, k, L->z_mm,
               j->layers[k].z_top);
        CHECKF(same_f32(L->exposure_s, j->layers[k].exposure_s), "%s: layer %zu exposed %g s, not %g", name, k,
               L->exposure_s, j->layers[k].exposure_s);
        CHECKF(same_f32(L->lift_mm, lift) && same_f32(L->lift_speed, speed) && same_f32(L->retract_speed, 180),
               "%s: layer %zu lifts %g mm at %g mm/min, retracts at %g", name, k, L->lift_mm, L->lift_speed,
               L->retract_speed);
        CHECK(same_f32(L->lift2_mm, 0) && same_f32(L->retract2_mm, 0));
        CHECK(same_f32(L->pwm, 255));
        if (as == AS_CTB3) CHECK(same_f32(L->light_off_s, bottom ? 11.92 : 7.25) && same_f32(L->wait_before_cure_s, 0));
        else CHECK(same_f32(L->light_off_s, 0) && same_f32(L->wait_before_cure_s, 1.25));
        if (as == AS_CTB4 || as == AS_CTBE) CHECK(same_f32(L->lift2_speed, speed) && same_f32(L->retract2_speed, 180));
        if (as == AS_GOO) CHECK(same_f32(L->retract_mm, lift) && L->pause == 0);
        CHECK(image_differences(j, as, &r, k, name) == 0);
    }
    jr_free(&r);
    free(file);
    remove(in_dir(name));
    job_free(j);
}

static void sphere_as_ctb_v3(void)
{
    check_sphere(AS_CTB3, 1, "sphere1.v3.ctb");
    check_sphere(AS_CTB3, 8, "sphere8.v3.ctb");
}

static void sphere_as_ctb_v4_on_a_non_square_panel(void)
{
    check_sphere(AS_CTB4, 1, "sphere1.v4.ctb");
    check_sphere(AS_CTB4, 8, "sphere8.v4.ctb");
}

static void sphere_as_encrypted_ctb(void)
{
    check_sphere(AS_CTBE, 1, "sphere1.encrypted.ctb");
    check_sphere(AS_CTBE, 8, "sphere8.encrypted.ctb");
}

static void sphere_as_goo(void)
{
    check_sphere(AS_GOO, 1, "sphere1.goo");
    check_sphere(AS_GOO, 8, "sphere8.goo");
}

/* A preset without a version writes CTB v4; none at all names the machine
   "adaslice". */
static void ctb_defaults_to_v4_and_adaslice(void)
{
    static const double t[3] = {0.05, 0.05, 0.05};
    test_job *j = job_new(40, 30, 1, 3, t);
    jr_job r;
    unsigned char *file = NULL;
    size_t size;
    set_pixel(j, 2, 5, 5, 255);
    j->d.preset = NULL;
    if (write_and_read(j, AS_CTB4, "plain.ctb", &r, &file, &size)) {
        CHECK(r.version == 4 && r.magic == 0x12FD0106u);
        CHECKF(!strcmp(r.machine_name, "adaslice"), "machine \"%s\"", r.machine_name);
        jr_free(&r);
    }
    free(file);
    remove(in_dir("plain.ctb"));
    job_free(j);
}

/* The layers are coded with the header's key, as UVtools codes every ctb it
   writes (sn4k3/UVtools @7b510f0d, UVtools.Core/FileFormats/ChituboxFile.cs:
   1786-1789 draws the key, :2225-2245 LayerRleCryptBuffer XORs the layers):
   the key is one UVtools could have drawn, the layers decode to what was
   handed in only through it (read with the key field zeroed, they do not),
   and the same job gets the same key. */
static void ctb_layers_are_coded_with_the_key(void)
{
    static const double t[5] = {0.05, 0.05, 0.04, 0.03, 0.05};
    int as;
    for (as = AS_CTB3; as <= AS_CTB4; as++) {
        test_job *j = job_new(48, 40, 8, 5, t);
        jr_job r, clear;
        unsigned char *file = NULL, *again = NULL;
        size_t size = 0, again_size = 0, k;
        int x, y;
        for (k = 0; k < 5; k++)
            for (y = 0; y < 40; y++)
                for (x = 0; x < 48; x++) set_pixel(j, k, x, y, (unsigned)((x * 5 + y * 9 + (int)k * 13) % 256));
        if (write_and_read(j, as, "keyed.ctb", &r, &file, &size)) {
            unsigned key = r.ctb_encryption_key;
            CHECKF(key >= 255 && key < 0x7FFFFFFFu, "v%u: EncryptionKey %u", r.version, key);
            for (k = 0; k < 5; k++) CHECK(image_differences(j, as, &r, k, "keyed.ctb") == 0);
            jr_free(&r);
            memset(file + 100, 0, 4);
            if (jr_read_ctb(file, size, &clear) == 0) {
                long bad = 0;
                for (k = 0; k < 5; k++)
                    for (y = 0; y < 40; y++)
                        for (x = 0; x < 48; x++)
                            bad += clear.layers[k].image[(size_t)y * 48 + (size_t)x] != jr_ctb_grey(source_grey(j, k, x, y));
                CHECKF(bad > 0, "v%u: the layers read the same without the key", clear.version);
                jr_free(&clear);
            }
            if (write_and_read(j, as, "keyed.ctb", &r, &again, &again_size)) {
                CHECKF(r.ctb_encryption_key == key, "the same job got keys %u and %u", key, r.ctb_encryption_key);
                jr_free(&r);
            }
        }
        free(file);
        free(again);
        remove(in_dir("keyed.ctb"));
        job_free(j);
    }
}

/* GOO's advance mode (header 195445) is on only when a layer differs from
   the header's globals, as UVtools writes it (sn4k3/UVtools @7b510f0d,
   UVtools.Core/FileFormats/GooFile.cs:1205, PerLayerSettings =
   SupportPerLayerSettings && UsingPerLayerSettings; FileFormat.cs:1988-1995;
   Layers/Layer.cs:1163-1240, a layer's Z within 0.001 mm of LayerHeight x
   its number, its exposure within 0.01 s of the global one): off for a
   uniform plan (its top layer, what is left of the part, thinner), on for
   adaptive layers and for a uniform one with an exposure of its own. Every
   layer's own Z is stored either way. */
static void goo_advance_mode_only_when_layers_differ(void)
{
    static const double uniform[6] = {0.05, 0.05, 0.05, 0.05, 0.05, 0.03};
    static const double adaptive[6] = {0.05, 0.05, 0.05, 0.04, 0.05, 0.05};
    int pass;
    for (pass = 0; pass < 3; pass++) {
        test_job *j = job_new(32, 24, 1, 6, pass == 1 ? adaptive : uniform);
        jr_job r;
        unsigned char *file = NULL;
        size_t size = 0, k;
        j->d.layer_height_mm = pass == 1 ? 0.04 : 0.05; /* the thinnest, the top one aside */
        j->d.exposure_s = 1.2 * exp(j->d.layer_height_mm / 0.08);
        if (pass == 2) j->layers[3].exposure_s += 0.5;
        if (write_and_read(j, AS_GOO, "advance.goo", &r, &file, &size)) {
            unsigned want = pass == 0 ? 0 : 1;
            CHECKF(r.per_layer_raw == want, "%s: advance mode %u", pass == 0 ? "uniform" : pass == 1 ? "adaptive" : "own exposure",
                   r.per_layer_raw);
            for (k = 0; k < 6; k++) CHECK(same_f32(r.layers[k].z_mm, j->layers[k].z_top));
            jr_free(&r);
        }
        free(file);
        remove(in_dir("advance.goo"));
        job_free(j);
    }
}

/* ---- 2. corruption is caught ------------------------------------------- */

static int corruption_seen(test_job *j, int as, unsigned char *file, size_t size, size_t at)
{
    jr_job r;
    int seen;
    size_t k;
    file[at] ^= 0x01;
    if (read_as(as, file, size, &r, 0) != 0) return 1;
    seen = 0;
    for (k = 0; k < r.layer_count; k++) {
        long bad = 0;
        int x, y;
        for (y = 0; y < j->d.height; y++)
            for (x = 0; x < j->d.width; x++) {
                unsigned char src = source_grey(j, k, x, y);
                bad += r.layers[k].image[(size_t)y * (size_t)j->d.width + (size_t)x] != (as == AS_GOO ? src : jr_ctb_grey(src));
            }
        if (bad) seen = 1;
    }
    jr_free(&r);
    return seen;
}

static void flipped_layer_bytes_are_detected(void)
{
    static const double t[6] = {0.05, 0.05, 0.03, 0.03, 0.02, 0.02};
    int as;
    for (as = AS_CTB3; as <= AS_CTBE; as++) {
        test_job *j = job_new(64, 48, 8, 6, t);
        jr_job r;
        unsigned char *file = NULL;
        size_t size, k;
        int x, y;
        for (k = 0; k < 6; k++)
            for (y = 0; y < 48; y++)
                for (x = 0; x < 64; x++) set_pixel(j, k, x, y, (unsigned)((x * 7 + y * 3 + (int)k * 11) % 256));
        if (write_and_read(j, as, "corrupt.job", &r, &file, &size)) {
            const jr_layer *L = &r.layers[3];
            /* Inside the data: past GOO's 0x55, before its checksum. */
            size_t at = (size_t)L->data_offset + (size_t)L->data_size / 2;
            jr_free(&r);
            CHECKF(corruption_seen(j, as, file, size, at), "%s: a flipped bit at offset %zu goes unnoticed",
                   format_of(as)->name, at);
        }
        free(file);
        remove(in_dir("corrupt.job"));
        job_free(j);
    }
}

/* ---- 3. a failure leaves nothing ---------------------------------------- */

static void failures_leave_no_file(void)
{
    static const double t[4] = {0.05, 0.05, 0.05, 0.05};
    int as;
    for (as = AS_CTB4; as <= AS_CTBE; as++) {
        const job_format *f = format_of(as);
        test_job *j = job_new(37, 23, 1, 4, t);
        char missing[200];
        job_writer w;
        size_t k;
        int rc;
        j->preset.version = as == AS_CTB4 ? 4 : 0;

        snprintf(missing, sizeof missing, "%s/no-such-dir/job%s", dir, f->extension);
        complaint_begins();
        rc = job_open(&w, f, missing, &j->d);
        complaint_ends(missing, "No such file");
        CHECKF(rc == RC_FAIL && w.state == NULL, "%s: open in a missing directory gave %d", f->name, rc);
        CHECK(!exists(missing) && entries_in_dir() == 0);

        /* Layers written, then a close that gives up. */
        rc = job_open(&w, f, in_dir("given_up.job"), &j->d);
        CHECK(rc == RC_OK);
        if (rc == RC_OK) {
            for (k = 0; k < 3; k++) CHECK(job_write_layer(&w, k, j->images[k], j->stride) == RC_OK);
            CHECK(entries_in_dir() == 1); /* the temporary file, while writing */
            CHECK(job_close(&w, 0) == RC_OK);
        }
        CHECKF(entries_in_dir() == 0, "%s: %d files left after close(ok=0)", f->name, entries_in_dir());

        /* A good close after too few layers is refused, and leaves nothing. */
        rc = job_open(&w, f, in_dir("short.job"), &j->d);
        CHECK(rc == RC_OK);
        if (rc == RC_OK) {
            CHECK(job_write_layer(&w, 0, j->images[0], j->stride) == RC_OK);
            complaint_begins();
            CHECK(job_close(&w, 1) == RC_FAIL);
            complaint_ends(in_dir("short.job"), "1 of 4 layers");
        }
        CHECK(entries_in_dir() == 0);

        /* Layers out of order are refused. */
        rc = job_open(&w, f, in_dir("order.job"), &j->d);
        CHECK(rc == RC_OK);
        if (rc == RC_OK) {
            complaint_begins();
            CHECK(job_write_layer(&w, 1, j->images[1], j->stride) == RC_FAIL);
            complaint_ends(in_dir("order.job"), "layer 1");
            job_close(&w, 0);
        }
        CHECK(entries_in_dir() == 0);

        /* A preview that cannot be drawn fails the open. */
        j->preview_fails = 1;
        complaint_begins();
        rc = job_open(&w, f, in_dir("no_preview.job"), &j->d);
        complaint_ends(in_dir("no_preview.job"), "preview");
        CHECK(rc == RC_FAIL && w.state == NULL);
        CHECK(entries_in_dir() == 0);
        job_free(j);
    }
}

/* ---- 4b. the encrypted CTB: v4 and v5, its seal, 4 GiB, the presets ------ */

static unsigned char *write_small_encrypted(test_job *j, unsigned version, const char *name, size_t *size)
{
    j->preset.version = version;
    j->preset.format = "ctb-encrypted";
    CHECKF(job_write(j, &JOB_FORMAT_CTB_ENCRYPTED, in_dir(name)) == RC_OK, "%s: not written", name);
    return read_whole_file(in_dir(name), size);
}

/* v5 (the default) has the resin parameters and 8 bytes before the
   signature, v4 neither; both end in the signature and 4 bytes. Version 3
   is refused. */
static void encrypted_ctb_v4_and_v5(void)
{
    static const double t[3] = {0.05, 0.03, 0.04};
    test_job *j = job_new(40, 30, 1, 3, t);
    unsigned version;
    void *w = (void *)&w;
    int rc;
    set_pixel(j, 2, 5, 5, 255);
    for (version = 4; version <= 5; version++) {
        unsigned char *file, s[288];
        size_t size = 0, k;
        jr_job r;
        file = write_small_encrypted(j, version == 5 ? 0 : 4, "small.ctb", &size);
        if (!file) continue;
        CHECKF(jr_read_ctb_encrypted(file, size, &r) == 0, "v%u: %s", version, r.error);
        CHECK(r.version == version && r.layer_count == 3 && r.width == 40 && r.height == 30);
        for (k = 0; k < r.layer_count; k++) CHECK(image_differences(j, AS_CTBE, &r, k, "small.ctb") == 0);
        CHECK(jr_ctb_encrypted_settings(file, size, s) == 0);
        CHECK(le_u32(file + 24) + 32 + 4 == size && le_u32(file + 20) == 32);
        if (version == 5) {
            static const unsigned char before_signature[8] = {0xFA, 0x52, 0x20, 0x42, 0, 0, 0, 0};
            CHECK(le_u32(s + 276) != 0 && !memcmp(file + le_u32(file + 24) - 8, before_signature, 8));
        } else {
            CHECK(le_u32(s + 276) == 0);
        }
        jr_free(&r);
        free(file);
        remove(in_dir("small.ctb"));
    }
    j->preset.version = 3;
    complaint_begins();
    rc = JOB_FORMAT_CTB_ENCRYPTED.open(&w, in_dir("v3.ctb"), &j->d);
    complaint_ends(in_dir("v3.ctb"), "version 3");
    CHECK(rc == RC_FAIL && w == NULL && entries_in_dir() == 0);
    job_free(j);
}

/* The seal: a bit flipped in the signature, in the settings' checksum or in
   the magic makes the reader refuse the file, saying what. */
static void encrypted_ctb_seal_is_checked(void)
{
    static const double t[2] = {0.05, 0.05};
    test_job *j = job_new(24, 16, 8, 2, t);
    unsigned char *file;
    size_t size = 0, i;
    set_pixel(j, 1, 3, 3, 200);
    file = write_small_encrypted(j, 0, "seal.ctb", &size);
    if (file) {
        struct { size_t at; const char *says; } flips[] = {
            {0, "magic"}, {le_u32(file + 24) + 31, "signature"}, {48 + 2, "signature"}};
        for (i = 0; i < sizeof flips / sizeof flips[0]; i++) {
            jr_job r;
            file[flips[i].at] ^= 0x10;
            CHECKF(jr_read_ctb_encrypted(file, size, &r) != 0 && strstr(r.error, flips[i].says),
                   "a bit flipped at offset %zu: \"%s\"", flips[i].at, r.error);
            file[flips[i].at] ^= 0x10;
        }
    }
    free(file);
    remove(in_dir("seal.ctb"));
    job_free(j);
}

/* The settings' and the header's offsets are 32-bit: a layer that would end
   the file past 4 GiB is refused, in one line, before a byte of it is
   written, and nothing is left; so are more layers than could ever fit. */
static void encrypted_ctb_past_4_gib_is_refused(void)
{
    static const double t[3] = {0.05, 0.05, 0.05};
    const job_format *f = &JOB_FORMAT_CTB_ENCRYPTED;
    test_job *j = job_new(24, 16, 1, 3, t);
    job_writer w;
    int rc = job_open(&w, f, in_dir("huge.ctb"), &j->d);
    CHECK(rc == RC_OK);
    if (rc == RC_OK) {
        job_blob blob;
        CHECK(job_write_layer(&w, 0, j->images[0], j->stride) == RC_OK);
        /* the size of a layer's code a 4 GiB file would take, not its bytes:
           the writer refuses it before it reads them */
        memset(&blob, 0, sizeof blob);
        blob.data = (unsigned char *)malloc(16);
        blob.cap = 16;
        blob.size = (size_t)0xFFFFFF00u;
        complaint_begins();
        rc = job_put(&w, 1, &blob);
        complaint_ends(in_dir("huge.ctb"), "past the 4 GiB");
        CHECK(rc == RC_FAIL && blob.data == NULL);
        job_close(&w, 0);
    }
    CHECK(entries_in_dir() == 0);
    j->d.layer_count = 50000000;
    complaint_begins();
    rc = job_open(&w, f, in_dir("many.ctb"), &j->d);
    complaint_ends(in_dir("many.ctb"), "4 GiB");
    CHECK(rc == RC_FAIL && w.state == NULL && entries_in_dir() == 0);
    j->d.layer_count = 3;
    job_free(j);
}

/* The printers that read only the encrypted CTB, with UVtools' figures
   (PrusaSlicer/printer, each printer's .ini): the display in pixels and mm, the build
   height, mirrored across. .ctb alone still names the unencrypted format. */
static void encrypted_ctb_presets(void)
{
    static const struct { const char *name; int w, h; double mm[2], z; } want[] = {
        {"elegoo-mars-3", 4098, 2560, {143.43, 89.6}, 175},
        {"elegoo-saturn-4-ultra", 11520, 5120, {218.88, 122.88}, 220},
        {"phrozen-sonic-mini-8k", 7500, 3240, {165, 71.28}, 180}};
    size_t i;
    for (i = 0; i < sizeof want / sizeof want[0]; i++) {
        const printer *p = printer_find(want[i].name);
        CHECKF(p && !strcmp(p->format, "ctb-encrypted") && p->width == want[i].w && p->height == want[i].h &&
                   fabs(p->width * p->pitch[0] - want[i].mm[0]) < 1e-9 && fabs(p->height * p->pitch[1] - want[i].mm[1]) < 1e-9 &&
                   p->z_max == want[i].z && p->mirror_x == 1 && p->mirror_y == 0 && p->rotate == 0 && p->version == 0,
               "%s", want[i].name);
    }
    CHECK(job_format_named("ctb-encrypted") == &JOB_FORMAT_CTB_ENCRYPTED);
    CHECK(job_format_for_path("job.ctb") == &JOB_FORMAT_CTB);
}

/* ---- 4. edges: odd widths, blank and full layers, runs past the limits --- */

static uint32_t rng_state = 2463534242u;

static uint32_t rng(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 17;
    rng_state ^= rng_state << 5;
    return rng_state;
}

static void round_trip(test_job *j, const char *what)
{
    int as;
    for (as = AS_CTB3; as <= AS_CTBE; as++) {
        static const char *const ext[] = {"v3.ctb", "v4.ctb", "goo", "encrypted.ctb"};
        char name[64];
        jr_job r;
        unsigned char *file = NULL;
        size_t size, k;
        snprintf(name, sizeof name, "%s.%s", what, ext[as]);
        if (write_and_read(j, as, name, &r, &file, &size)) {
            for (k = 0; k < j->d.layer_count; k++) CHECK(image_differences(j, as, &r, k, name) == 0);
            jr_free(&r);
        }
        free(file);
        remove(in_dir(name));
    }
}

/* 37 x 23: rows end inside a byte (and the padding bits are set). */
static void odd_width_blank_full_and_noisy_layers(void)
{
    static const double t[5] = {0.05, 0.05, 0.05, 0.05, 0.05};
    int bits;
    for (bits = 1; bits <= 8; bits += 7) {
        test_job *j = job_new(37, 23, bits, 5, t);
        int x, y;
        for (y = 0; y < 23; y++)
            for (x = 0; x < 37; x++) {
                set_pixel(j, 1, x, y, 255);                          /* all lit */
                set_pixel(j, 2, x, y, rng() & 0xFF);                 /* no runs at all */
                set_pixel(j, 3, x, y, (x + y) & 1 ? 255 : 0);        /* a checkerboard */
                set_pixel(j, 4, x, y, x == 36 || y == 22 ? 255 : 1); /* the last column and row */
            }
        /* layer 0 stays dark */
        round_trip(j, bits == 1 ? "odd1" : "odd8");
        job_free(j);
    }
}

/* Runs of every length at which a length form ends (CTB 127/128, 16383/16384,
   2097151/2097152; GOO 15/16, 4095/4096, 1048575/1048576, diff 255/256):
   each short length once with every grey in turn, so that each meets every
   change of grey (a small diff up or down, to and from black and white); the
   long ones once. */
static void run_lengths_at_every_form_boundary(void)
{
    static const double t[1] = {0.05};
    static const uint32_t lengths[] = {1,     2,     3,       15,      16,      127,     128,    255, 256, 4095,
                                       4096, 16383, 16384, 1048575, 1048576, 2097151, 2097152};
    /* Neighbours differ in their top 7 bits too, so CTB does not merge them. */
    static const unsigned greys[] = {100, 107, 0, 255, 93, 130, 129, 255, 1, 254};
    const size_t side = 2600, n = side * side, n_greys = sizeof greys / sizeof greys[0];
    test_job *j = job_new((int)side, (int)side, 8, 1, t);
    size_t at = 0, i, g = 0;
    for (i = 0; at < n; i++) {
        uint32_t len = lengths[i / n_greys % (sizeof lengths / sizeof lengths[0])];
        unsigned v = greys[g++ % n_greys];
        if (len > 4096) { /* the long ones once, each with its own grey */
            if (i % n_greys) continue;
            v = greys[i / n_greys % n_greys];
        }
        for (; len && at < n; len--, at++) j->images[0][at / side * j->stride + at % side] = (unsigned char)v;
    }
    round_trip(j, "runs8");
    job_free(j);
}

/* 16384 x 16384 (2^28 pixels, the readers' limit) all lit, then all dark:
   one run longer than either format's longest run code (2^28 - 1), cut
   into two; the bytes are checked, not just the decode. */
static void runs_longer_than_a_code_are_cut(void)
{
    static const double t[2] = {0.05, 0.05};
    static const unsigned char ctb_lit[] = {0xFF, 0xEF, 0xFF, 0xFF, 0xFF, 0x7F};
    static const unsigned char ctb_dark[] = {0x80, 0xEF, 0xFF, 0xFF, 0xFF, 0x00};
    static const unsigned char goo_lit[] = {0x55, 0xFF, 0xFF, 0xFF, 0xFF, 0xC1};
    static const unsigned char goo_dark[] = {0x55, 0x3F, 0xFF, 0xFF, 0xFF, 0x01};
    const int side = 16384;
    test_job *j = job_new(8, 8, 1, 2, t);
    int as;
    /* Only two images of 32 MiB: built here rather than by job_new. */
    free(j->images[0]);
    free(j->images[1]);
    j->stride = side / 8;
    j->d.width = j->d.height = j->preset.width = j->preset.height = side;
    j->d.display_mm[0] = j->d.display_mm[1] = side * 0.05;
    j->images[0] = (unsigned char *)malloc(j->stride * side);
    j->images[1] = (unsigned char *)calloc(j->stride, side);
    if (!j->images[0] || !j->images[1]) {
        CHECK(!"out of memory for two 16384 x 16384 masks");
        job_free(j);
        return;
    }
    memset(j->images[0], 0xFF, j->stride * side);
    for (as = AS_CTB3; as <= AS_GOO; as++) {
        const char *name = as == AS_GOO ? "long.goo" : "long.ctb";
        unsigned char *file;
        size_t size;
        jr_job r;
        int rc;
        j->preset.version = as == AS_CTB3 ? 3 : as == AS_CTB4 ? 4 : 0;
        CHECK(job_write(j, format_of(as), in_dir(name)) == RC_OK);
        file = read_whole_file(in_dir(name), &size);
        CHECK(file != NULL);
        if (!file) continue;
        rc = as == AS_GOO ? jr_read_goo_ex(file, size, &r, JR_SKIP_IMAGES) : jr_read_ctb_ex(file, size, &r, JR_SKIP_IMAGES);
        CHECKF(rc == 0, "%s: %s", name, r.error);
        if (rc == 0) {
            const jr_layer *lit = &r.layers[0], *dark = &r.layers[1];
            if (as == AS_GOO) {
                unsigned char want_lit[7], want_dark[7];
                memcpy(want_lit, goo_lit, 6);
                memcpy(want_dark, goo_dark, 6);
                want_lit[6] = (unsigned char)~(0xFF * 4 + 0xC1);
                want_dark[6] = (unsigned char)~(0x3F + 0xFF * 3 + 0x01);
                CHECK(lit->data_size == 7 && !memcmp(file + lit->data_offset, want_lit, 7));
                CHECK(dark->data_size == 7 && !memcmp(file + dark->data_offset, want_dark, 7));
            } else {
                unsigned char clear[2][6];
                CHECK(lit->data_size == 6 && dark->data_size == 6);
                if (lit->data_size == 6 && dark->data_size == 6) {
                    jr_ctb_decrypt(r.ctb_encryption_key, 0, file + lit->data_offset, 6, clear[0]);
                    jr_ctb_decrypt(r.ctb_encryption_key, 1, file + dark->data_offset, 6, clear[1]);
                    CHECK(!memcmp(clear[0], ctb_lit, 6) && !memcmp(clear[1], ctb_dark, 6));
                }
            }
            jr_free(&r);
        }
        free(file);
        remove(in_dir(name));
    }
    job_free(j);
}

void test_formats_resin(void)
{
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/adaslice-resin-XXXXXX", tmp && strlen(tmp) < 40 ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        perror("test_formats_resin: mkdtemp");
        return;
    }
    RUN(sphere_as_ctb_v3);
    RUN(sphere_as_ctb_v4_on_a_non_square_panel);
    RUN(sphere_as_encrypted_ctb);
    RUN(sphere_as_goo);
    RUN(ctb_defaults_to_v4_and_adaslice);
    RUN(ctb_layers_are_coded_with_the_key);
    RUN(goo_advance_mode_only_when_layers_differ);
    RUN(flipped_layer_bytes_are_detected);
    RUN(failures_leave_no_file);
    RUN(encrypted_ctb_v4_and_v5);
    RUN(encrypted_ctb_seal_is_checked);
    RUN(encrypted_ctb_past_4_gib_is_refused);
    RUN(encrypted_ctb_presets);
    RUN(odd_width_blank_full_and_noisy_layers);
    RUN(run_lengths_at_every_form_boundary);
    RUN(runs_longer_than_a_code_are_cut);
    rmdir(dir);
}
