/* Raw deflate (RFC 1951) decoding, for reading back the ZIP members the
   FDM project holds (a 3MF). Bounded by its input and output: any bytes
   give an answer, never a read or write outside them. */
#ifndef ADASLICE_HOST_INFLATE_H
#define ADASLICE_HOST_INFLATE_H
#include <stddef.h>

/* Decodes the raw deflate stream in[0, n) into out[0, size), which must be
   exactly the stream's output. 0, or -1 for a malformed stream, one that
   ends early, or output of another length. */
int inflate_bytes(const unsigned char *in, size_t n, unsigned char *out, size_t size);
#endif
