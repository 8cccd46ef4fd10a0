/* Job files: what adaslice slice writes for the printers and slicers people
   own (a ChiTuBox .ctb, an Elegoo .goo, a Phrozen .prz, a ChiTu G-code .zip, a
   Prusa .sl1, UVtools' .uvj, or the job directory of jobdir.h). Every format is written through one layer
   loop (pipeline.h): the masker renders each layer once, bottom-up (in
   row bands on several threads), the
   format's `encode` codes it (on any thread) and its `put` puts it into the
   job (in order); what the format needs besides the
   images (every layer's Z and exposure, the printer, the motion, previews) is
   in a job_desc known before the first layer. A file format writes under a
   temporary name and renames it into place on a good close, and the directory
   writes its manifest last, so a failed or interrupted run leaves nothing
   that looks complete. */
#ifndef ADASLICE_HOST_JOBFILE_H
#define ADASLICE_HOST_JOBFILE_H
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <time.h>
#include "../codec/maskrows.h"
#include "../output.h"
#include "../printer.h"

enum { DIR_PLAN_CSV = 1, DIR_PLOT_SVG = 2, DIR_LAYER_SVGS = 4 };

/* One layer as the printer moves and exposes it. */
typedef struct job_layer {
    double z_bottom, z_top;      /* mm above the plate: the part's bottom is at 0 */
    double thickness;            /* mm */
    double exposure_s;           /* UV time, s: the working curve's for its thickness,
                                    or the bottom exposure for the first bottom_layers */
    double lit_mm2;              /* lit area of its mask: set before layer k goes to `layer` */
} job_layer;

/* How the printer moves between layers (the formats' lift/retract and waits). */
typedef struct job_motion {
    double lift_mm;              /* peel: lift after each layer */
    double lift_speed;           /* mm/s */
    double retract_speed;        /* mm/s, back down */
    double wait_before_cure_s;   /* settle: resin at rest before the light goes on */
    double bottom_lift_mm, bottom_lift_speed;   /* the same for the bottom layers */
} job_motion;

/* Everything a format needs besides the images. The writer keeps the pointer:
   it lives until close, and lit_mm2 and volume_mm3 are filled in meanwhile. */
typedef struct job_desc {
    const printer *preset;       /* NULL for a display given by --pixels/--pitch */
    const char *model;           /* the model's file name, for headers */
    int width, height;           /* pixels of each image as stored (after any turn) */
    double pitch[2];             /* mm per stored pixel, across (x) and down (y) */
    double display_mm[2];        /* width * pitch[0], height * pitch[1] */
    double z_max_mm;             /* the printer's build height (0: unknown) */
    int bits;                    /* of the images handed to `layer`: 1 or 8 */
    int supersample;             /* 1: 1-bit masks; s: 8-bit from s x s rays */
    int mirror_x, mirror_y;      /* the images are flipped so for this display */
    int lit_rows[2];             /* the images' rows outside [0, 1) are dark in every layer, and
                                    coders need not read them ({0, 0}: any row may be lit) */
    size_t layer_count;
    const job_layer *layers;     /* all layer_count, bottom first */
    double exposure_s;           /* the normal layers' exposure for headers that hold
                                    one: the thinnest layer's, the top one aside */
    double bottom_exposure_s;
    unsigned bottom_layers;
    double layer_height_mm;      /* for headers that hold one: the thinnest layer, the top one aside */
    job_motion motion;
    double volume_mm3;           /* of the part (sum of lit area x thickness): known
                                    at close, as are the layers' lit_mm2 */
    double print_time_s;         /* estimated: exposures, waits and moves */
    /* What the plan was, for the formats that record it (the directory's manifest) */
    const char *metric, *method, *slice_at;
    double eps, bin_mm;          /* the plan's error bound; its bin (every thickness is
                                    a whole number of bins) */
    double cure[3];              /* the working curve: S seconds cure T mm, Dp mm (0: every
                                    layer gets S) */
    double part_mm[3], place_mm[2];
    int rotate;                  /* quarter turns, as --rotate */
    /* The directory format: the files the caller writes into it besides the
       writer's own (DIR_*), listed in its manifest and removed with it; and
       dir_force: write into a directory that holds files and no manifest. */
    unsigned dir_extras;
    int dir_force;
    /* A shaded picture of the part, w x h pixels, 3 bytes (R, G, B) a pixel,
       rows top first, for the formats' previews; 0 or -1 (out of memory). */
    int (*preview)(void *ctx, int w, int h, unsigned char *rgb);
    void *preview_ctx;
} job_desc;

/* A layer coded as its file holds it (its code, the PNG, ...), in a
   malloc'd buffer: data[0, size) of cap bytes, and a CRC-32 where the format
   keeps one. */
typedef struct job_blob {
    unsigned char *data;
    size_t size, cap;
    uint32_t crc;
} job_blob;
/* Room for `more` bytes after data + size: 0, or -1 when out of memory. */
int job_blob_reserve(job_blob *b, size_t more);

typedef struct job_format {
    const char *name;            /* --format NAME */
    const char *extension;       /* of -o that picks it (".ctb"); NULL: the directory */
    const char *what;            /* for --help */
    double min_layer_mm;         /* a thinner layer cannot be stored or will not print */
    int adaptive;                /* 0: every layer the same thickness (the file holds one) */
    size_t max_layers;           /* the most layers the file holds (0: no limit) */
    /* Begins the file (or directory) at path; RC_OK, or a complaint made and
       *writer NULL with nothing left behind. */
    int (*open)(void **writer, const char *path, const job_desc *d);
    /* Layer k's image coded into *blob (zeroed by the caller): rows top
       first, `stride` bytes apart, d->bits per pixel (1-bit rows packed MSB
       first, 1 = lit). Called for several layers at once on any threads
       (pipeline.h), so it reads the writer and the desc and changes nothing
       shared. RC_OK or a complaint made. */
    int (*encode)(const void *writer, size_t k, const unsigned char *image, size_t stride, job_blob *blob);
    /* If not NULL: the same from the layer's rows read in count bands
       where they were made (mask_band_scan), in place of its image. */
    int (*encode_bands)(const void *writer, size_t k, const mask_band *bands, int count, job_blob *blob);
    /* The coded layers into the file, in order of k, one at a time (on any
       thread; job_put keeps the order); takes the blob's data (and frees it)
       either way. */
    int (*put)(void *writer, size_t k, job_blob *blob);
    /* ok (job_close has seen every layer put): finish and put the file in
       place; !ok: remove what was written. Frees the writer either way. */
    int (*close)(void *writer, int ok);
    /* The sizes (w, h; 0: none) of the previews it asks d->preview for, so
       that they can be drawn ahead on a thread of their own. */
    int previews[2][2];
} job_format;

/* A job being written: the format's writer, and how many layers it has
   taken. Every job goes through these, which keep the guards the formats
   share (layer k only after layers 0 .. k-1, a good close only after all of
   them), so that a format's put and close need not. */
typedef struct job_writer {
    const job_format *format;
    void *state;                 /* the format's writer; NULL once closed */
    const job_desc *d;
    const char *path;            /* the caller's, until close */
    size_t layers_put;
} job_writer;
/* The format's open; RC_OK, or a complaint made and w->state NULL. */
int job_open(job_writer *w, const job_format *f, const char *path, const job_desc *d);
/* The format's put for layer k, which must be the next one; takes the
   blob's data (and frees it) either way. */
int job_put(job_writer *w, size_t k, job_blob *blob);
/* The format's close: ok, and every layer put, finishes the job; anything
   else removes what was written. A writer never opened, or closed, gives
   RC_OK for !ok. */
int job_close(job_writer *w, int ok);
/* encode and put one after the other: a layer on one thread. */
int job_write_layer(job_writer *w, size_t k, const unsigned char *image, size_t stride);

/* The formats: jobdir.c, fmt_ctb.c, fmt_ctb_encrypted.c, fmt_goo.c (.goo and
   .prz), fmt_chitu_zip.c, fmt_sl1.c, fmt_uvj.c. */
extern const job_format JOB_FORMAT_DIR, JOB_FORMAT_CTB, JOB_FORMAT_CTB_ENCRYPTED, JOB_FORMAT_GOO, JOB_FORMAT_PRZ,
    JOB_FORMAT_CHITU_ZIP, JOB_FORMAT_SL1, JOB_FORMAT_UVJ;
extern const job_format *const JOB_FORMATS[];  /* NULL-terminated */
/* The format called `name`, or NULL. */
const job_format *job_format_named(const char *name);
/* The format -o path's extension picks (case-insensitive): the first of
   JOB_FORMATS with it (.ctb: the unencrypted one); NULL for an extension no
   format has, the directory format for a path without one. */
const job_format *job_format_for_path(const char *path);

/* ---- helpers the formats share (and maskrows.h) ---------------------- */

/* The peel after a layer, bottom (one of the first bottom_layers) or not:
   its lift, mm, and speed, mm/s. The bottom ones fall back to the normal
   ones where the motion leaves them 0: a printer that does not peel tears
   the first layers off the plate. */
static inline double job_lift_mm(const job_motion *m, int bottom)
{
    return bottom && m->bottom_lift_mm > 0 ? m->bottom_lift_mm : m->lift_mm;
}
static inline double job_lift_speed(const job_motion *m, int bottom)
{
    return bottom && m->bottom_lift_speed > 0 ? m->bottom_lift_speed : m->lift_speed;
}
/* Seconds that peel takes: up at the lift speed, back at retract_speed. */
static inline double job_peel_s(const job_motion *m, int bottom)
{
    double lift = job_lift_mm(m, bottom), up = job_lift_speed(m, bottom), t = 0;
    if (up > 0) t += lift / up;
    if (m->retract_speed > 0) t += lift / m->retract_speed;
    return t;
}
/* The resin formats keep speeds in mm/min. */
static inline double mm_per_min(double mm_per_s) { return mm_per_s * 60.0; }

/* When the job was made, for the headers that carry it: SOURCE_DATE_EPOCH
   when set (the reproducible-builds convention: the same job, the same
   bytes), else now. *fixed says which; a fixed time is shown in UTC. */
time_t job_time(int *fixed);

/* A job file, through output.h: a regular file under "PATH.tmp.PID" renamed
   into place by job_file_commit (job_file_discard removes it); a device, a
   FIFO or "-" written straight at the commit. */
typedef struct job_file {
    FILE *f;                     /* seekable, whatever the path is */
    char *path;                  /* as given, for messages */
    int err;                     /* the first failed write's errno (0: none) */
    output out;
} job_file;
int job_file_open(job_file *jf, const char *path);
/* n bytes (src NULL: zeros) at byte `at`, or (append) where the last write
   ended. After a failure they write nothing and err keeps why, so a writer
   puts a whole block and looks once: job_file_check, or the commit,
   complains. */
void job_file_write_at(job_file *jf, uint64_t at, const void *src, size_t n);
void job_file_append(job_file *jf, const void *src, size_t n);
/* RC_OK, or the complaint "cannot write PATH: why" made for err. */
int job_file_check(const job_file *jf);
/* Puts the file in place, unless a write failed: then it is removed. */
int job_file_commit(job_file *jf);
void job_file_discard(job_file *jf);
#endif
