/* Raw deflate decoding, see inflate.h: canonical Huffman codes decoded a bit
   at a time by counts per length (RFC 1951 3.2.2), which is short and fast
   enough for a model file. */
#include "inflate.h"
#include <string.h>

typedef struct bits {
    const unsigned char *in;
    size_t n, at;               /* bytes, the next byte */
    unsigned buf, have;         /* bits not used yet, how many */
    int bad;                    /* read past the end */
} bits;

typedef struct huffman {
    unsigned short count[16];   /* codes of each length */
    unsigned short symbol[320]; /* symbols in code order */
} huffman;

static unsigned need(bits *b, unsigned k)
{
    unsigned v;
    while (b->have < k) {
        if (b->at >= b->n) { b->bad = 1; return 0; }
        b->buf |= (unsigned)b->in[b->at++] << b->have;
        b->have += 8;
    }
    v = b->buf & ((1u << k) - 1);
    b->buf >>= k;
    b->have -= k;
    return v;
}

/* 0, or -1 for an over-subscribed set of lengths (incomplete ones are
   allowed: a single distance code is one) */
static int build(huffman *h, const unsigned char *len, unsigned n)
{
    unsigned short offs[16];
    unsigned i;
    int left = 1;
    memset(h->count, 0, sizeof h->count);
    for (i = 0; i < n; i++) h->count[len[i]]++;
    for (i = 1; i < 16; i++) {
        left = 2 * left - h->count[i];
        if (left < 0) return -1;
    }
    offs[1] = 0;
    for (i = 1; i < 15; i++) offs[i + 1] = (unsigned short)(offs[i] + h->count[i]);
    for (i = 0; i < n; i++)
        if (len[i]) h->symbol[offs[len[i]]++] = (unsigned short)i;
    return 0;
}

static int decode(bits *b, const huffman *h)
{
    int code = 0, first = 0, index = 0, len;
    for (len = 1; len < 16; len++) {
        code |= (int)need(b, 1);
        if (b->bad) return -1;
        if (code - first < h->count[len]) return h->symbol[index + code - first];
        index += h->count[len];
        first = (first + h->count[len]) << 1;
        code <<= 1;
    }
    return -1;
}

static const unsigned short LEN_BASE[29] = {3, 4, 5, 6, 7, 8, 9, 10, 11, 13, 15, 17, 19, 23, 27, 31,
                                            35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
static const unsigned char LEN_EXTRA[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
static const unsigned short DIST_BASE[30] = {1, 2, 3, 4, 5, 7, 9, 13, 17, 25, 33, 49, 65, 97, 129,
                                             193, 257, 385, 513, 769, 1025, 1537, 2049, 3073, 4097,
                                             6145, 8193, 12289, 16385, 24577};
static const unsigned char DIST_EXTRA[30] = {0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};

static int codes(bits *b, const huffman *lit, const huffman *dist, unsigned char *out, size_t size, size_t *at)
{
    for (;;) {
        int s = decode(b, lit);
        if (s < 0) return -1;
        if (s < 256) {
            if (*at >= size) return -1;
            out[(*at)++] = (unsigned char)s;
        } else if (s == 256) {
            return 0;
        } else {
            size_t len, d;
            if ((s -= 257) >= 29) return -1;
            len = LEN_BASE[s] + need(b, LEN_EXTRA[s]);
            if ((s = decode(b, dist)) < 0 || s >= 30) return -1;
            d = DIST_BASE[s] + need(b, DIST_EXTRA[s]);
            if (b->bad || d > *at || len > size - *at) return -1;
            for (; len; len--, (*at)++) out[*at] = out[*at - d];
        }
    }
}

static int dynamic(bits *b, huffman *lit, huffman *dist)
{
    static const unsigned char ORDER[19] = {16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15};
    unsigned char len[320];
    unsigned nlen = need(b, 5) + 257, ndist = need(b, 5) + 1, ncode = need(b, 4) + 4, i = 0;
    huffman lencode;
    if (b->bad || nlen > 286 || ndist > 30) return -1;
    memset(len, 0, sizeof len);
    for (i = 0; i < ncode; i++) len[ORDER[i]] = (unsigned char)need(b, 3);
    if (b->bad || build(&lencode, len, 19)) return -1;
    for (i = 0; i < nlen + ndist;) {
        int s = decode(b, &lencode);
        unsigned rep, v = 0;
        if (s < 0) return -1;
        if (s < 16) { len[i++] = (unsigned char)s; continue; }
        if (s == 16) {
            if (!i) return -1;
            v = len[i - 1];
            rep = 3 + need(b, 2);
        } else {
            rep = s == 17 ? 3 + need(b, 3) : 11 + need(b, 7);
        }
        if (b->bad || i + rep > nlen + ndist) return -1;
        while (rep--) len[i++] = (unsigned char)v;
    }
    if (!len[256] || build(lit, len, nlen) || build(dist, len + nlen, ndist)) return -1;
    return 0;
}

int inflate_bytes(const unsigned char *in, size_t n, unsigned char *out, size_t size)
{
    bits b;
    size_t at = 0;
    int last;
    memset(&b, 0, sizeof b);
    b.in = in;
    b.n = n;
    do {
        unsigned type;
        last = (int)need(&b, 1);
        type = need(&b, 2);
        if (b.bad) return -1;
        if (type == 0) {
            size_t len;
            b.buf = b.have = 0; /* to the byte boundary */
            if (b.n - b.at < 4) return -1;
            len = (size_t)b.in[b.at] | (size_t)b.in[b.at + 1] << 8;
            if ((len ^ ((size_t)b.in[b.at + 2] | (size_t)b.in[b.at + 3] << 8)) != 0xffff) return -1;
            b.at += 4;
            if (len > b.n - b.at || len > size - at) return -1;
            memcpy(out + at, b.in + b.at, len);
            b.at += len;
            at += len;
        } else if (type == 1) {
            unsigned char len[318];
            huffman lit, dist;
            memset(len, 8, 144);
            memset(len + 144, 9, 112);
            memset(len + 256, 7, 24);
            memset(len + 280, 8, 8);
            memset(len + 288, 5, 30);
            build(&lit, len, 288);
            build(&dist, len + 288, 30);
            if (codes(&b, &lit, &dist, out, size, &at)) return -1;
        } else if (type == 2) {
            huffman lit, dist;
            if (dynamic(&b, &lit, &dist) || codes(&b, &lit, &dist, out, size, &at)) return -1;
        } else {
            return -1;
        }
    } while (!last);
    return at == size ? 0 : -1;
}
