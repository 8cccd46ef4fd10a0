/* ChiTuBox .ctb job files, versions 3 and 4, in the plain layout (not the
   AES-wrapped "encrypted CTB" of magic 0x12FD0107), little-endian: the header, both previews (400 x 300 and 200 x 125, RGB15
   run-length), PrintParameters, SlicerInfo with the machine's name, for v4 the
   disclaimer and PrintParametersV4, the 36-byte layer table, and per layer an
   84-byte LayerDefEx followed by the image in CTB's 7-bit run-length code,
   XORed with the EncryptionKey's stream.

   Byte layouts: UVtools, UVtools.Core/FileFormats/ChituboxFile.cs (classes
   Header, Preview, PrintParameters, SlicerInfo, PrintParametersV4, LayerDef,
   LayerDefEx; EncodeInternally for the order of the blocks), checked against
   mslicer's format/ctb_format; the facts, and where the sources disagree, are
   collected in the project's notes on resin formats (resin_formats.md). The
   file is laid out as UVtools writes it; readers follow the offsets.

   Each layer is encoded as it arrives and streamed through one fixed buffer;
   its LayerDefEx (which holds the data's size) is written after the data, by
   seeking back, and the table and the header blocks (the volume is known
   only then) at close. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* fseeko, off_t */
#endif
#include "../bytes.h"
#include "fmt_ctb.h"
#include "../report.h"
#include "../../adaslice_mcu.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <time.h>

#define CTB_MAGIC_V3 0x12FD0086u
#define CTB_MAGIC_V4 0x12FD0106u
#define CTB_HEADER 112
#define CTB_PREVIEW_HEADER 32
#define CTB_PRINT_PARAMS 60
#define CTB_SLICER_INFO 76
#define CTB_PARAMS_V4 464
#define CTB_LAYER_DEF 36
#define CTB_LAYER_DEF_EX 84
#define CTB_RUN_MAX 0x0FFFFFFFu     /* the longest run one code can hold (28 bits) */
#define CTB_PREVIEW_RUN_MAX 0xFFF   /* pixels per preview run word pair (UVtools RLE16EncodingLimit) */
#define CTB_CODE_MAX 5              /* bytes of the longest run code */

/* The v4 header text, exactly as ChiTuBox writes it (320 bytes, no NUL; the
   double full stop is in the original). */
const char ctb_disclaimer[] =
    "Layout and record format for the ctb and cbddlp file types are the copyrighted programs or codes of "
    "CBD Technology (China) Inc..The Customer or User shall not in any manner reproduce, distribute, modify, "
    "decompile, disassemble, decrypt, extract, reverse engineer, lease, assign, or sublicense the said "
    "programs or codes.";

typedef struct ctb_writer {
    job_file file;
    const job_desc *d;          /* read again at close: the volume is known only then */
    unsigned version;
    uint32_t key;               /* EncryptionKey: the layers' code is XORed with its stream */
    const char *machine;
    uint32_t small_preview_at, print_params_at, slicer_at, disclaimer_at, params_v4_at, table_at;
    unsigned char *table;       /* layer_count entries of 36 bytes, written at close */
    off_t end;                  /* where the next layer's LayerDefEx goes */
} ctb_writer;



static int is_bottom(const ctb_writer *w, size_t k) { return k < w->d->bottom_layers; }

/* The settle before each exposure. v4 has rests: like UVtools, a file with
   a rest before cure keeps its light-off delays 0 so that the printer does
   not wait twice. v3 has only the light-off delay, and a v3 printer counts it
   from the end of the exposure, through the peel: the resin rests only for
   what is left of it after the lift and retract. So v3 gets the peel's time
   plus the settle, as UVtools writes it (ChituboxFile.cs, WaitTimeBeforeCure
   below v4 -> FileFormat.SetLightOffDelay -> OperationCalculator.LightOffDelayC
   .CalculateSeconds), to the hundredth of a second. */
static double light_off_s(const ctb_writer *w, int bottom)
{
    const job_motion *m = &w->d->motion;
    if (w->version >= 4) return 0;
    return floor((job_peel_s(m, bottom) + m->wait_before_cure_s) * 100 + 0.5) / 100;
}
static double rest_before_cure_s(const ctb_writer *w) { return w->version >= 4 ? w->d->motion.wait_before_cure_s : 0; }

/* EncryptionKey: UVtools writes a random one in [255, 2^31 - 1) into every
   ctb it makes (ChituboxFile.cs, EncodeInternally) and codes the layers with
   it; a key of 0 (the layers in clear) is what no current slicer writes. Ours
   is drawn from the job, its size and every layer's Z and exposure, so that
   the same job gives the same bytes. */
static uint32_t job_key(const job_desc *d)
{
    unsigned char b[8];
    uint32_t crc;
    size_t k;
    put_le32(b, (uint32_t)d->width);
    put_le32(b + 4, (uint32_t)d->height);
    crc = adaslice_crc32(0, b, 8);
    for (k = 0; k < d->layer_count; k++) {
        put_le_f32(b, d->layers[k].z_top);
        put_le_f32(b + 4, d->layers[k].exposure_s);
        crc = adaslice_crc32(crc, b, 8);
    }
    return 255 + crc % (0x7FFFFFFFu - 255);
}

/* ---- previews --------------------------------------------------------- */

/* RGB15 with bit 5 as the run flag: a flagged word is followed by a count
   word (n - 1) | 0x3000; runs of one or two are plain words. */
size_t ctb_preview_encode(const unsigned char *rgb, size_t pixels, unsigned char *out)
{
    size_t i = 0, n = 0;
    while (i < pixels) {
        const unsigned char *p = rgb + i * 3;
        unsigned word = (unsigned)(p[0] >> 3) << 11 | (unsigned)(p[1] >> 3) << 6 | (unsigned)(p[2] >> 3);
        size_t run = 1;
        while (i + run < pixels && run < CTB_PREVIEW_RUN_MAX && !memcmp(p, p + run * 3, 3)) run++;
        if (run >= 3) {
            put_le16(out + n, word | 0x20);
            put_le16(out + n + 2, (unsigned)(run - 1) | 0x3000);
            n += 4;
        } else {
            put_le16(out + n, word);
            n += 2;
            if (run == 2) { put_le16(out + n, word); n += 2; }
        }
        i += run;
    }
    return n;
}

/* The preview header and its data at `at`; *next: where the next block goes. */
static int write_preview(ctb_writer *w, uint32_t at, int width, int height, uint32_t *next)
{
    size_t pixels = (size_t)width * (size_t)height;
    unsigned char *rgb = (unsigned char *)calloc(pixels, 3);
    unsigned char *code = (unsigned char *)malloc(pixels * 2);
    unsigned char head[CTB_PREVIEW_HEADER] = {0};
    size_t len;
    if (!rgb || !code || (w->d->preview && w->d->preview(w->d->preview_ctx, width, height, rgb) != 0)) {
        free(rgb);
        free(code);
        return complain(RC_FAIL, "cannot write %s: out of memory for the %dx%d preview", w->file.path, width, height);
    }
    len = ctb_preview_encode(rgb, pixels, code);
    put_le32(head, (uint32_t)width);
    put_le32(head + 4, (uint32_t)height);
    put_le32(head + 8, at + CTB_PREVIEW_HEADER);
    put_le32(head + 12, (uint32_t)len);
    job_file_write_at(&w->file, at, head, sizeof head);
    job_file_write_at(&w->file, at + CTB_PREVIEW_HEADER, code, len);
    free(rgb);
    free(code);
    *next = at + CTB_PREVIEW_HEADER + (uint32_t)len;
    return job_file_check(&w->file);
}

/* ---- the header blocks: placeholders at open, final at close ----------- */

static void write_header(ctb_writer *w)
{
    const job_desc *d = w->d;
    unsigned char h[CTB_HEADER] = {0};
    double total_mm = d->layers[d->layer_count - 1].z_top;
    put_le32(h, w->version >= 4 ? CTB_MAGIC_V4 : CTB_MAGIC_V3);
    put_le32(h + 4, w->version);
    put_le_f32(h + 8, d->display_mm[0]);
    put_le_f32(h + 12, d->display_mm[1]);
    /* An unknown build height: the job's own is the least the printer has. */
    put_le_f32(h + 16, d->z_max_mm > 0 ? d->z_max_mm : total_mm);
    put_le_f32(h + 28, total_mm);
    put_le_f32(h + 32, d->layer_height_mm);
    put_le_f32(h + 36, d->exposure_s);
    put_le_f32(h + 40, d->bottom_exposure_s);
    put_le_f32(h + 44, light_off_s(w, 0));
    put_le32(h + 48, d->bottom_layers);
    put_le32(h + 52, (uint32_t)d->width);
    put_le32(h + 56, (uint32_t)d->height);
    put_le32(h + 60, CTB_HEADER); /* the large preview comes first */
    put_le32(h + 64, w->table_at);
    put_le32(h + 68, (uint32_t)d->layer_count);
    put_le32(h + 72, w->small_preview_at);
    put_le32(h + 76, (uint32_t)(d->print_time_s > 0 ? d->print_time_s + 0.5 : 0));
    /* ProjectorType says only "mirrored" (UVtools reads any non-zero as
       flipped across); the images themselves are already flipped. */
    put_le32(h + 80, d->mirror_x || d->mirror_y);
    put_le32(h + 84, w->print_params_at);
    put_le32(h + 88, CTB_PRINT_PARAMS);
    put_le32(h + 92, 1); /* CTB keeps the real anti-alias level in SlicerInfo */
    put_le16(h + 96, 255);
    put_le16(h + 98, 255);
    put_le32(h + 100, w->key);
    put_le32(h + 104, w->slicer_at);
    put_le32(h + 108, CTB_SLICER_INFO);
    job_file_write_at(&w->file, 0, h, sizeof h);
}

static void write_print_params(ctb_writer *w)
{
    const job_desc *d = w->d;
    unsigned char p[CTB_PRINT_PARAMS] = {0};
    put_le_f32(p, job_lift_mm(&d->motion, 1));
    put_le_f32(p + 4, mm_per_min(job_lift_speed(&d->motion, 1)));
    put_le_f32(p + 8, d->motion.lift_mm);
    put_le_f32(p + 12, mm_per_min(d->motion.lift_speed));
    put_le_f32(p + 16, mm_per_min(d->motion.retract_speed));
    put_le_f32(p + 20, d->volume_mm3 / 1000.0);
    put_le_f32(p + 32, light_off_s(w, 1));
    put_le_f32(p + 36, light_off_s(w, 0));
    put_le32(p + 40, d->bottom_layers);
    job_file_write_at(&w->file, w->print_params_at, p, sizeof p);
}

static void write_slicer_info(ctb_writer *w)
{
    const job_desc *d = w->d;
    unsigned char s[CTB_SLICER_INFO] = {0};
    size_t name_len = strlen(w->machine);
    if (w->version >= 4) {
        /* One-stage moves: the second stage is 0 mm, at the first stage's speed. */
        put_le_f32(s + 4, mm_per_min(job_lift_speed(&d->motion, 1)));
        put_le_f32(s + 12, mm_per_min(d->motion.lift_speed));
        put_le_f32(s + 20, mm_per_min(d->motion.retract_speed));
        put_le32(s + 64, w->params_v4_at);
    }
    put_le32(s + 28, w->slicer_at + CTB_SLICER_INFO);
    put_le32(s + 32, (uint32_t)name_len);
    /* AntiAliasFlag: UVtools' comment says 7 without AA and 0x0F with, but it
       always writes 0x0F; so do we. */
    s[36] = 0x0F;
    /* PerLayerSettings: the layers differ in Z step and exposure, so the
       printer must take the table's values. Current UVtools writes Version x
       0x10 when any layer differs from the globals: 0x30 for v3, 0x40 for v4
       (ChituboxFile.cs @7b510f0d, PERLAYER_SETTINGS_CTBv3 and the
       SlicerInfoSettings.PerLayerSettings line of OnBeforeEncode). UVtools
       before 3.9.4 wrote 0x20 for v3; its CHANGELOG says the change "may fix
       some recent problems where printer doesn't respect per layer
       settings". */
    s[39] = (unsigned char)(w->version * 0x10);
    {
        int fixed;
        put_le32(s + 40, (uint32_t)(job_time(&fixed) / 60));
    }
    put_le32(s + 44, (uint32_t)(d->supersample > 1 ? d->supersample : 1));
    put_le32(s + 48, 0x01090000); /* SoftwareVersion: what UVtools writes for every version */
    put_le_f32(s + 52, rest_before_cure_s(w));
    job_file_write_at(&w->file, w->slicer_at, s, sizeof s);
    job_file_write_at(&w->file, w->slicer_at + CTB_SLICER_INFO, w->machine, name_len);
}

static void write_params_v4(ctb_writer *w)
{
    const job_desc *d = w->d;
    unsigned char p[CTB_PARAMS_V4] = {0};
    put_le_f32(p, mm_per_min(d->motion.retract_speed));
    put_le_f32(p + 4, mm_per_min(d->motion.retract_speed));
    /* 4.0, 4.0 and 5: constants both UVtools and mslicer write; what they
       mean is not known. */
    put_le_f32(p + 12, 4.0);
    put_le_f32(p + 20, 4.0);
    put_le_f32(p + 24, rest_before_cure_s(w));
    put_le32(p + 48, 5);
    put_le32(p + 52, (uint32_t)(d->layer_count - 1));
    put_le32(p + 72, w->disclaimer_at);
    put_le32(p + 76, CTB_DISCLAIMER_LEN);
    job_file_write_at(&w->file, w->params_v4_at, p, sizeof p);
}

static void write_blocks(ctb_writer *w)
{
    write_header(w);
    write_print_params(w);
    write_slicer_info(w);
    if (w->version >= 4) write_params_v4(w);
}

/* ---- layer images: 7-bit run-length ------------------------------------ */

/* A layer being coded: its runs, into a blob. */
typedef struct ctb_coder {
    job_blob *out;
    unsigned run_grey7;          /* the pending run */
    uint64_t run_length;
    int failed;                  /* out of memory */
} ctb_coder;

/* The pending run as codes: a byte with bit 7 clear is one pixel; bit 7 set
   is a run, its length after it in 1 to 4 big-endian bytes, prefix-coded
   (0xxxxxxx, 10xxxxxx, 110xxxxx, 1110xxxx); longer runs are cut. */
static void emit_run(ctb_coder *c)
{
    uint64_t left = c->run_length;
    unsigned v = c->run_grey7;
    while (left && !c->failed) {
        uint32_t n = left > CTB_RUN_MAX ? CTB_RUN_MAX : (uint32_t)left;
        unsigned char *p;
        if (job_blob_reserve(c->out, CTB_CODE_MAX)) { c->failed = 1; break; }
        p = c->out->data + c->out->size;
        if (n == 1) {
            *p++ = (unsigned char)v;
        } else {
            *p++ = (unsigned char)(0x80 | v);
            if (n <= 0x7F) {
                *p++ = (unsigned char)n;
            } else if (n <= 0x3FFF) {
                *p++ = (unsigned char)(0x80 | n >> 8);
                *p++ = (unsigned char)n;
            } else if (n <= 0x1FFFFF) {
                *p++ = (unsigned char)(0xC0 | n >> 16);
                *p++ = (unsigned char)(n >> 8);
                *p++ = (unsigned char)n;
            } else {
                *p++ = (unsigned char)(0xE0 | n >> 24);
                *p++ = (unsigned char)(n >> 16);
                *p++ = (unsigned char)(n >> 8);
                *p++ = (unsigned char)n;
            }
        }
        c->out->size = (size_t)(p - c->out->data);
        left -= n;
    }
    c->run_length = 0;
}

/* Runs cross rows: the image is one row-major stream. 8-bit grey keeps its
   top 7 bits (the printer shows v ? v << 1 | 1 : 0), so greys that differ
   only in the lowest bit make one run. mask_row_runs hands each run here. */
static void take_run(void *coder, unsigned grey, uint64_t n)
{
    ctb_coder *c = (ctb_coder *)coder;
    unsigned grey7 = grey >> 1;
    if (grey7 != c->run_grey7) {
        emit_run(c);
        c->run_grey7 = grey7;
    }
    c->run_length += n;
}

int ctb_rle_encode(const job_desc *d, const unsigned char *image, size_t stride, job_blob *blob)
{
    ctb_coder c;
    int y;
    memset(&c, 0, sizeof c);
    c.out = blob;
    for (y = 0; y < d->height; y++) mask_row_runs(image + (size_t)y * stride, d->bits, d->width, take_run, &c);
    emit_run(&c);
    return c.failed ? -1 : 0;
}

/* The key stream UVtools' ChituboxFile.LayerRleCryptBuffer (@5f33a73e)
   applies and undoes (it is its own inverse); mslicer's ctb_format layer.rs
   xor_cypher (@ec4374ad) is the same. Each key word is used low byte first. */
void ctb_layer_xor(uint32_t seed, uint32_t layer, unsigned char *data, size_t n)
{
    uint32_t init = seed * 0x2D83CDACu + 0xD8A83423u, key = (layer * 0x1E1530CDu + 0xEC3D47CDu) * init;
    size_t i;
    if (!seed) return;
    for (i = 0; i < n; i++) {
        data[i] ^= (unsigned char)(key >> 8 * (i % 4));
        if (i % 4 == 3) key += init;
    }
}

static int encode(const void *writer, size_t k, const unsigned char *image, size_t stride, job_blob *blob)
{
    const ctb_writer *w = (const ctb_writer *)writer;
    if (ctb_rle_encode(w->d, image, stride, blob))
        return complain(RC_FAIL, "%s: out of memory coding layer %zu", w->file.path, k + 1);
    ctb_layer_xor(w->key, (uint32_t)k, blob->data, blob->size);
    if (blob->size > 0xFFFFFFFFu)
        return complain(RC_FAIL, "%s: layer %zu encodes to %zu bytes, more than a ctb layer can hold", w->file.path,
                        k + 1, blob->size);
    return RC_OK;
}

/* The layer's LayerDefEx, then its code; its table entry waits for close. */
static int put(void *writer, size_t k, job_blob *blob)
{
    ctb_writer *w = (ctb_writer *)writer;
    const job_desc *d = w->d;
    const job_layer *L = &d->layers[k];
    unsigned char *entry, ex[CTB_LAYER_DEF_EX] = {0};
    off_t data_at = w->end + CTB_LAYER_DEF_EX;
    uint64_t size = blob->size;
    entry = w->table + k * CTB_LAYER_DEF;
    put_le_f32(entry, L->z_top);
    put_le_f32(entry + 4, L->exposure_s);
    put_le_f32(entry + 8, light_off_s(w, is_bottom(w, k)));
    put_le32(entry + 12, (uint32_t)data_at);              /* low 32 bits ... */
    put_le32(entry + 16, (uint32_t)size);
    put_le32(entry + 20, (uint32_t)((uint64_t)data_at >> 32)); /* ... and the 4 GiB page */
    put_le32(entry + 24, CTB_LAYER_DEF_EX);
    /* LayerDefEx repeats the entry byte for byte, then the layer's moves. */
    memcpy(ex, entry, CTB_LAYER_DEF);
    put_le32(ex + 36, (uint32_t)(CTB_LAYER_DEF_EX + size));
    put_le_f32(ex + 40, job_lift_mm(&d->motion, is_bottom(w, k))); /* v4: the total of both stages */
    put_le_f32(ex + 44, mm_per_min(job_lift_speed(&d->motion, is_bottom(w, k))));
    put_le_f32(ex + 56, mm_per_min(d->motion.retract_speed));
    if (w->version >= 4) {
        memcpy(ex + 52, ex + 44, 4); /* the second stage: 0 mm at the same speeds */
        memcpy(ex + 64, ex + 56, 4);
        put_le_f32(ex + 76, rest_before_cure_s(w));
    }
    put_le_f32(ex + 80, 255.0);
    /* the code's size is known, so both go out in order, with no seek back */
    job_file_write_at(&w->file, w->end, ex, sizeof ex);
    job_file_append(&w->file, blob->data, blob->size);
    free(blob->data);
    blob->data = NULL;
    if (w->file.err) return job_file_check(&w->file);
    w->end = data_at + (off_t)size;
    return RC_OK;
}

/* ---- open and close ------------------------------------------------------ */

static void free_writer(ctb_writer *w)
{
    job_file_discard(&w->file);
    free(w->table);
    free(w);
}

static int open_job(void **writer, const char *path, const job_desc *d)
{
    unsigned version = d->preset && d->preset->version ? d->preset->version : 4;
    ctb_writer *w;
    uint64_t table_end;
    uint32_t at;
    int rc;
    *writer = NULL;
    if (version != 3 && version != 4)
        return complain(RC_FAIL, "%s: ctb version %u is not one this writer makes (3 or 4)", path, version);
    w = (ctb_writer *)calloc(1, sizeof *w);
    if (w) w->table = (unsigned char *)calloc(d->layer_count, CTB_LAYER_DEF);
    if (!w || !w->table) {
        if (w) free(w->table);
        free(w);
        return complain(RC_FAIL, "cannot write %s: out of memory for %zu layer%s", path, d->layer_count,
                        plural(d->layer_count));
    }
    if ((rc = job_file_open(&w->file, path)) != RC_OK) {
        free(w->table);
        free(w);
        return rc;
    }
    w->d = d;
    w->version = version;
    w->key = job_key(d);
    w->machine = d->preset && d->preset->machine ? d->preset->machine : "adaslice";

    job_file_write_at(&w->file, 0, NULL, CTB_HEADER);
    if ((rc = write_preview(w, CTB_HEADER, 400, 300, &w->small_preview_at)) != RC_OK ||
        (rc = write_preview(w, w->small_preview_at, 200, 125, &w->print_params_at)) != RC_OK) {
        free_writer(w);
        return rc;
    }
    w->slicer_at = w->print_params_at + CTB_PRINT_PARAMS;
    at = w->slicer_at + CTB_SLICER_INFO + (uint32_t)strlen(w->machine);
    if (version >= 4) {
        w->disclaimer_at = at;
        w->params_v4_at = at + CTB_DISCLAIMER_LEN;
        at = w->params_v4_at + CTB_PARAMS_V4;
        job_file_write_at(&w->file, w->disclaimer_at, ctb_disclaimer, CTB_DISCLAIMER_LEN);
    }
    w->table_at = at;
    table_end = (uint64_t)at + (uint64_t)d->layer_count * CTB_LAYER_DEF;
    if (table_end > 0xFFFFFFFFu) {
        rc = complain(RC_FAIL, "%s: %zu layers make a ctb layer table past 4 GiB", path, d->layer_count);
        free_writer(w);
        return rc;
    }
    write_blocks(w);
    job_file_write_at(&w->file, at, NULL, d->layer_count * CTB_LAYER_DEF);
    w->end = (off_t)table_end;
    if ((rc = job_file_check(&w->file)) != RC_OK) {
        free_writer(w);
        return rc;
    }
    *writer = w;
    return RC_OK;
}

static int close_job(void *writer, int ok)
{
    ctb_writer *w = (ctb_writer *)writer;
    int rc = RC_OK;
    if (!w) return ok ? RC_FAIL : RC_OK;
    if (ok) {
        job_file_write_at(&w->file, w->table_at, w->table, w->d->layer_count * CTB_LAYER_DEF);
        write_blocks(w);
        rc = job_file_commit(&w->file);
    }
    free_writer(w); /* after a commit there is nothing left to discard */
    return rc;
}

const job_format JOB_FORMAT_CTB = {
    .name = "ctb",
    .extension = ".ctb",
    .what = "ChiTuBox CTB",
    .min_layer_mm = 0.01,
    .adaptive = 1,
    .open = open_job,
    .encode = encode,
    .put = put,
    .close = close_job,
    .previews = {{400, 300}, {200, 125}},
};
