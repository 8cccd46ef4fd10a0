/* PNG encoder for layer masks and previews, written from the PNG
   specification and RFC 1950 (zlib). Masks go to deflate.c's deflater as the
   runs of their rows, in time proportional to the runs; other images through
   its matcher, told that the same byte one row up is a row length + 1 back. */
#include "png.h"
#include "../bytes.h"
#include "deflate.h"
#include "maskrows.h"
#include "../../adaslice.h"
#include <pthread.h>
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

/* Rows of filter byte + data, for 8-bit grey and RGB images (1-bit masks go
   by their runs, below). The matcher codes runs and bytes repeated from one
   row up, so a row costs little under None where its words are flat (all
   bytes equal) or equal to the words above; Up only pays on rows whose Up
   difference has more flat words than that (gradients, say). */
static void filter_rows(const unsigned char *pixels, int height, size_t stride, size_t rowbytes, unsigned char *out)
{
    const uint64_t high = 0x8080808080808080u, ones = 0x0101010101010101u;
    for (int y = 0; y < height; y++, out += rowbytes + 1) {
        const unsigned char *cur = pixels + (size_t)y * stride, *prev = cur - (y ? stride : 0);
        size_t flat_none = 0, flat_up = 0;
        for (size_t x = 0; y > 0 && x + 8 <= rowbytes; x += 8) { /* the first row gets None */
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
            for (size_t x = 0; x < rowbytes; x++) out[1 + x] = (unsigned char)(cur[x] - prev[x]);
        } else {
            out[0] = 0;
            memcpy(out + 1, cur, rowbytes);
        }
    }
}

/* The PNG file around one IDAT of zlib data: deflate stream z and the
   Adler-32 of the filtered rows it holds. */
static int wrap(int width, int height, int bits, int colour, const unsigned char *z, size_t zsize, uint32_t adler,
                unsigned char **out, size_t *out_size)
{
    static const unsigned char signature[8] = {137, 80, 78, 71, 13, 10, 26, 10};
    const size_t head = 8 + 25 + 8, size = head + 2 + zsize + 4 + 4 + 12;
    unsigned char *o;
    if (zsize > 0x7F000000u || !(o = (unsigned char *)malloc(size))) return -1;
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
    put_be32(o + head + 2 + zsize, adler);
    put_be32(o + head + 2 + zsize + 4, adaslice_crc32(0, o + 37, 4 + 2 + zsize + 4));
    put_be32(o + size - 12, 0);
    memcpy(o + size - 8, "IEND", 4);
    put_be32(o + size - 4, adaslice_crc32(0, "IEND", 4));
    *out = o;
    *out_size = size;
    return 0;
}

/* One IDAT holding the filtered rows of rowbytes each; colour is the IHDR
   colour type. */
static int encode(const unsigned char *pixels, int width, int height, size_t stride, size_t rowbytes, int colour,
                  unsigned char **out, size_t *out_size)
{
    /* Up to 2 GB of row data keeps the one IDAT chunk under its 2^31 limit. */
    const size_t max_data = 0x7F000000u;
    unsigned char *filtered, *z = NULL;
    size_t n, zsize = 0;
    int rc;

    *out = NULL;
    *out_size = 0;
    if (width < 1 || height < 1 || !pixels || stride < rowbytes || rowbytes + 1 > max_data / (size_t)height)
        return -1;
    n = (rowbytes + 1) * (size_t)height;
    if (!(filtered = (unsigned char *)malloc(n))) return -1;
    filter_rows(pixels, height, stride, rowbytes, filtered);
    rc = deflate_bytes(filtered, n, rowbytes + 1, &z, &zsize) ? -1
         : wrap(width, height, 8, colour, z, zsize, png_adler32(1, filtered, n), out, out_size);
    free(filtered);
    free(z);
    return rc;
}

/* ---- masks from their runs ---------------------------------------------- */

/* The filtered stream (a 0 filter byte, then the row's bytes) goes to the
   deflater as runs of one byte (a literal, then copies from one byte back)
   and as copies from one row back, which the rows that repeat or change
   little take: the same part lit a row up, its edges moved. The Adler-32
   follows the runs in closed form, so the cost is in the runs, not the
   pixels. */
typedef struct mask_encoder {
    deflater *d;
    int depth;                   /* of the file's pixels: 1, or 8 (1-bit ones as 0 or 255) */
    size_t row_bytes, line;      /* a row; with its filter byte: a row copy's distance */
    uint64_t s1, s2, r1, r2;     /* the Adler-32's sums; r: the last row's own, from zero */
    uint64_t repeats;            /* rows that repeat the row above, not yet coded */
    int failed, have_last;
    unsigned last;               /* the byte before the pending run or copy */
    unsigned run_v;              /* the pending run: run_n bytes of run_v */
    uint64_t run_n;
    uint64_t copy_n;             /* or the pending copy of copy_n bytes from a row back */
    uint32_t *runs, *above;      /* the runs of the row and of the row above, grey << 24 | length */
    size_t run_count, above_count, run_cap, above_cap;
} mask_encoder;

static void emit_pending(mask_encoder *e)
{
    uint64_t n = e->run_n;
    if (e->copy_n) e->failed |= deflate_copy(e->d, (size_t)e->copy_n, e->line) != 0;
    e->copy_n = 0;
    if (!n) return;
    if (!e->have_last || e->last != e->run_v) {
        e->failed |= deflate_literal(e->d, (unsigned char)e->run_v) != 0;
        n--;
    }
    if (n >= 3) e->failed |= deflate_copy(e->d, (size_t)n, 1) != 0;
    else while (n--) e->failed |= deflate_literal(e->d, (unsigned char)e->run_v) != 0;
    e->last = e->run_v;
    e->have_last = 1;
    e->run_n = 0;
}

static void push_run(mask_encoder *e, unsigned v, uint64_t n)
{
    if (e->copy_n || (e->run_n && e->run_v != v)) emit_pending(e);
    e->run_v = v;
    e->run_n += n;
}

/* n >= 3 bytes from a row back, the last of them `last`: joins a copy just before */
static void push_copy(mask_encoder *e, uint64_t n, unsigned last)
{
    if (e->run_n) emit_pending(e);
    e->copy_n += n;
    e->last = last;
    e->have_last = 1;
}

static void keep_run(void *ctx, unsigned grey, uint64_t n)
{
    mask_encoder *e = (mask_encoder *)ctx;
    if (e->run_count && e->runs[e->run_count - 1] >> 24 == grey) { /* n and a row are under 2^24 */
        e->runs[e->run_count - 1] += (uint32_t)n;
        return;
    }
    if (e->run_count == e->run_cap) {
        size_t cap = e->run_cap ? 2 * e->run_cap : 256;
        uint32_t *r = (uint32_t *)realloc(e->runs, cap * sizeof *r);
        if (!r) { e->failed = 1; return; }
        e->runs = r;
        e->run_cap = cap;
    }
    e->runs[e->run_count++] = grey << 24 | (uint32_t)n;
}

/* Whether a part of a row, `bytes` long over `runs` of its runs, costs less
   as a copy from a row back than as runs, by what deflate's codes take on
   masks: about 15 bits a run (a literal and a length; the first joins the
   run before) against 18 a copied piece of up to 258 bytes (a length and a
   far distance), a piece fewer where it joins a pending copy. */
static int copy_pays(const mask_encoder *e, size_t bytes, size_t runs)
{
    uint64_t pieces = (e->copy_n + bytes + 257) / 258 - (e->copy_n + 257) / 258; /* joining a pending copy */
    return bytes >= 3 && 18 * pieces + 15 < 15 * (uint64_t)runs;
}

/* The row's runs over [from, to) into the stream (emit 0: passed over);
   *r and *x are the run that holds `from` and where that run starts. */
static void push_runs(mask_encoder *e, size_t from, size_t to, size_t *r, size_t *x, int emit)
{
    while (from < to) {
        size_t end = *x + (e->runs[*r] & 0xFFFFFF), upto = end < to ? end : to;
        if (emit) push_run(e, e->runs[*r] >> 24, upto - from);
        from = upto;
        if (upto == end) *x = end, ++*r;
    }
}

/* A part [from, to) of the row that is (same) or is not the row above's
   there, spanning `runs` of the row's runs and ending in a byte `last`. */
static void push_part(mask_encoder *e, size_t from, size_t to, int same, size_t runs, unsigned last, size_t *r,
                      size_t *x)
{
    int copy = same && e->line <= 32768 && copy_pays(e, to - from + !from, runs + !from); /* the filter byte with the first */
    if (copy) push_copy(e, to - from + !from, last);
    else if (!from) push_run(e, 0, 1); /* filter None */
    push_runs(e, from, to, r, x, !copy);
}

/* A row into the stream: walking its runs beside the row above's, the parts
   where the two agree go as copies from a row back where that costs less
   than their runs (all of the row when it repeats the one above; the part
   lit a row up, its edges moved, when it differs), the rest as runs. */
static void push_row(mask_encoder *e, size_t row_bytes, int repeats)
{
    const uint32_t *above = repeats ? e->runs : e->above;
    size_t i = 0, j = 0, in_i = 0, in_j = 0, x = 0, from = 0, runs = 0, r = 0, rx = 0;
    int same = -1;
    unsigned last = 0;
    if (!(repeats ? e->run_count : e->above_count)) { /* the first row */
        push_part(e, 0, row_bytes, 0, e->run_count, 0, &r, &rx);
        return;
    }
    while (x < row_bytes) { /* i, j: the runs of the row and the row above at x, in_i and in_j bytes into them */
        uint32_t a = e->runs[i], b = above[j];
        size_t left_a = (a & 0xFFFFFF) - in_i, left_b = (b & 0xFFFFFF) - in_j, step = left_a < left_b ? left_a : left_b;
        int agree = a >> 24 == b >> 24;
        if (agree != same && x > 0) {
            push_part(e, from, x, same, runs, last, &r, &rx);
            from = x;
            runs = 0;
        }
        same = agree;
        runs += in_i == 0 || x == from;
        last = a >> 24;
        x += step;
        if ((in_i += step) == (a & 0xFFFFFF)) i++, in_i = 0;
        if ((in_j += step) == (b & 0xFFFFFF)) j++, in_j = 0;
    }
    push_part(e, from, row_bytes, same, runs, last, &r, &rx);
}

/* k rows that repeat the row above, at once: one copy from a row back where
   push_row would copy each of them, one run where the row is dark (its
   filter byte is 0 too), else row by row. */
static void push_repeats(mask_encoder *e, size_t row_bytes, uint64_t k)
{
    if (e->line <= 32768 && copy_pays(e, e->line, e->run_count + 1))
        push_copy(e, k * e->line, e->runs[e->run_count - 1] >> 24);
    else if (e->run_count == 1 && !(e->runs[0] >> 24)) push_run(e, 0, k * e->line);
    else while (k--) push_row(e, row_bytes, 1);
}

/* What a layer's coding keeps for the next: the runs of the scan and the
   encoder, masks.rle's code, the deflater's 256 KB of symbols and its
   stream. Freed and taken again layer after layer, off the main thread
   glibc gave such memory back to the system and the next layer faulted it
   in again (two threads took 94,000 page faults on the turbine blade's
   directory job against 12,000 on one, and a third more CPU), so each
   coder goes back to a pool for the next layer, on whichever thread: there
   are as many as layers are coded at once. */
typedef struct coder {
    struct coder *next;
    mask_scan scan;
    mask_encoder png;
    mask_rle rle;
} coder;

static pthread_mutex_t pool_lock = PTHREAD_MUTEX_INITIALIZER;
static coder *pool;

static coder *take_coder(void)
{
    coder *c;
    pthread_mutex_lock(&pool_lock);
    if ((c = pool) != NULL) pool = c->next;
    pthread_mutex_unlock(&pool_lock);
    if (!c && (c = (coder *)calloc(1, sizeof *c)) != NULL && !(c->png.d = deflate_begin())) {
        free(c);
        c = NULL;
    }
    return c;
}

static void give_coder(coder *c)
{
    pthread_mutex_lock(&pool_lock);
    c->next = pool;
    pool = c;
    pthread_mutex_unlock(&pool_lock);
}

/* The file's rows at `depth` bits from an image's at `bits`: 8 from 1 makes
   1-bit pixels 0 or 255; 1 from 1 takes the packed bytes as they are, a
   row's padding bits cleared. */
static void png_begin(mask_encoder *e, int width, int depth)
{
    deflater *d = e->d;
    uint32_t *runs = e->runs, *above = e->above;
    size_t run_cap = e->run_cap, above_cap = e->above_cap;
    memset(e, 0, sizeof *e);
    deflate_reset(d);
    e->d = d;
    e->runs = runs, e->run_cap = run_cap;
    e->above = above, e->above_cap = above_cap;
    e->depth = depth;
    e->row_bytes = depth == 8 ? (size_t)width : ((size_t)width + 7) / 8;
    e->line = e->row_bytes + 1;
    e->s1 = 1;
}

/* Rows that repeat the row above go at once on that row's runs and sums
   (each adds line bytes and the row's sums: s2 += line s1 + r2, s1 += r1,
   k times). */
static void png_repeats(mask_encoder *e)
{
    const uint64_t M = 65521, k = e->repeats, line = e->line % M;
    if (!k) return;
    e->s2 = (e->s2 + k % M * line % M * e->s1 + (k * (k - 1) / 2) % M * line % M * e->r1 + k % M * e->r2) % M;
    e->s1 = (e->s1 + k % M * e->r1) % M;
    push_repeats(e, e->row_bytes, k);
    e->repeats = 0;
}

/* A step of the scan: rows that repeat the row above in the file's pixels
   wait to go at once; a row that differs goes by its runs. */
static void png_step(mask_encoder *e, const mask_scan *s)
{
    const uint64_t M = 65521;
    uint32_t *swap = e->above;
    size_t swap_cap = e->above_cap, r;
    if (s->repeat || s->same_pixels) {
        e->repeats += (uint64_t)s->rows;
        return;
    }
    png_repeats(e);
    e->above = e->runs, e->above_cap = e->run_cap, e->above_count = e->run_count;
    e->runs = swap, e->run_cap = swap_cap, e->run_count = 0;
    mask_scan_runs(s, e->depth == 8, keep_run, e);
    for (e->r1 = e->r2 = 0, r = 0; r < e->run_count; r++) {
        uint64_t v = e->runs[r] >> 24, n = e->runs[r] & 0xFFFFFF;
        e->r2 = (e->r2 + n * e->r1 + v * (n * (n + 1) / 2 % M)) % M;
        e->r1 = (e->r1 + n * v) % M;
    }
    e->s2 = (e->s2 + e->line % M * e->s1 + e->r2) % M;
    e->s1 = (e->s1 + e->r1) % M;
    if (!e->failed) push_row(e, e->row_bytes, 0);
}

static int png_end(mask_encoder *e, int width, int height, unsigned char **out, size_t *out_size)
{
    const unsigned char *z;
    size_t zsize;
    png_repeats(e);
    emit_pending(e);
    if (e->failed || deflate_finish(e->d, &z, &zsize)) return -1;
    return wrap(width, height, e->depth, 0, z, zsize, (uint32_t)(e->s2 << 16 | e->s1), out, out_size);
}

/* Whether a mask of width x height at bits can go to a PNG at depth and,
   for a layer, to masks.rle: rows under 2^24 bytes, and a layer's sizes
   under 2^24 pixels. */
static int codable(int width, int height, int bits, int depth, int layer)
{
    const size_t row_bytes = depth == 8 ? (size_t)width : ((size_t)width + 7) / 8;
    return (bits == 1 || bits == 8) && width >= 1 && height >= 1 && row_bytes < 1 << 24 &&
           row_bytes + 1 <= 0x7F000000u / (size_t)height && (!layer || (width < 1 << 24 && height < 1 << 24));
}

/* A mask's PNG at `depth` from the scan begun on c->scan and, if layer,
   masks.rle's code and the CRC from the same steps of it. Gives c back. */
static int encode_scan(coder *c, int width, int height, int bits, int depth, unsigned char **out, size_t *out_size,
                       png_layer *layer)
{
    mask_crc crc;
    int rc;
    png_begin(&c->png, width, depth);
    if (layer) {
        mask_rle_begin(&c->rle, width, bits);
        mask_crc_begin(&crc, c->scan.row_bytes);
    }
    while (!c->png.failed && mask_scan_next(&c->scan)) {
        png_step(&c->png, &c->scan);
        if (layer) {
            mask_rle_step(&c->rle, &c->scan);
            mask_crc_step(&crc, &c->scan);
        }
    }
    if ((rc = png_end(&c->png, width, height, out, out_size)) || !layer) goto done;
    rc = -1;
    if (!mask_rle_end(&c->rle) && (layer->rle = (unsigned char *)malloc(c->rle.code.size ? c->rle.code.size : 1)) != NULL) {
        memcpy(layer->rle, c->rle.code.data, c->rle.code.size);
        layer->rle_size = c->rle.code.size;
        layer->crc = crc.crc;
        rc = 0;
    }
    if (rc) {
        free(*out);
        *out = NULL;
        *out_size = 0;
    }
done:
    give_coder(c);
    return rc;
}

/* The same from an image, its rows read here (only the lit ones if lit). */
static int encode_runs(const unsigned char *image, int width, int height, size_t stride, int bits, int depth,
                       const int *lit, unsigned char **out, size_t *out_size, png_layer *layer)
{
    coder *c;
    *out = NULL;
    *out_size = 0;
    if (!codable(width, height, bits, depth, layer != NULL) || !image ||
        stride < (bits == 8 ? (size_t)width : ((size_t)width + 7) / 8) || !(c = take_coder()))
        return -1;
    if (mask_scan_image(&c->scan, image, stride, width, bits, height, lit)) {
        give_coder(c);
        return -1;
    }
    return encode_scan(c, width, height, bits, depth, out, out_size, layer);
}

int png_encode_layer(const unsigned char *image, int width, int height, size_t stride, int bits, const int lit_rows[2],
                     png_layer *layer)
{
    memset(layer, 0, sizeof *layer);
    return encode_runs(image, width, height, stride, bits, bits, lit_rows, &layer->png, &layer->png_size, layer);
}

int png_encode_bands(const mask_band *bands, int count, int width, int height, int bits, png_layer *layer)
{
    coder *c;
    memset(layer, 0, sizeof *layer);
    if (!codable(width, height, bits, bits, 1) || !(c = take_coder())) return -1;
    mask_scan_bands(&c->scan, bands, count, width, bits, height);
    return encode_scan(c, width, height, bits, bits, &layer->png, &layer->png_size, layer);
}

int png_encode_mask(const unsigned char *image, int width, int height, size_t stride, int bits, unsigned char **out,
                    size_t *out_size)
{
    return encode_runs(image, width, height, stride, bits, 8, NULL, out, out_size, NULL);
}

int png_encode_gray(const unsigned char *pixels, int width, int height, size_t stride, int bits,
                    unsigned char **out, size_t *out_size)
{
    if (bits == 1) return encode_runs(pixels, width, height, stride, 1, 1, NULL, out, out_size, NULL);
    if (bits != 8) {
        *out = NULL;
        *out_size = 0;
        return -1;
    }
    return encode(pixels, width, height, stride, (size_t)width, 0, out, out_size);
}

int png_encode_rgb(const unsigned char *rgb, int width, int height, unsigned char **out, size_t *out_size)
{
    return encode(rgb, width, height, 3 * (size_t)width, 3 * (size_t)width, 2, out, out_size);
}
