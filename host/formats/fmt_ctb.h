/* What the ChiTuBox formats share: fmt_ctb.c (CTB v3/v4) codes them and
   fmt_ctb_encrypted.c (the encrypted CTB) uses the same codes. */
#ifndef ADASLICE_HOST_FMT_CTB_H
#define ADASLICE_HOST_FMT_CTB_H
#include <stddef.h>
#include <stdint.h>
#include "jobfile.h"

/* The text ChiTuBox puts in every v4 and encrypted file, CTB_DISCLAIMER_LEN
   bytes with no NUL. */
#define CTB_DISCLAIMER_LEN 320
extern const char ctb_disclaimer[];

/* A preview of `pixels` RGB pixels (3 bytes each) in CTB's RGB15 run-length
   code into out (room for 2 bytes a pixel); the bytes written. */
size_t ctb_preview_encode(const unsigned char *rgb, size_t pixels, unsigned char *out);

/* A layer's image (as job_format.encode has it: d->width x d->height,
   d->bits per pixel, rows `stride` bytes apart) in CTB's 7-bit run-length
   code, appended to blob; 0, or -1 when out of memory. */
int ctb_rle_encode(const job_desc *d, const unsigned char *image, size_t stride, job_blob *blob);

/* Layer `layer`'s code enciphered (or deciphered: the same) with CTB's layer
   key `seed`; a seed of 0 leaves it clear. */
void ctb_layer_xor(uint32_t seed, uint32_t layer, unsigned char *data, size_t n);
#endif
