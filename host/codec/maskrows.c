/* Rows of layer masks: see maskrows.h. */
#include "maskrows.h"
#include "../../adaslice_mcu.h"
#include <pthread.h>
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

/* n bytes of v of a 1-bit row as runs of pixels: whole dark or lit bytes
   at once, the others (a layer's edges) a pixel at a time. */
static void byte_pixels(unsigned v, size_t n, mask_run_fn run, void *ctx)
{
    int i;
    if (v == 0 || v == 0xFF) {
        run(ctx, v, 8 * (uint64_t)n);
        return;
    }
    while (n--)
        for (i = 7; i >= 0; i--) run(ctx, (v >> i & 1) ? 255 : 0, 1);
}

/* A row's runs of pixels, from its runs of bytes (runs, as mask_scan's) or,
   runs NULL, found here: each run of whole bytes at once. */
static void pixel_runs(const unsigned char *row, const uint32_t *runs, int bits, int width, mask_run_fn run, void *ctx)
{
    const size_t whole = bits == 8 ? (size_t)width : (size_t)width >> 3;
    size_t x = 0, n;
    while (x < whole) {
        unsigned v = runs ? *runs >> 24 : row[x];
        n = runs ? *runs++ & 0xFFFFFF : same_bytes_end(row, x, whole) - x;
        if (n > whole - x) n = whole - x; /* a run on into a 1-bit row's last byte */
        if (bits == 8) run(ctx, v, n);
        else byte_pixels(v, n, run, ctx);
        x += n;
    }
    for (x *= 8; bits == 1 && x < (size_t)width; x++) run(ctx, (row[x >> 3] >> (7 - (x & 7)) & 1) ? 255 : 0, 1);
}

void mask_row_runs(const unsigned char *row, int bits, int width, mask_run_fn run, void *ctx)
{
    pixel_runs(row, NULL, bits, width, run, ctx);
}

/* ---- one reading of a layer's rows -------------------------------------- */

int mask_scan_begin(mask_scan *s, const unsigned char *image, size_t stride, int width, int bits, int height)
{
    const size_t n = bits == 8 ? (size_t)width : ((size_t)width + 7) / 8;
    if (n > s->cap) { /* a row has at most n runs */
        uint32_t *a = (uint32_t *)realloc(s->runs, n * sizeof *a), *b;
        unsigned char *z;
        if (a) s->runs = a;
        if (!a || !(b = (uint32_t *)realloc(s->spare, n * sizeof *b))) return -1;
        s->spare = b;
        if (!(z = (unsigned char *)realloc(s->dark, n))) return -1;
        memset(z, 0, n);
        s->dark = z;
        s->cap = n;
    }
    s->image = image;
    s->width = width;
    s->bits = bits;
    s->stride = stride;
    s->row_bytes = n;
    s->whole = bits == 8 ? n : (size_t)width / 8;
    s->tail = bits == 1 && width % 8 ? (0xFFu << (8 - width % 8)) & 0xFF : 0;
    s->height = height;
    s->lit[0] = 0;
    s->lit[1] = height;
    s->y = s->rows = 0;
    s->row = image;
    s->count = 0;
    return 0;
}

/* Row r of the image, or a dark row in place of one outside the lit rows. */
static const unsigned char *scan_row(const mask_scan *s, int r)
{
    return r < s->lit[0] || r >= s->lit[1] ? s->dark : s->image + (size_t)r * s->stride;
}

/* A row that differs from the one above (the edges of a part) is read twice:
   by memcmp, which brings it into the cache, and for its runs there. */
int mask_scan_next(mask_scan *s)
{
    const int y = s->y + s->rows;
    const unsigned char *row, *above;
    uint32_t *runs = s->spare;
    int k = 0;
    size_t x = 0, n = 0;
    if (y >= s->height) return 0;
    s->y = y;
    s->row = row = scan_row(s, y);
    if (y > 0)
        while (y + k < s->height) {
            const int r = y + k;
            if (r - 1 >= s->lit[1] || r < s->lit[0]) { /* it and the row above are dark */
                k = (r < s->lit[0] ? s->lit[0] : s->height) - y;
                continue;
            }
            if (memcmp(scan_row(s, r), scan_row(s, r - 1), s->row_bytes)) break;
            k++;
        }
    s->repeat = k > 0;
    s->rows = k ? k : 1;
    if (k) return 1;
    above = y > 0 ? scan_row(s, y - 1) : NULL;
    s->same_pixels = above && s->tail && !memcmp(row, above, s->whole) && !((row[s->whole] ^ above[s->whole]) & s->tail);
    while (x < s->row_bytes) {
        size_t end = same_bytes_end(row, x, s->row_bytes);
        runs[n++] = (uint32_t)row[x] << 24 | (uint32_t)(end - x);
        x = end;
    }
    s->spare = s->runs;
    s->runs = runs;
    s->count = n;
    return 1;
}

void mask_scan_runs(const mask_scan *s, int pixels, mask_run_fn run, void *ctx)
{
    if (pixels) {
        pixel_runs(s->row, s->runs, s->bits, s->width, run, ctx);
        return;
    }
    pixel_runs(s->row, s->runs, 8, (int)s->whole, run, ctx);
    if (s->whole < s->row_bytes) run(ctx, s->row[s->whole] & s->tail, 1);
}

void mask_scan_free(mask_scan *s)
{
    free(s->runs);
    free(s->spare);
    free(s->dark);
    memset(s, 0, sizeof *s);
}

/* ---- masks.rle's code --------------------------------------------------- */

void mask_rle_begin(mask_rle *r, int width, int bits)
{
    r->width = width;
    r->bits = bits;
    r->repeat = 0;
    r->code.size = 0;
    r->code.failed = 0;
    if (bits == 1 && r->lengths_cap < (size_t)width + 1) { /* a row has at most width + 1 runs, the first empty */
        uint32_t *p = (uint32_t *)realloc(r->lengths, ((size_t)width + 1) * sizeof *p);
        if (!p) r->code.failed = 1;
        else r->lengths = p, r->lengths_cap = (size_t)width + 1;
    }
}

/* 1-bit runs alternate dark and lit, dark first (of no pixels when the row
   starts lit). */
static void rle_length(void *ctx, unsigned grey, uint64_t n)
{
    mask_rle *r = (mask_rle *)ctx;
    if ((size_t)(grey != 0) == ((r->count - 1) & 1)) r->lengths[r->count - 1] += (uint32_t)n;
    else r->lengths[r->count++] = (uint32_t)n;
}

static void rle_repeats(mask_rle *r)
{
    unsigned char *p;
    if (!r->repeat || !(p = bytebuf_room(&r->code, 5))) return;
    r->code.size += adaslice_rle_put_repeat(p, r->repeat);
    r->repeat = 0;
}

/* A row that is the row above's in pixels goes into a repeat record, and so
   does a dark first row (the code starts as if after one); others as their
   runs: 1-bit ones from the runs of bytes, 8-bit ones are those. */
void mask_rle_step(mask_rle *r, const mask_scan *s)
{
    unsigned char *p;
    size_t runs, i, n;
    int dark;
    if (r->code.failed) return;
    if (s->repeat || s->same_pixels) {
        r->repeat += (uint32_t)s->rows;
        return;
    }
    if (r->bits == 1) {
        r->count = 1;
        r->lengths[0] = 0;
        mask_scan_runs(s, 1, rle_length, r);
        runs = r->count;
        dark = runs == 1;
    } else {
        runs = s->count;
        dark = runs == 1 && !(s->runs[0] >> 24);
    }
    if (s->y == 0 && dark) {
        r->repeat++;
        return;
    }
    rle_repeats(r);
    if (!(p = bytebuf_room(&r->code, 5 + 5 * runs))) return; /* lengths under 2^24: 4 bytes each at most */
    n = adaslice_rle_put_row(p, (uint32_t)runs);
    for (i = 0; i < runs; i++) {
        if (r->bits == 8) n += adaslice_rle_put_run(p + n, 8, s->runs[i] >> 24, s->runs[i] & 0xFFFFFF);
        else n += adaslice_rle_put_run(p + n, 1, (unsigned)(i & 1), r->lengths[i]);
    }
    r->code.size += n;
}

int mask_rle_end(mask_rle *r)
{
    rle_repeats(r);
    return r->code.failed ? -1 : 0;
}

void mask_rle_free(mask_rle *r)
{
    bytebuf_free(&r->code);
    free(r->lengths);
    memset(r, 0, sizeof *r);
}

/* ---- the CRC ------------------------------------------------------------ */

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
   costs a few lookups a bit of its length instead of its bytes. Made once,
   for every thread (a layer's coding made its own before, 50 KB of it). */
enum { RUN_BITS = 24 }; /* runs are shorter than 2^24 bytes */
static struct {
    uint32_t fixed[256];            /* F_v */
    uint32_t times[RUN_BITS][4][256]; /* times[k][j][b]: byte j of r being b, times x^(8 2^k) */
} crc_tables;
static pthread_once_t crc_tables_made = PTHREAD_ONCE_INIT;

/* t[b] = t[b - lowest bit] + t[lowest bit], from the eight single bits */
static void linear_table(uint32_t t[256])
{
    unsigned b;
    t[0] = 0;
    for (b = 3; b < 256; b++)
        if (b & (b - 1)) t[b] = t[b & (b - 1)] ^ t[b & (0u - b)];
}

static void make_crc_tables(void)
{
    uint32_t inverse = (uint32_t)1 << 31, a = 0x80800000u, power = (uint32_t)1 << 23; /* 1, x^8 + 1, x^8 */
    unsigned long long e = 0xFFFFFFFEull; /* a^(2^32 - 2) is a's inverse in the field of 2^32 elements */
    int k, j, i;
    for (; e; e >>= 1, a = adaslice_crc32_mul(a, a))
        if (e & 1u) inverse = adaslice_crc32_mul(a, inverse);
    for (i = 0; i < 8; i++) {
        uint32_t t = (uint32_t)1 << i;
        for (k = 0; k < 8; k++) t = t & 1u ? (t >> 1) ^ 0xedb88320u : t >> 1; /* T(2^i) */
        crc_tables.fixed[1u << i] = adaslice_crc32_mul(t, inverse);
    }
    linear_table(crc_tables.fixed);
    for (k = 0; k < RUN_BITS; k++, power = adaslice_crc32_mul(power, power))
        for (j = 0; j < 4; j++) {
            for (i = 0; i < 8; i++) crc_tables.times[k][j][1u << i] = adaslice_crc32_mul((uint32_t)1 << (8 * j + i), power);
            linear_table(crc_tables.times[k][j]);
        }
}

/* The register after a row, run by run. */
static uint32_t crc_runs_row(uint32_t r, const uint32_t *runs, size_t count)
{
    for (; count--; runs++) {
        uint32_t f = crc_tables.fixed[*runs >> 24], left = *runs & 0xFFFFFF;
        int k;
        r ^= f;
        for (k = 0; left; k++, left >>= 1)
            if (left & 1u) {
                uint32_t(*t)[256] = crc_tables.times[k];
                r = t[0][r & 0xFFu] ^ t[1][r >> 8 & 0xFFu] ^ t[2][r >> 16 & 0xFFu] ^ t[3][r >> 24];
            }
        r ^= f;
    }
    return r;
}

void mask_crc_begin(mask_crc *c, size_t row_bytes)
{
    pthread_once(&crc_tables_made, make_crc_tables);
    c->crc = 0;
    c->shift = x_to_8n(row_bytes);
    c->long_run = row_bytes ? 8192 / row_bytes + 1 : 1; /* shorter runs of rows are cheaper row by row */
}

/* Each row's CRC goes by its runs of equal bytes (a layer's rows are long
   runs of dark and lit with a few edge bytes), and a long run of rows that
   repeat the row above (the dark around the part) is added by combination
   instead. */
void mask_crc_step(mask_crc *c, const mask_scan *s)
{
    size_t k = (size_t)s->rows;
    if (s->repeat && k >= c->long_run) {
        c->crc = append_repeats(c->crc, ~crc_runs_row(0xFFFFFFFFu, s->runs, s->count), c->shift, k);
        return;
    }
    while (k--) c->crc = ~crc_runs_row(~c->crc, s->runs, s->count);
}

/* Rows of 2^24 bytes or more, or out of memory for a scan: through
   adaslice_crc32. */
uint32_t mask_crc32(const unsigned char *image, size_t stride, size_t row_bytes, int height)
{
    mask_scan s;
    mask_crc c;
    uint32_t crc = 0;
    int y;
    memset(&s, 0, sizeof s);
    if (row_bytes >= (size_t)1 << RUN_BITS || mask_scan_begin(&s, image, stride, (int)row_bytes, 8, height)) {
        for (y = 0; y < height; y++) crc = adaslice_crc32(crc, image + (size_t)y * stride, row_bytes);
        mask_scan_free(&s);
        return crc;
    }
    mask_crc_begin(&c, row_bytes);
    while (mask_scan_next(&s)) mask_crc_step(&c, &s);
    mask_scan_free(&s);
    return c.crc;
}
