/* Rows of a layer mask as the job formats get them: 1-bit rows packed most
   significant bit first (1 = lit) or 8-bit grey rows. */
#ifndef ADASLICE_HOST_MASKROWS_H
#define ADASLICE_HOST_MASKROWS_H
#include "../bytes.h"
#include <stddef.h>
#include <stdint.h>

/* Row y of an image of rows `stride` bytes apart as 8-bit grey (1-bit: 0 or 255). */
void mask_row_grey(const unsigned char *image, size_t stride, int bits, int width, int y, unsigned char *out);

/* The runs of equal pixels along one row, left to right: run(ctx, grey, n),
   1-bit pixels as 0 or 255. Neighbouring runs may share a grey (a run of
   whole bytes beside one of single pixels); the cost is in the runs, whole
   bytes of one colour are passed over eight at a time. */
typedef void (*mask_run_fn)(void *ctx, unsigned grey, uint64_t n);
void mask_row_runs(const unsigned char *row, int bits, int width, mask_run_fn run, void *ctx);

/* A layer's rows read once for all of its coders (the PNG, masks.rle's code
   and the CRC), so that a layer's megabytes come from memory once after the
   masker wrote them rather than once a coder. The reading (mask_band_scan)
   keeps each row that differs from the row above as its runs of equal bytes
   and the rows that repeat it as a count; the coders step through that
   (mask_scan_next) and work from the runs. A layer made in row bands on
   several threads is read band by band on the thread that made each, while
   its rows are in that core's cache: the coder on another core then reads
   the bands' runs, not the megabyte (reading it there, and copying the
   bands into one image for it, cost two threads a tenth more work than
   one). */
typedef struct mask_band_step {
    int rows;                        /* the step's rows */
    int repeat;                      /* they repeat the row above byte for byte */
    size_t run, count;               /* !repeat (one row): its runs, runs[run] on */
} mask_band_step;
typedef struct mask_band {
    int first, count;                /* the layer's rows [first, first + count) */
    mask_band_step *steps;           /* the first row is never a repeat (the row above is
                                        another band's): the scan of the layer tells */
    size_t step_count, step_cap;
    uint32_t *runs;                  /* value << 24 | length, each as long as it goes */
    size_t run_count, run_cap;
} mask_band;
/* Reads `count` rows of row_bytes (under 2^24) into b as the layer's rows
   from `first` on: the first at `rows`, each next `step` bytes on (negative:
   the rows are stored bottom-up). Only bytes [lo, hi) of a row are read;
   the rest are 0. b's buffers are kept from its last scan (zero it the
   first time). 0, or -1 when out of memory. */
int mask_band_scan(mask_band *b, const unsigned char *rows, ptrdiff_t step, int first, int count, size_t row_bytes,
                   size_t lo, size_t hi);
void mask_band_free(mask_band *b);

typedef struct mask_scan {
    int width, bits, height;
    size_t row_bytes, whole;         /* whole: bytes of eight pixels (8-bit: all) */
    unsigned tail;                   /* the pixels' bits of a 1-bit row's last byte when it is part padding */
    const mask_band *bands;          /* the layer's, apart; rows in none are dark */
    int band_count;
    const mask_band *in;             /* the band of the step's row, or NULL: a dark row */
    int until;                       /* where `in` (or the dark rows) ends */
    size_t next;                     /* in's next step */
    uint32_t dark;                   /* a dark row's runs */
    mask_band own;                   /* mask_scan_image's */
    /* the step */
    int y, rows;                     /* rows y to y + rows - 1 */
    int repeat;                      /* they repeat the row above byte for byte; runs are its */
    int same_pixels;                 /* !repeat: the row's pixels are the row above's (its padding differs) */
    const uint32_t *runs;            /* row y's runs of equal bytes, value << 24 | length, each as long as it goes */
    size_t count;
} mask_scan;
/* A scan of a layer of height rows of width pixels at bits (1 or 8; rows of
   fewer than 2^24 bytes) from its bands (count of them, not overlapping, in
   any order), which it points to: rows in none are dark. */
void mask_scan_bands(mask_scan *s, const mask_band *bands, int count, int width, int bits, int height);
/* The same from an image, rows stride bytes apart, read here: all of its
   rows, or when lit is not NULL only [lit[0], lit[1]) (a caller who knows
   that the others are dark: a layer's rows away from the part are half of
   a large display's megabyte). The buffers of a scan begun before are kept
   (zero it the first time). -1 when out of memory. */
int mask_scan_image(mask_scan *s, const unsigned char *image, size_t stride, int width, int bits, int height,
                    const int lit[2]);
/* The next step, or 0 after the last row. */
int mask_scan_next(mask_scan *s);
/* The step's row as runs, run(ctx, value, n), from its runs of bytes: of
   pixels (1-bit ones as 0 or 255) when pixels, else of bytes, a 1-bit
   row's padding bits cleared. Neighbouring runs may share a value. */
void mask_scan_runs(const mask_scan *s, int pixels, mask_run_fn run, void *ctx);
void mask_scan_free(mask_scan *s);

/* masks.rle's code of a layer, adaslice_rle_encode's bytes, from its scan,
   its records written by the same adaslice_rle_put_*: the printer's
   encoder (adaslice_mcu.h) reads the rows itself, which on the host would
   be a layer's megabytes from memory once more. 1-bit runs of pixels come
   from the runs of bytes. The code grows in `code` (kept by mask_rle_begin
   for the next layer; code.failed: out of memory). */
typedef struct mask_rle {
    int width, bits;
    uint32_t repeat;                 /* rows owed to a repeat record */
    bytebuf code;
    uint32_t *lengths;               /* a 1-bit row's runs of dark and lit, dark first */
    size_t count, lengths_cap;
} mask_rle;
void mask_rle_begin(mask_rle *r, int width, int bits);
void mask_rle_step(mask_rle *r, const mask_scan *s);
/* The last repeat record: 0, or -1 when out of memory. */
int mask_rle_end(mask_rle *r);
void mask_rle_free(mask_rle *r);

/* CRC-32 (adaslice_crc32's) of a scan's rows as one stream, in time
   proportional to the rows' runs of equal bytes (each run a few table
   lookups, not its bytes); a long run of rows that repeat the row above
   costs a few multiplications in GF(2) (CRC combination). */
typedef struct mask_crc { uint32_t crc, shift; size_t long_run; } mask_crc;
void mask_crc_begin(mask_crc *c, size_t row_bytes);
void mask_crc_step(mask_crc *c, const mask_scan *s);

/* The same over an image: height rows of row_bytes, stride apart. */
uint32_t mask_crc32(const unsigned char *image, size_t stride, size_t row_bytes, int height);
#endif
