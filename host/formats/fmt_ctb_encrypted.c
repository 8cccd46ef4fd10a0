/* The encrypted ChiTuBox .ctb (magic 0x12FD0107), versions 4 and 5: what
   ChiTuBox 1.9 and later write and the only .ctb that the Elegoo Mars 3,
   Saturn 2 / 8K / 4 Ultra, Jupiter and Phrozen Sonic Mini / Mighty / Mega 8K
   read (an unencrypted v4 shows "Unknown file" on a Mars 3 Pro).

   Byte layout: UVtools, UVtools.Core/FileFormats/CTBEncryptedFile.cs @5f33a73e
   (classes FileHeader, SlicerSettings, ResinParameters, LayerPointer,
   LayerDef, Preview; EncodeInternally for the order of the blocks and the
   constants after the layers; DecodeInternally for the signature check),
   checked against mslicer, format/ctb_format/src (file.rs, layer.rs,
   resin.rs, crypto.rs) @ec4374ad. The file, in the order written:

     0    header, 48 bytes, in clear: the settings' and the signature's
          offsets and sizes, the version
     48   the settings, 288 bytes enciphered with AES-256-CBC (no padding):
          the display, the layer count, the print's defaults, and the offsets
          of everything below
     336  the large and the small preview, each a 16-byte header (w, h,
          offset, size) and RGB15 run-length data, as CTB's (fmt_ctb.h)
          the machine's name, then the 320-byte disclaimer
          v5: the resin parameters (40 bytes and their strings)
          the layer pointers, 16 bytes a layer
          per layer an 88-byte LayerDef (its own Z, exposure and moves) and
          the image in CTB's 7-bit run-length code, XORed with the layer key
          (ctb_layer_xor) and not AES-enciphered (EncryptedDataLength 0, as
          UVtools and mslicer write)
          v5: 8 bytes; the 32-byte signature; 4 bytes

   The signature is SHA-256 of the settings' first field (a 64-bit value
   UVtools calls the checksum, sets to 0xCAFEBABE and checks only through the
   signature), enciphered like the settings. Every offset the settings and the
   header hold is 32-bit: a file past 4 GiB cannot be addressed, and is
   refused. The layers are streamed; the pointers, the settings and the header
   are written at close. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* fseeko, off_t */
#endif
#include "../codec/aes256.h"
#include "../bytes.h"
#include "fmt_ctb.h"
#include "../report.h"
#include "../codec/sha256.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

#define CTBE_MAGIC 0x12FD0107u
#define CTBE_HEADER 48u
#define CTBE_SETTINGS 288u
#define CTBE_PREVIEW_HEADER 16u
#define CTBE_RESIN 40u              /* the resin parameters before their strings */
#define CTBE_POINTER 16u
#define CTBE_LAYER_DEF 88u
#define CTBE_SIGNATURE 32u
#define CTBE_CHECKSUM 0xCAFEBABEu   /* UVtools' SlicerSettings.ChecksumValue */
#define CTBE_LAYER_KEY 0xEFBEADDEu  /* UVtools' LAYER_XOR_KEY: its files print */
#define CTBE_PER_LAYER 0x40u        /* UVtools' PERLAYER_SETTINGS_ALLOW: the printer takes each LayerDef's values */
#define CTBE_MAX_FILE 0xFFFFFFFFu

/* ChiTuBox's key and IV. UVtools keeps them XORed with "UVtools" in base64
   (CTBEncryptedFile.cs Secret1, Secret2); mslicer's crypto.rs ENCRYPT_KEY and
   ENCRYPT_IV hold the same bytes plain. */
static const unsigned char ctbe_key[32] = {
    0xD0, 0x5B, 0x8E, 0x33, 0x71, 0xDE, 0x3D, 0x1A, 0xE5, 0x4F, 0x22, 0xDD, 0xDF, 0x5B, 0xFD, 0x94,
    0xAB, 0x5D, 0x64, 0x3A, 0x9D, 0x7E, 0xBF, 0xAF, 0x42, 0x03, 0xF3, 0x10, 0xD8, 0x52, 0x2A, 0xEA};
static const unsigned char ctbe_iv[16] = {0x0F, 0x01, 0x0A, 0x05, 0x05, 0x0B, 0x06, 0x07,
                                          0x08, 0x06, 0x0A, 0x0C, 0x0C, 0x0D, 0x09, 0x0F};

typedef struct ctbe_writer {
    job_file file;
    const job_desc *d;          /* read again at close: the volume is known only then */
    unsigned version;
    const char *machine;
    uint32_t large_preview_at, small_preview_at, machine_at, disclaimer_at, resin_at, pointers_at;
    unsigned char *pointers;    /* layer_count entries of 16 bytes, written at close */
    uint64_t end;               /* where the next layer's LayerDef goes */
} ctbe_writer;



/* data[0, n) enciphered in place, n a multiple of 16, each time from the IV:
   the settings and the signature are enciphered apart. */
static void encipher(unsigned char *data, size_t n)
{
    aes256 a;
    unsigned char iv[16];
    aes256_init(&a, ctbe_key);
    memcpy(iv, ctbe_iv, sizeof iv);
    aes256_cbc_encrypt(&a, iv, data, n);
}

/* ---- the blocks before the layers ---------------------------------------- */

/* A preview's 16-byte header and its code, appended; its offset in *at. */
static int add_preview(ctbe_writer *w, bytebuf *b, int width, int height, uint32_t *at)
{
    size_t pixels = (size_t)width * (size_t)height, len;
    unsigned char *rgb = (unsigned char *)calloc(pixels, 3), *code = (unsigned char *)malloc(pixels * 2);
    if (!rgb || !code || (w->d->preview && w->d->preview(w->d->preview_ctx, width, height, rgb) != 0)) {
        free(rgb);
        free(code);
        return complain(RC_FAIL, "cannot write %s: out of memory for the %dx%d preview", w->file.path, width, height);
    }
    len = ctb_preview_encode(rgb, pixels, code);
    *at = (uint32_t)b->size;
    bytebuf_le32(b, (uint32_t)width);
    bytebuf_le32(b, (uint32_t)height);
    bytebuf_le32(b, (uint32_t)(b->size + 8));
    bytebuf_le32(b, (uint32_t)len);
    bytebuf_put(b, code, len);
    free(rgb);
    free(code);
    return RC_OK;
}

/* v5's ResinParameters: no resin is named (empty type and name, as UVtools
   leaves them), UVtools' density, and the machine's name again. Each
   string's address is where it lies: type, name, machine, one after another. */
static void add_resin(ctbe_writer *w, bytebuf *b)
{
    uint32_t at = (uint32_t)b->size, name_len = (uint32_t)strlen(w->machine);
    uint32_t strings = at + CTBE_RESIN;
    w->resin_at = at;
    bytebuf_le32(b, 0);
    bytebuf_put(b, NULL, 4);            /* the resin's colour, B G R A */
    bytebuf_le32(b, strings);           /* the machine's name, after the two empty strings */
    bytebuf_le32(b, 0);                 /* the resin type: its length, its address */
    bytebuf_le32(b, strings);
    bytebuf_le32(b, 0);                 /* the resin name */
    bytebuf_le32(b, strings);
    bytebuf_le32(b, name_len);
    bytebuf_le_f32(b, 1.1);             /* g/ml: UVtools' ResinDensity */
    bytebuf_le32(b, 0);
    bytebuf_put(b, w->machine, name_len);
}

/* ---- the blocks written at close ----------------------------------------- */

static void fill_header(const ctbe_writer *w, unsigned char h[CTBE_HEADER], uint32_t signature_at)
{
    memset(h, 0, CTBE_HEADER);
    put_le32(h, CTBE_MAGIC);
    put_le32(h + 4, CTBE_SETTINGS);
    put_le32(h + 8, CTBE_HEADER);
    put_le32(h + 16, w->version);
    put_le32(h + 20, CTBE_SIGNATURE);
    put_le32(h + 24, signature_at);
    /* 1, 1 and 42: what UVtools and mslicer write; what they mean is not known */
    put_le16(h + 32, 1);
    put_le16(h + 34, 1);
    put_le32(h + 40, 42);
}

/* SlicerSettings in clear. The print's defaults are what the printer shows;
   it prints each layer by its own LayerDef (PerLayerSettings). Like fmt_ctb.c
   v4, the wait before cure is a rest time and the light-off delays stay 0, so
   that the printer does not wait twice, and the moves are one stage: the
   second is 0 mm at the first's speed. */
static void fill_settings(const ctbe_writer *w, unsigned char s[CTBE_SETTINGS])
{
    const job_desc *d = w->d;
    const job_motion *m = &d->motion;
    double total_mm = d->layers[d->layer_count - 1].z_top, retract = mm_per_min(m->retract_speed);
    int fixed;
    memset(s, 0, CTBE_SETTINGS);
    put_le64(s, CTBE_CHECKSUM);
    put_le32(s + 8, w->pointers_at);
    put_le_f32(s + 12, d->display_mm[0]);
    put_le_f32(s + 16, d->display_mm[1]);
    /* An unknown build height: the job's own is the least the printer has. */
    put_le_f32(s + 20, d->z_max_mm > 0 ? d->z_max_mm : total_mm);
    put_le_f32(s + 32, total_mm);
    put_le_f32(s + 36, d->layer_height_mm);
    put_le_f32(s + 40, d->exposure_s);
    put_le_f32(s + 44, d->bottom_exposure_s);
    put_le32(s + 52, d->bottom_layers);
    put_le32(s + 56, (uint32_t)d->width);
    put_le32(s + 60, (uint32_t)d->height);
    put_le32(s + 64, (uint32_t)d->layer_count);
    put_le32(s + 68, w->large_preview_at);
    put_le32(s + 72, w->small_preview_at);
    put_le32(s + 76, (uint32_t)(d->print_time_s > 0 ? d->print_time_s + 0.5 : 0));
    /* ProjectorType: UVtools reads any non-zero as mirrored; the images are
       already flipped */
    put_le32(s + 80, d->mirror_x || d->mirror_y);
    put_le_f32(s + 84, job_lift_mm(m, 1));
    put_le_f32(s + 88, mm_per_min(job_lift_speed(m, 1)));
    put_le_f32(s + 92, m->lift_mm);
    put_le_f32(s + 96, mm_per_min(m->lift_speed));
    put_le_f32(s + 100, retract);
    put_le_f32(s + 104, d->volume_mm3 / 1000.0); /* ml */
    put_le32(s + 120, 1);                        /* UVtools' Unknown3 */
    put_le16(s + 124, 255);                      /* LightPWM, BottomLightPWM */
    put_le16(s + 126, 255);
    put_le32(s + 128, CTBE_LAYER_KEY);
    put_le_f32(s + 136, mm_per_min(job_lift_speed(m, 1)));   /* the second stages: 0 mm */
    put_le_f32(s + 144, mm_per_min(m->lift_speed));
    put_le_f32(s + 152, retract);
    put_le32(s + 160, w->machine_at);
    put_le32(s + 164, (uint32_t)strlen(w->machine));
    s[168] = 0x0F;                               /* AntiAliasFlag: what UVtools writes */
    s[171] = CTBE_PER_LAYER;
    put_le32(s + 172, (uint32_t)(job_time(&fixed) / 60));
    put_le32(s + 176, (uint32_t)(d->supersample > 1 ? d->supersample : 1));
    put_le_f32(s + 180, m->wait_before_cure_s);  /* RestTimeAfterRetract */
    put_le_f32(s + 192, retract);                /* BottomRetractSpeed and its second stage */
    put_le_f32(s + 196, retract);
    put_le_f32(s + 204, 4.0);                    /* 4.0, 4.0 and 4: constants UVtools and mslicer write */
    put_le_f32(s + 212, 4.0);
    put_le_f32(s + 216, m->wait_before_cure_s);  /* RestTimeAfterRetract2 */
    put_le32(s + 240, 4);
    put_le32(s + 244, (uint32_t)(d->layer_count - 1));
    put_le32(s + 264, w->disclaimer_at);
    put_le32(s + 268, CTB_DISCLAIMER_LEN);
    put_le32(s + 276, w->resin_at);
}

/* ---- layers ---------------------------------------------------------------- */

/* The image's code, keyed for layer k (on the coding thread). */
static int encode(const void *writer, size_t k, const unsigned char *image, size_t stride, job_blob *blob)
{
    const ctbe_writer *w = (const ctbe_writer *)writer;
    if (ctb_rle_encode(w->d, image, stride, blob))
        return complain(RC_FAIL, "%s: out of memory coding layer %zu", w->file.path, k + 1);
    ctb_layer_xor(CTBE_LAYER_KEY, (uint32_t)k, blob->data, blob->size);
    return RC_OK;
}

/* The tail after the last layer: v5's 8 bytes, the signature, 4 bytes. */
static uint32_t tail_size(const ctbe_writer *w) { return (w->version >= 5 ? 8 : 0) + CTBE_SIGNATURE + 4; }

/* The layer's LayerDef and its code; its pointer waits for close. */
static int put(void *writer, size_t k, job_blob *blob)
{
    ctbe_writer *w = (ctbe_writer *)writer;
    const job_desc *d = w->d;
    const job_layer *L = &d->layers[k];
    const job_motion *m = &d->motion;
    int bottom = k < d->bottom_layers;
    unsigned char def[CTBE_LAYER_DEF] = {0};
    uint64_t data_at = w->end + CTBE_LAYER_DEF, after = data_at + blob->size;
    int rc = RC_OK;
    if (after + tail_size(w) > CTBE_MAX_FILE)
        rc = complain(RC_FAIL, "%s: layer %zu of %zu would end at byte %llu, past the 4 GiB an encrypted ctb's 32-bit "
                      "offsets reach (fewer or smaller layers: a coarser plan, --aa 1, a smaller part)",
                      w->file.path, k + 1, d->layer_count, (unsigned long long)after);
    if (rc) {
        free(blob->data);
        blob->data = NULL;
        return rc;
    }
    put_le32(def, CTBE_LAYER_DEF);
    put_le_f32(def + 4, L->z_top);
    put_le_f32(def + 8, L->exposure_s);
    put_le32(def + 16, (uint32_t)data_at); /* the 4 GiB page at +20 stays 0 */
    put_le32(def + 24, (uint32_t)blob->size);
    put_le_f32(def + 40, job_lift_mm(m, bottom));
    put_le_f32(def + 44, mm_per_min(job_lift_speed(m, bottom)));
    memcpy(def + 52, def + 44, 4);         /* the second stage: 0 mm at the same speed */
    put_le_f32(def + 56, mm_per_min(m->retract_speed));
    memcpy(def + 64, def + 56, 4);
    put_le_f32(def + 76, m->wait_before_cure_s); /* RestTimeAfterRetract */
    put_le_f32(def + 80, 255.0);                 /* LightPWM */
    put_le32(w->pointers + k * CTBE_POINTER, (uint32_t)w->end);
    put_le32(w->pointers + k * CTBE_POINTER + 8, CTBE_LAYER_DEF);
    job_file_write_at(&w->file, w->end, def, sizeof def);
    job_file_append(&w->file, blob->data, blob->size);
    free(blob->data);
    blob->data = NULL;
    if (w->file.err) return job_file_check(&w->file);
    w->end = after;
    return RC_OK;
}

/* ---- open and close -------------------------------------------------------- */

static void free_writer(ctbe_writer *w)
{
    job_file_discard(&w->file);
    free(w->pointers);
    free(w);
}

static int open_job(void **writer, const char *path, const job_desc *d)
{
    unsigned version = d->preset && d->preset->version ? d->preset->version : 5;
    ctbe_writer *w;
    bytebuf b;
    int rc;
    *writer = NULL;
    if (version != 4 && version != 5)
        return complain(RC_FAIL, "%s: encrypted ctb version %u is not one this writer makes (4 or 5)", path, version);
    if (d->layer_count > (CTBE_MAX_FILE - CTBE_HEADER - CTBE_SETTINGS) / (CTBE_POINTER + CTBE_LAYER_DEF + 1))
        return complain(RC_FAIL, "%s: %zu layers cannot fit the 4 GiB an encrypted ctb's 32-bit offsets reach", path,
                        d->layer_count);
    w = (ctbe_writer *)calloc(1, sizeof *w);
    if (w) w->pointers = (unsigned char *)calloc(d->layer_count, CTBE_POINTER);
    if (!w || !w->pointers) {
        if (w) free(w->pointers);
        free(w);
        return complain(RC_FAIL, "cannot write %s: out of memory for %zu layer%s", path, d->layer_count,
                        plural(d->layer_count));
    }
    if ((rc = job_file_open(&w->file, path)) != RC_OK) {
        free(w->pointers);
        free(w);
        return rc;
    }
    w->d = d;
    w->version = version;
    w->machine = d->preset && d->preset->machine ? d->preset->machine : "adaslice";

    /* Everything up to the first layer, the header and the settings as zeros
       until close; the previews are the only large part. */
    memset(&b, 0, sizeof b);
    bytebuf_put(&b, NULL, CTBE_HEADER + CTBE_SETTINGS);
    if ((rc = add_preview(w, &b, 400, 300, &w->large_preview_at)) != RC_OK ||
        (rc = add_preview(w, &b, 200, 125, &w->small_preview_at)) != RC_OK) {
        bytebuf_free(&b);
        free_writer(w);
        return rc;
    }
    w->machine_at = (uint32_t)b.size;
    bytebuf_put(&b, w->machine, strlen(w->machine));
    w->disclaimer_at = (uint32_t)b.size;
    bytebuf_put(&b, ctb_disclaimer, CTB_DISCLAIMER_LEN);
    if (version >= 5) add_resin(w, &b);
    w->pointers_at = (uint32_t)b.size;
    if (b.failed) {
        bytebuf_free(&b);
        free_writer(w);
        return complain(RC_FAIL, "cannot write %s: out of memory", path);
    }
    job_file_write_at(&w->file, 0, b.data, b.size);
    w->end = b.size + (uint64_t)d->layer_count * CTBE_POINTER;
    bytebuf_free(&b);
    if ((rc = job_file_check(&w->file))) {
        free_writer(w);
        return rc;
    }
    *writer = w;
    return RC_OK;
}

/* The tail, the pointers, then the settings and the header that point at them. */
static void write_close_blocks(ctbe_writer *w)
{
    unsigned char tail[8 + CTBE_SIGNATURE + 4] = {0}, settings[CTBE_SETTINGS], header[CTBE_HEADER], *sig = tail;
    unsigned char checksum[8];
    uint32_t signature_at;
    if (w->version >= 5) {
        /* what UVtools writes here; what it means is not known */
        put_le32(tail, 0x422052FAu);
        sig += 8;
    }
    put_le64(checksum, CTBE_CHECKSUM);
    sha256_digest(checksum, sizeof checksum, sig);
    encipher(sig, CTBE_SIGNATURE);
    put_le32(sig + CTBE_SIGNATURE, 0x6D4232B3u); /* UVtools' 4 unknown bytes after the signature */
    signature_at = (uint32_t)(w->end + (uint64_t)(sig - tail));
    job_file_write_at(&w->file, w->end, tail, tail_size(w));
    job_file_write_at(&w->file, w->pointers_at, w->pointers, w->d->layer_count * CTBE_POINTER);
    fill_settings(w, settings);
    encipher(settings, sizeof settings);
    job_file_write_at(&w->file, CTBE_HEADER, settings, sizeof settings);
    fill_header(w, header, signature_at);
    job_file_write_at(&w->file, 0, header, sizeof header);
}

static int close_job(void *writer, int ok)
{
    ctbe_writer *w = (ctbe_writer *)writer;
    int rc = RC_OK;
    if (!w) return ok ? RC_FAIL : RC_OK;
    if (ok) {
        write_close_blocks(w);
        rc = job_file_commit(&w->file);
    }
    free_writer(w); /* after a commit there is nothing left to discard */
    return rc;
}

const job_format JOB_FORMAT_CTB_ENCRYPTED = {
    .name = "ctb-encrypted",
    .extension = ".ctb",
    .what = "ChiTuBox CTB, encrypted (ChiTuBox 1.9+)",
    .min_layer_mm = 0.01,
    .adaptive = 1,
    .open = open_job,
    .encode = encode,
    .put = put,
    .close = close_job,
    .previews = {{400, 300}, {200, 125}},
};
