/* PNG writer for printer layer masks (grayscale, 1 or 8 bits per pixel) and
   job previews (8-bit RGB), through deflate.h's deflate, which is tuned for
   mostly black images with a few smooth regions. */
#ifndef ADASLICE_HOST_PNG_H
#define ADASLICE_HOST_PNG_H
#include <stddef.h>
#include <stdint.h>
#include "maskrows.h"

/* Encodes a width x height grayscale image as a PNG file image in a malloc'd
   buffer (*out, *out_size; the caller frees *out). bits is 1 or 8. 1-bit rows
   are packed MSB first, 1 = white (lit); bits past the width in a row's last
   byte are ignored. stride is the number of bytes between rows of pixels.
   1-bit images (layer masks) are coded from their rows' runs of bytes, as
   png_encode_mask does, in time proportional to the runs of the rows that
   differ from the row above. Returns 0 on success; -1 when out of memory or
   for invalid arguments (bits not 1 or 8, width or height < 1, stride
   shorter than a row, 1-bit rows of 2^24 bytes or more, or more than 2 GB
   of row data), with *out = NULL and *out_size = 0. */
int png_encode_gray(const unsigned char *pixels, int width, int height, size_t stride, int bits,
                    unsigned char **out, size_t *out_size);

/* The same for a width x height truecolour image (colour type 2, 8 bits a
   channel): rows top first of 3 bytes (R, G, B) a pixel, 3 * width bytes
   apart. -1 for width or height < 1, more than 2 GB of row data or out of
   memory. */
int png_encode_rgb(const unsigned char *rgb, int width, int height, unsigned char **out, size_t *out_size);

/* An 8-bit grey PNG of a 1- or 8-bit mask (1-bit pixels as 0 or 255), as the
   ChiTu and Prusa jobs want their layers, in time proportional to the mask's
   runs rather than its pixels. Arguments as png_encode_gray; -1 as there
   too, and for widths of 2^24 or more. */
int png_encode_mask(const unsigned char *image, int width, int height, size_t stride, int bits, unsigned char **out,
                    size_t *out_size);

/* A layer of a job directory: its PNG (1-bit as png_encode_gray codes it,
   8-bit as png_encode_mask) and, from the same one reading of its rows
   (mask_scan: the coders share each row's runs), masks.rle's code of it
   (adaslice_rle_encode's bytes) and the CRC-32 of its rows' bytes. png and
   rle are malloc'd (the caller frees them). -1 as png_encode_mask, and for
   a height of 2^24 or more, with nothing allocated. lit_rows (NULL: every
   row) says that the rows outside [lit_rows[0], lit_rows[1]) are dark: they
   are not read. */
typedef struct png_layer {
    unsigned char *png, *rle;
    size_t png_size, rle_size;
    uint32_t crc;
} png_layer;
int png_encode_layer(const unsigned char *image, int width, int height, size_t stride, int bits, const int lit_rows[2],
                     png_layer *layer);
/* The same from the layer's rows read band by band where they were made
   (mask_band_scan; rows in none of the bands are dark): the same bytes as
   from the image they make. */
int png_encode_bands(const mask_band *bands, int count, int width, int height, int bits, png_layer *layer);

/* Adler-32 as zlib uses it: adler = png_adler32(1, data, n); feeding the
   result back in continues it over more data. (CRC-32 is adaslice_crc32.) */
uint32_t png_adler32(uint32_t adler, const void *data, size_t size);

#endif
