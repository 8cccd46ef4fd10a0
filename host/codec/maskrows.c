/* Rows of layer masks: see maskrows.h. */
#include "maskrows.h"
#include "../../adaslice_mcu.h"
#include <string.h>

void mask_row_grey(const unsigned char *image, size_t stride, int bits, int width, int y, unsigned char *out)
{
    const unsigned char *row = image + (size_t)y * stride;
    int x;
    if (bits == 8) { memcpy(out, row, (size_t)width); return; }
    for (x = 0; x + 8 <= width; x += 8) { /* a mask is mostly whole bytes of one colour */
        unsigned b = row[x >> 3];
        int i;
        if (b == 0 || b == 0xFF) memset(out + x, (int)(b & 0xFF), 8);
        else for (i = 0; i < 8; i++) out[x + i] = (unsigned char)((b >> (7 - i) & 1) ? 255 : 0);
    }
    for (; x < width; x++) out[x] = (unsigned char)((row[x >> 3] >> (7 - (x & 7)) & 1) ? 255 : 0);
}

/* Where the run of bytes equal to row[x] ends, at most at `end`: eight
   bytes at a time, as most of a mask is long runs of black. */
static int same_bytes_end(const unsigned char *row, int x, int end)
{
    const uint64_t all = 0x0101010101010101u * row[x];
    uint64_t word;
    for (x++; end - x >= 8; x += 8) {
        memcpy(&word, row + x, sizeof word);
        if (word != all) break;
    }
    while (x < end && row[x] == row[x - 1]) x++;
    return x;
}

void mask_row_runs(const unsigned char *row, int bits, int width, mask_run_fn run, void *ctx)
{
    int x = 0;
    if (bits == 8) {
        while (x < width) {
            int from = x;
            x = same_bytes_end(row, x, width);
            run(ctx, row[from], (uint64_t)(x - from));
        }
        return;
    }
    while (x < width) { /* whole 0x00 or 0xFF bytes go as runs of eight pixels a byte */
        const int whole_bytes = width >> 3;
        unsigned char b = row[x >> 3];
        if ((x & 7) == 0 && (x >> 3) < whole_bytes && (b == 0 || b == 0xFF)) {
            int from = x;
            x = same_bytes_end(row, x >> 3, whole_bytes) << 3;
            run(ctx, b, (uint64_t)(x - from));
        } else {
            run(ctx, (b >> (7 - (x & 7)) & 1) ? 255 : 0, 1);
            x++;
        }
    }
}


/* a * b modulo the CRC's polynomial, both as reflected polynomials (bit 31
   is x^0): what combining two CRCs needs (zlib's crc32_combine does the same). */
static uint32_t mult_mod_p(uint32_t a, uint32_t b)
{
    uint32_t m = (uint32_t)1 << 31, p = 0;
    while (m) {
        if (a & m) p ^= b;
        m >>= 1;
        b = b & 1u ? (b >> 1) ^ 0xedb88320u : b >> 1;
    }
    return p;
}

/* x^(8 n) modulo the polynomial: appending n bytes shifts a CRC by that. */
static uint32_t x_to_8n(size_t n)
{
    uint32_t result = (uint32_t)1 << 31, power = (uint32_t)1 << 30; /* x^0, x^1 */
    unsigned long long e = 8ull * n;
    while (e) {
        if (e & 1u) result = mult_mod_p(power, result);
        power = mult_mod_p(power, power);
        e >>= 1;
    }
    return result;
}

/* crc continued over rows [from, to): in one call when they lie back to back */
static uint32_t crc_rows(uint32_t crc, const unsigned char *image, size_t stride, size_t row_bytes, int from, int to)
{
    if (stride == row_bytes) return adaslice_crc32(crc, image + (size_t)from * stride, (size_t)(to - from) * row_bytes);
    for (; from < to; from++) crc = adaslice_crc32(crc, image + (size_t)from * stride, row_bytes);
    return crc;
}

/* crc after `times` more copies of a row whose own CRC is `row`: the map
   c -> c shift + row (shift: x^(8 n) for rows of n bytes) applied `times`
   times, by squaring (f twice is c -> c shift^2 + row shift + row), so a
   layer's thousand dark rows cost a few dozen multiplications. */
static uint32_t append_repeats(uint32_t crc, uint32_t row, uint32_t shift, size_t times)
{
    for (; times; times >>= 1) {
        if (times & 1) crc = mult_mod_p(shift, crc) ^ row;
        row = mult_mod_p(shift, row) ^ row;
        shift = mult_mod_p(shift, shift);
    }
    return crc;
}

/* Rows go through adaslice_crc32 as a running CRC in as few calls as can be:
   it slices sixteen bytes a step only in calls of 4 KiB or more (it builds
   its tables each call), so one call a row took the nibble loop, several
   times slower. Only a long run of rows that repeat the row above (the dark around
   the part) is left out of the calls and added by combination. */
uint32_t mask_crc32(const unsigned char *image, size_t stride, size_t row_bytes, int height)
{
    const size_t long_run = row_bytes ? 8192 / row_bytes + 1 : 1; /* shorter runs are cheaper as bytes */
    uint32_t crc = 0, shift = x_to_8n(row_bytes);
    int y = 0, from = 0; /* rows [from, y) are not yet in crc */
    while (y < height) {
        size_t k = 0;
        if (y > 0)
            while (y + (int)k < height &&
                   !memcmp(image + (size_t)(y + (int)k) * stride, image + (size_t)(y - 1) * stride, row_bytes))
                k++;
        if (k < long_run) {
            y += k ? (int)k : 1;
            continue;
        }
        crc = crc_rows(crc, image, stride, row_bytes, from, y);
        crc = append_repeats(crc, adaslice_crc32(0, image + (size_t)(y - 1) * stride, row_bytes), shift, k);
        y += (int)k;
        from = y;
    }
    return crc_rows(crc, image, stride, row_bytes, from, height);
}
