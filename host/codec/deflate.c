/* Raw deflate, written from RFC 1951, for the PNG and ZIP writers.

   A mask is mostly black with a few smooth white regions: every row is a few
   runs, and most rows repeat the row above except where an edge moved. The
   matcher tries only what pays off on such data: a run of the previous byte
   (distance 1), the same bytes one row up (the caller's `row`, which in a PNG
   does what the Up filter would without breaking the runs), and where those
   fall short one candidate from a small hash of four bytes. Each block of
   symbols is then coded as the smallest of dynamic Huffman (code lengths
   limited to 15 bits by package-merge), fixed Huffman or stored. */
#include "deflate.h"
#include "../bytes.h"
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

enum { WINDOW = 32768, MAX_MATCH = 258, BLOCK_SYMBOLS = 1 << 16, HASH_BITS = 14,
       /* a match this long from a run or the row above is not worth a hash probe */
       GOOD_MATCH = 32 };

/* RFC 1951 3.2.5 and 3.2.7 */
static const unsigned short len_base[29] = {3, 4, 5, 6, 7, 8, 9, 10, 11, 13, 15, 17, 19, 23, 27, 31, 35, 43,
                                            51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
static const unsigned char len_extra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                            2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
static const unsigned short dist_base[30] = {1, 2, 3, 4, 5, 7, 9, 13, 17, 25, 33, 49, 65, 97, 129, 193,
                                             257, 385, 513, 769, 1025, 1537, 2049, 3073, 4097, 6145,
                                             8193, 12289, 16385, 24577};
static const unsigned char dist_extra[30] = {0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6,
                                             6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};
static const unsigned char cl_order[19] = {16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15};

typedef struct huffman {
    unsigned char len[288]; /* 286 and 287 only count in the fixed code */
    uint16_t code[288];     /* bit-reversed, ready for the LSB-first stream */
} huffman;

struct deflater {
    unsigned char *out;
    size_t size, cap;
    uint64_t acc;       /* bits not yet in out, the oldest lowest */
    unsigned nacc;
    const unsigned char *data;
    size_t n, row;      /* row: distance to the same byte one row up */
    uint32_t *syms;     /* a literal byte, or dist << 9 | length */
    size_t nsyms;
    uint32_t lfreq[286], dfreq[30];
    uint32_t *hash;     /* position + 1 of the last probe per 4-byte hash, 0 if none */
    unsigned char lcode[256]; /* length - 3 -> length code - 257 */
    unsigned char dcode[512]; /* see dist_code */
    int failed;         /* token mode: out of memory */
};

static int reserve(deflater *d, size_t more)
{
    size_t cap = d->cap;
    unsigned char *p;
    if (d->size + more <= cap) return 0;
    while (cap < d->size + more) cap = cap / 2 * 3 + more;
    if (!(p = (unsigned char *)realloc(d->out, cap))) return -1;
    d->out = p;
    d->cap = cap;
    return 0;
}

/* n <= 32; the caller has reserved the room */
static void put(deflater *d, uint32_t bits, unsigned n)
{
    d->acc |= (uint64_t)bits << d->nacc;
    d->nacc += n;
    if (d->nacc >= 32) {
        put_le32(d->out + d->size, (uint32_t)d->acc);
        d->size += 4;
        d->acc >>= 32;
        d->nacc -= 32;
    }
}

static void align_byte(deflater *d)
{
    for (; d->nacc > 0; d->nacc = d->nacc > 8 ? d->nacc - 8 : 0, d->acc >>= 8)
        d->out[d->size++] = (unsigned char)d->acc;
}

/* dist: 1 to 32768. The mask changes no such distance's index; it keeps
   the table's bounds plain to gcc -O3, which otherwise warns of a distance
   of 0 (-Warray-bounds). */
static unsigned dist_code(const deflater *d, uint32_t dist)
{
    uint32_t back = dist - 1;
    return back < 256 ? d->dcode[back] : d->dcode[256 + ((back >> 7) & 255)];
}

static int by_key(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Optimal code lengths of at most `limit` bits for the counts (package-merge,
   limit <= 15). With fewer than two used symbols, two symbols get length 1:
   zlib's inflate rejects incomplete codes. */
static void code_lengths(const uint32_t *freq, int n, int limit, unsigned char *len)
{
    uint64_t leaf[286], weight[2][2 * 286];
    unsigned char is_leaf[15][2 * 286];
    int m = 0, size = 0, take;
    memset(len, 0, (size_t)n);
    for (int i = 0; i < n; i++)
        if (freq[i]) leaf[m++] = (uint64_t)freq[i] << 9 | (uint64_t)i;
    if (m < 2) {
        int used = m ? (int)(leaf[0] & 511) : 0;
        len[used] = 1;
        len[used ? 0 : 1] = 1;
        return;
    }
    qsort(leaf, (size_t)m, sizeof leaf[0], by_key);
    /* List k holds the leaves merged with the pairs ("packages") of list k-1,
       by weight; is_leaf remembers which is which. */
    for (int k = 0; k < limit; k++) {
        const uint64_t *prev = weight[(k + 1) & 1];
        uint64_t *cur = weight[k & 1];
        int a = 0, b = 0, packages = size / 2, t = 0;
        while (a < m || b < packages) {
            uint64_t pw = b < packages ? prev[2 * b] + prev[2 * b + 1] : UINT64_MAX;
            if (a < m && leaf[a] >> 9 <= pw) { cur[t] = leaf[a++] >> 9; is_leaf[k][t++] = 1; }
            else { cur[t] = pw; b++; is_leaf[k][t++] = 0; }
        }
        size = t;
    }
    /* The first 2m-2 items of the last list are the solution; each time a
       leaf is among the items chosen at a level, its code grows a bit. */
    take = 2 * m - 2;
    for (int k = limit - 1; k >= 0; k--) {
        int leaves = 0;
        for (int t = 0; t < take; t++) leaves += is_leaf[k][t];
        for (int i = 0; i < leaves; i++) len[leaf[i] & 511]++;
        take = 2 * (take - leaves);
    }
}

/* Canonical codes from lengths (RFC 1951 3.2.2). */
static void assign_codes(huffman *h, int n)
{
    unsigned count[16] = {0}, next[16];
    unsigned code = 0;
    for (int i = 0; i < n; i++) count[h->len[i]]++;
    count[0] = 0;
    for (int bits = 1; bits < 16; bits++) next[bits] = code = (code + count[bits - 1]) << 1;
    for (int i = 0; i < n; i++) {
        unsigned v = h->len[i] ? next[h->len[i]]++ : 0, r = 0;
        for (int k = 0; k < h->len[i]; k++, v >>= 1) r = r << 1 | (v & 1);
        h->code[i] = (uint16_t)r;
    }
}

static uint64_t data_bits(const deflater *d, const huffman *lit, const huffman *dist)
{
    uint64_t bits = 0;
    for (int i = 0; i < 286; i++)
        bits += (uint64_t)d->lfreq[i] * (lit->len[i] + (i > 256 ? len_extra[i - 257] : 0));
    for (int i = 0; i < 30; i++) bits += (uint64_t)d->dfreq[i] * (dist->len[i] + dist_extra[i]);
    return bits;
}

static void put_symbols(deflater *d, const huffman *lit, const huffman *dist)
{
    for (size_t s = 0; s < d->nsyms; s++) {
        uint32_t v = d->syms[s];
        if (v < 256) {
            put(d, lit->code[v], lit->len[v]);
        } else {
            uint32_t length = v & 511, distance = v >> 9;
            unsigned lc = d->lcode[length - 3], dc = dist_code(d, distance);
            put(d, lit->code[257 + lc] | (length - len_base[lc]) << lit->len[257 + lc],
                lit->len[257 + lc] + len_extra[lc]);
            put(d, dist->code[dc] | (distance - dist_base[dc]) << dist->len[dc],
                dist->len[dc] + dist_extra[dc]);
        }
    }
    put(d, lit->code[256], lit->len[256]);
}

/* Codes the pending symbols, which cover data[start, end), as the cheapest of
   a dynamic, a fixed or stored blocks. */
static int flush_block(deflater *d, size_t start, size_t end, int final)
{
    huffman lit, dist, fixed_lit, fixed_dist, cl;
    unsigned char lens[286 + 30], rle[286 + 30], rle_extra[286 + 30];
    uint32_t clfreq[19] = {0};
    int hlit = 286, hdist = 30, hclen = 19, nlens, nrle = 0;
    uint64_t dynamic_bits, fixed_bits, stored_bits, chunks = (end - start) / 65535 + 1;

    d->lfreq[256]++;
    code_lengths(d->lfreq, 286, 15, lit.len);
    code_lengths(d->dfreq, 30, 15, dist.len);
    lit.len[286] = lit.len[287] = 0;
    assign_codes(&lit, 288);
    assign_codes(&dist, 30);
    while (hlit > 257 && !lit.len[hlit - 1]) hlit--;
    while (hdist > 1 && !dist.len[hdist - 1]) hdist--;

    /* The code lengths, run-length coded with 16 (repeat the last 3-6 times),
       17 (3-10 zeros) and 18 (11-138 zeros). */
    memcpy(lens, lit.len, (size_t)hlit);
    memcpy(lens + hlit, dist.len, (size_t)hdist);
    nlens = hlit + hdist;
    for (int i = 0; i < nlens;) {
        int v = lens[i], run = 1;
        while (i + run < nlens && lens[i + run] == v) run++;
        i += run;
        if (v == 0) {
            while (run >= 11) {
                int r = run < 138 ? run : 138;
                rle[nrle] = 18;
                rle_extra[nrle++] = (unsigned char)(r - 11);
                run -= r;
            }
            if (run >= 3) { rle[nrle] = 17; rle_extra[nrle++] = (unsigned char)(run - 3); run = 0; }
        } else {
            rle[nrle++] = (unsigned char)v;
            for (run--; run >= 3;) {
                int r = run < 6 ? run : 6;
                rle[nrle] = 16;
                rle_extra[nrle++] = (unsigned char)(r - 3);
                run -= r;
            }
        }
        while (run-- > 0) rle[nrle++] = (unsigned char)v;
    }
    for (int i = 0; i < nrle; i++) clfreq[rle[i]]++;
    code_lengths(clfreq, 19, 7, cl.len);
    assign_codes(&cl, 19);
    while (hclen > 4 && !cl.len[cl_order[hclen - 1]]) hclen--;

    dynamic_bits = 3 + 5 + 5 + 4 + 3 * (uint64_t)hclen + data_bits(d, &lit, &dist) +
                   2 * (uint64_t)clfreq[16] + 3 * (uint64_t)clfreq[17] + 7 * (uint64_t)clfreq[18];
    for (int i = 0; i < 19; i++) dynamic_bits += (uint64_t)clfreq[i] * cl.len[i];
    for (int i = 0; i < 288; i++) fixed_lit.len[i] = i < 144 ? 8 : i < 256 ? 9 : i < 280 ? 7 : 8;
    for (int i = 0; i < 30; i++) fixed_dist.len[i] = 5;
    fixed_bits = 3 + data_bits(d, &fixed_lit, &fixed_dist);
    /* stored blocks copy the data, which the token mode never has */
    stored_bits = d->data ? 8 * (uint64_t)(end - start) + 40 * chunks : UINT64_MAX; /* header, padding, LEN, NLEN */

    if (stored_bits <= dynamic_bits && stored_bits <= fixed_bits) {
        if (reserve(d, end - start + 5 * chunks + 16)) return -1;
        do {
            size_t len = end - start < 65535 ? end - start : 65535;
            put(d, (uint32_t)(final && start + len == end), 3);
            align_byte(d);
            put_le16(d->out + d->size, (unsigned)len);
            put_le16(d->out + d->size + 2, (unsigned)(~len & 0xFFFF));
            d->size += 4;
            memcpy(d->out + d->size, d->data + start, len);
            d->size += len;
            start += len;
        } while (start < end);
    } else if (fixed_bits <= dynamic_bits) {
        if (reserve(d, fixed_bits / 8 + 16)) return -1;
        assign_codes(&fixed_lit, 288);
        assign_codes(&fixed_dist, 30);
        put(d, (unsigned)final | 1u << 1, 3);
        put_symbols(d, &fixed_lit, &fixed_dist);
    } else {
        if (reserve(d, dynamic_bits / 8 + 16)) return -1;
        put(d, (unsigned)final | 2u << 1, 3);
        put(d, (uint32_t)(hlit - 257) | (uint32_t)(hdist - 1) << 5 | (uint32_t)(hclen - 4) << 10, 14);
        for (int i = 0; i < hclen; i++) put(d, cl.len[cl_order[i]], 3);
        for (int i = 0; i < nrle; i++) {
            static const unsigned char extra_bits[3] = {2, 3, 7};
            put(d, cl.code[rle[i]], cl.len[rle[i]]);
            if (rle[i] >= 16) put(d, rle_extra[i], extra_bits[rle[i] - 16]);
        }
        put_symbols(d, &lit, &dist);
    }
    d->nsyms = 0;
    memset(d->lfreq, 0, sizeof d->lfreq);
    memset(d->dfreq, 0, sizeof d->dfreq);
    return 0;
}

static size_t match_length(const unsigned char *a, const unsigned char *b, size_t limit)
{
    size_t k = 0;
    for (; k + 8 <= limit; k += 8) {
        uint64_t x, y;
        memcpy(&x, a + k, 8);
        memcpy(&y, b + k, 8);
        if (x != y) break;
    }
    while (k < limit && a[k] == b[k]) k++;
    return k;
}

typedef struct match { size_t len, dist; } match;

/* What a match saves over literals, in bits, with literals guessed at 8 bits
   and the match's codes at a few bits plus its extra bits: it ranks a short
   run of the last byte above a slightly longer match from far away. */
static long savings(const deflater *d, match m)
{
    if (m.len < 3) return 0;
    return 8 * (long)m.len - 3 - len_extra[d->lcode[m.len - 3]] -
           (m.dist == 1 ? 1 : 4 + dist_extra[dist_code(d, (uint32_t)m.dist)]);
}

/* The best of a run of the previous byte, the bytes one row up and the last
   position with the same four bytes (which then becomes this one). */
static match find_match(deflater *d, size_t i)
{
    const unsigned char *p = d->data;
    size_t limit = d->n - i < MAX_MATCH ? d->n - i : MAX_MATCH;
    match best = {0, 0}, m;
    if (i >= 1) best = (match){match_length(p + i, p + i - 1, limit), 1};
    if (best.len < limit && d->row && d->row <= WINDOW && i >= d->row) {
        m = (match){match_length(p + i, p + i - d->row, limit), d->row};
        if (savings(d, m) > savings(d, best)) best = m;
    }
    if (best.len < GOOD_MATCH && i + 4 <= d->n) {
        uint32_t key, h, cand;
        memcpy(&key, p + i, 4);
        h = (key * 2654435761u) >> (32 - HASH_BITS);
        cand = d->hash[h];
        d->hash[h] = (uint32_t)i + 1;
        if (cand && i - (cand - 1) <= WINDOW) {
            m = (match){match_length(p + i, p + cand - 1, limit), i - (cand - 1)};
            if (savings(d, m) > savings(d, best)) best = m;
        }
    }
    return best;
}

/* LZ77 over d->data with one step of lazy evaluation: a literal goes first
   when the match one byte on saves more. After 64 literals in a row the data
   looks incompressible (noise) and only every 8th byte is probed. Flushes a
   block every BLOCK_SYMBOLS symbols. */
static int deflate_data(deflater *d)
{
    const unsigned char *p = d->data;
    size_t n = d->n, i = 0, block_start = 0, literals = 0;
    match m = find_match(d, 0), next = {0, 0};
    while (i < n) {
        int defer = m.len >= 3 && m.len < MAX_MATCH && i + 1 < n &&
                    (next = find_match(d, i + 1), savings(d, next) > savings(d, m));
        if (m.len >= 3 && !defer) {
            d->syms[d->nsyms++] = (uint32_t)m.dist << 9 | (uint32_t)m.len;
            d->lfreq[257 + d->lcode[m.len - 3]]++;
            d->dfreq[dist_code(d, (uint32_t)m.dist)]++;
            i += m.len;
            literals = 0;
        } else {
            d->syms[d->nsyms++] = p[i];
            d->lfreq[p[i]]++;
            i++;
            literals++;
        }
        if (d->nsyms == BLOCK_SYMBOLS) {
            if (flush_block(d, block_start, i, i == n)) return -1;
            block_start = i;
        }
        if (i < n) m = defer ? next : literals > 64 && literals % 8 ? (match){0, 0} : find_match(d, i);
    }
    /* nothing pending: the last block went out full, marked final (or there
       was no data, which still takes an empty final block) */
    return d->nsyms || !n ? flush_block(d, block_start, n, 1) : 0;
}

static void code_tables(deflater *d)
{
    for (int c = 0; c < 29; c++)
        for (int v = len_base[c] - 3; v < len_base[c] - 3 + (1 << len_extra[c]) && v < 256; v++)
            d->lcode[v] = (unsigned char)c;
    for (int c = 0; c < 30; c++)
        for (unsigned v = dist_base[c] - 1u; v < dist_base[c] - 1u + (1u << dist_extra[c]); v += v < 256 ? 1 : 128)
            d->dcode[v < 256 ? v : 256 + (v >> 7)] = (unsigned char)c;
}

int deflate_bytes(const unsigned char *data, size_t n, size_t row, unsigned char **out, size_t *out_size)
{
    deflater d;
    int rc = -1;

    *out = NULL;
    *out_size = 0;
    if (n > 0xFFFFFFFFu || (!data && n)) return -1;
    memset(&d, 0, sizeof d);
    d.data = data;
    d.n = n;
    d.row = row;
    d.syms = (uint32_t *)malloc((n < BLOCK_SYMBOLS ? n + 1 : BLOCK_SYMBOLS) * sizeof *d.syms);
    d.hash = (uint32_t *)calloc((size_t)1 << HASH_BITS, sizeof *d.hash);
    if (!d.syms || !d.hash || reserve(&d, n / 64 + 1024)) goto done;
    code_tables(&d);
    if (deflate_data(&d) || reserve(&d, 8)) goto done;
    align_byte(&d);
    *out = (unsigned char *)realloc(d.out, d.size); /* give back the spare room */
    if (!*out) *out = d.out;
    *out_size = d.size;
    d.out = NULL;
    rc = 0;
done:
    free(d.out);
    free(d.syms);
    free(d.hash);
    return rc;
}

/* ---- symbols from the caller --------------------------------------------- */

deflater *deflate_begin(void)
{
    deflater *d = (deflater *)calloc(1, sizeof *d);
    if (!d) return NULL;
    d->syms = (uint32_t *)malloc(BLOCK_SYMBOLS * sizeof *d->syms);
    if (!d->syms || reserve(d, 4096)) {
        free(d->syms);
        free(d->out);
        free(d);
        return NULL;
    }
    code_tables(d);
    return d;
}

/* A full block goes out, not final: deflate_end writes the final one. */
static int flush_full(deflater *d)
{
    if (d->nsyms < BLOCK_SYMBOLS) return 0;
    if (flush_block(d, 0, 0, 0)) d->failed = 1;
    return d->failed ? -1 : 0;
}

int deflate_literal(deflater *d, unsigned char byte)
{
    if (d->failed) return -1;
    d->syms[d->nsyms++] = byte;
    d->lfreq[byte]++;
    return flush_full(d);
}

int deflate_copy(deflater *d, size_t length, size_t distance)
{
    if (d->failed || length < 3 || distance < 1 || distance > WINDOW) return -1;
    while (length) {
        /* pieces of at most 258, the last never shorter than 3 */
        size_t piece = length <= MAX_MATCH ? length : length - 3 < MAX_MATCH ? length - 3 : MAX_MATCH;
        d->syms[d->nsyms++] = (uint32_t)distance << 9 | (uint32_t)piece;
        d->lfreq[257 + d->lcode[piece - 3]]++;
        d->dfreq[dist_code(d, (uint32_t)distance)]++;
        length -= piece;
        if (flush_full(d)) return -1;
    }
    return 0;
}

int deflate_finish(deflater *d, const unsigned char **out, size_t *out_size)
{
    *out = NULL;
    *out_size = 0;
    if (d->failed || flush_block(d, 0, 0, 1) || reserve(d, 8)) {
        d->failed = 1;
        return -1;
    }
    align_byte(d);
    *out = d->out;
    *out_size = d->size;
    return 0;
}

void deflate_reset(deflater *d)
{
    d->size = 0;
    d->acc = 0;
    d->nacc = 0;
    d->nsyms = 0;
    d->failed = 0;
    memset(d->lfreq, 0, sizeof d->lfreq); /* a failed stream leaves its counts */
    memset(d->dfreq, 0, sizeof d->dfreq);
}

void deflate_free(deflater *d)
{
    if (!d) return;
    free(d->out);
    free(d->syms);
    free(d);
}
