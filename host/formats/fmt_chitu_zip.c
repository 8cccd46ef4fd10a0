/* The ChiTu G-code zip (.zip), for printers whose firmware runs a G-code job
   (Phrozen Shuffle and Sonic, Wanhao D8, Kelant S400): run.gcode, one 8-bit
   grey PNG per layer (1.png to N.png), preview.png and preview_cropping.png.
   run.gcode is laid out as ChiTuBox writes it: its ";key:value" header keys
   in its order, its start and end blocks, and per layer show the image, lift
   and come back down to the layer's Z, wait, light on, expose, light off.
   The firmware executes those moves, so every layer is printed at its own
   absolute Z with its own exposure: adaptive plans print as planned. */
#include "jobfile.h"
#include "../output.h"
#include "../report.h"
#include "../codec/zip.h"

#include <stdio.h>
#include <stdlib.h>

/* UVtools' sizes for the two previews (ChituboxZipFile ThumbnailsOriginalSize). */
enum { PREVIEW_W = 954, PREVIEW_H = 850, CROPPING_W = 168, CROPPING_H = 150 };
/* What run.gcode's header says a millilitre weighs: ChiTuBox's own example
   weighs its 8 ml part at 8.8 g. */
#define RESIN_G_PER_ML 1.1

typedef struct chitu_zip {
    zip_writer *zip;
    const job_desc *d;
} chitu_zip;

static void key(FILE *f, const char *name, double v, int decimals)
{
    fprintf(f, ";%s:", name);
    zip_number(f, v, decimals);
    fputc('\n', f);
}

/* A move: "G0 Z5.05 F65;", mm and mm/min. */
static void move(FILE *f, const char *g, double z, double mm_per_s)
{
    fprintf(f, "%s Z", g);
    zip_number(f, z, 6);
    fputs(" F", f);
    zip_number(f, mm_per_min(mm_per_s), 3);
    fputs(";\n", f);
}

static void write_gcode(FILE *f, const void *ctx)
{
    const job_desc *d = (const job_desc *)ctx;
    const job_motion *m = &d->motion;
    /* the end block raises the plate to the top of the machine */
    double top = d->z_max_mm > 0 ? d->z_max_mm : d->layers[d->layer_count - 1].z_top + m->lift_mm;
    double ml = d->volume_mm3 / 1000, wait_ms = m->wait_before_cure_s * 1000;
    int mirror = d->mirror_x || d->mirror_y;
    size_t k;

    fputs(";fileName:", f);
    for (const char *s = d->model ? base_name(d->model) : "adaslice"; *s; s++)
        fputc(*s == '\n' || *s == '\r' ? '_' : *s, f);
    fprintf(f, "\n;machineType:%s\n", d->preset ? d->preset->machine : "default");
    key(f, "estimatedPrintTime", d->print_time_s, 2);
    key(f, "volume", ml, 3);
    fputs(";resin:normal\n", f);
    key(f, "weight", ml * RESIN_G_PER_ML, 3);
    fputs(";price:0\n", f); /* no price is known */
    key(f, "layerHeight", d->layer_height_mm, 6);
    fprintf(f, ";resolutionX:%d\n;resolutionY:%d\n", d->width, d->height);
    key(f, "machineX", d->display_mm[0], 6);
    key(f, "machineY", d->display_mm[1], 6);
    key(f, "machineZ", top, 6);
    fprintf(f, ";projectType:%s\n;transitionLayerCount:0\n;transitionLayerType:0\n", mirror ? "LCD_mirror" : "Normal");
    key(f, "normalExposureTime", d->exposure_s, 3);
    key(f, "bottomLayExposureTime", d->bottom_exposure_s, 3); /* sic, beside the next: ChiTuBox writes both */
    key(f, "bottomLayerExposureTime", d->bottom_exposure_s, 3);
    key(f, "normalDropSpeed", mm_per_min(m->retract_speed), 3);
    key(f, "normalLayerLiftHeight", m->lift_mm, 6);
    fputs(";zSlowUpDistance:0\n", f);
    key(f, "normalLayerLiftSpeed", mm_per_min(m->lift_speed), 3);
    fprintf(f, ";bottomLayCount:%u\n;bottomLayerCount:%u\n", d->bottom_layers, d->bottom_layers);
    fprintf(f, ";shrinkageX:100\n;shrinkageY:100\n;shrinkageZ:100\n;mirror:%d\n;totalLayer:%zu\n", mirror,
            d->layer_count);
    key(f, "bottomLayerLiftHeight", job_lift_mm(m, 1), 6);
    key(f, "bottomLayerLiftSpeed", mm_per_min(job_lift_speed(m, 1)), 3);
    key(f, "bottomLightOffTime", m->wait_before_cure_s, 3);
    key(f, "lightOffTime", m->wait_before_cure_s, 3);
    fputs(";START_GCODE_BEGIN\nG21;\nG90;\nM106 S0;\nG28 Z0;\n\n;START_GCODE_END\n\n", f);

    /* Each layer's peel comes before its exposure, from the layer below (the
       first rises from the homed Z0): up by the lift, down to the layer's top. */
    for (k = 0; k < d->layer_count; k++) {
        const job_layer *l = &d->layers[k];
        int bottom = k < d->bottom_layers;
        fprintf(f, ";LAYER_START:%zu\n;currPos:", k);
        zip_number(f, l->z_top, 6);
        fprintf(f, "\nM6054 \"%zu.png\";show Image\n", k + 1);
        move(f, "G0", l->z_top + job_lift_mm(m, bottom), job_lift_speed(m, bottom));
        move(f, "G0", l->z_top, m->retract_speed);
        fprintf(f, "G4 P%.0f;\nM106 S255;light on\nG4 P%.0f;\nM106 S0; light off\n\n;LAYER_END\n\n", wait_ms,
                l->exposure_s * 1000);
    }
    fputs(";END_GCODE_BEGIN\nM106 S0;\n", f);
    move(f, "G1", top, 25.0 / 60); /* ChiTuBox's slow F25 */
    fputs("M18;\n\n;END_GCODE_END\n", f);
}

static int open_job(void **writer, const char *path, const job_desc *d)
{
    chitu_zip *w;
    int rc;
    *writer = NULL;
    if (!d->layer_count) return complain(RC_FAIL, "cannot write %s: the job has no layers", path);
    if (!(w = (chitu_zip *)calloc(1, sizeof *w))) return complain(RC_FAIL, "cannot write %s: out of memory", path);
    w->d = d;
    if ((rc = zip_open(&w->zip, path))) {
        free(w);
        return rc;
    }
    if ((rc = zip_add_preview_png(w->zip, "preview.png", d, PREVIEW_W, PREVIEW_H)) ||
        (rc = zip_add_preview_png(w->zip, "preview_cropping.png", d, CROPPING_W, CROPPING_H))) {
        zip_close(w->zip, 0);
        free(w);
        return rc;
    }
    *writer = w;
    return RC_OK;
}

static int encode(const void *writer, size_t k, const unsigned char *image, size_t stride, job_blob *blob)
{
    (void)k;
    return zip_layer_png(((const chitu_zip *)writer)->d, image, stride, blob);
}

static int put(void *writer, size_t k, job_blob *blob)
{
    chitu_zip *w = (chitu_zip *)writer;
    char name[32];
    snprintf(name, sizeof name, "%zu.png", k + 1);
    return zip_add_blob(w->zip, name, blob);
}

/* run.gcode goes last: its header holds the volume, known once every layer is in. */
static int close_job(void *writer, int ok)
{
    chitu_zip *w = (chitu_zip *)writer;
    int rc = ok ? zip_add_text(w->zip, "run.gcode", write_gcode, w->d) : RC_FAIL, closed;
    closed = zip_close(w->zip, rc == RC_OK);
    free(w);
    return rc ? rc : closed;
}

const job_format JOB_FORMAT_CHITU_ZIP = {
    .name = "chitu-zip",
    .extension = ".zip",
    .what = "ChiTu G-code zip",
    .min_layer_mm = 0.01,
    .adaptive = 1,
    .max_layers = ZIP_MEMBERS_MAX - 3, /* two previews, run.gcode */
    .open = open_job,
    .encode = encode,
    .put = put,
    .close = close_job,
    .previews = {{PREVIEW_W, PREVIEW_H}, {CROPPING_W, CROPPING_H}},
};
