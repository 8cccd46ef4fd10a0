/* SHA-256 (FIPS 180-4), small and plain: what the encrypted CTB format signs
   its checksum with. */
#ifndef ADASLICE_HOST_SHA256_H
#define ADASLICE_HOST_SHA256_H
#include <stddef.h>
#include <stdint.h>

typedef struct sha256 {
    uint32_t h[8];
    uint64_t bytes;              /* taken so far */
    unsigned char block[64];     /* the part block, bytes % 64 of them */
} sha256;

void sha256_init(sha256 *s);
void sha256_update(sha256 *s, const void *data, size_t n);
void sha256_final(sha256 *s, unsigned char digest[32]);
/* The digest of data[0, n) in one call. */
void sha256_digest(const void *data, size_t n, unsigned char digest[32]);
#endif
