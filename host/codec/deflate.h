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

/* The same stream from symbols the caller finds, for data it knows as runs
   and repeated rows and never holds expanded (png_encode_mask): literals,
   and copies of `length` bytes (3 or more; longer ones are split) from
   `distance` bytes back (1 to 32768). The blocks are dynamic or fixed
   Huffman. deflate_begin: NULL when out of memory. deflate_literal and
   deflate_copy: 0, or -1 when out of memory, after which only
   deflate_finish, deflate_reset or deflate_free is called. deflate_finish
   ends the stream: *out and *out_size are its bytes, which d keeps until
   it is reset or freed; -1 when out of memory (or after a failure). A
   deflater is reused stream after stream (deflate_reset), so that a layer's
   PNG takes its buffers (256 KB of symbols, the stream) from the layer
   before, not from malloc. */
typedef struct deflater deflater;
deflater *deflate_begin(void);
int deflate_literal(deflater *d, unsigned char byte);
int deflate_copy(deflater *d, size_t length, size_t distance);
int deflate_finish(deflater *d, const unsigned char **out, size_t *out_size);
void deflate_reset(deflater *d);
void deflate_free(deflater *d);

#endif
