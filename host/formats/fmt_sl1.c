/* The Prusa SL1 / SL1S job (.sl1), as the printer's firmware (slafw) reads
   it: config.ini with the job's settings, one 8-bit grey PNG per layer named
   <jobDir>00000.png on, and thumbnail/thumbnail400x400.png and
   thumbnail800x480.png. prusaslicer.ini carries the display_* keys PrusaSlicer
   and UVtools need to open the file. slafw gives the first layer
   layerHeightFirst and every other layer layerHeight: there is one layer
   height, so adaptive plans cannot be stored. Exposure is expTimeFirst fading
   to expTime over numFade layers, then expTime throughout. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* gmtime_r */
#endif
#include "jobfile.h"
#include "../output.h"
#include "../report.h"
#include "../codec/zip.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* PrusaSlicer's area_fill: a layer lit over more than this share of the
   display counts as a slow (tilt) layer in numSlow. */
#define AREA_FILL 0.5

typedef struct sl1 {
    zip_writer *zip;
    const job_desc *d;
    double layer_height;   /* of every layer but the first */
    double exposure;       /* of the layers past the bottom ones */
    char *job_dir;         /* the layers' name prefix */
    char *name;            /* room for a layer's name */
    size_t name_size;
} sl1;

/* jobDir, the layers' name prefix: the file's stem. slafw takes every PNG
   whose name starts with it for a layer and reads it in TOML quotes,
   unescaped, so anything but letters, digits, '.', '-' and '_' becomes '_';
   and a stem that "thumbnail/" starts with, or that starts with "thumbnail"
   (UVtools' test for a thumbnail), gets "job_" in front. */
static char *job_dir_of(const char *path)
{
    const char *base = base_name(path), *dot = strrchr(base, '.');
    size_t n = dot && dot != base ? (size_t)(dot - base) : strlen(base), i, at;
    int clash = !strncmp(base, "thumbnail", n < 9 ? n : 9);
    char *dir = (char *)malloc(n + 5);
    if (!dir) return NULL;
    at = clash ? 4 : 0;
    memcpy(dir, "job_", at);
    for (i = 0; i < n; i++) {
        char c = base[i];
        dir[at + i] = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                      c == '-' ? c : '_';
    }
    dir[at + n] = 0;
    return dir;
}

static void key(FILE *f, const char *name, double v, int decimals)
{
    fprintf(f, "%s = ", name);
    zip_number(f, v, decimals);
    fputc('\n', f);
}

/* The first layer's exposure; the bottom exposure when there are bottom layers. */
static double first_exposure(const job_desc *d)
{
    return d->bottom_layers ? d->bottom_exposure_s : d->layers[0].exposure_s;
}

/* slafw's numFade counts the first and the last level of the fade, and the
   firmware of 2024 wants 2 to 200 of it: the bottom layers, so clamped. */
static unsigned num_fade(const job_desc *d)
{
    return d->bottom_layers < 2 ? 2 : d->bottom_layers > 200 ? 200 : d->bottom_layers;
}

/* Keys sorted, as PrusaSlicer writes them. */
static void write_config(FILE *f, const void *ctx)
{
    const sl1 *w = (const sl1 *)ctx;
    const job_desc *d = w->d;
    double slow_mm2 = AREA_FILL * d->display_mm[0] * d->display_mm[1];
    size_t k, slow = 0;
    int fixed;
    time_t now = job_time(&fixed);
    struct tm utc;
    char when[64] = "";
    for (k = 0; k < d->layer_count; k++) slow += d->layers[k].lit_mm2 > slow_mm2;
    if (gmtime_r(&now, &utc)) strftime(when, sizeof when, "%Y-%m-%d at %H:%M:%S UTC", &utc);
    fputs("action = print\n", f);
    key(f, "expTime", w->exposure, 6);
    key(f, "expTimeFirst", first_exposure(d), 6);
    fprintf(f, "expUserProfile = 0\nfileCreationTimestamp = %s\nhollow = 0\njobDir = %s\n", when, w->job_dir);
    key(f, "layerHeight", w->layer_height, 6);
    key(f, "layerHeightFirst", d->layers[0].thickness, 6);
    fprintf(f, "numFade = %u\nnumFast = %zu\nnumSlow = %zu\n", num_fade(d), d->layer_count - slow, slow);
    key(f, "printTime", d->print_time_s, 6);
    fprintf(f, "printerModel = %s\nprinterVariant = default\nprusaSlicerVersion = adaslice\n",
            d->preset ? d->preset->machine : "SL1");
    key(f, "usedMaterial", d->volume_mm3 / 1000, 6);
}

/* What PrusaSlicer's SL1 import and UVtools read. Their display is landscape
   (pixels_x the long side for the SL1 and SL1S): images turned a quarter
   (the Prusa presets) are "portrait", with the mirrors' axes swapped too, as
   PrusaSlicer 2.5 writes an SL1S (portrait, display_mirror_x = 1) whose
   images are --rotate 90 with the y flip. */
static void write_prusaslicer(FILE *f, const void *ctx)
{
    const sl1 *w = (const sl1 *)ctx;
    const job_desc *d = w->d;
    int portrait = d->rotate & 1;
    double wide = d->display_mm[portrait], high = d->display_mm[!portrait];
    fputs("bed_shape = 0x0,", f);
    zip_number(f, wide, 6);
    fputs("x0,", f);
    zip_number(f, wide, 6);
    fputc('x', f);
    zip_number(f, high, 6);
    fputs(",0x", f);
    zip_number(f, high, 6);
    fputc('\n', f);
    key(f, "display_height", high, 6);
    fprintf(f, "display_mirror_x = %d\ndisplay_mirror_y = %d\ndisplay_orientation = %s\n",
            portrait ? d->mirror_y : d->mirror_x, portrait ? d->mirror_x : d->mirror_y,
            portrait ? "portrait" : "landscape");
    fprintf(f, "display_pixels_x = %d\ndisplay_pixels_y = %d\n", portrait ? d->height : d->width,
            portrait ? d->width : d->height);
    key(f, "display_width", wide, 6);
    key(f, "exposure_time", w->exposure, 6);
    fprintf(f, "faded_layers = %u\ngamma_correction = %d\n", num_fade(d), d->bits == 8);
    key(f, "initial_exposure_time", first_exposure(d), 6);
    key(f, "initial_layer_height", d->layers[0].thickness, 6);
    key(f, "layer_height", w->layer_height, 6);
    if (d->z_max_mm > 0) key(f, "max_print_height", d->z_max_mm, 6);
    fprintf(f, "printer_model = %s\nprinter_settings_id = %s\nprinter_technology = SLA\nprinter_variant = default\n",
            d->preset ? d->preset->machine : "SL1", d->preset ? d->preset->machine : "adaslice");
}

/* Layer 2's thickness for every layer above the first; the top one may be
   thinner (the plan's last layer ends at the part's top, the printer prints
   it at full height, and slice has warned). */
static int one_height(const char *path, const job_desc *d, double *t)
{
    size_t k, n = d->layer_count;
    *t = d->layers[n > 1].thickness;
    for (k = 1; k < n; k++) {
        double dt = d->layers[k].thickness - *t;
        if (k + 1 < n ? fabs(dt) > 1e-6 : dt > 1e-6)
            return complain(RC_USAGE, "cannot write %s: the SL1 format holds one layer height, and layer %zu is %g mm "
                            "where layer 2 is %g mm: plan uniform layers with --method finest or --method coarsest, "
                            "or --uniform T", path, k + 1, d->layers[k].thickness, *t);
    }
    return RC_OK;
}

static void free_writer(sl1 *w)
{
    if (!w) return;
    free(w->job_dir);
    free(w->name);
    free(w);
}

static int open_job(void **writer, const char *path, const job_desc *d)
{
    sl1 *w;
    int rc;
    *writer = NULL;
    if (!d->layer_count) return complain(RC_FAIL, "cannot write %s: the job has no layers", path);
    if (!(w = (sl1 *)calloc(1, sizeof *w)) || !(w->job_dir = job_dir_of(path)) ||
        !(w->name = (char *)malloc(w->name_size = strlen(w->job_dir) + 32)))
        rc = complain(RC_FAIL, "cannot write %s: out of memory", path);
    else if (!(rc = one_height(path, d, &w->layer_height)) && !(rc = zip_open(&w->zip, path)) &&
             ((rc = zip_add_preview_png(w->zip, "thumbnail/thumbnail400x400.png", d, 400, 400)) ||
              (rc = zip_add_preview_png(w->zip, "thumbnail/thumbnail800x480.png", d, 800, 480))))
        zip_close(w->zip, 0);
    if (rc) {
        free_writer(w);
        return rc;
    }
    w->d = d;
    w->exposure = d->exposure_s;
    *writer = w;
    return RC_OK;
}

static int encode(const void *writer, size_t k, const unsigned char *image, size_t stride, job_blob *blob)
{
    (void)k;
    return zip_layer_png(((const sl1 *)writer)->d, image, stride, blob);
}

static int put(void *writer, size_t k, job_blob *blob)
{
    sl1 *w = (sl1 *)writer;
    snprintf(w->name, w->name_size, "%s%05zu.png", w->job_dir, k);
    return zip_add_blob(w->zip, w->name, blob);
}

/* The two ini files go last: config.ini holds the volume and the slow
   layers, known once every layer is in. */
static int close_job(void *writer, int ok)
{
    sl1 *w = (sl1 *)writer;
    int rc = ok ? zip_add_text(w->zip, "config.ini", write_config, w) : RC_FAIL, closed;
    if (!rc) rc = zip_add_text(w->zip, "prusaslicer.ini", write_prusaslicer, w);
    closed = zip_close(w->zip, rc == RC_OK);
    free_writer(w);
    return rc ? rc : closed;
}

const job_format JOB_FORMAT_SL1 = {
    .name = "sl1",
    .extension = ".sl1",
    .what = "Prusa SL1/SL1S",
    .min_layer_mm = 0.01,
    .adaptive = 0,
    .max_layers = ZIP_MEMBERS_MAX - 4, /* two thumbnails, two inis */
    .open = open_job,
    .encode = encode,
    .put = put,
    .close = close_job,
    .previews = {{400, 400}, {800, 480}},
};
