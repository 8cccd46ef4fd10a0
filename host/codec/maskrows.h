/* Rows of a layer mask as the job formats get them: 1-bit rows packed most
   significant bit first (1 = lit) or 8-bit grey rows. */
#ifndef ADASLICE_HOST_MASKROWS_H
#define ADASLICE_HOST_MASKROWS_H
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

/* CRC-32 (adaslice_crc32's) of height rows of row_bytes, stride apart, as
   one stream, in time proportional to the rows' runs of equal bytes (each
   run a few table lookups, not its bytes); a long run of rows that repeat
   the row above costs a few multiplications in GF(2) (CRC combination). */
uint32_t mask_crc32(const unsigned char *image, size_t stride, size_t row_bytes, int height);
#endif
