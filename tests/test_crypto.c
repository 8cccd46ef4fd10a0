/* host/codec/aes256.c and host/codec/sha256.c against the published vectors: FIPS-197
   Appendix C.3 (AES-256), NIST SP 800-38A F.2.5 and F.2.6 (CBC-AES256),
   FIPS 180-4's examples for SHA-256 (NIST CSRC "Example Algorithms":
   "abc", the 448-bit message, one million 'a'). */
#include "check.h"
#include "../host/codec/aes256.h"
#include "../host/codec/sha256.h"
#include <stdlib.h>
#include <string.h>

/* hex into bytes; the count written. */
static size_t unhex(const char *hex, unsigned char *out)
{
    size_t n = 0;
    for (; hex[0] && hex[1]; hex += 2) {
        unsigned v;
        if (sscanf(hex, "%2x", &v) != 1) break;
        out[n++] = (unsigned char)v;
    }
    return n;
}

static void fips197_c3_aes256(void)
{
    unsigned char key[32], in[16], want[16], got[16], back[16];
    aes256 a;
    unhex("000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f", key);
    unhex("00112233445566778899aabbccddeeff", in);
    unhex("8ea2b7ca516745bfeafc49904b496089", want);
    aes256_init(&a, key);
    aes256_encrypt_block(&a, in, got);
    CHECK(!memcmp(got, want, 16));
    aes256_decrypt_block(&a, got, back);
    CHECK(!memcmp(back, in, 16));
    /* FIPS-197 C.3's last round key, w[56..59] */
    unhex("24fc79ccbf0979e9371ac23c6d68de36", want);
    CHECK(!memcmp(a.round_key + 224, want, 16));
}

static const char *const sp800_38a_key = "603deb1015ca71be2b73aef0857d77811f352c073b6108d72d9810a30914dff4";
static const char *const sp800_38a_plain = "6bc1bee22e409f96e93d7e117393172aae2d8a571e03ac9c9eb76fac45af8e51"
                                           "30c81c46a35ce411e5fbc1191a0a52eff69f2445df4f9b17ad2b417be66c3710";
static const char *const sp800_38a_cipher = "f58c4c04d6e5f1ba779eabfb5f7bfbd69cfc4e967edb808d679f777bc6702c7d"
                                            "39f23369a9d9bacfa530e26304231461b2eb05e2c39be9fcda6c19078c6a9d1b";

/* F.2.5 whole, then in pieces of one block and three: the chaining value
   carries over. */
static void sp800_38a_f25_cbc_encrypt(void)
{
    unsigned char key[32], iv[16], data[64], want[64];
    aes256 a;
    unhex(sp800_38a_key, key);
    unhex(sp800_38a_cipher, want);
    aes256_init(&a, key);
    unhex("000102030405060708090a0b0c0d0e0f", iv);
    unhex(sp800_38a_plain, data);
    aes256_cbc_encrypt(&a, iv, data, 64);
    CHECK(!memcmp(data, want, 64));
    CHECK(!memcmp(iv, want + 48, 16));
    unhex("000102030405060708090a0b0c0d0e0f", iv);
    unhex(sp800_38a_plain, data);
    aes256_cbc_encrypt(&a, iv, data, 16);
    aes256_cbc_encrypt(&a, iv, data + 16, 48);
    CHECK(!memcmp(data, want, 64));
}

static void sp800_38a_f26_cbc_decrypt(void)
{
    unsigned char key[32], iv[16], data[64], want[64];
    aes256 a;
    unhex(sp800_38a_key, key);
    unhex(sp800_38a_plain, want);
    aes256_init(&a, key);
    unhex("000102030405060708090a0b0c0d0e0f", iv);
    unhex(sp800_38a_cipher, data);
    aes256_cbc_decrypt(&a, iv, data, 64);
    CHECK(!memcmp(data, want, 64));
    unhex("000102030405060708090a0b0c0d0e0f", iv);
    unhex(sp800_38a_cipher, data);
    aes256_cbc_decrypt(&a, iv, data, 32);
    aes256_cbc_decrypt(&a, iv, data + 32, 32);
    CHECK(!memcmp(data, want, 64));
}

static int digest_is(const void *data, size_t n, const char *hex)
{
    unsigned char got[32], want[32];
    sha256_digest(data, n, got);
    unhex(hex, want);
    return !memcmp(got, want, 32);
}

static void fips180_sha256_examples(void)
{
    static const char two_blocks[] = "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
    CHECK(digest_is("abc", 3, "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"));
    CHECK(strlen(two_blocks) * 8 == 448);
    CHECK(digest_is(two_blocks, 56, "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1"));
    /* the empty message: padding alone */
    CHECK(digest_is("", 0, "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"));
}

/* One million 'a', once in one call and once in pieces of 1 to 127 bytes
   that cross the 64-byte blocks everywhere. */
static void fips180_sha256_million_a(void)
{
    const char *want = "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0";
    unsigned char *a = (unsigned char *)malloc(1000000), got[32], expect[32];
    size_t at = 0, piece = 1;
    sha256 s;
    if (!a) { CHECK(!"out of memory"); return; }
    memset(a, 'a', 1000000);
    CHECK(digest_is(a, 1000000, want));
    sha256_init(&s);
    while (at < 1000000) {
        size_t n = piece < 1000000 - at ? piece : 1000000 - at;
        sha256_update(&s, a + at, n);
        at += n;
        piece = piece % 127 + 1;
    }
    sha256_final(&s, got);
    unhex(want, expect);
    CHECK(!memcmp(got, expect, 32));
    free(a);
}

void test_crypto(void)
{
    RUN(fips197_c3_aes256);
    RUN(sp800_38a_f25_cbc_encrypt);
    RUN(sp800_38a_f26_cbc_decrypt);
    RUN(fips180_sha256_examples);
    RUN(fips180_sha256_million_a);
}
