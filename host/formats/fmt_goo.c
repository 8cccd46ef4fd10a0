/* Elegoo .goo job files, "V3.0", big-endian: the 195477-byte header (with
   the 116 x 116 and 290 x 290 RGB565 previews), per layer a 70-byte
   definition and the image (0x55, run-length chunks, a checksum), each
   followed by 0D 0A, and the 11-byte ending.

   Byte layouts: UVtools, UVtools.Core/FileFormats/GooFile.cs (FileHeader,
   LayerDef, EncodeImage/DecodeImage, whose comments quote Elegoo's
   specification, FileFooter), checked against mslicer's format/goo_format;
   the facts, and where the sources disagree, are in the project's notes on
   resin formats (resin_formats.md).

   Each layer is encoded as it arrives and streamed through one fixed buffer,
   the checksum summed on the way; its DataLength, which precedes the data, is
   written after it by seeking back, and the header's fields (the volume is
   known only at close) again at close.

   Phrozen's .prz (the Sonic Mini 8K S) is the same file: UVtools reads and
   writes it with GooFile (its "prz" extension, added in v3.14.0, d8c42c6b),
   and since v4.1.0 (f0de25c0) writes it without diff chunks, which that
   printer's firmware decodes wrongly (UVtools issues 776, 810, 814): a
   layer's grey runs there are whole grey chunks. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* fseeko, localtime_r */
#endif
#include "../bytes.h"
#include "jobfile.h"
#include "../report.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <time.h>

#define GOO_HEADER 195477u          /* also the LayerDefAddress */
#define GOO_SMALL_PREVIEW 194u      /* 116 x 116, then 0D 0A */
#define GOO_BIG_PREVIEW 27108u      /* 290 x 290, then 0D 0A */
#define GOO_FIELDS 195310u          /* the fields after the previews */
#define GOO_LAYER_DEF 70u
#define GOO_RUN_MAX 0x0FFFFFFFu     /* the longest run one chunk can hold (28 bits) */
#define GOO_DIFF_RUN_MAX 255u       /* a diff chunk's run is one byte */
#define GOO_CHUNK_MAX 5             /* bytes of the longest chunk */

static const unsigned char goo_magic[8] = {0x07, 0x00, 0x00, 0x00, 0x44, 0x4C, 0x50, 0x00};

typedef struct goo_writer {
    job_file file;
    const job_desc *d;          /* read again at close: the volume is known only then */
    off_t end;                  /* where the next layer's definition goes */
} goo_writer;

/* A fixed-width text field: cut to leave room for the NUL, NUL-padded. */
static void put_text(unsigned char *p, size_t width, const char *s)
{
    size_t n = strlen(s);
    if (n > width - 1) n = width - 1;
    memcpy(p, s, n);
}



static double build_height_mm(const job_desc *d)
{
    /* An unknown build height: the job's own is the least the printer has. */
    return d->z_max_mm > 0 ? d->z_max_mm : d->layers[d->layer_count - 1].z_top;
}

/* Advance mode ("0: normal mode; 1: advance mode, printing use the value of
   'Layer Definition Content'", Elegoo's specification) is what makes the
   printer take each layer's own Z and exposure. UVtools sets it only when a
   layer differs from the header's globals (GooFile.cs @7b510f0d,
   OnBeforeEncode: SupportPerLayerSettings && UsingPerLayerSettings), as
   printers have frozen or started high with it on (UVtools #997, #1013,
   #1040); so a job the globals describe leaves it off. That is a job whose
   layers, the top one aside, each end at layer_height_mm times its number
   and are exposed for the header's bottom or normal time (UVtools'
   Layer.IsUsingGlobalParameters, with its tolerances: 0.001 mm, 0.01 s).
   The top layer is what is left of the part: without advance mode it is
   cured a whole layer thick at the normal time, which is what the normal
   time is for. */
static int advance_mode(const job_desc *d)
{
    size_t k;
    for (k = 0; k + 1 < d->layer_count; k++) {
        const job_layer *L = &d->layers[k];
        double exposure = k < d->bottom_layers ? d->bottom_exposure_s : d->exposure_s;
        if (fabs(L->z_top - d->layer_height_mm * (double)(k + 1)) > 0.001 || fabs(L->exposure_s - exposure) > 0.01)
            return 1;
    }
    return 0;
}

/* ---- the header -------------------------------------------------------- */

/* RGB565, big-endian words, rows top first; no size is stored. */
static int put_preview(goo_writer *w, unsigned char *to, int side)
{
    size_t pixels = (size_t)side * (size_t)side, i;
    unsigned char *rgb = (unsigned char *)calloc(pixels, 3);
    if (!rgb || (w->d->preview && w->d->preview(w->d->preview_ctx, side, side, rgb) != 0)) {
        free(rgb);
        return complain(RC_FAIL, "cannot write %s: out of memory for the %dx%d preview", w->file.path, side, side);
    }
    for (i = 0; i < pixels; i++) {
        const unsigned char *p = rgb + i * 3;
        put_be16(to + i * 2, (unsigned)(p[0] >> 3) << 11 | (unsigned)(p[1] >> 2) << 5 | (unsigned)(p[2] >> 3));
    }
    to[pixels * 2] = 0x0D;
    to[pixels * 2 + 1] = 0x0A;
    free(rgb);
    return RC_OK;
}

/* The header's first 194 bytes: names and levels. */
static void put_names(const goo_writer *w, unsigned char *h)
{
    const job_desc *d = w->d;
    char created[24];
    int fixed;
    time_t now = job_time(&fixed);
    struct tm t;
    if (!(fixed ? gmtime_r(&now, &t) : localtime_r(&now, &t)) || !strftime(created, sizeof created, "%Y-%m-%d %H:%M:%S", &t))
        created[0] = 0;
    memcpy(h, "V3.0", 4);
    memcpy(h + 4, goo_magic, sizeof goo_magic);
    put_text(h + 12, 32, "adaslice");
    put_text(h + 44, 24, ADASLICE_VERSION);
    put_text(h + 68, 24, created);
    put_text(h + 92, 32, d->preset && d->preset->machine ? d->preset->machine : "adaslice");
    put_text(h + 124, 32, "DLP"); /* MachineType as UVtools writes it (mslicer: "Default") */
    put_text(h + 156, 32, "adaslice");
    put_be16(h + 188, (unsigned)(d->supersample > 1 ? d->supersample : 1));
    put_be16(h + 190, 1); /* GreyLevel, as UVtools */
}

/* The fields from 195310 to the end of the header. */
static void put_fields(const goo_writer *w, unsigned char *f)
{
    const job_desc *d = w->d;
    const job_motion *m = &d->motion;
    double wait_s = m->wait_before_cure_s;
    put_be32(f, (uint32_t)d->layer_count);
    put_be16(f + 4, (unsigned)d->width);
    put_be16(f + 6, (unsigned)d->height);
    f[8] = d->mirror_x != 0;
    f[9] = d->mirror_y != 0;
    put_be_f32(f + 10, d->display_mm[0]);
    put_be_f32(f + 14, d->display_mm[1]);
    put_be_f32(f + 18, build_height_mm(d));
    put_be_f32(f + 22, d->layer_height_mm);
    put_be_f32(f + 26, d->exposure_s);
    /* Wait-time mode: the rest before each exposure is a WaitTimeBeforeCure
       and the light-off delay stays 0 (UVtools sets the two so). */
    f[30] = 1;
    put_be_f32(f + 43, wait_s); /* BottomWaitTimeBeforeCure */
    put_be_f32(f + 55, wait_s); /* WaitTimeBeforeCure */
    put_be_f32(f + 59, d->bottom_exposure_s);
    put_be32(f + 63, d->bottom_layers);
    put_be_f32(f + 67, job_lift_mm(m, 1));
    put_be_f32(f + 71, mm_per_min(job_lift_speed(m, 1)));
    put_be_f32(f + 75, m->lift_mm);
    put_be_f32(f + 79, mm_per_min(m->lift_speed));
    /* One-stage moves: retract all the way the lift went; the second stages
       are 0 mm at the first stages' speeds. */
    put_be_f32(f + 83, job_lift_mm(m, 1));
    put_be_f32(f + 87, mm_per_min(m->retract_speed));
    put_be_f32(f + 91, m->lift_mm);
    put_be_f32(f + 95, mm_per_min(m->retract_speed));
    put_be_f32(f + 103, mm_per_min(job_lift_speed(m, 1)));
    put_be_f32(f + 111, mm_per_min(m->lift_speed));
    put_be_f32(f + 119, mm_per_min(m->retract_speed));
    put_be_f32(f + 127, mm_per_min(m->retract_speed));
    put_be16(f + 131, 255);
    put_be16(f + 133, 255);
    f[135] = (unsigned char)advance_mode(d);
    put_be32(f + 136, (uint32_t)(d->print_time_s > 0 ? d->print_time_s + 0.5 : 0));
    put_be_f32(f + 140, d->volume_mm3);
    /* MaterialGrams: UVtools writes the millilitres there; we know no density. */
    put_be_f32(f + 144, d->volume_mm3 / 1000.0);
    put_text(f + 152, 8, "$");
    put_be32(f + 160, GOO_HEADER);
    f[164] = 1; /* GrayScaleLevel: grey 0x00-0xFF */
}

static void write_header_fields(goo_writer *w)
{
    unsigned char names[GOO_SMALL_PREVIEW] = {0}, fields[GOO_HEADER - GOO_FIELDS] = {0};
    put_names(w, names);
    put_fields(w, fields);
    job_file_write_at(&w->file, 0, names, sizeof names);
    job_file_write_at(&w->file, GOO_FIELDS, fields, sizeof fields);
}

/* ---- layer images: 0x55, chunks, checksum -------------------------------- */

/* A layer being coded: its runs, into a blob. */
typedef struct goo_coder {
    job_blob *out;
    unsigned run_grey;           /* the pending run */
    uint64_t run_length;
    unsigned previous_grey;      /* the pixel before it: diff chunks are relative to it */
    int diff_chunks;             /* 0: none (.prz) */
    int failed;                  /* out of memory */
} goo_coder;

/* The pending run as chunks. byte0[7:6]: 00 black, 11 white, 01 the grey in
   the next byte, each with byte0[5:4] extra length bytes (run =
   b1.. << 4 | byte0[3:0]); 10 a diff of up to 15 from the previous pixel,
   byte0[5] its sign, byte0[4] a run byte following (else a run of 1). Diff
   chunks as UVtools uses them: for greys between 0 and 255 and runs up to
   255 (none when c->diff_chunks is 0). Longer runs are cut. */
static void emit_run(goo_coder *c)
{
    uint64_t left = c->run_length;
    unsigned v = c->run_grey;
    while (left && !c->failed) {
        uint32_t n = left > GOO_RUN_MAX ? GOO_RUN_MAX : (uint32_t)left;
        unsigned prev = c->previous_grey, diff = v > prev ? v - prev : prev - v;
        unsigned char *p;
        if (job_blob_reserve(c->out, GOO_CHUNK_MAX)) { c->failed = 1; break; }
        p = c->out->data + c->out->size;
        if (c->diff_chunks && v > 0 && v < 255 && diff <= 15 && n <= GOO_DIFF_RUN_MAX) {
            *p++ = (unsigned char)(0x80 | (v < prev ? 0x20 : 0) | (n > 1 ? 0x10 : 0) | diff);
            if (n > 1) *p++ = (unsigned char)n;
        } else {
            unsigned char *b0 = p++;
            *b0 = (unsigned char)((v == 0 ? 0x00 : v == 255 ? 0xC0 : 0x40) | (n & 0x0F));
            if (v != 0 && v != 255) *p++ = (unsigned char)v;
            if (n > 0xFFFFF) {
                *b0 |= 0x30;
                *p++ = (unsigned char)(n >> 20);
                *p++ = (unsigned char)(n >> 12);
                *p++ = (unsigned char)(n >> 4);
            } else if (n > 0xFFF) {
                *b0 |= 0x20;
                *p++ = (unsigned char)(n >> 12);
                *p++ = (unsigned char)(n >> 4);
            } else if (n > 0xF) {
                *b0 |= 0x10;
                *p++ = (unsigned char)(n >> 4);
            }
        }
        c->out->size = (size_t)(p - c->out->data);
        c->previous_grey = v;
        left -= n;
    }
    c->run_length = 0;
}

/* Runs cross rows: the image is one row-major stream. mask_row_runs hands
   each run here. */
static void take_run(void *coder, unsigned grey, uint64_t n)
{
    goo_coder *c = (goo_coder *)coder;
    if (grey != c->run_grey) {
        emit_run(c);
        c->run_grey = grey;
    }
    c->run_length += n;
}

static void put_layer_def(const goo_writer *w, size_t k, unsigned char *e)
{
    const job_desc *d = w->d;
    const job_motion *m = &d->motion;
    int bottom = k < d->bottom_layers;
    double lift = job_lift_mm(m, bottom);
    double speed = mm_per_min(job_lift_speed(m, bottom));
    put_be_f32(e + 2, build_height_mm(d)); /* PausePositionZ, as UVtools and mslicer */
    put_be_f32(e + 6, d->layers[k].z_top);
    put_be_f32(e + 10, d->layers[k].exposure_s);
    put_be_f32(e + 26, m->wait_before_cure_s);
    put_be_f32(e + 30, lift);
    put_be_f32(e + 34, speed);
    put_be_f32(e + 42, speed);
    put_be_f32(e + 46, lift);
    put_be_f32(e + 50, mm_per_min(m->retract_speed));
    put_be_f32(e + 58, mm_per_min(m->retract_speed));
    put_be16(e + 62, 255);
    e[64] = 0x0D;
    e[65] = 0x0A;
}

/* The layer's data as DataLength counts it: the 0x55, the chunks and the
   checksum (the NOT of the chunks' sum, the magic left out). */
static int encode_runs(const goo_writer *w, size_t k, const unsigned char *image, size_t stride, job_blob *blob,
                       int diff_chunks)
{
    const job_desc *d = w->d;
    goo_coder c;
    unsigned sum = 0;
    size_t i;
    int y;
    memset(&c, 0, sizeof c);
    c.out = blob;
    c.diff_chunks = diff_chunks;
    if (job_blob_reserve(blob, 1)) return complain(RC_FAIL, "%s: out of memory coding layer %zu", w->file.path, k + 1);
    blob->data[blob->size++] = 0x55;
    for (y = 0; y < d->height; y++) mask_row_runs(image + (size_t)y * stride, d->bits, d->width, take_run, &c);
    emit_run(&c);
    if (c.failed || job_blob_reserve(blob, 1))
        return complain(RC_FAIL, "%s: out of memory coding layer %zu", w->file.path, k + 1);
    for (i = 1; i < blob->size; i++) sum += blob->data[i];
    blob->data[blob->size++] = (unsigned char)~sum;
    if (blob->size > 0xFFFFFFFFu)
        return complain(RC_FAIL, "%s: layer %zu encodes to %zu bytes, more than a goo layer can hold", w->file.path,
                        k + 1, blob->size);
    return RC_OK;
}

static int encode(const void *writer, size_t k, const unsigned char *image, size_t stride, job_blob *blob)
{
    return encode_runs((const goo_writer *)writer, k, image, stride, blob, 1);
}

static int encode_prz(const void *writer, size_t k, const unsigned char *image, size_t stride, job_blob *blob)
{
    return encode_runs((const goo_writer *)writer, k, image, stride, blob, 0);
}

/* The layer's definition, its data and the 0D 0A after each, in order. */
static int put(void *writer, size_t k, job_blob *blob)
{
    goo_writer *w = (goo_writer *)writer;
    unsigned char def[GOO_LAYER_DEF] = {0};
    size_t size = blob->size;
    put_layer_def(w, k, def);
    put_be32(def + 66, (uint32_t)size);
    job_file_write_at(&w->file, w->end, def, sizeof def);
    job_file_append(&w->file, blob->data, size);
    job_file_append(&w->file, "\r\n", 2);
    free(blob->data);
    blob->data = NULL;
    if (w->file.err) return job_file_check(&w->file);
    w->end += (off_t)(GOO_LAYER_DEF + size + 2);
    return RC_OK;
}

/* ---- open and close ------------------------------------------------------ */

static int open_job(void **writer, const char *path, const job_desc *d)
{
    goo_writer *w;
    unsigned char *header;
    int rc;
    *writer = NULL;
    if (d->width > 0xFFFF || d->height > 0xFFFF)
        return complain(RC_FAIL, "%s: a goo job holds at most 65535 pixels across and down (%dx%d)", path, d->width,
                        d->height);
    if (d->layer_count > 0xFFFFFFFFu)
        return complain(RC_FAIL, "%s: %zu layers are more than a goo file can count", path, d->layer_count);
    w = (goo_writer *)calloc(1, sizeof *w);
    header = (unsigned char *)calloc(1, GOO_HEADER);
    if (!w || !header) {
        free(w);
        free(header);
        return complain(RC_FAIL, "cannot write %s: out of memory", path);
    }
    if ((rc = job_file_open(&w->file, path)) != RC_OK) {
        free(w);
        free(header);
        return rc;
    }
    w->d = d;
    if ((rc = put_preview(w, header + GOO_SMALL_PREVIEW, 116)) == RC_OK &&
        (rc = put_preview(w, header + GOO_BIG_PREVIEW, 290)) == RC_OK) {
        job_file_write_at(&w->file, 0, header, GOO_HEADER);
        write_header_fields(w);
        rc = job_file_check(&w->file);
    }
    free(header);
    if (rc != RC_OK) {
        job_file_discard(&w->file);
        free(w);
        return rc;
    }
    w->end = GOO_HEADER;
    *writer = w;
    return RC_OK;
}

static int close_job(void *writer, int ok)
{
    static const unsigned char ending[11] = {0x00, 0x00, 0x00, 0x07, 0x00, 0x00, 0x00, 0x44, 0x4C, 0x50, 0x00};
    goo_writer *w = (goo_writer *)writer;
    int rc = RC_OK;
    if (!w) return ok ? RC_FAIL : RC_OK;
    if (ok) {
        job_file_write_at(&w->file, w->end, ending, sizeof ending);
        write_header_fields(w);
        rc = job_file_commit(&w->file);
    }
    job_file_discard(&w->file); /* after a commit there is nothing left to discard */
    free(w);
    return rc;
}

const job_format JOB_FORMAT_GOO = {
    .name = "goo",
    .extension = ".goo",
    .what = "Elegoo GOO",
    .min_layer_mm = 0.01,
    .adaptive = 1,
    .open = open_job,
    .encode = encode,
    .put = put,
    .close = close_job,
    .previews = {{116, 116}, {290, 290}},
};
const job_format JOB_FORMAT_PRZ = {
    .name = "prz",
    .extension = ".prz",
    .what = "Phrozen PRZ (GOO without diff runs)",
    .min_layer_mm = 0.01,
    .adaptive = 1,
    .open = open_job,
    .encode = encode_prz,
    .put = put,
    .close = close_job,
    .previews = {{116, 116}, {290, 290}},
};
