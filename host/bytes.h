/* Fixed-width fields in files' byte orders, and a growing byte buffer: the
   one place the host's formats (CTB, GOO, PNG, ZIP, the saliency PLY) put
   and get their integers and floats. The serial link's payloads keep their
   own (link/messages.h): the firmware compiles them and has no host/. */
#ifndef ADASLICE_HOST_BYTES_H
#define ADASLICE_HOST_BYTES_H
#include <stddef.h>
#include <stdint.h>
#include <string.h>

static inline void put_le16(unsigned char *p, unsigned v)
{
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
}
static inline void put_le32(unsigned char *p, uint32_t v)
{
    put_le16(p, (unsigned)(v & 0xffffu));
    put_le16(p + 2, (unsigned)(v >> 16));
}
static inline void put_le64(unsigned char *p, uint64_t v)
{
    put_le32(p, (uint32_t)v);
    put_le32(p + 4, (uint32_t)(v >> 32));
}
static inline void put_be16(unsigned char *p, unsigned v)
{
    p[0] = (unsigned char)(v >> 8);
    p[1] = (unsigned char)v;
}
static inline void put_be32(unsigned char *p, uint32_t v)
{
    put_be16(p, (unsigned)(v >> 16));
    put_be16(p + 2, (unsigned)(v & 0xffffu));
}
static inline void put_be64(unsigned char *p, uint64_t v)
{
    put_be32(p, (uint32_t)(v >> 32));
    put_be32(p + 4, (uint32_t)v);
}
/* IEEE 754 single precision, the float every format here stores. */
static inline uint32_t f32_bits(double v)
{
    float f = (float)v;
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}
static inline void put_le_f32(unsigned char *p, double v) { put_le32(p, f32_bits(v)); }
static inline void put_be_f32(unsigned char *p, double v) { put_be32(p, f32_bits(v)); }

static inline unsigned get_le16(const unsigned char *p) { return (unsigned)p[0] | (unsigned)p[1] << 8; }
static inline uint32_t get_le32(const unsigned char *p) { return get_le16(p) | (uint32_t)get_le16(p + 2) << 16; }
static inline uint64_t get_le64(const unsigned char *p) { return get_le32(p) | (uint64_t)get_le32(p + 4) << 32; }
static inline unsigned get_be16(const unsigned char *p) { return (unsigned)p[0] << 8 | (unsigned)p[1]; }
static inline uint32_t get_be32(const unsigned char *p) { return (uint32_t)get_be16(p) << 16 | get_be16(p + 2); }

/* A byte buffer that grows as fields are appended. A failed allocation sets
   `failed` and drops that field and every later one, so a writer appends a
   whole header and checks once. data is malloc'd: the owner frees it. */
typedef struct bytebuf {
    unsigned char *data;
    size_t size, cap;
    int failed;
} bytebuf;
/* Room for n more bytes at data + size, or NULL (and failed set). */
unsigned char *bytebuf_room(bytebuf *b, size_t n);
/* Appends n bytes (zeros when src is NULL). */
void bytebuf_put(bytebuf *b, const void *src, size_t n);
void bytebuf_le16(bytebuf *b, unsigned v);
void bytebuf_le32(bytebuf *b, uint32_t v);
void bytebuf_be16(bytebuf *b, unsigned v);
void bytebuf_be32(bytebuf *b, uint32_t v);
void bytebuf_le_f32(bytebuf *b, double v);
void bytebuf_be_f32(bytebuf *b, double v);
void bytebuf_free(bytebuf *b);
#endif
