/* PNG encoder for layer masks and previews, written from the PNG
   specification and RFC 1950 (zlib); the deflate inside is deflate.c's, told
   that the same byte one row up is a row length + 1 back. */
#include "png.h"
#include "deflate.h"
#include "../adaslice.h"
#include <stdlib.h>
#include <string.h>

uint32_t png_adler32(uint32_t adler, const void *data, size_t size)
{
    const uint64_t ones = 0x0101010101010101u;
    const unsigned char *p = (const unsigned char *)data;
    uint32_t a = adler & 0xffff, b = adler >> 16;
    while (size > 0) {
        /* 5552 bytes of 0xff is the most b can absorb before 32 bits overflow. */
        size_t n = size < 5552 ? size : 5552;
        size -= n;
        while (n >= 8) {
            uint64_t w, next;
            memcpy(&w, p, 8);
            if (w == (w & 0xff) * ones) { /* masks are mostly runs: sum m bytes of v at once */
                uint32_t m = 8, v = (uint32_t)(w & 0xff);
                while (m + 8 <= n && (memcpy(&next, p + m, 8), next == w)) m += 8;
                b += m * a + v * (m * (m + 1) / 2);
                a += m * v;
                p += m;
                n -= m;
                continue;
            }
            a += p[0]; b += a; a += p[1]; b += a; a += p[2]; b += a; a += p[3]; b += a;
            a += p[4]; b += a; a += p[5]; b += a; a += p[6]; b += a; a += p[7]; b += a;
            p += 8;
            n -= 8;
        }
        while (n--) { a += *p++; b += a; }
        a %= 65521;
        b %= 65521;
    }
    return b << 16 | a;
}

/* ---- PNG ---------------------------------------------------------------- */

static void put_be32(unsigned char *o, uint32_t v)
{
    o[0] = (unsigned char)(v >> 24);
    o[1] = (unsigned char)(v >> 16);
    o[2] = (unsigned char)(v >> 8);
    o[3] = (unsigned char)v;
}

/* Rows of filter byte + data. The matcher codes runs and bytes repeated from
   one row up, so a row costs little under None where its words are flat (all
   bytes equal) or equal to the words above; Up only pays on rows whose Up
   difference has more flat words than that (gradients, say). On masks None
   wins, which keeps every row matchable against the row above. */
static void filter_rows(const unsigned char *pixels, int height, size_t stride, size_t rowbytes,
                        unsigned char last_mask, unsigned char *out)
{
    const uint64_t high = 0x8080808080808080u, ones = 0x0101010101010101u;
    for (int y = 0; y < height; y++, out += rowbytes + 1) {
        const unsigned char *cur = pixels + (size_t)y * stride, *prev = cur - (y ? stride : 0);
        size_t body = rowbytes - 1, flat_none = 0, flat_up = 0;
        unsigned char last = cur[body] & last_mask;
        for (size_t x = 0; y > 0 && x + 8 <= body; x += 8) { /* the first row gets None */
            uint64_t c, p, up;
            memcpy(&c, cur + x, 8);
            memcpy(&p, prev + x, 8);
            if (c == p) continue; /* counts for both */
            /* bytewise c - p: the high bits set in c and clear in p stop borrows
               crossing bytes, the last xor puts the right high bits back */
            up = ((c | high) - (p & ~high)) ^ ((c ^ ~p) & high);
            flat_none += c == (c & 0xff) * ones;
            flat_up += up == (up & 0xff) * ones;
        }
        if (flat_up > flat_none) {
            out[0] = 2;
            for (size_t x = 0; x < body; x++) out[1 + x] = (unsigned char)(cur[x] - prev[x]);
            out[rowbytes] = (unsigned char)(last - (prev[body] & last_mask));
        } else {
            out[0] = 0;
            memcpy(out + 1, cur, body);
            out[rowbytes] = last;
        }
    }
}

/* One IDAT holding the filtered rows of rowbytes each; colour is the IHDR
   colour type, last_mask the bits of a row's last byte that are pixels. */
static int encode(const unsigned char *pixels, int width, int height, size_t stride, size_t rowbytes, int bits,
                  int colour, unsigned char last_mask, unsigned char **out, size_t *out_size)
{
    /* Up to 2 GB of row data keeps the one IDAT chunk under its 2^31 limit. */
    const size_t max_data = 0x7F000000u, head = 8 + 25 + 8;
    static const unsigned char signature[8] = {137, 80, 78, 71, 13, 10, 26, 10};
    unsigned char *filtered, *z = NULL, *o;
    size_t n, zsize = 0, size;

    *out = NULL;
    *out_size = 0;
    if (width < 1 || height < 1 || !pixels || stride < rowbytes || rowbytes + 1 > max_data / (size_t)height)
        return -1;
    n = (rowbytes + 1) * (size_t)height;
    if (!(filtered = (unsigned char *)malloc(n))) return -1;
    filter_rows(pixels, height, stride, rowbytes, last_mask, filtered);
    if (deflate_bytes(filtered, n, rowbytes + 1, &z, &zsize) ||
        !(o = (unsigned char *)malloc(size = head + 2 + zsize + 4 + 4 + 12))) {
        free(filtered);
        free(z);
        return -1;
    }
    memcpy(o, signature, 8);
    put_be32(o + 8, 13);
    memcpy(o + 12, "IHDR", 4);
    put_be32(o + 16, (uint32_t)width);
    put_be32(o + 20, (uint32_t)height);
    o[24] = (unsigned char)bits;
    o[25] = (unsigned char)colour;
    memset(o + 26, 0, 3); /* deflate, adaptive filters, no interlace */
    put_be32(o + 29, adaslice_crc32(0, o + 12, 17));
    put_be32(o + 33, (uint32_t)(2 + zsize + 4));
    memcpy(o + 37, "IDAT", 4);
    o[41] = 0x78; /* deflate, 32K window; 0x7801 is a multiple of 31 */
    o[42] = 0x01;
    memcpy(o + head + 2, z, zsize);
    put_be32(o + head + 2 + zsize, png_adler32(1, filtered, n));
    put_be32(o + head + 2 + zsize + 4, adaslice_crc32(0, o + 37, 4 + 2 + zsize + 4));
    put_be32(o + size - 12, 0);
    memcpy(o + size - 8, "IEND", 4);
    put_be32(o + size - 4, adaslice_crc32(0, "IEND", 4));
    free(filtered);
    free(z);
    *out = o;
    *out_size = size;
    return 0;
}

int png_encode_gray(const unsigned char *pixels, int width, int height, size_t stride, int bits,
                    unsigned char **out, size_t *out_size)
{
    if (bits != 1 && bits != 8) {
        *out = NULL;
        *out_size = 0;
        return -1;
    }
    return encode(pixels, width, height, stride, bits == 8 ? (size_t)width : ((size_t)width + 7) / 8, bits, 0,
                  (unsigned char)(bits == 1 && width % 8 ? 0xFF << (8 - width % 8) : 0xFF), out, out_size);
}

int png_encode_rgb(const unsigned char *rgb, int width, int height, unsigned char **out, size_t *out_size)
{
    return encode(rgb, width, height, 3 * (size_t)width, 3 * (size_t)width, 8, 2, 0xFF, out, out_size);
}
