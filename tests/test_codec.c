/* The trimmed build's parts the host shares with the printer: CRC-32, the
   mask run-length code, and the integers a printer plans on. */
#include "../adaslice.h"
#include "check.h"
#include "codec_reference.h"
#include "../host/codec/maskrows.h"
#include "../host/codec/png.h"
#include "maskgen.h"
#include "plan_oracle.h"
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

static unsigned codec_rng_state = 777u;
static unsigned codec_rng(void) { codec_rng_state = codec_rng_state * 1103515245u + 12345u; return (codec_rng_state >> 8) & 0xffffffu; }

static void crc32_known_values(void)
{
    unsigned char zeros[32] = {0};
    CHECK(adaslice_crc32(0, "123456789", 9) == 0xCBF43926u);
    CHECK(adaslice_crc32(0, "", 0) == 0);
    CHECK(adaslice_crc32(adaslice_crc32(0, "1234", 4), "56789", 5) == 0xCBF43926u);
    CHECK(adaslice_crc32(0, zeros, sizeof zeros) == 0x190A55ADu);
    CHECK(adaslice_crc32(0, "The quick brown fox jumps over the lazy dog", 43) == 0x414FA339u);
}

/* An independent reader of the code, written from the format's description
   as a whole-buffer parser, to check the streaming decoder against. */
static int reference_decode(const unsigned char *code, size_t size, uint32_t w, uint32_t h, int bits,
                            unsigned char *image, size_t stride)
{
    size_t at = 0;
    uint32_t rows = 0;
    memset(image, 0, stride * h);
    while (at < size) {
        uint64_t v = 0;
        int s = 0;
        do { if (at >= size || s > 28) return 0; v |= (uint64_t)(code[at] & 127) << s; s += 7; } while (code[at++] & 128);
        if (v & 1) {
            uint64_t t = (v >> 1) + 1;
            for (; t; t--, rows++) {
                if (rows >= h) return 0;
                if (rows) memcpy(image + rows * stride, image + (rows - 1) * stride, stride);
            }
        } else {
            uint64_t runs = v >> 1, x = 0;
            int lit = 0;
            if (rows >= h || !runs) return 0;
            while (runs--) {
                unsigned value = 0;
                uint64_t len = 0;
                if (bits == 8) { if (at >= size) return 0; value = code[at++]; }
                s = 0;
                do { if (at >= size || s > 28) return 0; len |= (uint64_t)(code[at] & 127) << s; s += 7; } while (code[at++] & 128);
                if (x + len > w) return 0;
                for (uint64_t i = x; i < x + len; i++) {
                    if (bits == 8) image[rows * stride + i] = (unsigned char)value;
                    else if (lit) image[rows * stride + i / 8] |= (unsigned char)(0x80 >> (i % 8));
                }
                x += len;
                lit = !lit;
            }
            if (x != w) return 0;
            rows++;
        }
    }
    return rows == h;
}

typedef struct collected { unsigned char *image; size_t stride; uint32_t next; int out_of_order; } collected;

static void collect_row(void *ctx, uint32_t y, const unsigned char *row)
{
    collected *c = (collected *)ctx;
    if (y != c->next) c->out_of_order = 1;
    memcpy(c->image + (size_t)y * c->stride, row, c->stride);
    c->next = y + 1;
}

/* Repeated rows take their CRC by multiplication (adaslice_mcu.h): for
   every row length from 1 to 100 bytes (1-bit and 8-bit), runs of repeated
   rows of random content, decoded whole and in a firmware's slices, give
   the CRC of the image's bytes. */
static void repeated_rows_crc_by_combination(void)
{
    uint32_t stride, failures = 0, trials = 0;
    for (stride = 1; stride <= 100; stride++) {
        int bits;
        for (bits = 1; bits <= 8; bits += 7) {
            uint32_t w = bits == 8 ? stride : 8 * stride - stride % 8, h = 1 + codec_rng() % 200, y, x;
            size_t cap = adaslice_rle_bound(w, h, bits), n = 0, at;
            unsigned char *image = (unsigned char *)calloc((size_t)stride * h, 1), *code = (unsigned char *)malloc(cap);
            unsigned char row[100];
            adaslice_rle_decoder dec;
            int sliced;
            if (!image || !code) { CHECK(!"out of memory"); free(image); free(code); return; }
            for (y = 0; y < h; y++) {
                unsigned char *r = image + (size_t)y * stride;
                if (y && codec_rng() % 8) { memcpy(r, r - stride, stride); continue; } /* mostly repeats */
                for (x = 0; x < w; x++) {
                    int on = codec_rng() % 3 == 0;
                    if (bits == 8) r[x] = (unsigned char)(on ? codec_rng() : 0);
                    else if (on) r[x / 8] |= (unsigned char)(0x80u >> (x % 8));
                }
            }
            CHECK(adaslice_rle_encode(image, stride, w, h, bits, code, cap, &n) == ADASLICE_OK);
            for (sliced = 0; sliced < 2; sliced++) {
                CHECK(adaslice_rle_decoder_init(&dec, w, h, bits, row, sizeof row) == ADASLICE_OK);
                for (at = 0; at < n || ADASLICE_RLE_PENDING(&dec);) {
                    size_t used = 0;
                    CHECK(adaslice_rle_decode_rows(&dec, code + at, n - at, sliced ? 1 + codec_rng() % 40 : UINT32_MAX, &used, NULL,
                                                   NULL) == ADASLICE_OK);
                    at += used;
                    if (check_case_failed()) break;
                }
                trials++;
                if (!adaslice_rle_finished(&dec) || ADASLICE_RLE_CRC(&dec) != adaslice_crc32(0, image, (size_t)stride * h)) failures++;
            }
            free(image);
            free(code);
        }
    }
    CHECKF(failures == 0, "%u of %u decodes gave another CRC than the image's bytes", failures, trials);
}

/* Masks of every kind (synthetic scenes, noise, full, empty, odd widths,
   garbage in 1-bit padding) round-trip through the encoder and the streaming
   decoder fed in random pieces, and both agree with the reference reader. */
static void masks_round_trip(void)
{
    int trial, failures = 0;
    for (trial = 0; trial < 120; trial++) {
        int bits = trial % 3 == 2 ? 8 : 1;
        uint32_t w = 1 + codec_rng() % 300, h = 1 + codec_rng() % 120, x, y;
        size_t stride = bits == 1 ? (w + 7) / 8 : w, cap = adaslice_rle_bound(w, h, bits), n, at, got;
        size_t in_stride = stride + trial % 3;
        unsigned char *grey = (unsigned char *)calloc((size_t)w * h, 1);
        unsigned char *image = (unsigned char *)calloc(in_stride * h, 1);
        unsigned char *clean = (unsigned char *)calloc(stride * h, 1);
        unsigned char *code = (unsigned char *)malloc(cap);
        unsigned char *back = (unsigned char *)calloc(stride * h, 1);
        unsigned char *ref = (unsigned char *)calloc(stride * h, 1);
        unsigned char row[400];
        adaslice_rle_decoder dec;
        collected c;
        int kind = trial % 5;
        if (kind == 0) mask_scene(grey, (int)w, (int)h, trial);
        for (y = 0; y < h; y++)
            for (x = 0; x < w; x++) {
                unsigned char *g = grey + (size_t)y * w + x;
                if (kind == 1) *g = (unsigned char)(codec_rng() % 4 == 0 ? 255 : 0);
                if (kind == 2) *g = 255;
                if (kind == 3) *g = (unsigned char)(codec_rng() % 7 == 0 ? codec_rng() : 0);
                if (kind == 4 && (y / 5) % 3 == 0 && x > w / 3) *g = 200;
            }
        if (bits == 1) mask_pack(grey, (int)w, (int)h, clean, stride);
        for (y = 0; y < h; y++) {
            if (bits == 8) { memcpy(image + y * in_stride, grey + (size_t)y * w, w); memcpy(clean + y * stride, grey + (size_t)y * w, w); continue; }
            memcpy(image + y * in_stride, clean + y * stride, stride);
            /* the encoder must ignore padding bits and bytes */
            if (w % 8) image[y * in_stride + stride - 1] |= (unsigned char)(0xff >> (w % 8));
            for (x = (uint32_t)stride; x < in_stride; x++) image[y * in_stride + x] = 0xa5;
        }
        CHECK(adaslice_rle_encode(image, in_stride, w, h, bits, code, cap, &n) == ADASLICE_OK);
        CHECKF(n > 0 && n <= cap, "trial %d: encoded %zu of bound %zu", trial, n, cap);
        {   /* the fast encoder writes the reference's bytes, and so it does in a buffer just big enough */
            unsigned char *want = (unsigned char *)malloc(cap);
            size_t wn = 0, tight = 0;
            CHECK(want && ref_rle_encode(image, in_stride, w, h, bits, want, cap, &wn) == ADASLICE_OK);
            if (want && (wn != n || memcmp(want, code, n))) failures++;
            CHECK(adaslice_rle_encode(image, in_stride, w, h, bits, want, n, &tight) == ADASLICE_OK && tight == n &&
                  !memcmp(want, code, n));
            free(want);
        }
        CHECK(adaslice_rle_encode(image, in_stride, w, h, bits, code, n - 1, &got) == ADASLICE_ERR_OVERFLOW || n == 0);
        CHECK(adaslice_rle_encode(image, in_stride, w, h, bits, code, cap, &n) == ADASLICE_OK);
        CHECK(adaslice_rle_decoder_init(&dec, w, h, bits, row, sizeof row) == ADASLICE_OK);
        c.image = back; c.stride = stride; c.next = 0; c.out_of_order = 0;
        for (at = 0; at < n || ADASLICE_RLE_PENDING(&dec);) {
            size_t piece = 1 + codec_rng() % 17, used = 0;
            if (piece > n - at) piece = n - at;
            if (trial % 2) {
                /* a firmware's short passes: a few row bytes of CRC a call, a
                   row or a repeat across calls (a repeated row costs at most
                   ADASLICE_RLE_REPEAT_COST: its CRC is a multiplication) */
                uint32_t budget = 1 + codec_rng() % (uint32_t)(3 * stride), before = c.next;
                uint32_t cheapest = stride < ADASLICE_RLE_REPEAT_COST ? (uint32_t)stride : ADASLICE_RLE_REPEAT_COST;
                CHECK(adaslice_rle_decode_rows(&dec, code + at, piece, budget, &used, collect_row, &c) == ADASLICE_OK);
                CHECKF(c.next - before <= (budget - 1) / cheapest + 1 && used <= piece,
                       "trial %d: %u rows of %zu bytes for a budget of %u bytes", trial, c.next - before, (size_t)stride, budget);
            } else {
                CHECK(adaslice_rle_decode(&dec, code + at, piece, collect_row, &c) == ADASLICE_OK);
                used = piece;
            }
            at += used;
        }
        CHECK(adaslice_rle_finished(&dec) && !c.out_of_order);
        CHECK(reference_decode(code, n, w, h, bits, ref, stride));
        if (memcmp(back, clean, stride * h) || memcmp(ref, clean, stride * h)) failures++;
        CHECK(ADASLICE_RLE_CRC(&dec) == adaslice_crc32(0, clean, stride * h));
        free(grey); free(image); free(clean); free(code); free(back); free(ref);
    }
    CHECKF(failures == 0, "%d masks did not survive the round trip", failures);
}

/* Slicing by eight (from 4 KiB) and nibbles agree with the reference on
   every length to 4096 and on long buffers, at every alignment, in pieces. */
static void crc32_agrees_with_the_reference(void)
{
    enum { BIG = 70000 };
    unsigned char *buf = (unsigned char *)malloc(BIG + 16);
    size_t n, bad = 0, i;
    if (!buf) { CHECK(!"out of memory"); return; }
    for (i = 0; i < BIG + 16; i++) buf[i] = (unsigned char)codec_rng();
    for (n = 0; n <= 4096; n++) {
        size_t off = codec_rng() % 16;
        if (adaslice_crc32(0, buf + off, n) != ref_crc32(0, buf + off, n)) bad++;
    }
    for (i = 0; i < 200; i++) {
        size_t off = codec_rng() % 16, len = 4096 + codec_rng() % (BIG - 4096), cut = codec_rng() % len;
        uint32_t whole = adaslice_crc32(0, buf + off, len);
        if (whole != ref_crc32(0, buf + off, len) || adaslice_crc32(adaslice_crc32(0, buf + off, cut), buf + off + cut, len - cut) != whole)
            bad++;
    }
    memset(buf, 0, BIG);
    CHECK(adaslice_crc32(0, buf, BIG) == ref_crc32(0, buf, BIG));
    CHECKF(bad == 0, "%zu buffers disagree", bad);
    free(buf);
}

/* Wide masks, long runs across words, rows that repeat and rows that do not,
   in every tight buffer near the end: the reference's bytes or its overflow. */
static void fast_encoder_writes_the_reference_bytes(void)
{
    int trial, failures = 0;
    for (trial = 0; trial < 40; trial++) {
        int bits = trial % 2 ? 8 : 1;
        uint32_t w = 1 + codec_rng() % 3000, h = 1 + codec_rng() % 40, x, y;
        size_t stride = (bits == 1 ? (w + 7) / 8 : w) + trial % 3, cap = adaslice_rle_bound(w, h, bits), n = 0, wn = 0, k;
        unsigned char *image = (unsigned char *)malloc(stride * h), *code = (unsigned char *)malloc(cap),
                      *want = (unsigned char *)malloc(cap);
        if (!image || !code || !want) { CHECK(!"out of memory"); free(image); free(code); free(want); return; }
        for (y = 0; y < h; y++) {
            unsigned char *row = image + (size_t)y * stride;
            if (y && codec_rng() % 3 == 0) { memcpy(row, row - stride, stride); continue; }
            for (x = 0; x < stride;) {
                uint32_t len = 1 + codec_rng() % (codec_rng() % 4 ? 200 : 5);
                unsigned char v = (unsigned char)(codec_rng() % 3 == 0 ? codec_rng() : codec_rng() % 2 ? 0xff : 0);
                while (len-- && x < stride) row[x++] = v;
            }
        }
        CHECK(adaslice_rle_encode(image, stride, w, h, bits, code, cap, &n) == ADASLICE_OK);
        CHECK(ref_rle_encode(image, stride, w, h, bits, want, cap, &wn) == ADASLICE_OK);
        if (n != wn || memcmp(code, want, n)) failures++;
        for (k = n > 40 ? n - 40 : 0; k <= n; k++) {
            size_t got = 0;
            adaslice_result r = adaslice_rle_encode(image, stride, w, h, bits, code, k, &got);
            if (k < n ? r != ADASLICE_ERR_OVERFLOW : r != ADASLICE_OK || got != n || memcmp(code, want, n)) failures++;
        }
        free(image);
        free(code);
        free(want);
    }
    CHECKF(failures == 0, "%d encodings differ from the reference", failures);
}

/* The host's CRC of a mask by rows (repeated rows combined in GF(2)) is the
   CRC of its bytes, on masks with every kind of repetition and width. */
static void mask_crc_by_rows_is_the_crc_of_the_bytes(void)
{
    int trial, bad = 0;
    for (trial = 0; trial < 200; trial++) {
        size_t w = 1 + codec_rng() % 700, h = 1 + codec_rng() % 60, y, x;
        unsigned char *img = (unsigned char *)malloc(w * h);
        if (!img) { CHECK(!"out of memory"); return; }
        for (y = 0; y < h; y++) {
            unsigned char *row = img + y * w;
            if (y && codec_rng() % 2) { memcpy(row, row - w, w); continue; }
            for (x = 0; x < w; x++) row[x] = (unsigned char)(codec_rng() % 5 ? 0 : codec_rng());
        }
        if (mask_crc32(img, w, w, (int)h) != ref_crc32(0, img, w * h)) bad++;
        if (h > 1 && w > 1) { /* rows with a byte of padding after them: the same rows as w - 1 bytes each */
            size_t r;
            uint32_t want = 0;
            unsigned char *packed = (unsigned char *)malloc((w - 1) * h);
            for (r = 0; packed && r < h; r++) memcpy(packed + r * (w - 1), img + r * w, w - 1);
            if (packed) want = ref_crc32(0, packed, (w - 1) * h);
            if (!packed || mask_crc32(img, w, w - 1, (int)h) != want) bad++;
            free(packed);
        }
        free(img);
    }
    CHECKF(bad == 0, "%d masks' row CRCs differ from their bytes'", bad);
}

/* The same on layers of long runs of repeated rows (dark bands, a lit band,
   runs just short of and past the length that is combined rather than read),
   1-bit 3840-pixel rows and odd widths, back to back and padded. */
static void mask_crc_over_long_repeats_is_the_crc_of_the_bytes(void)
{
    static const size_t widths[] = {1, 3, 480, 481, 2000, 8193, 20000};
    int bad = 0;
    for (size_t i = 0; i < sizeof widths / sizeof widths[0]; i++) {
        const size_t w = widths[i], stride = w + i % 2 * 3, h = 300;
        unsigned char *img = (unsigned char *)malloc(stride * h), *packed = (unsigned char *)malloc(w * h);
        size_t y = 0;
        if (!img || !packed) { CHECK(!"out of memory"); free(img); free(packed); return; }
        memset(img, 0x5A, stride * h); /* padding that must not count */
        while (y < h) { /* a band of 1 to 120 rows: dark, lit, or one random row repeated */
            size_t band = 1 + codec_rng() % 120, kind = codec_rng() % 3, x, k;
            for (x = 0; x < w; x++) img[y * stride + x] = (unsigned char)(kind == 0 ? 0 : kind == 1 ? 0xFF : codec_rng());
            for (k = 1; k < band && y + k < h; k++) memcpy(img + (y + k) * stride, img + y * stride, w);
            y += band;
        }
        for (y = 0; y < h; y++) memcpy(packed + y * w, img + y * stride, w);
        if (mask_crc32(img, stride, w, (int)h) != ref_crc32(0, packed, w * h)) bad++;
        if (mask_crc32(img, stride, w, 1) != ref_crc32(0, packed, w)) bad++;
        free(img);
        free(packed);
    }
    CHECKF(bad == 0, "%d masks' row CRCs differ from their bytes'", bad);
}

/* The same on anti-aliased rows: runs of dark, lit and one grey of every
   length from 1 to past 4096 (so each power of two of a run's length is
   used), greys alone at the edges, rows that differ and rows that repeat. */
static void mask_crc_over_grey_runs_is_the_crc_of_the_bytes(void)
{
    static const size_t widths[] = {1, 7, 3840, 5001};
    int bad = 0;
    for (size_t i = 0; i < sizeof widths / sizeof widths[0]; i++) {
        const size_t w = widths[i], h = 64;
        unsigned char *img = (unsigned char *)malloc(w * h);
        if (!img) { CHECK(!"out of memory"); return; }
        for (size_t y = 0; y < h; y++) {
            size_t x = 0;
            if (y && codec_rng() % 4 == 0) { memcpy(img + y * w, img + (y - 1) * w, w); continue; }
            while (x < w) {
                size_t n = codec_rng() % 3 ? 1 + codec_rng() % 5000 : 1 + codec_rng() % 3, kind = codec_rng() % 3;
                unsigned char v = (unsigned char)(kind == 0 ? 0 : kind == 1 ? 255 : codec_rng());
                for (; n-- && x < w; x++) img[y * w + x] = v;
            }
        }
        for (size_t hh = 1; hh <= h; hh += 21)
            if (mask_crc32(img, w, w, (int)hh) != ref_crc32(0, img, w * hh)) bad++;
        free(img);
    }
    CHECKF(bad == 0, "%d grey masks' row CRCs differ from their bytes'", bad);
}

/* A job directory's layer as png_encode_layer codes it, from one reading of
   each row for the PNG, masks.rle and the CRC, on threads that share its
   coders: masks.rle's code and the CRC of each layer's rows. */
enum { LAYERS = 48, LAYER_THREADS = 4 };
typedef struct coded_layer {
    unsigned char *image;
    uint32_t w, h;
    size_t stride;
    int bits, rc;
    png_layer out;
} coded_layer;

static void *code_layers(void *arg)
{
    coded_layer *l = (coded_layer *)arg;
    int i;
    for (i = 0; i < LAYERS / LAYER_THREADS; i++, l += LAYER_THREADS)
        l->rc = png_encode_layer(l->image, (int)l->w, (int)l->h, l->stride, l->bits, NULL, &l->out);
    return NULL;
}

/* Rows of every kind a layer has: dark, lit, lit from the first pixel,
   runs, rows that repeat the row above, and (1-bit, widths past a byte)
   rows that repeat its pixels but not the padding bits of its last byte. */
static void layer_rows(coded_layer *l, int kind)
{
    const size_t rs = l->bits == 1 ? (l->w + 7) / 8 : l->w;
    uint32_t y, x;
    for (y = 0; y < l->h; y++) {
        unsigned char *row = l->image + (size_t)y * l->stride;
        int what = kind == 0 ? 0 : kind == 1 ? 1 : (int)(codec_rng() % 6);
        if (y && (what == 3 || what == 4)) {
            memcpy(row, row - l->stride, rs);
            if (what == 4 && l->bits == 1 && l->w % 8) row[rs - 1] ^= (unsigned char)(codec_rng() & (0xFFu >> (l->w % 8)));
            continue;
        }
        for (x = 0; x < rs;) {
            uint32_t len = 1 + codec_rng() % (codec_rng() % 4 ? 300 : 3);
            unsigned char v = (unsigned char)(what == 0   ? 0u
                                              : what == 1 ? 0xFFu
                                              : codec_rng() % 3 == 0 ? codec_rng()
                                              : codec_rng() % 2 ? 0xFFu : 0u);
            if (what == 2 && x == 0) v = 0xff; /* lit from the first pixel: a 1-bit row's first run is empty */
            while (len-- && x < rs) row[x++] = v;
        }
    }
}

/* png_encode_layer's masks.rle code is the reference encoder's bytes
   (codec_reference.h, a pixel at a time), its CRC the CRC of the rows'
   bytes, and its PNG is there: dark, lit and mixed layers at 1 and 8 bits,
   odd widths and padded strides, coded on four threads at once. */
static void layer_code_is_the_reference_encoders(void)
{
    coded_layer l[LAYERS];
    pthread_t threads[LAYER_THREADS];
    int i, started = 0, bad_code = 0, bad_crc = 0;
    memset(l, 0, sizeof l);
    for (i = 0; i < LAYERS; i++) {
        l[i].bits = i % 2 ? 8 : 1;
        l[i].w = i < 8 ? 3840 : 1 + codec_rng() % 2000;
        l[i].h = i < 8 ? 2400 : 1 + codec_rng() % 300;
        l[i].stride = (l[i].bits == 1 ? (l[i].w + 7) / 8 : l[i].w) + (size_t)(i % 3);
        if (!(l[i].image = (unsigned char *)malloc(l[i].stride * l[i].h))) { CHECK(!"out of memory"); goto done; }
        memset(l[i].image, 0x5A, l[i].stride * l[i].h); /* padding bytes that must not count */
        layer_rows(&l[i], i < 8 ? i / 2 % 3 : i % 5);
    }
    for (; started < LAYER_THREADS; started++)
        if (pthread_create(&threads[started], NULL, code_layers, &l[started])) break;
    CHECK(started == LAYER_THREADS);
    for (i = 0; i < started; i++) pthread_join(threads[i], NULL);
    for (i = 0; i < LAYERS && started == LAYER_THREADS; i++) {
        const size_t rs = l[i].bits == 1 ? (l[i].w + 7) / 8 : l[i].w, cap = adaslice_rle_bound(l[i].w, l[i].h, l[i].bits);
        unsigned char *want = (unsigned char *)malloc(cap), *rows = (unsigned char *)malloc(rs * l[i].h);
        size_t n = 0, y;
        CHECKF(l[i].rc == 0 && l[i].out.png && l[i].out.png_size > 8 && l[i].out.rle, "layer %d: not coded", i);
        CHECK(want && rows && ref_rle_encode(l[i].image, l[i].stride, l[i].w, l[i].h, l[i].bits, want, cap, &n) == ADASLICE_OK);
        if (want && (n != l[i].out.rle_size || (n && memcmp(want, l[i].out.rle, n)))) bad_code++;
        for (y = 0; rows && y < l[i].h; y++) memcpy(rows + y * rs, l[i].image + y * l[i].stride, rs);
        if (rows && l[i].out.crc != ref_crc32(0, rows, rs * l[i].h)) bad_crc++;
        free(want);
        free(rows);
    }
    CHECKF(bad_code == 0, "%d of %d layers' masks.rle code differs from the reference encoder's", bad_code, LAYERS);
    CHECKF(bad_crc == 0, "%d of %d layers' CRC differs from the CRC of their rows' bytes", bad_crc, LAYERS);
done:
    for (i = 0; i < LAYERS; i++) {
        free(l[i].image);
        free(l[i].out.png);
        free(l[i].out.rle);
    }
}

/* With lit rows given, png_encode_layer codes the layer as it codes the same
   image dark outside them, and does not read the rows outside: they hold
   garbage here, and the code (PNG, masks.rle, CRC) is still that of dark
   rows. Lit ranges at the top, the bottom, inside, of one row and empty;
   1 and 8 bits, odd widths, padded strides. */
static void dark_rows_outside_the_lit_ones_are_not_read(void)
{
    int i, bad = 0;
    for (i = 0; i < 40; i++) {
        coded_layer l, dark;
        const uint32_t h = 1 + codec_rng() % 200;
        int lit[2], y;
        memset(&l, 0, sizeof l);
        l.bits = i % 2 ? 8 : 1;
        l.w = 1 + codec_rng() % 900;
        l.h = h;
        l.stride = (l.bits == 1 ? (l.w + 7) / 8 : l.w) + (size_t)(i % 3);
        lit[0] = i % 5 == 0 ? 0 : (int)(codec_rng() % h);
        lit[1] = i % 5 == 1 ? (int)h : i % 5 == 2 ? lit[0] : i % 5 == 3 ? lit[0] + 1 : lit[0] + (int)(codec_rng() % (h - (uint32_t)lit[0] + 1));
        if (lit[1] > (int)h) lit[1] = (int)h;
        dark = l;
        l.image = (unsigned char *)malloc(l.stride * h);
        dark.image = (unsigned char *)malloc(l.stride * h);
        if (!l.image || !dark.image) { free(l.image); free(dark.image); CHECK(!"out of memory"); return; }
        memset(l.image, 0, l.stride * h);
        layer_rows(&l, 2 + i % 3);
        memcpy(dark.image, l.image, l.stride * h);
        for (y = 0; y < (int)h; y++) {
            int outside = y < lit[0] || y >= lit[1];
            if (!outside) continue;
            memset(dark.image + (size_t)y * l.stride, 0, l.stride);
            memset(l.image + (size_t)y * l.stride, 0xA7, l.stride); /* never to be read */
        }
        if (png_encode_layer(l.image, (int)l.w, (int)h, l.stride, l.bits, lit, &l.out) ||
            png_encode_layer(dark.image, (int)l.w, (int)h, l.stride, l.bits, NULL, &dark.out))
            bad++;
        else if (l.out.png_size != dark.out.png_size || memcmp(l.out.png, dark.out.png, l.out.png_size) ||
                 l.out.rle_size != dark.out.rle_size || memcmp(l.out.rle, dark.out.rle, l.out.rle_size) ||
                 l.out.crc != dark.out.crc)
            bad++;
        free(l.image);
        free(dark.image);
        free(l.out.png);
        free(l.out.rle);
        free(dark.out.png);
        free(dark.out.rle);
    }
    CHECKF(bad == 0, "%d of 40 layers coded with their lit rows differ from the same layers dark outside them", bad);
}

/* A layer read band by band where it was made (mask_band_scan: its rows
   bottom-up or top-down in the masker's own buffer, garbage outside the
   bytes the part can light) codes to the same PNG, masks.rle code and CRC
   as the image those bands make, dark outside them: 1 to 9 bands (some
   empty) in any order, rows outside every band, band edges between rows
   that repeat or differ only in their padding bits, 1 and 8 bits. */
static void bands_code_as_their_image(void)
{
    int i, bad = 0;
    for (i = 0; i < 60; i++) {
        coded_layer l;
        mask_band bands[9];
        png_layer want, got;
        const uint32_t h = 1 + codec_rng() % 200;
        const int flip = i % 2, count = 1 + (int)(codec_rng() % 9);
        int lit[2], cuts[10], b, k;
        size_t rs, lo, hi, sstride, y;
        unsigned char *source;
        memset(&l, 0, sizeof l);
        memset(bands, 0, sizeof bands);
        l.bits = i % 4 < 2 ? 1 : 8;
        l.w = 1 + codec_rng() % 900;
        l.h = h;
        rs = l.bits == 1 ? (l.w + 7) / 8 : l.w;
        l.stride = rs + (size_t)(i % 3);
        sstride = rs + 3;
        lo = i % 3 ? codec_rng() % (rs + 1) : 0;
        hi = i % 3 == 2 ? rs : lo + codec_rng() % (rs - lo + 1);
        lit[0] = (int)(codec_rng() % (h + 1));
        lit[1] = lit[0] + (int)(codec_rng() % (h - (uint32_t)lit[0] + 1));
        l.image = (unsigned char *)calloc(l.stride, h);
        source = (unsigned char *)malloc(sstride * h);
        if (!l.image || !source) { free(l.image); free(source); CHECK(!"out of memory"); return; }
        layer_rows(&l, 2 + i % 3);
        memset(source, 0xA7, sstride * h);
        for (y = 0; y < h; y++) {
            unsigned char *row = l.image + y * l.stride;
            memcpy(source + (flip ? h - 1 - y : y) * sstride + lo, row + lo, hi - lo);
            if ((int)y < lit[0] || (int)y >= lit[1]) memset(row, 0, rs);
            else memset(row, 0, lo), memset(row + hi, 0, rs - hi);
        }
        for (k = 0; k <= count; k++) cuts[k] = lit[0] + (int)(codec_rng() % ((uint32_t)(lit[1] - lit[0]) + 1));
        cuts[0] = lit[0];
        cuts[count] = lit[1];
        for (k = 1; k < count; k++) /* in order */
            for (b = k; b > 1 && cuts[b] < cuts[b - 1]; b--) { int t = cuts[b]; cuts[b] = cuts[b - 1]; cuts[b - 1] = t; }
        for (k = 0; k < count; k++) {
            mask_band *into = &bands[k];
            const int first = cuts[k], n = cuts[k + 1] - first;
            const unsigned char *top = n <= 0 ? source : source + (flip ? h - 1 - (size_t)first : (size_t)first) * sstride;
            if (mask_band_scan(into, top, flip ? -(ptrdiff_t)sstride : (ptrdiff_t)sstride, first, n, rs, lo, hi)) bad++;
        }
        if (i % 3 == 1) /* any order */
            for (k = 0; k < count / 2; k++) { mask_band t = bands[k]; bands[k] = bands[count - 1 - k]; bands[count - 1 - k] = t; }
        if (png_encode_layer(l.image, (int)l.w, (int)h, l.stride, l.bits, NULL, &want)) bad++;
        else if (png_encode_bands(bands, count, (int)l.w, (int)h, l.bits, &got)) bad++, free(want.png), free(want.rle);
        else {
            if (got.png_size != want.png_size || memcmp(got.png, want.png, got.png_size) || got.rle_size != want.rle_size ||
                memcmp(got.rle, want.rle, got.rle_size) || got.crc != want.crc)
                bad++;
            free(want.png), free(want.rle), free(got.png), free(got.rle);
        }
        for (k = 0; k < count; k++) mask_band_free(&bands[k]);
        free(l.image);
        free(source);
    }
    CHECKF(bad == 0, "%d of 60 layers coded from their bands differ from their images' code", bad);
}

static void empty_and_full_masks_are_tiny(void)
{
    static unsigned char image[1440][320];
    unsigned char code[64];
    size_t n;
    memset(image, 0, sizeof image);
    CHECK(adaslice_rle_encode(&image[0][0], 320, 2560, 1440, 1, code, sizeof code, &n) == ADASLICE_OK && n == 2);
    memset(image, 0xff, sizeof image);
    /* a new row: header, a 0 dark run and a lit run of 2560 (2 bytes); then a repeat */
    CHECK(adaslice_rle_encode(&image[0][0], 320, 2560, 1440, 1, code, sizeof code, &n) == ADASLICE_OK &&
          n == 1 + 1 + 2 + 2);
}

static int decode_all(const unsigned char *code, size_t n, uint32_t w, uint32_t h, int bits, adaslice_rle_decoder *dec)
{
    static unsigned char row[64];
    CHECK(adaslice_rle_decoder_init(dec, w, h, bits, row, sizeof row) == ADASLICE_OK);
    return adaslice_rle_decode(dec, code, n, NULL, NULL);
}

/* Every malformed input is refused with its class and the byte at fault. */
static void malformed_code_is_refused(void)
{
    adaslice_rle_decoder dec;
    unsigned char row[8];
    static const unsigned char too_long[] = {0x80, 0x80, 0x80, 0x80, 0x10};
    static const unsigned char overrun[] = {0x04, 0x03, 0x06};      /* 2 runs: 3 + 6 > 8 */
    static const unsigned char short_row[] = {0x02, 0x05};           /* 1 run of 5 < 8 */
    static const unsigned char zero_run[] = {0x06, 0x02, 0x00, 0x06}; /* a 0 run after the first */
    static const unsigned char too_many[] = {0x02, 0x08, 0x03};      /* 1 row, then 2 repeats of 2 rows */
    static const unsigned char zero_runs[] = {0x00};
    static const unsigned char grey_zero[] = {0x02, 0x7f, 0x00};
    CHECK(decode_all(too_long, sizeof too_long, 8, 2, 1, &dec) == ADASLICE_ERR_VARINT && dec.offset == 4);
    CHECK(decode_all(overrun, sizeof overrun, 8, 2, 1, &dec) == ADASLICE_ERR_RUN && dec.offset == 2);
    CHECK(decode_all(short_row, sizeof short_row, 8, 2, 1, &dec) == ADASLICE_ERR_RUN && dec.offset == 1);
    CHECK(decode_all(zero_run, sizeof zero_run, 8, 2, 1, &dec) == ADASLICE_ERR_RUN && dec.offset == 2);
    CHECK(decode_all(too_many, sizeof too_many, 8, 2, 1, &dec) == ADASLICE_ERR_ROWS && dec.offset == 2);
    CHECK(decode_all(zero_runs, sizeof zero_runs, 8, 2, 1, &dec) == ADASLICE_ERR_RUN && dec.offset == 0);
    CHECK(decode_all(grey_zero, sizeof grey_zero, 8, 2, 8, &dec) == ADASLICE_ERR_RUN && dec.offset == 2);
    /* the error sticks; a truncated code is not finished */
    CHECK(adaslice_rle_decode(&dec, zero_runs, 0, NULL, NULL) == ADASLICE_ERR_RUN && !adaslice_rle_finished(&dec));
    CHECK(decode_all(short_row, 1, 8, 2, 1, &dec) == ADASLICE_OK && !adaslice_rle_finished(&dec));
    CHECK(adaslice_rle_decoder_init(&dec, 8, 2, 4, row, sizeof row) == ADASLICE_ERR_ARGUMENT);
    CHECK(adaslice_rle_decoder_init(&dec, 100, 2, 1, row, sizeof row) == ADASLICE_ERR_ARGUMENT);
    CHECK(adaslice_rle_decoder_init(&dec, 0, 2, 1, row, sizeof row) == ADASLICE_ERR_ARGUMENT);
}

/* A printer's integers planned by adaslice_dp give the fewest layers and the
   smallest worst layer that the quadratic oracle finds (tests/plan_oracle.h),
   in a plan that keeps every rule; adaslice_plan_profile's planes with the
   same options, bit for bit, with and without the pre-pass; and such a plan
   never exceeds eps in mm. */
static void printer_units_plan_like_the_tool(void)
{
    static uint64_t workspace[4096];
    int trial, mismatches = 0, over = 0, plans = 0, infeasible = 0, oracle_misses = 0;
    for (trial = 0; trial < 3000; trial++) {
        double phi[600];
        uint32_t units[600];
        unsigned char forced[600];
        adaslice_profile p;
        adaslice_plan_options o;
        adaslice_plan plan;
        adaslice_dp dp;
        int n = 30 + (int)(codec_rng() % 560), i;
        memset(&p, 0, sizeof p);
        for (i = 0; i < n; i++) phi[i] = (codec_rng() % 50 == 0) ? 3.0 + (codec_rng() % 100) / 10.0 : 0.05 + (codec_rng() % 100000) / 99991.0;
        p.metric = trial % 3 == 0 ? ADASLICE_METRIC_ROUGHNESS : ADASLICE_METRIC_CUSP;
        p.bin_count = (size_t)n; p.bin = 0.002; p.phi = phi; p.height = n * p.bin;
        memset(&o, 0, sizeof o);
        o.eps_units = ADASLICE_PRINTER_EPS_UNITS;
        o.eps = 0.02 + (codec_rng() % 100) / 1000.0;
        o.sharp = trial % 2 ? ADASLICE_SHARP_OFF : 1.5;
        CHECK(adaslice_plan_units(&p, &o, units, forced, NULL) == ADASLICE_OK);
        CHECK(adaslice_dp_init(&dp, workspace, sizeof workspace, (uint32_t)n, 25, 75, o.eps_units, 0, 0) == ADASLICE_OK);
        for (i = 0; i < n; i++) adaslice_dp_push(&dp, units[i], forced[i]);
        {   /* the oracle: fewest layers, then the smallest worst, and a valid plan that has both */
            oracle_plan want = oracle_fewest_layers(units, forced, (uint32_t)n, 25, 75, o.eps_units);
            uint32_t got = adaslice_dp_layers(&dp), lengths[600], at = (uint32_t)n, k;
            uint64_t worst;
            if (want.layers == 0) oracle_misses += got != ADASLICE_UNREACHED;
            else if (got != want.layers) oracle_misses++;
            else {
                for (k = got; k > 0; k--) { lengths[k - 1] = adaslice_dp_layer_below(&dp, at); at -= lengths[k - 1]; }
                if (!oracle_plan_is_valid(units, forced, (uint32_t)n, 25, 75, o.eps_units, lengths, got, &worst) ||
                    worst != want.worst)
                    oracle_misses++;
            }
        }
        if (adaslice_plan_profile(&p, &o, &plan, NULL) != ADASLICE_OK) {
            infeasible++;
            if (adaslice_dp_layers(&dp) != ADASLICE_UNREACHED) mismatches++;
            continue;
        }
        plans++;
        if (adaslice_dp_layers(&dp) != plan.layer_count) mismatches++;
        else {
            uint32_t at = (uint32_t)n;
            size_t k;
            for (k = plan.layer_count; k > 0; k--) {
                if (plan.planes[k] != at) { mismatches++; break; }
                at -= adaslice_dp_layer_below(&dp, at);
            }
        }
        {
            size_t k;
            for (k = 0; k < plan.layer_count; k++) over += adaslice_layer_error(&p, plan.planes[k], plan.planes[k + 1]) > o.eps;
        }
        adaslice_plan_free(&plan);
    }
    CHECKF(oracle_misses == 0, "%d of 3000 integer plans differ from the oracle", oracle_misses);
    CHECKF(mismatches == 0 && over == 0 && plans > 1000 && infeasible > 10,
           "%d mismatches, %d layers over eps, %d plans, %d infeasible", mismatches, over, plans, infeasible);
}

static void printer_units_refuse_what_a_printer_cannot_plan(void)
{
    double phi[100];
    uint32_t units[100];
    unsigned char forced[100];
    adaslice_profile p;
    adaslice_plan_options o;
    adaslice_plan plan;
    adaslice_error e;
    int i;
    for (i = 0; i < 100; i++) phi[i] = 1;
    memset(&p, 0, sizeof p);
    p.metric = ADASLICE_METRIC_VOLUME; p.bin_count = 100; p.bin = 0.002; p.phi = phi; p.height = 0.2;
    memset(&o, 0, sizeof o);
    o.eps_units = ADASLICE_PRINTER_EPS_UNITS;
    CHECK(adaslice_plan_units(&p, &o, units, forced, &e) == ADASLICE_ERR_ARGUMENT);
    CHECK(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "additive"));
    p.metric = ADASLICE_METRIC_CUSP;
    o.tmax = 0.6; /* 300 bins per layer */
    CHECK(adaslice_plan_units(&p, &o, units, forced, &e) == ADASLICE_ERR_ARGUMENT && strstr(e.message, "255"));
    o.tmax = 0; o.budget = 3;
    CHECK(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_ERR_ARGUMENT);
    o.budget = 0; o.eps = 0.01; /* 25 bins of 0.002 mm at phi 1 exceed 0.01: infeasible, and the message says what works */
    CHECK(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_ERR_INFEASIBLE && e.min_eps > 0.05);
    o.eps = e.min_eps;
    CHECK(adaslice_plan_profile(&p, &o, &plan, &e) == ADASLICE_OK);
    if (e.result == ADASLICE_OK) adaslice_plan_free(&plan);
}

void test_codec(void)
{
    RUN(crc32_known_values);
    RUN(crc32_agrees_with_the_reference);
    RUN(masks_round_trip);
    RUN(repeated_rows_crc_by_combination);
    RUN(fast_encoder_writes_the_reference_bytes);
    RUN(mask_crc_by_rows_is_the_crc_of_the_bytes);
    RUN(mask_crc_over_long_repeats_is_the_crc_of_the_bytes);
    RUN(mask_crc_over_grey_runs_is_the_crc_of_the_bytes);
    RUN(layer_code_is_the_reference_encoders);
    RUN(dark_rows_outside_the_lit_ones_are_not_read);
    RUN(bands_code_as_their_image);
    RUN(empty_and_full_masks_are_tiny);
    RUN(malformed_code_is_refused);
    RUN(printer_units_plan_like_the_tool);
    RUN(printer_units_refuse_what_a_printer_cannot_plan);
}
