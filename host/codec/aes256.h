/* AES-256 (FIPS-197) and its CBC mode (NIST SP 800-38A, 6.2), small and
   plain: a byte-oriented cipher with no tables beyond the S-boxes, for the
   few kilobytes the encrypted CTB format enciphers (its settings block and
   signature). Not hardened against timing: nothing secret goes through it,
   the keys it is used with are published. */
#ifndef ADASLICE_HOST_AES256_H
#define ADASLICE_HOST_AES256_H
#include <stddef.h>

/* The expanded key: 15 round keys of 16 bytes. */
typedef struct aes256 {
    unsigned char round_key[240];
} aes256;

void aes256_init(aes256 *a, const unsigned char key[32]);
void aes256_encrypt_block(const aes256 *a, const unsigned char in[16], unsigned char out[16]);
void aes256_decrypt_block(const aes256 *a, const unsigned char in[16], unsigned char out[16]);

/* CBC over data[0, n) in place, n a multiple of 16 (no padding: the callers'
   blocks are whole). iv is the chaining value: on return it holds the last
   cipher block, so a stream may be enciphered in pieces. */
void aes256_cbc_encrypt(const aes256 *a, unsigned char iv[16], unsigned char *data, size_t n);
void aes256_cbc_decrypt(const aes256 *a, unsigned char iv[16], unsigned char *data, size_t n);
#endif
