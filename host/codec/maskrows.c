/* Rows of layer masks: see maskrows.h. */
#include "maskrows.h"
#include "../../adaslice_mcu.h"
#include <stdlib.h>
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

/* Where the run of bytes equal to row[x] ends, at most at `end`: 32 bytes
   a step, then eight, as most of a mask is long runs of dark or lit (an
   anti-aliased layer's rows are thousands of bytes long). */
static size_t same_bytes_end(const unsigned char *row, size_t x, size_t end)
{
    const uint64_t all = 0x0101010101010101u * row[x];
    uint64_t word, a, b, c, d;
    for (x++; end - x >= 32; x += 32) {
        memcpy(&a, row + x, 8), memcpy(&b, row + x + 8, 8), memcpy(&c, row + x + 16, 8), memcpy(&d, row + x + 24, 8);
        if ((a ^ all) | (b ^ all) | (c ^ all) | (d ^ all)) break;
    }
    for (; end - x >= 8; x += 8) {
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
            x = (int)same_bytes_end(row, (size_t)x, (size_t)width);
            run(ctx, row[from], (uint64_t)(x - from));
        }
        return;
    }
    while (x < width) { /* whole 0x00 or 0xFF bytes go as runs of eight pixels a byte */
        const int whole_bytes = width >> 3;
        unsigned char b = row[x >> 3];
        if ((x & 7) == 0 && (x >> 3) < whole_bytes && (b == 0 || b == 0xFF)) {
            int from = x;
            x = (int)same_bytes_end(row, (size_t)(x >> 3), (size_t)whole_bytes) << 3;
            run(ctx, b, (uint64_t)(x - from));
        } else {
            run(ctx, (b >> (7 - (x & 7)) & 1) ? 255 : 0, 1);
            x++;
        }
    }
}


/* x^(8 n) modulo the polynomial: appending n bytes shifts a CRC by that. */
static uint32_t x_to_8n(size_t n)
{
    uint32_t result = (uint32_t)1 << 31, power = (uint32_t)1 << 30; /* x^0, x^1 */
    unsigned long long e = 8ull * n;
    while (e) {
        if (e & 1u) result = adaslice_crc32_mul(power, result);
        power = adaslice_crc32_mul(power, power);
        e >>= 1;
    }
    return result;
}

/* crc after `times` more copies of a row whose own CRC is `row`: the map
   c -> c shift + row (shift: x^(8 n) for rows of n bytes) applied `times`
   times, by squaring (f twice is c -> c shift^2 + row shift + row), so a
   layer's thousand dark rows cost a few dozen multiplications. */
static uint32_t append_repeats(uint32_t crc, uint32_t row, uint32_t shift, size_t times)
{
    for (; times; times >>= 1) {
        if (times & 1) crc = adaslice_crc32_mul(shift, crc) ^ row;
        row = adaslice_crc32_mul(shift, row) ^ row;
        shift = adaslice_crc32_mul(shift, shift);
    }
    return crc;
}

/* Tables to run the CRC register over a run of n equal bytes at once, as a
   register of bits (not inverted, bit 31 is x^0): n bytes of v take r to
   (r + F_v) x^(8 n) + F_v, F_v being the register that a byte v leaves as
   it is (F_v = T(v) / (x^8 + 1), T the byte table; the polynomial is
   irreducible, so x^8 + 1 has an inverse). The product by x^(8 n) goes a
   set bit k of n at a time, four byte tables of x^(8 2^k) each, so a run
   costs a few lookups a bit of its length instead of its bytes. */
typedef struct crc_runs {
    int powers;                  /* tables of x^(8 2^k), k < powers */
    uint32_t fixed[256];         /* F_v */
    uint32_t (*times)[4][256];   /* times[k][j][b]: byte j of r being b, times x^(8 2^k) */
} crc_runs;

/* t[b] = t[b - lowest bit] + t[lowest bit], from the eight single bits */
static void linear_table(uint32_t t[256])
{
    unsigned b;
    t[0] = 0;
    for (b = 3; b < 256; b++)
        if (b & (b - 1)) t[b] = t[b & (b - 1)] ^ t[b & (0u - b)];
}

static int crc_runs_init(crc_runs *c, size_t longest)
{
    uint32_t inverse = (uint32_t)1 << 31, a = 0x80800000u, power = (uint32_t)1 << 23; /* 1, x^8 + 1, x^8 */
    unsigned long long e = 0xFFFFFFFEull; /* a^(2^32 - 2) is a's inverse in the field of 2^32 elements */
    int k, j, i;
    for (c->powers = 1; c->powers < 64 && longest >> c->powers; c->powers++) {}
    if (!(c->times = (uint32_t(*)[4][256])malloc((size_t)c->powers * sizeof *c->times))) return -1;
    for (; e; e >>= 1, a = adaslice_crc32_mul(a, a))
        if (e & 1u) inverse = adaslice_crc32_mul(a, inverse);
    for (i = 0; i < 8; i++) {
        uint32_t t = (uint32_t)1 << i;
        for (k = 0; k < 8; k++) t = t & 1u ? (t >> 1) ^ 0xedb88320u : t >> 1; /* T(2^i) */
        c->fixed[1u << i] = adaslice_crc32_mul(t, inverse);
    }
    linear_table(c->fixed);
    for (k = 0; k < c->powers; k++, power = adaslice_crc32_mul(power, power))
        for (j = 0; j < 4; j++) {
            for (i = 0; i < 8; i++) c->times[k][j][1u << i] = adaslice_crc32_mul((uint32_t)1 << (8 * j + i), power);
            linear_table(c->times[k][j]);
        }
    return 0;
}

/* The register after a row of n bytes, run by run. */
static uint32_t crc_runs_row(const crc_runs *c, uint32_t r, const unsigned char *row, size_t n)
{
    size_t x = 0;
    while (x < n) {
        size_t end = same_bytes_end(row, x, n), left = end - x;
        uint32_t f = c->fixed[row[x]];
        int k;
        r ^= f;
        for (k = 0; left; k++, left >>= 1)
            if (left & 1u) {
                uint32_t(*t)[256] = c->times[k];
                r = t[0][r & 0xFFu] ^ t[1][r >> 8 & 0xFFu] ^ t[2][r >> 16 & 0xFFu] ^ t[3][r >> 24];
            }
        r ^= f;
        x = end;
    }
    return r;
}

/* Each row's CRC goes by its runs of equal bytes (a layer's rows are long
   runs of dark and lit with a few edge bytes), and a long run of rows that
   repeat the row above (the dark around the part) is added by combination
   instead. Out of memory for the tables, the bytes go through
   adaslice_crc32. */
uint32_t mask_crc32(const unsigned char *image, size_t stride, size_t row_bytes, int height)
{
    const size_t long_run = row_bytes ? 8192 / row_bytes + 1 : 1; /* shorter runs are cheaper row by row */
    uint32_t crc = 0, shift = x_to_8n(row_bytes);
    crc_runs c;
    int y = 0;
    if (crc_runs_init(&c, row_bytes)) {
        for (; y < height; y++) crc = adaslice_crc32(crc, image + (size_t)y * stride, row_bytes);
        return crc;
    }
    while (y < height) {
        const unsigned char *above = y > 0 ? image + (size_t)(y - 1) * stride : image;
        size_t k = 0;
        if (y > 0)
            while (y + (int)k < height && !memcmp(image + (size_t)(y + (int)k) * stride, above, row_bytes)) k++;
        if (k >= long_run) {
            crc = append_repeats(crc, ~crc_runs_row(&c, 0xFFFFFFFFu, above, row_bytes), shift, k);
            y += (int)k;
            continue;
        }
        for (k += !k; k--; y++) crc = ~crc_runs_row(&c, ~crc, image + (size_t)y * stride, row_bytes);
    }
    free(c.times);
    return crc;
}
