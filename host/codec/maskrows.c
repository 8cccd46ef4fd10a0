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
   runs NULL, found here in row: each run of whole bytes at once; `last` is
   a 1-bit row's last byte. */
static void pixel_runs(const unsigned char *row, const uint32_t *runs, unsigned last, int bits, int width,
                       mask_run_fn run, void *ctx)
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
    for (x *= 8; bits == 1 && x < (size_t)width; x++) run(ctx, (last >> (7 - (x & 7)) & 1) ? 255 : 0, 1);
}

void mask_row_runs(const unsigned char *row, int bits, int width, mask_run_fn run, void *ctx)
{
    pixel_runs(row, NULL, bits == 1 && width % 8 ? row[width / 8] : 0, bits, width, run, ctx);
}

/* ---- one reading of a layer's rows -------------------------------------- */

/* Room for one more step and `runs` more runs. */
static int band_room(mask_band *b, size_t runs)
{
    if (b->step_count == b->step_cap) {
        size_t cap = b->step_cap ? 2 * b->step_cap : 64;
        mask_band_step *p = (mask_band_step *)realloc(b->steps, cap * sizeof *p);
        if (!p) return -1;
        b->steps = p;
        b->step_cap = cap;
    }
    if (b->run_cap - b->run_count < runs) {
        size_t cap = b->run_cap ? 2 * b->run_cap : 1024;
        uint32_t *p;
        while (cap - b->run_count < runs) cap *= 2;
        if (!(p = (uint32_t *)realloc(b->runs, cap * sizeof *p))) return -1;
        b->runs = p;
        b->run_cap = cap;
    }
    return 0;
}

/* n bytes of v after the row's runs so far (from runs[first]), joining the
   last when it is of v: runs go as long as they go. */
static void band_put(mask_band *b, size_t first, unsigned v, size_t n)
{
    if (!n) return;
    if (b->run_count > first && b->runs[b->run_count - 1] >> 24 == v) b->runs[b->run_count - 1] += (uint32_t)n;
    else b->runs[b->run_count++] = (uint32_t)v << 24 | (uint32_t)n;
}

/* A row that differs from the one above (the edges of a part) is read twice:
   by memcmp, which brings it into the cache, and for its runs there. */
int mask_band_scan(mask_band *b, const unsigned char *rows, ptrdiff_t step, int first, int count, size_t row_bytes,
                   size_t lo, size_t hi)
{
    int i;
    b->first = first;
    b->count = count;
    b->step_count = b->run_count = 0;
    for (i = 0; i < count; i++) {
        const unsigned char *row = rows + (ptrdiff_t)i * step;
        mask_band_step *st = b->step_count ? &b->steps[b->step_count - 1] : NULL;
        size_t x = lo, start;
        if (i > 0 && !memcmp(row + lo, row - step + lo, hi - lo)) {
            if (st->repeat) st->rows++;
            else {
                if (band_room(b, 0)) return -1;
                st = &b->steps[b->step_count++];
                st->rows = st->repeat = 1;
                st->run = st->count = 0;
            }
            continue;
        }
        if (band_room(b, hi - lo + 2)) return -1;
        st = &b->steps[b->step_count++];
        st->rows = 1;
        st->repeat = 0;
        st->run = start = b->run_count;
        band_put(b, start, 0, lo);
        while (x < hi) {
            size_t end = same_bytes_end(row, x, hi);
            band_put(b, start, row[x], end - x);
            x = end;
        }
        band_put(b, start, 0, row_bytes - hi);
        st->count = b->run_count - start;
    }
    return 0;
}

void mask_band_free(mask_band *b)
{
    free(b->steps);
    free(b->runs);
    memset(b, 0, sizeof *b);
}

void mask_scan_bands(mask_scan *s, const mask_band *bands, int count, int width, int bits, int height)
{
    s->width = width;
    s->bits = bits;
    s->height = height;
    s->row_bytes = bits == 8 ? (size_t)width : ((size_t)width + 7) / 8;
    s->whole = bits == 8 ? s->row_bytes : (size_t)width / 8;
    s->tail = bits == 1 && width % 8 ? (0xFFu << (8 - width % 8)) & 0xFF : 0;
    s->bands = bands;
    s->band_count = count;
    s->in = NULL;
    s->until = 0;
    s->dark = (uint32_t)s->row_bytes;
    s->y = s->rows = 0;
    s->runs = NULL;
    s->count = 0;
}

int mask_scan_image(mask_scan *s, const unsigned char *image, size_t stride, int width, int bits, int height,
                    const int lit[2])
{
    int lo = lit ? (lit[0] < 0 ? 0 : lit[0] > height ? height : lit[0]) : 0;
    int hi = lit ? (lit[1] < lo ? lo : lit[1] > height ? height : lit[1]) : height;
    mask_scan_bands(s, &s->own, 1, width, bits, height);
    return mask_band_scan(&s->own, image + (size_t)lo * stride, (ptrdiff_t)stride, lo, hi - lo, s->row_bytes, 0,
                          s->row_bytes);
}

/* Steps row y on into: the band that holds it, else the dark rows up to
   the next band. */
static void enter(mask_scan *s, int y)
{
    int i;
    s->in = NULL;
    s->until = s->height;
    s->next = 0;
    for (i = 0; i < s->band_count; i++) {
        const mask_band *b = &s->bands[i];
        if (b->count <= 0) continue;
        if (b->first <= y && y < b->first + b->count) {
            s->in = b;
            s->until = b->first + b->count;
            return;
        }
        if (b->first > y && b->first < s->until) s->until = b->first;
    }
}

/* Whether two rows, as their runs, hold the same bytes before `upto`
   (less than the rows' length). */
static int runs_agree(const uint32_t *a, const uint32_t *b, size_t upto)
{
    size_t x = 0, end_a = *a & 0xFFFFFF, end_b = *b & 0xFFFFFF;
    while (x < upto) {
        if (*a >> 24 != *b >> 24) return 0;
        x = end_a < end_b ? end_a : end_b;
        if (x >= upto) break;
        if (x == end_a) end_a += *++a & 0xFFFFFF;
        if (x == end_b) end_b += *++b & 0xFFFFFF;
    }
    return 1;
}

/* Where a band or the dark rows begin, the row is checked against the row
   above (the end of another band), by their runs: runs that go as long as
   they go are the same runs for the same bytes. */
int mask_scan_next(mask_scan *s)
{
    const int y = s->y + s->rows;
    const uint32_t *runs;
    size_t count;
    int begins = y >= s->until;
    if (y >= s->height) return 0;
    if (begins) enter(s, y);
    s->y = y;
    s->rows = 1;
    s->repeat = s->same_pixels = 0;
    if (s->in) {
        const mask_band_step *st = &s->in->steps[s->next++];
        if (st->repeat) {
            s->repeat = 1;
            s->rows = st->rows;
            return 1;
        }
        runs = s->in->runs + st->run;
        count = st->count;
    } else if (!begins) { /* the rest of the dark rows, the first of them done */
        s->repeat = 1;
        s->rows = s->until - y;
        return 1;
    } else {
        runs = &s->dark;
        count = 1;
    }
    if (begins && y > 0 && count == s->count && !memcmp(runs, s->runs, count * sizeof *runs)) {
        s->repeat = 1;
        s->rows = s->in ? 1 : s->until - y;
        return 1;
    }
    s->same_pixels = y > 0 && s->tail && runs_agree(runs, s->runs, s->whole) &&
                     !(((runs[count - 1] ^ s->runs[s->count - 1]) >> 24) & s->tail);
    s->runs = runs;
    s->count = count;
    return 1;
}

void mask_scan_runs(const mask_scan *s, int pixels, mask_run_fn run, void *ctx)
{
    const unsigned last = s->runs[s->count - 1] >> 24;
    if (pixels) {
        pixel_runs(NULL, s->runs, last, s->bits, s->width, run, ctx);
        return;
    }
    pixel_runs(NULL, s->runs, last, 8, (int)s->whole, run, ctx);
    if (s->whole < s->row_bytes) run(ctx, last & s->tail, 1);
}

void mask_scan_free(mask_scan *s)
{
    mask_band_free(&s->own);
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
    if (row_bytes >= (size_t)1 << RUN_BITS || mask_scan_image(&s, image, stride, (int)row_bytes, 8, height, NULL)) {
        for (y = 0; y < height; y++) crc = adaslice_crc32(crc, image + (size_t)y * stride, row_bytes);
        mask_scan_free(&s);
        return crc;
    }
    mask_crc_begin(&c, row_bytes);
    while (mask_scan_next(&s)) mask_crc_step(&c, &s);
    mask_scan_free(&s);
    return c.crc;
}
