/* Raw deflate (RFC 1951) for the PNG and ZIP writers, tuned for layer masks:
   mostly runs, and rows that repeat the row above. */
#ifndef ADASLICE_HOST_DEFLATE_H
#define ADASLICE_HOST_DEFLATE_H
#include <stddef.h>

/* Compresses data[0, n) into one raw deflate stream (no zlib or gzip
   wrapper) in a malloc'd buffer (*out, *out_size; the caller frees *out).
   row is the distance from a byte to the same byte one row up, which the
   matcher tries besides runs and a hash (a PNG's row with its filter byte);
   0 for data without rows. n = 0 gives a valid empty stream. Returns 0 on
   success; -1 when out of memory or for n of 4 GiB or more (positions are
   32 bits), with *out = NULL and *out_size = 0. */
int deflate_bytes(const unsigned char *data, size_t n, size_t row, unsigned char **out, size_t *out_size);

#endif
