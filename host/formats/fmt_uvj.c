/* UVtools' vendor-neutral job (.uvj): a zip of config.json, one 8-bit grey
   PNG per layer (slice/00000000.png on, numbered from 0) and the previews
   preview/tiny.png (400 x 400) and preview/huge.png (800 x 480). UVtools
   opens it with every layer's own Z, exposure and moves, so an adaptive job
   goes through it to any format UVtools writes.

   The layout is UVtools', UVtools.Core/FileFormats/UVJFile.cs at 7b510f0d
   (v6.1.0): config.json is its Settings class as System.Text.Json writes and
   reads it without options, so its keys are the C# property names, matched
   case-sensitively; numbers are plain JSON numbers, X, Y, Count, Layers,
   LightPWM and AntiAliasLevel integers (ushort, uint, byte). UVtools needs
   config.json and Properties.Size.Layers PNGs, found by the digits of their
   file names (FileFormat.cs, DecodeLayersFromZip); the previews may be
   missing. Times are in seconds, heights in mm, speeds in mm/min; UVtools
   rounds each Z to 0.001 mm (Layer.cs, RoundHeight). The file holds no
   mirror: the images are stored as the printer shows them, as in every
   other format. */
#include "jobfile.h"
#include "../json.h"
#include "../report.h"
#include "../codec/zip.h"

#include <stdio.h>
#include <stdlib.h>

enum { TINY_W = 400, TINY_H = 400, HUGE_W = 800, HUGE_H = 480 }; /* UVJFile ThumbnailsOriginalSize */
#define UVJ_USHORT_MAX 65535        /* Size.X, Size.Y and Bottom.Count are ushort */
#define UVJ_AA_MAX 16               /* UVtools clamps AntiAliasLevel to 1..16 */

typedef struct uvj {
    zip_writer *zip;
    const job_desc *d;
} uvj;

/* One of UVtools' Exposure objects (the file's two defaults and every
   layer's): a wait, then the light, then a one-stage peel that comes all the
   way back (the second stages are 0 mm, at the first stages' speeds). The
   wait before the cure is the printer's rest; the light-off delay, UVtools'
   other way of saying a rest, is 0 beside it. */
static void exposure(json_writer *j, const job_desc *d, double exposure_s, int bottom)
{
    const job_motion *m = &d->motion;
    double lift = job_lift_mm(m, bottom);
    double lift_speed = mm_per_min(job_lift_speed(m, bottom)), retract_speed = mm_per_min(m->retract_speed);
    json_number(j, "WaitTimeBeforeCure", m->wait_before_cure_s);
    json_int(j, "LightOffTime", 0);
    json_number(j, "LightOnTime", exposure_s);
    json_int(j, "LightPWM", 255);
    json_int(j, "WaitTimeAfterCure", 0);
    json_number(j, "LiftHeight", lift);
    json_number(j, "LiftSpeed", lift_speed);
    json_int(j, "LiftHeight2", 0);
    json_number(j, "LiftSpeed2", lift_speed);
    json_int(j, "WaitTimeAfterLift", 0);
    json_number(j, "RetractHeight", lift);
    json_number(j, "RetractSpeed", retract_speed);
    json_int(j, "RetractHeight2", 0);
    json_number(j, "RetractSpeed2", retract_speed);
}

static void write_config(FILE *f, const void *ctx)
{
    const job_desc *d = (const job_desc *)ctx;
    int aa = d->supersample > 1 ? d->supersample : 1;
    json_writer j;
    size_t k;
    json_init(&j, f);
    json_begin_object(&j, NULL, 0);
    json_begin_object(&j, "Properties", 0);
    json_begin_object(&j, "Size", 0);
    json_int(&j, "X", d->width);
    json_int(&j, "Y", d->height);
    json_begin_object(&j, "Millimeter", 1);
    json_number(&j, "X", d->display_mm[0]);
    json_number(&j, "Y", d->display_mm[1]);
    json_end(&j);
    json_int(&j, "Layers", (long long)d->layer_count);
    json_number(&j, "LayerHeight", d->layer_height_mm);
    json_end(&j);
    json_begin_object(&j, "Exposure", 0);
    exposure(&j, d, d->exposure_s, 0);
    json_end(&j);
    json_begin_object(&j, "Bottom", 0);
    exposure(&j, d, d->bottom_exposure_s, 1);
    json_int(&j, "Count", d->bottom_layers);
    json_end(&j);
    json_int(&j, "AntiAliasLevel", aa < UVJ_AA_MAX ? aa : UVJ_AA_MAX);
    json_end(&j);
    json_begin_array(&j, "Layers", 0);
    for (k = 0; k < d->layer_count; k++) {
        json_begin_object(&j, NULL, 1);
        json_number(&j, "Z", d->layers[k].z_top);
        json_begin_object(&j, "Exposure", 1);
        exposure(&j, d, d->layers[k].exposure_s, k < d->bottom_layers);
        json_end(&j);
        json_end(&j);
    }
    json_end(&j);
    json_end(&j);
}

/* config.json first, as UVtools writes it: all it says is known before the
   first layer, and a reader finds the layer count before the layers. */
static int open_job(void **writer, const char *path, const job_desc *d)
{
    uvj *w;
    int rc;
    *writer = NULL;
    if (!d->layer_count) return complain(RC_FAIL, "cannot write %s: the job has no layers", path);
    if (d->width > UVJ_USHORT_MAX || d->height > UVJ_USHORT_MAX || d->bottom_layers > UVJ_USHORT_MAX)
        return complain(RC_USAGE, "cannot write %s: UVtools reads a .uvj of up to %d pixels across and down and %d "
                        "bottom layers, and this job has %d x %d pixels and %u bottom layers", path, UVJ_USHORT_MAX,
                        UVJ_USHORT_MAX, d->width, d->height, d->bottom_layers);
    if (!(w = (uvj *)calloc(1, sizeof *w))) return complain(RC_FAIL, "cannot write %s: out of memory", path);
    w->d = d;
    if ((rc = zip_open(&w->zip, path))) {
        free(w);
        return rc;
    }
    if ((rc = zip_add_text(w->zip, "config.json", write_config, d)) ||
        (rc = zip_add_preview_png(w->zip, "preview/tiny.png", d, TINY_W, TINY_H)) ||
        (rc = zip_add_preview_png(w->zip, "preview/huge.png", d, HUGE_W, HUGE_H))) {
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
    return zip_layer_png(((const uvj *)writer)->d, image, stride, blob);
}

static int put(void *writer, size_t k, job_blob *blob)
{
    uvj *w = (uvj *)writer;
    char name[32];
    snprintf(name, sizeof name, "slice/%08zu.png", k);
    return zip_add_blob(w->zip, name, blob);
}

static int close_job(void *writer, int ok)
{
    uvj *w = (uvj *)writer;
    int rc = zip_close(w->zip, ok);
    free(w);
    return rc;
}

const job_format JOB_FORMAT_UVJ = {
    .name = "uvj",
    .extension = ".uvj",
    .what = "UVtools UVJ, any printer's: UVtools converts it",
    .min_layer_mm = 0.01,
    .adaptive = 1,
    .max_layers = ZIP_MEMBERS_MAX - 3, /* config.json, two previews */
    .open = open_job,
    .encode = encode,
    .put = put,
    .close = close_job,
    .previews = {{TINY_W, TINY_H}, {HUGE_W, HUGE_H}},
};
