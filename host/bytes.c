/* The growing byte buffer: see bytes.h. */
#include "bytes.h"
#include <stdlib.h>

unsigned char *bytebuf_room(bytebuf *b, size_t n)
{
    if (b->failed) return NULL;
    if (n > b->cap - b->size) {
        size_t cap = b->cap ? b->cap : 64;
        unsigned char *p;
        while (cap - b->size < n) {
            if (cap > (size_t)-1 / 2) { b->failed = 1; return NULL; }
            cap *= 2;
        }
        p = (unsigned char *)realloc(b->data, cap);
        if (!p) { b->failed = 1; return NULL; }
        b->data = p;
        b->cap = cap;
    }
    return b->data + b->size;
}

void bytebuf_put(bytebuf *b, const void *src, size_t n)
{
    unsigned char *p = bytebuf_room(b, n);
    if (!p) return;
    if (src) memcpy(p, src, n);
    else memset(p, 0, n);
    b->size += n;
}

#define BYTEBUF_FIELD(name, width, put, type)                                                                     \
    void name(bytebuf *b, type v)                                                                                  \
    {                                                                                                              \
        unsigned char *p = bytebuf_room(b, width);                                                                 \
        if (!p) return;                                                                                            \
        put(p, v);                                                                                                 \
        b->size += width;                                                                                          \
    }
BYTEBUF_FIELD(bytebuf_le16, 2, put_le16, unsigned)
BYTEBUF_FIELD(bytebuf_le32, 4, put_le32, uint32_t)
BYTEBUF_FIELD(bytebuf_be16, 2, put_be16, unsigned)
BYTEBUF_FIELD(bytebuf_be32, 4, put_be32, uint32_t)
BYTEBUF_FIELD(bytebuf_le_f32, 4, put_le_f32, double)
BYTEBUF_FIELD(bytebuf_be_f32, 4, put_be_f32, double)

void bytebuf_free(bytebuf *b)
{
    free(b->data);
    memset(b, 0, sizeof *b);
}
